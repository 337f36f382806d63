"""Grid of the film and the Simpson weights used to integrate over it.

Nodes: ``n_theta`` distinct angles theta_i = 2*pi*i/n_theta (periodic, node
n_theta is node 0 again) and ``n_z`` axial nodes z_j = L*j/(n_z-1) including both
ends, where the pressure is prescribed (supply pressure at z = 0, ambient at
z = L).  So "30x30" means 30 angles and 30 axial nodes of which 28 are unknown.

theta is measured from the +X2 axis towards +X1 (so that the film thickness is
h = c - X1 sin(theta) - X2 cos(theta), CONVENTIONS.md).
"""
from __future__ import annotations

import numpy as np

MIN_N_THETA = 8
MIN_N_Z = 4


def simpson_weights(n_intervals: int, step: float) -> np.ndarray:
    """Composite Simpson weights for ``n_intervals`` equal intervals (n_intervals+1 nodes).

    An even interval count uses Simpson's 1/3 rule throughout.  An odd count
    uses the 1/3 rule on the first n-3 intervals and Simpson's 3/8 rule on the
    last three, which keeps fourth-order accuracy for smooth integrands.
    """
    n = int(n_intervals)
    if n < 2:
        raise ValueError(f"Simpson integration needs at least 2 intervals, got {n}")
    w = np.zeros(n + 1)
    if n % 2 == 0:
        n13 = n
        tail = 0
    else:
        if n < 3:
            raise ValueError(f"odd interval count {n} needs at least 3 intervals")
        n13 = n - 3
        tail = 3
    for k in range(0, n13, 2):
        w[k] += 1.0 / 3.0
        w[k + 1] += 4.0 / 3.0
        w[k + 2] += 1.0 / 3.0
    if tail:
        s = n13
        w[s] += 3.0 / 8.0
        w[s + 1] += 9.0 / 8.0
        w[s + 2] += 9.0 / 8.0
        w[s + 3] += 3.0 / 8.0
    return w * step


class FilmMesh:
    """Nodes, spacings and integration weights of an ``n_theta x n_z`` film grid."""

    def __init__(self, n_theta: int, n_z: int, length: float):
        for name, value, lo in (("n_theta", n_theta, MIN_N_THETA), ("n_z", n_z, MIN_N_Z)):
            if isinstance(value, bool) or int(value) != value:
                raise ValueError(f"{name} must be an integer, got {value!r}")
            if int(value) < lo:
                raise ValueError(f"{name}={value} is too small for the scheme (minimum {lo})")
        self.n_theta = int(n_theta)
        self.n_z = int(n_z)
        self.length = float(length)
        self.dtheta = 2.0 * np.pi / self.n_theta
        self.dz = self.length / (self.n_z - 1)
        self.theta = self.dtheta * np.arange(self.n_theta)
        self.z = self.dz * np.arange(self.n_z)
        # Periodic Simpson in theta: integrate over nodes 0..n_theta with the
        # closing node (theta = 2 pi) folded back onto node 0.
        wt = simpson_weights(self.n_theta, self.dtheta)
        wt[0] += wt[-1]
        self.w_theta = wt[:-1].copy()
        self.w_z = simpson_weights(self.n_z - 1, self.dz)
