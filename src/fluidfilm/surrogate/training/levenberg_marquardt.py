"""Levenberg-Marquardt training of a one-hidden-layer tanh network (the paper's tool's default optimiser).

The paper's networks (4 inputs, 50 tanh neurons, 2 linear outputs: 352
weights) were trained by MATLAB's ``trainlm``.  This module does the same,
full batch and in float64:

- ``mlp_forward`` / ``mlp_jacobian``: the network and the analytical
  Jacobian of its outputs with respect to all weights, vectorised over
  samples (row 2n + k is output k of sample n);
- ``normal_equations``: J^T J (352 x 352), J^T e and the sum of squared
  errors accumulated over chunks of samples from the Jacobian's structure,
  without forming it, so memory stays bounded (a chunk of 8192 samples
  holds an 8192 x 250 float64 block, 16 MB) while every product is one
  BLAS call;
- ``levenberg_marquardt``: the generic damped Gauss-Newton loop with
  MATLAB's mu schedule (mu 1e-3, times 0.1 on success, times 10 on failure,
  stop at mu > 1e10), taking any ``normal_equations``/``sse`` callables, so
  tests run it on problems with a known least-squares solution;
- ``init_nguyen_widrow``: MATLAB's default initialisation of a tansig layer.

Parallel accumulation: ``normal_equations`` and ``mlp_sse`` take ``workers``
threads (numpy and BLAS release the GIL).  The rows are cut into the same
fixed blocks whatever the number of workers, each block's partial sums are
computed alone, and the partials are added in block order, exactly as the
one-thread loop adds them: the result is bitwise the same for any number
of workers (with one BLAS thread per call, the protocol's setting).

Checkpoints: ``levenberg_marquardt`` hands its state (weights, mu, epoch,
wall time, history) to ``on_checkpoint`` after every epoch and resumes
from such a state (``start``); the epoch is a pure function of the weights
and mu, so a resumed run takes the same steps as an uninterrupted one.

Weight vector layout: W1 (50, 4) row-major, b1 (50,), W2 (2, 50) row-major, b2 (2,).
"""
from __future__ import annotations

import math
import os
import time
from collections import deque
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import cho_factor, cho_solve


def n_weights(n_in: int, n_hidden: int, n_out: int) -> int:
    return n_hidden * n_in + n_hidden + n_out * n_hidden + n_out


def unpack(theta: np.ndarray, n_in: int, n_hidden: int, n_out: int):
    """Weight vector -> (W1 (h, in), b1 (h,), W2 (out, h), b2 (out,)) views."""
    if theta.shape != (n_weights(n_in, n_hidden, n_out),):
        raise ValueError(f"weight vector of shape {theta.shape} does not fit a {n_in}-{n_hidden}-{n_out} network "
                         f"({n_weights(n_in, n_hidden, n_out)} weights)")
    a = n_hidden * n_in
    b = a + n_hidden
    c = b + n_out * n_hidden
    return (theta[:a].reshape(n_hidden, n_in), theta[a:b], theta[b:c].reshape(n_out, n_hidden), theta[c:])


def pack(W1, b1, W2, b2) -> np.ndarray:
    return np.concatenate([np.ravel(W1), np.ravel(b1), np.ravel(W2), np.ravel(b2)]).astype(np.float64)


def mlp_forward(theta: np.ndarray, Z: np.ndarray, n_hidden: int, n_out: int = 2):
    """Outputs (n, out) and hidden activations (n, h) of the tanh network."""
    W1, b1, W2, b2 = unpack(theta, Z.shape[1], n_hidden, n_out)
    H = np.tanh(Z @ W1.T + b1)
    return H @ W2.T + b2, H


def mlp_jacobian(theta: np.ndarray, Z: np.ndarray, H: np.ndarray, n_out: int = 2, out=None) -> np.ndarray:
    """d(outputs)/d(weights), shape (n * out, P); row n*out + k is output k of sample n.

    y_k = sum_j W2[k, j] h_j + b2[k],  h_j = tanh(W1[j] . z + b1[j]):
    dy_k/dW1[j, i] = W2[k, j] (1 - h_j^2) z_i,  dy_k/db1[j] = W2[k, j] (1 - h_j^2),
    dy_k/dW2[k, j] = h_j,  dy_k/db2[k] = 1, zero for the other output's W2, b2.
    """
    n, n_in = Z.shape
    n_hidden = H.shape[1]
    _, _, W2, _ = unpack(theta, n_in, n_hidden, n_out)
    P = theta.shape[0]
    J = np.zeros((n, n_out, P)) if out is None else out[: n * n_out].reshape(n, n_out, P)
    if out is not None:
        J.fill(0.0)
    D = 1.0 - H * H
    a = n_hidden * n_in
    b = a + n_hidden
    for k in range(n_out):
        G = D * W2[k]  # (n, h): dy_k / d(pre-activation)
        J[:, k, :a] = (G[:, :, None] * Z[:, None, :]).reshape(n, a)
        J[:, k, a:b] = G
        c0 = b + k * n_hidden
        J[:, k, c0:c0 + n_hidden] = H
        J[:, k, b + n_out * n_hidden + k] = 1.0
    return J.reshape(n * n_out, P)


def _shared_index(n_in: int, n_hidden: int) -> np.ndarray:
    """Weight-vector positions of the shared block laid out as (neuron j, input i or bias i = n_in)."""
    j, i = np.meshgrid(np.arange(n_hidden), np.arange(n_in + 1), indexing="ij")
    return np.where(i < n_in, j * n_in + i, n_hidden * n_in + j).ravel()


def default_workers() -> int:
    """Cores this process may run on (``os.sched_getaffinity``; ``os.cpu_count`` where that is missing)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        return os.cpu_count() or 1


def resolve_workers(workers: int | None) -> int:
    """``workers`` as a thread count: None or 0 means every core (``default_workers``)."""
    if workers is None or int(workers) == 0:
        return default_workers()
    if int(workers) < 0:
        raise ValueError(f"workers must be a positive number of threads, 0 or None (every core), got {workers!r}")
    return int(workers)


def _blocks_in_order(fn: Callable, starts: range, workers: int):
    """fn(start) for every block start, in block order; ``workers`` threads compute them.  The
    caller adds the partials in the order they come: the same order as a one-thread loop."""
    if workers <= 1 or len(starts) <= 1:
        yield from map(fn, starts)
        return
    with ThreadPoolExecutor(max_workers=min(workers, len(starts))) as pool:
        # at most 2 x workers blocks in flight, so a large table never holds all partials at once
        pending: deque = deque()
        it = iter(starts)
        for s0 in it:
            pending.append(pool.submit(fn, s0))
            if len(pending) >= 2 * workers:
                break
        while pending:
            yield pending.popleft().result()
            nxt = next(it, None)
            if nxt is not None:
                pending.append(pool.submit(fn, nxt))


def normal_equations(theta: np.ndarray, Z: np.ndarray, Y: np.ndarray, n_hidden: int, chunk: int = 8192,
                     workers: int = 1):
    """(J^T J, J^T e, sum e^2) over all samples, e = prediction - target, accumulated chunk by chunk.

    Uses the Jacobian's structure instead of forming J.  The hidden layer's
    weights (W1, b1: "shared") enter every output, each output's own weights
    (W2[k], b2[k]) only that output.  With d = 1 - h^2, zt = [z, 1] and
    E = [h, 1], the Jacobian row of output k and sample n on shared weight
    (j, i) is W2[k, j] d_j zt_i, so with U = d (x) zt (one row per sample,
    not per sample and output) and M = W2^T W2:

    - shared block   sum_k G_k^T G_k = (U^T U) * (M (x) 1): an element-wise
      product after U^T U;
    - shared x own   G_k^T E = W2[k, j] (U^T E) row by row;
    - own x own      E^T E per output, zero between outputs;
    - J^T e          U^T (d r) with r = e W2, and E^T e.

    U^T U, U^T E and E^T E come from one symmetric rank-k update (BLAS syrk)
    on [U, E]: one row per sample (not per sample and output) and 301
    columns.  That is about half the time of a syrk on the outputs'
    Jacobian rows stacked (docs/dataset_and_surrogates.md) and a
    small part of J^T J from the full Jacobian (``normal_equations_dense``,
    which the tests compare to 1e-15).

    ``workers`` threads compute the chunks' partial sums; they are added in
    chunk order, so the result does not depend on ``workers``.
    """
    n_tot, n_in = Z.shape
    n_out = Y.shape[1]
    W1, b1, W2, b2 = unpack(theta, n_in, n_hidden, n_out)
    m = n_in + 1
    ns = n_hidden * m
    nv = ns + n_hidden + 1
    chunk = int(chunk)
    if chunk < 1:
        raise ValueError(f"chunk must be a positive number of samples, got {chunk!r}")

    def block(s):
        z = Z[s:s + chunk]
        n = len(z)
        # [U, E]^T laid out (column; sample) in C order: its transpose is the Fortran-ordered matrix
        # syrk reads without a copy
        vt = np.empty((nv, n))
        # tanh into a contiguous array, then copied into place: written straight into the transposed view
        # it takes NumPy's strided (unvectorised) loop, 20 times slower (7 of 23 ms per block, one core)
        H = np.tanh(z @ W1.T + b1)
        vt[ns:ns + n_hidden] = H.T
        vt[-1] = 1.0
        E = vt[ns:].T
        e = H @ W2.T + b2 - Y[s:s + chunk]  # (n, out)
        D = 1.0 - H * H
        zt = np.empty((n, m))
        zt[:, :-1] = z
        zt[:, -1] = 1.0
        np.multiply(D.T[:, None, :], zt.T[None, :, :], out=vt[:ns].reshape(n_hidden, m, n))
        # NumPy's matmul of a matrix with its own transpose is BLAS syrk, and NumPy lets go of the GIL
        # around it (SciPy's f2py ``dsyrk`` holds it: with it the ``workers`` threads took turns)
        return (vt @ vt.T, (D * (e @ W2)).T @ zt, E.T @ e,
                float((e * e).sum()))

    V = np.zeros((nv, nv))  # [U, E]^T [U, E]: U^T U, U^T E and E^T E in one product
    Je_s = np.zeros((n_hidden, m))
    Je_o = np.zeros((n_hidden + 1, n_out))
    sse = 0.0
    for v_b, js_b, jo_b, sse_b in _blocks_in_order(block, range(0, n_tot, chunk), resolve_workers(workers)):
        V += v_b
        Je_s += js_b
        Je_o += jo_b
        sse += sse_b
    V = np.triu(V) + np.triu(V, 1).T  # the product is whole already; this keeps V exactly symmetric
    return _assemble(V, Je_s, Je_o, theta, n_in, n_hidden, n_out) + (sse,)


def _assemble(V: np.ndarray, Je_s: np.ndarray, Je_o: np.ndarray, theta: np.ndarray, n_in: int, n_hidden: int,
              n_out: int) -> tuple[np.ndarray, np.ndarray]:
    """J^T J and J^T e from [U, E]^T [U, E] (``V``, whole), U^T (d r) (``Je_s``) and E^T e (``Je_o``)."""
    _, _, W2, _ = unpack(theta, n_in, n_hidden, n_out)
    P = theta.shape[0]
    m = n_in + 1
    ns = n_hidden * m
    sidx = _shared_index(n_in, n_hidden)
    own0 = n_hidden * n_in + n_hidden
    A, UE, OO = V[:ns, :ns], V[:ns, ns:], V[ns:, ns:]
    wj = np.repeat(np.arange(n_hidden), m)  # neuron of each shared weight (j, i)
    JtJ = np.zeros((P, P))
    Jte = np.zeros(P)
    JtJ[np.ix_(sidx, sidx)] = A * (W2.T @ W2)[np.ix_(wj, wj)]
    Jte[sidx] = Je_s.ravel()
    for k in range(n_out):
        ok = np.r_[own0 + k * n_hidden: own0 + (k + 1) * n_hidden, own0 + n_out * n_hidden + k]
        SO = UE * W2[k, wj][:, None]
        JtJ[np.ix_(ok, ok)] = OO
        JtJ[np.ix_(sidx, ok)] = SO
        JtJ[np.ix_(ok, sidx)] = SO.T
        Jte[ok] = Je_o[:, k]
    return JtJ, Jte


class TorchNormalEquations:
    """``normal_equations`` and ``mlp_sse`` in torch float64 on one device (a CUDA GPU, or "cpu").

    The rows are copied to the device once; each call returns NumPy arrays, so ``levenberg_marquardt``
    (its 352 x 352 Cholesky solves stay in NumPy) takes ``normal_equations`` and ``sse`` unchanged.  The
    same structure as ``normal_equations`` ([U, E]^T [U, E] in one product per block of ``chunk`` rows,
    here a general matrix product: torch has no symmetric rank-k update), summed in another order: the
    results equal the NumPy path's to round-off, not bit for bit, so a run on a device and one on the
    CPU take the same steps while no comparison of errors falls within round-off of a tie (the tests
    compare both on a small problem).  Why: at the paper's full scale (3.2 M training rows) an epoch takes
    seconds on this project's two cores and the validation rule needs thousands of them; a GPU does an epoch
    in well under a second (docs/dataset_and_surrogates.md has the timings).

    Parameters
    ----------
    Z, Y : array_like
        Inputs (n, in) and targets (n, out).
    n_hidden : int
        Hidden neurons.
    device : str
        A torch device: "cuda", "cuda:1", "cpu", ...  A CUDA device torch cannot see is refused by name.
    chunk : int, default 262144
        Rows per block (a block holds chunk x (n_hidden (in + 2) + 1) float64: 630 MB at the default).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> Z, Y = rng.uniform(-1, 1, (500, 4)), rng.uniform(-1, 1, (500, 2))
    >>> th = init_nguyen_widrow(4, 8, 2, rng)
    >>> a = normal_equations(th, Z, Y, 8)
    >>> b = TorchNormalEquations(Z, Y, 8, "cpu").normal_equations(th)
    >>> bool(np.allclose(a[0], b[0], rtol=1e-12, atol=1e-12 * abs(a[0]).max()))
    True
    """

    def __init__(self, Z, Y, n_hidden: int, device: str, chunk: int = 262144):
        import torch

        try:
            dev = torch.device(device)
        except (RuntimeError, TypeError) as err:
            raise ValueError(f"device={device!r} is not a torch device (e.g. 'cuda', 'cuda:0', 'cpu'): {err}") from None
        if dev.type == "cuda" and not torch.cuda.is_available():
            raise ValueError(f"device={device!r}: torch sees no CUDA device here (torch {torch.__version__}); "
                             f"use device null for the NumPy path")
        if dev.type == "cuda" and dev.index is not None and dev.index >= torch.cuda.device_count():
            raise ValueError(f"device={device!r}: torch sees {torch.cuda.device_count()} CUDA device(s)")
        if int(chunk) < 1:
            raise ValueError(f"chunk must be a positive number of rows, got {chunk!r}")
        self._torch = torch
        self.device = dev
        self.chunk = int(chunk)
        self.n_hidden = int(n_hidden)
        self.Z = torch.as_tensor(np.ascontiguousarray(Z, dtype=np.float64), device=dev)
        self.Y = torch.as_tensor(np.ascontiguousarray(Y, dtype=np.float64), device=dev)
        self.n_in, self.n_out = self.Z.shape[1], self.Y.shape[1]

    def _weights(self, theta):
        W1, b1, W2, b2 = unpack(np.asarray(theta, dtype=np.float64), self.n_in, self.n_hidden, self.n_out)
        return [self._torch.as_tensor(np.ascontiguousarray(w), device=self.device) for w in (W1, b1, W2, b2)]

    def normal_equations(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        """(J^T J, J^T e, sum e^2), as ``normal_equations``."""
        torch = self._torch
        W1, b1, W2, b2 = self._weights(theta)
        h, m = self.n_hidden, self.n_in + 1
        nv = h * m + h + 1
        V = torch.zeros((nv, nv), dtype=torch.float64, device=self.device)
        Je_s = torch.zeros((h, m), dtype=torch.float64, device=self.device)
        Je_o = torch.zeros((h + 1, self.n_out), dtype=torch.float64, device=self.device)
        sse = torch.zeros((), dtype=torch.float64, device=self.device)
        for s0 in range(0, self.Z.shape[0], self.chunk):
            z = self.Z[s0:s0 + self.chunk]
            n = z.shape[0]
            ones = torch.ones((n, 1), dtype=torch.float64, device=self.device)
            H = torch.tanh(z @ W1.T + b1)
            e = H @ W2.T + b2 - self.Y[s0:s0 + self.chunk]
            D = 1.0 - H * H
            zt = torch.cat([z, ones], dim=1)
            # columns (neuron j, input i) in the order of ``_shared_index``, then [h, 1]
            UE = torch.cat([(D[:, :, None] * zt[:, None, :]).reshape(n, h * m), H, ones], dim=1)
            V += UE.T @ UE
            Je_s += (D * (e @ W2)).T @ zt
            Je_o += UE[:, h * m:].T @ e
            sse += (e * e).sum()
        JtJ, Jte = _assemble(V.cpu().numpy(), Je_s.cpu().numpy(), Je_o.cpu().numpy(),
                             np.asarray(theta, dtype=np.float64), self.n_in, h, self.n_out)
        return JtJ, Jte, float(sse)

    def sse(self, theta: np.ndarray) -> float:
        """Sum of squared errors, as ``mlp_sse``."""
        W1, b1, W2, b2 = self._weights(theta)
        total = self._torch.zeros((), dtype=self._torch.float64, device=self.device)
        for s0 in range(0, self.Z.shape[0], self.chunk):
            e = self._torch.tanh(self.Z[s0:s0 + self.chunk] @ W1.T + b1) @ W2.T + b2 - self.Y[s0:s0 + self.chunk]
            total += (e * e).sum()
        return float(total)


def normal_equations_dense(theta: np.ndarray, Z: np.ndarray, Y: np.ndarray, n_hidden: int, chunk: int = 8192):
    """The same from the full Jacobian (``mlp_jacobian``): the plain, slower way, kept as a check."""
    P = theta.shape[0]
    n_out = Y.shape[1]
    JtJ = np.zeros((P, P))
    Jte = np.zeros(P)
    sse = 0.0
    buf = np.empty((min(chunk, len(Z)) * n_out, P))
    for s in range(0, len(Z), chunk):
        z, y = Z[s:s + chunk], Y[s:s + chunk]
        pred, H = mlp_forward(theta, z, n_hidden, n_out)
        e = (pred - y).ravel()
        J = mlp_jacobian(theta, z, H, n_out, out=buf)
        JtJ += J.T @ J
        Jte += J.T @ e
        sse += float(e @ e)
    return JtJ, Jte, sse


def mlp_sse(theta: np.ndarray, Z: np.ndarray, Y: np.ndarray, n_hidden: int, chunk: int = 8192,
            workers: int = 1) -> float:
    """Sum of squared errors of the network over (Z, Y), chunk by chunk; ``workers`` threads, the chunks'
    sums added in chunk order (the result does not depend on ``workers``).  Chunks of 8192 rows, as the
    normal equations': a 40 k-sample fit's sums then spread over both workers (one chunk would idle one)."""
    def block(s):
        pred, _ = mlp_forward(theta, Z[s:s + chunk], n_hidden, Y.shape[1])
        return float(((pred - Y[s:s + chunk]) ** 2).sum())

    sse = 0.0
    for part in _blocks_in_order(block, range(0, len(Z), int(chunk)), resolve_workers(workers)):
        sse += part
    return sse


def init_nguyen_widrow(n_in: int, n_hidden: int, n_out: int, rng: np.random.Generator) -> np.ndarray:
    """Nguyen-Widrow initial weights for inputs in [-1, 1] (MATLAB's ``initnw`` for a tansig layer).

    Hidden neurons get weight vectors of norm 0.7 h^(1/in) in random directions
    and biases spread over [-norm, norm], so their active regions tile the
    input box; the linear output layer starts small and random.
    """
    beta = 0.7 * n_hidden ** (1.0 / n_in)
    W1 = rng.uniform(-1.0, 1.0, (n_hidden, n_in))
    W1 *= beta / np.linalg.norm(W1, axis=1, keepdims=True)
    b1 = beta * np.linspace(-1.0, 1.0, n_hidden) * np.sign(W1[:, 0])
    W2 = rng.uniform(-1.0, 1.0, (n_out, n_hidden)) / math.sqrt(n_hidden)
    b2 = rng.uniform(-1.0, 1.0, n_out) * 0.1
    return pack(W1, b1, W2, b2)


@dataclass
class LMSettings:
    """MATLAB ``trainlm`` defaults."""
    mu: float = 1e-3
    mu_dec: float = 0.1
    mu_inc: float = 10.0
    mu_max: float = 1e10
    min_grad: float = 1e-7
    max_epochs: int = 1000
    max_time_s: float = math.inf

    def __post_init__(self):
        if not (self.mu > 0 and 0 < self.mu_dec < 1 < self.mu_inc and self.mu_max > self.mu):
            raise ValueError(f"need mu > 0, 0 < mu_dec < 1 < mu_inc and mu_max > mu, got {self}")
        if int(self.max_epochs) < 1:
            raise ValueError(f"max_epochs must be >= 1, got {self.max_epochs!r}")


@dataclass
class LMResult:
    theta: np.ndarray
    epochs: int
    stop_reason: str
    sse: float
    wall_s: float
    history: list = field(default_factory=list)


#: stop reasons after which a resumed run has nothing left to do (the caps can be raised and continued)
FINAL_REASONS = ("validation", "min_grad", "mu_max", "non_finite")


def levenberg_marquardt(theta0: np.ndarray, normal_eq: Callable, sse_fn: Callable, n_residuals: int,
                        settings: LMSettings | None = None,
                        on_epoch: Callable[[int, np.ndarray, float], str | None] | None = None,
                        start: dict | None = None, on_checkpoint: Callable[[dict], None] | None = None) -> LMResult:
    """Minimise sum e(theta)^2 by Levenberg-Marquardt (MATLAB ``trainlm``'s schedule).

    ``normal_eq(theta) -> (J^T J, J^T e, sse)``, ``sse_fn(theta) -> sse``.
    Each epoch solves (J^T J + mu I) d = -J^T e, raising mu tenfold until the
    step lowers the error, then lowers mu tenfold.  Stops at ``max_epochs``,
    when the gradient of the mean squared error falls below ``min_grad``,
    when mu exceeds ``mu_max``, after ``max_time_s``, or when ``on_epoch``
    (called after every accepted epoch with the epoch number, the weights
    and the wall time so far) returns a reason.

    ``on_checkpoint(state)``, where given, is called after every accepted
    epoch (after ``on_epoch``) and when the run stops, with the state
    {"theta", "mu", "epoch", "wall_s", "history", "reason"} (reason None
    while it runs).  ``start``, such a state, resumes a run: epochs, wall
    time and history continue from it, and since an epoch depends on the
    weights and mu alone the resumed run takes the steps the uninterrupted
    one would have taken.
    """
    s = settings or LMSettings()
    if start is not None:
        theta = np.array(start["theta"], dtype=np.float64)
        mu = float(start["mu"])
        first = int(start["epoch"]) + 1
        history = list(start.get("history", []))
        t0 = time.perf_counter() - float(start.get("wall_s", 0.0))
        sse = float(history[-1]["sse"]) if history else float("nan")
    else:
        theta = np.array(theta0, dtype=np.float64)
        mu = s.mu
        first = 1
        history = []
        t0 = time.perf_counter()
        sse = float("nan")
    P = theta.shape[0]
    eye = np.eye(P)
    reason = "max_epochs"
    epoch = first - 1

    def state(r):
        # a resumed run that takes no further epoch (a cap already reached) adds no time
        wall = time.perf_counter() - t0 if start is None or epoch >= first else float(start.get("wall_s", 0.0))
        return {"theta": theta, "mu": mu, "epoch": epoch, "wall_s": wall, "history": history, "reason": r}

    for epoch in range(first, int(s.max_epochs) + 1):
        if time.perf_counter() - t0 > s.max_time_s:
            reason, epoch = "max_time", epoch - 1
            break
        JtJ, Jte, sse = normal_eq(theta)
        grad = 2.0 * Jte / n_residuals  # gradient of the mean squared error
        if float(np.linalg.norm(grad)) < s.min_grad:
            reason, epoch = "min_grad", epoch - 1
            break
        accepted = False
        while mu <= s.mu_max:
            try:
                # Cholesky: J^T J + mu I is symmetric positive definite for mu > 0
                step = -cho_solve(cho_factor(JtJ + mu * eye, lower=True, check_finite=False), Jte,
                                  check_finite=False)
            except np.linalg.LinAlgError:
                mu *= s.mu_inc
                continue
            trial = theta + step
            sse_trial = sse_fn(trial)
            if sse_trial < sse:
                theta, sse = trial, sse_trial
                mu = max(mu * s.mu_dec, 1e-20)
                accepted = True
                break
            mu *= s.mu_inc
        if not accepted:
            reason, epoch = "mu_max", epoch - 1
            break
        wall = time.perf_counter() - t0
        history.append({"epoch": epoch, "sse": sse, "mu": mu, "wall_s": wall})
        r = on_epoch(epoch, theta, wall) if on_epoch is not None else None
        if r:
            reason = r
            break
        if on_checkpoint is not None:
            on_checkpoint(state(None))
    final = state(reason)  # one wall time for the result and the checkpoint (a resumed finished run reports it)
    if on_checkpoint is not None:
        on_checkpoint(final)
    return LMResult(theta, epoch, reason, sse, final["wall_s"], history)
