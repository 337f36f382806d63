"""Reading a recorded probe file and the bearing's description, each bad input refused in one line naming it.

A probe file is CSV or Parquet with the columns ``time`` [s], ``x``, ``y`` [m] (the journal's position from two
proximity probes, resolved into the conventions' X1, X2 frame, +X2 along gravity, relative to the bearing's
centre) and ``speed`` [rpm]. A file with several bearings names them ``x_<name>``, ``y_<name>``
(``read_probe_file(path, bearing=name)``). The checks: the columns are there (the speed signal too, unless a
steady ``speed_rpm`` is given), no NaN or infinite sample, time strictly increasing at one sampling interval
(a gap of more than half a sample is named with its time), positions in metres (a peak beyond the clearance
is named: micrometres or mils give values 1e6 or 4e4 times larger), the speed in rpm (positive, within a
factor of two of the description's).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd


class ProbeFileError(ValueError):
    """A probe file the estimator cannot take; the message is one line naming the file, column and sample."""


@dataclass(frozen=True)
class BearingDescription:
    """What the estimator is told about the bearing: its geometry and speed [SI, rpm], the oil's nominal
    viscosity mu0 [Pa s], the rotor mass it carries [kg], the cavitation rule of the force model, the probes'
    noise [m] and digitiser step [m], the slow-roll runout vector ((c1, s1), (c2, s2), ...) per axis [m]."""

    length: float
    diameter: float
    clearance: float
    speed_rpm: float
    viscosity: float
    mass: float
    cavitation: str = "gumbel"
    noise: float = 1.0e-6
    lsb: float = 0.1e-6
    runout: tuple = ((), ())

    @classmethod
    def from_mapping(cls, d) -> "BearingDescription":
        d = dict(d)
        runout = d.pop("runout", None) or {}
        if isinstance(runout, dict):
            runout = (tuple(tuple(map(float, r)) for r in runout.get("x", ())),
                      tuple(tuple(map(float, r)) for r in runout.get("y", ())))
        known = {f for f in cls.__dataclass_fields__}
        unknown = sorted(set(d) - known)
        if unknown:
            raise ValueError(f"bearing description: unknown key(s) {unknown}; expected {sorted(known)}")
        return cls(runout=runout, **d)

    def journal_bearing(self):
        from fluidfilm.core.bearing import JournalBearing

        return JournalBearing(length=self.length, diameter=self.diameter, clearance=self.clearance,
                              speed_rpm=self.speed_rpm, viscosity=self.viscosity)


def read_probe_file(path, clearance: float, bearing: str | None = None, speed_rpm: float | None = None,
                    nominal_rpm: float | None = None) -> pd.DataFrame:
    """The record as a frame with columns ``time, x, y, speed`` (s, m, m, rpm), checked (module docstring).

    ``speed_rpm``: a steady speed to use where the file has no speed signal (otherwise a missing ``speed``
    column is refused); ``nominal_rpm``: the description's speed, against which the speed's units are checked.
    """
    path = Path(path)
    name = path.name
    if not path.exists():
        raise ProbeFileError(f"{path}: no such probe file")
    try:
        if path.suffix.lower() in (".parquet", ".pq"):
            raw = pd.read_parquet(path)
        elif path.suffix.lower() in (".csv", ".txt"):
            raw = pd.read_csv(path)
        else:
            raise ProbeFileError(f"{name}: unknown probe-file type {path.suffix!r} (CSV or Parquet)")
    except ProbeFileError:
        raise
    except Exception as err:  # a damaged file: name it, with the reader's first line
        raise ProbeFileError(f"{name}: cannot be read as a probe file: {str(err).splitlines()[0]}") from None
    return check_probe_frame(raw, clearance, name=name, bearing=bearing, speed_rpm=speed_rpm, nominal_rpm=nominal_rpm)


def check_probe_frame(raw: pd.DataFrame, clearance: float, name: str = "record", bearing: str | None = None,
                      speed_rpm: float | None = None, nominal_rpm: float | None = None) -> pd.DataFrame:
    """``read_probe_file``'s checks on a frame already in memory."""
    cx, cy = ("x", "y") if bearing is None else (f"x_{bearing}", f"y_{bearing}")
    for col in ("time", cx, cy):
        if col not in raw.columns:
            raise ProbeFileError(f"{name}: column {col!r} missing (columns: {', '.join(map(str, raw.columns))})")
    if "speed" not in raw.columns and speed_rpm is None:
        raise ProbeFileError(f"{name}: the speed signal (column 'speed', rpm) is missing; the estimator needs the "
                             f"shaft speed for the imbalance's phase (or pass a steady speed_rpm)")
    out = pd.DataFrame({"time": raw["time"], "x": raw[cx], "y": raw[cy],
                        "speed": raw["speed"] if "speed" in raw.columns else float(speed_rpm or 0.0)})
    if len(out) < 10:
        raise ProbeFileError(f"{name}: {len(out)} samples; at least 10 needed")
    for col, src in (("time", "time"), ("x", cx), ("y", cy), ("speed", "speed")):
        try:
            v = out[col].to_numpy(dtype=float)
        except (TypeError, ValueError):
            raise ProbeFileError(f"{name}: column {src!r} is not numeric") from None
        bad = ~np.isfinite(v)
        if bad.any():
            k = int(np.argmax(bad))
            raise ProbeFileError(f"{name}: column {src!r} has {int(bad.sum())} NaN/infinite sample(s), the first at "
                                 f"row {k}")
        out[col] = v
    t = out["time"].to_numpy()
    dt = np.diff(t)
    if (dt <= 0).any():
        k = int(np.argmax(dt <= 0))
        raise ProbeFileError(f"{name}: time does not increase at row {k + 1} (t = {t[k + 1]!r} s)")
    step = float(np.median(dt))
    gap = np.abs(dt - step) > 0.5 * step
    if gap.any():
        k = int(np.argmax(gap))
        raise ProbeFileError(f"{name}: a gap in time at t = {t[k]:.6g} s ({dt[k]:.3g} s between samples, the "
                             f"sampling interval is {step:.3g} s); the estimator needs an unbroken record")
    for col, src in (("x", cx), ("y", cy)):
        peak = float(np.max(np.abs(out[col])))
        if peak > 1.5 * clearance:
            raise ProbeFileError(f"{name}: column {src!r} reaches {peak:.3g}, beyond the clearance ({clearance:.3g} m): "
                                 f"positions must be in metres relative to the bearing's centre")
    sp = out["speed"].to_numpy()
    if (sp <= 0).any():
        raise ProbeFileError(f"{name}: column 'speed' is not positive at row {int(np.argmax(sp <= 0))}: the shaft "
                             f"speed must be in rpm")
    if nominal_rpm is not None:
        med = float(np.median(sp))
        if not 0.5 * nominal_rpm <= med <= 2.0 * nominal_rpm:
            raise ProbeFileError(f"{name}: column 'speed' has a median {med:.4g}, not within a factor 2 of the "
                                 f"description's {nominal_rpm:.4g} rpm: the speed must be in rpm")
    return out.reset_index(drop=True)
