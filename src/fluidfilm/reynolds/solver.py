"""``ReynoldsSolver``: the finite-length Reynolds equation of a journal bearing by finite differences.

The discretisation and the fast separable solve are described in
``kernels``; this module validates input, builds the kernel parameters and
offers the public, vectorised API shared by every force model:

    solver.forces(X, V)  (..., 2) m, (..., 2) m/s -> (..., 2) N
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from fluidfilm.core.bearing import JournalBearing
from fluidfilm.core.force_model import ReferenceModel, check_precision
from fluidfilm.core.states import V_MAX_PHYSICAL, as_state_pairs, check_states
from fluidfilm.reynolds import kernels
from fluidfilm.reynolds.mesh import FilmMesh
from fluidfilm.reynolds.params import SS_METHODS, Cavitation, FilmParams

CAVITATION_MODELS = ("gumbel", "swift-stieber", "none")


@njit(cache=True, inline="always")
def with_k_omega(p, k_omega):
    """``p`` (``FilmParams``) with the speed parameter K_omega = 6 mu omega R^2/c^2 replaced (numba has no
    ``_replace``: every field in order, the test suite checks the copy field by field)."""
    return FilmParams(p.n_theta, p.cavitation, p.sin_node, p.cos_node, p.sin_face, p.cos_face, p.inv_c,
                      p.inv_dtheta2, p.inv_dtheta, p.lam, p.sig, p.tau, p.inv_dzeta2, p.radius, k_omega, p.k_v,
                      p.supply_term, p.a_sin, p.a_cos, p.basis, p.w_rec, p.boundary, p.w_z, p.sor_omega, p.sor_tol,
                      p.sor_max_iter, p.full_basis, p.p_supply, p.ss_method)


@njit(cache=True)
def film_force_at_speed(sparams, omega, x1, x2, v1, v2):
    """``kernels.film_force`` at shaft speed ``omega`` [rad/s]: the film's own speed parameter K_omega set for it.

    ``sparams``: (``FilmParams``, the speed omega_ref [rad/s] its K_omega was built for).  A speed kernel
    (``core.force_model.SpeedScalableModel``); at omega = omega_ref the force is ``film_force``'s to the bit.
    """
    p, w_ref = sparams
    return kernels.film_force(with_k_omega(p, p.k_omega * (omega / w_ref)), x1, x2, v1, v2)


@njit(cache=True)
def film_force_ss_at_speed(sparams, omega, x1, x2, v1, v2):
    """``kernels.film_force_ss`` (Swift-Stieber) at shaft speed ``omega``, as ``film_force_at_speed``."""
    p, w_ref = sparams
    return kernels.film_force_ss(with_k_omega(p, p.k_omega * (omega / w_ref)), x1, x2, v1, v2)


def build_params(bearing: JournalBearing, mesh: FilmMesh, cavitation: str | Cavitation,
                 sor_omega: float, sor_tol: float, sor_max_iter: int, method: str = "active-set") -> FilmParams:
    """Kernel parameters of the cylindrical bearing (``params.FilmParams``: the fields are named there).

    The axial modes are the sine modes of the second difference; with no supply
    pressure only the odd ones (the field is symmetric about mid-length) and
    only the nodes of one half are reconstructed (``basis``, ``w_rec``).
    """
    r = bearing.radius
    c = bearing.clearance
    mu = bearing.viscosity
    n = mesh.n_theta
    m = mesh.n_z - 2  # interior axial nodes
    dzeta = mesh.dz / r
    theta_f = mesh.theta + 0.5 * mesh.dtheta
    p_s = bearing.supply_pressure
    symmetric = p_s == 0.0
    k_all = np.arange(1, m + 1)
    # with no supply pressure the field is symmetric in z: even modes vanish exactly
    k_used = k_all[k_all % 2 == 1] if symmetric else k_all
    j_int = np.arange(1, m + 1)
    lam = -4.0 * np.sin(np.pi * k_used / (2.0 * (m + 1))) ** 2 / dzeta**2
    sig = (2.0 / (m + 1)) * np.sin(np.pi * np.outer(k_used, j_int) / (m + 1)).sum(axis=1)
    tau = (2.0 / (m + 1)) * np.sin(np.pi * k_used / (m + 1))
    full_basis = np.ascontiguousarray(np.sin(np.pi * np.outer(j_int, k_used) / (m + 1)))
    w_z = mesh.w_z
    if symmetric:
        j_rec = np.arange(1, (m + 1) // 2 + 1 + (0 if m % 2 == 0 else 0))
        j_rec = j_rec[j_rec <= m + 1 - j_rec]
        w_rec = np.array([w_z[j] + (w_z[m + 1 - j] if j != m + 1 - j else 0.0) for j in j_rec])
    else:
        j_rec = j_int
        w_rec = w_z[1:-1].copy()
    basis = np.ascontiguousarray(full_basis[j_rec - 1])
    a_sin = r * mesh.w_theta * np.sin(mesh.theta)
    a_cos = r * mesh.w_theta * np.cos(mesh.theta)
    return FilmParams(
        n_theta=n,
        cavitation=int(Cavitation.parse(cavitation)),
        sin_node=np.sin(mesh.theta), cos_node=np.cos(mesh.theta),
        sin_face=np.sin(theta_f), cos_face=np.cos(theta_f),
        inv_c=1.0 / c,
        inv_dtheta2=1.0 / mesh.dtheta**2, inv_dtheta=1.0 / mesh.dtheta,
        lam=lam, sig=sig, tau=tau,
        inv_dzeta2=1.0 / dzeta**2,
        radius=r,
        k_omega=6.0 * mu * bearing.omega * r**2 / c**2,
        k_v=12.0 * mu * r**2 / c**3,
        supply_term=-p_s / dzeta**2,
        a_sin=a_sin, a_cos=a_cos,
        basis=basis, w_rec=w_rec,
        boundary=w_z[0] * p_s,
        w_z=w_z.copy(),
        sor_omega=float(sor_omega), sor_tol=float(sor_tol), sor_max_iter=int(sor_max_iter),
        full_basis=full_basis,
        p_supply=float(p_s),
        ss_method=SS_METHODS.index(method),
    )


class _GridSolver(ReferenceModel):
    """Read-only description shared by the finite-difference solvers (``_bearing`` and ``mesh`` set by them)."""

    mesh: FilmMesh
    params: Any  # FilmParams, or GeneralParams on the conical general path
    _c: float

    def forces(self, X, V) -> np.ndarray:
        raise NotImplementedError

    def _separable(self) -> bool:
        raise NotImplementedError

    @property
    def n_theta(self) -> int:
        return self.mesh.n_theta

    @property
    def n_z(self) -> int:
        return self.mesh.n_z

    @property
    def theta(self) -> np.ndarray:
        return self.mesh.theta.copy()

    @property
    def z(self) -> np.ndarray:
        return self.mesh.z.copy()

    def _state_limit(self) -> float:
        """Radius [m] a journal position must stay inside."""
        return self._c

    def forces_product(self, X, V) -> np.ndarray:
        """Forces for every velocity at every position: X (P, 2), V (Q, 2) -> (P, Q, 2).

        On the fast path one factorisation per position serves all its
        velocities (positions run in parallel): the dataset generator's path.
        Otherwise (PSOR, the general conical path) pair by pair.
        """
        x = np.ascontiguousarray(np.asarray(X, dtype=np.float64).reshape(-1, 2))
        v = np.ascontiguousarray(np.asarray(V, dtype=np.float64).reshape(-1, 2))
        check_states(x, v, self._state_limit())
        if not self._separable():
            xx = np.repeat(x, v.shape[0], axis=0)
            vv = np.tile(v, (x.shape[0], 1))
            return self.forces(xx, vv).reshape(x.shape[0], v.shape[0], 2)
        out = np.empty((x.shape[0], v.shape[0], 2))
        if out.size:
            kernels.forces_product(self.params, x, v, out)
        return out


class ReynoldsSolver(_GridSolver):
    """Finite-difference solution of the finite-length Reynolds equation of a journal bearing.

    ``forces(X, V)`` gives the film's force on the journal [N] for positions X [m] and
    velocities V [m/s], shape (..., 2) each, in the (X1, X2) frame with +X2 along gravity;
    ``pressure(x, v)`` the (n_theta, n_z) field [Pa] of one state at ``theta`` x ``z``.  A state
    with eccentricity >= 1 or a non-finite value raises a ``ValueError`` naming it.

    Parameters
    ----------
    bearing : JournalBearing
        Geometry, lubricant and speed.
    n_theta : int, default 30
        Circumferential nodes (periodic).
    n_z : int, default 30
        Axial nodes, both ends included.
    cavitation : {"gumbel", "swift-stieber", "none"} or Cavitation, default "gumbel"
        ``"gumbel"`` (half-Sommerfeld: negative pressures set to zero after the linear solve; the
        paper's model), ``"swift-stieber"`` (Reynolds condition as a complementarity problem, see
        ``method``) or ``"none"`` (full Sommerfeld, negative pressures kept; for verification).
    sor_omega : float or None, default None
        Relaxation factor of the projected SOR, in (0, 2); None: near the optimum for the grid.
    sor_tol : float, default 1e-10
        Convergence tolerance of the projected SOR (> 0).
    sor_max_iter : int, default 200000
        Iteration limit of the projected SOR.
    method : {"active-set", "psor"}, default "active-set"
        Solver of the Swift-Stieber problem: a primal-dual active-set iteration of direct solves
        (``kernels.active_set_field``: exact up to round-off, typically 3-8 solves, most by the axial sine
        transform with a capacitance matrix on the cavitated nodes) or the projected
        SOR (``kernels.psor_swift_stieber``, converged to ``sor_tol``; kept for comparison).  Not used
        by the other cavitation models (one direct solve).

    Raises
    ------
    ValueError
        For a bearing that is not a ``JournalBearing``, an unknown cavitation model or method, a grid
        too small for the scheme, or SOR settings out of range (each named).

    Examples
    --------
    >>> from fluidfilm import ReynoldsSolver, paper_bearing
    >>> solver = ReynoldsSolver(paper_bearing(), n_theta=16, n_z=8)
    >>> solver.forces([0.0, 60e-6], [0.0, 0.0]).round(2).tolist()   # eps = 0.5 along +X2 [N]
    [16.94, -7.68]
    >>> solver.forces([[0.0, 60e-6], [60e-6, 0.0]], [0.0, 0.0]).shape   # a batch
    (2, 2)
    >>> solver.pressure([0.0, 60e-6], [0.0, 0.0]).shape
    (16, 8)
    >>> solver.forces([0.0, 120e-6], [0.0, 0.0])
    Traceback (most recent call last):
    ...
    ValueError: eccentricity ratio 1 >= 1 at X=(...) m: the journal touches the sleeve (clearance 0.00012 m)
    """

    def __init__(self, bearing: JournalBearing, n_theta: int = 30, n_z: int = 30,
                 cavitation: str | Cavitation = "gumbel", sor_omega: float | None = None,
                 sor_tol: float = 1e-10, sor_max_iter: int = 200_000, method: str = "active-set"):
        if not isinstance(bearing, JournalBearing):
            raise ValueError(f"bearing must be a JournalBearing, got {type(bearing).__name__}")
        if isinstance(cavitation, Cavitation):
            cavitation = cavitation.label
        if cavitation not in CAVITATION_MODELS:
            raise ValueError(f"unknown cavitation model {cavitation!r}; choose one of {CAVITATION_MODELS}")
        if method not in SS_METHODS:
            raise ValueError(f"unknown Swift-Stieber method {method!r}; choose one of {SS_METHODS}")
        self._bearing = bearing
        self.mesh = FilmMesh(n_theta, n_z, bearing.length)
        self.cavitation = cavitation
        self.method = method
        if sor_omega is None:
            # near the optimum of SOR for a Poisson-like operator on this grid
            sor_omega = 2.0 / (1.0 + math.sin(math.pi / max(self.mesh.n_theta, self.mesh.n_z)))
        if not 0.0 < sor_omega < 2.0:
            raise ValueError(f"sor_omega must lie in (0, 2), got {sor_omega!r}")
        if not sor_tol > 0.0:
            raise ValueError(f"sor_tol must be positive, got {sor_tol!r}")
        self._options: dict[str, Any] = {"n_theta": n_theta, "n_z": n_z, "cavitation": cavitation, "sor_omega": sor_omega,
                         "sor_tol": sor_tol, "sor_max_iter": sor_max_iter, "method": method}
        self.params = build_params(bearing, self.mesh, cavitation, sor_omega, sor_tol, sor_max_iter, method)
        self._c = bearing.clearance
        self._kernel = kernels.film_force_ss if cavitation == "swift-stieber" else kernels.film_force
        self._grid_warned = False

    @classmethod
    def converged(cls, bearing: JournalBearing, tol: float = 0.01, eps_max: float = 0.9,
                  cavitation: str = "gumbel", **options) -> "ReynoldsSolver":
        """A solver on the smallest square grid whose static force is within ``tol`` of the grid-converged
        one up to ``eps_max``, by the measured convergence table (``reynolds.grid``,
        ``benchmarks/grid_convergence.py``).

        Parameters
        ----------
        bearing : JournalBearing
            The bearing.
        tol : float, default 0.01
            Largest relative force error, > 0.
        eps_max : float, default 0.9
            Largest eccentricity ratio the solver will be asked about, in [0, 1).
        cavitation : str, default "gumbel"
            As the constructor.
        **options
            The constructor's other keywords (``sor_omega``, ``sor_tol``, ``sor_max_iter``, ``method``).

        Returns
        -------
        ReynoldsSolver

        Raises
        ------
        ValueError
            A bad ``tol`` or ``eps_max`` (named), or no tabulated grid up to 320x320 meets ``tol``.

        Examples
        --------
        >>> from fluidfilm import ReynoldsSolver, paper_bearing
        >>> ReynoldsSolver.converged(paper_bearing(), tol=0.01, eps_max=0.9)
        ReynoldsSolver(60x60, cavitation='gumbel')
        """
        from fluidfilm.reynolds.grid import converged_grid

        if not isinstance(bearing, JournalBearing):
            raise ValueError(f"bearing must be a JournalBearing, got {type(bearing).__name__}")
        label = cavitation.label if isinstance(cavitation, Cavitation) else cavitation
        if label not in CAVITATION_MODELS:
            raise ValueError(f"unknown cavitation model {cavitation!r}; choose one of {CAVITATION_MODELS}")
        n = converged_grid(tol, eps_max, bearing.slenderness, label)
        return cls(bearing, n, n, cavitation=label, **options)

    def with_speed(self, speed_rpm: float) -> "ReynoldsSolver":
        """The same bearing, grid and solver settings at another shaft speed [rpm].

        Parameters
        ----------
        speed_rpm : float
            Shaft speed [rpm], finite and >= 0 (``JournalBearing``'s check names a bad one).

        Returns
        -------
        ReynoldsSolver

        Examples
        --------
        >>> from fluidfilm import ReynoldsSolver, paper_bearing
        >>> ReynoldsSolver(paper_bearing(), 16, 8).with_speed(6000).bearing.speed_rpm
        6000.0
        """
        import dataclasses

        return ReynoldsSolver(dataclasses.replace(self._bearing, speed_rpm=speed_rpm), **self._options)

    def grid_error(self, eps: float) -> float:
        """Upper envelope of this grid's relative static-force error at eccentricity ``eps``
        (``reynolds.grid.grid_error``)."""
        from fluidfilm.reynolds.grid import grid_error

        return grid_error(self.n_theta, self.n_z, eps, self._bearing.slenderness, self.cavitation)

    def check_grid(self, eps: float) -> None:
        """Warn once per solver where its grid is too coarse at eccentricity ``eps``: the measured envelope
        of its force error (``grid_error``) above ``reynolds.grid.GRID_WARN_TOL`` (2 %).  ``forces`` calls
        it with the largest eccentricity asked, ``simulate`` and ``simulate_batch`` with the run's."""
        from fluidfilm.reynolds.grid import GRID_WARN_TOL

        if self._grid_warned or not math.isfinite(eps):
            return
        err = self.grid_error(eps)
        if err > GRID_WARN_TOL:
            self._grid_warned = True
            import warnings

            warnings.warn(
                f"{self!r}: asked at eccentricity {eps:.3g}, where this grid's force is up to {100 * err:.2g} % off a "
                f"converged grid (measured: benchmarks/grid_convergence.py); ReynoldsSolver.converged(bearing, "
                f"tol=0.01, eps_max={min(eps, 0.98):.3g}, cavitation={self.cavitation!r}) gives a grid that meets a "
                "tolerance", RuntimeWarning, stacklevel=3)

    # --- read-only description (bearing, n_theta, n_z, theta, z: _GridSolver) ---
    @property
    def force_kernel(self):
        """(compiled function, params): ``fn(params, x1, x2, v1, v2) -> (F1, F2)`` for compiled callers."""
        return self._kernel, self.params

    def speed_kernel(self):
        """``(fn, (params, omega_ref))``: the force at any shaft speed omega through the film's speed parameter
        K_omega = 6 mu omega R^2/c^2 (``core.force_model.SpeedScalableModel``, run-ups)."""
        fn = film_force_ss_at_speed if self.cavitation == "swift-stieber" else film_force_at_speed
        return fn, (self.params, float(self._bearing.omega))

    def batch_force_kernel(self, precision: str = "float64", private: bool = False):
        """``(kernels.forces_serial, params)`` (``core.force_model.BatchForceModel``): each row exactly
        ``force_kernel``'s force, in float64 whatever ``precision``; nothing to count, nothing mutable (``private`` changes nothing)."""
        check_precision(precision)
        return kernels.forces_serial, self.params

    def __repr__(self) -> str:
        return f"ReynoldsSolver({self.n_theta}x{self.n_z}, cavitation={self.cavitation!r})"

    # --- evaluation ------------------------------------------------------------
    def forces(self, X, V) -> np.ndarray:
        """Film force on the journal [N] at positions X [m] and velocities V [m/s], shape (..., 2)."""
        if np.shape(X) == (2,) and np.shape(V) == (2,):
            # single state: the path a Python-level integrator takes, kept lean
            x1, x2 = float(X[0]), float(X[1])
            v1, v2 = float(V[0]), float(V[1])
            if not (math.isfinite(x1) and math.isfinite(x2)):
                raise ValueError(f"position X must be finite, got {(x1, x2)}")
            if not (math.isfinite(v1) and math.isfinite(v2)):
                raise ValueError(f"velocity V must be finite, got {(v1, v2)}")
            eps = math.hypot(x1, x2) / self._c
            if eps >= 1.0 or math.hypot(v1, v2) > V_MAX_PHYSICAL:
                check_states(np.array([[x1, x2]]), np.array([[v1, v2]]), self._c)
            if not self._grid_warned:
                self.check_grid(eps)
            return np.array(self._kernel(self.params, x1, x2, v1, v2))
        x, v, shape = as_state_pairs(X, V, self._c)
        out = np.empty_like(x)
        if x.shape[0]:
            if not self._grid_warned:
                self.check_grid(float(np.hypot(x[:, 0], x[:, 1]).max()) / self._c)
            kernels.forces_batch(self.params, x, v, out)
        return out.reshape(shape + (2,))

    def _separable(self) -> bool:
        return self.cavitation != "swift-stieber"

    def pressure(self, x, v) -> np.ndarray:
        """Pressure field [Pa] of one state, shape (n_theta, n_z), after the cavitation model."""
        xa, va, shape = as_state_pairs(x, v, self._c)
        if xa.shape[0] != 1:
            raise ValueError(f"pressure takes one position and one velocity, got shapes {np.shape(x)}, {np.shape(v)}")
        x1, x2 = xa[0]
        v1, v2 = va[0]
        p = self.linear_pressure(xa[0], va[0])
        if self.cavitation == "none":
            return p
        np.maximum(p, 0.0, out=p)
        if self.cavitation == "swift-stieber":
            kernels.swift_stieber_field(self.params, x1, x2, v1, v2, p)
        return p

    def linear_pressure(self, x, v) -> np.ndarray:
        """Pressure field before any cavitation model (the full-Sommerfeld linear solution)."""
        xa, va, _ = as_state_pairs(x, v, self._c)
        out = np.empty((self.n_theta, self.n_z))
        kernels.linear_field(self.params, xa[0, 0], xa[0, 1], va[0, 0], va[0, 1],
                             self.params.full_basis, self.params.p_supply, out)
        return out

    def integrate(self, p) -> np.ndarray:
        """Force [N] of a pressure field on this grid by Simpson integration."""
        p = np.ascontiguousarray(p, dtype=np.float64)
        if p.shape != (self.n_theta, self.n_z):
            raise ValueError(f"pressure field must have shape {(self.n_theta, self.n_z)}, got {p.shape}")
        return np.array(kernels.integrate_field(self.params, p))
