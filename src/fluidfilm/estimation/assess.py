"""``assess``: the user's entry point - a recorded probe file and the bearing's description in, the estimates,
their bands and the flags out."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from fluidfilm.estimation.estimator import EstimatorSettings, estimate
from fluidfilm.estimation.probes import BearingDescription, read_probe_file


def assess(path, description: BearingDescription, out_dir, bearing: str | None = None, speed_rpm: float | None = None,
           model=None, settings_overrides: dict | None = None) -> dict:
    """Estimate the journal's position, the static load, the imbalance and the viscosity from a probe file.

    ``path``: CSV or Parquet (``probes.read_probe_file``: columns time [s], x, y [m], speed [rpm]; ``bearing``
    picks ``x_<name>``, ``y_<name>`` in a file of several bearings; ``speed_rpm`` a steady speed where the file
    has no speed signal); ``description``: the bearing, its nominal viscosity, the rotor mass per bearing, the
    probes' noise and the slow-roll runout vector; ``model``: the force model at the description's viscosity
    (default: ``universal_bearing`` of the description). Writes ``estimates.csv`` (on-line, per sample),
    ``estimates_smoothed.csv`` (the offline RTS review of the whole record) and ``summary.json`` (final values
    with their 2-sigma bands, the flags' fractions) under ``out_dir``; returns ``{"summary": ..., "files": [...],
    "estimates": Estimates}``.
    """
    from fluidfilm import io

    if model is None:
        from fluidfilm.surrogate.universal import universal_bearing

        model = universal_bearing(description.journal_bearing(), cavitation=description.cavitation)
    frame = read_probe_file(path, description.clearance, bearing=bearing, speed_rpm=speed_rpm,
                            nominal_rpm=description.speed_rpm)
    settings = EstimatorSettings(noise=description.noise, lsb=description.lsb)
    if settings_overrides:
        settings = dataclasses.replace(settings, **settings_overrides)
    runout = description.runout if any(len(a) for a in description.runout) else None
    est = estimate(frame, model, description.mass, runout=runout, settings=settings)
    out = Path(out_dir)
    online = est.frame()
    files = [out / "estimates.csv", out / "summary.json"]
    io.write_csv(files[0], online)
    last = online.iloc[-1]
    summary = {"file": str(path), "n_samples": int(len(online)), "duration_s": float(est.t[-1] - est.t[0]),
               "load_N": float(last["load"]), "load_band_N": [float(last["load_lo"]), float(last["load_hi"])],
               "imbalance_kg_m": float(last["imbalance"]),
               "imbalance_band_kg_m": [float(last["imbalance_lo"]), float(last["imbalance_hi"])],
               "imbalance_phase_rad": float(last["imbalance_phase"]),
               "viscosity_Pa_s": float(last["viscosity"]),
               "viscosity_band_Pa_s": [float(last["viscosity_lo"]), float(last["viscosity_hi"])],
               "baseline_load_N": float(last["baseline_load"]),
               "mismatch_flag_fraction": float(np.mean(est.mismatch)),
               "out_of_domain_flag_fraction": float(np.mean(est.out_of_domain)),
               "us_per_sample": float(est.us_per_sample), "model": model.name}
    if est.zs is not None:
        smoothed = est.frame(smoothed=True)
        files.insert(1, out / "estimates_smoothed.csv")
        io.write_csv(files[1], smoothed)
        mid = smoothed.iloc[len(smoothed) // 2]
        summary["smoothed_mid_record"] = {"time_s": float(mid["time"]), "load_N": float(mid["load"]),
                                          "imbalance_kg_m": float(mid["imbalance"]),
                                          "viscosity_Pa_s": float(mid["viscosity"])}
    io.write_json(out / "summary.json", summary)
    return {"summary": summary, "files": [str(f) for f in files], "estimates": est}
