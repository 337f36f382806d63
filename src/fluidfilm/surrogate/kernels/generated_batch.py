"""The generated batched kernel: one compiled function per model shape, what ``simulate_batch`` calls per RK4 stage.

``batch_kernel(batch_shape_key(model), dtype)`` takes ``forces_batch``'s signature (``fast_batch_params``
makes its parameters): per state in order the inputs, frame and gain without a branch (vectorised), the
domain count and region(s) as selects, a counting sort by region, each region's network on tiles with
literal widths and its last hidden layer fused with the output layer, then the blend, gain and frame per
state.  Equal to the generic kernel to round-off (float64; one reciprocal per division) or within 1e-5
relative (float32 networks), tested on every surrogate shape of the test models.  To read a model's
source: ``batch_kernel_source(batch_shape_key(model), dtype)``, or ``write_kernel_sources``
(``fluidfilm.surrogate.kernels``).
"""
from __future__ import annotations

import math
import re
from typing import Any, NamedTuple

import numpy as np
from numba import njit

from fluidfilm.surrogate.activations import (ACTIVATIONS, relu64, unit_name,
                                             unit_names)
from fluidfilm.surrogate.contract import (FRAME_POLAR, FRAME_WHIRL, KIND_PHYSICS, KIND_PHYSICS_V, ROW_CLEARANCE, ROW_FRAME, ROW_KIND, ROW_N_EXTRA, ROW_OMEGA, ROW_SLEEVE, SLEEVE_AWARE)
from fluidfilm.surrogate.kernels.cache import _cached_module_function, kernel_files
from fluidfilm.surrogate.kernels.folding import _folded_networks, _power_source, shape_key
from fluidfilm.surrogate.kernels.generic_batch import LANE, TILE


# ---------------------------------------------------------------------------------------------- batched, per shape

class FastBatchParams(NamedTuple):
    """Parameters of a batched kernel generated per model shape (``batch_kernel``)."""

    weights: np.ndarray   # flat folded weights in the network's arithmetic type (float64 or float32)
    consts: np.ndarray    # float64 [c, omega, eps_max, blend, boundaries..., domain rows..., power per region]
    counter: np.ndarray   # the model's domain counter (float64 view, mutable; a private one per thread)
    setting: np.ndarray   # the model's setting [1/c^2, sleeve...] (view, mutable)
    # scratch of one thread's calls (``with_workspace``): float64, int64 and the networks' type; empty ones
    # (the default, shareable between threads) make the kernel allocate its scratch per call
    work: np.ndarray = np.empty(0)
    iwork: np.ndarray = np.empty(0, dtype=np.int64)
    wwork: np.ndarray = np.empty(0)


#: states a private workspace holds (``with_workspace``): a larger call allocates its scratch itself
WORKSPACE_STATES = 4096


def _workspace_terms(key) -> tuple[tuple[int, int], tuple[int, int], tuple[int, int]]:
    """Scratch of a batched kernel call as (per state, fixed) elements: float64, int64, networks' type."""
    layout, _ = _batch_layout(key)
    n_in = 3 if key.regions[0].frame >= FRAME_POLAR else 4
    nr = len(key.regions)
    width = max([k for r in layout for (_, _, k, _) in r] + [1])
    return (9, 2), (6, nr + 2), (n_in + 5, n_in * TILE + 3 * TILE + 2 * width * TILE + width)


def _workspace_sizes(key, n: int) -> tuple[int, int, int]:
    """Scratch of a batched kernel call of n states: (float64, int64, networks' type) elements."""
    (a64, b64), (ai, bi), (aw, bw) = _workspace_terms(key)
    return a64 * n + b64, ai * n + bi, aw * n + bw


def with_workspace(bp: FastBatchParams, key, n_states: int = WORKSPACE_STATES) -> FastBatchParams:
    """``bp`` with its own scratch for calls of up to ``n_states`` states (one thread's parameters only).

    The generated kernel otherwise allocates about twenty arrays per call (what that costs:
    docs/fast_surrogates.md).

    Parameters
    ----------
    bp : FastBatchParams
        Parameters of one thread (a private counter): the scratch is overwritten by every call.
    key : tuple
        ``batch_shape_key`` of the model.
    n_states : int, default WORKSPACE_STATES
        The largest call served from the scratch.

    Returns
    -------
    FastBatchParams
    """
    if n_states < 1:
        raise ValueError(f"n_states must be a positive integer, got {n_states!r}")
    n64, ni, nw = _workspace_sizes(key, int(n_states))
    return bp._replace(work=np.empty(n64), iwork=np.empty(ni, dtype=np.int64),
                       wwork=np.empty(nw, dtype=bp.weights.dtype))


def batch_shape_key(model) -> tuple | None:
    """What a generated batched kernel depends on (``batch_kernel``), or None where the model's shape has none.

    Parameters
    ----------
    model : SurrogateForceModel

    Returns
    -------
    tuple or None
        ``shape_key(model)``; None for the damping structure, for regions that differ in scaling family,
        frame, extra inputs, sleeve gain, clearance or speed, and for extra inputs into a network without a
        hidden layer (``forces_batch`` serves those).
    """
    key = shape_key(model)
    structure, act, regions, nb, blending, n_dom = key
    if structure != "plain" or (regions[0].n_extra and any(len(r.static) < 2 for r in regions)):
        return None
    rows = [sc.kernel_row() for sc in model.scalings]
    common = {(int(r[ROW_KIND]) >= KIND_PHYSICS, int(r[ROW_FRAME]), int(r[ROW_N_EXTRA]), bool(r[ROW_SLEEVE] == SLEEVE_AWARE),
               float(r[ROW_CLEARANCE]), float(r[ROW_OMEGA])) for r in rows}
    if len(common) != 1:
        return None
    return key


def _batch_layout(key):
    """Per region: [(W offset, b offset, n_out, n_in)] of its folded layers in the flat weights; the size."""
    off, out = 0, []
    for region in key.regions:
        layers = []
        for n_out, n_in in region.static:
            layers.append((off, off + n_out * n_in, n_out, n_in))
            off += n_out * n_in + n_out
        out.append(layers)
    return out, off


def fast_batch_params(model, dtype: str = "float64") -> FastBatchParams:
    """The parameters of ``model``'s generated batched kernel (``batch_kernel``), its networks in ``dtype``.

    The input standardisation is folded into the first layer; the output's and, for the physics scalings,
    the force scale (times c_r^2 where the gain follows the sleeve) into the last.

    Parameters
    ----------
    model : SurrogateForceModel
        A model whose ``batch_shape_key`` is not None.
    dtype : {"float64", "float32"}, default "float64"
        The networks' arithmetic.

    Returns
    -------
    FastBatchParams
    """
    if dtype not in ("float64", "float32"):
        raise ValueError(f"dtype must be 'float64' or 'float32', got {dtype!r}")
    key = batch_shape_key(model)
    if key is None:
        raise ValueError(f"{model.name}: no generated batched kernel for this shape (use forces_batch)")
    layout, size = _batch_layout(key)
    w = np.zeros(max(size, 1))
    out_bias = []  # the output layers' biases stay float64 (added after the network: module doc)
    for r, ((static, _), sc) in enumerate(zip(_folded_networks(model), model.scalings)):
        physics = sc.kernel_row()[ROW_KIND] >= KIND_PHYSICS
        gain = sc.force_scale * (sc.clearance ** 2 if sc.sleeve_gain else 1.0) if physics else 1.0
        for k, ((W, b), (wo, bo, _, _)) in enumerate(zip(static, layout[r])):
            if k == len(static) - 1:
                W, b = W * gain, b * gain
                out_bias += list(b)
                b = np.zeros_like(b)
            w[wo:bo] = np.ascontiguousarray(W).ravel()
            w[bo:bo + b.size] = b
    sc0 = model.scalings[0]
    consts = np.concatenate([[sc0.clearance, sc0.omega, model.eps_max, model.blend_width],
                             np.asarray(model.boundaries, dtype=np.float64).ravel(),
                             np.asarray(model.domain, dtype=np.float64).ravel(),
                             [sc.power for sc in model.scalings], out_bias])
    return FastBatchParams(w.astype(dtype), consts, model._counter, model._setting, wwork=np.empty(0, dtype=dtype))


def _dense_rows(n_out, n_in, wo, bo, src, ind, body, n_terms=None, bias="w[{bo} + o]"):
    """Lines: for each output o of a layer (rows of ``n_in`` weights from ``wo``), its pre-activation ``a``
    over the tile, then ``body`` (lines using ``a``, ``o`` and ``j``, inside ``for j``).  ``src``: "T" (the
    tile's first ``n_terms`` inputs T[i, j], an unrolled sum) or a buffer name (rows of the previous layer)."""
    bias = bias.format(bo=bo)
    L = [f"{ind}for o in range({n_out}):"]
    if src == "T":
        n_terms = n_in if n_terms is None else n_terms
        L += [f"{ind}    c{i} = w[{wo} + o * {n_in} + {i}]" for i in range(n_terms)]
        L.append(f"{ind}    bb = {bias}")
        expr = "bb + " + " + ".join(f"c{i} * T[{i}, j]" for i in range(n_terms))
        L += [f"{ind}    for j in range(m):", f"{ind}        a = {expr}"]
    else:
        L += [f"{ind}    bb = {bias}", f"{ind}    for j in range(m):", f"{ind}        acc[j] = bb",
              f"{ind}    for i in range({n_in}):", f"{ind}        ci = w[{wo} + o * {n_in} + i]",
              f"{ind}        for j in range(m):", f"{ind}            acc[j] += ci * {src}[i, j]",
              f"{ind}    for j in range(m):", f"{ind}        a = acc[j]"]
    L += [f"{ind}        {line}" for line in body]
    return L


def _batch_net_source(layers, act_fn, ind, n_terms, bias0):
    """Lines evaluating one region's folded network on the tile's first ``n_terms`` inputs T[:, :m] into
    Y1t, Y2t (``bias0``: the first layer's bias expression)."""
    wo_l, bo_l, _, n_hid_l = layers[-1]
    # the output layer's bias (in the constants, float64) is added after the network: a force dominated by it
    # (the output's mean) keeps float64 precision there
    L = [f"{ind}for j in range(m):", f"{ind}    Y1t[j] = 0.0", f"{ind}    Y2t[j] = 0.0"]
    if len(layers) == 1:
        L += [f"{ind}for j in range(m):"]
        for r, name in ((0, "Y1t"), (1, "Y2t")):
            expr = " + ".join(f"w[{wo_l + r * n_hid_l + i}] * T[{i}, j]" for i in range(n_terms))
            L.append(f"{ind}    {name}[j] += {expr}")
        return L
    L += [f"{ind}u1s = w[{wo_l}:{wo_l + n_hid_l}]", f"{ind}u2s = w[{wo_l + n_hid_l}:{wo_l + 2 * n_hid_l}]"]
    src = "T"
    for k, (wo, bo, n_out, n_in) in enumerate(layers[:-1]):
        kw = {"n_terms": n_terms, "bias": bias0} if k == 0 else {}
        if k == len(layers) - 2:
            # the last hidden layer fused with the output layer: its activations never leave the registers
            body = [f"h = {act_fn}(a)", "Y1t[j] += u1 * h", "Y2t[j] += u2 * h"]
            lines = _dense_rows(n_out, n_in, wo, bo, src, ind, body, **kw)
            lines[1:1] = [f"{ind}    u1 = u1s[o]", f"{ind}    u2 = u2s[o]"]  # unit o's output weights
            L += lines
        else:
            dst = "HA" if src != "HA" else "HB"
            L += _dense_rows(n_out, n_in, wo, bo, src, ind, [f"{dst}[o, j] = {act_fn}(a)"], **kw)
            src = dst
    return L


def _batch_unit(act: str) -> str:
    """The activation's unit in a batched kernel's source: ``<name>_n``, bound to the float64 or float32
    unit by the module's imports (``_batch_units``)."""
    return f"{act}_n"


def _batch_units(f32: bool) -> dict[str, Any]:
    """``_batch_unit`` name -> the compiled unit of the networks' precision, for every registered activation."""
    return {_batch_unit(a): fn for a, fn in ((a, unit_names()[unit_name(a, f32)]) for a in ACTIVATIONS)}


def batch_kernel_source(key, dtype: str = "float64") -> str:
    """Python source of the batched kernel of a model shape, compiled by ``batch_kernel``.

    Parameters
    ----------
    key : tuple
        ``batch_shape_key(model)`` (not None).
    dtype : {"float64", "float32"}, default "float64"
        The networks' arithmetic. With float32 the per-state frame (unit vectors, drive, gain) is computed
        in float32 as well; the eccentricity, which routes the state to its region(s) and counts it
        against the training domain, and 1 - eps^2 stay float64, so routing and counting equal the
        float64 kernel's exactly.

    Returns
    -------
    str
        The source of ``batch_kernel(bp, x, v, out)``: ``forces_batch``'s signature and meaning, in four
        passes (docs/fast_surrogates.md): per state the inputs, frame, gain, domain count and region(s)
        without a branch; a counting sort by region; each region's network on tiles, its last hidden layer
        fused with the output layer; per state the regions' outputs blended, the gain and the frame back.
        A call of more than ``WORKSPACE_STATES`` states runs in blocks of that many (``_states_block``: the
        four passes on one block), so that its scratch fits a default workspace (``with_workspace``; else
        it is allocated once per block) and stays within the cache: one pass over many more states took
        about twice the time per force (docs/fast_surrogates.md); blocked, the same bits (every state's
        arithmetic is independent of the others').
    """
    structure, act, regions, nb, blending, n_dom = key
    layout, _ = _batch_layout(key)
    kind0, frame, n_extra, sleeve = regions[0].kind, regions[0].frame, regions[0].n_extra, regions[0].sleeve
    physics = kind0 >= KIND_PHYSICS
    polar = frame >= FRAME_POLAR
    n_in = (3 if polar else 4)
    any_kind2 = any(r.kind == KIND_PHYSICS_V for r in regions)
    nr = len(regions)
    width = max([n for r in layout for (_, _, n, _) in r] + [1])
    uniform_gain = physics and len({(r.kind, r.power) for r in regions}) == 1 and regions[0].power is not None
    ind1 = "    "
    ind2 = ind1 + "    "
    (a64, b64), (ai, bi), (aw, bw) = _workspace_terms(key)  # the sizes with_workspace allocates
    L = ["def batch_kernel(bp, x, v, out):",
         f"{ind1}w = bp.weights", f"{ind1}q = bp.consts", f"{ind1}inv_c2 = bp.setting[0]", f"{ind1}n = x.shape[0]",
         # the scratch: the thread's workspace where it is large enough (with_workspace), else allocated here
         f"{ind1}k64 = {a64} * n + {b64}", f"{ind1}ki = {ai} * n + {bi}", f"{ind1}kw = {aw} * n + {bw}",
         f"{ind1}s64 = bp.work if bp.work.size >= k64 else np.empty(k64)",
         f"{ind1}si = bp.iwork if bp.iwork.size >= ki else np.empty(ki, dtype=np.int64)",
         f"{ind1}sw = bp.wwork if bp.wwork.size >= kw else np.empty(kw, dtype=w.dtype)",
         f"{ind1}Z = sw[0:{n_in} * n].reshape(({n_in}, n))"]
    L += [f"{ind1}{a} = sw[{n_in + i} * n:{n_in + i + 1} * n]" for i, a in enumerate(("G", "E1", "E2", "DD", "KV"))]
    L += [f"{ind1}EPS = s64[0:n]", f"{ind1}VA = s64[n:2 * n]", f"{ind1}WB = s64[2 * n:3 * n]",
          f"{ind1}RA = si[0:n]", f"{ind1}RB = si[n:2 * n]", f"{ind1}PA = si[2 * n:3 * n]", f"{ind1}PB = si[3 * n:4 * n]",
          f"{ind1}c = q[0]", f"{ind1}omega = q[1]"]
    if sleeve:
        L.append(f"{ind1}c = 1.0 / math.sqrt(inv_c2)")
    L += [f"{ind1}cw = c * omega", f"{ind1}gs = {'inv_c2' if sleeve else '1.0'}", f"{ind1}eps_max = q[2]",
          f"{ind1}blend = q[3]", f"{ind1}half = 0.5 * blend",
          f"{ind1}inv_blend = 1.0 / blend if blend > 0.0 else 0.0"]
    L += [f"{ind1}bd{b} = q[{4 + b}]" for b in range(nb)]
    for s in range(n_dom):
        L += [f"{ind1}dl{s} = q[{4 + nb + 3 * s}]", f"{ind1}dh{s} = q[{5 + nb + 3 * s}]", f"{ind1}dv{s} = q[{6 + nb + 3 * s}]"]
    # 1a. per state, in order, without branches (vectorises): inputs, frame, gains
    # float32 networks: the frame in float32 too (twice the vector lanes for its square roots and divisions;
    # measured 3-6 ns of ~60 per force), the eccentricity and 1 - eps^2 in float64 (exact routing and counting)
    f32 = dtype == "float32"
    ft = "f" if f32 else ""
    one, two, zero_ = (("one", "two", "zf") if f32 else ("1.0", "2.0", "0.0"))
    if f32:
        L += [f"{ind1}f = np.float32", f"{ind1}one = f(1.0)", f"{ind1}two = f(2.0)", f"{ind1}zf = f(0.0)"]
        L += [f"{ind1}inv_c = f(1.0 / c)", f"{ind1}inv_cw = f(1.0 / cw)", f"{ind1}gsf = f(gs)"]
    else:
        L += [f"{ind1}inv_c = 1.0 / c", f"{ind1}inv_cw = 1.0 / cw"]
    L += [f"{ind1}sc2 = math.sqrt(inv_c2)"]
    passes = [[len(L)]]  # [first line, end] of each pass's loops (_outline_passes)
    L += [f"{ind1}for p in range(n):",
          f"{ind2}x1 = x[p, 0]", f"{ind2}x2 = x[p, 1]", f"{ind2}v1 = v[p, 0]", f"{ind2}v2 = v[p, 1]",
          f"{ind2}r2 = x1 * x1 + x2 * x2", f"{ind2}e2 = r2 * inv_c2", f"{ind2}rr = math.sqrt(r2)", f"{ind2}EPS[p] = rr * sc2",
          f"{ind2}VA[p] = max(abs(v1), abs(v2))", f"{ind2}drive = {one}"]
    if f32:
        L += [f"{ind2}{a}f = f({a})" for a in ("x1", "x2", "v1", "v2", "rr")]
    # (one reciprocal per division of the one-state kernel's expressions: equal to round-off)
    if polar:
        L += [f"{ind2}at0 = {one} if rr{ft} == {zero_} else {zero_}", f"{ind2}inv = {one} / (rr{ft} + at0)",
              f"{ind2}er1 = x1{ft} * inv", f"{ind2}er2 = x2{ft} * inv + at0",
              f"{ind2}z0 = rr{ft} * inv_c", f"{ind2}z1 = (v1{ft} * er1 + v2{ft} * er2) * inv_cw",
              f"{ind2}z2 = (v1{ft} * er2 - v2{ft} * er1) * inv_cw"]
        if frame == FRAME_WHIRL:
            L += [f"{ind2}ua = z0 - {two} * z2", f"{ind2}ub = {two} * z1", f"{ind2}drive = math.sqrt(ua * ua + ub * ub)",
                  f"{ind2}zero = {one} if drive == {zero_} else {zero_}", f"{ind2}inv = {one} / (drive + zero)",
                  f"{ind2}z1 = ua * inv + zero", f"{ind2}z2 = ub * inv"]
        L += [f"{ind2}Z[0, p] = z0", f"{ind2}Z[1, p] = z1", f"{ind2}Z[2, p] = z2", f"{ind2}E1[p] = er1", f"{ind2}E2[p] = er2"]
    elif physics:
        L += [f"{ind2}Z[0, p] = x1{ft} * inv_c", f"{ind2}Z[1, p] = x2{ft} * inv_c", f"{ind2}Z[2, p] = v1{ft} * inv_cw",
              f"{ind2}Z[3, p] = v2{ft} * inv_cw"]
    else:
        L += [f"{ind2}Z[0, p] = x1", f"{ind2}Z[1, p] = x2", f"{ind2}Z[2, p] = v1", f"{ind2}Z[3, p] = v2"]
    if physics:
        L += [f"{ind2}d = {'f(1.0 - e2)' if f32 else '1.0 - e2'}"] + ([] if uniform_gain else [f"{ind2}DD[p] = d"])
        L.append(f"{ind2}G[p] = gs{ft} * drive / ({_power_source('d', regions[0].power)})" if uniform_gain
                 else f"{ind2}G[p] = gs{ft} * drive")
        if any_kind2:
            L.append(f"{ind2}KV[p] = {one} + math.sqrt(v1{ft} * v1{ft} + v2{ft} * v2{ft}) * inv_cw")
        if uniform_gain and any_kind2:
            L.append(f"{ind2}G[p] *= KV[p]")
    # 1b. the domain count and the region(s) of every state, as selects (vectorises)
    passes[-1].append(len(L))
    passes.append([len(L)])
    L += [f"{ind1}outside = 0", f"{ind1}for p in range(n):", f"{ind2}eps = EPS[p]", f"{ind2}vmax = 0.0", f"{ind2}hit = False"]
    for s in range(n_dom):  # the first row holding eps (the last one also beyond its top) bounds the velocities
        cond = f"(eps >= dl{s}) & (eps < dh{s})" + (f" | (eps >= dh{s})" if s == n_dom - 1 else "")
        L += [f"{ind2}now = (~hit) & ({cond})", f"{ind2}vmax = dv{s} if now else vmax", f"{ind2}hit = hit | now"]
    L += [f"{ind2}outside += 1 if ((eps > eps_max) | (hit & (VA[p] > vmax))) else 0", f"{ind2}r = 0"]
    L += [f"{ind2}r += 1 if eps >= bd{b} else 0" for b in range(nb)]
    L += [f"{ind2}ra = r", f"{ind2}rb = {nr}", f"{ind2}wb = 0.0"]  # rb = nr: no second region (a bucket never evaluated)
    if blending:
        for b in reversed(range(nb)):  # the first boundary in order wins, as in the generic kernel
            L += [f"{ind2}lo = bd{b} - half", f"{ind2}t = (eps - lo) * inv_blend", f"{ind2}inz = (eps >= lo) & (eps < bd{b} + half)",
                  f"{ind2}ra = {b} if inz else ra", f"{ind2}rb = {b + 1} if inz else rb",
                  f"{ind2}wb = t * t * (3.0 - 2.0 * t) if inz else wb"]
    L += [f"{ind2}RA[p] = ra", f"{ind2}RB[p] = rb", f"{ind2}WB[p] = wb"]
    L.append(f"{ind1}bp.counter[0] += outside")
    passes[-1].append(len(L))
    # 2. each region's entries (state, weight), in state order; PA[p], PB[p]: where state p's results go
    # (every state has two entries, its second region's possibly the bucket nr that is never evaluated: 2 n)
    L += [f"{ind1}start = si[6 * n:6 * n + {nr + 2}]",
          f"{ind1}ent = si[4 * n:6 * n]", f"{ind1}went = s64[3 * n:5 * n]",
          f"{ind1}YE1 = s64[5 * n:7 * n + 1]", f"{ind1}YE2 = s64[7 * n + 1:9 * n + 2]",
          f"{ind1}YE1[2 * n] = 0.0", f"{ind1}YE2[2 * n] = 0.0"]
    passes.append([len(L)])
    # a counting sort whose per-bucket counters are local variables (registers), one per bucket 0..nr
    # (known here), chosen by selects: counters in an array (fill[RA[p]] += 1) chained every state through
    # a store and a reload, 7.5 ns per state of the best-shaped kernel's ~45 ns per force
    buckets = range(nr + 1)
    L += [f"{ind1}c{b} = 0" for b in buckets]
    L += [f"{ind1}for p in range(n):", f"{ind2}ra = RA[p]", f"{ind2}rb = RB[p]"]
    L += [f"{ind2}c{b} += (1 if ra == {b} else 0) + (1 if rb == {b} else 0)" for b in buckets]
    L += [f"{ind1}start[0] = 0"] + [f"{ind1}start[{b + 1}] = start[{b}] + c{b}" for b in buckets]
    L += [f"{ind1}k{b} = start[{b}]" for b in buckets]

    def pick(var: str, last: int) -> str:  # the counter of bucket var's value, of buckets 0..last
        expr = f"k{last}"
        for b in reversed(range(last)):
            expr = f"k{b} if {var} == {b} else ({expr})"
        return expr

    L += [f"{ind1}for p in range(n):", f"{ind2}ra = RA[p]", f"{ind2}k = {pick('ra', nr - 1)}",
          f"{ind2}ent[k] = p", f"{ind2}went[k] = 1.0 - WB[p]", f"{ind2}PA[p] = k"]
    L += [f"{ind2}k{b} += 1 if ra == {b} else 0" for b in range(nr)]
    L += [f"{ind2}rb = RB[p]", f"{ind2}k = {pick('rb', nr)}", f"{ind2}ent[k] = p", f"{ind2}went[k] = WB[p]",
          # the second region's result; none (the extra bucket, not evaluated): the zero after the last entry
          f"{ind2}PB[p] = k if rb < {nr} else start[{nr + 1}]"]
    L += [f"{ind2}k{b} += 1 if rb == {b} else 0" for b in buckets]
    passes[-1].append(len(L))
    # 3. each region's network on tiles of its states
    o0 = f"{n_in + 5} * n"
    offs = np.cumsum([0, n_in * TILE, TILE, TILE, TILE, width * TILE, width * TILE, width])
    L += [f"{ind1}T = sw[{o0} + {offs[0]}:{o0} + {offs[1]}].reshape(({n_in}, {TILE}))",
          f"{ind1}Y1t = sw[{o0} + {offs[1]}:{o0} + {offs[2]}]", f"{ind1}Y2t = sw[{o0} + {offs[2]}:{o0} + {offs[3]}]",
          f"{ind1}acc = sw[{o0} + {offs[3]}:{o0} + {offs[4]}]",
          f"{ind1}HA = sw[{o0} + {offs[4]}:{o0} + {offs[5]}].reshape(({width}, {TILE}))",
          f"{ind1}HB = sw[{o0} + {offs[5]}:{o0} + {offs[6]}].reshape(({width}, {TILE}))"]
    if n_extra:
        L.append(f"{ind1}wx = sw[{o0} + {offs[6]}:{o0} + {offs[7]}]")
    for r, region in enumerate(regions):
        passes.append([len(L)])
        kind, power = region.kind, region.power
        layers = list(layout[r])
        ind3 = ind1 + "    "
        # a region's last tile is partial: its states are padded with zero inputs to a whole number of
        # vector lanes (LANE), so that the networks' loops run no scalar remainder (a half batch per thread
        # has as many partial tiles as a whole one: ~12 % per state at 512 states before); only the m real
        # states' results are kept
        L += [f"{ind1}for t0 in range(start[{r}], start[{r + 1}], {TILE}):",
              f"{ind3}mr = min({TILE}, start[{r + 1}] - t0)",
              f"{ind3}m = min({TILE}, (mr + {LANE - 1}) // {LANE} * {LANE})",
              f"{ind3}for j in range(mr):", f"{ind3}    p = ent[t0 + j]"]
        L += [f"{ind3}    T[{i}, j] = Z[{i}, p]" for i in range(n_in)]
        L += [f"{ind3}for j in range(mr, m):"] + [f"{ind3}    T[{i}, j] = 0.0" for i in range(n_in)]
        n_tot = layers[0][3]
        if n_extra:
            # the extra inputs (the sleeve) are the same for every state: folded into the first layer's bias
            wo, bo, n_out0, _ = layers[0]
            L += [f"{ind3}for o in range({n_out0}):", f"{ind3}    wx[o] = w[{bo} + o]"]
            for k in range(n_extra):
                L += [f"{ind3}    wx[o] += w[{wo} + o * {n_tot} + {n_in + k}] * bp.setting[{1 + k}]"]
        L += _batch_net_source(layers, _batch_unit(act), ind3, n_in, "wx[o]" if n_extra else "w[{bo} + o]")
        ob = 4 + nb + 3 * n_dom + nr + 2 * r
        L += [f"{ind3}ob1 = q[{ob}]", f"{ind3}ob2 = q[{ob + 1}]"]
        gain = "went[t0 + j]"
        if physics and not uniform_gain:
            gain += (f" * DD[p] ** -q[{4 + nb + 3 * n_dom + r}]" if power is None
                     else f" / ({_power_source('DD[p]', power)})")
            if kind == KIND_PHYSICS_V:
                gain += " * KV[p]"
        L += [f"{ind3}for j in range(mr):"]
        if gain != "went[t0 + j]":
            L.append(f"{ind3}    p = ent[t0 + j]")
        L += [f"{ind3}    gw = {gain}",
              f"{ind3}    YE1[t0 + j] = gw * (Y1t[j] + ob1)", f"{ind3}    YE2[t0 + j] = gw * (Y2t[j] + ob2)"]
        passes[-1].append(len(L))
    # 4. per state in order: its one or two regions' results, the gain and the frame back
    passes.append([len(L)])
    L += [f"{ind1}for p in range(n):", f"{ind2}y1 = YE1[PA[p]] + YE1[PB[p]]", f"{ind2}y2 = YE2[PA[p]] + YE2[PB[p]]"]
    if physics:
        L += [f"{ind2}f1 = y1 * G[p]", f"{ind2}f2 = y2 * G[p]"]
    else:
        L += [f"{ind2}f1 = y1", f"{ind2}f2 = y2"]
    if polar:
        L += [f"{ind2}out[p, 0] = f1 * E1[p] + f2 * E2[p]", f"{ind2}out[p, 1] = f1 * E2[p] - f2 * E1[p]"]
    else:
        L += [f"{ind2}out[p, 0] = f1", f"{ind2}out[p, 1] = f2"]
    passes[-1].append(len(L))
    L[0] = "def _states_block(bp, x, v, out):"
    return _outline_passes(L, passes) + f"""
def batch_kernel(bp, x, v, out):
    n = x.shape[0]
    if n <= {WORKSPACE_STATES}:
        _states_block(bp, x, v, out)
        return
    for s0 in range(0, n, {WORKSPACE_STATES}):
        e = min(n, s0 + {WORKSPACE_STATES})
        _states_block(bp, x[s0:e], v[s0:e], out[s0:e])
"""


def _outline_passes(L: list[str], passes: list[list[int]]) -> str:
    """The kernel's lines ``L`` with each pass (``L[a:b]`` for ``[a, b]`` in ``passes``, in order) moved
    into a function of its own, ``_pass{i}``, which the kernel calls with the names the pass reads from it.

    Why: in one function holding every pass, LLVM vectorised the passes' loops worse; the same loops as
    separate functions run faster (docs/fast_surrogates.md has the timings), with the same results to the bit.
    A pass's arguments are the names it loads that the kernel assigned before it (or the kernel's own
    arguments), less the names it assigns itself: no pass writes a name a later one reads (they
    communicate through the arrays), which ``test_surrogate_kernels`` checks by comparing every shape's
    kernel with the generic one."""
    import ast
    import textwrap

    def names(lines: list[str]) -> tuple[set[str], set[str]]:
        tree = ast.parse(textwrap.dedent("\n".join(lines)))
        loaded: set[str] = set()
        stored: set[str] = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.Name):
                (stored if isinstance(node.ctx, ast.Store) else loaded).add(node.id)
        return loaded, stored

    head = L[0]
    kernel_args = [a.strip() for a in head[head.index("(") + 1:head.index(")")].split(",")]
    helpers: list[str] = []
    body: list[str] = []
    pos = 0
    for i, (a, b) in enumerate(passes):
        body += L[pos:a]
        _, before = names(body[1:])  # what the kernel itself assigned so far (not the earlier passes' locals)
        loaded, stored = names(L[a:b])
        args = sorted((loaded & (before | set(kernel_args))) - stored)
        helpers += [f"def _pass{i}({', '.join(args)}):"] + L[a:b] + ["    return 0", ""]
        body.append(f"    _pass{i}({', '.join(args)})")
        pos = b
    body += L[pos:]
    return "\n".join(helpers + body) + "\n"


#: (an older name of ``activations.relu64``)
_relu = relu64




_COMPILED_BATCH: dict[tuple, Any] = {}


def _exec_batch_kernel(key, dtype: str):
    """The batched kernel compiled from its source in this process only (no on-disk cache)."""
    source = batch_kernel_source(key, dtype)
    f32 = dtype == "float32"
    namespace: dict[str, Any] = {"__name__": "fluidfilm_generated", "math": math, "np": np, **_batch_units(f32)}
    exec(compile(source, f"<surrogate batch kernel {len(_COMPILED_BATCH)}>", "exec"), namespace)
    jit = njit(error_model="numpy", fastmath={"contract", "reassoc"}, nogil=True)
    # the passes, each compiled on its own, and the block that calls them
    for name in [k for k in namespace if k.startswith(("_pass", "_states_block"))]:
        namespace[name] = jit(namespace[name])
    return jit(namespace["batch_kernel"])


def batch_kernel(key, dtype: str = "float64"):
    """The batched kernel of a model shape (``batch_shape_key``) with its networks in ``dtype``, compiled
    once per process (``batch_kernel_source``); numba compiles it on its first call.

    The source is written as a module into ``kernel_cache_dir()`` (named by the hash of its text, written
    atomically) and imported from there with numba's ``cache=True``: the first call in a later process loads
    the compiled code instead of compiling it (seconds), with the same flags and so the same bits.  Where
    the folder cannot be written (or ``FLUIDFILM_KERNEL_CACHE=off``) the source is compiled in the process,
    as before the cache existed.

    Parameters
    ----------
    key : tuple
        ``batch_shape_key(model)`` (not None).
    dtype : {"float64", "float32"}, default "float64"
        The networks' arithmetic (``tanh64`` or ``tanh32``).

    Returns
    -------
    numba dispatcher
        ``fn(bp, x, v, out)``: ``forces_batch``'s signature, ``bp`` a ``FastBatchParams``.
    """
    fn = _COMPILED_BATCH.get((key, dtype))
    if fn is None:
        source = batch_kernel_source(key, dtype)
        header = ["import math", "", "import numpy as np", "from numba import njit", ""] + [
            f"from fluidfilm.surrogate.activations import {unit_name(a, dtype == 'float32')} as {_batch_unit(a)}"
            for a in ACTIVATIONS]
        # the passes, each compiled on its own, then the block that calls them and the kernel (as below)
        helpers = [name for name in re.findall(r"^def (\w+)\(", source, flags=re.M)
                   if name.startswith(("_pass", "_states_block"))] + ["batch_kernel"]
        fn = _cached_module_function(source, "batch", helpers, header, 'njit(error_model="numpy", '
                                     'fastmath={"contract", "reassoc"}, nogil=True, cache=True)')
        path = getattr(fn, "__fluidfilm_file__", None)
        if fn is None or path is None:
            fn = _exec_batch_kernel(key, dtype)
        _COMPILED_BATCH[(key, dtype)] = fn
        kernel_files[(key, dtype)] = path
    return fn
