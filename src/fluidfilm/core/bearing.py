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
    """A plain cylindrical journal bearing with a fixed sleeve.

    Parameters (SI): ``length`` L [m], ``diameter`` D [m] (of the bearing bore,
    R = D/2 is used as the film radius), ``clearance`` c [m] (radial, c/R <
    ``MAX_CLEARANCE_RATIO``), ``speed_rpm`` shaft speed [rev/min] (>= 0: 0 is a
    pure squeeze film, which carries no static load), ``viscosity`` mu [Pa s],
    ``supply_pressure`` gauge pressure at the supply end z = 0 [Pa],
    ``density`` rho [kg/m^3] (only used for the Couette Reynolds number).
    Every field is a real number (not a bool or a string), finite, positive
    unless stated; a bad one raises ValueError naming the field and the value.
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
    """The paper's test bearing (CONVENTIONS.md): L=64 mm, D=40 mm, c=120 um, 3000 rpm, water at 40 C."""
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
    """An adjustable conical journal bearing: the film lies between two coaxial cones.

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
    ``sleeve_max`` bound the sleeve travel [m].
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
        """Radial clearance at the supply end [m] with the sleeve displaced axially by ``sleeve`` [m]."""
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
    """A bearing from a mapping: ``kind: conical`` gives a ``ConicalBearing``, otherwise a ``JournalBearing``."""
    kind = cfg.get("kind", "journal") if hasattr(cfg, "get") else "journal"
    if kind == "conical":
        return ConicalBearing.from_dict(cfg)
    if kind != "journal":
        raise ValueError(f"unknown bearing kind {kind!r}; choose 'journal' or 'conical'")
    return JournalBearing.from_dict(cfg)
