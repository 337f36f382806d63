"""Grid-density study: force error against the converged grid and time per evaluation, to MLflow.

    python experiments/grid_sweep.py -m solver.n_theta=20,30,55,60,90 solver.n_z=20,30,55,60
"""
import hydra
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig, OmegaConf

from fluidfilm import io
from fluidfilm.workflow import tracking
from fluidfilm.workflow.config import bearing_from_cfg, solver_from_cfg
from fluidfilm.studies.plots import grid_error_study
from fluidfilm.workflow.config_check import check_config


@hydra.main(config_path="../conf", config_name="grid_sweep", version_base="1.3")
def main(cfg: DictConfig) -> dict:
    check_config(cfg)  # a mistyped value or an unknown key is refused here, before any work
    bearing = bearing_from_cfg(cfg.bearing)
    solver = solver_from_cfg(bearing, cfg.solver)
    converged = solver_from_cfg(bearing, cfg.converged)
    result = grid_error_study(solver, converged, list(cfg.eccentricities), cfg.angle_deg,
                              cfg.timing_repeats, cfg.timing_calls)
    hc = HydraConfig.get()
    tags = {"study": "grid_sweep", "sweep_dir": str(hc.sweep.dir) if hc.mode.name == "MULTIRUN" else ""}
    with tracking.run(cfg.tracking, f"grid_{solver.n_theta}x{solver.n_z}",
                      OmegaConf.to_container(cfg, resolve=True), tags=tags):
        tracking.log_metrics(result)
    print(f"{solver}: " + ", ".join(f"{k}={v:.4g}" for k, v in result.items()))
    return result


if __name__ == "__main__":
    io.run_interruptible(main, "the grid-density sweep", "run the same command again")
