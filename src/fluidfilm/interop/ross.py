"""fluidfilm force models at the bearing nodes of a ROSS rotor (ROSS 3.1, ``ross-rotordynamics``).

Two ways in.  ``FluidFilmBearingElement(n=..., model=..., load=...)`` is a ROSS ``BearingElement`` a ROSS user
places in ``rs.Rotor(...)`` like any other: it holds the film's stiffness and damping at its static equilibrium
under ``load`` (ROSS's frame), so ROSS's linear analyses (modal, Campbell, stability, unbalance and linear time
responses) run on it as they are; ``run_nonlinear_response(rotor, speed, t, F)`` then runs ROSS's Newmark time
response with the films' nonlinear forces, ROSS's gravity on (``weight=True``), orbits in ROSS's frame.  ROSS 3.1
has no per-element force hook for time responses (its only one, ``add_to_RHS`` of ``Rotor.run_time_response``,
is an argument of the run; magnetic bearings are special-cased), hence the function beside the element.
``FilmBearings`` is the lower-level route: the callback itself, for any rotor and models, by node.

ROSS integrates a finite-element rotor with the Newmark method; nonlinear forces enter through the
``add_to_RHS`` callback of ``Rotor.run_time_response``, called at every step with the displacements and
velocities of all degrees of freedom.  ``FilmBearings`` is that callback for any fluidfilm force model
(``ReynoldsSolver``, the grooved solvers, a surrogate), one per bearing node, and ``run_time_response``
runs it and returns the journal orbits.

Frames and units.  ROSS: SI, node ``n``'s translations at DOFs ``rotor.number_dof * n + (0, 1)`` = (x, y),
y up (ROSS's static loads are ``fys_load = -W``), the shaft turning from +x to +y.  fluidfilm
(``docs/conventions.md``): X2 along gravity, the journal turning from +X2 to +X1.  So x = X1, y = -X2 (a
reflection that keeps the sense of rotation), for positions, velocities and forces alike, and a stiffness
``K`` becomes ``T K T`` with ``T = diag(1, -1)`` (kxy = -K12, kyx = -K21).  Both codes define
``K = -dF/dX`` (ROSS: ``M q'' + C q' + K q = F``).

Two ways to hand the film to ROSS (``linear_part``):

- ``"implicit"`` (default): the rotor gets ROSS ``BearingElement``s holding the film's stiffness and damping
  at the origin, so ROSS's implicit Newmark step carries the stiff linear part, and the callback adds only
  the rest, F(X0 + q, v) - F(X0, 0) + K q + C v (zero for a linear film).  Stable at any step.
- ``"none"``: the bearing elements hold nothing and the callback carries the whole film force; with
  ``newmark_type="robust"`` ROSS iterates the callback within each step (implicit), with ``"simple"``
  the force is explicit (predicted at the end of the step) and needs a step well below 2 m / c of the
  journal's node.

Origin.  With ``loads`` (the static load each bearing carries, ROSS frame), ROSS's displacements are
measured from the film's static equilibrium X0 under that load and the callback returns
F(X0 + q, v) - F(X0, 0): run ROSS without gravity; the orbits come back absolute (X0 + q).  Without
``loads`` X0 = 0 (the bearing centre) and the callback returns the film force itself: add ROSS's weight
(``weight=True``) and the journal falls from the centre.

ROSS is imported inside the functions that need it, so ``fluidfilm.interop.ross`` imports without it.
"""
from __future__ import annotations

import copy
import functools
import math
import time
from collections.abc import Mapping
from typing import Any

import numpy as np

from fluidfilm.characteristics import coefficients as _coef
from fluidfilm.characteristics import static as _static
from fluidfilm.core.force_model import ForceModel

__all__ = ["FluidFilmBearingElement", "run_nonlinear_response", "static_loads", "film_static_forces", "FilmBearings", "LinearisedFilm", "to_ross", "matrix_to_ross", "run_time_response", "film_bearing_rotor",
           "min_log_dec", "stability_threshold", "growth_rate", "jeffcott_rotor"]

#: fluidfilm (X1, X2) -> ROSS (x, y) and back: x = X1, y = -X2
_T = np.array([1.0, -1.0])
LINEAR_PARTS = ("implicit", "none")
#: where ``run_nonlinear_response`` starts the journals: the bearing centre, or each film's static equilibrium
STARTS = ("centre", "equilibrium")


def _node_step(i, j, origin, f_origin, k, c, c2, fn):
    """One film node's part of the callback, compiled with its constants and its model's compiled force
    kernel ``fn`` frozen in (the kernel's parameters come as an argument: some kernels write scratch arrays
    held in them).  Same arithmetic as ``FilmBearings.__call__``'s Python loop; returns False (and writes
    nothing) where the journal would touch the sleeve."""
    from numba import njit

    ox1, ox2 = (float(x) for x in origin)
    f01, f02 = (float(x) for x in f_origin)
    implicit = k is not None
    k00, k01, k10, k11 = (float(x) for x in np.ravel(k)) if implicit else (0.0, 0.0, 0.0, 0.0)
    c00, c01, c10, c11 = (float(x) for x in np.ravel(c)) if implicit else (0.0, 0.0, 0.0, 0.0)

    @njit
    def step(q, v, acc, dt, predict, out, params):
        qi, qj, vi, vj = q[i], q[j], v[i], v[j]
        if predict:
            h = 0.5 * dt * dt
            qi, qj = qi + dt * vi + h * acc[i], qj + dt * vj + h * acc[j]
            vi, vj = vi + dt * acc[i], vj + dt * acc[j]
        d1, d2, v1, v2 = qi, -qj, vi, -vj
        x1, x2 = ox1 + d1, ox2 + d2
        if x1 * x1 + x2 * x2 >= c2:
            return False
        f1, f2 = fn(params, x1, x2, v1, v2)
        f1 -= f01
        f2 -= f02
        if implicit:
            f1 += k00 * d1 + k01 * d2 + c00 * v1 + c01 * v2
            f2 += k10 * d1 + k11 * d2 + c10 * v1 + c11 * v2
        out[i] = f1
        out[j] = -f2
        return True

    return step


def _chain(prev, step, index):
    """The compiled callback of the nodes so far (``prev``, or None) followed by node ``index``'s ``step``:
    returns 0, or 1 + the index of the first node whose journal touches its sleeve.  The kernels' parameters
    come nested: node 0's alone, then (the earlier nodes', this node's)."""
    from numba import njit

    if prev is None:
        @njit
        def run(q, v, acc, dt, predict, out, params):
            return 0 if step(q, v, acc, dt, predict, out, params) else index + 1
    else:
        @njit
        def run(q, v, acc, dt, predict, out, params):
            status = prev(q, v, acc, dt, predict, out, params[0])
            if status:
                return status
            return 0 if step(q, v, acc, dt, predict, out, params[1]) else index + 1
    return run


def to_ross(vec) -> np.ndarray:
    """A vector (position, velocity or force; (..., 2)) from fluidfilm's (X1, X2) to ROSS's (x, y) or back.

    Parameters
    ----------
    vec : array_like
        Components in one frame, last axis of length 2.

    Returns
    -------
    numpy.ndarray
        The same vector in the other frame (x = X1, y = -X2: the map is its own inverse).

    Examples
    --------
    >>> to_ross([1.0, 2.0]).tolist()
    [1.0, -2.0]
    """
    v = np.asarray(vec, dtype=float)
    if v.shape[-1:] != (2,):
        raise ValueError(f"a vector in the bearing plane has 2 components, got shape {v.shape}")
    return v * _T


def matrix_to_ross(m) -> np.ndarray:
    """A 2 x 2 stiffness or damping matrix from fluidfilm's frame to ROSS's (or back): ``T m T``, T = diag(1, -1).

    Parameters
    ----------
    m : array_like
        (2, 2) matrix, ``m[i, j] = -dF_i/dX_j`` in one frame.

    Returns
    -------
    numpy.ndarray
        The matrix in the other frame: the cross terms change sign.

    Examples
    --------
    >>> matrix_to_ross([[1.0, 2.0], [3.0, 4.0]]).tolist()
    [[1.0, -2.0], [-3.0, 4.0]]
    """
    a = np.asarray(m, dtype=float)
    if a.shape != (2, 2):
        raise ValueError(f"a bearing matrix is 2 x 2, got shape {a.shape}")
    return a * np.outer(_T, _T)


class LinearisedFilm:
    """A film model replaced by its linearisation at ``x0``: F = F0 - K (X - x0) - C V (fluidfilm's frame).

    Parameters
    ----------
    model : force model
        Any fluidfilm force model (``forces(X, V)``, ``bearing``).
    x0 : array_like
        The position [m] to linearise at (e.g. the static equilibrium).
    h_rel : float, default 1e-4
        Relative step of the central differences (``characteristics.coefficients.coefficients``: the
        derivative of the model's own ``forces``, which a nonlinear run linearises to; the film-region
        shortcut of a Gumbel solver differs from it by a few per cent).

    Examples
    --------
    >>> from fluidfilm import JournalBearing, ReynoldsSolver
    >>> b = JournalBearing(length=0.025, diameter=0.05, clearance=50e-6, speed_rpm=6000.0, viscosity=0.02)
    >>> lin = LinearisedFilm(ReynoldsSolver(b, 30, 30), [0.0, 20e-6])
    >>> bool(np.allclose(lin.forces([0.0, 20e-6], [0.0, 0.0]), lin.F0))
    True
    """

    name = "linearised"

    def __init__(self, model, x0, h_rel: float = 1e-4):
        self.model = model
        self.bearing = model.bearing
        self.x0 = np.asarray(x0, dtype=float)
        kc = _coef.coefficients(model, self.x0, h_rel)
        self.K, self.C = np.asarray(kc["K"], dtype=float), np.asarray(kc["C"], dtype=float)
        self.F0 = np.asarray(model.forces(self.x0, np.zeros(2)), dtype=float)

    def forces(self, X, V) -> np.ndarray:
        """F0 - K (X - x0) - C V [N] for positions X [m] and velocities V [m/s], (..., 2) each.

        Parameters
        ----------
        X, V : array_like
            Positions and velocities, last axis of length 2.

        Returns
        -------
        numpy.ndarray
            The forces, same shape.
        """
        X, V = np.asarray(X, dtype=float), np.asarray(V, dtype=float)
        return self.F0 - (X - self.x0) @ self.K.T - V @ self.C.T


def film_bearing_rotor(rotor, matrices: Mapping[int, tuple]):
    """A copy of ROSS rotor ``rotor`` whose bearing elements at the given nodes hold the given K and C.

    Parameters
    ----------
    rotor : ross.Rotor
        The rotor; it keeps its shaft, discs, point masses and its other bearings.
    matrices : mapping
        ``{node: (K, C)}``, 2 x 2 in ROSS's frame [N/m, N s/m] (zeros: an empty bearing for a film carried
        wholly by the callback).

    Returns
    -------
    ross.Rotor
        The new rotor.
    """
    import ross as rs

    nodes = set(matrices)
    shaft_nodes = set(range(len(rotor.shaft_elements) + 1))
    if nodes - shaft_nodes:
        raise ValueError(f"bearing nodes {sorted(nodes - shaft_nodes)} are not shaft nodes 0..{max(shaft_nodes)}")
    keep = [b for b in rotor.bearing_elements if int(b.n) not in nodes]  # a film node without one gets one
    new = []
    for n in sorted(nodes):
        k, c = (np.asarray(m, dtype=float) for m in matrices[n])
        new.append(rs.BearingElement(n=n, kxx=k[0, 0], kxy=k[0, 1], kyx=k[1, 0], kyy=k[1, 1],
                                     cxx=c[0, 0], cxy=c[0, 1], cyx=c[1, 0], cyy=c[1, 1], tag=f"fluidfilm_{n}"))
    return rs.Rotor(rotor.shaft_elements, rotor.disk_elements, keep + new,
                    point_mass_elements=rotor.point_mass_elements)


class FilmBearings:
    """fluidfilm force models at bearing nodes of a ROSS rotor, as ROSS's ``add_to_RHS`` callback.

    Call it as ROSS does: ``film(step, disp_resp=..., velc_resp=..., accl_resp=..., time_step=...)`` returns
    the forces on all ``rotor.ndof`` DOFs (the film's at the bearing nodes' x, y; zero elsewhere).  It counts
    its calls and the time spent in them (``calls``, ``seconds``; ``reset_timing``).

    Parameters
    ----------
    rotor : ross.Rotor
        The rotor (its shaft, discs and other bearings); ``self.rotor`` is the copy to integrate, whose
        bearings at the film nodes hold the film's linear part (``linear_part="implicit"``) or nothing.
    models : mapping
        ``{node: force model}``; each model's bearing speed must be the speed ROSS runs at.
    loads : mapping or None, default None
        ``{node: (Fx, Fy)}`` [N], ROSS's frame: the static load each bearing carries (e.g. (0, -m g / 2)).
        Given: ROSS's displacements are measured from each film's equilibrium under it (run without
        gravity).  None: from the bearing centre (run with ROSS's ``weight=True``).
    linear_part : {"implicit", "none"}, default "implicit"
        Where the film's linearisation at the origin goes: into ROSS's bearing elements (the callback adds
        the nonlinear rest) or nowhere (the callback carries the whole force).
    h_rel : float, default 1e-4
        Relative step of the linearisation (central differences of the model's forces,
        ``characteristics.coefficients.coefficients``).

    Raises
    ------
    ValueError
        For an unknown ``linear_part``, a node that is not a shaft node, or loads at nodes without a model.
    """

    def __init__(self, rotor, models: Mapping[int, ForceModel], loads: Mapping[int, tuple] | None = None,
                 linear_part: str = "implicit", h_rel: float = 1e-4):
        if linear_part not in LINEAR_PARTS:
            raise ValueError(f"linear_part must be one of {LINEAR_PARTS}, got {linear_part!r}")
        if not models:
            raise ValueError("models is empty: give {node: force model} for at least one bearing node")
        if loads is not None and set(loads) - set(models):
            raise ValueError(f"loads at nodes {sorted(set(loads) - set(models))} that carry no model")
        self.nodes = sorted(int(n) for n in models)
        self.models: dict[int, ForceModel] = {int(n): m for n, m in models.items()}
        self.linear_part = linear_part
        self.predict = True  # set by run_time_response: only ROSS's "simple" Newmark calls at the step's start
        self.origin, self.f_origin, self.K, self.C = {}, {}, {}, {}
        for n in self.nodes:
            m = self.models[n]
            if loads is not None and n in loads:
                w = to_ross(np.asarray(loads[n], dtype=float))  # the load on the journal, fluidfilm's frame
                x0 = np.asarray(_static.equilibrium(m, (float(w[0]), float(w[1])))["X"], dtype=float)
                f0 = np.asarray(m.forces(x0, np.zeros(2)), dtype=float)
            else:
                x0, f0 = np.zeros(2), np.zeros(2)
            self.origin[n], self.f_origin[n] = x0, f0
            if linear_part == "implicit":
                kc = _coef.coefficients(m, x0, h_rel)
                self.K[n], self.C[n] = np.asarray(kc["K"], dtype=float), np.asarray(kc["C"], dtype=float)
            else:
                self.K[n], self.C[n] = np.zeros((2, 2)), np.zeros((2, 2))
        self.rotor = film_bearing_rotor(rotor, {n: (matrix_to_ross(self.K[n]), matrix_to_ross(self.C[n]))
                                                for n in self.nodes})
        self.ndof = int(self.rotor.ndof)
        nd = int(self.rotor.number_dof)
        self.dofs = {n: np.array([nd * n, nd * n + 1]) for n in self.nodes}
        self._c2 = {n: float(self.models[n].bearing.clearance) ** 2 for n in self.nodes}
        self.use_kernels = True  # each model's compiled force_kernel where it has one (else its forces())
        # with every node on a compiled kernel: the whole callback compiled too (``_node_step``), built on its
        # first call after ``refresh``; False: the Python loop over the nodes
        self.compiled = True
        self.reset_timing()
        self.refresh()

    def refresh(self) -> None:
        """Rebuild the callback's per-node plan (plain Python numbers) after ``origin``, ``f_origin``, ``K``,
        ``C`` or ``use_kernels`` changed; ``run_time_response`` calls it before every run."""
        plan = []
        for n in self.nodes:
            m = self.models[n]
            kernel = getattr(m, "force_kernel", None) if self.use_kernels else None
            imp = self.linear_part == "implicit"
            plan.append((n, (int(self.dofs[n][0]), int(self.dofs[n][1])),
                         tuple(float(x) for x in self.origin[n]), tuple(float(x) for x in self.f_origin[n]),
                         self.K[n].tolist() if imp else None, self.C[n].tolist() if imp else None, kernel, m))
        # the compiled callback of this plan (built on the first call that uses it), kept while the plan stays
        # the same (``run_time_response`` refreshes before every run)
        key = tuple((n, d, o, f, k, c, None if kernel is None else (id(kernel[0]), id(kernel[1])), id(m))
                    for n, d, o, f, k, c, kernel, m in plan)
        if key != getattr(self, "_plan_key", None):
            self._run = None
            self._run_params = None  # the kernels' parameters it is called with
        self._plan, self._plan_key = plan, key

    def reset_timing(self) -> None:
        """Set the call counter and the time spent in the callback to zero."""
        self.calls, self.seconds = 0, 0.0

    def journal_state(self, node: int, disp, velc) -> tuple[np.ndarray, np.ndarray]:
        """The journal's position and velocity at ``node`` in fluidfilm's frame (absolute: origin + q).

        Parameters
        ----------
        node : int
            A film node.
        disp, velc : array_like
            ROSS's displacement and velocity vectors (all DOFs).

        Returns
        -------
        tuple of numpy.ndarray
            X [m], V [m/s].
        """
        d = self.dofs[node]
        return self.origin[node] + to_ross(np.asarray(disp)[d]), to_ross(np.asarray(velc)[d])

    def __call__(self, step, time_step=None, disp_resp=None, velc_resp=None, accl_resp=None, args=None):
        """ROSS's ``add_to_RHS``: the film forces [N] on every DOF (ROSS's frame) at this state.

        Parameters
        ----------
        step : int
            ROSS's step number (unused).
        time_step : float or None
            The step dt [s]; with ``predict`` the state is carried to the step's end with it.
        disp_resp, velc_resp, accl_resp : numpy.ndarray
            ROSS's displacements, velocities and accelerations (all DOFs).
        args : object
            ROSS's extra arguments (unused).

        Returns
        -------
        numpy.ndarray
            The forces, length ``ndof``.
        """
        t0 = time.perf_counter()
        predict = bool(self.predict and time_step and accl_resp is not None)
        if self.compiled and all(p[6] is not None for p in self._plan):
            return self._call_compiled(t0, disp_resp, velc_resp, accl_resp, time_step, predict)
        # plain Python floats: a handful of components is cheaper in Python than in numpy (the call's own
        # overhead is what a fast model would otherwise pay per step)
        q, v = np.asarray(disp_resp, dtype=float).tolist(), np.asarray(velc_resp, dtype=float).tolist()
        if predict:
            acc = np.asarray(accl_resp, dtype=float).tolist()
            dt = float(time_step)
            h = 0.5 * dt * dt
        out = np.zeros(self.ndof)
        for n, (i, j), (ox1, ox2), (f01, f02), k, c, kernel, model in self._plan:
            # fluidfilm's frame (x = X1, y = -X2), relative to the origin
            qi, qj, vi, vj = q[i], q[j], v[i], v[j]
            if predict:
                # ROSS's simple Newmark calls at the start of the step and keeps the force for its end: carry
                # the state there (second order), so the explicit part is as accurate as the implicit step
                qi, qj = qi + dt * vi + h * acc[i], qj + dt * vj + h * acc[j]
                vi, vj = vi + dt * acc[i], vj + dt * acc[j]
            d1, d2, v1, v2 = qi, -qj, vi, -vj
            x1, x2 = ox1 + d1, ox2 + d2
            if kernel is not None:
                if x1 * x1 + x2 * x2 >= self._c2[n]:
                    raise ValueError(f"eccentricity ratio {math.hypot(x1, x2) / math.sqrt(self._c2[n]):.6g} >= 1 "
                                     f"at node {n}, X=({x1!r}, {x2!r}) m: the journal touches the sleeve")
                f1, f2 = kernel[0](kernel[1], x1, x2, v1, v2)
            else:
                f1, f2 = model.forces(np.array([x1, x2]), np.array([v1, v2]))
            f1, f2 = float(f1) - f01, float(f2) - f02
            if k is not None:  # ROSS's bearing element applies -K q - C v itself
                f1 += k[0][0] * d1 + k[0][1] * d2 + c[0][0] * v1 + c[0][1] * v2
                f2 += k[1][0] * d1 + k[1][1] * d2 + c[1][0] * v1 + c[1][1] * v2
            out[i], out[j] = f1, -f2
        self.seconds += time.perf_counter() - t0
        self.calls += 1
        return out

    def _call_compiled(self, t0, disp_resp, velc_resp, accl_resp, time_step, predict):
        """``__call__`` by the compiled callback (every node on a compiled kernel): one compiled call per step."""
        q = np.ascontiguousarray(disp_resp, dtype=float)
        v = np.ascontiguousarray(velc_resp, dtype=float)
        acc = np.ascontiguousarray(accl_resp, dtype=float) if predict else q
        out = np.zeros(self.ndof)
        args = (q, v, acc, float(time_step) if predict else 0.0, predict, out, self._run_params)
        if self._run is None:
            run, params = None, None
            for index, (n, (i, j), origin, f_origin, k, c, kernel, _) in enumerate(self._plan):
                run = _chain(run, _node_step(i, j, origin, f_origin, k, c, self._c2[n], kernel[0]), index)
                params = kernel[1] if params is None else (params, kernel[1])
            self._run_params = params
            args = args[:-1] + (params,)
            status = run(*args)  # compiles (not counted in ``seconds``)
            # later calls go to the compiled entry point itself: numba's dispatcher would type the parameter
            # tuples on every call (microseconds: the Python overhead this path removes)
            self._run = run.overloads[run.signatures[0]].entry_point
            t0 = time.perf_counter()
            status = self._run(*args)
        else:
            status = self._run(*args)
        if status:  # the same state and message as the Python loop's
            n, (i, j), (ox1, ox2) = self._plan[status - 1][:3]
            qi, qj = float(q[i]), float(q[j])
            if predict:
                dt = float(time_step)
                qi += dt * float(v[i]) + 0.5 * dt * dt * float(acc[i])
                qj += dt * float(v[j]) + 0.5 * dt * dt * float(acc[j])
            x1, x2 = ox1 + qi, ox2 - qj
            raise ValueError(f"eccentricity ratio {math.hypot(x1, x2) / math.sqrt(self._c2[n]):.6g} >= 1 "
                             f"at node {n}, X=({x1!r}, {x2!r}) m: the journal touches the sleeve")
        self.seconds += time.perf_counter() - t0
        self.calls += 1
        return out


def run_time_response(film: FilmBearings, speed: float, t, F=None, newmark_type: str = "simple", **kwargs) -> dict:
    """ROSS's nonlinear Newmark response of ``film.rotor`` with the film forces, and the journal orbits.

    Parameters
    ----------
    film : FilmBearings
        The film models and the rotor to integrate.
    speed : float
        Rotor speed [rad/s]; every film model's bearing must turn at it.
    t : array_like
        Time points [s] (ROSS starts from rest at q = 0, i.e. at the origin of ``film``).
    F : array_like or None, default None
        External forces, (len(t), ndof) [N] (None: zero).
    newmark_type : {"simple", "robust"}, default "simple"
        ROSS's Newmark variant: ``"simple"`` calls the callback once per step (explicit, predicted);
        ``"robust"`` iterates it within the step.
    **kwargs
        Passed to ``Rotor.run_time_response`` (e.g. ``weight=True``, ``tol``).

    Returns
    -------
    dict
        ``t``; ``orbits`` {node: (len(t), 2) journal positions [m], fluidfilm's frame, absolute};
        ``orbits_ross`` {node: (len(t), 2) ROSS displacements (x, y)}; ``seconds`` (wall time of the run);
        ``film_seconds``, ``film_calls`` (the callback's share); ``response`` (ROSS's result).

    Raises
    ------
    ValueError
        For a model whose bearing speed is not ``speed``, or an unknown ``newmark_type``.
    """
    if newmark_type not in ("simple", "robust"):
        raise ValueError(f"newmark_type must be 'simple' or 'robust', got {newmark_type!r}")
    for n, m in film.models.items():
        omega = float(m.bearing.omega)
        if not np.isclose(omega, float(speed), rtol=1e-9):
            raise ValueError(f"the model at node {n} turns at {omega!r} rad/s, ROSS runs at speed={speed!r}")
    t = np.asarray(t, dtype=float)
    F = np.zeros((t.size, film.ndof)) if F is None else np.asarray(F, dtype=float)
    film.predict = newmark_type == "simple"
    film.refresh()
    film.reset_timing()
    t0 = time.perf_counter()
    res = film.rotor.run_time_response(float(speed), F, t, method="newmark", add_to_RHS=film,
                                       newmark_type=newmark_type, **kwargs)
    seconds = time.perf_counter() - t0
    y = np.asarray(res.yout)
    orbits_ross = {n: y[:, film.dofs[n]] for n in film.nodes}
    orbits = {n: film.origin[n] + to_ross(orbits_ross[n]) for n in film.nodes}
    return {"t": t, "orbits": orbits, "orbits_ross": orbits_ross, "seconds": seconds,
            "film_seconds": film.seconds, "film_calls": film.calls, "response": res}


_COEFFICIENT_KWARGS = ("kxx", "kxy", "kyx", "kyy", "cxx", "cxy", "cyx", "cyy", "speed", "frequency")


def _check_load(load) -> np.ndarray:
    w = np.asarray(load, dtype=float) if not isinstance(load, (str, bytes)) else np.array([np.nan])
    if w.shape != (2,) or not np.all(np.isfinite(w)) or not np.any(w):
        raise ValueError(f"load must be the static load (Fx, Fy) [N] on the bearing in ROSS's frame (y up; the "
                         f"weight share of a horizontal rotor is (0, -W)), two finite numbers not both zero; got {load!r}")
    return w


def _check_speeds(speeds, model) -> np.ndarray:
    """``FluidFilmBearingElement``'s ``speeds`` [rad/s], checked: at least two, finite, positive, increasing, and a
    model that can be moved to them (``with_speed``)."""
    sp = np.asarray(speeds, dtype=float).ravel() if not isinstance(speeds, (str, bytes)) else np.array([np.nan])
    if sp.size < 2 or not np.all(np.isfinite(sp)) or np.any(sp <= 0) or np.any(np.diff(sp) <= 0):
        raise ValueError(f"speeds must be two or more increasing rotor speeds > 0 [rad/s]; got {speeds!r}")
    if not callable(getattr(model, "with_speed", None)):
        raise TypeError(f"speeds needs a model with with_speed(speed_rpm) (e.g. universal_bearing(...)); {model!r} "
                        f"has none: leave speeds out (coefficients at the model's own speed) or make one element "
                        f"per speed")
    return sp


@functools.lru_cache(maxsize=None)
def _element_class() -> type:
    """The ROSS ``BearingElement`` subclass behind ``FluidFilmBearingElement`` (built on first use: ROSS is
    imported here, not when this module is)."""
    try:
        import ross as rs
    except ImportError as exc:
        raise ImportError(f"FluidFilmBearingElement needs ROSS 3.1 (ross-rotordynamics, Python >= 3.13): "
                          f"pip install \"fluidfilm[ross]\" ({exc})") from exc

    class FluidFilmBearingElement(rs.BearingElement):
        __doc__ = _ELEMENT_DOC

        def __init__(self, n, model, load, h_rel: float = 1e-4, speeds=None, tag=None, n_link=None,
                     scale_factor=1, **kwargs):
            given = sorted(set(kwargs) & set(_COEFFICIENT_KWARGS))
            if given:
                raise TypeError(f"FluidFilmBearingElement computes its coefficients from the film model; got {given}")
            if not hasattr(model, "forces") or not hasattr(model, "bearing"):
                raise TypeError(f"model must be a fluidfilm force model (forces(X, V), bearing); got {model!r}")
            w = _check_load(load)
            # the load on the journal in fluidfilm's frame (X2 along gravity); the equilibrium raises, naming the
            # load, where the film cannot carry it
            w_film = tuple(float(v) for v in to_ross(w))

            def linearise(m):
                x = np.asarray(_static.equilibrium(m, w_film)["X"], dtype=float)
                kc = _coef.coefficients(m, x, h_rel)
                return x, np.asarray(kc["K"], dtype=float), np.asarray(kc["C"], dtype=float)

            x0, K, C = linearise(model)
            if speeds is None:
                k, c = matrix_to_ross(K), matrix_to_ross(C)
                table: dict[str, Any] = {}
            else:
                table = {"speed": _check_speeds(speeds, model)}
                ks, cs = [], []
                for omega in table["speed"]:
                    _, Ks, Cs = linearise(model.with_speed(float(omega) * 30.0 / math.pi))
                    ks.append(matrix_to_ross(Ks))
                    cs.append(matrix_to_ross(Cs))
                k, c = np.moveaxis(np.array(ks), 0, -1), np.moveaxis(np.array(cs), 0, -1)
            super().__init__(n=n, kxx=k[0, 0], kxy=k[0, 1], kyx=k[1, 0], kyy=k[1, 1], cxx=c[0, 0], cxy=c[0, 1],
                             cyx=c[1, 0], cyy=c[1, 1], tag=tag if tag is not None else f"fluidfilm_{n}",
                             n_link=n_link, scale_factor=scale_factor,
                             radial_clearance=float(model.bearing.clearance), **table, **kwargs)
            self.model = model
            self.load = w
            self.h_rel = float(h_rel)
            self.x0 = x0                                   # fluidfilm's frame
            self.equilibrium_position = to_ross(x0)       # ROSS's frame, from the bearing centre
            self.eccentricity = float(np.hypot(*x0) / float(model.bearing.clearance))
            self.K_film, self.C_film = K, C                # fluidfilm's frame
            self.operating_speed = float(model.bearing.omega)  # [rad/s]: where K and C hold

        def __deepcopy__(self, memo):
            # ROSS deep-copies elements in some analyses; the film model (compiled kernels) is shared, not copied
            new = copy.copy(self)
            memo[id(self)] = new
            for key, value in self.__dict__.items():
                if key != "model":
                    setattr(new, key, copy.deepcopy(value, memo))
            return new

    FluidFilmBearingElement.__module__ = __name__
    FluidFilmBearingElement.__qualname__ = "FluidFilmBearingElement"
    return FluidFilmBearingElement


_ELEMENT_DOC = """A fluidfilm bearing as a ROSS bearing element: place it in ``rs.Rotor(...)`` like ``rs.BearingElement``.

    It is a ``ross.BearingElement`` (ROSS is imported when the first one is made) holding the film's stiffness
    and damping at its static equilibrium under ``load``, mapped into ROSS's frame (``matrix_to_ross``), so every
    linear analysis of ROSS (``run_modal``, ``run_campbell``, ``run_unbalance_response``, a linear
    ``run_time_response``) uses it as it is. ``run_nonlinear_response`` runs the rotor's time response with the
    film's nonlinear force instead, with ROSS's gravity.

    Parameters
    ----------
    n : int
        The shaft node.
    model : force model
        Any fluidfilm force model (``ReynoldsSolver``, ``universal_bearing(...)``, the grooved solvers, a
        surrogate); its bearing's speed is the operating speed (without ``speeds`` the coefficients are those at
        that speed and ROSS's analyses at other speeds keep them, as for any constant ``BearingElement``).
    load : tuple of float
        (Fx, Fy) [N], ROSS's frame (y up): the static load the bearing carries, e.g. ``(0, -W)`` for its share
        W of a horizontal rotor's weight (``static_loads(rotor)`` gives ROSS's own).
    h_rel : float, default 1e-4
        Relative step of the linearisation (``characteristics.coefficients.coefficients``).
    speeds : array_like or None, default None
        Rotor speeds [rad/s] (two or more, increasing) to tabulate the coefficients at, each at the equilibrium
        under ``load`` at that speed, for ROSS's analyses over speed (``run_campbell``; ROSS interpolates between
        them); needs a model with ``with_speed`` (``universal_bearing``). None: the model's speed only (constant
        coefficients). The nonlinear response always runs the model itself, at its speed.
    tag, n_link, scale_factor, **kwargs
        As for ``ross.BearingElement`` (its coefficients come from the film: passing any is a TypeError).

    Attributes
    ----------
    model, load, h_rel
        As given (``load`` as an array).
    equilibrium_position : numpy.ndarray
        The journal centre at equilibrium [m], ROSS's frame, from the bearing centre (y < 0 under a load along -y).
    x0 : numpy.ndarray
        The same in fluidfilm's frame (X2 along gravity).
    eccentricity : float
        Its eccentricity ratio.
    K_film, C_film : numpy.ndarray
        The film's K [N/m] and C [N s/m] there, fluidfilm's frame (the element's ``kxx``... are them in ROSS's).
    operating_speed : float
        The model's speed [rad/s].

    Raises
    ------
    ValueError
        For a load that is not two finite numbers, or one the film cannot carry (named by the equilibrium); for
        bad ``speeds``.
    TypeError
        For a model that is not a force model, coefficients passed by hand, or ``speeds`` with a model that has
        no ``with_speed``.
    """


class _RossElementType(type):
    """``FluidFilmBearingElement`` without importing ROSS here: calling it builds (once) and instantiates the
    ``ross.BearingElement`` subclass; ``isinstance`` asks that class."""

    def __call__(cls, *args, **kwargs) -> Any:
        return _element_class()(*args, **kwargs)

    def __instancecheck__(cls, obj) -> bool:
        try:
            return isinstance(obj, _element_class())
        except ImportError:  # no ROSS here: nothing is one
            return False


class FluidFilmBearingElement(metaclass=_RossElementType):
    __doc__ = _ELEMENT_DOC


def _film_elements(rotor) -> list[Any]:
    """The rotor's ``FluidFilmBearingElement``s (ROSS objects: typed Any)."""
    return [b for b in rotor.bearing_elements if isinstance(b, FluidFilmBearingElement)]


def static_loads(rotor) -> dict[int, tuple[float, float]]:
    """The static loads ROSS's own static analysis (``rotor.run_static()``, its gravity) puts on the rotor's bearings.

    Parameters
    ----------
    rotor : ross.Rotor
        The rotor, on any bearings (e.g. placeholders: the reactions of a rotor on two bearings do not depend on
        them; with more, they do).

    Returns
    -------
    dict
        ``{node: (0, -R)}`` [N], ROSS's frame: the load each bearing carries (``FluidFilmBearingElement``'s
        ``load``, ``FilmBearings``' ``loads``).
    """
    forces = rotor.run_static().bearing_forces
    return {int(b.n): (0.0, -float(forces[f"node_{int(b.n)}"])) for b in rotor.bearing_elements}


def film_static_forces(rotor, t) -> np.ndarray:
    """The films' static forces on the journals, as ROSS force rows: for ROSS's linear response about the equilibria.

    ROSS's linear time response of a rotor on ``FluidFilmBearingElement``s, with its weight, starts at the bearing
    centres' linearisation; adding these forces (each element's film force at its equilibrium, -``load``, at its
    node's x, y) makes it the linear response about the films' equilibria, the linear counterpart of
    ``run_nonlinear_response(..., start="equilibrium")``:
    ``rotor.run_time_response(speed, F + film_static_forces(rotor, t), t, method="newmark", weight=True)``.

    Parameters
    ----------
    rotor : ross.Rotor
        The rotor.
    t : array_like
        Time points [s].

    Returns
    -------
    numpy.ndarray
        (len(t), ndof) [N], ROSS's frame.
    """
    t = np.asarray(t, dtype=float)
    out = np.zeros((t.size, int(rotor.ndof)))
    nd = int(rotor.number_dof)
    for b in _film_elements(rotor):
        out[:, nd * int(b.n)] -= b.load[0]
        out[:, nd * int(b.n) + 1] -= b.load[1]
    return out


def run_nonlinear_response(rotor, speed: float, t, F=None, start: str = "centre", weight: bool = True,
                           newmark_type: str = "simple", **kwargs) -> dict:
    """ROSS's Newmark time response of a rotor on ``FluidFilmBearingElement``s, with the films' nonlinear forces.

    ROSS's gravity is on (``weight=True``, ROSS's ``Rotor.gravitational_force``): the films carry the rotor's
    weight. The linear part of each film (the element's K and C) stays in ROSS's implicit step and the rest goes
    through ``add_to_RHS`` (``FilmBearings``, ``linear_part="implicit"``), so the run is stable at any step.

    Parameters
    ----------
    rotor : ross.Rotor
        The rotor; its ``FluidFilmBearingElement``s are the films (other bearings stay linear).
    speed : float
        Rotor speed [rad/s]; every film model's bearing must turn at it.
    t : array_like
        Time points [s].
    F : array_like or None, default None
        External forces, (len(t), ndof) [N], ROSS's frame (None: zero; the weight is added by ROSS).
    start : {"centre", "equilibrium"}, default "centre"
        Where ROSS's displacements are measured from and the journals start at rest: ``"centre"``: the bearing
        centres (ROSS's own convention: the journals fall under gravity and settle at the films' equilibria);
        ``"equilibrium"``: each film's static equilibrium under its element's ``load`` (no fall; the loads must
        be the reactions of ROSS's gravity, ``static_loads``).
    weight : bool, default True
        ROSS's gravity. ``start="equilibrium"`` needs it (the films there carry the weight).
    newmark_type : {"simple", "robust"}, default "simple"
        As for ``run_time_response``.
    **kwargs
        Passed to ``Rotor.run_time_response`` (e.g. ``tol``).

    Returns
    -------
    dict
        ``run_time_response``'s (``orbits``: absolute journal positions [m] in fluidfilm's frame, ``orbits_ross``:
        ROSS's displacements at the film nodes, ``response``: ROSS's result, ...) and ``positions_ross``
        {node: (len(t), 2) journal positions [m] in ROSS's frame, from the bearing centre}, ``film`` (the
        ``FilmBearings`` it ran), ``start``.

    Raises
    ------
    ValueError
        For a rotor without ``FluidFilmBearingElement``s, an unknown ``start``, ``start="equilibrium"`` without
        the weight, elements with different ``h_rel``, or a model whose speed is not ``speed``.
    """
    if start not in STARTS:
        raise ValueError(f"start must be one of {STARTS}, got {start!r}")
    if start == "equilibrium" and not weight:
        raise ValueError("start='equilibrium' needs weight=True: the films there carry the rotor's weight, and "
                         "without it they would push the journals up")
    films = _film_elements(rotor)
    if not films:
        raise ValueError("the rotor has no FluidFilmBearingElement: place fluidfilm.interop.ross."
                         "FluidFilmBearingElement(n=..., model=..., load=...) among its bearing elements")
    h_rel = {b.h_rel for b in films}
    if len(h_rel) > 1:
        raise ValueError(f"the film elements were linearised with different h_rel {sorted(h_rel)}: use one")
    film = FilmBearings(rotor, {int(b.n): b.model for b in films}, {int(b.n): tuple(b.load) for b in films},
                        linear_part="implicit", h_rel=h_rel.pop())
    for n in film.nodes:
        # the callback returns the film's whole force (it carries ROSS's weight), measured from the chosen origin;
        # the elements' K and C (at the equilibrium) stay in ROSS's step and are added back by the callback
        film.f_origin[n] = np.zeros(2)
        if start == "centre":
            film.origin[n] = np.zeros(2)
    film.refresh()
    t = np.asarray(t, dtype=float)
    # a copy: ROSS adds the weight into the force array it is given
    F = np.zeros((t.size, film.ndof)) if F is None else np.array(F, dtype=float)
    out = run_time_response(film, speed, t, F, newmark_type=newmark_type, weight=bool(weight), **kwargs)
    out["positions_ross"] = {n: to_ross(out["orbits"][n]) for n in film.nodes}
    out["film"], out["start"] = film, start
    return out


def min_log_dec(rotor, models: Mapping[int, ForceModel], loads: Mapping[int, tuple], num_modes: int = 12) -> dict:
    """ROSS's modal analysis of ``rotor`` on the films' linearisations at their static equilibria.

    Parameters
    ----------
    rotor : ross.Rotor
        The rotor.
    models : mapping
        ``{node: force model}``, all turning at the same speed (the rotor's).
    loads : mapping
        ``{node: (Fx, Fy)}`` [N], ROSS's frame: the static loads (``FilmBearings``).
    num_modes : int, default 12
        Modes ROSS computes.

    Returns
    -------
    dict
        ``log_dec`` (the smallest logarithmic decrement: negative = unstable), ``wd`` (that mode's damped
        frequency [rad/s]), ``growth_rate`` (-log_dec wd / 2 pi [1/s]), ``speed`` [rad/s].
    """
    film = FilmBearings(rotor, models, loads, linear_part="implicit")
    speed = float(next(iter(models.values())).bearing.omega)
    modal = film.rotor.run_modal(speed, num_modes=num_modes)
    ld, wd = np.asarray(modal.log_dec, dtype=float), np.asarray(modal.wd, dtype=float)
    i = int(np.argmin(ld))
    return {"log_dec": float(ld[i]), "wd": float(wd[i]), "growth_rate": float(-ld[i] * wd[i] / (2 * np.pi)),
            "speed": speed}


def stability_threshold(rotor, make_models, loads: Mapping[int, tuple], bracket_rpm: tuple[float, float],
                        rtol: float = 1e-5) -> dict:
    """The onset speed of oil whirl by ROSS's stability analysis fed the films' K and C at every speed.

    Parameters
    ----------
    rotor : ross.Rotor
        The rotor.
    make_models : callable
        ``speed_rpm -> {node: force model}`` (the films at that speed).
    loads : mapping
        ``{node: (Fx, Fy)}`` [N], ROSS's frame.
    bracket_rpm : tuple of float
        Speeds [rpm] with a stable (positive smallest log dec) low end and an unstable high end.
    rtol : float, default 1e-5
        Relative tolerance of the root (Brent).

    Returns
    -------
    dict
        ``speed_rpm`` of the threshold, ``whirl_frequency`` [rad/s] there, ``evaluations``.

    Raises
    ------
    ValueError
        When the bracket does not change sign.
    """
    from scipy.optimize import brentq

    seen = {}

    def f(rpm):
        r = min_log_dec(rotor, make_models(float(rpm)), loads)
        seen[float(rpm)] = r
        return r["log_dec"]

    lo, hi = (float(v) for v in bracket_rpm)
    flo, fhi = f(lo), f(hi)
    if not (flo > 0 > fhi):
        raise ValueError(f"bracket_rpm={bracket_rpm!r} does not bracket the threshold: smallest log dec "
                         f"{flo:.4g} at {lo} rpm, {fhi:.4g} at {hi} rpm (need > 0, then < 0)")
    rpm = brentq(f, lo, hi, rtol=rtol)
    return {"speed_rpm": float(rpm), "whirl_frequency": seen[min(seen, key=lambda s: abs(s - rpm))]["wd"],
            "evaluations": len(seen)}


def growth_rate(t, orbit, period: float, t_from: float) -> float:
    """Exponential growth rate [1/s] of an orbit's amplitude: a straight line through log(peak |q|) per period.

    Parameters
    ----------
    t : array_like
        Times [s].
    orbit : array_like
        (len(t), 2) displacements from the equilibrium (``run_time_response``'s ``orbits_ross``).
    period : float
        The whirl period [s]: the window of each peak.
    t_from : float
        Start of the fit [s] (after the faster modes have died out).

    Returns
    -------
    float
        The slope of log amplitude over time (> 0: the whirl grows).
    """
    t = np.asarray(t, dtype=float)
    r = np.linalg.norm(np.asarray(orbit, dtype=float), axis=1)
    edges = np.arange(t_from, t[-1] - period, period)
    if edges.size < 3:
        raise ValueError(f"too short a run for a growth rate: t_end={t[-1]!r}, t_from={t_from!r}, period={period!r}")
    idx = np.searchsorted(t, edges)
    peaks = np.array([r[a:b].max() for a, b in zip(idx[:-1], idx[1:])])
    times = np.array([t[a:b][np.argmax(r[a:b])] for a, b in zip(idx[:-1], idx[1:])])
    return float(np.polyfit(times, np.log(peaks), 1)[0])


def jeffcott_rotor(n_elements: int = 4, length: float = 0.5, diameter: float = 0.05, disc_mass: float = 20.0,
                   disc_inertia: tuple[float, float] = (0.05, 0.1)):
    """A ROSS Jeffcott rotor: a steel shaft of ``n_elements`` Timoshenko elements, a disc at the middle node,
    bearing nodes 0 and ``n_elements`` (their elements are placeholders for the films).

    Parameters
    ----------
    n_elements : int, default 4
        Shaft elements (even: the disc sits on the middle node).
    length, diameter : float, default 0.5, 0.05
        Shaft length and diameter [m].
    disc_mass : float, default 20.0
        Disc mass [kg].
    disc_inertia : tuple of float, default (0.05, 0.1)
        Diametral and polar moments of inertia of the disc [kg m^2].

    Returns
    -------
    ross.Rotor
        The rotor (bearing nodes 0 and ``n_elements``, disc node ``n_elements // 2``).
    """
    import ross as rs

    if n_elements < 2 or n_elements % 2:
        raise ValueError(f"n_elements must be an even number >= 2, got {n_elements!r}")
    shaft = [rs.ShaftElement(length / n_elements, idl=0.0, odl=diameter, material=rs.materials.steel,
                             shear_effects=True, rotary_inertia=True, gyroscopic=True) for _ in range(n_elements)]
    disc = rs.DiskElement(n=n_elements // 2, m=disc_mass, Id=disc_inertia[0], Ip=disc_inertia[1])
    placeholders = [rs.BearingElement(n=0, kxx=1e8, cxx=0.0), rs.BearingElement(n=n_elements, kxx=1e8, cxx=0.0)]
    return rs.Rotor(shaft, [disc], placeholders)
