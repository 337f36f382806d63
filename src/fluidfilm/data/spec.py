"""The dataset's layout as validated plain data: position sections, graded velocities, sizes.

The paper (Section 3.1, CONVENTIONS.md): positions on a polar grid of
``n_eps x n_angle`` (12 x 40) laid out separately over eps 0-0.9 and
0.9-eps_max; velocities graded per eccentricity section, 40 negative and 40
positive values per component, a share of them inside a core band
(section eps 0.1-0.5: +-0.2 m/s, 70 % within +-0.05; section eps 0.5-1:
+-0.5 m/s, 50 % within +-0.2).  Position sections and velocity sections are
independent lists, so the paper's overlapping splits (0.9 for positions,
0.5 for velocities) are both expressible: a position takes the velocity
section whose eccentricity range contains it.

How V1 and V2 combine: ``product`` (every V1 with every V2: 80 x 80 pairs
per position) or ``zip`` (pairs of equal index, 80 per position).

Every bad value fails here, before any work, with a message naming its key.
"""
from __future__ import annotations

from typing import Any

import hashlib
import json
import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass

import numpy as np


class DatasetConfigError(ValueError):
    """A dataset config value is invalid; the message names the key.

    Examples
    --------
    >>> from fluidfilm.data import DatasetConfigError, DatasetSpec
    >>> try:
    ...     DatasetSpec.from_cfg({"position_sections": []})
    ... except DatasetConfigError as err:
    ...     print(err)
    dataset.position_sections must list at least one section
    """


def _num(cfg: Mapping, key: str, where: str) -> float:
    if key not in cfg:
        raise DatasetConfigError(f"{where}.{key} is missing")
    try:
        value = float(cfg[key])
    except (TypeError, ValueError):
        raise DatasetConfigError(f"{where}.{key}={cfg[key]!r} must be a number") from None
    if not math.isfinite(value):
        raise DatasetConfigError(f"{where}.{key}={value!r} must be finite")
    return value


def _count(cfg: Mapping, key: str, where: str, minimum: int = 1) -> int:
    value = _num(cfg, key, where)
    if value != int(value) or value < minimum:
        raise DatasetConfigError(f"{where}.{key}={cfg[key]!r} must be an integer >= {minimum}")
    return int(value)


@dataclass(frozen=True)
class PositionSection:
    name: str
    eps_start: float
    eps_stop: float
    n_eps: int
    endpoint: bool
    n_angle: int

    def eccentricities(self) -> np.ndarray:
        return np.linspace(self.eps_start, self.eps_stop, self.n_eps, endpoint=self.endpoint)

    def polar_grid(self) -> tuple[np.ndarray, np.ndarray]:
        """(eps, angle) of every position, eps-major.  At eps = 0 every angle is the same point (the
        bearing's centre), so it appears once: n_angle copies would repeat identical rows and weigh the
        centre n_angle times in training."""
        eps = self.eccentricities()
        ang = 2 * np.pi * np.arange(self.n_angle) / self.n_angle
        e, a = np.meshgrid(eps, ang, indexing="ij")
        keep = (e > 0.0) | (a == 0.0)
        return e[keep], a[keep]

    def positions(self, clearance: float) -> np.ndarray:
        """(P, 2) positions [m]; angle from +X2 towards +X1, eps-major order, the centre once."""
        e, a = self.polar_grid()
        return clearance * np.stack([e * np.sin(a), e * np.cos(a)], axis=1)


@dataclass(frozen=True)
class VelocitySection:
    eps_low: float
    eps_high: float
    v_max: float
    core: float
    core_fraction: float
    n_per_side: int
    include_zero: bool = False

    def values(self) -> np.ndarray:
        """Graded values of one velocity component, ascending: n_per_side negative, n_per_side positive
        (and 0 between them with ``include_zero``; the paper's layout has no zero).

        Per side, round(core_fraction * n) values evenly spaced in (0, core]
        and the rest evenly in (core, v_max]; the negative side mirrors it.
        """
        n_core = int(round(self.core_fraction * self.n_per_side))
        n_out = self.n_per_side - n_core
        core = np.linspace(0.0, self.core, n_core + 1)[1:]
        outer = np.linspace(self.core, self.v_max, n_out + 1)[1:]
        side = np.concatenate([core, outer])
        zero = np.zeros(1 if self.include_zero else 0)
        return np.concatenate([-side[::-1], zero, side])


@dataclass(frozen=True)
class DatasetSpec:
    """The layout of the graded force dataset: where the positions and velocities lie (frozen).

    Built from a config mapping (``conf/dataset/*.yaml``) with ``from_cfg``, which checks every
    value and raises ``DatasetConfigError`` naming the key (e.g. ``dataset.combine``).

    Parameters
    ----------
    position_sections : tuple of PositionSection
        Eccentricity ranges (eps_start, eps_stop, n_eps) times n_angle angles from +X2 towards +X1.
    velocity_sections : tuple of VelocitySection
        Per eccentricity band [eps_low, eps_high): velocity values within +-v_max [m/s].
    combine : {"product", "zip"}
        Every (V1, V2) pair of the values, or the values zipped with their reverse.
    positions_per_chunk : int
        Positions per part file (one unit of work).
    n_test : int
        Size of the held-out random test set.
    test_seed : int
        Its random seed.
    sleeve_positions : tuple of float, default ()
        Sleeve positions [m] of an active (conical) bearing; empty for a fixed bearing.

    Examples
    --------
    >>> from fluidfilm.data import DatasetConfigError, DatasetSpec
    >>> cfg = {"position_sections": [{"eps_start": 0.1, "eps_stop": 0.5, "n_eps": 2, "n_angle": 4}],
    ...        "velocity_sections": [{"eps_low": 0.0, "eps_high": 0.5, "v_max": 0.01, "core": 0.01,
    ...                               "core_fraction": 0.0, "n_per_side": 2}],
    ...        "positions_per_chunk": 8, "n_test": 10, "test_seed": 0}
    >>> DatasetSpec.from_cfg(cfg).n_samples(clearance=120e-6)    # 8 positions x 16 (V1, V2) pairs
    128
    >>> DatasetSpec.from_cfg({**cfg, "combine": "cross"})
    Traceback (most recent call last):
    ...
    fluidfilm.data.spec.DatasetConfigError: dataset.combine='cross' must be 'product' or 'zip'
    """

    position_sections: tuple[PositionSection, ...]
    velocity_sections: tuple[VelocitySection, ...]
    combine: str
    positions_per_chunk: int
    n_test: int
    test_seed: int
    sleeve_positions: tuple[float, ...] = ()

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_cfg(cls, cfg: Mapping) -> "DatasetSpec":
        """The spec of a dataset config mapping; ``DatasetConfigError`` naming the first bad key."""
        where = "dataset"
        if "position_sections" not in cfg or not cfg["position_sections"]:
            raise DatasetConfigError(f"{where}.position_sections must list at least one section")
        if "velocity_sections" not in cfg or not cfg["velocity_sections"]:
            raise DatasetConfigError(f"{where}.velocity_sections must list at least one section")
        psecs = []
        for k, s in enumerate(cfg["position_sections"]):
            w = f"{where}.position_sections[{k}]"
            start, stop = _num(s, "eps_start", w), _num(s, "eps_stop", w)
            if start < 0.0:
                raise DatasetConfigError(f"{w}.eps_start={start} must be >= 0")
            if stop >= 1.0:
                raise DatasetConfigError(f"{w}.eps_stop={stop} must be < 1 (eps = 1 is contact with the sleeve)")
            if not stop > start:
                raise DatasetConfigError(f"{w}: empty range, eps_stop={stop} must exceed eps_start={start}")
            psecs.append(PositionSection(name=str(s.get("name", f"section{k}")), eps_start=start, eps_stop=stop,
                                         n_eps=_count(s, "n_eps", w), endpoint=bool(s.get("endpoint", True)),
                                         n_angle=_count(s, "n_angle", w)))
        vsecs = []
        for k, s in enumerate(cfg["velocity_sections"]):
            w = f"{where}.velocity_sections[{k}]"
            lo, hi = _num(s, "eps_low", w), _num(s, "eps_high", w)
            if not hi > lo:
                raise DatasetConfigError(f"{w}: empty range, eps_high={hi} must exceed eps_low={lo}")
            v_max, core, frac = _num(s, "v_max", w), _num(s, "core", w), _num(s, "core_fraction", w)
            if not v_max > 0.0:
                raise DatasetConfigError(f"{w}.v_max={v_max} must be > 0")
            if not 0.0 < core <= v_max:
                raise DatasetConfigError(f"{w}.core={core} must lie in (0, v_max={v_max}]")
            if not 0.0 <= frac <= 1.0:
                raise DatasetConfigError(f"{w}.core_fraction={frac} must lie in [0, 1]")
            n = _count(s, "n_per_side", w)
            n_core = int(round(frac * n))
            if core < v_max and n_core == n:
                raise DatasetConfigError(f"{w}: core_fraction={frac} leaves no value in (core, v_max]")
            if n_core == 0 and frac > 0:
                raise DatasetConfigError(f"{w}: core_fraction={frac} of n_per_side={n} rounds to no core value")
            vsecs.append(VelocitySection(lo, hi, v_max, core, frac, n, bool(s.get("include_zero", False))))
        combine = str(cfg.get("combine", "product"))
        if combine not in ("product", "zip"):
            raise DatasetConfigError(f"{where}.combine={combine!r} must be 'product' or 'zip'")
        sleeves = cfg.get("sleeve_positions", None) or ()
        try:
            sleeves = tuple(float(v) for v in sleeves)
        except (TypeError, ValueError):
            raise DatasetConfigError(f"{where}.sleeve_positions={sleeves!r} must be a list of numbers (m)") from None
        if not all(math.isfinite(v) for v in sleeves) or len(set(sleeves)) != len(sleeves):
            raise DatasetConfigError(f"{where}.sleeve_positions={list(sleeves)} must be distinct finite values (m)")
        spec = cls(tuple(psecs), tuple(vsecs), combine,
                   _count(cfg, "positions_per_chunk", where), _count(cfg, "n_test", where, minimum=0),
                   _count(cfg, "test_seed", where, minimum=0), tuple(sorted(sleeves)))
        for p in psecs:  # every position needs a velocity section
            for e in p.eccentricities():
                spec.velocity_section_index(e)
        return spec

    def velocity_section_index(self, eps: float) -> int:
        """Index of the velocity section containing eps (ranges are [low, high); the last is closed)."""
        last = len(self.velocity_sections) - 1
        for k, s in enumerate(self.velocity_sections):
            if s.eps_low <= eps < s.eps_high or (k == last and eps == s.eps_high):
                return k
        raise DatasetConfigError(f"dataset.velocity_sections: no section covers eps={eps:.6g}")

    # ------------------------------------------------------------------ layout
    def velocity_pairs(self, k: int) -> np.ndarray:
        vals = self.velocity_sections[k].values()
        if self.combine == "product":
            v1, v2 = np.meshgrid(vals, vals, indexing="ij")
            return np.stack([v1.ravel(), v2.ravel()], axis=1)
        return np.stack([vals, vals[::-1]], axis=1)

    def positions(self, clearance: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """All grid positions (P, 2) [m], their position-section index (P,) and nominal eps (P,).

        The nominal eccentricity (not |X|/c recomputed, which can land a hair
        below a section boundary such as 0.9) decides the velocity section
        and the reference grid of a position.
        """
        xs, sec, eps = [], [], []
        for k, p in enumerate(self.position_sections):
            x = p.positions(clearance)
            xs.append(x)
            sec.append(np.full(len(x), k, dtype=np.int16))
            eps.append(p.polar_grid()[0])
        return np.concatenate(xs), np.concatenate(sec), np.concatenate(eps)

    def n_samples(self, clearance: float) -> int:
        """Samples planned: per position its velocity pairs, times the sleeve positions (if any)."""
        _, _, eps = self.positions(clearance)
        per_sleeve = int(sum(len(self.velocity_pairs(self.velocity_section_index(e))) for e in eps))
        return per_sleeve * max(1, len(self.sleeve_positions))

    @property
    def eps_max(self) -> float:
        return max(p.eps_stop for p in self.position_sections)

    def to_dict(self) -> dict:
        return asdict(self)


def example_spec() -> DatasetSpec:
    """A tiny layout for examples and smoke runs: 8 positions at eps 0.1 and 0.5, 16 velocity pairs each.

    Returns
    -------
    DatasetSpec
        128 samples (a second or so with a 16 x 8 reference grid), a test set of 10.

    Examples
    --------
    >>> from fluidfilm.data import example_spec
    >>> example_spec().n_samples(clearance=120e-6)
    128
    """
    return DatasetSpec.from_cfg({
        "position_sections": [{"eps_start": 0.1, "eps_stop": 0.5, "n_eps": 2, "n_angle": 4}],
        "velocity_sections": [{"eps_low": 0.0, "eps_high": 0.5, "v_max": 0.01, "core": 0.01, "core_fraction": 0.0,
                               "n_per_side": 2}],
        "positions_per_chunk": 8, "n_test": 10, "test_seed": 0})


CAVITATION_MODELS = ("gumbel", "swift-stieber")


def check_reference(cfg: Mapping, where: str = "reference") -> dict:
    """The reference grid policy {coarse, dense, eps_threshold, cavitation} as plain data, every value
    checked (naming its key) before any work or any output is touched."""
    out: dict[str, Any] = {}
    for key in ("coarse", "dense"):
        grid: Any = cfg.get(key) if hasattr(cfg, "get") else None
        try:
            ok = grid is not None and len(grid) == 2 and all(float(n) == int(n) >= 3 for n in grid)
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise DatasetConfigError(f"{where}.{key}={grid!r} must be a pair of grid sizes [n_theta, n_z], "
                                     "each an integer >= 3")
        out[key] = [int(n) for n in grid]
    thr = _num(cfg, "eps_threshold", where)
    if not 0.0 < thr <= 1.0:
        raise DatasetConfigError(f"{where}.eps_threshold={thr!r} must lie in (0, 1]")
    out["eps_threshold"] = thr
    cav = cfg.get("cavitation", "gumbel")
    if cav not in CAVITATION_MODELS:
        raise DatasetConfigError(f"{where}.cavitation={cav!r} must be one of {CAVITATION_MODELS}")
    out["cavitation"] = cav
    unknown = sorted(set(cfg) - {"coarse", "dense", "eps_threshold", "cavitation"})
    if unknown:
        raise DatasetConfigError(f"{where}: unknown key(s) {unknown}")
    return out


def config_hash(*parts) -> str:
    """Stable hash of JSON-serialisable config parts.

    Parameters
    ----------
    *parts
        JSON-serialisable values (mappings are hashed with sorted keys; other objects by ``str``).

    Returns
    -------
    str
        The first 16 hex digits of the SHA-256 of their JSON text.

    Examples
    --------
    >>> from fluidfilm.data import config_hash
    >>> config_hash({"a": 1, "b": 2}) == config_hash({"b": 2, "a": 1}), len(config_hash([1.0]))
    (True, 16)
    """
    blob = json.dumps(parts, sort_keys=True, default=str).encode()
    return hashlib.sha256(blob).hexdigest()[:16]
