"""Fig. 4 a-g overlays (reference / single / split / best) and the speed comparison, measured side by side.

    python experiments/compare.py
"""
from pathlib import Path

import hydra
import pandas as pd
from omegaconf import DictConfig, OmegaConf

from fluidfilm import ReynoldsSolver, io, load_surrogate
from fluidfilm.workflow import tracking
from fluidfilm.perf.benchmarking import machine
from fluidfilm.studies.compare import sparse_reference_speed, speed_comparison, trajectory_comparison
from fluidfilm.workflow.config import bearing_from_cfg, reference_from_cfg
from fluidfilm.studies.plots import plot_orbits
from fluidfilm.workflow.config_check import check_config


def _with_dense_share(table, trajs, clearance, eps_threshold):
    """The table plus, per row, the share of recorded states at or above the grid policy's threshold."""
    table = table.copy()
    table["dense_share"] = [float((trajs[r.case][r.model].eccentricity(clearance) >= eps_threshold).mean())
                            for r in table.itertuples()]
    return table


@hydra.main(config_path="../conf", config_name="compare", version_base="1.3")
def main(cfg: DictConfig) -> None:
    check_config(cfg)  # a mistyped value or an unknown key is refused here, before any work
    bearing = bearing_from_cfg(cfg.bearing)
    reference = reference_from_cfg(bearing, cfg.reference)
    surrogates = {name: load_surrogate(path) for name, path in cfg.models.items()}
    models = {"reference": reference, **surrogates}
    cases = {k: cfg.cases[k] for k in sorted(cfg.cases)}
    table, trajs = trajectory_comparison(models, "reference", cfg.rotor, cases, cfg.integrator,
                                         cfg.metrics.threshold_pct, cfg.timing_repeats)
    for case, by_model in trajs.items():
        for name, traj in by_model.items():
            traj.to_npz(Path(cfg.out_dir) / name / f"{case}.npz")
    report = Path(cfg.report_dir)
    io.write_csv(report / "trajectory_metrics.csv", table)
    panels = {k: (cases[k].label, trajs[k]) for k in cases}
    fig = plot_orbits(panels, bearing.clearance, cfg.integrator.t_settle,
                      "Fig. 4 - rotor trajectories: reference vs surrogates")
    io.save_figure(fig, Path(cfg.figure_dir) / "fig4_comparison.png", dpi=130)
    grids = {f"{n}x{m}": ReynoldsSolver(bearing, n, m) for n, m in cfg.paper_grids}
    speed = speed_comparison(surrogates, {"graded": reference, **grids}, cfg.force_eval_states)
    io.write_csv(report / "speed.csv", speed)
    t_ref = table[table.model == "reference"].wall_time_s.sum()
    sparse_speed = {}
    if cfg.sparse_reference.enabled:
        # the paper-like reference: the same system assembled and solved by SuperLU on every call
        from fluidfilm.reynolds.sparse_reference import SparseReferenceModel

        sparse = SparseReferenceModel(bearing, tuple(cfg.reference.coarse), tuple(cfg.reference.dense),
                                      cfg.reference.eps_threshold, cfg.reference.cavitation)
        sparse_speed = sparse_reference_speed(sparse, _with_dense_share(table, trajs, bearing.clearance,
                                                                         cfg.reference.eps_threshold),
                                              cfg.rotor, cases, cfg.integrator, surrogates,
                                              cfg.sparse_reference.force_states, cfg.sparse_reference.trajectory_steps)
    summary = {"machine": machine(), "trajectory_wall_time_reference_s": float(t_ref)}
    per_eval = dict(zip(speed.model, speed.time_per_eval_us))
    for name in surrogates:
        rows = table[table.model == name]
        summary[f"trajectory_wall_time_{name}_s"] = float(rows.wall_time_s.sum())
        summary[f"speedup_trajectory_{name}"] = float(t_ref / rows.wall_time_s.sum())
        summary[f"speedup_force_eval_{name}"] = per_eval["graded"] / per_eval[name]
        for grid in grids:
            summary[f"speedup_force_eval_{name}_vs_{grid}"] = per_eval[grid] / per_eval[name]
        summary[f"satisfactory_cases_{name}"] = "".join(rows[rows.satisfactory == True].case)  # noqa: E712
        for _, r in rows.iterrows():
            summary[f"orbit_rms_pct_{name}_{r.case}"] = float(r.rms_pct)
            summary[f"orbit_hausdorff_pct_{name}_{r.case}"] = float(r.hausdorff_pct)
            # per trajectory: force evaluations outside the surrogate's training domain (logged, not warned once)
            summary[f"outside_domain_evals_{name}_{r.case}"] = float(r.n_outside_domain)
    summary.update({k: v for k, v in sparse_speed.items() if k != "sparse_per_case"})
    if sparse_speed:
        summary["sparse_reference_per_case"] = sparse_speed["sparse_per_case"]
    io.write_json(report / "comparison.json", summary)
    with tracking.run(cfg.tracking, "compare", OmegaConf.to_container(cfg, resolve=True)):
        tracking.log_metrics({k: v for k, v in summary.items() if isinstance(v, float)})
        tracking.log_artifact(Path(cfg.figure_dir) / "fig4_comparison.png")
    pd.set_option("display.width", 200)
    print(table[["case", "model", "status", "span", "rms_pct", "hausdorff_pct", "satisfactory", "wall_time_s"]])
    print(speed)


if __name__ == "__main__":
    io.run_interruptible(main, "the model comparison", "run the same command again")
