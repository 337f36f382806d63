"""An isotropic linear spring-damper 'bearing': F = -K X - C V.

Not a film model: an exactly solvable force model with the same interface,
used to check the integrator against analytic responses.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from fluidfilm.core.bearing import JournalBearing
from fluidfilm.core.force_model import ReferenceModel


class LinearParams(NamedTuple):
    stiffness: float  # K [N/m]
    damping: float    # C [N s/m]


@njit(cache=True)
def linear_force(params, x1, x2, v1, v2):
    """Force kernel (``LinearParams``)."""
    k, c = params.stiffness, params.damping
    return -k * x1 - c * v1, -k * x2 - c * v2


class LinearBearing(ReferenceModel):
    """F = -K X - C V on ``bearing`` (its clearance bounds the journal): ``stiffness`` K [N/m], ``damping`` C [N s/m].

    A physics-based model in the protocol's sense (``ReferenceModel``: valid everywhere, nothing counted).
    """

    name = "linear"

    def __init__(self, bearing: JournalBearing, stiffness: float, damping: float):
        self._bearing = bearing
        self.stiffness = stiffness
        self.damping = damping

    def __repr__(self) -> str:
        return f"LinearBearing(bearing={self._bearing!r}, stiffness={self.stiffness!r}, damping={self.damping!r})"

    @property
    def force_kernel(self):
        return linear_force, LinearParams(float(self.stiffness), float(self.damping))

    def forces(self, X, V) -> np.ndarray:
        X = np.asarray(X, dtype=float)
        V = np.asarray(V, dtype=float)
        return -self.stiffness * X - self.damping * V
