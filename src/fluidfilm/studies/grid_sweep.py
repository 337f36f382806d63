"""Grid-density study: force error against the converged grid and time per evaluation, to MLflow
(``experiments/grid_sweep.py``)."""
from __future__ import annotations

from fluidfilm.studies.plots import grid_error_study
from fluidfilm.workflow.config import bearing_from_cfg, solver_from_cfg
from fluidfilm.workflow.entry import current_job
from fluidfilm.workflow.tracking import Logged


def tracking_run(cfg):
    job = current_job()
    return (f"grid_{int(cfg.solver.n_theta)}x{int(cfg.solver.n_z)}",
            {"study": "grid_sweep", "sweep_dir": job.sweep_dir if job.multirun else ""})


def run(cfg):  # unannotated: models built from a config are typed as unions; the library calls are checked
    bearing = bearing_from_cfg(cfg.bearing)
    solver = solver_from_cfg(bearing, cfg.solver)
    converged = solver_from_cfg(bearing, cfg.converged)
    result = grid_error_study(solver, converged, list(cfg.eccentricities), cfg.angle_deg,
                              cfg.timing_repeats, cfg.timing_calls)
    print(f"{solver}: " + ", ".join(f"{k}={v:.4g}" for k, v in result.items()))
    return Logged(result)
