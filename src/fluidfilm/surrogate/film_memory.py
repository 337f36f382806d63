"""A force surrogate of the mass-conserving (JFO) film with memory: the journal's recent path as input.

Under the Jakobsson-Floberg-Olsson conditions the film force is not a function of the journal's position and
velocity alone: the liquid left in the cavity is carried round at half the surface speed and sets where the
film re-forms, so the force depends on the gap's history over about one fluid transit (two shaft periods).
The gap is fixed by the journal's path, so the path is the film's memory: this surrogate's inputs are the
position and velocity now and the positions at ``n_lags`` earlier times ``k * lag_dt``, k = 1 .. n_lags
(``memory_inputs``).  Trained on trajectories of ``reynolds.elrod_adams.ElrodAdamsSolver`` (``studies.
jfo_surrogate``), it is a ``TransientFilmModel``: ``simulate`` integrates it in ``rotor.film_memory`` with
the path history as the carried state, exactly where the reference carries its film content.

The history (``steady_field``: the journal at rest at x0 for all earlier times, the reference's steady film)
holds the path sampled at multiples of ``lag_dt``; each committed step adds the samples it crosses
(linear in the step) and the lagged positions at any time are linear between the samples.  The training
features are computed by the same rule from the recorded reference paths (``memory_inputs``), so the network
sees the inputs it was trained on.

One network evaluation (``surrogate.inference``'s compiled MLP) per RK4 stage, no film solve: a commit is a
few assignments.  ``forces``/``force_kernel`` give the force with the history at rest at the current
position (equilibria, K and C), as the reference's with its content at its steady value.

Domain: the eccentricities of the training paths; a stage above ``validity.eps_max`` is counted and the
run's status says so (``rotor.integrate``'s "outside-domain").  The bearing's speed is the network's:
``simulate`` refuses a speed schedule.
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from numba import njit

from fluidfilm import io
from fluidfilm.core.bearing import JournalBearing, bearing_from_dict
from fluidfilm.core.force_model import ValidityDomain
from fluidfilm.core.states import as_state_pairs
from fluidfilm.surrogate.activations import ACTIVATIONS
from fluidfilm.surrogate.kernels.generic import _mlp, pack_network

#: the saved model's file names
WEIGHTS_FILE = "film_memory.npz"
META_FILE = "model.json"
KIND = "film-memory"


class MemoryParams(NamedTuple):
    """What the compiled kernels read (``MemorySurrogate.params``)."""

    weights: np.ndarray     # flat network weights (``inference.pack_network``)
    table: np.ndarray       # (n_layers, 4) layer table
    n_layers: int
    act: int                # ``inference.ACTIVATIONS`` code
    in_mean: np.ndarray     # (n_inputs,) standardisation of the inputs
    in_std: np.ndarray
    out_mean: np.ndarray    # (2,) of the targets F / force_scale
    out_std: np.ndarray
    force_scale: float      # N
    gain_power: float       # the targets are F (1 - eps^2)^gain_power / force_scale (``film_gain``)
    inv_c: float            # 1 / clearance
    inv_cw: float           # 1 / (clearance omega)
    lag_dt: float           # s
    n_lags: int
    eps_max: float          # the training paths' largest eccentricity
    k_omega: float          # the film's speed factor (``rotor.film_memory`` passes it back; the network has one speed)
    tol: float              # not read: no film solve (``rotor.film_memory``'s interface)
    max_sweeps: int         # not read (ditto)
    counter: np.ndarray     # (1,) int64: stages outside the domain since the last reset
    z: np.ndarray           # scratch: inputs
    buf_a: np.ndarray       # scratch: layer buffers
    buf_b: np.ndarray


@njit(cache=True)
def _lagged(hist, k, frac):
    """The journal's position k lag steps before the history's clock, linear between its samples; ``frac``:
    the clock's place between the latest sample and the next, (clock - t_last) / lag_dt."""
    # sample j (j = 0 the latest, at time hist[0, 1]) lies in row j + 1
    a = hist[k, 0] * frac + hist[k + 1, 0] * (1.0 - frac)
    b = hist[k, 1] * frac + hist[k + 1, 1] * (1.0 - frac)
    return a, b


@njit(cache=True)
def _network_force(ep, x1, x2, v1, v2):
    """(F1, F2) of the network on the raw inputs in ``ep.z`` from index 4 on; writes the first four."""
    z = ep.z
    z[0] = x1 * ep.inv_c
    z[1] = x2 * ep.inv_c
    z[2] = v1 * ep.inv_cw
    z[3] = v2 * ep.inv_cw
    for i in range(4 + 2 * ep.n_lags):
        z[i] = (z[i] - ep.in_mean[i]) / ep.in_std[i]
    out = _mlp(ep.weights, ep.table, ep.n_layers, ep.act, z, ep.buf_a, ep.buf_b)
    e2 = (x1 * x1 + x2 * x2) * ep.inv_c * ep.inv_c
    s = ep.force_scale / max(1.0 - e2, 1e-6) ** ep.gain_power
    return (out[0] * ep.out_std[0] + ep.out_mean[0]) * s, (out[1] * ep.out_std[1] + ep.out_mean[1]) * s


@njit(cache=True)
def _count_domain(ep, x1, x2):
    if (x1 * x1 + x2 * x2) * ep.inv_c * ep.inv_c > ep.eps_max * ep.eps_max:
        ep.counter[0] += 1


@njit(cache=True)
def memory_force(ep, x1, x2, v1, v2):
    """The one-state force kernel: the history at rest at x (equilibria, K and C)."""
    _count_domain(ep, x1, x2)
    for i in range(4, 4 + 2 * ep.n_lags):
        ep.z[i] = 0.0
    return _network_force(ep, x1, x2, v1, v2)


@njit(cache=True)
def memory_stage(ep, k_omega, x1, x2, v1, v2, dt, tol, th_n, content, p, th):
    """One RK4 stage (``rotor.film_memory``'s stage interface): the network with the committed history
    ``th_n``; returns (F1, F2, 0 sweeps, 0 status)."""
    _count_domain(ep, x1, x2)
    frac = (th_n[0, 0] - th_n[0, 1]) / ep.lag_dt  # once per stage, not per lag
    for k in range(1, ep.n_lags + 1):
        a, b = _lagged(th_n, k, frac)
        ep.z[2 + 2 * k] = (a - x1) * ep.inv_c
        ep.z[3 + 2 * k] = (b - x2) * ep.inv_c
    f1, f2 = _network_force(ep, x1, x2, v1, v2)
    return f1, f2, 0, 0


@njit(cache=True)
def memory_commit(ep, k_omega, x1_old, x2_old, x1, x2, dt, th_n, content, p, th):
    """The committed step: ``th`` = ``th_n`` advanced by dt, with the path's samples at the multiples of
    ``lag_dt`` that the step crosses (linear in the step).  Returns (0 sweeps, 0 status)."""
    th[:, :] = th_n
    clock = th_n[0, 0]
    t_last = th_n[0, 1]
    new_clock = clock + dt
    n_rows = th.shape[0]
    # 1e-9 of a lag step: a sample due at the step's end is taken despite the clock's rounding
    while t_last + ep.lag_dt <= new_clock + 1e-9 * ep.lag_dt:
        ts = t_last + ep.lag_dt
        frac = min(max((ts - clock) / dt, 0.0), 1.0)
        for j in range(n_rows - 1, 1, -1):
            th[j, 0] = th[j - 1, 0]
            th[j, 1] = th[j - 1, 1]
        th[1, 0] = x1_old + frac * (x1 - x1_old)
        th[1, 1] = x2_old + frac * (x2 - x2_old)
        t_last = ts
    th[0, 0] = new_clock
    th[0, 1] = t_last
    return 0, 0


def film_gain(x: np.ndarray, clearance: float, force_scale: float, gain_power: float) -> np.ndarray:
    """force_scale / (1 - eps^2)^gain_power at positions x (n, 2) [m]: what the network's output is scaled by."""
    e2 = (np.asarray(x, dtype=float) ** 2).sum(axis=-1) / clearance**2
    return force_scale / np.maximum(1.0 - e2, 1e-6) ** gain_power


@njit(cache=True)
def memory_flows(ep, omega, e1, e2, p, th):
    """No film field, hence no side flow, friction or committed force: NaN (``rotor.film_memory``'s records)."""
    return np.nan, np.nan, np.nan, np.nan


def memory_inputs(t: np.ndarray, x: np.ndarray, v: np.ndarray, clearance: float, omega: float, lag_dt: float,
                  n_lags: int) -> np.ndarray:
    """The network's raw inputs along a recorded path, by the kernels' rule (module doc).

    ``t`` (n,) from 0, ``x``, ``v`` (n, 2): the path, with the journal at rest at ``x[0]`` before t = 0; the
    samples at multiples of ``lag_dt`` are interpolated linearly in ``t``.  Returns (n, 4 + 2 n_lags):
    x/c, v/(c omega), then (x(t_k) - x)/c for k = 1 .. n_lags.

    Examples
    --------
    >>> t = np.linspace(0.0, 0.01, 101)
    >>> x = np.stack([1e-5 * t / 0.01, 0 * t], axis=1)
    >>> z = memory_inputs(t, x, np.zeros_like(x), 1e-4, 100.0, 0.002, 3)
    >>> np.round(z[-1, 4:] * 1e-4 / 1e-5, 6).tolist()  # the journal moved at a constant rate: lags 0.2, 0.4, 0.6
    [-0.2, 0.0, -0.4, 0.0, -0.6, 0.0]
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    n = len(t)
    out = np.empty((n, 4 + 2 * n_lags))
    out[:, 0:2] = x / clearance
    out[:, 2:4] = np.asarray(v, dtype=float) / (clearance * omega)
    t_last = np.floor(t / lag_dt + 1e-9) * lag_dt
    frac = (t - t_last) / lag_dt
    for k in range(1, n_lags + 1):
        # samples j = k - 1 and k before the latest: at t_last - (k - 1) lag_dt and t_last - k lag_dt
        ta = t_last - (k - 1) * lag_dt
        tb = t_last - k * lag_dt
        for d in range(2):
            xa = np.interp(ta, t, x[:, d], left=x[0, d])
            xb = np.interp(tb, t, x[:, d], left=x[0, d])
            out[:, 2 + 2 * k + d] = (frac * xa + (1.0 - frac) * xb - x[:, d]) / clearance
    return out


class MemorySurrogate:
    """The JFO film's force surrogate with memory (module doc): a ``ForceModel`` and a ``TransientFilmModel``.

    Parameters
    ----------
    bearing : JournalBearing
        The bearing (and speed) the network was trained for.
    layers : list of (W, b)
        The network's dense layers, W (out, in).
    activation : str
        Its hidden activation (``inference.ACTIVATIONS``).
    in_mean, in_std : array (4 + 2 n_lags,)
        Standardisation of the inputs (``memory_inputs``).
    out_mean, out_std : array (2,)
        Of the targets F / film_gain (``film_gain``).
    lag_dt : float
        Spacing of the lagged positions [s].
    n_lags : int
        Their number.
    eps_max : float
        The training paths' largest eccentricity.
    gain_power : float, default 0
        The targets' scaling with the eccentricity (``film_gain``): the film's force grows as about
        (1 - eps^2)^-1.5, so the network learns a target of even size at every eccentricity.
    meta : dict, optional
        What the training wrote (the reference's grid and rule, the data, the fit).
    """

    fixed_speed = True  # one network, one shaft speed: ``simulate`` refuses a speed schedule

    def __init__(self, bearing: JournalBearing, layers, activation: str, in_mean, in_std, out_mean, out_std,
                 lag_dt: float, n_lags: int, eps_max: float, gain_power: float = 0.0, meta: dict | None = None):
        if activation not in ACTIVATIONS:
            raise ValueError(f"unknown activation {activation!r}; choose one of {tuple(ACTIVATIONS)}")
        n_in = 4 + 2 * int(n_lags)
        if int(n_lags) < 1 or not lag_dt > 0.0:
            raise ValueError(f"n_lags must be >= 1 and lag_dt > 0, got n_lags={n_lags}, lag_dt={lag_dt}")
        if np.shape(layers[0][0])[1] != n_in or np.shape(layers[-1][0])[0] != 2:
            raise ValueError(f"the network takes {np.shape(layers[0][0])[1]} inputs and gives "
                             f"{np.shape(layers[-1][0])[0]} outputs; {n_lags} lags need {n_in} inputs and 2 outputs")
        self._bearing = bearing
        self._layers = [(np.asarray(W, dtype=float), np.asarray(b, dtype=float)) for W, b in layers]
        self.activation = activation
        self.lag_dt = float(lag_dt)
        self.n_lags = int(n_lags)
        self.meta = dict(meta or {})
        weights, table = pack_network(self._layers)
        width = max(max(W.shape) for W, _ in self._layers)
        self.params = MemoryParams(weights, table, len(self._layers), ACTIVATIONS[activation],
                                   np.asarray(in_mean, dtype=float), np.asarray(in_std, dtype=float),
                                   np.asarray(out_mean, dtype=float), np.asarray(out_std, dtype=float),
                                   float(bearing.force_scale), float(gain_power), 1.0 / bearing.clearance,
                                   1.0 / (bearing.clearance * bearing.omega), self.lag_dt, self.n_lags,
                                   float(eps_max), 1.0, 0.0, 0, np.zeros(1, dtype=np.int64), np.zeros(max(width, n_in)),
                                   np.zeros(width), np.zeros(width))
        self._validity = ValidityDomain(eps_max=float(eps_max))

    # --- ForceModel ---------------------------------------------------------------------------------------
    @property
    def name(self) -> str:
        return "MemorySurrogate"

    @property
    def bearing(self) -> Any:
        return self._bearing

    @property
    def clearance(self) -> float:
        return float(self._bearing.clearance)

    @property
    def validity(self) -> ValidityDomain:
        return self._validity

    @property
    def force_kernel(self):
        return memory_force, self.params

    def forces(self, X, V) -> np.ndarray:
        """Film force [N] at positions X [m] and velocities V [m/s], (..., 2), the history at rest at X."""
        x, v, shape = as_state_pairs(X, V, self.clearance)
        out = np.empty_like(x)
        for k in range(x.shape[0]):
            out[k] = memory_force(self.params, x[k, 0], x[k, 1], v[k, 0], v[k, 1])
        return out.reshape(shape + (2,))

    def reset_domain_counter(self) -> None:
        self.params.counter[0] = 0

    def domain_report(self) -> str | None:
        return None

    @property
    def n_outside_domain(self) -> int:
        return int(self.params.counter[0])

    # --- TransientFilmModel -------------------------------------------------------------------------------
    def transient_kernels(self):
        """``(memory_stage, memory_commit, memory_flows, params)`` for ``rotor.film_memory``."""
        return memory_stage, memory_commit, memory_flows, self.params

    @property
    def film_state_shape(self) -> tuple[int, int]:
        """The carried history: a clock row, then n_lags + 1 samples of the path."""
        return (self.n_lags + 2, 2)

    def steady_field(self, x, omega: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(unused field, history): the journal at rest at x [m] for all earlier times."""
        xa, _, _ = as_state_pairs(x, (0.0, 0.0), self.clearance)
        hist = np.empty(self.film_state_shape)
        hist[0] = 0.0
        hist[1:] = xa[0]
        return np.zeros((1, 1)), hist

    def check_film_state(self, state) -> np.ndarray:
        """``state`` as this model's history (a ``film_content`` to continue a run), or a ValueError."""
        a = np.array(state, dtype=float)
        if a.shape != self.film_state_shape or not np.isfinite(a).all():
            raise ValueError(f"film_content must be a finite history of shape {self.film_state_shape} (the "
                             f"meta['film_content'] of an earlier run of this model), got shape {a.shape}")
        return a

    # --- files ----------------------------------------------------------------------------------------------
    def save(self, path) -> Path:
        """Write ``film_memory.npz`` and ``model.json`` into the folder ``path`` (atomically, each)."""
        path = Path(path)
        path.mkdir(parents=True, exist_ok=True)
        p = self.params
        arrays: dict[str, Any] = {f"W{i}": W for i, (W, _) in enumerate(self._layers)}
        arrays.update({f"b{i}": b for i, (_, b) in enumerate(self._layers)})
        arrays.update(in_mean=p.in_mean, in_std=p.in_std, out_mean=p.out_mean, out_std=p.out_std)
        with io.atomic_path(path / WEIGHTS_FILE) as tmp:
            np.savez(tmp, **arrays)
        meta = {"kind": KIND, "activation": self.activation, "n_layers": len(self._layers), "lag_dt": self.lag_dt,
                "n_lags": self.n_lags, "eps_max": p.eps_max, "gain_power": p.gain_power, "bearing": self._bearing.to_dict(), **self.meta}
        io.write_json(path / META_FILE, meta)
        return path

    @classmethod
    def load(cls, path) -> MemorySurrogate:
        """The model saved in the folder ``path`` (``save``); a ValueError naming what is missing or wrong."""
        path = Path(path)
        meta_file, npz = path / META_FILE, path / WEIGHTS_FILE
        for f in (meta_file, npz):
            if not f.is_file():
                raise ValueError(f"{f} is missing: not a saved film-memory surrogate")
        meta = json.loads(meta_file.read_text())
        if meta.get("kind") != KIND:
            raise ValueError(f"{meta_file} holds a {meta.get('kind')!r} model, not a {KIND!r} one")
        with np.load(npz) as a:
            n = int(meta["n_layers"])
            layers = [(a[f"W{i}"], a[f"b{i}"]) for i in range(n)]
            stats = {k: a[k] for k in ("in_mean", "in_std", "out_mean", "out_std")}
        bearing = bearing_from_dict(meta["bearing"])
        rest = {k: v for k, v in meta.items() if k not in ("kind", "activation", "n_layers", "lag_dt", "n_lags",
                                                           "eps_max", "gain_power", "bearing")}
        return cls(bearing, layers, meta["activation"], lag_dt=float(meta["lag_dt"]), n_lags=int(meta["n_lags"]),
                   eps_max=float(meta["eps_max"]), gain_power=float(meta["gain_power"]), meta=rest, **stats)

    def __repr__(self) -> str:
        return (f"MemorySurrogate({len(self._layers) - 1} hidden layers, {self.n_lags} lags of "
                f"{1e3 * self.lag_dt:g} ms, eps <= {self.params.eps_max:.3g})")


__all__ = ["MemorySurrogate", "MemoryParams", "memory_inputs", "film_gain", "memory_force", "memory_stage", "memory_commit",
           "memory_flows"]
