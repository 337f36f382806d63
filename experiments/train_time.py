"""The paper's training-time comparison: single vs three split networks, same rows, same protocol, many seeds.

    python experiments/train_time.py                       # reports/train_time.json
    python experiments/train_time.py protocol=adam         # the second protocol
    python experiments/train_time.py samples_per_seed=40000 ranking_check.enabled=false

Per seed: one random subsample of the dataset, one 70/15/15 division; the
single network and the three split networks (eps 0-0.5, 0.5-0.7, > 0.7, each
with its own min-max map) train on it to the validation stopping rule.
Reported: the mean of the per-seed reductions 100 (1 - T_split / T_single)
with a bootstrap 95 % confidence interval (seeds are added, up to
``seeds_max``, until its half-width is at most the target), the time the
split networks need to reach the single network's final validation error
on the same rows, every network's epochs / stop reason / errors / time, and
a ranking check at twice the subsample size.  Seeds run as parallel
processes (``n_jobs``), each single-threaded; single and split of one seed
run in the same process, one after the other.
"""
from __future__ import annotations

import math
import time

import hydra
import numpy as np
from joblib import Parallel, delayed
from omegaconf import DictConfig, OmegaConf
from scipy.stats import bootstrap

from fluidfilm import io, tracking
from fluidfilm.benchmarking import machine
from fluidfilm.surrogate.protocol import band_sq_errors, subsample, time_to_accuracy, train_protocol_model
from fluidfilm.surrogate.training import read_dataset
from fluidfilm.config_check import check_config


def _net_summary(n: dict) -> dict:
    keys = ("eps_low", "eps_high", "n_train", "n_val", "n_test", "epochs", "best_epoch", "stop_reason",
            "train_mse", "val_mse", "test_mse", "train_rel_rmse", "val_rel_rmse", "test_rel_rmse", "train_time_s")
    out = {k: n[k] for k in keys}
    out["eps_high"] = None if math.isinf(out["eps_high"]) else out["eps_high"]
    return out


def run_seed(sub, meta, protocol: dict, boundaries, seed: int) -> dict:
    """Single and split model on one subsample; the order alternates with the seed's parity."""
    order = ("single", "split") if seed % 2 == 0 else ("split", "single")
    models, reps = {}, {}
    for which in order:
        models[which], reps[which] = train_protocol_model(sub, meta, protocol, [] if which == "single" else boundaries,
                                                          seed=seed, n_samples=None, name=which)
    # the single network's final error on the validation rows of each split network
    targets = band_sq_errors(reps["single"]["_sub"], reps["single"]["_division"].val, models["single"], boundaries)
    tte = time_to_accuracy(reps["split"], targets)
    row = {"seed": seed, "order": list(order), "time_to_equal_accuracy_split_s": tte}
    for which, rep in reps.items():
        row[which] = {"train_time_s": rep["train_time_s"], "train_time_parallel_s": rep["train_time_parallel_s"],
                      "converged": rep["converged"], "stop_reasons": rep["stop_reasons"],
                      "val_rel_rmse": rep["val_rel_rmse"], "test_rel_rmse": rep["test_rel_rmse"],
                      "networks": [_net_summary(n) for n in rep["networks"]]}
    row["reduction_pct"] = 100.0 * (1.0 - row["split"]["train_time_s"] / row["single"]["train_time_s"])
    row["reduction_at_equal_accuracy_pct"] = (None if tte is None else
                                              100.0 * (1.0 - tte / row["single"]["train_time_s"]))
    return row


def ci_half_width(values, n_resamples: int, seed: int = 0) -> tuple[float, float, float]:
    """Bootstrap (percentile) 95 % interval of the mean: (low, high, half-width)."""
    v = np.asarray(values, dtype=float)
    if len(v) < 2:
        return math.nan, math.nan, math.inf
    res = bootstrap((v,), np.mean, confidence_level=0.95, n_resamples=n_resamples, method="percentile",
                    random_state=np.random.default_rng(seed))
    lo, hi = float(res.confidence_interval.low), float(res.confidence_interval.high)
    return lo, hi, 0.5 * (hi - lo)


def study(frame, meta, protocol: dict, boundaries, n_samples: int, seeds_min: int, seeds_max: int, target_hw: float,
          n_jobs: int, n_resamples: int, budget_s: float, seed_offset: int = 0) -> dict:
    t0 = time.perf_counter()
    rows = []
    next_seed = seed_offset
    batch = max(seeds_min, 1)
    while True:
        seeds = list(range(next_seed, next_seed + batch))
        next_seed += batch
        subs = [frame.iloc[subsample(len(frame), n_samples, s)].reset_index(drop=True) for s in seeds]
        for r in Parallel(n_jobs=n_jobs, return_as="generator")(delayed(run_seed)(sub, meta, protocol, boundaries, s)
                                                                for sub, s in zip(subs, seeds)):
            rows.append(r)
            print(f"  seed {r['seed']}: single {r['single']['train_time_s']:.1f} s "
                  f"{r['single']['stop_reasons']}, split {r['split']['train_time_s']:.1f} s "
                  f"{r['split']['stop_reasons']}, reduction {r['reduction_pct']:.1f} %, to equal accuracy "
                  f"{r['time_to_equal_accuracy_split_s']}", flush=True)
        red = [r["reduction_pct"] for r in rows]
        lo, hi, hw = ci_half_width(red, n_resamples)
        elapsed = time.perf_counter() - t0
        if hw <= target_hw or len(rows) >= seeds_max or elapsed > budget_s:
            break
        batch = max(1, min(n_jobs, seeds_max - len(rows)))
    tte = [r["reduction_at_equal_accuracy_pct"] for r in rows]
    tte_ok = [v for v in tte if v is not None]
    single_t = [r["single"]["train_time_s"] for r in rows]
    split_t = [r["split"]["train_time_s"] for r in rows]
    return {
        "train_time_reduction_pct": float(np.mean(red)),
        "train_time_reduction_ci95": hw,
        "train_time_reduction_ci95_low": lo,
        "train_time_reduction_ci95_high": hi,
        "train_time_reduction_pct_per_seed": red,
        "train_time_reduction_pct_per_seed_min": float(np.min(red)),
        "train_time_reduction_pct_per_seed_max": float(np.max(red)),
        "train_time_seeds": len(rows),
        "train_time_converged": all(r[m]["converged"] for r in rows for m in ("single", "split")),
        "train_time_samples_per_seed": int(n_samples),
        "train_time_single_s": float(np.median(single_t)),
        "train_time_split_s": float(np.median(split_t)),
        "train_time_single_s_min": float(np.min(single_t)), "train_time_single_s_max": float(np.max(single_t)),
        "train_time_split_s_min": float(np.min(split_t)), "train_time_split_s_max": float(np.max(split_t)),
        "train_time_split_parallel_s": float(np.median([r["split"]["train_time_parallel_s"] for r in rows])),
        "val_rel_rmse_single_median": float(np.median([r["single"]["val_rel_rmse"] for r in rows])),
        "val_rel_rmse_split_median": float(np.median([r["split"]["val_rel_rmse"] for r in rows])),
        "test_rel_rmse_single_median": float(np.median([r["single"]["test_rel_rmse"] for r in rows])),
        "test_rel_rmse_split_median": float(np.median([r["split"]["test_rel_rmse"] for r in rows])),
        "reduction_at_equal_accuracy_pct_mean": float(np.mean(tte_ok)) if tte_ok else None,
        "equal_accuracy_reached_seeds": len(tte_ok),
        "study_wall_s": time.perf_counter() - t0,
        "runs": rows,
    }


def ranking(s: dict) -> dict:
    """Which structure trains faster and which is more accurate (validation), by the means over seeds."""
    return {"faster": "split" if s["train_time_reduction_pct"] > 0 else "single",
            "more_accurate": "split" if s["val_rel_rmse_split_median"] < s["val_rel_rmse_single_median"] else "single"}


@hydra.main(config_path="../conf", config_name="train_time", version_base="1.3")
def main(cfg: DictConfig) -> None:
    check_config(cfg)  # a mistyped value or an unknown key is refused here, before any work
    c = OmegaConf.to_container(cfg, resolve=True)
    protocol = c["protocol"]
    boundaries = list(cfg.boundaries)
    frame, meta = read_dataset(cfg.dataset_dir)
    print(f"training-time study: protocol {protocol['name']}, {cfg.samples_per_seed:,} of {len(frame):,} samples "
          f"per seed, at least {cfg.seeds_min} seeds", flush=True)
    head = study(frame, meta, protocol, boundaries, cfg.samples_per_seed, cfg.seeds_min, cfg.seeds_max,
                 cfg.ci_half_width_target_pct, cfg.n_jobs, cfg.bootstrap_resamples, cfg.budget_s)
    out = {k: v for k, v in head.items() if k != "runs"}
    out.update(train_time_protocol=protocol["name"], protocol=protocol, boundaries=boundaries,
               dataset_samples=len(frame), machine=machine(), ranking=ranking(head),
               # the old report's name for "every run stopped by its rule"
               all_reached_target=head["train_time_converged"], target_val_rel_rmse=None,
               max_epochs=protocol["max_epochs"], n_seeds=head["train_time_seeds"])
    rc = cfg.ranking_check
    if rc.enabled:
        print(f"ranking check: {rc.samples_per_seed:,} samples per seed, {rc.seeds} seeds", flush=True)
        check = study(frame, meta, protocol, boundaries, rc.samples_per_seed, rc.seeds, rc.seeds, 0.0, cfg.n_jobs,
                      cfg.bootstrap_resamples, math.inf, seed_offset=1000)
        out["ranking_check"] = {k: v for k, v in check.items() if k != "runs"} | {
            "ranking": ranking(check), "same_ranking": ranking(check) == ranking(head), "runs": check["runs"]}
    fs = cfg.full_scale
    if fs.enabled:
        proto_fs = dict(protocol) | OmegaConf.to_container(fs.protocol, resolve=True)
        print(f"full-scale run: protocol {proto_fs['name']} on all {len(frame):,} samples", flush=True)
        full = study(frame, meta, proto_fs, boundaries, len(frame), 1, 1, 0.0, 1, cfg.bootstrap_resamples, math.inf,
                     seed_offset=2000)
        out["full_scale"] = {k: v for k, v in full.items() if k != "runs"} | {
            "ranking": ranking(full), "protocol": proto_fs, "runs": full["runs"]}
    out["runs"] = head["runs"]
    io.write_json(cfg.out, out)
    with tracking.run(cfg.tracking, "train_time", c) as parent:
        tracking.log_metrics({k: float(v) for k, v in out.items()
                              if isinstance(v, (int, float)) and not isinstance(v, bool)})
        tracking.log_metric("train_time_converged", float(out["train_time_converged"]))
        # one child run per seed and structure: its networks' epochs, times and errors
        for r in head["runs"]:
            for which in ("single", "split"):
                metrics = {}
                for k, n in enumerate(r[which]["networks"]):
                    metrics.update({f"net{k}.epochs": n["epochs"], f"net{k}.train_time_s": n["train_time_s"],
                                    f"net{k}.val_rel_rmse": n["val_rel_rmse"],
                                    f"net{k}.test_rel_rmse": n["test_rel_rmse"] or math.nan,
                                    f"net{k}.train_rel_rmse": n["train_rel_rmse"]})
                tracking.log_child_run(parent, f"train_time seed {r['seed']} {which}", metrics,
                                       params={"seed": r["seed"], "structure": which}, uri=cfg.tracking.uri)
        tracking.log_artifact(str(cfg.out))
    print({k: v for k, v in out.items() if k not in ("runs", "ranking_check", "full_scale", "protocol")})


if __name__ == "__main__":
    io.run_interruptible(main, "the training-time study", "run the same command again")
