"""Training of force networks with Lightning: the module, the data module, the stopping rule.

- ``ForceMLP``: fully connected (X1, X2, V1, V2) -> (F1, F2) in scaled
  units, configurable width, depth, activation, optimiser and schedule.
- ``ForceDataModule``: the Parquet dataset held in memory as tensors, split
  into training and validation *by position* (whole grid positions are held
  out, so validation measures generalisation across the grid), optionally
  restricted to an eccentricity band (one region of a split model).
- ``TargetStop``: stops when the validation relative RMS force error
  reaches a target and records the wall time to get there; its state is
  checkpointed, so an interrupted run that resumes keeps counting.
- ``train_network``: fit one network, return its weights and timings.

The validation metric is physical, the same for every network whatever its
scaling: rel_rmse = sqrt(sum |F_pred - F|^2 / sum |F|^2) over the
validation rows, in newtons.
"""
from __future__ import annotations

import math
import time
from pathlib import Path

import lightning as L
import numpy as np
import pandas as pd
import torch
from torch import nn

from fluidfilm.core.bearing import ConicalBearing
from fluidfilm.data.schema import EXTRA_INPUTS, dataset_bearing, load_dataset
from fluidfilm.surrogate.activations import REGISTRY, TRAINABLE_ACTIVATIONS
from fluidfilm.surrogate.scaling import Scaling, check_whirl_use

class _TanhFunction(torch.autograd.Function):
    """tanh(x) = 2 sigmoid(2x) - 1, with tanh's own backward (1 - y^2) g.

    Why: torch 2.13's CPU ``tanh`` is not vectorised while ``sigmoid`` is, so this form takes a third off the
    training step (benchmarks/bench_training_step.py; the timings are in docs/dataset_and_surrogates.md).  It differs from ``torch.tanh`` by at most 1.8e-7 (absolute,
    float32), the rounding of the float32 sum 2 s - 1
    (tests/surrogate/test_surrogate.py::test_training_layers_equal_torchs_own_in_value_and_gradient).
    """

    @staticmethod
    def forward(ctx, x):
        y = torch.sigmoid(2.0 * x).mul_(2.0).sub_(1.0)
        ctx.save_for_backward(y)
        return y

    @staticmethod
    def backward(ctx, grad):
        (y,) = ctx.saved_tensors
        return torch.ops.aten.tanh_backward(grad, y)


class Tanh(nn.Module):
    """The hyperbolic tangent by ``_TanhFunction`` (vectorised on the CPU); no parameters."""

    def forward(self, x):
        return _TanhFunction.apply(x)


class _NarrowInputLinearFunction(torch.autograd.Function):
    """x W^T + b with the weight's gradient formed as (x^T g)^T.

    Why: autograd's g^T x, a (width x rows) by (rows x 4) product with the transposed operand first, is
    six times slower in MKL than x^T g, the same products (summed in BLAS's order, so equal to round-off;
    timings in docs/dataset_and_surrogates.md).  Only the first layer has so few inputs.
    """

    @staticmethod
    def forward(ctx, x, weight, bias):
        ctx.save_for_backward(x, weight)
        return torch.addmm(bias, x, weight.t())

    @staticmethod
    def backward(ctx, grad):
        x, weight = ctx.saved_tensors
        grad_x = grad @ weight if ctx.needs_input_grad[0] else None
        grad_w = (x.t() @ grad).t() if ctx.needs_input_grad[1] else None
        grad_b = grad.sum(0) if ctx.needs_input_grad[2] else None
        return grad_x, grad_w, grad_b


class NarrowInputLinear(nn.Linear):
    """``nn.Linear`` (same parameters and state-dict keys) for a layer with a handful of inputs:
    its weight gradient is one fast product (``_NarrowInputLinearFunction``)."""

    def forward(self, x):
        if x.dim() != 2 or self.bias is None:
            return super().forward(x)
        return _NarrowInputLinearFunction.apply(x, self.weight, self.bias)


#: the Lightning networks' activations (``surrogate.activations``), as torch modules (tanh: ``Tanh``)
_ACT = {name: REGISTRY[name].torch_module(training=True) for name in TRAINABLE_ACTIVATIONS}


def _mlp(n_in: int, n_out: int, width: int, depth: int, activation: str) -> nn.Sequential:
    layers = []
    for i in range(depth):
        linear = NarrowInputLinear if i == 0 and n_in <= 8 else nn.Linear
        layers += [linear(n_in, width), _ACT[activation]()]
        n_in = width
    layers.append(nn.Linear(n_in, n_out))
    return nn.Sequential(*layers)


STRUCTURES = ("plain", "damping")


class ForceMLP(L.LightningModule):
    """Fully connected force network in scaled units.

    ``structure="plain"``: y = net(z), z the four standardised inputs.
    ``structure="damping"``: y = S(z_X) + C(z) v, a static-load network S of
    the position alone plus a learned 2x2 matrix C times the velocity v in
    units of c omega (unstandardised, so v = 0 is the static state).  The
    force at rest is then S alone, whatever the squeeze errors are, and the
    film's damping appears as C at small velocities.
    """

    def __init__(self, width: int = 50, depth: int = 1, activation: str = "tanh", optimizer: str = "adam",
                 lr: float = 3e-3, weight_decay: float = 0.0, scheduler: str = "cosine", max_epochs: int = 20,
                 out_std=(1.0, 1.0), out_mean=(0.0, 0.0), structure: str = "plain", v_mean=(0.0, 0.0),
                 v_std=(1.0, 1.0), n_inputs: int = 4):
        super().__init__()
        if activation not in _ACT:
            raise ValueError(f"unknown activation {activation!r}; choose one of {tuple(_ACT)}")
        if int(width) < 1 or int(depth) < 1:
            raise ValueError(f"width and depth must be >= 1, got width={width}, depth={depth}")
        if structure not in STRUCTURES:
            raise ValueError(f"unknown structure {structure!r}; choose one of {STRUCTURES}")
        self.save_hyperparameters()
        if structure == "plain":
            self.net = _mlp(n_inputs, 2, width, depth, activation)
        else:  # the last two inputs are the velocity, the others the position
            self.static = _mlp(n_inputs - 2, 2, width, depth, activation)
            self.damping = _mlp(n_inputs, 4, width, depth, activation)
        self.register_buffer("out_std", torch.tensor(out_std, dtype=torch.float32))
        self.register_buffer("out_mean", torch.tensor(out_mean, dtype=torch.float32))
        self.register_buffer("v_mean", torch.tensor(v_mean, dtype=torch.float32))
        self.register_buffer("v_std", torch.tensor(v_std, dtype=torch.float32))
        self._sq_err = 0.0
        self._sq_ref = 0.0
        self._train_sq_sum = torch.zeros((), dtype=torch.float64)
        self._train_rows = 0

    def forward(self, z):
        if self.hparams.structure == "plain":
            return self.net(z)
        v = z[:, -2:] * self.v_std + self.v_mean  # velocity in units of c omega, 0 at rest
        C = self.damping(z).view(-1, 2, 2)
        return self.static(z[:, :-2]) + torch.bmm(C, v.unsqueeze(-1)).squeeze(-1)

    def on_train_epoch_start(self):
        self._train_sq_sum = torch.zeros((), dtype=torch.float64)
        self._train_rows = 0

    def training_step(self, batch, batch_idx):
        z, y = batch[0], batch[1]
        loss = nn.functional.mse_loss(self(z), y)
        # the epoch's row-weighted mean loss, summed here and logged once at the epoch's end: the value
        # ``self.log(on_epoch=True)`` gives, without its per-step bookkeeping (benchmarks/bench_training_step.py)
        self._train_sq_sum += loss.detach().double() * z.shape[0]
        self._train_rows += z.shape[0]
        return loss

    def on_train_epoch_end(self):
        if self._train_rows:
            self.log("train_loss", float(self._train_sq_sum) / self._train_rows, prog_bar=True)

    def on_validation_epoch_start(self):
        self._sq_err = 0.0
        self._sq_ref = 0.0

    def validation_step(self, batch, batch_idx):
        z, y, F, gain = batch
        pred = self(z)
        self.log("val_loss", nn.functional.mse_loss(pred, y), on_step=False, on_epoch=True)
        F_pred = (pred * self.out_std + self.out_mean) * gain[:, None]
        self._sq_err += float(((F_pred.double() - F.double()) ** 2).sum())
        self._sq_ref += float((F.double() ** 2).sum())

    def on_validation_epoch_end(self):
        rel = math.sqrt(self._sq_err / max(self._sq_ref, 1e-300))
        self.log("val_rel_rmse", rel, prog_bar=True)

    def configure_optimizers(self):
        h = self.hparams
        # fused: one kernel for all parameters instead of a dozen small foreach ops per step (the CPU's
        # fused Adam, torch >= 2.4); the same update to round-off
        fused = True if self.device.type == "cpu" else None
        if h.optimizer == "adam":
            opt = torch.optim.Adam(self.parameters(), lr=h.lr, weight_decay=h.weight_decay, fused=fused)
        elif h.optimizer == "adamw":
            opt = torch.optim.AdamW(self.parameters(), lr=h.lr, weight_decay=h.weight_decay, fused=fused)
        elif h.optimizer == "sgd":
            opt = torch.optim.SGD(self.parameters(), lr=h.lr, momentum=0.9, weight_decay=h.weight_decay)
        else:
            raise ValueError(f"unknown optimizer {h.optimizer!r}; choose adam, adamw or sgd")
        if h.scheduler == "none":
            return opt
        if h.scheduler == "cosine":
            sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, T_max=max(1, h.max_epochs), eta_min=h.lr * 0.01)
            return {"optimizer": opt, "lr_scheduler": {"scheduler": sched, "interval": "epoch"}}
        if h.scheduler == "plateau":
            sched = torch.optim.lr_scheduler.ReduceLROnPlateau(opt, factor=0.5, patience=2)
            return {"optimizer": opt, "lr_scheduler": {"scheduler": sched, "monitor": "val_rel_rmse"}}
        raise ValueError(f"unknown scheduler {h.scheduler!r}; choose none, cosine or plateau")

    def layers_numpy(self):
        """Plain: [(W, b), ...]; damping: ([(W, b), ...] of S, [(W, b), ...] of C)."""
        def grab(seq):
            return [(m.weight.detach().double().numpy().copy(), m.bias.detach().double().numpy().copy())
                    for m in seq if isinstance(m, nn.Linear)]
        if self.hparams.structure == "plain":
            return grab(self.net)
        return grab(self.static), grab(self.damping)


class _Batches(torch.utils.data.IterableDataset):
    """Whole batches sliced from in-memory tensors (no per-sample collation), reshuffled each epoch."""

    def __init__(self, tensors, batch_size: int, shuffle: bool, seed: int, epoch_of=None):
        self.tensors = tensors
        self.batch_size = int(batch_size)
        self.shuffle = shuffle
        self.seed = seed
        self.epoch = 0
        # the trainer's epoch, so a run resumed from a checkpoint draws the same order as one never stopped
        self.epoch_of = epoch_of

    def __iter__(self):
        n = self.tensors[0].shape[0]
        if self.shuffle:
            epoch = self.epoch_of() if self.epoch_of is not None else self.epoch
            g = torch.Generator().manual_seed(self.seed + epoch)
            self.epoch = epoch + 1
            order = torch.randperm(n, generator=g)
        for start in range(0, n, self.batch_size):
            if self.shuffle:
                idx = order[start:start + self.batch_size]
                # index_select, not t[idx]: the same rows, a quarter of the time (advanced indexing's
                # generic path costs as much as a small network's backward pass)
                yield tuple(t.index_select(0, idx) for t in self.tensors)
            else:
                yield tuple(t[start:start + self.batch_size] for t in self.tensors)

    def __len__(self):
        return math.ceil(self.tensors[0].shape[0] / self.batch_size)


# the data layer owns the schema and the reading (old name kept for callers)
read_dataset = load_dataset


class ForceDataModule(L.LightningDataModule):
    """In-memory training/validation split by position, optionally restricted to eps in [eps_low, eps_high)."""

    def __init__(self, dataset_dir, scaling: str = "standard", power: float = 1.5, frame: str = "cartesian",
                 eps_low: float = 0.0,
                 eps_high: float = math.inf, val_fraction: float = 0.1, batch_size: int = 4096, seed: int = 0,
                 table: pd.DataFrame | None = None, meta: dict | None = None):
        super().__init__()
        if not 0.0 < val_fraction < 1.0:
            raise ValueError(f"val_fraction must lie in (0, 1), got {val_fraction!r}")
        self.dataset_dir = dataset_dir
        self.scaling_kind = scaling
        self.power = power
        self.frame = frame
        self.eps_low, self.eps_high = eps_low, eps_high
        self.val_fraction = val_fraction
        self.batch_size = batch_size
        self.seed = seed
        self._table, self._meta = table, meta
        self.scaling: Scaling | None = None

    def setup(self, stage=None):
        if self.scaling is not None:
            return
        df, meta = (self._table, self._meta) if self._table is not None else load_dataset(self.dataset_dir)
        self.bearing = dataset_bearing(meta)
        check_whirl_use(self.frame, "plain", self.bearing)  # before any training: the frame's premise
        df = df[(df["eps"] >= self.eps_low) & (df["eps"] < self.eps_high)]
        if len(df) == 0:
            raise ValueError(f"no samples with eps in [{self.eps_low}, {self.eps_high})")
        pos = df.groupby(["X1", "X2"], sort=True).ngroup().to_numpy()
        rng = np.random.default_rng(self.seed)
        n_pos = pos.max() + 1
        val_pos = rng.random(n_pos) < self.val_fraction
        if val_pos.all() or not val_pos.any():
            val_pos[:] = False
            val_pos[rng.integers(n_pos)] = n_pos > 1
        is_val = val_pos[pos]
        X = df[["X1", "X2"]].to_numpy()
        V = df[["V1", "V2"]].to_numpy()
        F = df[["F1", "F2"]].to_numpy()
        extras = tuple(c for c in EXTRA_INPUTS if c in df.columns)
        E = df[list(extras)].to_numpy() if extras else None
        b = self.bearing
        self.scaling = Scaling.fit(self.scaling_kind, X[~is_val], V[~is_val], F[~is_val], b.clearance, b.omega,
                                   b.force_scale, self.power, self.frame,
                                   E=None if E is None else E[~is_val], extras=extras,
                                   sleeve_gain=b.tan_half_angle if extras == ("S",) and isinstance(b, ConicalBearing)
                                   else 0.0)
        z = self.scaling.inputs(X, V, E)
        y = self.scaling.targets(X, V, F, E)
        gain = self.scaling.gain(X, V, E)  # F = (network output unscaled) * gain
        t = lambda a: torch.as_tensor(np.ascontiguousarray(a), dtype=torch.float32)  # noqa: E731
        tr, va = ~is_val, is_val
        self.train_tensors = (t(z[tr]), t(y[tr]))
        # validation compares forces in the model's frame (a rotation keeps the RMS error)
        self.val_tensors = (t(z[va]), t(y[va]), t(self.scaling.to_frame(X[va], F[va])), t(gain[va]))
        self.n_train, self.n_val = int(tr.sum()), int(va.sum())
        self.eps_data_max = float(df["eps"].max())

    def transfer_batch_to_device(self, batch, device, dataloader_idx):
        # batches are sliced from CPU tensors already; Lightning's generic walk over the batch costs as much
        # as a small network's forward pass, at every step
        if device.type == "cpu":
            return batch
        return super().transfer_batch_to_device(batch, device, dataloader_idx)

    def train_dataloader(self):
        epoch_of = (lambda: self.trainer.current_epoch) if self.trainer is not None else None  # noqa: E731
        return torch.utils.data.DataLoader(_Batches(self.train_tensors, self.batch_size, True, self.seed, epoch_of),
                                           batch_size=None)

    def val_dataloader(self):
        return torch.utils.data.DataLoader(_Batches(self.val_tensors, 65536, False, self.seed), batch_size=None)


class TargetStop(L.Callback):
    """Stop when ``val_rel_rmse`` <= target; record the training wall time to get there.

    The clock runs from the start of fitting (validation included, as any
    stopping rule needs it) and survives checkpoint/resume.
    """

    def __init__(self, target: float | None):
        self.target = target
        self.elapsed = 0.0
        self.time_to_target: float | None = None
        self.epoch_at_target: int | None = None
        self._t0 = None

    def on_train_start(self, trainer, pl_module):
        self._t0 = time.perf_counter()

    def _now(self):
        return self.elapsed + (time.perf_counter() - self._t0 if self._t0 is not None else 0.0)

    def on_validation_end(self, trainer, pl_module):
        if trainer.sanity_checking or self.target is None or self.time_to_target is not None:
            return
        val = trainer.callback_metrics.get("val_rel_rmse")
        if val is not None and float(val) <= self.target:
            self.time_to_target = self._now()
            self.epoch_at_target = trainer.current_epoch
            trainer.should_stop = True

    def on_train_end(self, trainer, pl_module):
        self.elapsed = self._now()
        self._t0 = None

    def state_dict(self):
        return {"elapsed": self._now(), "time_to_target": self.time_to_target,
                "epoch_at_target": self.epoch_at_target}

    def load_state_dict(self, state):
        self.elapsed = state["elapsed"]
        self.time_to_target = state["time_to_target"]
        self.epoch_at_target = state["epoch_at_target"]


class AtomicLastCheckpoint(L.pytorch.callbacks.ModelCheckpoint):
    """``last.ckpt`` after every epoch, written aside and renamed into place: a kill during the write
    leaves the previous epoch's checkpoint whole, never a truncated one that cannot be resumed."""

    # Lightning saves ``last`` only alongside a top-k checkpoint, so with save_top_k=0 it wrote one at the
    # very end of training and a killed run restarted from nothing; here it is written every epoch, at the
    # point where Lightning's own per-epoch checkpoint would be.
    def on_train_epoch_end(self, trainer, pl_module) -> None:
        if not self._should_skip_saving_checkpoint(trainer) and self._should_save_on_train_epoch_end(trainer):
            self._save_last_checkpoint(trainer, self._monitor_candidates(trainer))

    def on_validation_end(self, trainer, pl_module) -> None:
        if not self._should_skip_saving_checkpoint(trainer) and not self._should_save_on_train_epoch_end(trainer):
            self._save_last_checkpoint(trainer, self._monitor_candidates(trainer))

    def _save_checkpoint(self, trainer, filepath: str) -> None:
        import os

        tmp = f"{filepath}.partial"
        trainer.save_checkpoint(tmp, self.save_weights_only)
        if trainer.is_global_zero:
            os.replace(tmp, filepath)
        self._last_global_step_saved = trainer.global_step
        self._last_checkpoint_saved = filepath
        if trainer.is_global_zero:
            for logger in trainer.loggers:
                logger.after_save_checkpoint(self)


def train_network(dm: ForceDataModule, model_cfg: dict, trainer_cfg: dict, target: float | None,
                  ckpt_dir=None, logger=None, seed: int = 0, what: str = "training") -> dict:
    """Fit one network; returns its layers (numpy), scaling and timings.

    With ``ckpt_dir``, every epoch ends with an atomic ``last.ckpt`` there, and
    a rerun resumes from it: weights, optimiser, learning-rate schedule,
    the shuffle order (drawn from the trainer's epoch) and the training clock,
    so in deterministic mode kill + resume ends with the weights and metrics
    of an uninterrupted run.
    """
    L.seed_everything(seed, workers=True, verbose=False)
    dm.setup()
    assert dm.scaling is not None  # set by setup()
    check_whirl_use(dm.scaling.frame, model_cfg.get("structure", "plain"), dm.bearing)
    model = ForceMLP(width=model_cfg["width"], depth=model_cfg["depth"], activation=model_cfg["activation"],
                     optimizer=model_cfg.get("optimizer", "adam"), lr=model_cfg["lr"],
                     weight_decay=model_cfg.get("weight_decay", 0.0), scheduler=model_cfg.get("scheduler", "cosine"),
                     max_epochs=trainer_cfg["max_epochs"], out_std=[float(s) for s in dm.scaling.out_std],
                     out_mean=[float(s) for s in dm.scaling.out_mean],  # plain floats: checkpoints load with weights_only
                     structure=model_cfg.get("structure", "plain"),
                     v_mean=[float(s) for s in dm.scaling.in_mean[-2:]], v_std=[float(s) for s in dm.scaling.in_std[-2:]],
                     n_inputs=dm.scaling.n_inputs)
    stop = TargetStop(target)
    callbacks = [stop]
    if not trainer_cfg.get("progress_bar", False):
        # a line per epoch instead of a bar: readable in DVC stage output and CI logs
        from fluidfilm.progress import epoch_log_callback

        callbacks.append(epoch_log_callback(trainer_cfg["max_epochs"], what))
    from fluidfilm.progress import quiet_third_party

    quiet_third_party()
    ckpt_path = None
    if ckpt_dir is not None:
        ckpt_dir = Path(ckpt_dir)
        callbacks.append(AtomicLastCheckpoint(dirpath=ckpt_dir, save_last=True, save_top_k=0))
        if (ckpt_dir / "last.ckpt").exists():
            ckpt_path = str(ckpt_dir / "last.ckpt")
    trainer = L.Trainer(max_epochs=trainer_cfg["max_epochs"], max_time=trainer_cfg.get("max_time"),
                        accelerator=trainer_cfg.get("accelerator", "cpu"), devices=1, logger=logger or False,
                        callbacks=callbacks, enable_progress_bar=trainer_cfg.get("progress_bar", False),
                        enable_model_summary=False, num_sanity_val_steps=0, deterministic=True,
                        check_val_every_n_epoch=1, enable_checkpointing=ckpt_dir is not None)
    t0 = time.perf_counter()
    try:
        trainer.fit(model, datamodule=dm, ckpt_path=ckpt_path)
    except SystemExit:
        # Lightning turns Ctrl-C into sys.exit(1) (after saving nothing further) and ignores SIGINT from
        # then on; callers see it as what it is, an interruption, with Ctrl-C working again
        if trainer.interrupted:
            import signal

            signal.signal(signal.SIGINT, signal.default_int_handler)
            raise KeyboardInterrupt from None
        raise
    wall = time.perf_counter() - t0
    if "val_rel_rmse" not in trainer.callback_metrics:
        # resumed from a checkpoint of a finished run: nothing was trained, so measure it once
        trainer.validate(model, datamodule=dm, verbose=False)
    metrics = {k: float(v) for k, v in trainer.callback_metrics.items()}
    return {"layers": model.layers_numpy(), "scaling": dm.scaling, "module": model,
            "time_to_target_s": stop.time_to_target, "train_time_s": stop.elapsed, "fit_wall_s": wall,
            "epochs": trainer.current_epoch, "epoch_at_target": stop.epoch_at_target,
            "val_rel_rmse": metrics.get("val_rel_rmse"), "n_train": dm.n_train, "n_val": dm.n_val,
            "eps_data_max": dm.eps_data_max}
