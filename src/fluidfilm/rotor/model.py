"""``Rotor``: the point mass of the paper's eq. 4 as one bearing sees it."""
from __future__ import annotations

import math
from dataclasses import dataclass


def ramped(start: float, final: float, t: float, ramp_time: float) -> float:
    """A value growing uniformly from ``start`` at t = 0 to ``final`` at t = ``ramp_time``, then held.

    The one definition of the imbalance ramp (paper Fig. 5's developing fault): ``Rotor``, the
    compiled integrator (``integrate._acceleration`` runs it jitted) and the control environment.
    """
    return start + (final - start) * min(max(t / ramp_time, 0.0), 1.0)


@dataclass(frozen=True)
class Rotor:
    """What one bearing carries (paper eq. 4), SI units.

    ``mass`` [kg], ``imbalance`` m_u*d [kg m], ``external_force`` (F1, F2) [N]
    constant, ``gravity`` [m/s^2] acting along +X2.  ``imbalance_direction``:
    +1 applies the imbalance force as eq. 4 writes it, m_u d w^2 (cos wt, sin wt);
    -1 makes it turn the other way, (cos wt, -sin wt), i.e. with the journal
    surface, which moves towards +theta (from +X2 towards +X1) in the
    conventions' frame.  The paper's eq. 4 is the default.

    ``imbalance_final`` and ``ramp_time``: the imbalance grows uniformly from
    ``imbalance`` at t = 0 to ``imbalance_final`` at t = ``ramp_time`` and stays
    there (the paper's Fig. 5 scenario, a fault developing over 5 s); by
    default it is constant.

    A rotor on two equal bearings is expressed by what each carries (half
    the mass, imbalance and load), see ``Rotor.shared``.

    Parameters
    ----------
    mass : float
        Mass carried by the bearing [kg], > 0.
    imbalance : float, default 0.0
        Imbalance m_u*d [kg m] (at t = 0 when it ramps), >= 0.
    external_force : (float, float), default (0.0, 0.0)
        Constant external force (F1, F2) on the journal [N], besides gravity.
    gravity : float, default 9.81
        Acceleration of gravity along +X2 [m/s^2].
    imbalance_direction : {1, -1}, default 1
        Sense of rotation of the imbalance force (see above).
    imbalance_final : float or None, default None
        Imbalance at the end of the ramp [kg m]; None: constant.
    ramp_time : float, default 0.0
        Duration of the imbalance ramp [s]; > 0 where ``imbalance_final`` differs from ``imbalance``.

    Raises
    ------
    ValueError
        Naming the field: a mass <= 0, a negative imbalance, a non-finite value, an external force
        that is not two numbers, a direction other than +-1, or a ramp without a duration.

    Examples
    --------
    >>> from fluidfilm import Rotor
    >>> rotor = Rotor(mass=2.5, imbalance=1e-4, external_force=(10.0, 0.0))
    >>> [round(f, 3) for f in rotor.static_load()]          # (W1, W2) [N]: the weight on +X2
    [10.0, 24.525]
    >>> Rotor.shared(5.0, total_imbalance=2e-4, load_share=0.5).mass   # one of two equal bearings
    2.5
    >>> Rotor(mass=0.0)
    Traceback (most recent call last):
    ...
    ValueError: mass must be a positive finite number in kg, got 0.0
    """

    mass: float
    imbalance: float = 0.0
    external_force: tuple[float, float] = (0.0, 0.0)
    gravity: float = 9.81
    imbalance_direction: int = 1
    imbalance_final: float | None = None
    ramp_time: float = 0.0

    def __post_init__(self) -> None:
        m = float(self.mass)
        if not math.isfinite(m) or m <= 0.0:
            raise ValueError(f"mass must be a positive finite number in kg, got {self.mass!r}")
        u = float(self.imbalance)
        if not math.isfinite(u) or u < 0.0:
            raise ValueError(f"imbalance must be a finite m_u*d >= 0 in kg m, got {self.imbalance!r}")
        f = tuple(float(v) for v in self.external_force)
        if len(f) != 2 or not all(math.isfinite(v) for v in f):
            raise ValueError(f"external_force must be two finite numbers (F1, F2) in N, got {self.external_force!r}")
        g = float(self.gravity)
        if not math.isfinite(g):
            raise ValueError(f"gravity must be finite, got {self.gravity!r}")
        if self.imbalance_direction not in (1, -1):
            raise ValueError(f"imbalance_direction must be +1 or -1, got {self.imbalance_direction!r}")
        object.__setattr__(self, "mass", m)
        object.__setattr__(self, "imbalance", u)
        object.__setattr__(self, "external_force", f)
        object.__setattr__(self, "gravity", g)
        if self.imbalance_final is not None:
            u1 = float(self.imbalance_final)
            if not math.isfinite(u1) or u1 < 0.0:
                raise ValueError(f"imbalance_final must be a finite m_u*d >= 0 in kg m, got {self.imbalance_final!r}")
            object.__setattr__(self, "imbalance_final", u1)
        rt = float(self.ramp_time)
        if not math.isfinite(rt) or rt < 0.0:
            raise ValueError(f"ramp_time must be a finite time >= 0 s, got {self.ramp_time!r}")
        if self.imbalance_final is not None and self.imbalance_final != u and rt == 0.0:
            raise ValueError("an imbalance ramp (imbalance_final != imbalance) needs ramp_time > 0 s")
        object.__setattr__(self, "ramp_time", rt)

    def imbalance_at(self, t) -> float:
        """m_u*d at time t [kg m] (the ramp, if any)."""
        if self.imbalance_final is None or self.ramp_time == 0.0:
            return self.imbalance
        return ramped(self.imbalance, self.imbalance_final, t, self.ramp_time)

    @classmethod
    def shared(cls, total_mass: float, total_imbalance: float = 0.0, total_external_force=(0.0, 0.0),
               load_share: float = 1.0, **kwargs) -> "Rotor":
        """The part of a rotor one bearing carries: ``load_share`` = 1 (one bearing) or 0.5 (two equal ones)."""
        s = float(load_share)
        if not 0.0 < s <= 1.0:
            raise ValueError(f"load_share must lie in (0, 1], got {load_share!r}")
        return cls(mass=total_mass * s, imbalance=total_imbalance * s,
                   external_force=(s * float(total_external_force[0]), s * float(total_external_force[1])), **kwargs)

    def static_load(self) -> tuple[float, float]:
        """Constant load on the bearing: weight plus external force [N]."""
        return (self.external_force[0], self.external_force[1] + self.mass * self.gravity)
