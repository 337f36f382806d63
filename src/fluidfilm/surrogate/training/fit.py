"""Fit a single or split surrogate on the dataset and judge it on the held-out test set."""
from __future__ import annotations

import contextlib
import math
import os
import time
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np

from fluidfilm.data.schema import dataset_bearing, load_dataset, load_test_set, relative_force_errors, training_domain
from fluidfilm.data.spec import config_hash
from fluidfilm.surrogate.model import SurrogateForceModel
from fluidfilm.surrogate.training.lightning import ForceDataModule, train_network

EPS_BANDS = ((0.0, 0.5), (0.5, 0.7), (0.7, 0.9), (0.9, 1.0))


def regions(boundaries, blend_width: float = 0.0) -> list[tuple[float, float]]:
    """Training eccentricity ranges of the networks; with blending they overlap by half the width."""
    b = [0.0] + [float(v) for v in boundaries] + [math.inf]
    half = 0.5 * float(blend_width)
    return [(max(0.0, lo - half) if k else 0.0, hi + half if hi != math.inf else hi)
            for k, (lo, hi) in enumerate(zip(b[:-1], b[1:]))]


def training_digest(model_cfg: Mapping, split_cfg: Mapping, scaling_cfg: Mapping, trainer_cfg: Mapping, *rest) -> str:
    """The hash that names a training's checkpoints: everything that shapes the weights, not ``workers``
    (how many networks train at once), so a rerun with another count resumes the same checkpoints."""
    trainer = {k: v for k, v in trainer_cfg.items() if k != "workers"}
    return config_hash(model_cfg, split_cfg, scaling_cfg, trainer, *rest)


_WATCHING_PARENT = False


def _exit_with_parent(parent_pid: int) -> None:
    """In a worker: end this process when the job's process is gone (killed, so it could not stop us), rather
    than train on for minutes beside a rerun.  Checked once a second by a daemon thread."""
    global _WATCHING_PARENT
    if _WATCHING_PARENT:
        return
    import threading

    def watch():
        while os.getppid() == parent_pid:
            time.sleep(1.0)
        os._exit(1)

    threading.Thread(target=watch, name="fluidfilm-parent-watch", daemon=True).start()
    _WATCHING_PARENT = True


def worker_count(workers: int | None, n_jobs: int) -> int:
    """How many processes train ``n_jobs`` networks side by side: ``workers`` (None: one per core this
    process may use), at most one per network."""
    if workers is not None and int(workers) < 1:
        raise ValueError(f"workers must be >= 1 or null (one per core), got {workers!r}")
    if workers is None:
        from joblib import cpu_count  # the cores this process may use (affinity, container limits)

        workers = cpu_count(only_physical_cores=False)
    return min(n_jobs, int(workers))


def side_by_side(func: Callable[[dict], dict], jobs: list[dict], n_workers: int, cost=None) -> list[dict]:
    """``func(job)`` for every job, in the jobs' order: here one after the other (``n_workers`` 1), or in
    ``n_workers`` loky worker processes, the largest ``cost(job)`` first so that the workers finish together."""
    if n_workers == 1:
        return [func(job) for job in jobs]
    from joblib import Parallel, delayed

    order = sorted(range(len(jobs)), key=lambda r: -cost(jobs[r])) if cost is not None else list(range(len(jobs)))
    done = Parallel(n_jobs=n_workers, backend="loky")(delayed(func)(jobs[r]) for r in order)
    by_job = dict(zip(order, done))
    return [by_job[r] for r in range(len(jobs))]


@contextlib.contextmanager
def torch_threads(n: int | None):
    """Torch's intra-op threads set to ``n`` (None: left as they are) inside the block, restored after."""
    import torch

    threads = torch.get_num_threads()
    if n:
        torch.set_num_threads(n)
    try:
        yield
    finally:
        torch.set_num_threads(threads)


def _train_region(job: dict) -> dict:
    """Fit one region's network, here or in a worker process; returns what the model needs (the Lightning
    module stays in the process that trained it)."""
    if job["parent_pid"] != os.getpid():
        _exit_with_parent(job["parent_pid"])
    with torch_threads(job["threads"]):
        dm = ForceDataModule(job["dataset_dir"], table=job["table"], meta=job["meta"], **job["data"])
        run = job["run"]
        res = train_network(dm, job["model_cfg"], job["trainer_cfg"], job["target"], ckpt_dir=job["ckpt_dir"],
                            logger=None if run is None else run.logger(), seed=job["seed"], what=job["what"])
    return {k: res[k] for k in ("layers", "scaling", "time_to_target_s", "train_time_s", "epochs", "epoch_at_target",
                                "val_rel_rmse", "n_train", "n_val")}


def fit_surrogate(dataset_dir, model_cfg: Mapping, split_cfg: Mapping, scaling_cfg: Mapping,
                  trainer_cfg: Mapping, target: float | None, seed: int = 0, name: str = "surrogate",
                  ckpt_root=None, logger_for: Callable[[int], object] | None = None,
                  val_fraction: float = 0.1, batch_size: int = 4096,
                  workers: int | None = None) -> tuple[SurrogateForceModel, dict]:
    """Train one network per eccentricity region (one region: the single model).

    The networks of a split model train side by side, ``workers`` at a time (None: one per core), in worker
    processes (with ``workers=1``: one after the other in this process), each with one torch thread.  One
    thread per network always, however many train at once, so the weights do not depend on ``workers`` nor
    on the machine's core count; a single network uses torch's default threads.  ``logger_for(r)`` gives
    network r's MLflow child run (``tracking.child_logger_factory``).

    Returns the force model and a report with per-network and total
    training times (to the target validation error, and in all) and the wall time of the training.
    """
    frame, meta = load_dataset(dataset_dir)
    bearing = dataset_bearing(meta)
    boundaries = list(split_cfg.get("boundaries", []))
    blend = float(split_cfg.get("blend_width", 0.0))
    bounds = regions(boundaries, blend)
    n_workers = worker_count(workers, len(bounds))
    jobs = []
    for r, (lo, hi) in enumerate(bounds):
        # a worker gets only its region's rows (the data module selects the same rows from the whole table)
        table = frame if n_workers == 1 else frame[(frame["eps"] >= lo) & (frame["eps"] < hi)]
        jobs.append({"dataset_dir": dataset_dir, "table": table, "meta": meta,
                     "data": {"scaling": scaling_cfg["kind"], "power": scaling_cfg.get("power", 1.5),
                              "frame": scaling_cfg.get("frame", "cartesian"), "eps_low": lo, "eps_high": hi,
                              "val_fraction": val_fraction, "batch_size": batch_size, "seed": seed},
                     "model_cfg": dict(model_cfg), "trainer_cfg": dict(trainer_cfg), "target": target,
                     "ckpt_dir": None if ckpt_root is None else Path(ckpt_root) / f"region{r}",
                     "run": logger_for(r) if logger_for else None, "seed": seed + r,
                     "threads": 1 if len(bounds) > 1 else None, "parent_pid": os.getpid(),
                     "what": "training" if len(bounds) == 1 else
                     f"network {r} (eps {lo:.2f}-{hi:.2f})" if math.isfinite(hi) else f"network {r} (eps >= {lo:.2f})"})
    t0 = time.perf_counter()
    try:
        results = side_by_side(_train_region, jobs, n_workers, cost=lambda job: len(job["table"]))
    except BaseException as exc:
        # every network's run was made up front; those a stopped worker or a network not yet started left
        # open end here, as Lightning ends the run of the network it was training (joblib stops the workers)
        for job in jobs:
            if job["run"] is not None and hasattr(job["run"], "end_if_running"):
                with contextlib.suppress(Exception):
                    job["run"].end_if_running("KILLED" if isinstance(exc, KeyboardInterrupt) else "FAILED")
        raise
    wall = time.perf_counter() - t0
    nets, scalings, per_net = [], [], []
    for (lo, hi), res in zip(bounds, results):
        nets.append(res["layers"])
        scalings.append(res["scaling"])
        per_net.append({k: res[k] for k in ("time_to_target_s", "train_time_s", "epochs", "epoch_at_target",
                                            "val_rel_rmse", "n_train", "n_val")} | {"eps_low": lo, "eps_high": hi})
    reached = all(p["time_to_target_s"] is not None for p in per_net)
    domain = training_domain(meta)
    report = {
        "networks": per_net,
        "train_time_s": float(sum(p["train_time_s"] for p in per_net)),
        "train_wall_s": wall,  # with networks side by side, less than their sum
        "workers": n_workers,
        "time_to_target_s": float(sum(p["time_to_target_s"] for p in per_net)) if reached else None,
        "reached_target": reached,
        "target_val_rel_rmse": target,
        "dataset_hash": meta["config_hash"],
        "n_samples": meta["n_samples"],
    }
    model = SurrogateForceModel(bearing, nets, scalings, model_cfg["activation"], boundaries, blend, domain,
                                eps_max=float(frame["eps"].max()), name=name,
                                info={"model": dict(model_cfg), "split": dict(split_cfg),
                                      "scaling": dict(scaling_cfg), "seed": seed},
                                structure=model_cfg.get("structure", "plain"))
    return model, report


def held_out_errors(model, testset_dir, floor_N: float = 0.1) -> dict:
    """Relative force error |F_model - F| / max(|F|, floor) on the held-out set: median and 99th percentile,
    overall and per eccentricity band."""
    df = load_test_set(testset_dir)
    X = df[["X1", "X2"]].to_numpy()
    V = df[["V1", "V2"]].to_numpy()
    F = df[["F1", "F2"]].to_numpy()
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        if "S" in df.columns:  # an active bearing: evaluate at each sample's sleeve position
            P = np.empty_like(F)
            S = df["S"].to_numpy()
            keep = model.sleeve
            for s in np.unique(S):
                m = S == s
                model.set_sleeve(s)
                P[m] = model.forces(X[m], V[m])
            model.set_sleeve(keep)
        else:
            P = model.forces(X, V)
    rel = relative_force_errors(P, F, floor_N)
    out = {"test_rel_err_median": float(np.median(rel)), "test_rel_err_p99": float(np.quantile(rel, 0.99))}
    eps = df["eps"].to_numpy()
    for lo, hi in EPS_BANDS:
        m = (eps >= lo) & (eps < hi)
        if m.any():
            out[f"test_rel_err_median_eps_{lo:g}_{hi:g}"] = float(np.median(rel[m]))
            out[f"test_rel_err_p99_eps_{lo:g}_{hi:g}"] = float(np.quantile(rel[m], 0.99))
    return out
