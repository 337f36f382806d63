"""A reference like the paper's: the same finite-difference system assembled as a sparse matrix and
solved by a sparse direct solver on every call.

The paper's numerical model (a MATLAB finite-difference solver) assembles
the discrete Reynolds equation and solves it directly for each force.  Our
``ReynoldsSolver`` solves the *same* discrete system far faster (a sine
transform in z and one periodic tridiagonal solve per mode, compiled), so
a surrogate's speed-up over it says little about the paper's 12x.  This
model is the plain way: per call, fill the five-point stencil's values into
a sparse matrix (scipy.sparse, CSC), factorise it with SuperLU
(``scipy.sparse.linalg.splu``), solve, clip negative pressures (Gumbel) and
integrate with the same Simpson weights.  Only the stencil's index pattern
is built once, as any solver reuses its mesh.  The grid policy is the
paper's: 30x30 below the eccentricity threshold, 55x55 above.

Its forces equal ``GradedReynoldsModel``'s to rounding (tests check 0.1 %).

For the rotor integrator, which calls a compiled force kernel, the model
offers ``force_kernel`` as a numba function that calls back into Python
(``numba.objmode``) for each force: the integrator is the same, and the
callback's overhead (microseconds) is small beside a sparse solve
(milliseconds).
"""
from __future__ import annotations

import math
import weakref

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numba import njit, objmode

from fluidfilm.core.bearing import JournalBearing
from fluidfilm.core.force_model import ReferenceModel
from fluidfilm.core.states import as_state_pairs
from fluidfilm.reynolds.mesh import FilmMesh


class SparseGridSolver:
    """One grid: the stencil pattern is fixed, its values and the factorisation are made per call."""

    def __init__(self, bearing: JournalBearing, n_theta: int, n_z: int, cavitation: str = "gumbel"):
        if cavitation not in ("gumbel", "none"):
            raise ValueError(f"the sparse reference supports cavitation 'gumbel' or 'none', got {cavitation!r}")
        self.bearing = bearing
        self.cavitation = cavitation
        self.mesh = FilmMesh(n_theta, n_z, bearing.length)
        r, c, mu = bearing.radius, bearing.clearance, bearing.viscosity
        n, m = self.mesh.n_theta, self.mesh.n_z - 2
        self.n, self.m = n, m
        dth = self.mesh.dtheta
        self.inv_dth2 = 1.0 / dth**2
        self.inv_dth = 1.0 / dth
        self.inv_dzeta2 = (r / self.mesh.dz) ** 2
        self.th = self.mesh.theta
        self.thf = self.mesh.theta + 0.5 * dth
        self.k_omega = 6.0 * mu * bearing.omega * r**2 / c**2
        self.k_v = 12.0 * mu * r**2 / c**3
        self.p_supply = float(bearing.supply_pressure)
        self.c = c
        self.r = r
        # stencil pattern: unknown (i, j) -> i*m + j, j = 0..m-1 the interior axial nodes
        i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
        row = (i * m + j).ravel()
        west = (((i - 1) % n) * m + j).ravel()
        east = (((i + 1) % n) * m + j).ravel()
        jn = j.ravel()
        down = jn > 0
        up = jn < m - 1
        self._rows = np.concatenate([row, row, row, row[down], row[up]])
        self._cols = np.concatenate([row, west, east, row[down] - 1, row[up] + 1])
        self._down, self._up = down, up
        self._i = i.ravel()
        self._first_row = jn == 0  # next to the supply end z = 0
        self.w_theta = self.mesh.w_theta
        self.w_z = self.mesh.w_z
        self.shape = (n * m, n * m)

    def linear_pressure(self, x1, x2, v1, v2) -> np.ndarray:
        """Pressure (n_theta, n_z) before cavitation, both ends included."""
        e1, e2 = x1 / self.c, x2 / self.c
        H = 1.0 - e1 * np.sin(self.th) - e2 * np.cos(self.th)
        Hf = 1.0 - e1 * np.sin(self.thf) - e2 * np.cos(self.thf)
        Hb = np.roll(Hf, 1)  # face theta_{i-1/2}
        aw = Hb**3 * self.inv_dth2
        ae = Hf**3 * self.inv_dth2
        an = H**3 * self.inv_dzeta2
        i = self._i
        diag = -(aw + ae + 2.0 * an)[i]
        vals = np.concatenate([diag, aw[i], ae[i], an[i][self._down], an[i][self._up]])
        A = sp.csc_matrix((vals, (self._rows, self._cols)), shape=self.shape)
        rhs_theta = self.k_omega * (Hf - Hb) * self.inv_dth + self.k_v * (-v1 * np.sin(self.th) - v2 * np.cos(self.th))
        b = rhs_theta[i].copy()
        if self.p_supply:
            b[self._first_row] -= an[i][self._first_row] * self.p_supply
        p_int = spla.splu(A).solve(b)
        p = np.zeros((self.n, self.m + 2))
        p[:, 0] = self.p_supply
        p[:, 1:-1] = p_int.reshape(self.n, self.m)
        return p

    def pressure(self, x1, x2, v1, v2) -> np.ndarray:
        p = self.linear_pressure(x1, x2, v1, v2)
        if self.cavitation == "gumbel":
            np.maximum(p, 0.0, out=p)
        return p

    def force(self, x1, x2, v1, v2) -> tuple[float, float]:
        p = self.pressure(x1, x2, v1, v2)
        col = p @ self.w_z
        wc = self.w_theta * col
        return (-self.r * float(wc @ np.sin(self.th)), -self.r * float(wc @ np.cos(self.th)))


# Python objects the compiled callback kernel reaches by number (numba kernels take no Python objects)
_REGISTRY: "weakref.WeakValueDictionary[int, SparseReferenceModel]" = weakref.WeakValueDictionary()


def _python_force(key, x1, x2, v1, v2):
    return _REGISTRY[int(key)].force(x1, x2, v1, v2)


@njit
def sparse_callback_force(params, x1, x2, v1, v2):
    """Force kernel with the solver's signature that calls the sparse reference back in Python."""
    with objmode(f1="float64", f2="float64"):
        f1, f2 = _python_force(params[0], x1, x2, v1, v2)
    return f1, f2


class SparseReferenceModel(ReferenceModel):
    """Paper-like reference: 30x30 below ``eps_threshold``, 55x55 above, sparse direct solve per call.

    A force model like every other (``fluidfilm.core.force_model.ForceModel``): valid in the whole film.
    """

    def __init__(self, bearing: JournalBearing, coarse=(30, 30), dense=(55, 55), eps_threshold: float = 0.9,
                 cavitation: str = "gumbel"):
        if not isinstance(bearing, JournalBearing):
            raise ValueError(f"bearing must be a JournalBearing, got {type(bearing).__name__}")
        if not 0.0 < float(eps_threshold) <= 1.0:
            raise ValueError(f"eps_threshold must lie in (0, 1], got {eps_threshold!r}")
        self._bearing = bearing
        self.coarse = SparseGridSolver(bearing, int(coarse[0]), int(coarse[1]), cavitation=cavitation)
        self.dense = SparseGridSolver(bearing, int(dense[0]), int(dense[1]), cavitation=cavitation)
        self.eps_threshold = float(eps_threshold)
        key = id(self)
        _REGISTRY[key] = self
        self.params = (np.int64(key),)

    @property
    def name(self) -> str:
        return "sparse_reference"

    @property
    def force_kernel(self):
        return sparse_callback_force, self.params

    def force(self, x1, x2, v1, v2) -> tuple[float, float]:
        eps = math.hypot(x1, x2) / self._bearing.clearance
        solver = self.coarse if eps < self.eps_threshold else self.dense
        return solver.force(x1, x2, v1, v2)

    def forces(self, X, V) -> np.ndarray:
        x, v, shape = as_state_pairs(X, V, self._bearing.clearance)
        out = np.array([self.force(*x[k], *v[k]) for k in range(len(x))]).reshape(-1, 2)
        return out.reshape(shape + (2,))

    def __repr__(self) -> str:
        return (f"SparseReferenceModel({self.coarse.n}x{self.coarse.m + 2} below eps {self.eps_threshold}, "
                f"{self.dense.n}x{self.dense.m + 2} above, splu per call)")
