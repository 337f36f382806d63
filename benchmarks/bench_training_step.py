"""Cost of one optimiser step of the best recipe's network: Lightning as the stages run it vs a bare torch loop.

    python benchmarks/bench_training_step.py [--rows 400000] [--epochs 3] [--repeats 5] [--quick]

The network is the one `train_best` fits per eccentricity region (4 inputs, one hidden layer of 64 tanh
units, 2 outputs, Adam, batches of 4096 rows sliced from in-memory tensors and reshuffled each epoch).
Four arms on the same synthetic rows, side by side, at 1 and 2 torch threads:

- ``bare torch``: forward, loss, backward, Adam step in a Python loop with the workspace's layers
  (``training.Tanh``, ``training.NarrowInputLinear``, fused Adam, ``index_select`` batches): the floor;
- ``Lightning``: ``ForceMLP`` under ``lightning.Trainer`` with the workspace's data module's batches,
  validation every epoch (as ``train_network`` runs it, without logger and checkpoints);
- ``Lightning, per-step log``: the same with ``self.log(on_epoch=True)`` at every step and Lightning's
  generic batch transfer, as the module was before 2026-11-26;
- ``Lightning, stock torch layers``: ``nn.Tanh``, ``nn.Linear`` and foreach Adam, as the module was
  before 2026-12-05 (torch's CPU tanh is not vectorised; its first-layer weight gradient is a slow product).

Prints the median milliseconds per step over the repeats and the ratios to the bare loop; writes
``reports/benchmarks/training_step.json``.  The rows are synthetic: the cost of a step does not depend
on the values, only on the shapes.
"""
from __future__ import annotations

import argparse
import math
import time

import lightning as L
import numpy as np
import torch
from torch import nn

from fluidfilm.perf.benchmarking import write_benchmark
from fluidfilm.progress import quiet_third_party
from fluidfilm.surrogate.training.lightning import ForceMLP, _Batches, _mlp

BATCH = 4096


class _PerStepLog(ForceMLP):
    """The module as it was: the epoch's training loss through Lightning's per-step bookkeeping."""

    def training_step(self, batch, batch_idx):
        loss = nn.functional.mse_loss(self(batch[0]), batch[1])
        self.log("train_loss", loss, on_step=False, on_epoch=True, prog_bar=True)
        return loss


class _StockLayers(ForceMLP):
    """The module with torch's stock layers and optimiser, as it was before 2026-12-05: ``nn.Tanh`` (not
    vectorised on the CPU), ``nn.Linear`` first (weight gradient g^T x), foreach Adam."""

    def __init__(self, **kw):
        super().__init__(**kw)
        self.net = nn.Sequential(nn.Linear(4, 64), nn.Tanh(), nn.Linear(64, 2))

    def configure_optimizers(self):
        opt = torch.optim.Adam(self.parameters(), lr=self.hparams.lr)
        sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, T_max=max(1, self.hparams.max_epochs))
        return {"optimizer": opt, "lr_scheduler": {"scheduler": sched, "interval": "epoch"}}


class _Data(L.LightningDataModule):
    def __init__(self, train, val, fast_transfer: bool):
        super().__init__()
        self.train, self.val, self.fast = train, val, fast_transfer

    def train_dataloader(self):
        return torch.utils.data.DataLoader(_Batches(self.train, BATCH, True, 0), batch_size=None)

    def val_dataloader(self):
        return torch.utils.data.DataLoader(_Batches(self.val, 65536, False, 0), batch_size=None)

    def transfer_batch_to_device(self, batch, device, dataloader_idx):
        if self.fast:
            return batch
        return super().transfer_batch_to_device(batch, device, dataloader_idx)


def lightning_ms(module_cls, fast: bool, train, val, epochs: int) -> float:
    model = module_cls(width=64, depth=1, activation="tanh", lr=3e-3, max_epochs=epochs)
    trainer = L.Trainer(max_epochs=epochs, accelerator="cpu", devices=1, logger=False, enable_progress_bar=False,
                        enable_model_summary=False, num_sanity_val_steps=0, deterministic=True,
                        enable_checkpointing=False)
    t0 = time.perf_counter()
    trainer.fit(model, datamodule=_Data(train, val, fast))
    return 1e3 * (time.perf_counter() - t0) / (epochs * math.ceil(len(train[0]) / BATCH))


def bare_ms(train, epochs: int) -> float:
    """The workspace's layers (``training._mlp``) and fused Adam in a plain loop: the same arithmetic as
    ``ForceMLP`` without Lightning."""
    z, y = train
    net = _mlp(4, 2, 64, 1, "tanh")
    opt = torch.optim.Adam(net.parameters(), lr=3e-3, fused=True)
    g = torch.Generator().manual_seed(0)
    t0 = time.perf_counter()
    for _ in range(epochs):
        order = torch.randperm(len(z), generator=g)
        for start in range(0, len(z), BATCH):
            idx = order[start:start + BATCH]
            loss = nn.functional.mse_loss(net(z.index_select(0, idx)), y.index_select(0, idx))
            opt.zero_grad()
            loss.backward()
            opt.step()
    return 1e3 * (time.perf_counter() - t0) / (epochs * math.ceil(len(z) / BATCH))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rows", type=int, default=400_000, help="training rows (a region of train_best: 0.3-0.9 M)")
    ap.add_argument("--epochs", type=int, default=3)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--quick", action="store_true", help="40,000 rows, 2 repeats")
    a = ap.parse_args()
    rows, repeats = (40_000, 2) if a.quick else (a.rows, a.repeats)
    quiet_third_party()
    rng = np.random.default_rng(0)
    Z = rng.uniform(-1, 1, (rows + rows // 9, 4))
    Y = np.stack([np.sin(2 * Z[:, 0]) * Z[:, 2], np.tanh(Z[:, 1] + Z[:, 3])], axis=1)
    t = lambda a: torch.as_tensor(a, dtype=torch.float32)  # noqa: E731
    train = (t(Z[:rows]), t(Y[:rows]))
    v = slice(rows, None)
    val = (t(Z[v]), t(Y[v]), t(Y[v]), torch.ones(len(Z[v])))  # z, y, force, gain: the module's validation
    arms = {"bare torch": lambda: bare_ms(train, a.epochs),
            "Lightning": lambda: lightning_ms(ForceMLP, True, train, val, a.epochs),
            "Lightning, per-step log": lambda: lightning_ms(_PerStepLog, False, train, val, a.epochs),
            "Lightning, stock torch layers": lambda: lightning_ms(_StockLayers, True, train, val, a.epochs)}
    print(f"{rows:,} rows, batch {BATCH}, {a.epochs} epochs per run, median of {repeats} runs (ms per step)")
    out = []
    for threads in (1, 2):
        torch.set_num_threads(threads)
        med = {}
        for _ in range(1):  # warm-up: first-call costs (Lightning's imports, the thread pool)
            for fn in arms.values():
                fn()
        times: dict[str, list[float]] = {k: [] for k in arms}
        for _ in range(repeats):  # interleaved, so a slow spell of the machine hits every arm alike
            for k, fn in arms.items():
                times[k].append(fn())
        for k in arms:
            med[k] = float(np.median(times[k]))
            print(f"  threads {threads}  {k:<24} {med[k]:6.2f} ms/step  ({med[k] / med['bare torch']:.2f}x bare)")
            out.append([str(threads), k, f"{med[k]:.2f}", f"{med[k] / med['bare torch']:.2f}"])
        print(f"  threads {threads}  per-step log / Lightning now: "
              f"{med['Lightning, per-step log'] / med['Lightning']:.2f}x")
    write_benchmark("training_step", "Milliseconds per optimiser step of a 1x64 tanh network, batch 4096",
                    ["torch threads", "arm", "ms per step (median)", "vs bare torch"], out,
                    notes=f"{rows:,} synthetic rows, {a.epochs} epochs per run, median of {repeats} interleaved "
                          "runs; Lightning runs include one validation pass per epoch, as the stages do.")


if __name__ == "__main__":
    main()
