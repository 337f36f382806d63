"""Where the surrogates' force errors sit (eccentricity, journal speed), held out and along the orbits
(``experiments/error_map.py``)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from fluidfilm import io, load_surrogate
from fluidfilm.data import load_test_set
from fluidfilm.studies.grading_study import OrbitBenchmark, binned_errors, error_quantiles, relative_errors
from fluidfilm.studies.plots import plot_error_map
from fluidfilm.workflow.config import bearing_from_cfg, reference_from_cfg
from fluidfilm.workflow.config_check import ConfigError
from fluidfilm.workflow.tracking import Logged

INPUTS = ("models", "testset_dir", "reference_trajectories_dir")
OUTPUTS = {"report_dir": ["error_map.csv", "error_map.json"], "figure_dir": ["error_map.png"]}


def tracking_run(cfg):
    return "error_map", None


def check(cfg) -> None:
    if cfg.figure_model not in cfg.models:
        raise ConfigError(f"figure_model={cfg.figure_model!r} is not one of models: {list(cfg.models)}")


def run(cfg) -> Logged:
    check(cfg)
    bearing = bearing_from_cfg(cfg.bearing)
    bench = OrbitBenchmark.from_dir(reference_from_cfg(bearing, cfg.reference), cfg.reference_trajectories_dir,
                                    list(cfg.cases))
    held = load_test_set(cfg.testset_dir)
    sets = {"held-out random states": (held[["X1", "X2"]].to_numpy(), held[["V1", "V2"]].to_numpy(),
                                       held[["F1", "F2"]].to_numpy()),
            "states along the reference orbits": (bench.x, bench.v, bench.forces)}
    summary: dict = {}
    tables, maps = [], {}
    for name, path in cfg.models.items():
        model = load_surrogate(path)
        summary[name] = {}
        for label, (x, v, f) in sets.items():
            rel = relative_errors(np.asarray(model.forces(x, v)), f, cfg.error_floor_N)
            eps = np.hypot(x[:, 0], x[:, 1]) / bearing.clearance
            bins = binned_errors(rel, eps, np.hypot(v[:, 0], v[:, 1]), list(cfg.eps_edges), list(cfg.speed_edges))
            key = "held_out" if label.startswith("held") else "orbit_states"
            worst = bins[bins.n_states >= 20].nlargest(3, "p99")
            summary[name][key] = error_quantiles(rel) | {"n_states": int(len(rel)),
                                                         "worst_bins": worst.to_dict(orient="records")}
            tables.append(bins.assign(model=name, states=key))
            if name == cfg.figure_model:
                maps[label] = bins
        print(f"{name}: held-out median {100 * summary[name]['held_out']['median']:.2f} %, p99 "
              f"{100 * summary[name]['held_out']['p99']:.1f} %; along the orbits median "
              f"{100 * summary[name]['orbit_states']['median']:.2f} %, p99 {100 * summary[name]['orbit_states']['p99']:.1f} %")
    report = Path(cfg.report_dir)
    io.write_csv(report / "error_map.csv", pd.concat(tables, ignore_index=True))
    io.save_figure(plot_error_map(maps, f"Where the force errors of the {cfg.figure_model} surrogate sit"),
                   Path(cfg.figure_dir) / "error_map.png", dpi=120)
    io.write_json(report / "error_map.json", {"models": summary, "floor_N": cfg.error_floor_N,
                                              "eps_edges": list(cfg.eps_edges), "speed_edges": list(cfg.speed_edges)})
    metrics = {f"{k}_rel_err_{q}_{name}": float(s[k][q]) for name, s in summary.items()
               for k in ("held_out", "orbit_states") for q in ("median", "p99")}
    return Logged(metrics, [report / "error_map.json", Path(cfg.figure_dir) / "error_map.png"])
