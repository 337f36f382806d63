"""The paper's training-time comparison: single vs three split networks, same rows, same protocol, many seeds.

    python experiments/train_time.py                       # reports/train_time.json
    python experiments/train_time.py protocol=adam         # the second protocol
    python experiments/train_time.py samples_per_seed=40000 ranking_check.enabled=false

Per seed: one random subsample of the dataset, one 70/15/15 division; the
single network and the three split networks (eps 0-0.5, 0.5-0.7, > 0.7, each
with its own min-max map) train on it to the validation stopping rule.
Reported (src/fluidfilm/studies/train_time.py): the reduction of the
mean training time 100 (1 - mean T_split / mean T_single) with a paired
bootstrap 95 % confidence interval (seeds are added, up to ``seeds_max`` or
the time budget, until its half-width is at most the target), the seeds the
target would need, the mean of the per-seed reductions, the time the
split networks need to reach the single network's final validation error
on the same rows, every network's epochs / stop reason / errors / time, and
a ranking check at twice the subsample size.  Every finished seed is kept
under ``cache_dir``: run the same command again after an interruption and it
resumes at the next seed (delete the folder to measure afresh).  Seeds run as parallel
processes (``n_jobs``), each single-threaded; single and split of one seed
run in the same process, one after the other.
"""
from __future__ import annotations

import math
import time

import hydra
from omegaconf import DictConfig, OmegaConf

from fluidfilm import io
from fluidfilm.workflow import tracking
from fluidfilm.perf.benchmarking import machine
from fluidfilm.workflow.config_check import check_config
from fluidfilm.studies.train_time import ranking, study
from fluidfilm.surrogate.training import read_dataset


@hydra.main(config_path="../conf", config_name="train_time", version_base="1.3")
def main(cfg: DictConfig) -> None:
    check_config(cfg)  # a mistyped value or an unknown key is refused here, before any work
    if not (cfg.main_study or cfg.full_scale.enabled):
        raise ValueError("main_study=false and full_scale.enabled=false: nothing to run")
    c = OmegaConf.to_container(cfg, resolve=True)
    protocol = c["protocol"]
    boundaries = list(cfg.boundaries)
    frame, meta = read_dataset(cfg.dataset_dir)
    out: dict = {"train_time_protocol": protocol["name"], "protocol": protocol, "boundaries": boundaries,
                 "dataset_samples": len(frame), "machine": machine(), "date": time.strftime("%Y-%m-%d")}
    head: dict = {"runs": []}
    if cfg.main_study:
        print(f"training-time study: protocol {protocol['name']}, {cfg.samples_per_seed:,} of {len(frame):,} samples "
              f"per seed, at least {cfg.seeds_min} seeds", flush=True)
        head = study(frame, meta, protocol, boundaries, cfg.samples_per_seed, cfg.seeds_min, cfg.seeds_max,
                     cfg.ci_half_width_target_pct, cfg.n_jobs, cfg.bootstrap_resamples, cfg.budget_s,
                     cache_dir=cfg.cache_dir)
        out.update({k: v for k, v in head.items() if k != "runs"})
        out.update(ranking=ranking(head),
                   # the old report's name for "every run stopped by its rule"
                   all_reached_target=head["train_time_converged"], target_val_rel_rmse=None,
                   max_epochs=protocol["max_epochs"], n_seeds=head["train_time_seeds"])
        rc = cfg.ranking_check
        if rc.enabled:
            print(f"ranking check: {rc.samples_per_seed:,} samples per seed, {rc.seeds} seeds", flush=True)
            check = study(frame, meta, protocol, boundaries, rc.samples_per_seed, rc.seeds, rc.seeds, 0.0, cfg.n_jobs,
                          cfg.bootstrap_resamples, math.inf, seed_offset=1000, cache_dir=cfg.cache_dir)
            out["ranking_check"] = {k: v for k, v in check.items() if k != "runs"} | {
                "ranking": ranking(check), "same_ranking": ranking(check) == ranking(head),
                # the point estimates' signs say little when both intervals hold 0; overlapping intervals say the
                # two sizes are not measurably different
                "consistent": bool(
                    check["train_time_reduction_ci95_low"] <= head["train_time_reduction_ci95_high"]
                    and head["train_time_reduction_ci95_low"] <= check["train_time_reduction_ci95_high"]),
                "runs": check["runs"]}
    fs = cfg.full_scale
    if fs.enabled:
        proto_fs = dict(protocol) | OmegaConf.to_container(fs.protocol, resolve=True)
        print(f"full-scale run: protocol {proto_fs['name']} on all {len(frame):,} samples", flush=True)
        full = study(frame, meta, proto_fs, boundaries, len(frame), 1, 1, 0.0, 1, cfg.bootstrap_resamples, math.inf,
                     seed_offset=2000, cache_dir=cfg.cache_dir)
        out["full_scale"] = {k: v for k, v in full.items() if k != "runs"} | {
            "ranking": ranking(full), "protocol": proto_fs, "runs": full["runs"]}
    out["runs"] = head["runs"]
    io.write_json(cfg.out, out)
    with tracking.run(cfg.tracking, "train_time", c) as parent:
        tracking.log_metrics({k: float(v) for k, v in out.items()
                              if isinstance(v, (int, float)) and not isinstance(v, bool)})
        if "train_time_converged" in out:
            tracking.log_metric("train_time_converged", float(out["train_time_converged"]))
        if "full_scale" in out:
            tracking.log_metrics({f"full_scale.{k}": float(v) for k, v in out["full_scale"].items()
                                  if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)})
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
