"""One surrogate for any plain journal bearing: ``universal_bearing(bearing, cavitation)``.

For a plain bearing without supply pressure and an isoviscous film the film force is

    F = mu omega R L (R/c)^2 |u| R(phi) G(eps, u/|u|, L/D),   u = (eps - 2 v_t, 2 v_r),

exactly (``data.universal``; velocities in units of c omega, R(phi) the rotation into the line of
centres).  Speed, viscosity, clearance and size enter through the factor in front; a network learns G
as a function of three variables (eps, the direction of u and L/D), once per cavitation rule, on the
dimensionless dataset.  Its weights ship with the package (``universal_weights/<cavitation>.npz``, checked
against ``universal_weights/SHA256SUMS`` on load), so no dataset, training or DVC pull is needed.

For one bearing, L/D is a constant: its input is folded into the first layer's bias, and the model is a
``SurrogateForceModel`` of one 3-input network in the ``whirl`` frame (``surrogate.scaling``), with the
bearing's own force scale times ``slenderness_gain(L/D)``.  It therefore runs in the compiled
integrator with the fast kernels of ``surrogate.kernels``, answers ``exact_coefficients`` (K and C from
the network's exact Jacobian), and plugs into ``simulate``, ``equilibrium``, ``bearing_characteristics``
and ``threshold_speed`` unchanged.

The speed scaling is exact: ``speed_scaling_exact`` is True and ``with_speed(speed_rpm)`` gives the
same network at another speed (the force at omega' is (omega'/omega) F(X, V omega/omega'), to
round-off).
"""
from __future__ import annotations

from typing import Any

import dataclasses
import hashlib
import json
import math
from functools import lru_cache
from pathlib import Path

import numpy as np

from fluidfilm.core.bearing import JournalBearing
from fluidfilm.core.states import as_state_pairs
from fluidfilm.surrogate.model import SurrogateForceModel
from fluidfilm.surrogate.scaling import Scaling

__all__ = ["universal_bearing", "UniversalBearingModel", "slenderness_gain", "WEIGHTS_DIR", "UNIVERSAL_RULES",
           "weights_file", "load_weights"]

#: where the shipped weights live (package data)
WEIGHTS_DIR = Path(__file__).with_name("universal_weights")
#: the cavitation rules with shipped weights
UNIVERSAL_RULES = ("gumbel", "swift-stieber")
#: L/D at which the force scale's short-bearing law (L/D)^2 and the long bearing's constant meet
_LD_KNEE = 0.5


def slenderness_gain(slenderness):
    """The L/D part of the output scaling: 4 (L/D)^2 / (1 + 4 (L/D)^2).

    A short bearing's force grows as L^3 (Ocvirk), a long one's as L; over mu omega R L (R/c)^2 the
    dimensionless force goes from 4 (L/D)^2 (short) to a constant (long).  Dividing by this factor keeps
    the network's targets O(1) across L/D 0.2-2.

    Parameters
    ----------
    slenderness : float or ndarray
        L/D.

    Returns
    -------
    float or ndarray

    Examples
    --------
    >>> slenderness_gain(0.5), round(slenderness_gain(0.1), 4)
    (0.5, 0.0385)
    """
    q = (np.asarray(slenderness, dtype=float) / _LD_KNEE) ** 2
    out = q / (1.0 + q)
    return float(out) if np.ndim(out) == 0 else out


def weights_file(cavitation: str) -> Path:
    """The shipped weights of a cavitation rule (a ValueError naming an unknown rule).

    Parameters
    ----------
    cavitation : {"gumbel", "swift-stieber"}
        The cavitation rule.

    Returns
    -------
    Path
    """
    if cavitation not in UNIVERSAL_RULES:
        raise ValueError(f"no universal model for cavitation {cavitation!r}; choose one of {UNIVERSAL_RULES}")
    return WEIGHTS_DIR / f"{cavitation}.npz"


def _recorded_sha256(name: str) -> str:
    sums = WEIGHTS_DIR / "SHA256SUMS"
    for line in sums.read_text().splitlines():
        parts = line.split()
        if len(parts) == 2 and parts[1] == name:
            return parts[0]
    raise ValueError(f"{sums} lists no checksum for {name}")


@lru_cache(maxsize=4)
def load_weights(cavitation: str) -> dict:
    """The shipped network of a cavitation rule, its bytes checked against ``SHA256SUMS`` first.

    Parameters
    ----------
    cavitation : {"gumbel", "swift-stieber"}
        The cavitation rule.

    Returns
    -------
    dict
        ``regions``: per eccentricity region ``layers`` [(W (out, in), b)], ``in_mean``, ``in_std`` (4: eps,
        the drive's direction (2), ln L/D), ``out_mean``, ``out_std`` (2); ``boundaries`` (between the
        regions), ``blend_width``, ``power``, ``eps_max``, ``ld_min``, ``ld_max``, ``activation``, ``info``.

    Raises
    ------
    ValueError
        For an unknown rule, or weights whose SHA-256 differs from the recorded one (naming the file).

    Examples
    --------
    >>> w = load_weights("gumbel")
    >>> [W.shape for W, _ in w["regions"][0]["layers"]], w["ld_min"], w["ld_max"]
    ([(64, 4), (2, 64)], 0.2, 2.0)
    """
    path = weights_file(cavitation)
    data = path.read_bytes()
    digest = hashlib.sha256(data).hexdigest()
    if digest != _recorded_sha256(path.name):
        raise ValueError(f"{path} is damaged or was replaced: its SHA-256 {digest} differs from the one in "
                         f"{WEIGHTS_DIR / 'SHA256SUMS'}")
    with np.load(path, allow_pickle=False) as z:
        regions = []
        for r in range(int(z["n_regions"])):
            n = int(z[f"r{r}_n_layers"])
            reg: dict[str, Any] = {k: np.array(z[f"r{r}_{k}"]) for k in ("in_mean", "in_std", "out_mean", "out_std")}
            reg["layers"] = [(np.array(z[f"r{r}_W{k}"]), np.array(z[f"r{r}_b{k}"])) for k in range(n)]
            regions.append(reg)
        out: dict[str, Any] = {k: float(z[k]) for k in ("power", "blend_width", "eps_max", "ld_min", "ld_max")}
        out["boundaries"] = tuple(float(b) for b in z["boundaries"])
        out["info"] = json.loads(str(z["info"]))
        out["activation"] = str(z["activation"])
    out["regions"] = regions
    return out


def _fold_slenderness(region: dict, slenderness: float) -> tuple[list, np.ndarray, np.ndarray]:
    """One region's network at one L/D: its standardised ln(L/D) input folded into the first layer's bias."""
    W0, b0 = region["layers"][0]
    s = (math.log(slenderness) - region["in_mean"][3]) / region["in_std"][3]
    layers = [(np.ascontiguousarray(W0[:, :3]), b0 + W0[:, 3] * s)] + [(W, b) for W, b in region["layers"][1:]]
    return layers, region["in_mean"][:3], region["in_std"][:3]


class UniversalBearingModel(SurrogateForceModel):
    """The universal surrogate for one plain journal bearing (made by ``universal_bearing``).

    A ``SurrogateForceModel`` (one 3-input network in the ``whirl`` frame) that refuses states beyond its
    data's eccentricity in ``forces`` (the compiled kernel counts them instead, as every surrogate does)
    and knows that its speed scaling is exact.

    Parameters
    ----------
    bearing : JournalBearing
        A plain bearing without supply pressure, L/D inside the data's range.
    cavitation : {"gumbel", "swift-stieber"}, default "gumbel"
        The cavitation rule.
    """

    #: the force at another speed is the same network's, exactly (module doc): a run-up may vary omega
    speed_scaling_exact = True

    def __init__(self, bearing: JournalBearing, cavitation: str = "gumbel"):
        if not isinstance(bearing, JournalBearing):
            raise ValueError(f"the universal model covers plain journal bearings, got a {type(bearing).__name__}")
        w = load_weights(cavitation)  # refuses an unknown rule first
        if bearing.supply_pressure != 0.0:
            raise ValueError(f"the universal model assumes no supply pressure (the film force is then homogeneous "
                             f"in its drive); this bearing has supply_pressure={bearing.supply_pressure!r} Pa")
        ld = bearing.slenderness
        if not w["ld_min"] * (1 - 1e-12) <= ld <= w["ld_max"] * (1 + 1e-12):
            raise ValueError(f"L/D = {ld:.6g} lies outside the universal model's range [{w['ld_min']}, {w['ld_max']}]")
        if bearing.speed_rpm <= 0.0:
            raise ValueError(f"the universal model needs a turning shaft (its scale is mu omega R L (R/c)^2), "
                             f"got speed_rpm={bearing.speed_rpm!r}")
        networks, scalings = [], []
        for region in w["regions"]:
            layers, in_mean, in_std = _fold_slenderness(region, ld)
            networks.append(layers)
            scalings.append(Scaling("physics", bearing.clearance, bearing.omega,
                                    bearing.force_scale * slenderness_gain(ld), w["power"], in_mean, in_std,
                                    region["out_mean"], region["out_std"], frame="whirl"))
        super().__init__(bearing, networks, scalings, w["activation"], boundaries=w["boundaries"],
                         blend_width=w["blend_width"], eps_max=w["eps_max"], name=f"universal ({cavitation})",
                         info=dict(w["info"]))
        self.cavitation = cavitation

    def with_speed(self, speed_rpm: float) -> "UniversalBearingModel":
        """The same bearing and network at another shaft speed [rpm] (exact: module doc).

        Parameters
        ----------
        speed_rpm : float
            Shaft speed [rpm], > 0.

        Returns
        -------
        UniversalBearingModel
        """
        bearing = self.bearing
        assert isinstance(bearing, JournalBearing)  # the constructor refuses any other
        return UniversalBearingModel(dataclasses.replace(bearing, speed_rpm=float(speed_rpm)), self.cavitation)

    def forces(self, X, V) -> np.ndarray:
        """Film force [N] at positions X [m] and velocities V [m/s], (..., 2); a ValueError naming the
        eccentricity for a state beyond the data's ``eps_max``."""
        x, _, _ = as_state_pairs(X, V, self.clearance)
        if x.size:
            eps = float(np.hypot(x[:, 0], x[:, 1]).max()) / self.clearance
            if eps > self.eps_max * (1.0 + 1e-9):
                raise ValueError(f"eccentricity ratio {eps:.6g} lies beyond the universal model's data "
                                 f"(eps <= {self.eps_max:g})")
        return super().forces(X, V)

    def __repr__(self) -> str:
        bearing = self.bearing
        assert isinstance(bearing, JournalBearing)
        return f"UniversalBearingModel({self.cavitation!r}, L/D={bearing.slenderness:.4g})"


def universal_bearing(bearing: JournalBearing, cavitation: str = "gumbel") -> UniversalBearingModel:
    """The universal surrogate of a plain journal bearing: a force model like every other, no training.

    Parameters
    ----------
    bearing : JournalBearing
        Any plain bearing without supply pressure with L/D in the data's range (0.2-2).
    cavitation : {"gumbel", "swift-stieber"}, default "gumbel"
        The cavitation rule: Gumbel (half-Sommerfeld) or Swift-Stieber (Reynolds).

    Returns
    -------
    UniversalBearingModel

    Raises
    ------
    ValueError
        Naming the value: a supply pressure, L/D outside the range, an unknown cavitation rule, a bearing
        that is not a plain journal bearing, a shaft at rest; ``forces`` also for eps beyond the data.

    Examples
    --------
    >>> from fluidfilm import JournalBearing, universal_bearing
    >>> b = JournalBearing(length=0.02, diameter=0.04, clearance=50e-6, speed_rpm=6000, viscosity=0.02)
    >>> model = universal_bearing(b)
    >>> F = model.forces([0.0, 25e-6], [0.0, 0.0])        # [N] at eps = 0.5, at rest
    >>> bool(F[1] < 0), model.speed_scaling_exact
    (True, True)
    >>> universal_bearing(JournalBearing(0.1, 0.04, 50e-6, 6000, 0.02))
    Traceback (most recent call last):
    ...
    ValueError: L/D = 2.5 lies outside the universal model's range [0.2, 2.0]
    """
    return UniversalBearingModel(bearing, cavitation)
