"""The paper's grid policy: a coarse grid below an eccentricity threshold, a dense one above.

Section 2 of the paper: 30x30 for low eccentricities and 55x55 for higher
ones, because the coarse grid's error grows sharply towards the sleeve
(Fig. 2).  The threshold is not given in the paper; 0.9 (where its dataset
sections split) is our default and a config value.
"""
from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from numba import njit

from fluidfilm.core.bearing import ConicalBearing, JournalBearing
from fluidfilm.core.force_model import ReferenceModel, check_precision
from fluidfilm.core.states import as_state_pairs
from fluidfilm.reynolds import kernels
from fluidfilm.reynolds.conical import ConicalReynoldsSolver
from fluidfilm.reynolds.params import FilmParams
from fluidfilm.reynolds.solver import ReynoldsSolver


class GradedParams(NamedTuple):
    """Kernel parameters of the graded model: both grids' and the radius [m] where the dense one starts."""

    coarse: FilmParams
    dense: FilmParams
    dense_radius: float


def make_solver(bearing: JournalBearing | ConicalBearing, n_theta: int, n_z: int,
                cavitation: str = "gumbel") -> ReynoldsSolver | ConicalReynoldsSolver:
    """The finite-difference solver for this kind of bearing (cylindrical or conical).

    Parameters
    ----------
    bearing : JournalBearing or ConicalBearing
        The bearing.
    n_theta : int
        Circumferential nodes.
    n_z : int
        Axial nodes.
    cavitation : str, default "gumbel"
        Cavitation rule (see ``ReynoldsSolver``).

    Returns
    -------
    ReynoldsSolver or ConicalReynoldsSolver

    Examples
    --------
    >>> from fluidfilm import paper_bearing
    >>> from fluidfilm.reynolds import make_solver
    >>> make_solver(paper_bearing(), 16, 8)
    ReynoldsSolver(16x8, cavitation='gumbel')
    """
    if isinstance(bearing, ConicalBearing):
        return ConicalReynoldsSolver(bearing, n_theta, n_z, cavitation=cavitation)
    return ReynoldsSolver(bearing, n_theta, n_z, cavitation=cavitation)


@njit(cache=True)
def graded_force(params, x1, x2, v1, v2):
    """Force kernel of the graded model (``GradedParams``)."""
    if x1 * x1 + x2 * x2 < params.dense_radius * params.dense_radius:
        return kernels.film_force(params.coarse, x1, x2, v1, v2)
    return kernels.film_force(params.dense, x1, x2, v1, v2)


@njit(cache=True)
def graded_force_ss(params, x1, x2, v1, v2):
    """``graded_force`` with Swift-Stieber cavitation."""
    if x1 * x1 + x2 * x2 < params.dense_radius * params.dense_radius:
        return kernels.film_force_ss(params.coarse, x1, x2, v1, v2)
    return kernels.film_force_ss(params.dense, x1, x2, v1, v2)


@njit(cache=True)
def graded_forces(params, x, v, out):
    """``graded_force`` (``graded_force_ss`` with Swift-Stieber cavitation) of every row of x, v (m, 2) into
    out (m, 2), in the calling thread (``simulate_batch``'s stage kernel; it runs its own threads over chunks
    of trajectories)."""
    if params.coarse.cavitation == kernels.CAV_SWIFT_STIEBER:
        kernels.kernel_rows(graded_force_ss, params, x, v, out)
    else:
        kernels.kernel_rows(graded_force, params, x, v, out)


class GradedReynoldsModel(ReferenceModel):
    """Reference force model with the paper's grid policy (same interface as ``ReynoldsSolver``).

    For a conical bearing (matched cones) the sub-solvers run the conical
    fast path and ``set_sleeve`` moves the sleeve of both; eccentricities are
    then relative to the current clearance c_r(s).

    Parameters
    ----------
    bearing : JournalBearing or ConicalBearing
        The bearing.
    coarse : (int, int), default (30, 30)
        (n_theta, n_z) below ``eps_threshold``.
    dense : (int, int), default (55, 55)
        (n_theta, n_z) at and above ``eps_threshold``.
    eps_threshold : float, default 0.9
        Eccentricity ratio where the dense grid starts, in (0, 1].
    cavitation : str, default "gumbel"
        Cavitation rule (see ``ReynoldsSolver``).

    Raises
    ------
    ValueError
        For an ``eps_threshold`` outside (0, 1], a conical bearing with tapered cones, or what
        the sub-solvers refuse.

    Examples
    --------
    >>> from fluidfilm import GradedReynoldsModel, paper_bearing
    >>> model = GradedReynoldsModel(paper_bearing(), coarse=(16, 8), dense=(24, 12))
    >>> [n.tolist() for n in model.grid_for([0.5, 0.95])]          # n_theta, n_z per eps
    [[16, 24], [8, 12]]
    >>> model.forces([0.0, 60e-6], [0.0, 0.0]).round(2).tolist()   # eps 0.5: the coarse grid [N]
    [16.94, -7.68]
    """

    def __init__(self, bearing: JournalBearing | ConicalBearing, coarse: tuple[int, int] = (30, 30),
                 dense: tuple[int, int] = (55, 55),
                 eps_threshold: float = 0.9, cavitation: str = "gumbel"):
        if not 0.0 < float(eps_threshold) <= 1.0:
            raise ValueError(f"eps_threshold must lie in (0, 1], got {eps_threshold!r}")
        self.coarse = make_solver(bearing, *coarse, cavitation=cavitation)
        self.dense = make_solver(bearing, *dense, cavitation=cavitation)
        if isinstance(self.coarse, ConicalReynoldsSolver) and self.coarse.method != "fast":
            raise ValueError("the graded model needs the fast solver path (a conical bearing with matched cones)")
        self.eps_threshold = float(eps_threshold)
        self.cavitation = cavitation
        self._rebuild()
        ss = cavitation == "swift-stieber"
        self._kernel = graded_force_ss if ss else graded_force
        self._options: dict[str, Any] = {"coarse": tuple(coarse), "dense": tuple(dense), "eps_threshold": eps_threshold,
                         "cavitation": cavitation}

    def with_speed(self, speed_rpm: float) -> "GradedReynoldsModel":
        """The same bearing, grids and threshold at another shaft speed [rpm] (finite, >= 0).

        Parameters
        ----------
        speed_rpm : float
            Shaft speed [rpm].

        Returns
        -------
        GradedReynoldsModel
        """
        import dataclasses

        return GradedReynoldsModel(dataclasses.replace(self.bearing, speed_rpm=speed_rpm), **self._options)

    def _rebuild(self) -> None:
        self.params = GradedParams(self.coarse.params, self.dense.params, self.eps_threshold * self.clearance)

    @property
    def clearance(self) -> float:
        """Radial clearance at the current setting [m]."""
        return self.coarse.clearance

    @property
    def adjustable(self) -> bool:
        """True for a conical bearing, whose sleeve moves."""
        return isinstance(self.coarse, ConicalReynoldsSolver)

    @property
    def sleeve(self) -> float:
        return self.coarse.sleeve if isinstance(self.coarse, ConicalReynoldsSolver) else 0.0

    def set_sleeve(self, sleeve: float) -> None:
        """Move the sleeve of an active (conical) bearing [m]."""
        if not (isinstance(self.coarse, ConicalReynoldsSolver) and isinstance(self.dense, ConicalReynoldsSolver)):
            raise ValueError(f"{type(self.bearing).__name__} has no sleeve to move")
        self.coarse.set_sleeve(sleeve)
        self.dense.set_sleeve(sleeve)
        self._rebuild()

    @property
    def bearing(self) -> JournalBearing | ConicalBearing:
        return self.coarse.bearing

    @property
    def force_kernel(self):
        return self._kernel, self.params

    def batch_force_kernel(self, precision: str = "float64", private: bool = False):
        """``(graded_forces, params)`` (``core.force_model.BatchForceModel``): each row exactly ``force_kernel``'s
        force, in float64 whatever ``precision``; nothing to count, nothing mutable (``private`` changes nothing)."""
        check_precision(precision)
        return graded_forces, self.params

    def grid_for(self, eps) -> tuple[np.ndarray, np.ndarray]:
        """(n_theta, n_z) the policy uses at eccentricity ratio(s) ``eps``."""
        dense = np.asarray(eps) >= self.eps_threshold
        n_theta = np.where(dense, self.dense.n_theta, self.coarse.n_theta)
        n_z = np.where(dense, self.dense.n_z, self.coarse.n_z)
        return n_theta, n_z

    def forces_product(self, X, V, eps=None) -> np.ndarray:
        """Forces for every velocity at every position: X (P, 2), V (Q, 2) -> (P, Q, 2).

        Each position on its grid (``eps``: the positions' eccentricity ratios, when the caller
        has them exactly, e.g. a dataset grid; by default |X| / clearance); one factorisation per
        position serves all its velocities.
        """
        x = np.asarray(X, dtype=np.float64).reshape(-1, 2)
        e = np.hypot(x[:, 0], x[:, 1]) / self.clearance if eps is None else np.asarray(eps, dtype=float).ravel()
        dense = e >= self.eps_threshold
        out = np.empty((x.shape[0], np.asarray(V).reshape(-1, 2).shape[0], 2))
        for solver, rows in ((self.coarse, ~dense), (self.dense, dense)):
            if rows.any():
                out[rows] = solver.forces_product(x[rows], V)
        return out

    def forces(self, X, V) -> np.ndarray:
        """Film force [N] at positions X [m] and velocities V [m/s], (..., 2), each state on its grid."""
        x, v, shape = as_state_pairs(X, V, self.clearance)
        out = np.empty_like(x)
        dense = x[:, 0] * x[:, 0] + x[:, 1] * x[:, 1] >= self.params.dense_radius * self.params.dense_radius
        # each sub-batch runs the solvers' own parallel kernels (numba's parallel
        # loops cannot take the nested parameter tuple of ``graded_force``)
        for solver, rows in ((self.coarse, ~dense), (self.dense, dense)):
            if rows.any():
                out[rows] = solver.forces(x[rows], v[rows])
        return out.reshape(shape + (2,))

    def __repr__(self) -> str:
        return (f"GradedReynoldsModel({self.coarse.n_theta}x{self.coarse.n_z} below eps "
                f"{self.eps_threshold}, {self.dense.n_theta}x{self.dense.n_z} above, {self.cavitation!r})")
