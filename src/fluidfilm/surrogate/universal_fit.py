"""Training of the universal plain-bearing network with Lightning, and writing the shipped weights.

The network maps (eps, cos alpha, sin alpha, ln L/D), standardised, to the dimensionless force
G (1 - eps^2)^p / slenderness_gain(L/D), standardised (``surrogate.universal``).  The loss is the
squared *relative* error of G per row, the quantity the accuracy goals are stated in: since F = |u| G
in the journal's frame, a row's relative force error is that of G whatever the speed, viscosity, size
or drive magnitude.  Adam with a cosine schedule on mini-batches, then full-batch L-BFGS, both as
Lightning fits in float64 (the network is tiny; float64 lets L-BFGS converge below 1e-4 relative).
"""
from __future__ import annotations

from typing import Any

import hashlib
import json
import time
from pathlib import Path

import lightning as L
import numpy as np
import pandas as pd
import torch
from torch import nn

from fluidfilm import io
from fluidfilm.surrogate.universal import WEIGHTS_DIR, slenderness_gain

__all__ = ["UniversalNet", "features", "train_universal", "write_weights"]


def features(frame: pd.DataFrame, power: float) -> tuple[np.ndarray, np.ndarray]:
    """Raw network inputs (eps, cos alpha, sin alpha, ln L/D) and raw targets G (1 - eps^2)^p / gain(L/D).

    Parameters
    ----------
    frame : DataFrame
        Rows of the dimensionless dataset (``ld``, ``eps``, ``alpha``, ``G_r``, ``G_t``).
    power : float
        The exponent p.

    Returns
    -------
    (ndarray (n, 4), ndarray (n, 2))
    """
    eps = frame["eps"].to_numpy()
    alpha = frame["alpha"].to_numpy()
    ld = frame["ld"].to_numpy()
    z = np.stack([eps, np.cos(alpha), np.sin(alpha), np.log(ld)], axis=-1)
    factor = (1.0 - eps**2) ** power / slenderness_gain(ld)
    y = np.stack([frame["G_r"].to_numpy(), frame["G_t"].to_numpy()], axis=-1) * factor[:, None]
    return z, y


class UniversalNet(L.LightningModule):
    """A tanh MLP 4 -> width^depth -> 2 trained on the squared relative error of its raw targets.

    Parameters
    ----------
    width, depth : int
        Hidden units per layer and hidden layers.
    out_mean, out_std : sequence of float
        The targets' standardisation (the loss un-standardises to compare raw values).
    optimizer : {"adam", "lbfgs"}
        Adam with a cosine schedule over ``max_epochs``, or full-batch L-BFGS.
    lr : float
        Learning rate.
    max_epochs : int
        The schedule's length (Adam).
    floor : float
        The loss is |pred - y|^2 / (|y|^2 + floor^2): relative where |y| is above the floor, absolute below
        (the separating squeeze at high eccentricity has a force 1e-4 of the squeeze's other direction).
    """

    def __init__(self, width: int = 64, depth: int = 2, out_mean=(0.0, 0.0), out_std=(1.0, 1.0),
                 optimizer: str = "adam", lr: float = 3e-3, max_epochs: int = 100, floor: float = 0.0):
        super().__init__()
        self.save_hyperparameters()
        layers: list[nn.Module] = []
        n_in = 4
        for _ in range(depth):
            layers += [nn.Linear(n_in, width), nn.Tanh()]
            n_in = width
        layers.append(nn.Linear(n_in, 2))
        self.net = nn.Sequential(*layers).double()
        self.register_buffer("out_mean", torch.tensor(out_mean, dtype=torch.float64))
        self.register_buffer("out_std", torch.tensor(out_std, dtype=torch.float64))

    def forward(self, z):
        return self.net(z)

    def _rel(self, batch):
        z, y = batch
        pred = self(z) * self.out_std + self.out_mean
        return ((pred - y) ** 2).sum(-1) / ((y**2).sum(-1) + self.hparams.floor ** 2)

    def training_step(self, batch, batch_idx):
        loss = self._rel(batch).mean()
        self.log("train_rel_mse", loss, on_step=False, on_epoch=True, prog_bar=True)
        return loss

    def validation_step(self, batch, batch_idx):
        rel = self._rel(batch).sqrt()
        self.log("val_rel_median", rel.median(), on_step=False, on_epoch=True)
        self.log("val_rel_max", rel.max(), on_step=False, on_epoch=True)

    def configure_optimizers(self):
        if self.hparams.optimizer == "lbfgs":
            return torch.optim.LBFGS(self.parameters(), lr=self.hparams.lr, max_iter=50, history_size=50,
                                     line_search_fn="strong_wolfe")
        opt = torch.optim.Adam(self.parameters(), lr=self.hparams.lr)
        sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, T_max=max(1, int(self.hparams.max_epochs)))
        return {"optimizer": opt, "lr_scheduler": sched}

    def layers(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """The weights as [(W (out, in), b)] in float64."""
        return [(m.weight.detach().numpy().copy(), m.bias.detach().numpy().copy())
                for m in self.net if isinstance(m, nn.Linear)]


def _loader(z, y, batch_size, shuffle, seed=0):
    ds = torch.utils.data.TensorDataset(torch.as_tensor(z), torch.as_tensor(y))
    g = torch.Generator().manual_seed(seed)
    return torch.utils.data.DataLoader(ds, batch_size=batch_size, shuffle=shuffle, generator=g)


def train_universal(frame: pd.DataFrame, *, power: float = 2.0, width: int = 64, depth: int = 2,
                    adam_epochs: int = 300, lbfgs_steps: int = 40, batch_size: int = 512, lr: float = 3e-3,
                    floor_share: float = 0.05, val_fraction: float = 0.1, seed: int = 0, logger=None, progress: bool = False) -> dict:
    """Fit the universal network on the rows of one cavitation rule.

    Parameters
    ----------
    frame : DataFrame
        Rows of the dimensionless dataset (one cavitation rule).
    power : float, default 2.0
        Exponent p of the (1 - eps^2)^p factor of the targets.
    width, depth : int, default 64, 2
        The network.
    adam_epochs : int, default 300
        Adam epochs (mini-batches, cosine schedule).
    lbfgs_steps : int, default 40
        Full-batch L-BFGS steps after Adam (each up to 50 iterations); 0: none.
    batch_size : int, default 512
        Adam's mini-batch.
    lr : float, default 3e-3
        Adam's initial learning rate.
    floor_share : float, default 0.05
        The loss's floor (``UniversalNet``) as a share of the median |target|.
    val_fraction : float, default 0.1
        Rows held out (at random) for the validation metrics.
    seed : int, default 0
        Seed of the split, the initialisation and the shuffling.
    logger : Lightning logger or None, default None
        Where Lightning logs the metrics (an MLflow logger from the workflow layer).
    progress : bool, default False
        Lightning's progress bar.

    Returns
    -------
    dict
        ``layers``, ``in_mean``, ``in_std``, ``out_mean``, ``out_std``, ``power``, ``train_seconds`` and the
        validation relative errors of G (``val_rel_median``, ``val_rel_p99``, ``val_rel_max``).
    """
    L.seed_everything(seed, workers=True, verbose=False)
    z, y = features(frame, power)
    rng = np.random.default_rng(seed)
    val = rng.random(len(z)) < val_fraction
    in_mean, in_std = z[~val].mean(0), z[~val].std(0) + 1e-12
    out_mean, out_std = y[~val].mean(0), y[~val].std(0) + 1e-12
    zs = (z - in_mean) / in_std
    floor = float(floor_share * np.median(np.linalg.norm(y[~val], axis=-1)))
    train_dl = _loader(zs[~val], y[~val], batch_size, True, seed)
    val_dl = _loader(zs[val], y[val], max(1, int(val.sum())), False)
    kw = dict(accelerator="cpu", devices=1, logger=logger if logger is not None else False,
              enable_checkpointing=False, enable_progress_bar=progress, enable_model_summary=False)
    t0 = time.perf_counter()
    net = UniversalNet(width, depth, out_mean.tolist(), out_std.tolist(), "adam", lr, adam_epochs, floor)
    L.Trainer(max_epochs=adam_epochs, check_val_every_n_epoch=max(1, adam_epochs // 10), **kw).fit(
        net, train_dl, val_dl)
    if lbfgs_steps > 0:
        fine = UniversalNet(width, depth, out_mean.tolist(), out_std.tolist(), "lbfgs", 1.0, lbfgs_steps, floor)
        fine.load_state_dict(net.state_dict())
        # the Adam phase logged the shared hyperparameters to this run; MLflow refuses a changed value
        # (optimizer, lr) in one run, and the L-BFGS settings are in the run's config already
        fine._log_hyperparams = False
        full = _loader(zs[~val], y[~val], int((~val).sum()), False)
        L.Trainer(max_epochs=lbfgs_steps, check_val_every_n_epoch=max(1, lbfgs_steps // 4), **kw).fit(
            fine, full, val_dl)
        net = fine
    seconds = time.perf_counter() - t0
    with torch.no_grad():
        pred = net(torch.as_tensor(zs[val])).numpy() * out_std + out_mean
    rel = np.linalg.norm(pred - y[val], axis=-1) / np.linalg.norm(y[val], axis=-1)
    return {"layers": net.layers(), "in_mean": in_mean, "in_std": in_std, "out_mean": out_mean, "out_std": out_std,
            "power": float(power), "train_seconds": seconds, "val_rel_median": float(np.median(rel)),
            "val_rel_p99": float(np.quantile(rel, 0.99)), "val_rel_max": float(rel.max())}


def write_weights(fit: dict, cavitation: str, eps_max: float, ld_range: tuple[float, float], info: dict,
                  directory=WEIGHTS_DIR) -> Path:
    """Write one rule's network as ``<directory>/<cavitation>.npz`` and its SHA-256 into ``SHA256SUMS``.

    Parameters
    ----------
    fit : dict
        What ``train_universal`` returned.
    cavitation : str
        The rule.
    eps_max : float
        The data's largest eccentricity ratio.
    ld_range : (float, float)
        The data's L/D range.
    info : dict
        Provenance (dataset hash, sizes, validation errors), stored as JSON.
    directory : path-like, default the package's weights folder
        Where to write.

    Returns
    -------
    Path
        The weights file.
    """
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    arrays: dict[str, Any] = {"n_layers": np.array(len(fit["layers"])), "activation": np.array("tanh"),
              "power": np.array(fit["power"]), "eps_max": np.array(float(eps_max)),
              "ld_min": np.array(float(ld_range[0])), "ld_max": np.array(float(ld_range[1])),
              "info": np.array(json.dumps(info, sort_keys=True))}
    for k in ("in_mean", "in_std", "out_mean", "out_std"):
        arrays[k] = np.asarray(fit[k], dtype=np.float64)
    for i, (W, b) in enumerate(fit["layers"]):
        arrays[f"W{i}"] = np.asarray(W, dtype=np.float64)
        arrays[f"b{i}"] = np.asarray(b, dtype=np.float64)
    path = d / f"{cavitation}.npz"
    with io.atomic_path(path, suffix=".npz") as tmp:
        np.savez_compressed(tmp, **arrays)
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    sums = d / "SHA256SUMS"
    lines = [ln for ln in (sums.read_text().splitlines() if sums.exists() else []) if not ln.endswith(f"  {path.name}")]
    io.write_text(sums, "\n".join(sorted(lines + [f"{digest}  {path.name}"])) + "\n")
    return path
