"""Fig. 4 reference: the seven trajectory cases with the reference model.

    python experiments/trajectories.py       # data/trajectories/reference/<case>.npz, reports/figures/fig4_reference.png
"""
from pathlib import Path

import hydra
import pandas as pd
from omegaconf import DictConfig, OmegaConf

from fluidfilm import io
from fluidfilm.workflow import tracking
from fluidfilm.workflow.config import bearing_from_cfg, reference_from_cfg
import numpy as np

from fluidfilm.studies.plots import plot_equilibrium_locus, plot_orbits
from fluidfilm.rotor import equilibrium_locus
from fluidfilm.rotor.cases import case_summary, run_case
from fluidfilm.workflow.config_check import check_config


@hydra.main(config_path="../conf", config_name="trajectories", version_base="1.3")
def main(cfg: DictConfig) -> None:
    check_config(cfg)  # a mistyped value or an unknown key is refused here, before any work
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
    with tracking.run(cfg.tracking, f"trajectories_{cfg.model_name}", OmegaConf.to_container(cfg, resolve=True)):
        for r in rows:
            tracking.log_metrics({f"span_{r['case']}": r["span"], f"eps_max_{r['case']}": r["eps_max"],
                                  f"wall_time_s_{r['case']}": r["wall_time_s"],
                                  f"outside_domain_evals_{r['case']}": r["n_outside_domain"]})


if __name__ == "__main__":
    io.run_interruptible(main, "the reference trajectories", "run the same command again")
