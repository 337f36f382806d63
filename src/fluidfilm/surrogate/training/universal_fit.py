"""Training of the universal plain-bearing networks with Lightning, and writing the shipped weights.

One network per eccentricity region (the ``best`` model's layout: regions blended over a narrow band of
eps), each an MLP 4 -> width -> 2 (hidden activation tanh or ``pade_tanh``, tanh's [5/4] Pade approximant:
``surrogate.activations``) mapping (eps, cos alpha, sin alpha, ln L/D), standardised, to the
dimensionless force G (1 - eps^2)^p / slenderness_gain(L/D), standardised (``surrogate.universal``).  One
hidden layer keeps the cost per force at the best model's (L/D is folded into the first layer's bias for one
bearing); the regions give the capacity.

The loss is the squared *relative* error of G per row, the quantity the accuracy goals are stated in: since
F = |u| G in the journal's frame, a row's relative force error is that of G whatever the speed, viscosity,
size or drive magnitude.  A floor (a share of the region's median |target|) keeps the separating squeeze at
high eccentricity (a force 1e-4 of the approaching one) from dominating.  The optimiser is Levenberg-Marquardt
on the full batch (the paper's tool's optimiser, ``surrogate.training.levenberg_marquardt``, here in torch with the
row weights of the relative loss), one damped Gauss-Newton step per Lightning epoch (manual optimisation): for
a network of a few hundred weights it reaches relative errors Adam and L-BFGS did not approach in the same
time (docs/universal.md).  Each region trains on the rows of its eccentricities, its blend zones and one more
data eccentricity on each side, so neighbouring networks agree where they are blended.  Every fit checkpoints
(atomically) and a rerun resumes: a finished region is kept, an unfinished one continues from its last step.
"""
from __future__ import annotations

from typing import Any

import dataclasses
import hashlib
import json
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import lightning as L
import numpy as np
import pandas as pd
import torch
from torch import nn

from fluidfilm import io
from fluidfilm.data.spec import config_hash
from fluidfilm.surrogate.activations import HIDDEN_ACTIVATIONS, REGISTRY
from fluidfilm.surrogate.training.fit import _exit_with_parent, side_by_side, torch_threads, worker_count
from fluidfilm.surrogate.universal import WEIGHTS_DIR, slenderness_gain

__all__ = ["UniversalNet", "features", "derivative_targets", "region_rows", "train_region", "train_universal",
           "train_universals", "save_fit", "write_weights"]


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


def derivative_targets(frame: pd.DataFrame, power: float, rows: str = "static") -> np.ndarray:
    """Raw target derivatives d y / d eps and d y / d alpha of ``features``' targets, NaN where not fitted.

    y = G (1 - eps^2)^p / gain(L/D), so d y / d eps = (dG/deps (1 - eps^2)^p - 2 p eps G (1 - eps^2)^(p-1)) /
    gain and d y / d alpha = dG/dalpha (1 - eps^2)^p / gain, from the dataset's derivative columns.

    Parameters
    ----------
    frame : DataFrame
        Rows of the dimensionless dataset with the derivative columns (``data.universal``).
    power : float
        The exponent p.
    rows : {"static", "all"}, default "static"
        Which rows carry derivative targets: "static", the rows at alpha = 0 (the journal at rest, where
        stiffness and damping are taken: K comes from dG/deps there, C from dG/dalpha and the homogeneity);
        "all", every row.

    Returns
    -------
    ndarray, shape (n, 2, 2)
        [row, (d/deps, d/dalpha), (radial, tangential)]; NaN for rows without a target.
    """
    if rows not in ("static", "all"):
        raise ValueError(f"derivative rows must be 'static' or 'all', got {rows!r}")
    missing = [c for c in ("dG_r_deps", "dG_t_deps", "dG_r_dalpha", "dG_t_dalpha") if c not in frame]
    if missing:
        raise ValueError(f"the dataset has no derivative columns {missing} (made before format 2: regenerate it)")
    eps = frame["eps"].to_numpy()
    ld = frame["ld"].to_numpy()
    gain = slenderness_gain(ld)
    f = (1.0 - eps**2) ** power
    df = -2.0 * power * eps * (1.0 - eps**2) ** (power - 1.0)
    G = np.stack([frame["G_r"].to_numpy(), frame["G_t"].to_numpy()], axis=-1)
    dGe = np.stack([frame["dG_r_deps"].to_numpy(), frame["dG_t_deps"].to_numpy()], axis=-1)
    dGa = np.stack([frame["dG_r_dalpha"].to_numpy(), frame["dG_t_dalpha"].to_numpy()], axis=-1)
    out = np.stack([(dGe * f[:, None] + G * df[:, None]) / gain[:, None], dGa * (f / gain)[:, None]], axis=1)
    if rows == "static":
        alpha = np.mod(frame["alpha"].to_numpy(), 2.0 * np.pi)
        at_rest = np.minimum(alpha, 2.0 * np.pi - alpha) < 1e-12
        out[~at_rest] = np.nan
    return out


def region_rows(eps: np.ndarray, boundaries, blend_width: float, region: int, overlap: int = 1) -> np.ndarray:
    """Which rows a region's network trains on: eccentricities in the region and its blend zones, and
    ``overlap`` more of the data's eccentricities beyond each end (so both neighbours fit the blend zone).

    Parameters
    ----------
    eps : ndarray
        The rows' eccentricity ratios.
    boundaries : sequence of float
        Eccentricities between the regions (increasing).
    blend_width : float
        Width of the blend around each boundary.
    region : int
        The region, 0 .. len(boundaries).
    overlap : int, default 1
        Data eccentricities added beyond each end.

    Returns
    -------
    ndarray of bool

    Examples
    --------
    >>> eps = np.array([0.1, 0.2, 0.3, 0.4, 0.5, 0.6])
    >>> region_rows(eps, [0.35], 0.04, 0).tolist()
    [True, True, True, True, False, False]
    >>> region_rows(eps, [0.35], 0.04, 1, overlap=0).tolist()
    [False, False, False, True, True, True]
    """
    bounds = [float(b) for b in boundaries]
    if not 0 <= region <= len(bounds):
        raise ValueError(f"region {region!r} does not exist: {len(bounds) + 1} regions (0 .. {len(bounds)})")
    lo = bounds[region - 1] - 0.5 * blend_width if region > 0 else -np.inf
    hi = bounds[region] + 0.5 * blend_width if region < len(bounds) else np.inf
    values = np.unique(eps)
    inside = np.flatnonzero((values >= lo) & (values <= hi))
    if inside.size == 0:
        raise ValueError(f"region {region} ({lo:.3g} <= eps <= {hi:.3g}) holds none of the data's eccentricities")
    keep = values[max(0, inside[0] - overlap):inside[-1] + overlap + 1]
    return np.isin(eps, keep)


def units(A, activation: str):
    """The activation's values and first and second derivatives (H, D, E) at pre-activations ``A`` (NumPy or
    torch): tanh (the paper's tansig), or ``pade_tanh`` (``surrogate.activations``: tanh's [5/4] Pade
    approximant as the activation itself, which the one-state float64 kernel evaluates exactly with 6 vector
    operations and a division where tanh takes 19 and a division)."""
    if activation in HIDDEN_ACTIVATIONS:
        return REGISTRY[activation].derivatives(A)
    raise ValueError(f"activation={activation!r}: choose one of {HIDDEN_ACTIVATIONS}")


class PadeTanh(nn.Module):
    """The ``pade_tanh`` activation as a torch module."""

    def forward(self, a):
        x2 = a * a                       # pade_tanh's value alone, the same arithmetic as activations.pade_tanh
        return a * (945.0 + x2 * (105.0 + x2)) / (945.0 + x2 * (420.0 + 15.0 * x2))


def _weight_order(h: int) -> np.ndarray:
    """For each weight in ``UniversalNet._theta``'s order (W1 (h, 4) by unit, b1, W2 (2, h), b2), its index in
    the normal equations' order [W1 by input (i h + j), b1, W2_0, b2_0, W2_1, b2_1]."""
    j, i = np.divmod(np.arange(4 * h), 4)
    return np.concatenate([i * h + j, 4 * h + np.arange(h), 5 * h + np.arange(h), 6 * h + 1 + np.arange(h),
                           [6 * h, 7 * h + 1]])


class UniversalNet(L.LightningModule):
    """An MLP 4 -> width -> 2 (``activation``: tanh or ``pade_tanh``) fitted by Levenberg-Marquardt on weighted residuals, one full-batch step per
    epoch (Lightning's manual optimisation).

    The batch is (z standardised, y standardised, w): the residual of row n and output k is
    (net(z_n)_k - y_nk) w_nk, with w the relative loss's row weight times the output's spread, so the sum of
    squares is the relative loss of the raw targets.  The damping mu follows MATLAB's trainlm schedule in
    spirit (divided by 3 after a step that lowers the loss, times 4 until one does) and is part of the state
    (checkpoints resume it); the fit stops when mu passes ``mu_max`` (no step lowers the loss).

    Parameters
    ----------
    width : int
        Hidden units.
    out_mean, out_std : sequence of float
        The targets' standardisation (validation un-standardises to report raw relative errors).
    mu : float, default 1e-3
        Initial damping.
    mu_max : float, default 1e10
        Damping at which the fit has converged.
    derivative_weight : float, default 0.0
        Weight of the derivative residuals (``train_region``).
    activation : {"tanh", "pade_tanh"}, default "tanh"
        Hidden activation (``units``).
    """

    def __init__(self, width: int = 64, out_mean=(0.0, 0.0), out_std=(1.0, 1.0), mu: float = 1e-3,
                 mu_max: float = 1e10, derivative_weight: float = 0.0, activation: str = "tanh"):
        super().__init__()
        if activation not in HIDDEN_ACTIVATIONS:
            raise ValueError(f"activation={activation!r}: choose one of {HIDDEN_ACTIVATIONS}")
        self.save_hyperparameters()
        self.automatic_optimization = False
        self.net = nn.Sequential(nn.Linear(4, width), REGISTRY[activation].torch_module()(),
                                 nn.Linear(width, 2)).double()
        self.register_buffer("out_mean", torch.tensor(out_mean, dtype=torch.float64))
        self.register_buffer("out_std", torch.tensor(out_std, dtype=torch.float64))
        self.register_buffer("mu", torch.tensor(float(mu), dtype=torch.float64))

    def forward(self, z):
        return self.net(z)

    def _theta(self) -> torch.Tensor:
        return torch.cat([p.detach().reshape(-1) for p in self.net.parameters()])

    def _set_theta(self, theta: torch.Tensor) -> None:
        with torch.no_grad():
            k = 0
            for p in self.net.parameters():
                p.copy_(theta[k:k + p.numel()].view_as(p))
                k += p.numel()

    def _unpack(self, theta):
        h = self.hparams.width
        return theta[:4 * h].view(h, 4), theta[4 * h:5 * h], theta[5 * h:7 * h].view(2, h), theta[7 * h:]

    def _residuals(self, theta, z, y, w):
        W1, b1, W2, b2 = self._unpack(theta)
        H = self.net[1](z @ W1.T + b1)
        return H, ((H @ W2.T + b2) - y) * w

    def _derivative_residuals(self, theta, z, S, T, Wd):
        """Residuals of the network's input derivatives: (d_a net_k - T_ak) Wd_ak for the directions S_a.

        ``S`` (m, 2, 4): the directions d/deps and d/dalpha in standardised input space; ``T`` (m, 2, 2) the
        targets (standardised outputs per raw eps or alpha); the network's derivative along S_a is
        W2 (D * (W1 S_a)), D the activation's slope (``units``)."""
        W1, b1, W2, _ = self._unpack(theta)
        H, D, _ = units(z @ W1.T + b1, self.hparams.activation)
        Q = S @ W1.T                                              # (m, 2, h): W1 S_a
        d = (D[:, None, :] * Q) @ W2.T                            # (m, 2, 2): [row, direction, output]
        return H, D, Q, (d - T) * Wd

    def _jacobian(self, theta, z, H, w):
        """d residual / d theta, rows (n, k) flattened, columns in ``_theta``'s order (W1, b1, W2, b2)."""
        h = self.hparams.width
        n = z.shape[0]
        W1, b1, W2, _ = self._unpack(theta)
        D = units(z @ W1.T + b1, self.hparams.activation)[1]
        J = torch.zeros((n, 2, theta.numel()), dtype=theta.dtype)
        for k in range(2):
            G = w[:, k:k + 1] * W2[k] * D                      # (n, h): d r_k / d (pre-activation)
            J[:, k, :4 * h] = (G[:, :, None] * z[:, None, :]).reshape(n, 4 * h)
            J[:, k, 4 * h:5 * h] = G
            J[:, k, 5 * h + k * h:5 * h + (k + 1) * h] = w[:, k:k + 1] * H
            J[:, k, 7 * h + k] = w[:, k]
        return J.reshape(2 * n, -1)

    def _derivative_jacobian(self, theta, z, S, Wd, H, D, Q):
        """d (derivative residual) / d theta, rows (m, a, k) flattened (``_derivative_residuals``'s order).

        With A = W1 z + b1, d_ak = sum_j W2_kj D_j Q_aj: d/dW2_kj = D_j Q_aj, d/db1_j = W2_kj E_j Q_aj,
        d/dW1_ji = W2_kj (E_j Q_aj z_i + D_j S_ai), d/db2 = 0, with D and E the activation's first and second
        derivatives (tanh: 1 - H^2 and -2 H D)."""
        h = self.hparams.width
        m = z.shape[0]
        W2 = theta[5 * h:7 * h].view(2, h)
        J = torch.zeros((m, 2, 2, theta.numel()), dtype=theta.dtype)
        HD2 = units(z @ self._unpack(theta)[0].T + self._unpack(theta)[1], self.hparams.activation)[2]
        for a in range(2):
            for k in range(2):
                c = Wd[:, a, k:k + 1] * W2[k]                    # (m, h)
                g1 = c * HD2 * Q[:, a, :]                          # coefficient of z_i (and of b1)
                g2 = c * D                                         # coefficient of S_ai
                J[:, a, k, :4 * h] = (g1[:, :, None] * z[:, None, :] + g2[:, :, None] * S[:, a, None, :]).reshape(m, 4 * h)
                J[:, a, k, 4 * h:5 * h] = g1
                J[:, a, k, 5 * h + k * h:5 * h + (k + 1) * h] = Wd[:, a, k:k + 1] * D * Q[:, a, :]
        return J.reshape(4 * m, -1)

    def _sse(self, theta, z, y, w, deriv):
        _, r = self._residuals(theta, z, y, w)
        sse = float((r * r).sum())
        if deriv is not None:
            rd = self._derivative_residuals(theta, *deriv)[3]
            sse += float((rd * rd).sum())
        return sse

    @staticmethod
    def _derivative_rows(batch):
        """The rows of the batch with derivative targets: (z, S, T, Wd) restricted to them, or None."""
        z, _, _, S, T, Wd = batch
        rows = torch.nonzero(Wd.abs().sum(dim=(1, 2)) > 0).flatten()
        if rows.numel() == 0:
            return None
        return z[rows], S[rows], T[rows], Wd[rows]

    def _normal_equations(self, theta, z, y, w, deriv):
        """J^T J, J^T r and the sums of squares (all rows; value rows only) of the Gauss-Newton step.

        The Jacobian of ``_jacobian`` and ``_derivative_jacobian`` (the plain way, kept as the check in the
        tests), formed by output: the rows of output k (values, then derivatives) depend on the first layer,
        its bias and output k's second-layer row and bias only, so each output's rows go into one buffer of
        those 5 h + h + 1 columns (kept between steps), J^T J is the sum of the two blocks' products, and the
        cross block of the two second-layer rows is zero.  Each product is BLAS ``dsyrk`` (one triangle).  On
        one thread it takes a quarter of the time of torch's full ``J.T @ J`` of the whole Jacobian
        (docs/dataset_and_surrogates.md); the fit's time is these products."""
        from scipy.linalg.blas import dsyrk

        h = self.hparams.width
        th = theta.numpy()
        W1, b1, W2 = th[:4 * h].reshape(h, 4), th[4 * h:5 * h], th[5 * h:7 * h].reshape(2, h)
        zn, yn, wn = z.numpy(), y.numpy(), w.numpy()
        n, m = zn.shape[0], (0 if deriv is None else deriv[0].shape[0])
        p, q = th.size, 6 * h + 1                      # all weights; those one output's rows depend on
        bufs = getattr(self, "_jbufs", None)
        if bufs is None or bufs[0].shape != (n + 2 * m, q):
            bufs = self._jbufs = [np.zeros((n + 2 * m, q)) for _ in range(2)]   # derivative rows' b2 column: 0
        act = self.hparams.activation
        H, D, _ = units(zn @ W1.T + b1, act)
        r = (H @ W2.T + th[7 * h:] - yn) * wn                                     # (n, 2)
        sse_values = float(np.einsum("ij,ij->", r, r))
        sse = sse_values
        if deriv is not None:
            zd, Sd, Td, Wdd = (a.numpy() for a in deriv)
            Hd, Dd, HD2 = units(zd @ W1.T + b1, act)
            Q = Sd @ W1.T                                                         # (m, 2, h): W1 S_a
            rd = (np.einsum("mah,kh->mak", Dd[:, None, :] * Q, W2) - Td) * Wdd    # (m, 2 directions, 2 outputs)
            sse += float(np.einsum("mak,mak->", rd, rd))
        # J^T J in the order [W1 by input (i h + j), b1, W2_0, b2_0, W2_1, b2_1]: output k's buffer columns
        # are the first 5 h and one contiguous block, and the first layer's columns by input make its block
        # of the buffer (n, 4, h) products of a row's input and its h-vector (vectorised; by unit, (n, h, 4),
        # a third of the step went there)
        P = np.zeros((p, p))
        gP = np.zeros(p)
        for k in range(2):
            Jk = bufs[k]
            G = (wn[:, k:k + 1] * W2[k]) * D                                      # d r_k / d (pre-activation)
            blk = Jk[:n, :4 * h]
            blk.shape = (n, 4, h)                                                 # a view (raises if it were a copy)
            np.multiply(zn[:, :, None], G[:, None, :], out=blk)
            Jk[:n, 4 * h:5 * h] = G
            np.multiply(wn[:, k:k + 1], H, out=Jk[:n, 5 * h:6 * h])
            Jk[:n, 6 * h] = wn[:, k]
            rk = [r[:, k]]
            for a in range(2 if deriv is not None else 0):
                rows = slice(n + a * m, n + (a + 1) * m)
                c = Wdd[:, a, k:k + 1] * W2[k]
                g1 = c * HD2 * Q[:, a, :]                                         # coefficient of z_i (and of b1)
                g2 = c * Dd                                                       # coefficient of S_ai
                blk = Jk[rows, :4 * h]
                blk.shape = (m, 4, h)
                blk[...] = zd[:, :, None] * g1[:, None, :] + Sd[:, a, :, None] * g2[:, None, :]
                Jk[rows, 4 * h:5 * h] = g1
                Jk[rows, 5 * h:6 * h] = Wdd[:, a, k:k + 1] * Dd * Q[:, a, :]
                rk.append(rd[:, a, k])
            U = dsyrk(1.0, Jk.T, trans=0, lower=0)                                # upper triangle of Jk^T Jk
            o = 5 * h + k * (h + 1)
            P[:5 * h, :5 * h] += U[:5 * h, :5 * h]
            P[:5 * h, o:o + h + 1] = U[:5 * h, 5 * h:]
            P[o:o + h + 1, o:o + h + 1] = U[5 * h:, 5 * h:]
            gv = Jk.T @ np.concatenate(rk)
            gP[:5 * h] += gv[:5 * h]
            gP[o:o + h + 1] = gv[5 * h:]
        P = np.triu(P) + np.triu(P, 1).T
        order = _weight_order(h)                                                  # P's index of each weight
        A = P[np.ix_(order, order)]
        g = gP[order]
        return torch.from_numpy(A), torch.from_numpy(g), sse, sse_values

    def training_step(self, batch, batch_idx):
        z, y, w = batch[:3]
        deriv = self._derivative_rows(batch)
        theta = self._theta()
        A, g, sse, sse_values = self._normal_equations(theta, z, y, w, deriv)
        diag = torch.diagonal(A) + 1e-12
        mu = float(self.mu)
        while mu <= self.hparams.mu_max:
            step = torch.linalg.solve(A + mu * torch.diag(diag), -g)
            sse_new = self._sse(theta + step, z, y, w, deriv)
            if sse_new < sse:
                self._set_theta(theta + step)
                sse = sse_new
                mu = max(mu / 3.0, 1e-15)
                break
            mu *= 4.0
        self.mu.fill_(mu)
        if mu > self.hparams.mu_max:
            self.trainer.should_stop = True
        self.log("train_rel_rms", (sse_values / z.shape[0]) ** 0.5, on_step=False, on_epoch=True)
        self.log("train_loss", sse, on_step=False, on_epoch=True)
        self.log("mu", mu, on_step=False, on_epoch=True)

    def validation_step(self, batch, batch_idx):
        z, y = batch[:2]
        pred = self(z) * self.out_std + self.out_mean
        raw = y * self.out_std + self.out_mean
        rel = (pred - raw).norm(dim=-1) / raw.norm(dim=-1)
        self.log("val_rel_median", rel.median(), on_step=False, on_epoch=True)
        self.log("val_rel_p99", torch.quantile(rel, 0.99), on_step=False, on_epoch=True)
        deriv = self._derivative_rows(batch)
        if deriv is not None:
            rd = self._derivative_residuals(self._theta(), *deriv)[3]
            scaled = rd.norm(dim=-1).flatten() / float(self.hparams.derivative_weight)
            self.log("val_deriv_rel_median", scaled.median(), on_step=False, on_epoch=True)

    def configure_optimizers(self):
        # the Levenberg-Marquardt step is taken in training_step; Lightning's loop only needs an optimiser object
        return torch.optim.SGD(self.parameters(), lr=0.0)

    def layers(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """The weights as [(W (out, in), b)] in float64."""
        return [(m.weight.detach().numpy().copy(), m.bias.detach().numpy().copy())
                for m in self.net if isinstance(m, nn.Linear)]


class _FullBatch(torch.utils.data.Dataset):
    """The whole set as its one batch: a loader over it (``batch_size=None``) hands the tensors on as they are.
    A loader over a ``TensorDataset`` with the batch as large as the set fetched the rows one by one and
    stacked them again every epoch, that is every Levenberg-Marquardt step: ~40 % of a step's time for a
    region of ~5,000 rows (the same tensors, so the same steps)."""

    def __init__(self, tensors):
        self.tensors = list(tensors)

    def __len__(self) -> int:
        return 1

    def __getitem__(self, index: int):
        if index != 0:
            raise IndexError(f"a full batch has only index 0, got {index}")
        return self.tensors


class _EveryNCheckpoint(L.pytorch.callbacks.Callback):
    """``last.ckpt`` (written aside and renamed into place) every ``every`` steps and when the fit stops."""

    def __init__(self, path: Path, every: int):
        self.path, self.every = Path(path), int(every)

    def _save(self, trainer):
        import os

        self.path.parent.mkdir(parents=True, exist_ok=True)
        tmp = f"{self.path}.partial"
        trainer.save_checkpoint(tmp)
        os.replace(tmp, self.path)

    def on_train_epoch_end(self, trainer, pl_module):
        if (trainer.current_epoch + 1) % self.every == 0 or trainer.should_stop:
            self._save(trainer)

    def on_train_end(self, trainer, pl_module):
        self._save(trainer)


class _EpochLog(L.Callback):
    """A progress line every ``every`` epochs (LM steps) with the loss, the damping and the elapsed time."""

    def __init__(self, what: str, every: int):
        self.what, self.every, self.t0 = what, every, time.perf_counter()

    def on_train_epoch_end(self, trainer, pl_module):
        e = trainer.current_epoch
        if e % self.every == 0:
            m = trainer.callback_metrics
            val = f", val median {100 * float(m['val_rel_median']):.3f} %" if "val_rel_median" in m else ""
            print(f"    {self.what}: step {e}, rel rms {float(m['train_rel_rms']):.3e}, mu {float(m['mu']):.1e}{val}, "
                  f"{time.perf_counter() - self.t0:.0f} s", flush=True)


def train_region(z: np.ndarray, y: np.ndarray, *, width: int = 64, steps: int = 3000, max_minutes: float | None = None,
                 floor_share: float = 0.01, val_fraction: float = 0.1, seed: int = 0, ckpt_dir=None, logger=None,
                 what: str = "region", derivatives: np.ndarray | None = None, derivative_weight: float = 0.0,
                 init: dict | None = None, activation: str = "tanh") -> dict:
    """Fit one region's network (``UniversalNet``) on raw inputs ``z`` and raw targets ``y``, and optionally on
    the targets' derivatives (a Sobolev fit).

    Parameters
    ----------
    z, y : ndarray, shape (n, 4), (n, 2)
        Raw inputs and targets (``features``).
    derivatives : ndarray, shape (n, 2, 2), or None, default None
        Raw target derivatives d y / d eps and d y / d alpha (``derivative_targets``), NaN where not fitted.
        Each is a residual of relative weight ``derivative_weight`` / sqrt(|dy|^2 + |y|^2 + floor^2): an error
        of 1 % in a derivative costs what one of 1 % x ``derivative_weight`` in a value does.
    derivative_weight : float, default 0.0
        Weight of the derivative residuals (0: values only).
    init : dict or None, default None
        A finished fit (what this function returns) to start from: its weights and standardisation.
    activation : {"tanh", "pade_tanh"}, default "tanh"
        Hidden activation (``units``); the second phase must use the first's.
    width : int, default 64
        Hidden units.
    steps : int, default 3000
        Levenberg-Marquardt steps (Lightning epochs): the fit's stopping rule, the same on any machine (of
        the same arithmetic: another CPU's BLAS kernels may sum in another order).
    max_minutes : float or None, default None
        A wall-time cap on the fit (Lightning's ``max_time``; its clock is part of the checkpoint); None: none.
        A fit stopped by it has taken fewer than ``steps`` steps, a number that depends on the machine
        (``stopped_by_time`` in the result).
    floor_share : float, default 0.01
        The relative loss's floor as a share of the median |target|: rows weigh 1 / sqrt(|y|^2 + floor^2).
    val_fraction : float, default 0.1
        Rows held out (at random) for the validation metrics.
    seed : int, default 0
        Seed of the split and the initialisation.
    ckpt_dir : path-like or None, default None
        Where ``last.ckpt`` is written (atomically, every 25 steps and at the end); a rerun resumes from it.
    logger : Lightning logger or None, default None
        Where Lightning logs the metrics.
    what : str, default "region"
        The fit's name in the progress lines.

    Returns
    -------
    dict
        ``layers``, ``in_mean``, ``in_std``, ``out_mean``, ``out_std``, ``steps``, ``stopped_by_time``,
        ``train_seconds`` and the validation relative errors of the raw targets (``val_rel_median``, ``val_rel_p99``, ``val_rel_max``).
    """
    from datetime import timedelta

    from threadpoolctl import threadpool_limits

    from fluidfilm.progress import quiet_third_party

    quiet_third_party()
    L.seed_everything(seed, workers=True, verbose=False)
    rng = np.random.default_rng(seed)
    val = rng.random(len(z)) < val_fraction
    if init is not None:
        in_mean, in_std, out_mean, out_std = (np.asarray(init[k], dtype=np.float64)
                                              for k in ("in_mean", "in_std", "out_mean", "out_std"))
    else:
        in_mean, in_std = z[~val].mean(0), z[~val].std(0) + 1e-12
        out_mean, out_std = y[~val].mean(0), y[~val].std(0) + 1e-12
    floor = float(floor_share * np.median(np.linalg.norm(y[~val], axis=-1)))
    w = (1.0 / np.sqrt((y**2).sum(-1) + floor**2))[:, None] * out_std
    # derivative rows: directions d/deps and d/dalpha in standardised input space (z = eps, cos a, sin a, ln L/D),
    # targets per standardised output, weights (0 where a row has no target)
    S = np.zeros((len(z), 2, 4))
    S[:, 0, 0] = 1.0 / in_std[0]
    S[:, 1, 1], S[:, 1, 2] = -z[:, 2] / in_std[1], z[:, 1] / in_std[2]
    T = np.zeros((len(z), 2, 2))
    Wd = np.zeros((len(z), 2, 2))
    if derivatives is not None and derivative_weight > 0.0:
        has = np.isfinite(derivatives).all(axis=-1)                       # (n, 2)
        dy = np.where(np.isfinite(derivatives), derivatives, 0.0)
        scale = np.sqrt((dy**2).sum(-1) + (y**2).sum(-1)[:, None] + floor**2)   # (n, 2)
        T = dy / out_std
        Wd = np.where(has[:, :, None], float(derivative_weight) * out_std / scale[:, :, None], 0.0)

    def tensors(mask):
        return [torch.as_tensor(a[mask]) for a in ((z - in_mean) / in_std, (y - out_mean) / out_std, w, S, T, Wd)]

    def loader(mask):
        return torch.utils.data.DataLoader(_FullBatch(tensors(mask)), batch_size=None)

    net = UniversalNet(width, out_mean.tolist(), out_std.tolist(), derivative_weight=float(derivative_weight),
                       activation=activation)
    if init is not None:
        with torch.no_grad():
            linears = [m for m in net.net if isinstance(m, nn.Linear)]
            if len(linears) != len(init["layers"]):
                raise ValueError(f"init has {len(init['layers'])} layers, the network {len(linears)}")
            for m, (W, b) in zip(linears, init["layers"]):
                if tuple(m.weight.shape) != np.shape(W):
                    raise ValueError(f"init layer of shape {np.shape(W)} does not fit the network's {tuple(m.weight.shape)}")
                m.weight.copy_(torch.as_tensor(np.asarray(W, dtype=np.float64)))
                m.bias.copy_(torch.as_tensor(np.asarray(b, dtype=np.float64)))
    callbacks: list[Any] = [_EpochLog(what, 100)]
    ckpt_path = None
    if ckpt_dir is not None:
        ckpt_dir = Path(ckpt_dir)
        callbacks.append(_EveryNCheckpoint(ckpt_dir / "last.ckpt", 25))
        if (ckpt_dir / "last.ckpt").exists():
            ckpt_path = str(ckpt_dir / "last.ckpt")
    if int(steps) < 1:
        raise ValueError(f"steps={steps!r}: a fit needs at least one Levenberg-Marquardt step")
    if max_minutes is not None and not float(max_minutes) > 0.0:
        raise ValueError(f"max_minutes={max_minutes!r} must be > 0 (or None: no wall-time cap)")
    cap = timedelta(minutes=float(max_minutes)) if max_minutes is not None else None
    trainer = L.Trainer(max_epochs=int(steps), max_time=cap, accelerator="cpu",
                        devices=1, logger=logger if logger is not None else False, callbacks=callbacks,
                        enable_progress_bar=False, enable_model_summary=False, num_sanity_val_steps=0,
                        check_val_every_n_epoch=100, enable_checkpointing=False)
    # one thread, torch's and numpy's BLAS (dsyrk), for the fit and its validation errors: another count sums
    # J^T J in another order, and Levenberg-Marquardt carries round-off into other weights
    with torch_threads(1), threadpool_limits(limits=1, user_api="blas"):
        t0 = time.perf_counter()
        trainer.fit(net, loader(~val), loader(val), ckpt_path=ckpt_path)
        seconds = time.perf_counter() - t0
        with torch.no_grad():
            pred = net(torch.as_tensor((z[val] - in_mean) / in_std)).numpy() * out_std + out_mean
        rel = np.linalg.norm(pred - y[val], axis=-1) / np.linalg.norm(y[val], axis=-1)
        out = {"layers": net.layers(), "in_mean": in_mean, "in_std": in_std, "out_mean": out_mean,
               "out_std": out_std, "steps": int(trainer.current_epoch),
               "stopped_by_time": bool(trainer.current_epoch < int(steps)), "train_seconds": seconds,
               "val_rel_median": float(np.median(rel)), "val_rel_p99": float(np.quantile(rel, 0.99)),
               "val_rel_max": float(rel.max())}
        if derivatives is not None and derivative_weight > 0.0:
            rows = val & (Wd.reshape(len(z), -1) != 0).any(-1)
            if rows.any():
                v = [torch.as_tensor(a[rows]) for a in ((z - in_mean) / in_std, S, T, Wd)]
                rd = net._derivative_residuals(net._theta(), *v)[3].detach().numpy()
                out["val_deriv_rel_median"] = float(np.median(np.linalg.norm(rd, axis=-1)) / derivative_weight)
        return out


@dataclass(frozen=True)
class UniversalFitSettings:
    """The settings of a universal fit and their defaults, written once: ``train_universal``'s and the pipeline's
    (conf/universal.yaml's ``train`` block names these fields: tests/surrogate/test_universal.py checks it).

    Parameters
    ----------
    boundaries : sequence of float, default (0.3, 0.5, 0.65, 0.78, 0.87)
        Eccentricity ratios between the regions.
    blend_width : float, default 0.04
        Width of the blend between neighbouring regions (the force model's).
    overlap : int, default 1
        Data eccentricities beyond a region's blend zones that its network also fits (``region_rows``).
    power : float, default 2.0
        Exponent p of the (1 - eps^2)^p factor of the targets.
    width : int, default 64
        Hidden units of each network (one hidden layer).
    steps : int or sequence of int, default 3000
        Levenberg-Marquardt steps per region, or one count per region (the high eccentricities converge
        slowest): the stopping rule, so the same data and settings give the same weights whatever the clock.
    max_minutes : float, sequence of float or None, default None
        A wall-time cap per region, or one per region (None: none). A cap reached makes the step count, and
        so the weights, depend on the machine's speed (``train_region``).
    floor_share : float, default 0.01
        The relative loss's floor (``train_region``).
    val_fraction : float, default 0.1
        Rows held out (at random) for the validation metrics.
    seed : int, default 0
        Seed.
    derivative_weight : float, default 0.0
        Weight of the derivative residuals in the second phase (``train_region``); 0: no second phase.
    derivative_rows : {"static", "all"}, default "static"
        The rows with derivative targets (``derivative_targets``).
    refine_minutes : float, sequence of float or None, default None
        A wall-time cap on the second phase per region, or one per region (None: none).
    refine_steps : int or sequence of int, default 3000
        Levenberg-Marquardt steps of the second phase per region, or one count per region.
    activation : {"tanh", "pade_tanh"}, default "tanh"
        Hidden activation of every region's network (``units``); a fit's finished files are named by it (tanh's
        without a tag).
    """

    boundaries: Sequence[float] = (0.3, 0.5, 0.65, 0.78, 0.87)
    blend_width: float = 0.04
    overlap: int = 1
    power: float = 2.0
    width: int = 64
    steps: int | Sequence[int] = 3000
    max_minutes: float | Sequence[float] | None = None
    floor_share: float = 0.01
    val_fraction: float = 0.1
    seed: int = 0
    derivative_weight: float = 0.0
    derivative_rows: str = "static"
    refine_minutes: float | Sequence[float] | None = None
    refine_steps: int | Sequence[int] = 3000
    activation: str = "tanh"


def train_universal(frame: pd.DataFrame, *, work_dir=None, logger_for=None, what: str = "",
                    workers: int | None = None, **settings: Any) -> dict:
    """Fit the universal networks of one cavitation rule, one per eccentricity region.

    Two phases per region: a fit to the values G (Levenberg-Marquardt from a random start), then, if
    ``derivative_weight`` > 0, the same fit continued on the values and their derivatives d/deps and d/dalpha
    (``derivative_rows``; a Sobolev fit): a value error of a few tenths of a per cent becomes a few per cent in
    stiffness and damping at high eccentricity (docs/universal.md), so the derivatives are fitted directly.

    Parameters
    ----------
    frame : DataFrame
        Rows of the dimensionless dataset (one cavitation rule).
    work_dir : path-like or None, default None
        Where each finished region is kept (``region<r>.npz``) and each running fit checkpoints: a rerun
        skips finished regions and resumes the running one.
    logger_for : callable or None, default None
        ``key -> Lightning logger`` (MLflow child runs from the workflow layer); called, when a phase trains,
        with the region ``r`` (first phase) or ``f"{r}_derivatives"`` (second phase), in the process that
        fits the region: picklable when ``workers`` > 1 (``workflow.tracking.ChildRunFactory.logger_for``).
    what : str, default ""
        Prefix of the progress lines.
    workers : int or None, default None
        Regions fitted side by side in worker processes (None: one per core; 1: one after the other in this
        process). Each fit uses one torch thread whatever ``workers`` is: BLAS sums in another order with
        another thread count, and Levenberg-Marquardt carries round-off into other weights within a few
        hundred steps, so one thread per fit is what makes the weights the same on any machine of the same
        arithmetic (another CPU's BLAS kernels may sum in another order).
    **settings
        The fit's settings: the fields of ``UniversalFitSettings`` (their defaults where not given; an unknown
        name is a TypeError).

    Returns
    -------
    dict
        ``regions`` (per region what ``train_region`` returns), ``boundaries``, ``blend_width``, ``power``,
        ``train_seconds`` (all regions, one core each), ``train_wall_s``, ``workers`` and the validation errors over all regions (``val_rel_median``,
        ``val_rel_p99``, ``val_rel_max``: each the worst region's).
    """
    return train_universals({"": dict(frame=frame, work_dir=work_dir, logger_for=logger_for, what=what,
                                      **dataclasses.asdict(UniversalFitSettings(**settings)))},
                            workers=workers)[""]


def train_universals(fits: dict, workers: int | None = None) -> dict:
    """Several ``train_universal`` fits (e.g. one per cavitation rule) with all their regions in one pool.

    ``fits`` maps a name to ``train_universal``'s keyword arguments (``frame`` included, ``workers`` not).
    Why one pool: a rule's regions differ fivefold in cost, so a pool per rule idles a worker while its
    largest region finishes; the regions of both rules, largest first, keep both busy (about a minute of
    ``universal_train`` here).  Each region is fitted alone on one thread, so the weights are those of
    separate calls.  Returns {name: what ``train_universal`` returns}; ``train_wall_s`` is the pool's.
    """
    jobs: list[dict] = []
    summaries = {}
    for name, kwargs in fits.items():
        job_list, summary = _region_jobs(**kwargs)
        summaries[name] = (len(jobs), len(job_list), summary)
        jobs += job_list
    n_workers = worker_count(workers, len(jobs))
    t0 = time.perf_counter()
    # most steps first (steps x rows: the cost of a fit), so the workers finish together
    done = side_by_side(_fit_region, jobs, n_workers,
                        cost=lambda job: (job["steps"] + job["refine_steps"]) * len(job["z"]))
    wall = time.perf_counter() - t0
    out = {}
    for name, (first, count, summary) in summaries.items():
        regions = done[first:first + count]
        out[name] = {"regions": regions, **summary,
                     "train_seconds": float(sum(r["train_seconds"] for r in regions)),
                     "train_wall_s": wall, "workers": n_workers,
                     **{k: float(max(r[k] for r in regions)) for k in ("val_rel_median", "val_rel_p99", "val_rel_max")}}
    return out


def _region_jobs(frame: pd.DataFrame, *, work_dir=None, logger_for=None, what: str = "",
                 **settings: Any) -> tuple[list[dict], dict]:
    """``train_universal``'s settings (``UniversalFitSettings``) checked and cut into one job per region
    (``_fit_region``), with the model's settings that the result carries."""
    st = UniversalFitSettings(**settings)
    boundaries, blend_width, overlap, power, width = st.boundaries, st.blend_width, st.overlap, st.power, st.width
    steps, max_minutes, floor_share, val_fraction, seed = (st.steps, st.max_minutes, st.floor_share,
                                                           st.val_fraction, st.seed)
    derivative_weight, derivative_rows, refine_minutes, refine_steps, activation = (
        st.derivative_weight, st.derivative_rows, st.refine_minutes, st.refine_steps, st.activation)
    bounds = [float(b) for b in boundaries]
    if any(b1 - b0 <= blend_width for b0, b1 in zip(bounds, bounds[1:])) or not all(0 < b < 1 for b in bounds):
        raise ValueError(f"boundaries {bounds} must increase inside (0, 1) by more than blend_width={blend_width!r}")
    n_regions = len(bounds) + 1
    steps_r = _per_region("steps", steps, n_regions, int)
    minutes = _per_region("max_minutes", max_minutes, n_regions, float)
    refine_steps_r = _per_region("refine_steps", refine_steps, n_regions, int)
    refine = _per_region("refine_minutes", refine_minutes, n_regions, float)
    if derivative_weight < 0.0:
        raise ValueError(f"derivative_weight must be >= 0, got {derivative_weight!r}")
    if activation not in HIDDEN_ACTIVATIONS:
        raise ValueError(f"activation={activation!r}: choose one of {HIDDEN_ACTIVATIONS}")
    z, y = features(frame, power)
    dy = derivative_targets(frame, power, derivative_rows) if derivative_weight > 0.0 else None
    eps = frame["eps"].to_numpy()
    work = Path(work_dir) if work_dir is not None else None
    jobs = []
    for r in range(n_regions):
        rows = region_rows(eps, bounds, blend_width, r, overlap)
        # the second phase's file is keyed by its own settings: another weight or budget is another fit
        # (and the activation's, when not tanh: tanh fits keep the names they had before there was a choice)
        tag = "" if activation == "tanh" else f"-{activation}"
        key = config_hash(float(derivative_weight), derivative_rows, refine[r], refine_steps_r[r],
                          *(() if activation == "tanh" else (activation,)))[:8]
        # what both phases share: the region's rows, the network, the loss floor and the validation split.
        # Not the logger: each phase is its own tracked run (its hyperparameters differ, and MLflow refuses
        # to change a logged parameter), created only when that phase actually trains
        jobs.append({"r": r, "z": z[rows], "y": y[rows], "dy": None if dy is None else dy[rows], "work": work,
                     "what": f"{what}region {r}", "logger_for": logger_for, "derivative_key": key, "tag": tag,
                     "steps": steps_r[r], "max_minutes": minutes[r], "refine_steps": refine_steps_r[r],
                     "refine_minutes": refine[r], "derivative_weight": float(derivative_weight),
                     "common": dict(width=width, floor_share=floor_share, val_fraction=val_fraction, seed=seed + r,
                                    activation=activation),
                     "parent_pid": os.getpid()})
    return jobs, {"boundaries": bounds, "blend_width": float(blend_width), "power": float(power),
                  "activation": activation}


def _fit_region(job: dict) -> dict:
    """Both phases of one region's fit (each kept in ``job["work"]`` when finished), here or in a worker
    process; each fit runs on one thread (``train_region``), so the weights do not depend on ``workers`` nor on
    the machine's cores."""
    if job["parent_pid"] != os.getpid():
        _exit_with_parent(job["parent_pid"])
    r, z, y, dy, work, what, logger_for = (job[k] for k in ("r", "z", "y", "dy", "work", "what", "logger_for"))
    res = _finished_or_fit(work, f"region{r}{job['tag']}", what, lambda ckpt: {
        **train_region(z, y, steps=job["steps"], max_minutes=job["max_minutes"], ckpt_dir=ckpt, what=what,
                       logger=logger_for(r) if logger_for is not None else None, **job["common"]),
        "n_rows": len(z)})
    if dy is None:
        return res
    first = res
    res = _finished_or_fit(work, f"region{r}_derivatives-{job['derivative_key']}", f"{what} (values and derivatives)",
                           lambda ckpt: {
        **train_region(z, y, steps=job["refine_steps"], max_minutes=job["refine_minutes"], ckpt_dir=ckpt,
                       what=f"{what} (values and derivatives)", derivatives=dy,
                       derivative_weight=job["derivative_weight"], init=first,
                       logger=logger_for(f"{r}_derivatives") if logger_for is not None else None, **job["common"]),
        "n_rows": len(z), "n_derivative_rows": int(np.isfinite(dy).all(-1).any(-1).sum())})
    res["train_seconds"] = float(first["train_seconds"] + res["train_seconds"])
    res["steps_values"], res["steps_derivatives"] = int(first["steps"]), int(res["steps"])
    res["steps"] = int(first["steps"] + res["steps"])
    res["val_rel_median_values_only"] = float(first["val_rel_median"])
    return res


def _per_region(name: str, value, n: int, kind) -> list:
    """``value`` for each of ``n`` regions: one value for all, or a sequence of ``n`` (None: no value)."""
    values = [value] * n if value is None or np.ndim(value) == 0 else list(value)
    if len(values) != n:
        raise ValueError(f"{name}={list(values)} needs one value or one per region ({n})")
    out = [None if v is None else kind(v) for v in values]
    if any(v is not None and not v > 0 for v in out):
        raise ValueError(f"{name}={list(values)}: every value must be > 0")
    return out


def _finished_or_fit(work, name: str, what: str, fit) -> dict:
    """A finished fit kept as ``<work>/<name>.npz``, or ``fit(checkpoint folder)``, then kept there (atomically)."""
    done = work / f"{name}.npz" if work is not None else None
    if done is not None and done.exists():
        with np.load(done, allow_pickle=False) as f:
            res: dict[str, Any] = json.loads(str(f["meta"]))
            res["layers"] = [(np.array(f[f"W{k}"]), np.array(f[f"b{k}"])) for k in range(int(f["n_layers"]))]
            res |= {k: np.array(f[k]) for k in ("in_mean", "in_std", "out_mean", "out_std")}
        print(f"  {what}: finished before, kept", flush=True)
    else:
        res = fit(work / f"{name}_ckpt" if work is not None else None)
        if done is not None:
            save_fit(res, done)
    deriv = f", derivatives {100 * res['val_deriv_rel_median']:.2f} %" if "val_deriv_rel_median" in res else ""
    print(f"  {what}: validation median {100 * res['val_rel_median']:.3f} %, p99 {100 * res['val_rel_p99']:.2f} %"
          f"{deriv} ({res['steps']} steps, {res['train_seconds']:.0f} s)", flush=True)
    return res


def save_fit(res: dict, path) -> None:
    """Keep one region's finished fit (what ``train_region`` returns) as an ``.npz``, written atomically."""
    arrays: dict[str, Any] = {f"W{k}": W for k, (W, _) in enumerate(res["layers"])}
    arrays |= {f"b{k}": b for k, (_, b) in enumerate(res["layers"])}
    arrays |= {k: res[k] for k in ("in_mean", "in_std", "out_mean", "out_std")}
    arrays |= {"n_layers": np.array(len(res["layers"])), "meta": np.array(json.dumps(
        {k: v for k, v in res.items() if isinstance(v, (int, float))}))}
    with io.atomic_path(Path(path), suffix=".npz") as tmp:
        np.savez(tmp, **arrays)


def write_weights(fit: dict, cavitation: str, eps_max: float, ld_range: tuple[float, float], info: dict,
                  directory=WEIGHTS_DIR) -> Path:
    """Write one rule's networks as ``<directory>/<cavitation>.npz`` and its SHA-256 into ``SHA256SUMS``.

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
    arrays: dict[str, Any] = {"n_regions": np.array(len(fit["regions"])), "activation": np.array(fit.get("activation", "tanh")),
                              "boundaries": np.asarray(fit["boundaries"], dtype=np.float64),
                              "blend_width": np.array(float(fit["blend_width"])), "power": np.array(fit["power"]),
                              "eps_max": np.array(float(eps_max)), "ld_min": np.array(float(ld_range[0])),
                              "ld_max": np.array(float(ld_range[1])), "info": np.array(json.dumps(info, sort_keys=True))}
    for r, reg in enumerate(fit["regions"]):
        arrays[f"r{r}_n_layers"] = np.array(len(reg["layers"]))
        for k in ("in_mean", "in_std", "out_mean", "out_std"):
            arrays[f"r{r}_{k}"] = np.asarray(reg[k], dtype=np.float64)
        for i, (W, b) in enumerate(reg["layers"]):
            arrays[f"r{r}_W{i}"] = np.asarray(W, dtype=np.float64)
            arrays[f"r{r}_b{i}"] = np.asarray(b, dtype=np.float64)
    path = d / f"{cavitation}.npz"
    with io.atomic_path(path, suffix=".npz") as tmp:
        np.savez_compressed(tmp, **arrays)
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    sums = d / "SHA256SUMS"
    lines = [ln for ln in (sums.read_text().splitlines() if sums.exists() else []) if not ln.endswith(f"  {path.name}")]
    io.write_text(sums, "\n".join(sorted(lines + [f"{digest}  {path.name}"])) + "\n")
    return path
