"""reports/metrics.json and reports/paper_comparison.md: our numbers beside the paper's.

    python experiments/report.py
"""
import json
from pathlib import Path

import hydra
import pandas as pd
from omegaconf import DictConfig, OmegaConf

from fluidfilm import io, tracking


def _load(path):
    return json.loads(Path(path).read_text())


def _f(x, spec=".1f"):
    return "n/a" if x is None else format(x, spec)


@hydra.main(config_path="../conf", config_name="report", version_base="1.3")
def main(cfg: DictConfig) -> None:
    rd = Path(cfg.report_dir)
    comp = _load(rd / "comparison.json")
    tt = _load(rd / "train_time.json")
    traj = pd.read_csv(rd / "trajectory_metrics.csv")
    speed = pd.read_csv(rd / "speed.csv")
    models = {m: _load(Path(cfg.models_dir) / m / "report.json") for m in cfg.models}
    data_meta = _load(Path(cfg.dataset_dir) / "_metadata.json")
    paper = cfg.paper
    metrics = {
        "train_time_single_s": tt["train_time_single_s"],
        "train_time_split_s": tt["train_time_split_s"],
        "train_time_reduction_pct": tt["train_time_reduction_pct"],
        "train_time_reduction_pct_per_seed_min": tt["train_time_reduction_pct_per_seed_min"],
        "train_time_reduction_pct_per_seed_max": tt["train_time_reduction_pct_per_seed_max"],
        "train_time_all_reached_target": tt["all_reached_target"],
        "speedup_trajectory_single": comp["speedup_trajectory_single"],
        "speedup_trajectory_split": comp["speedup_trajectory_split"],
        "speedup_trajectory_best": comp["speedup_trajectory_best"],
        "speedup_force_eval": comp["speedup_force_eval_split"],
        "speedup_force_eval_single": comp["speedup_force_eval_single"],
        "speedup_force_eval_split": comp["speedup_force_eval_split"],
        "speedup_force_eval_best": comp["speedup_force_eval_best"],
        "dataset_samples": data_meta["n_samples"],
        "dataset_generation_s": data_meta["generation_seconds_last_run"],
    }
    for m in ("single", "split", "best"):
        rows = traj[traj.model == m]
        for _, r in rows.iterrows():
            metrics[f"orbit_rms_pct_{m}_{r.case}"] = float(r.rms_pct)
        metrics[f"satisfactory_cases_{m}"] = int(rows.satisfactory.astype(bool).sum())
    for name, rep in models.items():
        metrics[f"test_rel_err_median_{name}"] = rep["metrics"]["test_rel_err_median"]
        metrics[f"test_rel_err_p99_{name}"] = rep["metrics"]["test_rel_err_p99"]
    control = _load(rd / "control.json")
    active_meta = _load(Path(cfg.active_dataset_dir) / "_metadata.json")
    active = _load(Path(cfg.models_dir) / cfg.active_model / "report.json")
    ctl = control["controllers"]
    metrics.update({
        "controller_amplitude_reduction_pct": control["controller_amplitude_reduction_pct"],
        "mpc_amplitude_reduction_pct": control["mpc_amplitude_reduction_pct"],
        "controller_decision_ms_dqn": ctl["dqn"]["decision_ms_median"],
        "controller_decision_ms_mpc": ctl["mpc"]["decision_ms_median"],
        "active_dataset_samples": active_meta["n_samples"],
        "active_dataset_generation_s": active_meta["generation_seconds_last_run"],
        "test_rel_err_median_active": active["metrics"]["test_rel_err_median"],
    })
    # fast surrogates (docs/fast_surrogates.md): per-force cost, batched trajectories, controller training
    per_eval = dict(zip(speed.model, speed.time_per_eval_us))
    metrics["force_eval_us_best"] = float(per_eval["best"])
    batch = _load(rd / "batch_speed.json")
    metrics["trajectories_per_s_batch_speedup"] = batch["trajectories_per_s_batch_speedup"]
    metrics["trajectories_per_s_single_speedup"] = batch["trajectories_per_s_single_speedup"]
    cts = _load(rd / "controller_training_speed.json")
    metrics["controller_training_speedup"] = cts["controller_training_speedup"]
    io.write_json(rd / "metrics.json", metrics)

    thr = cfg.metrics.threshold_pct
    case_rows = []
    for case in sorted(traj.case.unique()):
        ref = traj[(traj.case == case) & (traj.model == "reference")].iloc[0]
        cells = []
        for m in ("single", "split", "best"):
            r = traj[(traj.case == case) & (traj.model == m)].iloc[0]
            ok = "yes" if bool(r.satisfactory) else "no"
            cells.append(f"{_f(r.rms_pct, '.2f')} / {_f(r.hausdorff_pct, '.2f')} ({ok})")
        case_rows.append(f"| {case} | {ref.span:.3f} | " + " | ".join(cells) + " |")
    speed_rows = "\n".join(f"| {r.model} | {r.kind} | {r.time_per_eval_us:.2f} |" for r in speed.itertuples())
    seeds = "\n".join(f"| {r['seed']} | {r['model']} | {r['time_s']:.1f} | {'yes' if r['reached_target'] else 'no'} | "
                      f"{', '.join(f'{v:.3f}' for v in r['val_rel_rmse'])} |" for r in tt["runs"])
    model_rows = "\n".join(
        f"| {n} | {json.dumps(r['config']['model'])} | {r['config']['split']['boundaries']} | "
        f"{r['config']['scaling']['kind']} | {r['metrics']['test_rel_err_median']:.4f} | "
        f"{r['metrics']['test_rel_err_p99']:.3f} | {r['report']['train_time_s']:.0f} |" for n, r in models.items())
    md = f"""# The paper's comparisons, reproduced

Machine: **{comp['machine']}** (no GPU). Paper: {paper.machine}.
All numbers below are regenerated by `dvc repro`; headline values are in `reports/metrics.json`.

## Headline numbers

| quantity | paper | ours |
|---|---|---|
| dataset samples | {paper.samples:,} | {data_meta['n_samples']:,} |
| dataset generation | hours (not given) | {data_meta['generation_seconds_last_run']:.0f} s |
| training time, single network | {paper.train_time_single_s / 3600:.2f} h | {tt['train_time_single_s']:.0f} s (median of {tt['n_seeds']} seeds, {tt['train_time_single_s_min']:.0f}-{tt['train_time_single_s_max']:.0f} s) |
| training time, split (3 networks) | {paper.train_time_split_s / 3600:.2f} h | {tt['train_time_split_s']:.0f} s ({tt['train_time_split_s_min']:.0f}-{tt['train_time_split_s_max']:.0f} s) |
| training time reduction, split vs single | {paper.train_time_reduction_pct} % | {tt['train_time_reduction_pct']:.0f} % (per seed {tt['train_time_reduction_pct_per_seed_min']:.0f} to {tt['train_time_reduction_pct_per_seed_max']:.0f} %) |
| speed-up per force evaluation, split vs reference | {paper.speedup_force_model}x | {comp['speedup_force_eval_split']:.1f}x (vs 30x30: {comp['speedup_force_eval_split_vs_30x30']:.1f}x, vs 55x55: {comp['speedup_force_eval_split_vs_55x55']:.1f}x) |
| speed-up per trajectory, single / split / best | {paper.speedup_force_model}x | {comp['speedup_trajectory_single']:.1f}x / {comp['speedup_trajectory_split']:.1f}x / {comp['speedup_trajectory_best']:.1f}x |
| cases satisfactory, single | e only | {comp['satisfactory_cases_single'] or 'none'} |
| cases satisfactory, split | a-e | {comp['satisfactory_cases_split'] or 'none'} |
| cases satisfactory, best (ours) | - | {comp['satisfactory_cases_best'] or 'none'} |

Training-time rule: each network trains until its validation relative RMS force error reaches
{tt['target_val_rel_rmse']} (at most {tt['max_epochs']} epochs; a run that does not get there counts with its full time
and is marked). All targets reached: {tt['all_reached_target']}.

## Fig. 4: trajectory accuracy per case

RMS distance / Hausdorff distance from the reference orbit over the settled cycles, in % of the clearance;
"satisfactory" means both are within {thr} %.

| case | reference span / c | single | split | best |
|---|---|---|---|---|
{chr(10).join(case_rows)}

![Fig. 4](figures/fig4_comparison.png)

## Models

| model | network | split | scaling | test median rel. error | test p99 | train s |
|---|---|---|---|---|---|---|
{model_rows}

## Speed per force evaluation (same compiled loop, same states)

| model | kind | us per evaluation |
|---|---|---|
{speed_rows}

## Training time per seed

| seed | model | s to target (or total) | reached | final val. rel. RMSE per network |
|---|---|---|---|---|
{seeds}

## Active conical bearing (Section 3.2, Fig. 5), evaluated on the reference model

Imbalance ramp {control['scenario']['imbalance_start']:g} -> {control['scenario']['imbalance_end']:g} kg m over
{control['scenario']['ramp_time']:g} s; sleeve positions {[round(1e3 * v, 2) for v in control['sleeve_positions_m']]} mm;
the DQN was trained on the surrogate `models/{cfg.active_model}` (dataset: {active_meta['n_samples']:,} samples with the
sleeve as an input, {active_meta['generation_seconds_last_run']:.0f} s; held-out median error
{active['metrics']['test_rel_err_median']:.4f}). Paper (qualitative): the DQN agent "tends to restrain the growth" of
the orbit, the passive bearing's orbit grows.

| controller | max amplitude um | reduction vs none % | final amplitude um | mean friction W | sleeve travel mm | ms per decision | axial force N (last rev.) |
|---|---|---|---|---|---|---|---|
{chr(10).join(f"| {n} | {1e6 * r['max_amplitude_m']:.1f} | {r['amplitude_reduction_pct']:.1f} | {1e6 * r['final_amplitude_m']:.1f} | {r['mean_friction_power_W']:.2f} | {1e3 * r['sleeve_travel_m']:.1f} | {r['decision_ms_median']:.3f} | {r['axial_force_N_mean_last_rev']:.1f} |" for n, r in ctl.items())}

![Fig. 5 a](figures/fig5_a_dqn.png) ![Fig. 5 b](figures/fig5_b_none.png) ![MPC](figures/fig5_c_mpc.png)

![Fig. 5 amplitude](figures/fig5_amplitude.png)

## Reference model

![Fig. 2](figures/fig2_grid.png)

![Fig. 3](figures/fig3_velocity.png)
"""
    io.write_text(rd / "paper_comparison.md", md)
    with tracking.run(cfg.tracking, "paper_comparison", OmegaConf.to_container(cfg, resolve=True)):
        if cfg.tracking.enabled:
            import mlflow
            mlflow.log_metrics({k: float(v) for k, v in metrics.items() if isinstance(v, (int, float))})
            mlflow.log_artifact(str(rd / "paper_comparison.md"))
    print(json.dumps(metrics, indent=1))


if __name__ == "__main__":
    main()
