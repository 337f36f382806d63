"""The paper's training protocol (its tool's fitting network), and mini-batch Adam under the same rules.

The paper trained MATLAB fitting networks.  What that means, and what this
module does:

- one hidden layer of 50 tanh (``tansig``) neurons, linear outputs;
- inputs (X1, X2, V1, V2) and outputs (F1, F2) mapped linearly from the
  data's [min, max] to [-1, 1] (``mapminmax``; the ``minmax`` scaling),
  each network with its own map, fitted on all the rows it is given (the
  tool maps before it divides);
- a random 70/15/15 division into training, validation and test rows
  (``dividerand``);
- stopping when the validation error has not improved for 6 consecutive
  epochs (``max_fail``), or at ``max_epochs`` (the tool's 1000; the config raises it so that the
  validation rule decides), or at a minimum gradient, and
  keeping the weights of the best validation epoch;
- Levenberg-Marquardt, full batch (``trainlm``; ``levenberg_marquardt``).

The second protocol, ``adam``, keeps all of the above but replaces the
optimiser with mini-batch Adam and a learning rate halved whenever the
validation error stalls for two epochs.

The split model of the paper is three such networks on eccentricity
0-0.5, 0.5-0.7 and above 0.7.  Both structures see the same rows: one
random subsample of the dataset per seed, one division of it; each split
network takes the rows of its band from each part.

Errors in the reports: ``*_mse`` in the mapped units (what the stopping
rule watches, as the tool does), ``*_rel_rmse`` physical,
sqrt(sum |F_pred - F|^2 / sum |F|^2) in newtons.
"""
from __future__ import annotations

import hashlib
import json
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from fluidfilm import io
from fluidfilm.core.bearing import bearing_from_dict
from fluidfilm.data.schema import relative_force_errors
from fluidfilm.surrogate.training.fit import regions
from fluidfilm.surrogate.model import SurrogateForceModel
from fluidfilm.surrogate.training.levenberg_marquardt import (FINAL_REASONS, LMResult, LMSettings, init_nguyen_widrow,
                                                    TorchNormalEquations, levenberg_marquardt, mlp_forward, mlp_sse,
                                                    normal_equations,
                                                    resolve_workers, unpack)
from fluidfilm.surrogate.scaling import Scaling

PROTOCOLS = ("paper", "adam")

#: What the weights of a network trained here depend on in the code, for the caches of runs that take hours
#: (``studies.paper_scale`` keys its records and LM checkpoints by it, with the data, the point and the
#: protocol). Give it a new value with any change to this module, ``levenberg_marquardt`` or ``scaling``
#: that changes the weights a run ends with; ``tests/surrogate/test_protocol.py`` pins the result of a whole LM run made
#: with the code of 2026-12-04 to catch one made without it. Its value is the SHA-256 of those three files as
#: they were then: the key the records and checkpoints committed before it were made with (until then the
#: key hashed the files' bytes, so a comment or a new device path would have discarded hours of training).
RECIPE_VERSION = "2b173f1572a32c2c0a8d49bc882ea4223fa9feb2041032dcb363dccc0a3e0acc"
INPUTS = ["X1", "X2", "V1", "V2"]
OUTPUTS = ["F1", "F2"]


# --------------------------------------------------------------------------- division
@dataclass(frozen=True)
class Division:
    """Row indices of the training, validation and test parts."""
    train: np.ndarray
    val: np.ndarray
    test: np.ndarray


def divide_random(n: int, fractions=(0.70, 0.15, 0.15), seed: int = 0) -> Division:
    """Random division of n rows into parts of the given shares (MATLAB ``dividerand``).

    Part sizes: validation and test round(share * n), training the rest, so
    the three are disjoint and cover every row.
    """
    f = np.asarray(fractions, dtype=float)
    if f.shape != (3,) or (f < 0).any() or not math.isclose(f.sum(), 1.0, abs_tol=1e-9) or f[0] <= 0:
        raise ValueError(f"fractions must be three non-negative shares summing to 1 with a training share > 0, "
                         f"got {fractions!r}")
    if int(n) < 3:
        raise ValueError(f"cannot divide {n} rows into three parts")
    order = np.random.default_rng(seed).permutation(int(n))
    n_val = int(round(f[1] * n))
    n_test = int(round(f[2] * n))
    n_train = int(n) - n_val - n_test
    return Division(np.sort(order[:n_train]), np.sort(order[n_train:n_train + n_val]),
                    np.sort(order[n_train + n_val:]))


# --------------------------------------------------------------------------- stopping rule
class ValidationStop:
    """Stop when the validation error has not improved for ``max_fail`` consecutive epochs.

    ``update(epoch, error, weights)`` returns "validation" when the rule
    fires; the best epoch's error and a copy of its weights are kept, and
    those are the weights the network ends with (as in the paper's tool).
    """

    def __init__(self, max_fail: int = 6):
        if int(max_fail) < 1:
            raise ValueError(f"max_fail must be a positive integer, got {max_fail!r}")
        self.max_fail = int(max_fail)
        self.best = math.inf
        self.best_epoch = 0
        self.best_weights: np.ndarray | None = None
        self.fails = 0

    def update(self, epoch: int, error: float, weights=None) -> str | None:
        if not math.isfinite(error):
            return "non_finite"
        if error < self.best:
            self.best, self.best_epoch, self.fails = float(error), int(epoch), 0
            if weights is not None:
                self.best_weights = np.array(weights, copy=True)
            return None
        self.fails += 1
        return "validation" if self.fails >= self.max_fail else None


# --------------------------------------------------------------------------- one network
@dataclass
class NetworkData:
    """One network's rows: mapped inputs/outputs per part, and the raw forces for physical errors."""
    scaling: Scaling
    z: dict
    y: dict
    F: dict
    X: dict | None = None  # positions and velocities per part (a non-affine map needs them for forces)
    V: dict | None = None


#: the paper's map: min-max of (X1, X2, V1, V2) and (F1, F2), cartesian
PAPER_MAP: dict[str, str | float] = {"kind": "minmax", "frame": "cartesian", "power": 0.0}


def minmax_scaling(X, V, F, bearing, kind: str = "minmax", frame: str = "cartesian", power: float = 0.0) -> Scaling:
    """A ``Scaling`` of ``kind``/``frame`` whose affine part is the min-max map to [-1, 1] (``mapminmax``).

    ``kind`` "minmax" is the paper's map.  The physics kinds divide the force first (by the film
    scale, (1 - eps^2)^-power and, for ``physics_v``, 1 + |V|/(c omega); the ``whirl`` frame by the
    drive |u|) and then map min-max instead of standardising, so that an ablation changes one
    ingredient: with power 0 in the cartesian frame, ``physics`` is the paper's map up to rounding
    (a min-max map is invariant to a constant factor).
    """
    sc = Scaling.fit(kind, X, V, F, bearing.clearance, bearing.omega, bearing.force_scale, power=power, frame=frame)
    if kind != "minmax":
        from fluidfilm.surrogate.scaling import _centre_half_range

        sc.in_mean, sc.in_std = _centre_half_range(sc._raw_inputs(X, V))
        sc.out_mean, sc.out_std = _centre_half_range(sc._raw_targets(X, V, F))
    return sc


def network_data(frame: pd.DataFrame, parts: Mapping[str, np.ndarray], bearing,
                 scaling: Mapping | None = None) -> NetworkData:
    """Fit the min-max map on all rows of the network (training, validation and test) and map each part.

    ``scaling``: {"kind", "frame", "power"} of ``minmax_scaling`` (default ``PAPER_MAP``)."""
    rows = np.concatenate(list(parts.values()))
    X = frame[["X1", "X2"]].to_numpy()[rows]
    V = frame[["V1", "V2"]].to_numpy()[rows]
    F = frame[OUTPUTS].to_numpy()[rows]
    m = dict(PAPER_MAP) | dict(scaling or {})
    sc = minmax_scaling(X, V, F, bearing, str(m["kind"]), str(m["frame"]), float(str(m["power"])))
    z, y, f, xs, vs = {}, {}, {}, {}, {}
    for name, idx in parts.items():
        xs[name] = Xp = frame[["X1", "X2"]].to_numpy()[idx]
        vs[name] = Vp = frame[["V1", "V2"]].to_numpy()[idx]
        f[name] = frame[OUTPUTS].to_numpy()[idx]
        z[name] = np.ascontiguousarray(sc.inputs(Xp, Vp))
        y[name] = np.ascontiguousarray(sc.targets(Xp, Vp, f[name]))
    return NetworkData(sc, z, y, f, xs, vs)


def _physical_sq(data: NetworkData, part: str, y_pred: np.ndarray) -> float:
    """sum |F_pred - F|^2 [N^2] over a part's rows for network outputs in mapped units."""
    sc = data.scaling
    F = data.F[part]
    if sc.kind == "minmax":  # affine map: no state needed
        Fp = y_pred * sc.out_std + sc.out_mean
    else:
        if data.X is None or data.V is None:
            raise ValueError(f"a {sc.kind!r} map needs the rows' positions and velocities (NetworkData.X, .V)")
        Fp = sc.forces(data.X[part], data.V[part], y_pred)
    return float(((Fp - F) ** 2).sum())


def _layers(theta, n_in, n_hidden, n_out=2):
    W1, b1, W2, b2 = unpack(theta, n_in, n_hidden, n_out)
    return [(W1.copy(), b1.copy()), (W2.copy(), b2.copy())]


def _fingerprint(*parts) -> str:
    """sha256 of arrays and JSON-able values: what a checkpoint belongs to."""
    h = hashlib.sha256()
    for p in parts:
        if isinstance(p, np.ndarray):
            h.update(str((p.shape, p.dtype.str)).encode())
            h.update(np.ascontiguousarray(p).tobytes())
        else:
            h.update(json.dumps(p, sort_keys=True, default=str).encode())
    return h.hexdigest()


def save_lm_checkpoint(path, state: dict) -> None:
    """Write a Levenberg-Marquardt checkpoint (arrays and a JSON record) atomically (``fluidfilm.io``)."""
    arrays = {k: np.asarray(v, dtype=np.float64) for k, v in state.items() if isinstance(v, np.ndarray)}
    record = {k: v for k, v in state.items() if not isinstance(v, np.ndarray)}
    with io.atomic_path(path, ".npz") as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, record=np.array(json.dumps(record)), **arrays)  # type: ignore[arg-type]


def load_lm_checkpoint(path) -> dict | None:
    """The state ``save_lm_checkpoint`` wrote, or None when there is no file."""
    path = Path(path)
    if not path.exists():
        return None
    with np.load(path, allow_pickle=False) as f:
        out = json.loads(str(f["record"]))
        out.update({k: f[k].copy() for k in f.files if k != "record"})
    return out


def train_network_lm(data: NetworkData, n_hidden: int = 50, seed: int = 0, max_fail: int = 6,
                     settings: LMSettings | None = None, chunk: int = 8192, workers: int | None = 1,
                     checkpoint: str | Path | None = None, progress_every_s: float | None = None,
                     label: str = "lm", device: str | None = None) -> dict:
    """Levenberg-Marquardt on the training rows, stopped by the validation rule; the best epoch's weights.

    ``workers`` threads accumulate J^T J (None or 0: every core; the weights do not depend on it).
    ``checkpoint``: a file (.npz) written atomically after every epoch with the weights, mu, the
    epoch, the best validation weights and error, the stopping rule's count and the history; a
    call with the same data and settings finds it and resumes, to the weights an uninterrupted run
    ends with (a checkpoint of other data or settings is not used: the run starts afresh).
    ``progress_every_s``: a progress line at most this often (0: every epoch; None: silent), with
    the time per epoch and bounds on the rest.
    ``device``: None, the NumPy path (``workers`` threads); or a torch device ("cuda", "cpu", ...) on
    which J^T J and the errors are computed in float64 (``TorchNormalEquations``: equal to the NumPy path
    to round-off; the checkpoint is the same either way, so a run continues on another device).
    """
    z_tr, y_tr = data.z["train"], data.y["train"]
    z_va, y_va = data.z["val"], data.y["val"]
    if len(z_tr) == 0 or len(z_va) == 0:
        raise ValueError(f"a network needs training and validation rows, got {len(z_tr)} and {len(z_va)}")
    s = settings or LMSettings()
    n_in, n_out = z_tr.shape[1], y_tr.shape[1]
    theta0 = init_nguyen_widrow(n_in, n_hidden, n_out, np.random.default_rng(seed))
    workers = resolve_workers(workers)
    stop = ValidationStop(max_fail)
    hist: dict[str, list[float]] = {"wall_s": [], "val_mse": [], "val_sq_N2": [], "train_mse": []}
    # the caps (max_epochs, max_time_s) are not part of it: a run stopped by one continues when it is raised
    key = _fingerprint(z_tr, y_tr, z_va, y_va, theta0,
                       {"n_hidden": n_hidden, "max_fail": int(max_fail), "chunk": int(chunk), "mu": s.mu,
                        "mu_dec": s.mu_dec, "mu_inc": s.mu_inc, "mu_max": s.mu_max, "min_grad": s.min_grad})
    start = load_lm_checkpoint(checkpoint) if checkpoint is not None else None
    if start is not None and start.get("key") != key:
        print(f"    {label}: checkpoint {checkpoint} belongs to other data or settings: starting afresh", flush=True)
        start = None
    if start is not None:
        stop.best, stop.best_epoch, stop.fails = float(start["best"]), int(start["best_epoch"]), int(start["fails"])
        stop.best_weights = start["best_weights"]
        hist = {k: list(v) for k, v in start["hist"].items()}
        print(f"    {label}: resuming at epoch {start['epoch']} ({start['wall_s']:.0f} s done; best validation mse "
              f"{stop.best:.4g} at epoch {stop.best_epoch})", flush=True)
    else:
        # the starting point counts as epoch 0 of the validation record, as in the tool
        pred0, _ = mlp_forward(theta0, z_va, n_hidden, n_out)
        stop.update(0, float(((pred0 - y_va) ** 2).mean()), theta0)
    last_line = [-math.inf]

    def on_epoch(epoch, theta, wall):
        pred, _ = mlp_forward(theta, z_va, n_hidden, n_out)
        mse = float(((pred - y_va) ** 2).mean())
        hist["wall_s"].append(wall)
        hist["val_mse"].append(mse)
        hist["val_sq_N2"].append(_physical_sq(data, "val", pred))
        return stop.update(epoch, mse, theta)

    def on_checkpoint(state):
        if checkpoint is not None:
            save_lm_checkpoint(checkpoint, {
                "key": key, "theta": state["theta"], "mu": state["mu"], "epoch": state["epoch"],
                "wall_s": state["wall_s"], "history": state["history"], "reason": state["reason"],
                "best": stop.best, "best_epoch": stop.best_epoch, "fails": stop.fails,
                "best_weights": stop.best_weights if stop.best_weights is not None else state["theta"],
                "hist": hist})
        if progress_every_s is not None and (state["reason"] or state["wall_s"] - last_line[0] >= progress_every_s):
            last_line[0] = state["wall_s"]
            print(lm_progress_line(label, state, stop, s, len(z_tr)), flush=True)

    if start is not None and start.get("reason") in FINAL_REASONS:
        res = LMResult(start["theta"], int(start["epoch"]), start["reason"], math.nan, float(start["wall_s"]),
                       list(start["history"]))
    else:
        if device is None:
            def normal_eq(t):
                return normal_equations(t, z_tr, y_tr, n_hidden, chunk, workers)

            def sse_fn(t):
                return mlp_sse(t, z_tr, y_tr, n_hidden, workers=workers)
        else:
            on_device = TorchNormalEquations(z_tr, y_tr, n_hidden, device)
            normal_eq, sse_fn = on_device.normal_equations, on_device.sse
        res = levenberg_marquardt(theta0, normal_eq, sse_fn, y_tr.size, s, on_epoch, start, on_checkpoint)
    hist["train_mse"] = [h["sse"] / y_tr.size for h in res.history]
    theta = stop.best_weights if stop.best_weights is not None else res.theta
    out = _finish(data, _layers(theta, n_in, n_hidden, n_out), res.epochs, stop.best_epoch, res.stop_reason,
                  res.wall_s, hist)
    out["workers"] = workers
    out["device"] = device
    return out


def lm_progress_line(label: str, state: dict, stop: ValidationStop, settings: LMSettings, n_train: int) -> str:
    """One line on a Levenberg-Marquardt run: epoch, time per epoch, mu, validation error and the rule's
    count, and bounds on the rest (the rule cannot fire in fewer than its remaining failures; the caps
    end it at the latest)."""
    epoch, wall = int(state["epoch"]), float(state["wall_s"])
    per = wall / max(epoch, 1)
    head = (f"    {label}: epoch {epoch}, {wall:.0f} s ({per:.2f} s/epoch, {n_train:,} rows), mu {state['mu']:.1e}, "
            f"best validation mse {stop.best:.4g} at epoch {stop.best_epoch} ({stop.fails} of {stop.max_fail} "
            f"epochs without improvement)")
    if state["reason"]:
        return f"{head}; stopped: {state['reason']}"
    at_least = (stop.max_fail - stop.fails) * per
    at_most = min((int(settings.max_epochs) - epoch) * per, max(settings.max_time_s - wall, 0.0))
    return f"{head}; rest: at least {at_least:.0f} s, at most {at_most:.0f} s"


def train_network_adam(data: NetworkData, n_hidden: int = 50, seed: int = 0, max_fail: int = 6,
                       max_epochs: int = 1000, lr: float = 3e-3, batch_size: int = 512, max_time_s: float = math.inf,
                       threads: int | None = None, progress_every_s: float | None = 30.0) -> dict:
    """Mini-batch Adam (learning rate halved after 2 epochs without improvement), same stopping rule.

    A progress line every ``progress_every_s`` seconds of training (None: silent)."""
    import torch

    if threads:
        torch.set_num_threads(int(threads))
    torch.manual_seed(seed)
    z_tr = torch.as_tensor(data.z["train"], dtype=torch.float32)
    y_tr = torch.as_tensor(data.y["train"], dtype=torch.float32)
    z_va = torch.as_tensor(data.z["val"], dtype=torch.float32)
    y_va_np = data.y["val"]
    n_in, n_out = z_tr.shape[1], y_tr.shape[1]
    theta0 = init_nguyen_widrow(n_in, n_hidden, n_out, np.random.default_rng(seed))
    W1, b1, W2, b2 = (torch.tensor(a, dtype=torch.float32, requires_grad=True)
                      for a in unpack(theta0, n_in, n_hidden, n_out))
    params = [W1, b1, W2, b2]
    opt = torch.optim.Adam(params, lr=lr)
    sched = torch.optim.lr_scheduler.ReduceLROnPlateau(opt, factor=0.5, patience=2)
    stop = ValidationStop(max_fail)
    gen = torch.Generator().manual_seed(seed)
    hist: dict[str, list[float]] = {"wall_s": [], "val_mse": [], "val_sq_N2": [], "train_mse": []}

    def weights():
        return np.concatenate([p.detach().double().numpy().ravel() for p in params])

    def predict(z):
        with torch.no_grad():
            return (torch.tanh(z @ W1.T + b1) @ W2.T + b2).double().numpy()

    stop.update(0, float(((predict(z_va) - y_va_np) ** 2).mean()), weights())
    reason, epoch = "max_epochs", 0
    last_line = 0.0
    t0 = time.perf_counter()
    for epoch in range(1, int(max_epochs) + 1):
        order = torch.randperm(len(z_tr), generator=gen)
        total = 0.0
        for s in range(0, len(order), batch_size):
            idx = order[s:s + batch_size]
            loss = ((torch.tanh(z_tr[idx] @ W1.T + b1) @ W2.T + b2 - y_tr[idx]) ** 2).mean()
            opt.zero_grad(set_to_none=True)
            loss.backward()
            opt.step()
            total += float(loss.detach()) * len(idx)
        pred = predict(z_va)
        mse = float(((pred - y_va_np) ** 2).mean())
        sched.step(mse)
        wall = time.perf_counter() - t0
        hist["wall_s"].append(wall)
        hist["val_mse"].append(mse)
        hist["val_sq_N2"].append(_physical_sq(data, "val", pred))
        hist["train_mse"].append(total / len(z_tr))
        r = stop.update(epoch, mse, weights())
        if progress_every_s is not None and (r or wall - last_line >= progress_every_s):
            # a full-scale network takes many minutes: say where it is (the stopping rule has no ETA)
            last_line = wall
            print(f"    adam: epoch {epoch}, {wall:.0f} s, validation mse {mse:.4g} (best {stop.best:.4g} at epoch "
                  f"{stop.best_epoch}; {stop.fails} of {max_fail} epochs without improvement)", flush=True)
        if r:
            reason = r
            break
        if wall > max_time_s:
            reason = "max_time"
            break
    wall = time.perf_counter() - t0
    return _finish(data, _layers(stop.best_weights, n_in, n_hidden, n_out), epoch, stop.best_epoch, reason, wall,
                   hist)


def _finish(data: NetworkData, layers, epochs, best_epoch, reason, wall, hist) -> dict:
    theta = np.concatenate([a.ravel() for W, b in layers for a in (W, b)])
    n_hidden = layers[0][0].shape[0]
    out = {"layers": layers, "scaling": data.scaling, "epochs": int(epochs), "best_epoch": int(best_epoch),
           "stop_reason": reason, "converged": reason == "validation", "train_time_s": float(wall),
           "history": hist}
    for part in ("train", "val", "test"):
        z, y, F = data.z[part], data.y[part], data.F[part]
        out[f"n_{part}"] = int(len(z))
        if len(z):
            pred, _ = mlp_forward(theta, z, n_hidden, y.shape[1])
            out[f"{part}_mse"] = float(((pred - y) ** 2).mean())
            out[f"{part}_rel_rmse"] = math.sqrt(_physical_sq(data, part, pred) / max(float((F ** 2).sum()), 1e-300))
        else:
            out[f"{part}_mse"] = out[f"{part}_rel_rmse"] = None
    return out


# --------------------------------------------------------------------------- a whole model
def subsample(n_rows: int, n_samples: int | None, seed: int) -> np.ndarray:
    """Sorted random rows (without replacement) of a table of ``n_rows``; all rows for None or >= n_rows."""
    if n_samples is None or int(n_samples) >= n_rows:
        return np.arange(n_rows)
    if int(n_samples) < 3:
        raise ValueError(f"n_samples must be at least 3, got {n_samples!r}")
    return np.sort(np.random.default_rng(seed).choice(n_rows, int(n_samples), replace=False))


def train_protocol_model(frame: pd.DataFrame, meta: dict, protocol: Mapping, boundaries=(), seed: int = 0,
                         n_samples: int | None = None, name: str = "surrogate", n_hidden: int = 50,
                         log_network=None, scaling: Mapping | None = None, extra_rows: pd.DataFrame | None = None,
                         checkpoint_dir: str | Path | None = None,
                         network_protocol: Mapping | None = None) -> tuple[SurrogateForceModel, dict]:
    """Train a single (no boundaries) or split model under ``protocol`` on one subsample and division.

    ``protocol``: {"name": "paper" | "adam", "fractions": [...], "max_fail", "max_epochs", "max_time_s",
    for paper "workers" (threads accumulating J^T J, None: every core), "device" (None: NumPy; a torch
    device such as "cuda": J^T J on it, ``train_network_lm``), "progress_every_s" (None: silent), and for adam "lr", "batch_size"}.  ``log_network(r, result)`` is called after each network.
    ``scaling``: the networks' map (``network_data``; default the paper's min-max).  ``extra_rows``:
    rows (the dataset's columns) added to the subsample before the division.  ``checkpoint_dir``:
    with the paper protocol, each network checkpoints there after every epoch
    (``train_network_lm``), so the same call resumes an interrupted run.  ``network_protocol``:
    {network index: protocol keys} overriding ``protocol`` for that network (e.g. a time budget, or
    ``name: adam``, for the eps > 0.7 network).
    Returns the force model and a report (per network: rows, epochs, best epoch, stop reason, errors,
    wall time, validation history).
    """
    kind = protocol.get("name", "paper")
    if kind not in PROTOCOLS:
        raise ValueError(f"unknown training protocol {kind!r}; choose one of {PROTOCOLS}")
    args = (frame, meta, protocol, boundaries, seed, n_samples, name, n_hidden, log_network, scaling, extra_rows,
            checkpoint_dir, network_protocol)
    threads = protocol.get("threads")
    if threads:
        # one BLAS thread per process: parallel work runs as processes (or as the J^T J workers'
        # threads), and OpenBLAS threads that spin-wait on a busy machine slow a 352 x 352 Cholesky
        # down a hundredfold
        from threadpoolctl import threadpool_limits

        with threadpool_limits(int(threads)):
            return _train_protocol_model(*args)
    return _train_protocol_model(*args)


def _train_protocol_model(frame, meta, protocol, boundaries, seed, n_samples, name, n_hidden, log_network,
                          scaling=None, extra_rows=None, checkpoint_dir=None, network_protocol=None):
    base_protocol = protocol
    bearing = bearing_from_dict(meta["bearing"])
    rows = subsample(len(frame), n_samples, seed)
    sub = frame.iloc[rows].reset_index(drop=True)
    if extra_rows is not None and len(extra_rows):
        sub = pd.concat([sub, extra_rows[list(sub.columns)]], ignore_index=True)
    div = divide_random(len(sub), protocol.get("fractions", (0.70, 0.15, 0.15)), seed)
    eps = sub["eps"].to_numpy()
    bounds = [float(b) for b in boundaries]
    smap = dict(PAPER_MAP) | dict(scaling or {})
    nets, scalings, per_net = [], [], []
    for r, (lo, hi) in enumerate(regions(bounds)):
        parts = {p: idx[(eps[idx] >= lo) & (eps[idx] < hi)] for p, idx in
                 (("train", div.train), ("val", div.val), ("test", div.test))}
        data = network_data(sub, parts, bearing, smap)
        over = (network_protocol or {}).get(r, (network_protocol or {}).get(str(r), {}))
        protocol = dict(base_protocol) | dict(over or {})
        kind = protocol.get("name", "paper")
        if kind not in PROTOCOLS:
            raise ValueError(f"unknown training protocol {kind!r} for network {r}; choose one of {PROTOCOLS}")
        common = dict(n_hidden=n_hidden, seed=seed * 100 + r, max_fail=int(protocol.get("max_fail", 6)))
        if kind == "paper":
            settings = LMSettings(max_epochs=int(protocol.get("max_epochs", 1000)),
                                  max_time_s=float(protocol.get("max_time_s") or math.inf),
                                  min_grad=float(protocol.get("min_grad", 1e-7)))
            ckpt = None if checkpoint_dir is None else Path(checkpoint_dir) / f"network{r}.npz"
            res = train_network_lm(data, settings=settings, chunk=int(protocol.get("chunk", 8192)),
                                   workers=protocol.get("workers"), checkpoint=ckpt, device=protocol.get("device"),
                                   progress_every_s=protocol.get("progress_every_s"),
                                   label=f"{name} network {r} (eps {lo:g}-{hi:g})", **common)
        else:
            res = train_network_adam(data, max_epochs=int(protocol.get("max_epochs", 1000)),
                                     lr=float(protocol.get("lr", 3e-3)),
                                     batch_size=int(protocol.get("batch_size", 512)),
                                     max_time_s=float(protocol.get("max_time_s") or math.inf),
                                     threads=protocol.get("threads"), **common)
        res.update(eps_low=lo, eps_high=hi, time_to_target_s=None, val_rel_rmse=res["val_rel_rmse"], protocol=kind)
        if log_network is not None:
            log_network(r, res)
        nets.append(res.pop("layers"))
        scalings.append(res.pop("scaling"))
        per_net.append(res)
    spec = meta["spec"]
    domain = [[s["eps_low"], s["eps_high"], s["v_max"]] for s in spec["velocity_sections"]]
    model = SurrogateForceModel(bearing, nets, scalings, "tanh", bounds, 0.0, domain,
                                eps_max=float(frame["eps"].max()), name=name,
                                info={"protocol": dict(base_protocol), "split": {"boundaries": bounds},
                                      "network_protocol": {str(k): dict(v) for k, v in (network_protocol or {}).items()},
                                      "scaling": smap, "seed": seed, "n_samples": len(sub),
                                      "model": {"width": n_hidden, "depth": 1, "activation": "tanh"}})
    times = [p["train_time_s"] for p in per_net]
    report = {
        "protocol": base_protocol.get("name", "paper"), "networks": per_net, "n_samples": int(len(sub)), "n_samples_dataset": int(len(frame)),
        "dataset_hash": meta.get("config_hash"), "seed": seed,
        "train_time_s": float(sum(times)), "train_time_parallel_s": float(max(times)),
        "time_to_target_s": None, "target_val_rel_rmse": None,
        "converged": all(p["converged"] for p in per_net),
        "stop_reasons": [p["stop_reason"] for p in per_net],
        "val_rel_rmse": _model_rel_rmse(sub, div.val, model),
        "test_rel_rmse": _model_rel_rmse(sub, div.test, model),
        "division": {"train": int(len(div.train)), "val": int(len(div.val)), "test": int(len(div.test))},
    }
    # the rows and division, for callers that compare models on the same rows (not saved)
    report["_sub"] = sub
    report["_division"] = div
    return model, report


def _predicted_and_true(sub: pd.DataFrame, idx: np.ndarray | slice, model) -> tuple[np.ndarray, np.ndarray]:
    """(model forces, dataset forces) at the rows ``idx`` of ``sub``, the model's outside-the-domain warnings
    silenced."""
    X = sub[["X1", "X2"]].to_numpy()[idx]
    V = sub[["V1", "V2"]].to_numpy()[idx]
    F = sub[OUTPUTS].to_numpy()[idx]
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        P = model.forces(X, V)
    return P, F


def _model_rel_rmse(sub: pd.DataFrame, idx: np.ndarray, model: SurrogateForceModel) -> float | None:
    if len(idx) == 0:
        return None
    P, F = _predicted_and_true(sub, idx, model)
    return math.sqrt(float(((P - F) ** 2).sum()) / max(float((F ** 2).sum()), 1e-300))


def band_sq_errors(sub: pd.DataFrame, idx: np.ndarray, model: SurrogateForceModel, boundaries) -> list[float]:
    """sum |F_pred - F|^2 [N^2] of a model over the rows ``idx`` in each eccentricity region."""
    eps = sub["eps"].to_numpy()[idx]
    P, F = _predicted_and_true(sub, idx, model)
    sq = ((P - F) ** 2).sum(axis=1)
    return [float(sq[(eps >= lo) & (eps < hi)].sum()) for lo, hi in regions(boundaries)]


def time_to_accuracy(split_report: dict, targets_sq_N2: list[float]) -> float | None:
    """Training time [s] the split networks need to reach given validation errors, summed over networks.

    Network r counts from its start to the first epoch whose summed squared
    validation force error on its own rows is at most ``targets_sq_N2[r]``;
    None if a network never gets there.
    """
    total = 0.0
    for net, target in zip(split_report["networks"], targets_sq_N2):
        hist = net["history"]
        hit = [w for w, s in zip(hist["wall_s"], hist["val_sq_N2"]) if s <= target]
        if not hit:
            return None
        total += hit[0]
    return total


def band_test_errors(model, testset: pd.DataFrame, bands=((0.0, 0.5), (0.5, 0.7), (0.7, 1.0)),
                     floor_N: float = 0.1) -> dict:
    """Median and 99th percentile of |F_model - F| / max(|F|, floor) per eccentricity band and below 0.7."""
    P, F = _predicted_and_true(testset, slice(None), model)
    rel = relative_force_errors(P, F, floor_N)
    eps = testset["eps"].to_numpy()
    out = {}
    for lo, hi in bands:
        m = (eps >= lo) & (eps < hi)
        if m.any():
            out[f"test_rel_err_median_band_{lo:g}_{hi:g}"] = float(np.median(rel[m]))
            out[f"test_rel_err_p99_band_{lo:g}_{hi:g}"] = float(np.quantile(rel[m], 0.99))
            out[f"test_rows_band_{lo:g}_{hi:g}"] = int(m.sum())
    m = eps < 0.7
    if m.any():
        out["test_rel_err_median_eps_below_0.7"] = float(np.median(rel[m]))
    return out
