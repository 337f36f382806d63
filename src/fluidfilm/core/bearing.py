"""Bearing description: geometry, lubricant and operating point, in SI units.

Plain frozen dataclasses, as in ROSS: they carry numbers and derived
quantities, no solver state.  Everything the Reynolds solver needs to know
about the bearing is here.
"""
from __future__ import annotations

import math
import numbers
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING

#: the largest radial clearance accepted, as a fraction of the film radius: the Reynolds equation is the
#: thin-film limit (it drops terms of order c/R, the film's curvature and the pressure change across it),
#: so at c/R = 0.1 its error is already ~10 %; real journal bearings have c/R ~ 1e-3
MAX_CLEARANCE_RATIO = 0.1


def _real(name: str, value) -> float:
    """``value`` as a finite float; a bool, a string or anything else that is not a real number is refused
    (``float("abc")`` or ``float(True)`` would otherwise fail without the field's name, or pass)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name} must be a number, got {value!r} ({type(value).__name__})")
    v = float(value)
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return v


def _require_positive(name: str, value) -> float:
    v = _real(name, value)
    if v <= 0.0:
        raise ValueError(f"{name} must be a positive finite number, got {value!r}")
    return v


def _require_non_negative(name: str, value, what: str = "number") -> float:
    v = _real(name, value)
    if v < 0.0:
        raise ValueError(f"{name} must be a finite {what} >= 0, got {value!r}")
    return v


def _check_clearance_ratio(clearance: float, radius: float) -> None:
    if clearance >= MAX_CLEARANCE_RATIO * radius:
        raise ValueError(f"clearance {clearance!r} m is {clearance / radius:.3g} of the radius {radius!r} m; "
                         f"the thin-film (Reynolds) model needs c/R < {MAX_CLEARANCE_RATIO} (typically ~1e-3)")


class _FilmScales:
    """Derived scales shared by every bearing (needs radius, clearance, length, speed_rpm, viscosity, density)."""

    if TYPE_CHECKING:  # supplied by the dataclasses that use this mixin
        clearance: float
        length: float
        speed_rpm: float
        viscosity: float
        density: float

        @property
        def radius(self) -> float: ...

    @property
    def omega(self) -> float:
        """Shaft angular speed [rad/s]."""
        return self.speed_rpm * 2.0 * math.pi / 60.0

    @property
    def force_scale(self) -> float:
        """Film-force scale mu*omega*R*L*(R/c)^2 [N]: forces divided by it are O(1)."""
        r = self.radius
        return self.viscosity * self.omega * r * self.length * (r / self.clearance) ** 2

    @property
    def couette_reynolds(self) -> float:
        """rho*omega*R*c/mu; laminar Reynolds theory assumes it is well below Taylor's limit."""
        return self.density * self.omega * self.radius * self.clearance / self.viscosity

    @property
    def taylor_limit(self) -> float:
        """Couette Reynolds number at which Taylor vortices appear, 41.3*sqrt(R/c)."""
        return 41.3 * math.sqrt(self.radius / self.clearance)


@dataclass(frozen=True)
class JournalBearing(_FilmScales):
    """A plain cylindrical journal bearing with a fixed sleeve (frozen; SI units).

    The frame of every force model built on it: X1 horizontal, X2 along gravity; the angle theta
    runs from +X2 towards +X1 and the journal surface moves towards +theta (docs/conventions.md).

    Parameters
    ----------
    length : float
        Axial length L [m].
    diameter : float
        Bore diameter D [m]; R = D/2 is the film radius.
    clearance : float
        Radial clearance c [m]; c/R below ``MAX_CLEARANCE_RATIO`` (the Reynolds equation drops terms of
        order c/R).
    speed_rpm : float
        Shaft speed [rpm], >= 0 (0 is a pure squeeze film, which carries no static load).
    viscosity : float
        Dynamic viscosity mu of the lubricant [Pa s].
    supply_pressure : float, default 0.0
        Gauge pressure at the supply end z = 0 [Pa], >= 0.
    density : float, default 992.0
        Lubricant density rho [kg/m^3] (only used for the Couette Reynolds number).

    Raises
    ------
    ValueError
        Naming the field and the value, for a value that is not a real number (a bool or a string
        included) or not finite, a length, diameter, clearance, viscosity or density <= 0, a negative
        supply pressure or speed, or a clearance not far smaller than the radius.

    Examples
    --------
    >>> from fluidfilm import JournalBearing
    >>> b = JournalBearing(length=0.02, diameter=0.04, clearance=50e-6, speed_rpm=6000, viscosity=0.02)
    >>> round(b.omega, 3), b.slenderness          # [rad/s], L/D
    (628.319, 0.5)
    >>> round(b.sommerfeld(1000.0), 4)            # S under 1000 N
    0.256
    >>> JournalBearing(0.02, 0.04, -50e-6, 6000, 0.02)
    Traceback (most recent call last):
    ...
    ValueError: clearance must be a positive finite number, got -5e-05
    """

    length: float
    diameter: float
    clearance: float
    speed_rpm: float
    viscosity: float
    supply_pressure: float = 0.0
    density: float = 992.0

    def __post_init__(self) -> None:
        for name in ("length", "diameter", "clearance", "viscosity", "density"):
            object.__setattr__(self, name, _require_positive(name, getattr(self, name)))
        object.__setattr__(self, "speed_rpm", _require_non_negative("speed_rpm", self.speed_rpm))
        object.__setattr__(self, "supply_pressure",
                           _require_non_negative("supply_pressure", self.supply_pressure, "gauge pressure in Pa"))
        _check_clearance_ratio(self.clearance, 0.5 * self.diameter)

    # --- derived quantities -------------------------------------------------
    @property
    def radius(self) -> float:
        return 0.5 * self.diameter

    @property
    def slenderness(self) -> float:
        """L/D."""
        return self.length / self.diameter

    def sommerfeld(self, load: float) -> float:
        """Sommerfeld number S = (R/c)^2 * mu * N / P, N in rev/s, P = W/(L D), of a load magnitude W [N] > 0."""
        load = _require_positive("load", load)
        p_mean = load / (self.length * self.diameter)
        return (self.radius / self.clearance) ** 2 * self.viscosity * (self.speed_rpm / 60.0) / p_mean

    def to_dict(self) -> dict:
        """The fields as a plain dict (what ``from_dict`` and the dataset metadata take)."""
        return asdict(self)

    @classmethod
    def from_dict(cls, cfg) -> "JournalBearing":
        """Build from a mapping (e.g. a Hydra/OmegaConf node); extra keys like ``name`` are ignored."""
        keys = ("length", "diameter", "clearance", "speed_rpm", "viscosity", "supply_pressure", "density")
        missing = [k for k in ("length", "diameter", "clearance", "speed_rpm", "viscosity") if k not in cfg]
        if missing:
            raise ValueError(f"bearing config is missing keys: {missing}")
        return cls(**{k: cfg[k] for k in keys if k in cfg})


def paper_bearing(supply_pressure: float = 0.0) -> JournalBearing:
    """The paper's test bearing (docs/conventions.md): L=64 mm, D=40 mm, c=120 um, 3000 rpm, water at 40 C.

    Parameters
    ----------
    supply_pressure : float, default 0.0
        Gauge pressure at the supply end z = 0 [Pa].

    Returns
    -------
    JournalBearing
        mu = 6.53e-4 Pa s, rho = 992 kg/m^3.

    Examples
    --------
    >>> from fluidfilm import paper_bearing
    >>> b = paper_bearing()
    >>> b.length, b.diameter, b.clearance, b.speed_rpm
    (0.064, 0.04, 0.00012, 3000.0)
    >>> f"{b.force_scale:.4g}"                    # mu omega R L (R/c)^2 [N]
    '7.294'
    """
    return JournalBearing(
        length=0.064,
        diameter=0.040,
        clearance=120e-6,
        speed_rpm=3000.0,
        viscosity=6.53e-4,
        supply_pressure=supply_pressure,
        density=992.0,
    )


@dataclass(frozen=True)
class ConicalBearing(_FilmScales):
    """An adjustable conical journal bearing: the film lies between two coaxial cones (frozen; SI units).

    The journal radius grows linearly along the axis, from ``diameter_small/2``
    at the supply end z = 0 to ``diameter_large/2`` at z = L (half-cone angle
    alpha = atan((r1 - r0)/L)).  The sleeve can slide axially; ``s`` is its
    displacement towards the journal's small end (towards -z).  The bore then
    faces a thinner part of the journal, so s > 0 opens the radial clearance
    by s tan(alpha) and s < 0 (towards the large end) closes it,

        c_r(s) = clearance + s tan(alpha),

    which is how the active bearing changes its average film thickness.
    ``clearance_taper`` is the radial clearance at z = L minus that at z = 0
    (a sleeve cone angle slightly off the journal's); 0 for matched cones,
    where the film thickness does not depend on z.  ``sleeve_min`` and
    ``sleeve_max`` bound the sleeve travel [m].  The frame (X1, X2 with +X2 along gravity) is the
    journal bearing's.

    Parameters
    ----------
    length : float
        Axial length L [m].
    diameter_small : float
        Journal diameter at the supply end z = 0 [m].
    diameter_large : float
        Journal diameter at z = L [m], >= ``diameter_small``.
    clearance : float
        Nominal radial clearance c at the supply end, sleeve at s = 0 [m].
    speed_rpm : float
        Shaft speed [rpm], >= 0.
    viscosity : float
        Dynamic viscosity mu [Pa s].
    supply_pressure : float, default 0.0
        Gauge pressure at z = 0 [Pa], >= 0.
    density : float, default 992.0
        Lubricant density [kg/m^3].
    clearance_taper : float, default 0.0
        Radial clearance at z = L minus that at z = 0 [m].
    sleeve_min, sleeve_max : float, default 0.0
        Bounds of the sleeve's axial travel s [m].

    Raises
    ------
    ValueError
        Naming the field, for a non-finite or non-positive geometry or viscosity, a negative speed
        or supply pressure, ``diameter_large < diameter_small``, ``sleeve_min > sleeve_max``, a sleeve
        position in the travel that closes the film, or a clearance not far smaller than the radius.

    Examples
    --------
    >>> import math
    >>> from fluidfilm import ConicalBearing
    >>> b = ConicalBearing(length=0.05, diameter_small=0.04, diameter_large=0.05, clearance=100e-6,
    ...                    speed_rpm=3000, viscosity=6.53e-4, sleeve_min=-0.5e-3, sleeve_max=0.5e-3)
    >>> round(b.radius, 4), round(math.degrees(b.half_angle), 3)   # mean radius [m], alpha [deg]
    (0.0225, 5.711)
    >>> f"{b.clearance_at(0.2e-3):.3g}"            # s = +0.2 mm opens the clearance [m]
    '0.00012'
    """

    length: float
    diameter_small: float
    diameter_large: float
    clearance: float
    speed_rpm: float
    viscosity: float
    supply_pressure: float = 0.0
    density: float = 992.0
    clearance_taper: float = 0.0
    sleeve_min: float = 0.0
    sleeve_max: float = 0.0

    kind = "conical"

    def __post_init__(self) -> None:
        for name in ("length", "diameter_small", "diameter_large", "clearance", "viscosity", "density"):
            object.__setattr__(self, name, _require_positive(name, getattr(self, name)))
        for name in ("speed_rpm", "supply_pressure"):
            object.__setattr__(self, name, _require_non_negative(name, getattr(self, name)))
        for name in ("clearance_taper", "sleeve_min", "sleeve_max"):
            object.__setattr__(self, name, _real(name, getattr(self, name)))
        if self.diameter_large < self.diameter_small:
            raise ValueError(f"diameter_large {self.diameter_large!r} m must be >= diameter_small "
                             f"{self.diameter_small!r} m (the cone opens towards z = L)")
        if self.sleeve_min > self.sleeve_max:
            raise ValueError(f"sleeve_min {self.sleeve_min!r} must not exceed sleeve_max {self.sleeve_max!r}")
        for s in (self.sleeve_min, self.sleeve_max):
            c0 = self.clearance_at(s, check_travel=False)
            if min(c0, c0 + self.clearance_taper) <= 0.0:
                raise ValueError(f"sleeve position {s!r} m closes the film (radial clearance {c0!r} m, "
                                 f"taper {self.clearance_taper!r} m)")
        _check_clearance_ratio(self.clearance, 0.5 * self.diameter_small)

    # --- derived quantities -------------------------------------------------
    @property
    def radius_small(self) -> float:
        return 0.5 * self.diameter_small

    @property
    def radius_large(self) -> float:
        return 0.5 * self.diameter_large

    @property
    def radius(self) -> float:
        """Mean journal radius [m] (used for scales, not by the solver)."""
        return 0.25 * (self.diameter_small + self.diameter_large)

    @property
    def diameter(self) -> float:
        return 2.0 * self.radius

    @property
    def tan_half_angle(self) -> float:
        return (self.radius_large - self.radius_small) / self.length

    @property
    def half_angle(self) -> float:
        """Half-cone angle alpha [rad]."""
        return math.atan(self.tan_half_angle)

    @property
    def couette_reynolds(self) -> float:
        """At the large end, where the surface is fastest (scales use the mean radius and nominal clearance)."""
        return self.density * self.omega * self.radius_large * self.clearance / self.viscosity

    def clearance_at(self, sleeve: float, check_travel: bool = True) -> float:
        """Radial clearance at the supply end [m] with the sleeve displaced axially by ``sleeve`` [m];
        a ``ValueError`` outside the travel (when ``check_travel``) or for a non-finite value."""
        s = float(sleeve)
        if not math.isfinite(s):
            raise ValueError(f"sleeve displacement must be finite, got {s!r}")
        if check_travel and not (self.sleeve_min - 1e-12 <= s <= self.sleeve_max + 1e-12):
            raise ValueError(f"sleeve displacement {s!r} m lies outside the travel "
                             f"[{self.sleeve_min!r}, {self.sleeve_max!r}] m")
        return self.clearance + s * self.tan_half_angle

    def to_dict(self) -> dict:
        d = asdict(self)
        d["kind"] = self.kind
        return d

    @classmethod
    def from_dict(cls, cfg) -> "ConicalBearing":
        keys = ("length", "diameter_small", "diameter_large", "clearance", "speed_rpm", "viscosity",
                "supply_pressure", "density", "clearance_taper", "sleeve_min", "sleeve_max")
        missing = [k for k in keys[:6] if k not in cfg]
        if missing:
            raise ValueError(f"conical bearing config is missing keys: {missing}")
        return cls(**{k: cfg[k] for k in keys if k in cfg})


def bearing_from_dict(cfg):
    """A bearing from a mapping: ``kind: conical`` gives a ``ConicalBearing``, otherwise a ``JournalBearing``.

    Parameters
    ----------
    cfg : Mapping
        The bearing's fields in SI units and rpm (a dict, a Hydra/OmegaConf node); ``kind`` is
        ``"journal"`` (the default) or ``"conical"``; extra keys such as ``name`` are ignored.

    Returns
    -------
    JournalBearing or ConicalBearing

    Raises
    ------
    ValueError
        For an unknown ``kind``, missing keys (named) or an invalid value (see the classes).

    Examples
    --------
    >>> from fluidfilm import bearing_from_dict
    >>> bearing_from_dict({"name": "mine", "length": 0.02, "diameter": 0.04, "clearance": 50e-6,
    ...                    "speed_rpm": 6000, "viscosity": 0.02})
    JournalBearing(length=0.02, diameter=0.04, clearance=5e-05, speed_rpm=6000.0, viscosity=0.02,
                   supply_pressure=0.0, density=992.0)
    >>> bearing_from_dict({"kind": "tilting-pad"})
    Traceback (most recent call last):
    ...
    ValueError: unknown bearing kind 'tilting-pad'; choose 'journal' or 'conical'
    """
    kind = cfg.get("kind", "journal") if hasattr(cfg, "get") else "journal"
    if kind == "conical":
        return ConicalBearing.from_dict(cfg)
    if kind != "journal":
        raise ValueError(f"unknown bearing kind {kind!r}; choose 'journal' or 'conical'")
    return JournalBearing.from_dict(cfg)
