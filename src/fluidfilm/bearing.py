"""Bearing description: geometry, lubricant and operating point, in SI units.

Plain frozen dataclasses, as in ROSS: they carry numbers and derived
quantities, no solver state.  Everything the Reynolds solver needs to know
about the bearing is here.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass


def _require_positive(name: str, value: float) -> float:
    value = float(value)
    if not math.isfinite(value) or value <= 0.0:
        raise ValueError(f"{name} must be a positive finite number, got {value!r}")
    return value


@dataclass(frozen=True)
class JournalBearing:
    """A plain cylindrical journal bearing with a fixed sleeve.

    Parameters (SI): ``length`` L [m], ``diameter`` D [m] (of the bearing bore,
    R = D/2 is used as the film radius), ``clearance`` c [m] (radial),
    ``speed_rpm`` shaft speed [rev/min], ``viscosity`` mu [Pa s],
    ``supply_pressure`` gauge pressure at the supply end z = 0 [Pa],
    ``density`` rho [kg/m^3] (only used for the Couette Reynolds number).
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
        speed = float(self.speed_rpm)
        if not math.isfinite(speed) or speed < 0.0:
            raise ValueError(f"speed_rpm must be a finite non-negative number, got {speed!r}")
        object.__setattr__(self, "speed_rpm", speed)
        supply = float(self.supply_pressure)
        if not math.isfinite(supply) or supply < 0.0:
            raise ValueError(
                f"supply_pressure must be a finite gauge pressure >= 0 Pa, got {supply!r}"
            )
        object.__setattr__(self, "supply_pressure", supply)
        if self.clearance >= 0.5 * self.diameter:
            raise ValueError(
                f"clearance {self.clearance!r} m must be far smaller than the radius "
                f"{0.5 * self.diameter!r} m"
            )

    # --- derived quantities -------------------------------------------------
    @property
    def radius(self) -> float:
        return 0.5 * self.diameter

    @property
    def omega(self) -> float:
        """Shaft angular speed [rad/s]."""
        return self.speed_rpm * 2.0 * math.pi / 60.0

    @property
    def slenderness(self) -> float:
        """L/D."""
        return self.length / self.diameter

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

    def sommerfeld(self, load: float) -> float:
        """Sommerfeld number S = (R/c)^2 * mu * N / P, N in rev/s, P = W/(L D)."""
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
