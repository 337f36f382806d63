"""An isotropic linear spring-damper 'bearing': F = -K X - C V.

Not a film model: an exactly solvable force model with the same interface,
used to check the integrator against analytic responses.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from fluidfilm.core.bearing import JournalBearing
from fluidfilm.core.force_model import ReferenceModel, check_precision
from fluidfilm.reynolds.kernels import kernel_rows


class LinearParams(NamedTuple):
    stiffness: float  # K [N/m]
    damping: float    # C [N s/m]


@njit(cache=True)
def linear_force(params, x1, x2, v1, v2):
    """Force kernel (``LinearParams``)."""
    k, c = params.stiffness, params.damping
    return -k * x1 - c * v1, -k * x2 - c * v2


@njit(cache=True)
def linear_force_at_speed(params, omega, x1, x2, v1, v2):
    """Speed kernel (``core.force_model.SpeedScalableModel``): a spring-damper does not depend on the speed."""
    return linear_force(params, x1, x2, v1, v2)


@njit(cache=True)
def linear_forces(params, x, v, out):
    """``linear_force`` of every row of x, v (m, 2) into out (m, 2) (the batched kernel)."""
    kernel_rows(linear_force, params, x, v, out)


class LinearBearing(ReferenceModel):
    """An isotropic spring-damper force model, F = -K X - C V [N]: not a film, an exact check.

    It has the force-model interface (``forces``, ``force_kernel``, ``bearing``, ...): a physics-based
    model in the protocol's sense (``ReferenceModel``: valid everywhere, nothing counted), so the
    integrator runs it as any film model; its responses are known in closed form.

    Parameters
    ----------
    bearing : JournalBearing
        Gives the clearance (the radius the journal must stay inside) and the speed omega.
    stiffness : float
        K [N/m].
    damping : float
        C [N s/m].

    Examples
    --------
    >>> from fluidfilm import LinearBearing, paper_bearing
    >>> spring = LinearBearing(paper_bearing(), stiffness=1e6, damping=1e3)
    >>> spring.forces([0.0, 1e-5], [0.01, 0.0]).tolist()        # -K X - C V [N]
    [-10.0, -10.0]
    """

    name = "linear"

    def __init__(self, bearing: JournalBearing, stiffness: float, damping: float):
        self._bearing = bearing
        self.stiffness = stiffness
        self.damping = damping

    def __repr__(self) -> str:
        return f"LinearBearing(bearing={self._bearing!r}, stiffness={self.stiffness!r}, damping={self.damping!r})"

    def with_speed(self, speed_rpm: float) -> "LinearBearing":
        """The same K and C on the bearing at another shaft speed [rpm] (the spring-damper does not depend on
        it; the speed sets the imbalance's frequency and the step check's shaft period).

        Parameters
        ----------
        speed_rpm : float
            Shaft speed [rpm], finite and >= 0.

        Returns
        -------
        LinearBearing
        """
        import dataclasses

        return LinearBearing(dataclasses.replace(self._bearing, speed_rpm=speed_rpm), self.stiffness, self.damping)

    @property
    def force_kernel(self):
        return linear_force, LinearParams(float(self.stiffness), float(self.damping))

    def speed_kernel(self):
        """``(linear_force_at_speed, params)``: the same -K X - C V at every shaft speed (run-ups)."""
        return linear_force_at_speed, self.force_kernel[1]

    def batch_force_kernel(self, precision: str = "float64", private: bool = False):
        """``(linear_forces, params)`` (``core.force_model.BatchForceModel``), float64 whatever ``precision``."""
        check_precision(precision)
        return linear_forces, self.force_kernel[1]

    def forces(self, X, V) -> np.ndarray:
        """-K X - C V [N] for positions X [m] and velocities V [m/s], (..., 2) each."""
        X = np.asarray(X, dtype=float)
        V = np.asarray(V, dtype=float)
        return -self.stiffness * X - self.damping * V
