"""Fig. 4 reference: the seven trajectory cases with the reference model (``experiments/trajectories.py``)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from fluidfilm import io
from fluidfilm.characteristics.static import equilibrium_locus
from fluidfilm.rotor.cases import case_summary, run_case
from fluidfilm.studies.plots import plot_equilibrium_locus, plot_orbits
from fluidfilm.workflow.config import bearing_from_cfg, reference_from_cfg
from fluidfilm.workflow.tracking import Logged


def outputs(cfg) -> dict:
    m = cfg.model_name
    return {"out_dir": [m], "figure_dir": [f"fig4_{m}.png", f"equilibrium_locus_{m}.csv", f"equilibrium_locus_{m}.png"]}


def tracking_run(cfg):
    return f"trajectories_{cfg.model_name}", None


def run(cfg) -> Logged:
    bearing = bearing_from_cfg(cfg.bearing)
    model = reference_from_cfg(bearing, cfg.reference)
    out = Path(cfg.out_dir) / cfg.model_name
    rows, panels = [], {}
    for name in cfg.run_cases:
        case = cfg.cases[name]
        traj = run_case(model, cfg.rotor, case, cfg.integrator)
        traj.to_npz(out / f"{name}.npz")
        summary = {"case": name, "label": case.label, **case_summary(traj, bearing.clearance, cfg.integrator.t_settle)}
        rows.append(summary)
        panels[name] = (case.label, {cfg.model_name: traj})
        print(f"case {name}: {traj.status}, span {summary['span']:.3f} c, "
              f"eps_max {summary['eps_max']:.3f}, {traj.wall_time_s:.2f} s")
    table = pd.DataFrame(rows)
    io.write_csv(out / "summary.csv", table)
    fig = plot_orbits(panels, bearing.clearance, cfg.integrator.t_settle,
                      f"Fig. 4 - rotor trajectories, {cfg.model_name} model "
                      f"(m = {cfg.rotor.mass} kg, load share {cfg.rotor.load_share})")
    io.save_figure(fig, Path(cfg.figure_dir) / f"fig4_{cfg.model_name}.png", dpi=130)
    # the static equilibrium locus: where the film carries a growing load along gravity
    locus = equilibrium_locus(model, np.geomspace(cfg.locus.load_min, cfg.locus.load_max, cfg.locus.n))
    io.write_csv(Path(cfg.figure_dir) / f"equilibrium_locus_{cfg.model_name}.csv", locus)
    io.save_figure(plot_equilibrium_locus(locus, bearing.clearance),
                   Path(cfg.figure_dir) / f"equilibrium_locus_{cfg.model_name}.png", dpi=130)
    metrics: dict = {}
    for r in rows:
        metrics |= {f"span_{r['case']}": r["span"], f"eps_max_{r['case']}": r["eps_max"],
                    f"wall_time_s_{r['case']}": r["wall_time_s"],
                    f"outside_domain_evals_{r['case']}": r["n_outside_domain"]}
    return Logged(metrics)
