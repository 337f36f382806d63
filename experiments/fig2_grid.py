"""Fig. 2: film reaction against rotor position for the 30x30 and 60x60 grids.

    python experiments/fig2_grid.py            # writes reports/figures/fig2_grid.{png,csv}
"""
from pathlib import Path

import hydra
import numpy as np
from omegaconf import DictConfig, OmegaConf

from fluidfilm import io
from fluidfilm.workflow import tracking
from fluidfilm.workflow.config import bearing_from_cfg, solver_from_cfg
from fluidfilm.studies.plots import grid_comparison, plot_grid_comparison
from fluidfilm.workflow.config_check import check_config


@hydra.main(config_path="../conf", config_name="fig2", version_base="1.3")
def main(cfg: DictConfig) -> None:
    check_config(cfg)  # a mistyped value or an unknown key is refused here, before any work
    bearing = bearing_from_cfg(cfg.bearing)
    solvers = {name: solver_from_cfg(bearing, cfg[name]) for name in ("coarse", "dense", "converged")}
    eps = np.linspace(cfg.eps_min, cfg.eps_max, cfg.n_eps)
    frame = grid_comparison(solvers, eps, cfg.angle_deg, reference="converged")
    labels = {k: f"{s.n_theta}x{s.n_z}" for k, s in solvers.items()}
    out = Path(cfg.out_dir)
    io.write_csv(out / "fig2_grid.csv", frame)
    fig = plot_grid_comparison(frame, ["coarse", "dense"], labels, "converged")
    io.save_figure(fig, out / "fig2_grid.png", dpi=130)
    summary = {f"err_{k}_pct_eps_{e:g}": float(np.interp(e, frame["eps"], frame[f"err_{k}_pct"]))
               for k in ("coarse", "dense") for e in (0.5, 0.9, 0.95, 0.98)}
    with tracking.run(cfg.tracking, "fig2_grid", OmegaConf.to_container(cfg, resolve=True)):
        tracking.log_metrics(summary)
        tracking.log_artifact(out / "fig2_grid.png")
    print(frame.iloc[:: max(1, len(frame) // 10)].to_string(index=False))


if __name__ == "__main__":
    io.run_interruptible(main, "the Fig. 2 grid study", "run the same command again")
