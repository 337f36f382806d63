"""The paper's training-time comparison as a library: seeds, the reduction and its confidence interval.

The paper reports one training time per structure (5 h 42 min for the single network, 4.5 h for the
three split networks: 26 % less).  Here each seed draws its own subsample and division, trains both
structures on the same rows to the validation stopping rule, and the study reports

- the **reduction of the mean training time**, 100 (1 - mean T_split / mean T_single) over seeds, the
  estimator that corresponds to the paper's one-number comparison, with a paired percentile-bootstrap
  95 % interval (seeds resampled with both of their times);
- the mean of the per-seed reductions 100 (1 - T_split / T_single) and its interval, as a second view:
  a ratio of two noisy times is skewed (one fast single run gives -200 %), so this mean is the noisier
  of the two and is not the headline;
- how many seeds the interval's target half-width would need, from the 1/sqrt(n) law.

Seeds are added (in batches of ``n_jobs`` parallel processes) until the headline half-width reaches
the target, ``seeds_max`` or the time budget.  With a ``cache_dir`` every finished seed is kept there
(one JSON file, written atomically), so an interrupted study resumes at the next seed; the files are
keyed by everything a seed's result depends on (the dataset's content, the protocol, the split, the
subsample size, the training code and the machine), so a change of any of them trains afresh.
"""
from __future__ import annotations

import hashlib
import json
import math
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from joblib import Parallel, delayed
from scipy.stats import bootstrap

from fluidfilm import io
from fluidfilm.perf.benchmarking import machine
from fluidfilm.surrogate import scaling
from fluidfilm.surrogate.training import levenberg_marquardt, protocol as protocol_module
from fluidfilm.surrogate.training.protocol import band_sq_errors, subsample, time_to_accuracy, train_protocol_model


def _net_summary(n: Mapping) -> dict:
    keys = ("eps_low", "eps_high", "n_train", "n_val", "n_test", "epochs", "best_epoch", "stop_reason",
            "train_mse", "val_mse", "test_mse", "train_rel_rmse", "val_rel_rmse", "test_rel_rmse", "train_time_s")
    out = {k: n[k] for k in keys}
    out["eps_high"] = None if math.isinf(out["eps_high"]) else out["eps_high"]
    return out


def run_seed(sub, meta, protocol: dict, boundaries: Sequence[float], seed: int) -> dict:
    """Single and split model on one subsample; the order alternates with the seed's parity."""
    order = ("single", "split") if seed % 2 == 0 else ("split", "single")
    models, reps = {}, {}
    for which in order:
        models[which], reps[which] = train_protocol_model(sub, meta, protocol, [] if which == "single" else boundaries,
                                                          seed=seed, n_samples=None, name=which)
    # the single network's final error on the validation rows of each split network
    targets = band_sq_errors(reps["single"]["_sub"], reps["single"]["_division"].val, models["single"], boundaries)
    tte = time_to_accuracy(reps["split"], targets)
    row: dict = {"seed": seed, "order": list(order), "time_to_equal_accuracy_split_s": tte}
    for which, rep in reps.items():
        row[which] = {"train_time_s": rep["train_time_s"], "train_time_parallel_s": rep["train_time_parallel_s"],
                      "converged": rep["converged"], "stop_reasons": rep["stop_reasons"],
                      "val_rel_rmse": rep["val_rel_rmse"], "test_rel_rmse": rep["test_rel_rmse"],
                      "networks": [_net_summary(n) for n in rep["networks"]]}
    row["reduction_pct"] = 100.0 * (1.0 - row["split"]["train_time_s"] / row["single"]["train_time_s"])
    row["reduction_at_equal_accuracy_pct"] = (None if tte is None else
                                              100.0 * (1.0 - tte / row["single"]["train_time_s"]))
    return row


def _reduction_of_means(single, split, axis=-1):
    return 100.0 * (1.0 - np.mean(split, axis=axis) / np.mean(single, axis=axis))


def reduction_ci(single_s: Sequence[float], split_s: Sequence[float], n_resamples: int = 10000,
                 seed: int = 0) -> tuple[float, float, float, float]:
    """Reduction of the mean time in % and its paired percentile-bootstrap 95 % interval.

    Returns (reduction, low, high, half-width); with fewer than two seeds the interval is unknown
    (nan, nan, inf).
    """
    s, p = np.asarray(single_s, dtype=float), np.asarray(split_s, dtype=float)
    if s.shape != p.shape or s.ndim != 1:
        raise ValueError(f"need one single and one split time per seed, got {s.shape} and {p.shape}")
    if not (np.all(np.isfinite(s)) and np.all(s > 0) and np.all(np.isfinite(p)) and np.all(p > 0)):
        raise ValueError(f"training times must be positive and finite, got single {s} and split {p}")
    red = float(_reduction_of_means(s, p))
    if len(s) < 2:
        return red, math.nan, math.nan, math.inf
    if np.ptp(s) == 0 and np.ptp(p) == 0:  # no spread: the bootstrap has nothing to resample
        return red, red, red, 0.0
    res = bootstrap((s, p), _reduction_of_means, paired=True, vectorized=True, confidence_level=0.95,
                    n_resamples=n_resamples, method="percentile", random_state=np.random.default_rng(seed))
    lo, hi = float(res.confidence_interval.low), float(res.confidence_interval.high)
    return red, lo, hi, 0.5 * (hi - lo)


def mean_ci(values: Sequence[float], n_resamples: int = 10000, seed: int = 0) -> tuple[float, float, float]:
    """Percentile-bootstrap 95 % interval of a mean: (low, high, half-width)."""
    v = np.asarray(values, dtype=float)
    if len(v) < 2:
        return math.nan, math.nan, math.inf
    if np.ptp(v) == 0:
        return float(v[0]), float(v[0]), 0.0
    res = bootstrap((v,), np.mean, confidence_level=0.95, n_resamples=n_resamples, method="percentile",
                    random_state=np.random.default_rng(seed))
    lo, hi = float(res.confidence_interval.low), float(res.confidence_interval.high)
    return lo, hi, 0.5 * (hi - lo)


def seeds_needed(n_seeds: int, half_width: float, target: float) -> int | None:
    """Seeds for the target half-width by the 1/sqrt(n) law (None when the width is unknown)."""
    if not (math.isfinite(half_width) and target > 0 and n_seeds >= 2):
        return None
    return max(n_seeds, int(math.ceil(n_seeds * (half_width / target) ** 2)))


def seed_cache_key(meta: Mapping, n_rows: int, protocol: Mapping, boundaries: Sequence[float],
                   n_samples: int) -> str:
    """What one seed's result depends on, hashed: the dataset's content (its parts' checksums), the
    protocol, the split, the subsample size, the training code and the machine (times are measured)."""
    code = hashlib.sha256()
    for module in (levenberg_marquardt, protocol_module, scaling):
        code.update(Path(str(module.__file__)).read_bytes())
    what = {"parts": meta.get("parts"), "config_hash": meta.get("config_hash"), "n_rows": int(n_rows),
            "protocol": dict(protocol), "boundaries": [float(b) for b in boundaries], "n_samples": int(n_samples),
            "code": code.hexdigest(), "machine": machine()}
    return hashlib.sha256(json.dumps(what, sort_keys=True, default=str).encode()).hexdigest()[:16]


def _seconds_or_never(t: float | None) -> str:
    return "never" if t is None else f"{t:.1f} s"


def _train_or_load(cache: Path | None, sub, meta, protocol, boundaries, s) -> dict:
    """One seed's row: from the cache when this seed finished before, else trained (and then cached)."""
    path = None if cache is None else cache / f"seed_{s}.json"
    if path is not None and path.exists():
        return json.loads(path.read_text()) | {"resumed": True}
    row = run_seed(sub, meta, protocol, boundaries, s)
    if path is not None:
        io.write_json(path, row)
    return row


def study(frame, meta, protocol: dict, boundaries: Sequence[float], n_samples: int, seeds_min: int, seeds_max: int,
          target_hw: float, n_jobs: int, n_resamples: int, budget_s: float, seed_offset: int = 0,
          cache_dir: str | Path | None = None) -> dict:
    """Train both structures on per-seed subsamples until the headline interval is narrow enough.

    ``budget_s`` counts the time of this call only: seeds resumed from ``cache_dir`` cost nothing, and
    a resumed study goes on with the next seeds (the same ones the interrupted study would have
    trained) with its budget counted afresh."""
    if not (1 <= seeds_min <= seeds_max):
        raise ValueError(f"need 1 <= seeds_min <= seeds_max, got seeds_min={seeds_min}, seeds_max={seeds_max}")
    cache = None
    if cache_dir is not None:
        cache = Path(cache_dir) / seed_cache_key(meta, len(frame), protocol, boundaries, n_samples)
        cache.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    rows: list[dict] = []
    next_seed = seed_offset
    batch = seeds_min
    while True:
        seeds = list(range(next_seed, next_seed + batch))
        next_seed += batch
        subs = [frame.iloc[subsample(len(frame), n_samples, s)].reset_index(drop=True) for s in seeds]
        for r in Parallel(n_jobs=n_jobs, return_as="generator")(
                delayed(_train_or_load)(cache, sub, meta, protocol, boundaries, s) for sub, s in zip(subs, seeds)):
            rows.append(r)
            print(f"  seed {r['seed']}{' (resumed)' if r.get('resumed') else ''}: "
                  f"single {r['single']['train_time_s']:.1f} s "
                  f"{r['single']['stop_reasons']}, split {r['split']['train_time_s']:.1f} s "
                  f"{r['split']['stop_reasons']}, reduction {r['reduction_pct']:.1f} %, split to the single's "
                  f"accuracy {_seconds_or_never(r['time_to_equal_accuracy_split_s'])}", flush=True)
        single_t = [r["single"]["train_time_s"] for r in rows]
        split_t = [r["split"]["train_time_s"] for r in rows]
        red, lo, hi, hw = reduction_ci(single_t, split_t, n_resamples)
        elapsed = time.perf_counter() - t0
        print(f"  {len(rows)} seeds, {elapsed:.0f} s: reduction of the mean time {red:.1f} % +- {hw:.1f}", flush=True)
        if hw <= target_hw or len(rows) >= seeds_max or elapsed > budget_s:
            break
        batch = max(1, min(n_jobs, seeds_max - len(rows)))
    per_seed = [r["reduction_pct"] for r in rows]
    m_lo, m_hi, m_hw = mean_ci(per_seed, n_resamples)
    tte_ok = [r["reduction_at_equal_accuracy_pct"] for r in rows if r["reduction_at_equal_accuracy_pct"] is not None]
    wall = time.perf_counter() - t0
    resumed = sum(bool(r.pop("resumed", False)) for r in rows)
    needed = seeds_needed(len(rows), hw, target_hw)
    wall_per_seed = wall / (len(rows) - resumed) if len(rows) > resumed else math.nan
    return {
        "train_time_reduction_pct": red,
        "train_time_reduction_ci95": hw,
        "train_time_reduction_ci95_low": lo,
        "train_time_reduction_ci95_high": hi,
        "train_time_reduction_estimator": "reduction of the mean time over seeds, paired bootstrap",
        "train_time_reduction_ci95_target": float(target_hw),
        "train_time_seeds_needed_for_target": needed,
        "train_time_study_s_needed_for_target": (None if needed is None or math.isnan(wall_per_seed)
                                                 else wall_per_seed * needed),
        "train_time_reduction_pct_mean_of_seeds": float(np.mean(per_seed)),
        "train_time_reduction_pct_mean_of_seeds_ci95": m_hw,
        "train_time_reduction_pct_per_seed": per_seed,
        "train_time_reduction_pct_per_seed_min": float(np.min(per_seed)),
        "train_time_reduction_pct_per_seed_max": float(np.max(per_seed)),
        "train_time_seeds": len(rows),
        "train_time_converged": all(r[m]["converged"] for r in rows for m in ("single", "split")),
        "train_time_samples_per_seed": int(n_samples),
        "train_time_single_s": float(np.median(single_t)),
        "train_time_split_s": float(np.median(split_t)),
        "train_time_single_s_mean": float(np.mean(single_t)),
        "train_time_split_s_mean": float(np.mean(split_t)),
        "train_time_single_s_min": float(np.min(single_t)), "train_time_single_s_max": float(np.max(single_t)),
        "train_time_split_s_min": float(np.min(split_t)), "train_time_split_s_max": float(np.max(split_t)),
        "train_time_split_parallel_s": float(np.median([r["split"]["train_time_parallel_s"] for r in rows])),
        "val_rel_rmse_single_median": float(np.median([r["single"]["val_rel_rmse"] for r in rows])),
        "val_rel_rmse_split_median": float(np.median([r["split"]["val_rel_rmse"] for r in rows])),
        "test_rel_rmse_single_median": float(np.median([r["single"]["test_rel_rmse"] for r in rows])),
        "test_rel_rmse_split_median": float(np.median([r["split"]["test_rel_rmse"] for r in rows])),
        "reduction_at_equal_accuracy_pct_mean": float(np.mean(tte_ok)) if tte_ok else None,
        "equal_accuracy_reached_seeds": len(tte_ok),
        "study_wall_s": wall,
        "resumed_seeds": resumed,
        "runs": rows,
    }


def ranking(s: Mapping) -> dict:
    """Which structure trains faster (mean time) and which is more accurate (median validation error)."""
    return {"faster": "split" if s["train_time_reduction_pct"] > 0 else "single",
            "more_accurate": "split" if s["val_rel_rmse_split_median"] < s["val_rel_rmse_single_median"] else "single"}


# --- the study run by experiments/train_time.py (conf/train_time.yaml) ---

INPUTS = ("dataset_dir",)
OUTPUTS = {"out": [""]}


def tracking_run(cfg):
    return "train_time", None


def check(cfg) -> None:
    from fluidfilm.workflow.config_check import ConfigError

    if not (cfg.main_study or cfg.full_scale.enabled):
        raise ConfigError("main_study=false and full_scale.enabled=false: nothing to run")


def run(cfg):
    """The paper's training-time comparison (see ``experiments/train_time.py``); returns the MLflow record."""
    from fluidfilm.surrogate.training.lightning import read_dataset
    from fluidfilm.workflow import tracking
    from fluidfilm.workflow.entry import plain

    check(cfg)
    c = plain(cfg)
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
            check_run = study(frame, meta, protocol, boundaries, rc.samples_per_seed, rc.seeds, rc.seeds, 0.0,
                              cfg.n_jobs, cfg.bootstrap_resamples, math.inf, seed_offset=1000, cache_dir=cfg.cache_dir)
            out["ranking_check"] = {k: v for k, v in check_run.items() if k != "runs"} | {
                "ranking": ranking(check_run), "same_ranking": ranking(check_run) == ranking(head),
                # the point estimates' signs say little when both intervals hold 0; overlapping intervals say the
                # two sizes are not measurably different
                "consistent": bool(
                    check_run["train_time_reduction_ci95_low"] <= head["train_time_reduction_ci95_high"]
                    and head["train_time_reduction_ci95_low"] <= check_run["train_time_reduction_ci95_high"]),
                "runs": check_run["runs"]}
    fs = cfg.full_scale
    if fs.enabled:
        proto_fs = dict(protocol) | c["full_scale"]["protocol"]
        print(f"full-scale run: protocol {proto_fs['name']} on all {len(frame):,} samples", flush=True)
        full = study(frame, meta, proto_fs, boundaries, len(frame), 1, 1, 0.0, 1, cfg.bootstrap_resamples, math.inf,
                     seed_offset=2000, cache_dir=cfg.cache_dir)
        out["full_scale"] = {k: v for k, v in full.items() if k != "runs"} | {
            "ranking": ranking(full), "protocol": proto_fs, "runs": full["runs"]}
    out["runs"] = head["runs"]
    io.write_json(cfg.out, out)
    metrics = {k: float(v) for k, v in out.items() if isinstance(v, (int, float)) and not isinstance(v, bool)}
    if "train_time_converged" in out:
        metrics["train_time_converged"] = float(out["train_time_converged"])
    if "full_scale" in out:
        metrics |= {f"full_scale.{k}": float(v) for k, v in out["full_scale"].items()
                    if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)}
    # one child run per seed and structure: its networks' epochs, times and errors
    parent = tracking.active_run()
    for r in head["runs"]:
        for which in ("single", "split"):
            nets = {}
            for k, n in enumerate(r[which]["networks"]):
                nets.update({f"net{k}.epochs": n["epochs"], f"net{k}.train_time_s": n["train_time_s"],
                             f"net{k}.val_rel_rmse": n["val_rel_rmse"],
                             f"net{k}.test_rel_rmse": n["test_rel_rmse"] or math.nan,
                             f"net{k}.train_rel_rmse": n["train_rel_rmse"]})
            tracking.log_child_run(parent, f"train_time seed {r['seed']} {which}", nets,
                                   params={"seed": r["seed"], "structure": which}, uri=cfg.tracking.uri)
    print({k: v for k, v in out.items() if k not in ("runs", "ranking_check", "full_scale", "protocol")})
    return tracking.Logged(metrics, [str(cfg.out)])
