"""Fit a single or split surrogate on the dataset and judge it on the held-out test set."""
from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np

from ..data.schema import dataset_bearing, load_dataset, load_test_set, relative_force_errors, training_domain
from .inference import SurrogateForceModel
from .training import ForceDataModule, train_network

EPS_BANDS = ((0.0, 0.5), (0.5, 0.7), (0.7, 0.9), (0.9, 1.0))


def regions(boundaries, blend_width: float = 0.0) -> list[tuple[float, float]]:
    """Training eccentricity ranges of the networks; with blending they overlap by half the width."""
    b = [0.0] + [float(v) for v in boundaries] + [math.inf]
    half = 0.5 * float(blend_width)
    return [(max(0.0, lo - half) if k else 0.0, hi + half if hi != math.inf else hi)
            for k, (lo, hi) in enumerate(zip(b[:-1], b[1:]))]


def fit_surrogate(dataset_dir, model_cfg: Mapping, split_cfg: Mapping, scaling_cfg: Mapping,
                  trainer_cfg: Mapping, target: float | None, seed: int = 0, name: str = "surrogate",
                  ckpt_root=None, logger_for: Callable[[int], object] | None = None,
                  val_fraction: float = 0.1, batch_size: int = 4096) -> tuple[SurrogateForceModel, dict]:
    """Train one network per eccentricity region (one region: the single model).

    Returns the force model and a report with per-network and total
    training times (to the target validation error, and in all).
    """
    frame, meta = load_dataset(dataset_dir)
    bearing = dataset_bearing(meta)
    boundaries = list(split_cfg.get("boundaries", []))
    blend = float(split_cfg.get("blend_width", 0.0))
    nets, scalings, per_net = [], [], []
    for r, (lo, hi) in enumerate(regions(boundaries, blend)):
        dm = ForceDataModule(dataset_dir, scaling=scaling_cfg["kind"], power=scaling_cfg.get("power", 1.5),
                             frame=scaling_cfg.get("frame", "cartesian"),
                             eps_low=lo, eps_high=hi, val_fraction=val_fraction, batch_size=batch_size, seed=seed,
                             table=frame, meta=meta)
        res = train_network(dm, dict(model_cfg), dict(trainer_cfg), target,
                            ckpt_dir=None if ckpt_root is None else Path(ckpt_root) / f"region{r}",
                            logger=logger_for(r) if logger_for else None, seed=seed + r)
        nets.append(res["layers"])
        scalings.append(res["scaling"])
        per_net.append({k: res[k] for k in ("time_to_target_s", "train_time_s", "epochs", "epoch_at_target",
                                            "val_rel_rmse", "n_train", "n_val")} | {"eps_low": lo, "eps_high": hi})
    reached = all(p["time_to_target_s"] is not None for p in per_net)
    domain = training_domain(meta)
    report = {
        "networks": per_net,
        "train_time_s": float(sum(p["train_time_s"] for p in per_net)),
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
