"""The paper's comparisons: trajectory accuracy per case, speed side by side, training time over seeds.

Every model runs through the same integrator with the same settings, and
timings of two models are taken in the same run, on the same machine.
"""
from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from fluidfilm.core.force_model import ForceModel
from fluidfilm.rotor.cases import case_summary, run_case
from fluidfilm.perf.speed import sample_states, time_per_force_eval


def trajectory_comparison(models: Mapping[str, ForceModel], reference_name: str, rotor_cfg: Mapping,
                          cases: Mapping[str, Mapping], integrator_cfg: Mapping, threshold_pct: float,
                          repeats: int = 3, after_run: Callable[[str, ForceModel], dict] | None = None
                          ) -> tuple[pd.DataFrame, dict]:
    """Run every case with every model; score each against the reference.

    Returns a table (one row per case and model: orbit statistics, distances
    from the reference, satisfactory or not, median wall time of ``repeats``
    runs) and the trajectories {case: {model: Trajectory}}.  ``after_run(name, model)``, where
    given, is called after each case's last run of a model and its dict joins that row (e.g. the
    counters a model keeps per trajectory).
    """
    clearance = models[reference_name].bearing.clearance
    t_settle = integrator_cfg["t_settle"]
    rows: list[dict] = []
    trajs: dict[str, dict] = {}
    for name, case in cases.items():
        trajs[name] = {}
        extra: dict[str, dict] = {}
        for model_name, model in models.items():
            runs = [run_case(model, rotor_cfg, case, integrator_cfg) for _ in range(repeats)]
            traj = runs[-1]
            traj.wall_time_s = float(np.median([r.wall_time_s for r in runs]))
            trajs[name][model_name] = traj
            extra[model_name] = after_run(model_name, model) if after_run is not None else {}
        ref = trajs[name][reference_name]
        for model_name, traj in trajs[name].items():
            is_ref = model_name == reference_name
            s = case_summary(traj, clearance, t_settle, None if is_ref else ref, None if is_ref else threshold_pct)
            rows.append({"case": name, "model": model_name, **s, **extra[model_name]})
    return pd.DataFrame(rows), trajs


def speed_comparison(models: Mapping[str, ForceModel], references: Mapping[str, ForceModel], n_states: int = 5000,
                     repeats: int = 7) -> pd.DataFrame:
    """Time per force evaluation of every model in the same compiled loop over the same states."""
    first = next(iter(references.values()))
    x, v = sample_states(first.bearing.clearance, n_states)
    rows = []
    for group, items in (("reference", references), ("surrogate", models)):
        for name, model in items.items():
            rows.append({"model": name, "kind": group, "time_per_eval_us": 1e6 * time_per_force_eval(model, x, v, repeats)})
    return pd.DataFrame(rows)


def reduction_pct(single, split):
    """How much less time the split model took, in % of the single model's time (the paper: 26 %)."""
    return 100.0 * (single - split) / single


def summarise_training_times(rows: pd.DataFrame) -> dict:
    """Per-seed times -> medians, spread and the reduction in % (median and range over seeds)."""
    out: dict = {}
    piv = rows.pivot(index="seed", columns="model", values="time_s")
    for m in ("single", "split"):
        out[f"train_time_{m}_s"] = float(piv[m].median())
        out[f"train_time_{m}_s_min"] = float(piv[m].min())
        out[f"train_time_{m}_s_max"] = float(piv[m].max())
    red = reduction_pct(piv["single"], piv["split"])
    out["train_time_reduction_pct"] = reduction_pct(out["train_time_single_s"], out["train_time_split_s"])
    out["train_time_reduction_pct_per_seed_min"] = float(red.min())
    out["train_time_reduction_pct_per_seed_max"] = float(red.max())
    out["n_seeds"] = int(len(piv))
    return out


def sparse_reference_speed(sparse, table: pd.DataFrame, rotor_cfg: Mapping, cases: Mapping[str, Mapping],
                           integrator_cfg: Mapping, surrogates: Mapping[str, object], n_states: int = 200,
                           n_steps: int = 50, repeats: int = 3) -> dict:
    """Speed-ups of surrogates over the paper-like sparse reference, per force and per trajectory.

    Per force: the same compiled loop over the same states as ``speed_comparison`` (the sparse model's
    kernel calls back into Python), fewer states since one solve takes milliseconds.
    Per trajectory: a full case would take minutes per case, so each case runs ``n_steps`` steps through
    the same integrator with the sparse model; its measured seconds per force evaluation (callback
    included), scaled by the dense grid's extra cost for the share of the reference trajectory's recorded
    states above the grid threshold, times the reference trajectory's number of force evaluations, is the
    sparse model's estimated trajectory time.  The surrogates' trajectory times are the measured ones in
    ``table``.
    """
    from fluidfilm.rotor.cases import run_case
    from fluidfilm.perf.speed import sample_states, time_per_force_eval

    c = sparse.bearing.clearance
    x, v = sample_states(c, n_states)
    t_sparse = time_per_force_eval(sparse, x, v, repeats)
    # the dense grid's cost relative to the coarse one, per force at the same states
    xd = x / np.maximum(np.hypot(*x.T), 1e-30)[:, None] * 0.93 * c
    t_dense = time_per_force_eval(sparse, xd[: max(20, n_states // 4)], v[: max(20, n_states // 4)], repeats)
    out: dict = {"sparse_time_per_force_us": 1e6 * t_sparse, "sparse_time_per_force_dense_us": 1e6 * t_dense}
    for name, model in surrogates.items():
        out[f"speedup_force_{name}_vs_sparse_reference"] = t_sparse / time_per_force_eval(model, x, v, repeats)
    est_total = 0.0
    per_case = {}
    # compile the integrator for the callback kernel once, outside any timing
    first = next(iter(cases.values()))
    run_case(sparse, rotor_cfg, first, dict(integrator_cfg) | {"t_end": integrator_cfg["dt"]})
    for case_name, case in cases.items():
        short = dict(integrator_cfg) | {"t_end": n_steps * integrator_cfg["dt"]}
        traj = run_case(sparse, rotor_cfg, case, short)
        per_eval = traj.wall_time_s / max(traj.n_force_evals, 1)
        ref = table[(table.case == case_name) & (table.model == "reference")].iloc[0]
        dense_share = float(ref["dense_share"]) if "dense_share" in ref.index else 0.0
        est = ref.n_force_evals * per_eval * (1.0 + dense_share * (t_dense / t_sparse - 1.0))
        per_case[case_name] = {"per_eval_in_integrator_us": 1e6 * per_eval, "estimated_s": est}
        est_total += est
    out["sparse_trajectory_per_eval_us_median"] = float(np.median([p["per_eval_in_integrator_us"]
                                                                   for p in per_case.values()]))
    out["sparse_trajectory_time_estimated_s"] = est_total
    out["sparse_per_case"] = per_case
    for name in surrogates:
        rows = table[table.model == name]
        out[f"speedup_trajectory_{name}_vs_sparse_reference"] = est_total / float(rows.wall_time_s.sum())
    return out


def ensemble_study(reference: ForceModel, members: Mapping[str, ForceModel], rotor_cfg: Mapping,
                   cases: Mapping[str, Mapping], integrator_cfg: Mapping, threshold_pct: float, rel_tol: float,
                   hybrid_rel_tols: Sequence[float], floor_N: float, repeats: int = 3,
                   held_out: pd.DataFrame | None = None) -> tuple[pd.DataFrame, dict]:
    """The members (seeds of one surrogate) one by one, their ensemble and hybrids, through the seven cases.

    Every model runs every case through the same integrator (``trajectory_comparison``); the ensemble
    (mean of the members) records the share of its force evaluations whose members disagree beyond
    ``rel_tol`` (``fluidfilm.surrogate.ensemble``), each hybrid (one per tolerance in ``hybrid_rel_tols``) the
    share it answered with the reference.  Returns the per-case table and a summary (per model: the
    satisfactory cases, orbit errors, flagged/fallback shares, trajectory time and its speed-up on the
    reference).  ``held_out`` (a test set: X1, X2, V1, V2, F1, F2) adds the flag's calibration there
    (``ensemble.flag_calibration``: does the flag mark the states where the ensemble is wrong?).
    """
    from fluidfilm.surrogate.ensemble import EnsembleForceModel, HybridForceModel, flag_calibration

    ensemble = EnsembleForceModel(list(members.values()), rel_tol=rel_tol, floor_N=floor_N, name="ensemble")
    hybrids = {f"hybrid_{tol:g}": HybridForceModel(list(members.values()), reference, rel_tol=tol, floor_N=floor_N,
                                                   name=f"hybrid_{tol:g}") for tol in hybrid_rel_tols}
    counted: dict[str, EnsembleForceModel] = {"ensemble": ensemble, **hybrids}
    models: dict[str, ForceModel] = {"reference": reference, **members, **counted}

    def counters(name: str, model: ForceModel) -> dict:
        if name not in counted:
            return {}
        m = counted[name]
        return {"n_flagged": m.n_flagged, "flagged_share": m.n_flagged / max(m.n_evaluations, 1)}

    table, _ = trajectory_comparison(models, "reference", rotor_cfg, cases, integrator_cfg, threshold_pct,
                                     repeats, after_run=counters)
    t_ref = float(table[table.model == "reference"].wall_time_s.sum())
    summary: dict = {"members": list(members), "rel_tol": rel_tol, "hybrid_rel_tols": list(hybrid_rel_tols),
                     "floor_N": floor_N, "threshold_pct": threshold_pct, "n_cases": len(cases),
                     "trajectory_wall_time_reference_s": t_ref, "models": {}}
    for name in models:
        if name == "reference":
            continue
        rows = table[table.model == name]
        good = "".join(rows[rows.satisfactory == True].case)  # noqa: E712
        entry = {"satisfactory_cases": good, "n_satisfactory": len(good),
                 "orbit_rms_pct_max": float(rows.rms_pct.max()), "orbit_hausdorff_pct_max": float(rows.hausdorff_pct.max()),
                 "trajectory_wall_time_s": float(rows.wall_time_s.sum()),
                 "speedup_trajectory": t_ref / float(rows.wall_time_s.sum())}
        if name in counted:
            entry["flagged_share_mean"] = float(rows.flagged_share.mean())
            entry["flagged_share_max"] = float(rows.flagged_share.max())
        summary["models"][name] = entry
    summary["n_seeds_all_cases"] = sum(summary["models"][m]["n_satisfactory"] == len(cases) for m in members)
    if held_out is not None:
        summary["flag_calibration"] = flag_calibration(ensemble, held_out[["X1", "X2"]].to_numpy(),
                                                       held_out[["V1", "V2"]].to_numpy(),
                                                       held_out[["F1", "F2"]].to_numpy())
    return table, summary


# --- the study run by experiments/compare.py (conf/compare.yaml) ---

INPUTS = ("models",)
OUTPUTS = {"out_dir": [""], "report_dir": ["trajectory_metrics.csv", "speed.csv", "comparison.json"],
           "figure_dir": ["fig4_comparison.png"]}


def tracking_run(cfg):
    return "compare", None


def _with_dense_share(table, trajs, clearance, eps_threshold):
    """The table plus, per row, the share of recorded states at or above the grid policy's threshold."""
    table = table.copy()
    table["dense_share"] = [float((trajs[r.case][r.model].eccentricity(clearance) >= eps_threshold).mean())
                            for r in table.itertuples()]
    return table


def run(cfg):
    """Fig. 4 a-g overlays (reference / surrogates) and the speed comparison, measured side by side."""
    from fluidfilm import ReynoldsSolver, io, load_surrogate
    from fluidfilm.perf.benchmarking import machine
    from fluidfilm.studies.plots import plot_orbits
    from fluidfilm.workflow.config import bearing_from_cfg, reference_from_cfg
    from fluidfilm.workflow.tracking import Logged

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
        # the paper's own reading: span and shape after removing the mean offset (rotor.metrics)
        summary[f"satisfactory_cases_{name}_paper_reading"] = "".join(
            rows[rows.satisfactory_paper_reading == True].case)  # noqa: E712
        for _, r in rows.iterrows():
            summary[f"orbit_rms_pct_{name}_{r.case}"] = float(r.rms_pct)
            summary[f"orbit_hausdorff_pct_{name}_{r.case}"] = float(r.hausdorff_pct)
            summary[f"orbit_span_err_pct_{name}_{r.case}"] = float(r.span_err_pct)
            summary[f"orbit_shape_pct_{name}_{r.case}"] = float(r.shape_pct)
            # per trajectory: force evaluations outside the surrogate's training domain (logged, not warned once)
            summary[f"outside_domain_evals_{name}_{r.case}"] = float(r.n_outside_domain)
    summary.update({k: v for k, v in sparse_speed.items() if k != "sparse_per_case"})
    if sparse_speed:
        summary["sparse_reference_per_case"] = sparse_speed["sparse_per_case"]
    io.write_json(report / "comparison.json", summary)
    pd.set_option("display.width", 200)
    print(table[["case", "model", "status", "span", "rms_pct", "hausdorff_pct", "satisfactory", "wall_time_s"]])
    print(speed)
    return Logged({k: v for k, v in summary.items() if isinstance(v, float)},
                  [Path(cfg.figure_dir) / "fig4_comparison.png"])
