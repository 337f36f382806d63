"""A journal bearing fed through an axial groove held at the supply pressure.

``ReynoldsSolver`` bounds the film by cavitation all the way round: nothing
pins the pressure anywhere on the circumference.  Real bearings are fed
through a groove (or hole); Raimondi & Boyd's (1958) tables, for example,
assume p = 0 (the supply pressure) on the line of maximum film thickness.
``GroovedReynoldsSolver`` adds that as an option: one full-length axial line
theta = ``groove_angle`` (fixed in the bearing, measured like theta: from +X2
towards +X1) at ``bearing.supply_pressure``.  The groove is a line of
nodes, not a band of finite width.

The groove breaks the separable fast solve, so the discrete system (the same
conservative finite-difference scheme, grid and Simpson integration as
``ReynoldsSolver``, see ``kernels``) is solved with the groove columns held
fixed: by direct sparse solves (``kernels.active_set_field``: one for the
linear system, an active-set iteration of them for Swift-Stieber; the
default) or, with ``method="psor"``, by (projected) SOR.  The grid is rotated so that the groove sits on
node 0: the computation is done in a frame turned by the groove angle, and
positions, velocities and forces are rotated in and out.
"""
from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from numba import njit

from fluidfilm.core.bearing import JournalBearing
from fluidfilm.core.states import as_state_pairs
from fluidfilm.reynolds import kernels
from fluidfilm.reynolds.params import SS_PSOR, FilmParams
from fluidfilm.reynolds.solver import CAVITATION_MODELS, ReynoldsSolver, _GridSolver

_CAV = {"none": kernels.CAV_NONE, "gumbel": kernels.CAV_GUMBEL, "swift-stieber": kernels.CAV_SWIFT_STIEBER}


class GroovedParams(NamedTuple):
    """Parameters of the grooved-bearing kernel (``grooved_force``)."""

    film: FilmParams            # the groove-free solver's kernel parameters (grid, film, SOR settings)
    cos_groove: float           # cos/sin of the groove angle: the turn into the groove frame
    sin_groove: float
    cavitation: int             # a ``Cavitation`` value
    fixed: np.ndarray           # (n_theta,) bool: node columns held at the supply pressure (the grooves)


@njit(cache=True)
def to_groove_frame(cos_g, sin_g, a1, a2):
    """Components of a bearing-frame vector in the frame whose theta = 0 is the groove."""
    return a1 * cos_g - a2 * sin_g, a1 * sin_g + a2 * cos_g


@njit(cache=True)
def from_groove_frame(cos_g, sin_g, b1, b2):
    """Inverse of ``to_groove_frame``."""
    return b1 * cos_g + b2 * sin_g, -b1 * sin_g + b2 * cos_g


@njit(cache=True)
def grooved_field(gparams, x1, x2, v1, v2, p, warm=None, warm_in=False):
    """Pressure field in the groove frame (boundaries, groove and cavitation applied); returns the number of
    SOR sweeps or direct solves (``params.ss_method``), or -1 if they did not converge.  ``warm``: the free
    (uncavitated) node set of the active-set solver (``kernels.active_set_field``), shape (n_theta, rows + 2),
    receives the solution's; with ``warm_in`` it is also the start (a nearby earlier state's)."""
    params = gparams.film
    cos_g = gparams.cos_groove
    sin_g = gparams.sin_groove
    cav = gparams.cavitation
    fixed = gparams.fixed
    y1, y2 = to_groove_frame(cos_g, sin_g, x1, x2)
    w1, w2 = to_groove_frame(cos_g, sin_g, v1, v2)
    n = params.n_theta
    nz = p.shape[1]
    p_s = params.p_supply
    # start from the groove-free linear field (clipped where cavitation applies): close to the answer (not
    # needed by a warm start: the free set is given, the interior values are solved for; nor by a cold
    # Swift-Stieber start of a symmetric field: the active-set iteration's first guess is then
    # ``kernels.mode_one_film``'s)
    direct = params.ss_method != SS_PSOR
    if direct and ((warm_in and warm is not None) or (cav == kernels.CAV_SWIFT_STIEBER and p_s == 0.0)):
        for i in range(n):
            p[i, 0] = p_s
            p[i, nz - 1] = 0.0
    else:
        kernels.linear_field(params, y1, y2, w1, w2, params.full_basis, p_s, p)
    for i in range(n):
        for j in range(1, nz - 1):
            if cav != kernels.CAV_NONE and p[i, j] < 0.0:
                p[i, j] = 0.0
    for i in range(n):
        if fixed[i]:
            for j in range(nz):
                p[i, j] = p_s
    # Swift-Stieber is the complementarity problem p >= 0 (active-set iteration, or Cryer's PSOR); the
    # other models solve the linear system (Gumbel clips afterwards)
    ss = cav == kernels.CAV_SWIFT_STIEBER
    if params.ss_method == SS_PSOR:
        it = kernels.sor_sweeps(params, y1, y2, w1, w2, p, fixed, ss, params.sor_omega, params.sor_tol,
                                params.sor_max_iter)
    else:
        it = kernels.active_set_field(params, (y1, y2, w1, w2), p, fixed, kernels.ActiveSetOptions(ss, n * nz, True),
                                      warm, warm_in)
    if cav == kernels.CAV_GUMBEL:
        for i in range(n):
            for j in range(nz):
                if p[i, j] < 0.0:
                    p[i, j] = 0.0
    return it


@njit(cache=True)
def grooved_force(gparams, x1, x2, v1, v2):
    """Force kernel of the grooved bearing (the compiled signature every force model shares)."""
    params = gparams.film
    n = params.n_theta
    nz = params.full_basis.shape[0] + 2
    p = np.empty((n, nz))
    it = grooved_field(gparams, x1, x2, v1, v2, p)
    if it < 0:
        raise RuntimeError("the grooved bearing's solver did not converge (with method='psor': raise sor_max_iter)")
    g1, g2 = kernels.integrate_field(params, p)
    return from_groove_frame(gparams.cos_groove, gparams.sin_groove, g1, g2)


@njit(cache=True)
def grooved_forces_warm(gparams, x, v, out, warm, warm_in):
    """``grooved_force`` for each row of x, v (groove frame in and out as there), each solve started from the
    free set the one before it left in ``warm`` (the first from ``warm`` if ``warm_in``, else cold): the
    states of an equilibrium search or a difference quotient lie close together, so most need one solve."""
    params = gparams.film
    n = params.n_theta
    nz = params.full_basis.shape[0] + 2
    p = np.empty((n, nz))
    for k in range(x.shape[0]):
        it = grooved_field(gparams, x[k, 0], x[k, 1], v[k, 0], v[k, 1], p, warm, warm_in or k > 0)
        if it < 0:
            raise RuntimeError("the grooved bearing's solver did not converge (with method='psor': raise sor_max_iter)")
        g1, g2 = kernels.integrate_field(params, p)
        out[k, 0], out[k, 1] = from_groove_frame(gparams.cos_groove, gparams.sin_groove, g1, g2)


class GroovedReynoldsSolver(_GridSolver):
    """Finite-length Reynolds solver with an axial feed groove at ``groove_angle`` [rad] held at the supply pressure.

    >>> s = GroovedReynoldsSolver(bearing, 90, 61, cavitation="swift-stieber", groove_angle=math.pi)
    >>> F = s.forces(X, V)

    Same interface as ``ReynoldsSolver`` (``forces``, ``pressure``,
    ``force_kernel``, ``bearing``, ``theta``, ``z``); ``pressure`` and
    ``theta`` are in the groove frame (theta = 0 at the groove).
    ``n_grooves`` > 1 places that many grooves equally spaced from
    ``groove_angle`` (e.g. 2: the common two-axial-groove bearing, grooves at
    +-90 deg from a vertical load line with ``groove_angle=pi/2``);
    ``n_theta`` must be a multiple of it.  ``groove_width`` [rad]: each groove
    holds the supply pressure at the nodes within +-width/2 of its centre (0: a line).
    ``method``: ``"active-set"`` (direct sparse solves, for every cavitation model; the default) or
    ``"psor"`` ((projected) SOR with the ``sor_*`` settings, as before; for comparison).
    """

    def __init__(self, bearing: JournalBearing, n_theta: int = 60, n_z: int = 31, cavitation: str = "swift-stieber",
                 groove_angle: float = math.pi, n_grooves: int = 1, groove_width: float = 0.0, sor_omega: float | None = None, sor_tol: float = 1e-11,
                 sor_max_iter: int = 400_000, method: str = "active-set"):
        if cavitation not in CAVITATION_MODELS:
            raise ValueError(f"unknown cavitation model {cavitation!r}; choose one of {CAVITATION_MODELS}")
        g = float(groove_angle)
        if not math.isfinite(g):
            raise ValueError(f"groove_angle must be a finite angle in rad, got {groove_angle!r}")
        self._options: dict[str, Any] = {"n_theta": n_theta, "n_z": n_z, "cavitation": cavitation, "groove_angle": groove_angle,
                         "n_grooves": n_grooves, "groove_width": groove_width, "sor_omega": sor_omega,
                         "sor_tol": sor_tol, "sor_max_iter": sor_max_iter, "method": method}
        # the groove-free solver provides the grid, the kernel parameters and the starting field
        self._base = ReynoldsSolver(bearing, n_theta, n_z, cavitation=cavitation, sor_omega=sor_omega,
                                    sor_tol=sor_tol, sor_max_iter=sor_max_iter, method=method)
        self.cavitation = cavitation
        self.method = method
        self.groove_angle = g
        ng = int(n_grooves)
        if ng < 1 or ng != n_grooves or n_theta % ng:
            raise ValueError(f"n_grooves must be a positive integer dividing n_theta={n_theta}, got {n_grooves!r}")
        width = float(groove_width)
        if not (math.isfinite(width) and 0.0 <= width < 2.0 * math.pi / ng):
            raise ValueError(f"groove_width must lie in [0, 2 pi / n_grooves) rad, got {groove_width!r}")
        fixed = np.zeros(n_theta, dtype=np.bool_)
        dth = 2.0 * math.pi / n_theta
        half = int(math.floor(0.5 * width / dth + 1e-9))  # nodes within +-width/2 of a groove centre
        for centre in range(0, n_theta, n_theta // ng):
            for k in range(-half, half + 1):
                fixed[(centre + k) % n_theta] = True
        self.n_grooves = ng
        self.gparams = GroovedParams(self._base.params, math.cos(g), math.sin(g), _CAV[cavitation], fixed)
        self._c = bearing.clearance
        self._bearing = bearing
        self.mesh = self._base.mesh
        self._warm: np.ndarray | None = None  # the last Swift-Stieber free set (``forces``' warm start)

    # --- read-only description (bearing, n_theta, n_z, theta, z: _GridSolver, on the groove-free solver's mesh) ---
    def _separable(self) -> bool:
        return False  # the groove couples the axial modes: no factorisation shared between velocities


    def with_speed(self, speed_rpm: float) -> "GroovedReynoldsSolver":
        """The same bearing, grooves, grid and solver settings at another shaft speed [rpm] (finite, >= 0).

        Parameters
        ----------
        speed_rpm : float
            Shaft speed [rpm].

        Returns
        -------
        GroovedReynoldsSolver
        """
        import dataclasses

        return GroovedReynoldsSolver(dataclasses.replace(self._bearing, speed_rpm=speed_rpm), **self._options)

    @property
    def force_kernel(self):
        return grooved_force, self.gparams

    def __repr__(self) -> str:
        return (f"GroovedReynoldsSolver({self.n_theta}x{self.n_z}, cavitation={self.cavitation!r}, "
                f"groove_angle={math.degrees(self.groove_angle):.4g} deg)")

    def forces(self, X, V) -> np.ndarray:
        """Film force [N] at positions X [m] and velocities V [m/s], shape (..., 2).  With Swift-Stieber
        cavitation and the active-set method each call starts from the cavitation set of the call before
        (the solution is the same, unique one; a nearby state needs fewer solves)."""
        x, v, shape = as_state_pairs(X, V, self._c)
        out = np.empty_like(x)
        if self.cavitation == "swift-stieber" and self.method != "psor" and x.shape[0]:
            warm_in = self._warm is not None
            if self._warm is None:
                m = self.n_z - 2
                rows = (m + 1) // 2 if self._base.params.p_supply == 0.0 else m
                self._warm = np.zeros((self.n_theta, rows + 2), dtype=np.bool_)
            grooved_forces_warm(self.gparams, x, v, out, self._warm, warm_in)
        else:
            for k in range(x.shape[0]):
                out[k] = grooved_force(self.gparams, x[k, 0], x[k, 1], v[k, 0], v[k, 1])
        return out.reshape(shape + (2,))

    def to_groove_frame(self, a) -> np.ndarray:
        """A bearing-frame vector (position, velocity) in the groove frame."""
        a = np.asarray(a, dtype=float).reshape(2)
        return np.array(to_groove_frame(self.gparams.cos_groove, self.gparams.sin_groove, a[0], a[1]))

    def pressure(self, x, v) -> np.ndarray:
        """Pressure field [Pa], shape (n_theta, n_z), on the groove-frame grid (theta = 0 at the groove)."""
        xa, va, _ = as_state_pairs(x, v, self._c)
        if xa.shape[0] != 1:
            raise ValueError(f"pressure takes one position and one velocity, got shapes {np.shape(x)}, {np.shape(v)}")
        p = np.empty((self.n_theta, self.n_z))
        it = grooved_field(self.gparams, xa[0, 0], xa[0, 1], va[0, 0], va[0, 1], p)
        if it < 0:
            raise RuntimeError("the grooved bearing's solver did not converge (with method='psor': raise sor_max_iter)")
        return p
