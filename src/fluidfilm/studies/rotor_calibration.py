"""Rotor calibration: orbit spans of the imbalance cases over rotor mass, load share and imbalance sense
(``experiments/rotor_calibration.py``, reports/rotor_calibration.csv)."""
from __future__ import annotations

import itertools

import numpy as np
import pandas as pd

from fluidfilm import io
from fluidfilm.rotor.cases import case_summary, run_cases
from fluidfilm.workflow.config import bearing_from_cfg, reference_from_cfg

OUTPUTS = {"out": [""]}


def run(cfg) -> None:
    bearing = bearing_from_cfg(cfg.bearing)
    model = reference_from_cfg(bearing, cfg.reference)
    combos = list(itertools.product(cfg.masses, cfg.load_shares, cfg.imbalance_directions))
    runs = [({"mass": mass, "load_share": share, "gravity": cfg.gravity, "imbalance_direction": sense},
             {"imbalance": case.imbalance, "external_force": [0.0, 0.0]})
            for mass, share, sense in combos for case in cfg.cases.values()]
    print(f"{len(runs)} reference orbits in one batch (every core)", flush=True)
    trajectories = iter(run_cases(model, runs, cfg.integrator))
    rows = []
    for mass, share, sense in combos:
        row = {"mass": mass, "load_share": share, "imbalance_direction": sense}
        sq = []
        for name, case in cfg.cases.items():
            s = case_summary(next(trajectories), bearing.clearance, cfg.integrator.t_settle)
            row[f"span_{name}"] = s["span"]
            row[f"eps_max_{name}"] = s["eps_max"]
            sq.append((s["span"] - case.target_span) ** 2)
        row["rms_span_misfit"] = float(np.sqrt(np.mean(sq)))
        rows.append(row)
        print({k: (round(v, 3) if isinstance(v, float) else v) for k, v in row.items()})
    table = pd.DataFrame(rows).sort_values("rms_span_misfit")
    io.write_csv(cfg.out, table)
    print(table.head(5).to_string(index=False))
