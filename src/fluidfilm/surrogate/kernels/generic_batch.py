"""The generic batched kernel ``forces_batch``: many states per call, for every model shape.

Each state is routed to its region (a state in a blend zone to both neighbours), each region's network runs
on tiles of states as dense products with the states along the vector lanes, then the forces are blended
and turned back into the (X1, X2) frame.  float64 by default; ``batch_params(model, "float32")`` runs the
network arithmetic in float32 (``activations.unit32``), forces within 1e-5 relative of float64 (tested).
It serves the shapes without a generated batched kernel (``generated_batch.batch_shape_key`` None).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from fluidfilm.surrogate.activations import (ACTIVATIONS, unit32, unit64)
from fluidfilm.surrogate.contract import (FRAME_POLAR, FRAME_WHIRL, KIND_PHYSICS, KIND_PHYSICS_V, REGION_CLEARANCE,
                                         REGION_FORCE_SCALE, REGION_FRAME, REGION_KIND, REGION_N_EXTRA, REGION_OMEGA,
                                         REGION_POWER, REGION_SLEEVE, SLEEVE_AWARE, region_row)
from fluidfilm.surrogate.kernels.folding import _folded_networks


# ---------------------------------------------------------------------------------------------- batched

#: states per tile of a region's network evaluation (the hidden activations of a tile, 64 x TILE
#: float64, stay within the second-level cache)
TILE = 128
#: vector lanes a partial tile is padded to (16 float32 in a 512-bit register; a divisor of TILE)
LANE = 16


class BatchParams(NamedTuple):
    """Parameters of ``forces_batch`` (made by ``batch_params``)."""

    weights: np.ndarray      # flat folded weights, float64 or float32 (the network arithmetic's type)
    tables: np.ndarray       # (R, L, 4) int64 per region and layer [W offset, b offset, n_in, n_out], W (out, in)
    n_layers: np.ndarray     # (R,) int64
    damping_tables: np.ndarray  # (R, L, 4) the damping-matrix networks' layers (damping structure)
    damping_n_layers: np.ndarray  # (R,) int64 (0: plain structure)
    regions: np.ndarray      # (R, REGION_ROW_LENGTH) float64 [kind, frame, n_extra, sleeve-aware, c, omega, F_scale, power]
    #                          (``surrogate.contract.region_row``)
    boundaries: np.ndarray   # (R-1,) eccentricity ratios between the regions
    blend_width: float
    domain: np.ndarray       # (S, 3) [eps_low, eps_high, v_max]
    eps_max: float
    counter: np.ndarray      # the model's domain counter (float64 view, mutable)
    setting: np.ndarray      # the model's setting [1/c^2, sleeve] (view, mutable)
    activation: int          # 0 tanh, 1 relu, 2 silu, 3 sigmoid
    width: int               # widest layer


def _flat_tables(chains, dtype):
    """[region][layers (W (out, in), b)] -> flat weights of ``dtype`` and an (R, L, 4) table."""
    flat, tabs, off = [], [], 0
    for layers in chains:
        t = []
        for W, b in layers:
            t.append([off, off + W.size, W.shape[1], W.shape[0]])
            flat += [np.ascontiguousarray(W).ravel(), b]
            off += W.size + b.size
        tabs.append(t)
    table = np.zeros((len(chains), max([len(t) for t in tabs] + [1]), 4), dtype=np.int64)
    for r, t in enumerate(tabs):
        if t:
            table[r, :len(t)] = t
    weights = np.concatenate(flat) if flat else np.zeros(1)
    return weights.astype(dtype), table


def batch_params(model, dtype: str = "float64") -> BatchParams:
    """``forces_batch``'s parameters of ``model``, its network arithmetic in ``dtype``.

    Parameters
    ----------
    model : SurrogateForceModel
    dtype : {"float64", "float32"}, default "float64"
        float32 runs the networks (inputs, weights, activations) in single precision with ``tanh32``; the
        routing, the scalings and the blend stay float64.  Forces within 1e-5 relative of float64 (tested).

    Returns
    -------
    BatchParams
    """
    if dtype not in ("float64", "float32"):
        raise ValueError(f"dtype must be 'float64' or 'float32', got {dtype!r}")
    folded = _folded_networks(model)
    static = [s for s, _ in folded]
    damping = [d for _, d in folded]
    # the damping chains follow the static ones in one flat array
    w_s, t_s = _flat_tables(static, dtype)
    w_d, t_d = _flat_tables(damping, dtype)
    t_d = t_d.copy()
    t_d[:, :, :2] += w_s.size
    rows = []
    for sc in model.scalings:
        rows.append(region_row(sc.kernel_row(), sc.clearance, sc.omega, sc.force_scale, sc.power))
    width = max([W.shape[0] for s, d in folded for W, _ in s + d] + [4])
    return BatchParams(np.concatenate([w_s, w_d]), t_s, np.array([len(s) for s in static], dtype=np.int64),
                       t_d, np.array([len(d) for d in damping], dtype=np.int64), np.array(rows, dtype=np.float64),
                       np.ascontiguousarray(model.boundaries if len(model.boundaries) else np.zeros(0),
                                            dtype=np.float64),
                       float(model.blend_width), np.ascontiguousarray(model.domain, dtype=np.float64),
                       float(model.eps_max), model._counter, model._setting, ACTIVATIONS[model.activation], int(width))


@njit(cache=True, error_model="numpy", fastmath={"contract", "reassoc"})
def _activate_tile(dst, n_out, n, act, f32):
    """The activation ``act`` (a registry code, ``surrogate.activations``) over a tile's n_out rows of n states."""
    for o in range(n_out):
        if f32:
            for p in range(n):
                dst[o, p] = unit32(act, dst[o, p])
        else:
            for p in range(n):
                dst[o, p] = unit64(act, dst[o, p])


@njit(cache=True, error_model="numpy", fastmath={"contract", "reassoc"})
def _mlp_tile(w, table, n_layers, act, f32, z, buf_a, buf_b, n):
    """One network on the n states of a tile, states along the rows' vector lanes: z (n_in, n) ->
    the buffer holding (n_out, n).  Dense products written as axpy updates over the tile."""
    src = z
    for layer in range(n_layers):
        w_off, b_off, n_in, n_out = table[layer, 0], table[layer, 1], table[layer, 2], table[layer, 3]
        dst = buf_a if layer % 2 == 0 else buf_b
        for o in range(n_out):
            bo = w[b_off + o]
            for p in range(n):
                dst[o, p] = bo
            for i in range(n_in):
                c = w[w_off + o * n_in + i]
                for p in range(n):
                    dst[o, p] += c * src[i, p]
        if layer < n_layers - 1:
            _activate_tile(dst, n_out, n, act, f32)
        src = dst
    return src


@njit(cache=True, error_model="numpy", fastmath={"contract", "reassoc"})
def forces_batch(bp, x, v, out):
    """Film forces [N] of the states (x (N, 2) [m], v (N, 2) [m/s]) into ``out`` (N, 2), counting the states
    outside the training domain in the model's counter as the one-state kernels do.

    Each state goes to its region (a state within a blend zone to both neighbours, with the smoothstep
    weights); each region's network runs on tiles of its states as dense products; the forces are blended
    and turned back into the (X1, X2) frame.
    """
    n = x.shape[0]
    nr = bp.regions.shape[0]
    nb = bp.boundaries.shape[0]
    inv_c2 = bp.setting[0]
    blend = bp.blend_width
    dom = bp.domain
    n_dom = dom.shape[0]
    f32 = bp.weights.itemsize == 4
    # 1. route: region(s) and weight(s) of every state, the domain count
    ra = np.empty(n, dtype=np.int64)
    rb = np.empty(n, dtype=np.int64)
    wb = np.empty(n)
    count = np.zeros(nr, dtype=np.int64)
    outside = 0
    for p in range(n):
        x1, x2, v1, v2 = x[p, 0], x[p, 1], v[p, 0], v[p, 1]
        eps = math.sqrt((x1 * x1 + x2 * x2) * inv_c2)
        vout = False
        for s in range(n_dom):
            if dom[s, 0] <= eps < dom[s, 1] or (s == n_dom - 1 and eps >= dom[s, 1]):
                vout = abs(v1) > dom[s, 2] or abs(v2) > dom[s, 2]
                break
        if eps > bp.eps_max or vout:
            outside += 1
        r = 0
        while r < nb and eps >= bp.boundaries[r]:
            r += 1
        ra[p] = r
        rb[p] = -1
        wb[p] = 0.0
        if blend > 0.0:
            for b in range(nb):
                lo = bp.boundaries[b] - 0.5 * blend
                if lo <= eps < bp.boundaries[b] + 0.5 * blend:
                    t = (eps - lo) / blend
                    ra[p] = b
                    rb[p] = b + 1
                    wb[p] = t * t * (3.0 - 2.0 * t)
                    break
        count[ra[p]] += 1
        if rb[p] >= 0:
            count[rb[p]] += 1
        out[p, 0] = 0.0
        out[p, 1] = 0.0
    bp.counter[0] += outside
    # 2. each region's entries (state, weight), in state order
    start = np.zeros(nr + 1, dtype=np.int64)
    for r in range(nr):
        start[r + 1] = start[r] + count[r]
    fill = start[:nr].copy()
    ent = np.empty(start[nr], dtype=np.int64)
    ent_w = np.empty(start[nr])
    for p in range(n):
        k = fill[ra[p]]
        ent[k] = p
        ent_w[k] = 1.0 - wb[p] if rb[p] >= 0 else 1.0
        fill[ra[p]] = k + 1
        if rb[p] >= 0:
            k = fill[rb[p]]
            ent[k] = p
            ent_w[k] = wb[p]
            fill[rb[p]] = k + 1
    # 3. each region's network on tiles
    wdt = bp.weights
    z = np.empty((8, TILE), dtype=wdt.dtype)
    buf_a = np.empty((bp.width, TILE), dtype=wdt.dtype)
    buf_b = np.empty((bp.width, TILE), dtype=wdt.dtype)
    post = np.empty((5, TILE))  # gain, e_r (2), raw velocity inputs (2, damping structure)
    y1 = np.empty(TILE)  # the tile's forces before the gain (allocated once per call: a small batch pays per call)
    y2 = np.empty(TILE)
    for r in range(nr):
        kind, frame, n_extra = bp.regions[r, REGION_KIND], bp.regions[r, REGION_FRAME], int(bp.regions[r, REGION_N_EXTRA])
        physics = kind >= KIND_PHYSICS
        polar = frame >= FRAME_POLAR
        for t0 in range(start[r], start[r + 1], TILE):
            m = min(TILE, start[r + 1] - t0)
            for j in range(m):
                p = ent[t0 + j]
                x1, x2, v1, v2 = x[p, 0], x[p, 1], v[p, 0], v[p, 1]
                c, omega, fscale = bp.regions[r, REGION_CLEARANCE], bp.regions[r, REGION_OMEGA], bp.regions[r, REGION_FORCE_SCALE]
                if bp.regions[r, REGION_SLEEVE] == SLEEVE_AWARE:
                    fscale = fscale * c * c * inv_c2
                    c = 1.0 / math.sqrt(inv_c2)
                e2 = (x1 * x1 + x2 * x2) * inv_c2
                drive = 1.0
                er1, er2 = 0.0, 1.0
                if polar:
                    rr = math.sqrt(x1 * x1 + x2 * x2)
                    at0 = 1.0 if rr == 0.0 else 0.0
                    safe = rr + at0
                    er1 = x1 / safe
                    er2 = x2 / safe + at0
                    cw = c * omega
                    z0 = rr / c
                    z1 = (v1 * er1 + v2 * er2) / cw
                    z2 = (v1 * er2 - v2 * er1) / cw
                    if frame == FRAME_WHIRL:
                        ua = z0 - 2.0 * z2
                        ub = 2.0 * z1
                        drive = math.sqrt(ua * ua + ub * ub)
                        zero = 1.0 if drive == 0.0 else 0.0
                        z1 = ua / (drive + zero) + zero
                        z2 = ub / (drive + zero)
                    z[0, j], z[1, j], z[2, j] = z0, z1, z2
                    n_in = 3
                    post[3, j], post[4, j] = z1, z2
                else:
                    if physics:
                        z0, z1, z2, z3 = x1 / c, x2 / c, v1 / (c * omega), v2 / (c * omega)
                    else:
                        z0, z1, z2, z3 = x1, x2, v1, v2
                    z[0, j], z[1, j], z[2, j], z[3, j] = z0, z1, z2, z3
                    n_in = 4
                    post[3, j], post[4, j] = z2, z3
                for k in range(n_extra):
                    z[n_in + k, j] = bp.setting[1 + k]
                g = 1.0
                if physics:
                    d = 1.0 - e2
                    power = bp.regions[r, REGION_POWER]
                    g = fscale / (d * math.sqrt(d)) if power == 1.5 else fscale / d ** power
                    if kind == KIND_PHYSICS_V:
                        g *= 1.0 + math.sqrt(v1 * v1 + v2 * v2) / (c * omega)
                    g *= drive
                post[0, j], post[1, j], post[2, j] = g, er1, er2
            y = _mlp_tile(wdt, bp.tables[r], bp.n_layers[r], bp.activation, f32, z, buf_a, buf_b, m)
            for j in range(m):
                y1[j] = y[0, j]
                y2[j] = y[1, j]
            if bp.damping_n_layers[r] > 0:
                dm = _mlp_tile(wdt, bp.damping_tables[r], bp.damping_n_layers[r], bp.activation, f32, z, buf_a,
                               buf_b, m)
                for j in range(m):
                    w1, w2 = post[3, j], post[4, j]
                    y1[j] += dm[0, j] * w1 + dm[1, j] * w2
                    y2[j] += dm[2, j] * w1 + dm[3, j] * w2
            for j in range(m):
                p = ent[t0 + j]
                g, er1, er2 = post[0, j], post[1, j], post[2, j]
                f1 = y1[j] * g
                f2 = y2[j] * g
                if polar:
                    f1, f2 = f1 * er1 + f2 * er2, f1 * er2 - f2 * er1
                out[p, 0] += ent_w[t0 + j] * f1
                out[p, 1] += ent_w[t0 + j] * f2


