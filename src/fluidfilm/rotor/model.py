"""``Rotor``: the point mass of the paper's eq. 4 as one bearing sees it; ``SpeedSchedule``: its shaft speed in time."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


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


RPM = 2.0 * math.pi / 60.0  # rad/s per rpm


@dataclass(frozen=True, eq=False)
class SpeedSchedule:
    """The shaft speed against time, omega(t): piecewise linear through a table, held before and after it.

    Made with ``SpeedSchedule.ramp`` (a linear run-up or run-down) or ``SpeedSchedule.table`` (any
    sequence of ramps and holds); ``simulate(..., speed=schedule)`` drives the rotor with it. The
    rotation angle is phi(t) = integral of omega from 0 to t (``angle``), not omega(t) t: the
    imbalance turns with the shaft.

    Parameters
    ----------
    times : array_like, shape (n,)
        Times [s] of the table, strictly increasing and finite (n >= 1).
    omega : array_like, shape (n,)
        Shaft speeds [rad/s] at those times, finite and > 0.

    Raises
    ------
    ValueError
        Naming the value: times that are not finite or not strictly increasing, a speed that is not
        finite or not positive, arrays of different or zero length, a ramp without a duration.

    Examples
    --------
    >>> from fluidfilm.rotor import SpeedSchedule
    >>> up = SpeedSchedule.ramp(start_rpm=3000.0, end_rpm=6000.0, duration=2.0, t_start=1.0)
    >>> [round(v) for v in up.speed_rpm([0.0, 2.0, 5.0])]        # held, half-way, held
    [3000, 4500, 6000]
    >>> round(float(up.angle(1.0)), 4), round(float(up.angle(3.0)) / (2 * 3.141592653589793), 6)   # revolutions
    (314.1593, 200.0)
    >>> SpeedSchedule.table(times=[0.0, 1.0], speeds_rpm=[3000.0, -10.0])
    Traceback (most recent call last):
    ...
    ValueError: speeds must be finite and > 0, got -10 rpm at t=1.0 s
    """

    times: np.ndarray
    omega: np.ndarray

    def __post_init__(self) -> None:
        t = np.array(self.times, dtype=float).reshape(-1)
        w = np.array(self.omega, dtype=float).reshape(-1)
        if t.size == 0 or t.size != w.size:
            raise ValueError(f"a speed schedule needs as many times as speeds (at least one), got {t.size} times "
                             f"and {w.size} speeds")
        if not np.isfinite(t).all():
            raise ValueError(f"schedule times must be finite, got {float(t[~np.isfinite(t)][0])!r} s")
        if t.size > 1 and not (np.diff(t) > 0.0).all():
            k = int(np.argmin(np.diff(t) > 0.0))
            raise ValueError(f"schedule times must increase strictly, got {float(t[k])!r} s then {float(t[k + 1])!r} s")
        bad = ~(np.isfinite(w) & (w > 0.0))
        if bad.any():
            k = int(np.argmax(bad))
            raise ValueError(f"speeds must be finite and > 0, got {w[k] / RPM:.6g} rpm at t={float(t[k])!r} s")
        t.flags.writeable = False
        w.flags.writeable = False
        object.__setattr__(self, "times", t)
        object.__setattr__(self, "omega", w)

    @classmethod
    def ramp(cls, start_rpm: float, end_rpm: float, duration: float, t_start: float = 0.0) -> "SpeedSchedule":
        """A linear change of speed from ``start_rpm`` to ``end_rpm`` over ``duration`` [s] from ``t_start`` [s]
        (held at ``start_rpm`` before it and at ``end_rpm`` after it)."""
        d = float(duration)
        if not (math.isfinite(d) and d > 0.0):
            raise ValueError(f"a ramp needs a finite duration > 0 s, got {duration!r}")
        return cls.table([t_start, float(t_start) + d], [start_rpm, end_rpm])

    @classmethod
    def table(cls, times, speeds_rpm) -> "SpeedSchedule":
        """Speeds ``speeds_rpm`` [rpm] at ``times`` [s], linear in between."""
        return cls(np.asarray(times, dtype=float), np.asarray(speeds_rpm, dtype=float) * RPM)

    @classmethod
    def constant(cls, speed_rpm: float) -> "SpeedSchedule":
        """One speed [rpm] at all times."""
        return cls.table([0.0], [speed_rpm])

    @property
    def is_constant(self) -> bool:
        """Whether the speed never changes."""
        return bool((self.omega == self.omega[0]).all())

    def omega_at(self, t):
        """omega(t) [rad/s] (scalar or array)."""
        return np.interp(t, self.times, self.omega)

    def speed_rpm(self, t):
        """omega(t) in rpm."""
        return self.omega_at(t) / RPM

    def acceleration(self, t):
        """d omega/dt [rad/s^2] (that of the segment holding t; 0 outside the table)."""
        t = np.asarray(t, dtype=float)
        if self.times.size == 1:
            return np.zeros_like(t)
        slope = np.diff(self.omega) / np.diff(self.times)
        k = np.clip(np.searchsorted(self.times, t, side="right") - 1, 0, slope.size - 1)
        inside = (t >= self.times[0]) & (t < self.times[-1])
        return np.where(inside, slope[k], 0.0)

    def angle(self, t):
        """The rotation angle phi(t) = integral of omega from 0 to t [rad] (exact for the piecewise-linear speed)."""
        t = np.asarray(t, dtype=float)
        nodes = np.concatenate([[0.0], self.times])
        order = np.argsort(nodes, kind="stable")
        nodes = nodes[order]
        w = self.omega_at(nodes)
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(nodes))])
        at0 = cum[int(np.searchsorted(nodes, 0.0))]
        k = np.clip(np.searchsorted(nodes, t, side="right") - 1, 0, nodes.size - 1)
        tk = nodes[k]
        wk = self.omega_at(tk)
        wt = self.omega_at(t)
        # below the first node the speed is held: the same trapezoid, backwards
        return cum[k] - at0 + 0.5 * (wk + wt) * (t - tk)
