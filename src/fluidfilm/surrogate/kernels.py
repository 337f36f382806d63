"""The surrogates' fast force kernels: one compiled function per model shape, and a batched kernel.

``inference.surrogate_force`` is the generic kernel: it reads its layer
table, region count and scaling codes at run time, standardises the inputs,
evaluates ``tanh`` through one scalar ``exp`` per unit (which never
vectorises here: numba has no SVML on this machine) and checks every
division for zero (numba's default ``error_model="python"``).  This module
holds what the integrator runs instead:

- ``fast_force_kernel(model)`` -> ``(fn, params)`` with the generic
  kernel's signature ``fn(params, x1, x2, v1, v2) -> (F1, F2)``.  ``fn`` is
  compiled from source generated for the model's *shape* (regions, frames,
  scaling kinds, layer widths, activation, blending, domain rows): widths
  and offsets are literal constants, the regions' bodies are written out
  one by one, ``error_model="numpy"``.  The weights sit in one flat array
  of ``params`` with the input standardisation folded into the first
  layer and the output un-standardisation into the last, so every model of
  one shape (an ensemble's members) shares one compiled function.  ``tanh``
  is ``tanh64``: a [9/8] Pade approximant at x/4 doubled twice, pure
  arithmetic (it vectorises over a layer) and within 1.5e-15 relative of
  ``math.tanh`` (tests/test_surrogate_kernels.py states and checks the
  bound), so the fast kernel equals the generic one to round-off.
  ``fast_force_kernel(model, "float32")`` is the same source with the networks in float32 (inputs rounded,
  weights and scratch read from the parameter vector's float32 copy, ``tanh32``, outputs widened back):
  forces within 1e-5 of float64 relative to the larger of |F| and the RMS force of the states (tested),
  1.7-1.9x faster per force on the best model's and the universal model's shapes (``make bench``,
  ``universal_evaluate``; ``simulate(precision="float32")``; the float64 kernel stays the default).
- ``forces_batch(bparams, x, v, out)``: many states at once: each state
  routed to its region (a state in a blend zone to both neighbours),
  each region's network run on tiles of states as dense products with the
  states along the vector lanes, then blended and turned back into the
  (X1, X2) frame.  float64 by default; ``batch_params(model, "float32")``
  runs the network arithmetic in float32 with Eigen's rational ``tanh32``
  (within 4e-7 relative of ``math.tanh``), forces within 1e-5 relative of
  float64 (tested).  SiLU and sigmoid units go through the same rational
  tanh (``silu64``, ``sigmoid64``, ``silu32``, ``sigmoid32``), never a
  scalar ``math.exp``.  The universal networks' ``pade_tanh`` units
  (``surrogate.activations``: tanh's [5/4] Pade approximant as the activation
  itself) are ``pade_tanh64`` / ``pade_tanh32``: 6 vector operations and a
  division, and no approximation error: each is the function itself, to the
  round-off of its precision.
- ``batch_kernel(batch_shape_key(model), dtype)``: the batched kernel generated per model shape, what
  ``simulate_batch`` calls once per RK4 stage (``forces_batch``'s signature; ``fast_batch_params`` makes
  its parameters): per state in order the inputs, frame and gain without a branch (vectorised), the
  domain count and region(s) as selects, a counting sort by region, each region's network on tiles with
  literal widths and its last hidden layer fused with the output layer, then the blend, gain and frame
  per state.  Equal to the generic kernel to round-off (float64; one reciprocal per division) or within
  1e-5 relative (float32 networks), tested on every surrogate shape of the test models.

The training-domain counter keeps its meaning: every evaluation outside the
domain adds one to the model's counter, exactly as the generic kernel
counts (the count is a few scalar compares per call, written without
early exits; the per-unit loops that vectorise are not touched by it).  It
stays inside the kernel because every caller (``simulate``,
``simulate_batch``, the ensemble's members) reports that count.

The generated one-state functions live in no importable module, so numba cannot
cache them on disk: the integrator runs them through its uncached loops
(``rotor.integrate._library_types`` is False for them).  Compiling the best
model's shape (five regions, 3-64-2) took 1.5-1.9 s on the 2-core project
machine under load (``compile_seconds`` records each one-state kernel's), and the
integrator's uncached loop about 1 s more on the first ``simulate`` of a
process; a model of a shape already compiled in the process costs neither.
The batched kernels (``batch_kernel``) are written as modules into a cache folder
(``kernel_cache_dir``: ``~/.cache/fluidfilm/kernels`` by default) and imported with
``cache=True``, so a later process loads them instead of compiling them.
"""
from __future__ import annotations

import math
import re
import time
from typing import Any, NamedTuple

import numpy as np
from numba import njit, types
from numba.extending import intrinsic

from fluidfilm.core.force_model import check_precision
from fluidfilm.surrogate.activations import (ACTIVATIONS, pade_tanh32, pade_tanh64, relu64, sigmoid32,
                                             sigmoid64, silu32, silu64, tanh32, tanh64, unit32, unit64, unit_name,
                                             unit_names)
from fluidfilm.surrogate.contract import (FRAME_POLAR, FRAME_WHIRL, KIND_PHYSICS, KIND_PHYSICS_V, REGION_CLEARANCE,
                                         REGION_FORCE_SCALE, REGION_FRAME, REGION_KIND, REGION_N_EXTRA, REGION_OMEGA,
                                         REGION_POWER, REGION_SLEEVE, ROW_CLEARANCE, ROW_FRAME, ROW_IN_MEAN,
                                         ROW_IN_STD, ROW_KIND, ROW_N_EXTRA, ROW_OMEGA, ROW_OUT_MEAN, ROW_OUT_STD,
                                         ROW_POWER, ROW_SLEEVE, SLEEVE_AWARE, region_row)

__all__ = ["tanh64", "tanh32", "silu64", "silu32", "sigmoid64", "sigmoid32", "pade_tanh64", "pade_tanh32", "fast_force_kernel", "shape_key", "pack", "kernel_source", "one_state_function", "compiled_kernel",
           "compile_seconds", "BatchParams", "batch_params", "forces_batch", "TILE", "FastBatchParams",
           "batch_shape_key", "fast_batch_params", "batch_kernel_source", "batch_kernel", "with_workspace",
           "WORKSPACE_STATES"]

# ---------------------------------------------------------------------------------------------- folding

def _fold_network(layers, in_mean, in_std, out_mean=None, out_std=None, out_rows=None):
    """Layers [(W (out, in), b)] with z = (raw - in_mean)/in_std folded into the first layer and, when
    given, y = out_std[row] * y + out_mean[row] into the last (``out_rows``: which output scale each row
    takes; ``out_mean`` None: the rows are only scaled)."""
    folded = [(np.array(W, dtype=np.float64), np.array(b, dtype=np.float64)) for W, b in layers]
    W, b = folded[0]
    mean = np.asarray(in_mean, dtype=np.float64)[:W.shape[1]]
    std = np.asarray(in_std, dtype=np.float64)[:W.shape[1]]
    folded[0] = (W / std[None, :], b - (W / std[None, :]) @ mean)
    if out_std is not None:
        W, b = folded[-1]
        s = np.asarray(out_std, dtype=np.float64)[out_rows]
        m = np.zeros_like(s) if out_mean is None else np.asarray(out_mean, dtype=np.float64)[out_rows]
        folded[-1] = (W * s[:, None], b * s + m)
    return folded


def _folded_networks(model):
    """Per region: (static layers, damping layers or []) with the scalings folded in (module doc)."""
    out = []
    for net, sc in zip(model.networks, model.scalings):
        row = sc.kernel_row()
        n_in = len(sc.in_mean)
        mean, std = row[ROW_IN_MEAN:ROW_IN_MEAN + n_in], row[ROW_IN_STD:ROW_IN_STD + n_in]
        om, os_ = row[ROW_OUT_MEAN:ROW_OUT_MEAN + 2], row[ROW_OUT_STD:ROW_OUT_STD + 2]
        if model.structure == "plain":
            out.append((_fold_network(net, mean, std, om, os_, [0, 1]), []))
        else:
            # y = out_std (S + C w) + out_mean: the mean goes with S, the scale with both (C's rows 0, 1
            # make y1 and rows 2, 3 make y2)
            static, damping = net
            out.append((_fold_network(static, mean, std, om, os_, [0, 1]),
                        _fold_network(damping, mean, std, None, os_, [0, 0, 1, 1])))
    return out


def power_form(power: float) -> float | None:
    """The physics scaling's exponent p of (1 - eps^2)^p as the compiled kernels take it: a multiple of 1/2
    up to 6 is built into the code as products and one square root (``_power_source``); any other is None,
    a run-time ``**`` (a generic pow costs about as much as a quarter of a 3-64-2 network here).

    >>> power_form(1.5), power_form(2), power_form(1.7)
    (1.5, 2.0, None)
    """
    twice = 2.0 * power
    return float(power) if twice == round(twice) and 0.0 <= power <= 6.0 else None


def _power_source(x: str, power: float) -> str:
    """Source of x**power for a ``power_form`` exponent: x * x * math.sqrt(x) for 2.5, 1.0 for 0.

    >>> _power_source("d", 1.5), _power_source("d", 2.0), _power_source("d", 0.0)
    ('d * math.sqrt(d)', 'd * d', '1.0')
    """
    n = int(power)
    terms = [x] * n + ([f"math.sqrt({x})"] if power - n == 0.5 else [])
    return " * ".join(terms) if terms else "1.0"


class RegionKey(NamedTuple):
    """One region of a ``ShapeKey``: what its compiled code depends on (codes of ``surrogate.contract``)."""

    kind: int          # ``ROW_KIND`` code: 0 affine, 1 physics, 2 physics_v
    frame: int         # ``ROW_FRAME`` code: 0 cartesian, 1 polar, 2 whirl
    n_extra: int       # extra inputs (the sleeve)
    sleeve: bool       # the clearance follows the sleeve
    power: float | None  # ``power_form`` of the physics gain's exponent (None: a run-time power)
    static: tuple      # (n_out, n_in) of each layer of the network
    damping: tuple     # the same for the damping-matrix network (empty: plain structure)


class ShapeKey(NamedTuple):
    """What a compiled kernel depends on (``shape_key``); a tuple, so equal to and hashed as one."""

    structure: str     # "plain" or "damping"
    activation: str    # a registered activation's name
    regions: tuple     # a ``RegionKey`` per region
    n_boundaries: int
    blending: bool     # blend_width > 0
    n_domain: int      # rows of the training domain


def shape_key(model) -> ShapeKey:
    """What the compiled one-state kernel depends on (everything else is in its parameter vector)."""
    regions = []
    for net, sc in zip(model.networks, model.scalings):
        static, damping = (net, []) if model.structure == "plain" else net
        row = sc.kernel_row()
        regions.append(RegionKey(int(row[ROW_KIND]), int(row[ROW_FRAME]), int(row[ROW_N_EXTRA]),
                                 bool(row[ROW_SLEEVE] == SLEEVE_AWARE), power_form(float(row[ROW_POWER])),
                                 tuple(np.shape(W) for W, _ in static), tuple(np.shape(W) for W, _ in damping)))
    return ShapeKey(model.structure, model.activation, tuple(regions), len(model.boundaries), model.blend_width > 0.0,
                    int(np.shape(model.domain)[0]))


# ---------------------------------------------------------------------------------------------- one state

#: the parameter vector's head: [1/c^2, sleeve] (the model's setting), the domain counter, eps_max, blend
SETTING, COUNTER, EPS_MAX, BLEND, HEAD = 0, 2, 3, 4, 5


class Layout:
    """Where each part sits in the one-state kernel's parameter vector (the same for every model of a shape).

    One float64 vector holds everything the kernel reads, the model's mutable setting and domain counter
    included (the model's ``setting_array`` and counter are views of it): numba passes an array argument
    without reference counting, while each array taken out of a tuple costs an atomic increment and
    decrement per call (measured: 16 of them, ~60 ns of a ~220 ns force).
    """

    def __init__(self, key):
        structure, act, regions, nb, blending, n_dom = key
        self.bounds = HEAD
        self.domain = self.bounds + nb
        self.regions = self.domain + 3 * n_dom  # per region [c, omega, F_scale, power]
        widths = [shape[0] for r in regions for chain in (r.static, r.damping) for shape in chain]
        self.maxw = max(widths + [1])
        self.scratch = self.regions + 4 * len(regions)  # two rows of maxw hidden activations
        off = self.scratch + 2 * self.maxw
        self.layers = []  # per region, per chain (static, damping): [(W offset, b offset)]
        for r in regions:
            region = []
            for chain in (r.static, r.damping):
                offs = []
                for n_out, n_in in chain:
                    offs.append((off, off + n_out * n_in))
                    off += n_out * n_in + n_out
                region.append(offs)
            self.layers.append(region)
        self.size = off
        # with the float32 copy of the first ``size`` entries behind them (``pack``, ``float32_tail``)
        self.total = off + (off + 1) // 2


def pack(model, key=None) -> np.ndarray:
    """The one-state kernel's parameter vector of ``model`` (``Layout``), scalings folded into the weights.

    The setting (1/c^2 of the nominal clearance, sleeve 0) and the counter (0) start fresh; the model makes
    its setting and counter views of this vector.  Behind the ``Layout.size`` float64 entries follows a
    float32 copy of them (``float32_tail``): the weights and scratch of the float32 kernel, so that both
    precisions run on one vector and share the model's setting and counter.
    """
    key = shape_key(model) if key is None else key
    lay = Layout(key)
    w = np.zeros(lay.total)
    w[SETTING] = 1.0 / model.bearing.clearance ** 2
    w[EPS_MAX] = model.eps_max
    w[BLEND] = model.blend_width
    nb = len(model.boundaries)
    w[lay.bounds:lay.bounds + nb] = model.boundaries
    w[lay.domain:lay.regions] = np.asarray(model.domain, dtype=np.float64).ravel()
    for r, ((static, damping), sc) in enumerate(zip(_folded_networks(model), model.scalings)):
        w[lay.regions + 4 * r:lay.regions + 4 * r + 4] = [sc.clearance, sc.omega, sc.force_scale, sc.power]
        for layers, offs in zip((static, damping), lay.layers[r]):
            for k, ((W, b), (wo, bo)) in enumerate(zip(layers, offs)):
                # the first layer is axpy updates vectorised over its outputs (columns contiguous); the
                # others are dot products over the previous layer's units (rows contiguous): a reduction
                # that reads the parameter vector only, which vectorises (an axpy there would read and write
                # the same vector, which LLVM does not vectorise: 75x slower at 64 x 64)
                stored = W.T if k == 0 and len(layers) > 1 else W
                w[wo:bo] = np.ascontiguousarray(stored).ravel()
                w[bo:bo + b.size] = b
    w[lay.size:].view(np.float32)[:lay.size] = w[:lay.size]
    return w


@intrinsic
def float32_tail(typingctx, w, start):
    """A float32 pointer to the bytes of ``w`` from float64 index ``start`` on (``pack``'s float32 copy).

    An array view (``w[start:].view(np.float32)``) costs a reference-count increment and decrement per call
    (~4 ns of a ~65 ns float32 force, measured); the pointer borrows ``w``'s memory, which the caller holds.
    """
    if not (isinstance(w, types.Array) and w.dtype == types.float64 and w.ndim == 1 and w.layout == "C"
            and isinstance(start, types.Integer)):
        return None  # a typing error naming the arguments, not a failure in code generation
    sig = types.CPointer(types.float32)(w, start)

    def codegen(context, builder, signature, args):
        data = context.make_array(signature.args[0])(context, builder, args[0]).data
        return builder.bitcast(builder.gep(data, [args[1]]), context.get_value_type(signature.return_type))
    return sig, codegen


def _act_expr(act: str, x: str, f32: bool = False) -> str:
    """The activation's call in generated source: its compiled unit by name (``activations.unit_name``)."""
    return f"{unit_name(act, f32)}({x})"


def _net_source(chain, offs, inputs, act, lay, ind, out_names, base="", f32=False):
    """Source lines evaluating one folded network (layer shapes ``chain``) on the named scalar inputs
    (as many leading ones as its first layer takes: the generic kernel's rule) into ``out_names``.
    ``base``: an expression added to every weight offset ("off + ": the region's weights found at run time,
    ``_uniform_kernel_source``); the scratch rows are not moved.  ``f32``: the network in float32, its
    weights and scratch read from ``v`` (the parameter vector's float32 copy, ``pack``), the inputs rounded
    to float32 and the outputs widened back to float64 (float64 arithmetic around the network, as in the
    batched kernel's float32 path)."""
    if base:
        offs = [(f"{base}{wo}", f"{base}{bo}") for wo, bo in offs]
    if not f32:
        return _net_lines(chain, offs, inputs, act, lay, ind, out_names, "w", False)
    n_used = chain[0][1]
    sums = [f"s_{name}" for name in out_names]
    return ([f"{ind}s_{name} = np.float32({name})" for name in inputs[:n_used]]
            + _net_lines(chain, offs, [f"s_{name}" for name in inputs], act, lay, ind, sums, "v", True)
            + [f"{ind}{name} = float({total})" for name, total in zip(out_names, sums)])


def _net_lines(chain, offs, inputs, act, lay, ind, out_names, arr, f32):
    """``_net_source``'s body: weights and scratch in the array ``arr``."""
    def at(o, k):  # offset o (a number, or an expression with base) plus the literal k
        return f"{o} + {k}" if isinstance(o, str) else o + k

    lines = []
    src = None  # offset of the previous layer's activations in the scratch rows
    h = lay.scratch
    for k, ((n_out, n_in), (wo, bo)) in enumerate(zip(chain, offs)):
        if k == len(chain) - 1:
            for j, name in enumerate(out_names):
                if src is None:
                    terms = " + ".join(f"{arr}[{at(wo, j * n_in + i)}] * {inputs[i]}" for i in range(n_in))
                    lines.append(f"{ind}{name} = {arr}[{at(bo, j)}] + {terms}")
                else:
                    lines.append(f"{ind}{name} = {arr}[{at(bo, j)}]")
            if src is not None:
                lines.append(f"{ind}for i in range({n_in}):")
                lines.append(f"{ind}    hi = {arr}[{src} + i]")
                for j, name in enumerate(out_names):
                    lines.append(f"{ind}    {name} += {arr}[{at(wo, j * n_in)} + i] * hi")
            break
        dst = h if src != h else h + lay.maxw
        lines.append(f"{ind}for o in range({n_out}):")
        if src is None:
            terms = " + ".join(f"{arr}[{at(wo, i * n_out)} + o] * {inputs[i]}" for i in range(n_in))
            lines.append(f"{ind}    a = {arr}[{bo} + o] + {terms}")
        else:
            # a dot product per output over the previous layer (``pack``: rows contiguous), then the
            # activation over the layer in a loop of its own (which vectorises)
            lines.append(f"{ind}    a = {arr}[{bo} + o]")
            lines.append(f"{ind}    for i in range({n_in}):")
            lines.append(f"{ind}        a += {arr}[{wo} + o * {n_in} + i] * {arr}[{src} + i]")
            lines.append(f"{ind}    {arr}[{dst} + o] = a")
            lines.append(f"{ind}for o in range({n_out}):")
            lines.append(f"{ind}    a = {arr}[{dst} + o]")
        lines.append(f"{ind}    {arr}[{dst} + o] = {_act_expr(act, 'a', f32)}")
        src = dst
    return lines


def _frame_source(frame, ind):
    """Lines of the polar (frame 1) or whirl (frame 2) frame from x1, x2, v1, v2, c, omega: the unit vectors
    er1, er2, the inputs z0, z1, z2 and, in the whirl frame, the drive |u| (``inference._region_force``)."""
    # one reciprocal per divisor (as the batched kernel), 1/c from 1/(c omega): divisions off a state's
    # critical path (~6 ns of a ~130 ns float64 force here); the forces move by round-off (7e-16 relative)
    L = [f"{ind}s2 = x1 * x1 + x2 * x2", f"{ind}rr = math.sqrt(s2)", f"{ind}at0 = 1.0 if s2 == 0.0 else 0.0",
         f"{ind}x2e = x2 + at0", f"{ind}inv = 1.0 / (rr + at0)", f"{ind}er1 = x1 * inv", f"{ind}er2 = x2e * inv",
         f"{ind}icw = 1.0 / (c * omega)", f"{ind}ic = omega * icw", f"{ind}z0 = rr * ic"]
    if frame == FRAME_WHIRL:
        # the drive u = (z0 - 2 z2, 2 z1) times rr: the same direction without the division by rr on the way
        # to the network's inputs (the critical path of a one-state force; ~3 ns of ~70 with float32 networks)
        L += [f"{ind}ua = s2 * ic - 2.0 * (v1 * x2e - v2 * x1) * icw", f"{ind}ub = 2.0 * (v1 * x1 + v2 * x2e) * icw",
              f"{ind}n2 = ua * ua + ub * ub", f"{ind}nd = math.sqrt(n2)", f"{ind}zero = 1.0 if n2 == 0.0 else 0.0",
              f"{ind}invd = 1.0 / (nd + zero)", f"{ind}z1 = ua * invd + zero", f"{ind}z2 = ub * invd",
              f"{ind}drive = nd * inv"]
    else:
        L += [f"{ind}z1 = (v1 * er1 + v2 * er2) * icw", f"{ind}z2 = (v1 * er2 - v2 * er1) * icw"]
    return L


def _region_source(r, region_key, act, lay, ind, f32=False):
    """The body of region r: inputs from the state, the network(s), the gain and the frame back.
    Mirrors ``inference._region_force`` step by step (the generic kernel is the specification)."""
    kind, frame, n_extra, sleeve, power, static, damping = region_key
    physics = kind >= KIND_PHYSICS
    polar = frame >= FRAME_POLAR
    rc = lay.regions + 4 * r
    L = [f"{ind}c = w[{rc}]", f"{ind}omega = w[{rc + 1}]", f"{ind}fscale = w[{rc + 2}]"]
    if sleeve:
        # sleeve-aware: normalise by the current clearance c_r; forces scale as (c/c_r)^2
        L += [f"{ind}fscale = fscale * c * c * inv_c2", f"{ind}c = 1.0 / math.sqrt(inv_c2)"]
    if polar:
        L += _frame_source(frame, ind)
        inputs = ["z0", "z1", "z2"]
    elif physics:
        L += [f"{ind}z0 = x1 / c", f"{ind}z1 = x2 / c", f"{ind}z2 = v1 / (c * omega)", f"{ind}z3 = v2 / (c * omega)"]
        inputs = ["z0", "z1", "z2", "z3"]
    else:
        inputs = ["x1", "x2", "v1", "v2"]
    for k in range(n_extra):
        L.append(f"{ind}e{k} = w[{SETTING + 1 + k}]")  # extra inputs (the sleeve) come from the setting
        inputs.append(f"e{k}")
    L += _net_source(static, lay.layers[r][0], inputs, act, lay, ind, ["y1", "y2"], f32=f32)
    if damping:
        # y = S(position inputs) + C(all inputs) w, w the raw velocity inputs (units of c omega)
        L += _net_source(damping, lay.layers[r][1], inputs, act, lay, ind, ["d0", "d1", "d2", "d3"], f32=f32)
        w1, w2 = inputs[len(inputs) - 2], inputs[len(inputs) - 1]
        L += [f"{ind}y1 += d0 * {w1} + d1 * {w2}", f"{ind}y2 += d2 * {w1} + d3 * {w2}"]
    if physics:
        L.append(f"{ind}d = 1.0 - e2")
        L.append(f"{ind}g = fscale / d ** w[{rc + 3}]" if power is None else f"{ind}g = fscale / ({_power_source('d', power)})")
        if kind == KIND_PHYSICS_V:
            L.append(f"{ind}g *= 1.0 + math.sqrt(v1 * v1 + v2 * v2) / (c * omega)")
        if frame == FRAME_WHIRL:
            L.append(f"{ind}g *= drive")
        L += [f"{ind}y1 *= g", f"{ind}y2 *= g"]
    if polar:
        L += [f"{ind}g1 = y1 * er1 + y2 * er2", f"{ind}g2 = y1 * er2 - y2 * er1"]
    else:
        L += [f"{ind}g1 = y1", f"{ind}g2 = y2"]
    return L


def _uniform(key) -> bool:
    """Whether every region of a shape has the same layers, scaling family, frame and exponent, in a polar
    frame, with no sleeve, extra inputs or damping network (``best``, the universal model; not the paper's
    min-max networks):
    then one body serves every region, its weights found at run time (``_uniform_kernel_source``)."""
    structure, act, regions, nb, blending, n_dom = key
    r0 = regions[0]
    kind, frame, n_extra, sleeve, power, static, damping = r0
    return (structure == "plain" and len(set(regions)) == 1 and kind >= KIND_PHYSICS and frame >= FRAME_POLAR and not n_extra
            and not sleeve and not damping and len(static) >= 2)


def _uniform_kernel_source(key, lay, head, f32=False) -> list[str]:
    """The region loop of a ``_uniform`` shape: one body for every region instead of a branch per region.
    The frame (unit vectors, inputs, drive) is computed once for the state with region 0's c and omega and
    again only for a region whose c or omega differ; the region's weights sit at ``k * stride``
    from region 0's (``Layout``).  Region by region the expressions are ``_region_source``'s, so the forces
    are the same to round-off; the branch per region (mispredicted for states that change region) and the
    blend zone's second frame are gone."""
    act, regions = key.activation, key.regions
    kind, frame, _, _, power, static, _ = regions[0]
    offs0 = lay.layers[0][0]
    stride = (lay.layers[1][0][0][0] - offs0[0][0]) if len(regions) > 1 else 0
    ind, ind2 = "    ", "        "

    L = list(head)
    # the frame with region 0's c and omega (the same in every region of ``best`` and the universal model), so
    # that it need not wait for the region's choice; redone below for a region whose c or omega differ
    L += [f"{ind}c = w[{lay.regions}]", f"{ind}omega = w[{lay.regions + 1}]"]
    L += _frame_source(frame, ind)
    L += [f"{ind}d = 1.0 - e2"] + ([] if power is None else [f"{ind}dp = {_power_source('d', power)}"])
    L += [f"{ind}fa1 = 0.0", f"{ind}fa2 = 0.0", f"{ind}fb1 = 0.0", f"{ind}fb2 = 0.0",
          f"{ind}for j in range(n_eval):",
          f"{ind2}k = ra if j == 0 else rb",
          f"{ind2}rc = {lay.regions} + 4 * k",
          f"{ind2}if w[rc] != c or w[rc + 1] != omega:",
          f"{ind2}    c = w[rc]", f"{ind2}    omega = w[rc + 1]"]
    L += _frame_source(frame, ind2 + "    ")
    L += [f"{ind2}fscale = w[rc + 2]", f"{ind2}off = k * {stride}"]
    L += _net_source(static, offs0, ["z0", "z1", "z2"], act, lay, ind2, ["y1", "y2"], base="off + ", f32=f32)
    L.append(f"{ind2}g = fscale / d ** w[rc + 3]" if power is None else f"{ind2}g = fscale / (dp)")
    if kind == KIND_PHYSICS_V:
        L.append(f"{ind2}g *= 1.0 + math.sqrt(v1 * v1 + v2 * v2) / (c * omega)")
    if frame == FRAME_WHIRL:
        L.append(f"{ind2}g *= drive")
    L += [f"{ind2}y1 *= g", f"{ind2}y2 *= g",
          f"{ind2}g1 = y1 * er1 + y2 * er2", f"{ind2}g2 = y1 * er2 - y2 * er1",
          f"{ind2}if j == 0:", f"{ind2}    fa1 = g1", f"{ind2}    fa2 = g2",
          f"{ind2}else:", f"{ind2}    fb1 = g1", f"{ind2}    fb2 = g2",
          f"{ind}if n_eval == 2:",
          f"{ind}    return (1.0 - wb) * fa1 + wb * fb1, (1.0 - wb) * fa2 + wb * fb2",
          f"{ind}return fa1, fa2"]
    return L


def kernel_source(key, precision: str = "float64") -> str:
    """Python source of the one-state kernel of a model shape (``shape_key``), compiled by ``fast_force_kernel``;
    ``precision`` "float32": the networks in float32 (``_net_source``), everything else as in float64."""
    structure, act, regions, nb, blending, n_dom = key
    f32 = check_precision(precision) == "float32"
    lay = Layout(key)
    L = ["def surrogate_kernel(w, x1, x2, v1, v2):"]
    if f32:
        # the float32 copy lies behind the float64 vector (``pack``): a shorter vector would be read past
        L += [f"    if w.shape[0] < {lay.total}:",
              "        raise ValueError('the float32 kernel needs the parameter vector of pack(), with its "
              "float32 copy')",
              f"    v = float32_tail(w, {lay.size})"]
    L += [
         f"    inv_c2 = w[{SETTING}]",
         "    e2 = (x1 * x1 + x2 * x2) * inv_c2",
         "    eps = math.sqrt(e2)",
         # training domain: the first row holding eps (the last one also beyond its top) bounds the velocities
         "    vout = False"]
    for s in reversed(range(n_dom)):
        d = lay.domain + 3 * s
        hit = f"w[{d}] <= eps < w[{d + 1}]" + (f" or eps >= w[{d + 1}]" if s == n_dom - 1 else "")
        L.append(f"    vout = (abs(v1) > w[{d + 2}] or abs(v2) > w[{d + 2}]) if ({hit}) else vout")
    L += [f"    w[{COUNTER}] += 1.0 if (eps > w[{EPS_MAX}] or vout) else 0.0",
          "    r = 0"]
    for b in range(nb):
        L.append(f"    r += 1 if eps >= w[{lay.bounds + b}] else 0")
    L += ["    ra = r", "    rb = r", "    wb = 0.0", "    n_eval = 1"]
    if blending:
        # the blend zone holding eps as selects, then one division: a branch per zone made LLVM compute every
        # zone's weight ahead of its test (five divisions per state: ~7 ns of ~72 with float32 networks)
        L += [f"    half = 0.5 * w[{BLEND}]", "    zone = -1"]
        for b in reversed(range(nb)):  # the first boundary in order wins, as in the generic kernel
            L.append(f"    zone = {b} if w[{lay.bounds + b}] - half <= eps < w[{lay.bounds + b}] + half else zone")
        L += ["    if zone >= 0:",
              f"        t = (eps - (w[{lay.bounds} + zone] - half)) / w[{BLEND}]",
              "        ra = zone", "        rb = zone + 1", "        wb = t * t * (3.0 - 2.0 * t)",
              "        n_eval = 2"]
    if _uniform(key):
        return "\n".join(_uniform_kernel_source(key, lay, L, f32)) + "\n"
    L += ["    fa1 = 0.0", "    fa2 = 0.0", "    fb1 = 0.0", "    fb2 = 0.0",
          "    for j in range(n_eval):",
          "        k = ra if j == 0 else rb",
          "        g1 = 0.0", "        g2 = 0.0"]
    for r in range(len(regions)):
        L.append(f"        {'if' if r == 0 else 'elif'} k == {r}:")
        L += _region_source(r, regions[r], act, lay, " " * 12, f32)
    L += ["        if j == 0:", "            fa1 = g1", "            fa2 = g2",
          "        else:", "            fb1 = g1", "            fb2 = g2",
          "    if n_eval == 2:",
          "        return (1.0 - wb) * fa1 + wb * fb1, (1.0 - wb) * fa2 + wb * fb2",
          "    return fa1, fa2"]
    return "\n".join(L) + "\n"


_COMPILED: dict[tuple, Any] = {}
#: shape key -> seconds its one-state kernel took to compile, in this process
compile_seconds: dict[tuple, float] = {}


def one_state_function(source: str, label: str, units: dict[str, Any] | None = None):
    """The numba dispatcher (not yet compiled) of a one-state kernel's ``source`` (``kernel_source``), with
    ``compiled_kernel``'s flags; ``units`` replaces unit functions by name (``benchmarks/bench_tanh64.py``
    compiles the same source with another tanh)."""
    # a module name outside the package: the integrator takes its uncached loops for this kernel
    # (numba cannot cache a function generated at run time; see rotor.integrate._library_types)
    namespace: dict[str, Any] = {"__name__": "fluidfilm_generated", "math": math, "np": np, **unit_names(),
                                 "float32_tail": float32_tail, **(units or {})}
    exec(compile(source, label, "exec"), namespace)
    return njit(error_model="numpy", fastmath={"contract", "reassoc"})(namespace["surrogate_kernel"])


def compiled_kernel(key, precision: str = "float64"):
    """The one-state kernel of a model shape in ``precision``, compiled once per process (``kernel_source``);
    ``compile_seconds`` records the time under ``key`` (float64) or ``(key, "one-state float32")``.

    As ``batch_kernel``'s, the source is imported from a module in ``kernel_cache_dir()`` with numba's
    ``cache=True`` (same flags, same bits): a later process loads the compiled code instead of compiling it."""
    check_precision(precision)
    name = key if precision == "float64" else (key, f"one-state {precision}")
    fn = _COMPILED.get(name)
    if fn is None:
        source = kernel_source(key, precision)
        fn = _cached_module_function(source, "state", ["surrogate_kernel"], _ONE_STATE_HEADER,
                                     'njit(error_model="numpy", fastmath={"contract", "reassoc"}, cache=True)')
        path = getattr(fn, "__fluidfilm_file__", None)
        if fn is None or path is None:
            fn = one_state_function(source, f"<surrogate kernel {len(_COMPILED)}>")
        t0 = time.perf_counter()
        fn.compile((types.float64[::1], types.float64, types.float64, types.float64, types.float64))
        compile_seconds[name] = time.perf_counter() - t0
        _COMPILED[name] = fn
        kernel_files[name] = path
    return fn


def fast_force_kernel(model, precision: str = "float64"):
    """``(fn, params)``: the one-state kernel of ``model``'s shape and the model's parameter vector.

    Parameters
    ----------
    model : SurrogateForceModel
        Its ``_fast_weights`` (``pack``) is the parameter vector; the model's domain counter and setting
        (sleeve) are views of it, so counting and moving the sleeve work as with the generic kernel.
    precision : {"float64", "float32"}, default "float64"
        The networks' arithmetic: float32 reads the weights from the vector's float32 copy (``pack``) and
        runs ``tanh32``, forces within 1e-5 of float64 relative to the larger of |F| and the states' RMS force (tested); the frame, gains and blend stay
        float64.

    Returns
    -------
    fn : numba dispatcher
        ``fn(params, x1, x2, v1, v2) -> (F1, F2)`` [N], compiled for the model's shape (``shape_key``).
    params : ndarray
        The parameter vector (``Layout``), the same for both precisions.
    """
    return compiled_kernel(model._fast_key, precision), model._fast_weights


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

    The generated kernel otherwise allocates about twenty arrays per call: ~1.9 ns per force at 1024 states
    on the project machine, 3 % of the float32 kernel.

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
        it is allocated once per block) and stays within the cache: at
        N = 16384 and 65536 one pass over all states took twice the time per force of N = 4096 (allocated
        scratch, streamed from memory; measured 92 and 123 ns against 41 ns, float32 best-shaped); blocked,
        50-57 ns, the same bits (every state's arithmetic is independent of the others').
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

    Why: in one function holding every pass, LLVM vectorised the passes' loops worse (the route pass took
    8.5 ns per state inside the kernel against 1.5 ns on its own, the frame pass 10 against 2.5 with
    column-major states); the same loops as separate functions ran the best-shaped float32 kernel in 44 ns
    per force against 52 (1024 states, project machine 2026-12-04), with the same results to the bit.
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
#: kernel name (``compiled_kernel``'s, or (shape key, dtype) of a batched one) -> the module file it was
#: imported from in this process (None: compiled from its source in this process, no on-disk cache:
#: ``FLUIDFILM_KERNEL_CACHE=off`` or a folder that cannot be written)
kernel_files: dict[Any, Any] = {}
batch_kernel_files = kernel_files

#: where the generated kernels are written as modules, numba's cache of each beside it (``kernel_cache_dir``);
#: "off" (or empty) compiles them in every process, as before the cache existed
KERNEL_CACHE_ENV = "FLUIDFILM_KERNEL_CACHE"
_ONE_STATE_HEADER = ["import math", "", "import numpy as np", "from numba import njit", "",
                     "from fluidfilm.surrogate.kernels import float32_tail"] + [
    f"from fluidfilm.surrogate.activations import {name}" for name in sorted(unit_names())]


def kernel_cache_dir():
    """The folder of the generated kernels' modules: ``$FLUIDFILM_KERNEL_CACHE``, else the user's cache
    folder (``platformdirs.user_cache_dir("fluidfilm")/kernels``, e.g. ``~/.cache/fluidfilm/kernels``);
    ``None`` when the variable is ``off`` or empty."""
    import os
    from pathlib import Path

    value = os.environ.get(KERNEL_CACHE_ENV)
    if value is not None:
        return None if value.strip().lower() in ("", "off", "0", "false", "no") else Path(value)
    import platformdirs

    return Path(platformdirs.user_cache_dir("fluidfilm")) / "kernels"


def kernel_module_source(source: str, header: list[str], jit_lines: list[str]) -> str:
    """A generated kernel as the text of an importable module: ``header`` (imports of what ``source`` calls),
    ``source``, then ``jit_lines`` (the compilation, with the in-process flags plus ``cache=True``).  Its first
    lines name what the compiled code depends on besides the text (this file's bytes, through the unit
    functions it inlines, and numba's version), so that the file's name, the hash of the text, changes with
    them."""
    import hashlib
    from pathlib import Path

    import numba

    from fluidfilm.surrogate import activations

    # the unit functions it inlines live in activations.py: both files' bytes name the build
    here = hashlib.sha256(Path(__file__).read_bytes() + Path(activations.__file__).read_bytes()).hexdigest()
    head = ["# Generated by fluidfilm.surrogate.kernels: the kernel of one surrogate shape. numba caches its",
            "# compiled code beside this file (cache=True). Do not edit: the name is the hash of this text.",
            f"# Built against fluidfilm/surrogate/activations.py + kernels.py sha256 {here}, numba {numba.__version__}."]
    return "\n".join(head + header + ["", ""]) + source.rstrip("\n") + "\n\n\n" + "\n".join(jit_lines) + "\n"


def _import_kernel_module(text: str, folder, prefix: str):
    """Write ``text`` to ``folder/<prefix>_<hash>.py`` unless a file of that text is there (created atomically:
    a temporary file hard-linked to the name, so a file once there is never replaced and numba's cache of it
    stays valid), import it as ``fluidfilm_generated.<prefix>_<hash>`` and return the module and its path."""
    import contextlib
    import hashlib
    import importlib.util
    import os
    import sys
    import tempfile
    from pathlib import Path

    digest = hashlib.sha256(text.encode()).hexdigest()[:32]
    folder = Path(folder)
    path = folder / f"{prefix}_{digest}.py"
    if not (path.exists() and path.read_text() == text):
        folder.mkdir(parents=True, exist_ok=True)
        fd, tmp_name = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=".tmp", dir=folder)
        tmp: str | None = tmp_name
        try:
            with os.fdopen(fd, "w") as f:
                f.write(text)
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(tmp_name, 0o666 & ~umask)  # mkstemp makes 0600; the cache is an ordinary file
            try:
                os.link(tmp_name, path)           # atomic, and never over a file another process made
            except FileExistsError:
                if path.read_text() != text:  # damaged: replaced whole (its numba cache is then rebuilt)
                    os.replace(tmp_name, path)
                    tmp = None
        finally:
            if tmp is not None:
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(tmp)
    name = f"fluidfilm_generated.{prefix}_{digest}"
    module = sys.modules.get(name)
    if module is None:
        spec = importlib.util.spec_from_file_location(name, path)
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        try:
            spec.loader.exec_module(module)
        except BaseException:
            del sys.modules[name]
            raise
    return module, path


def _cached_module_function(source: str, prefix: str, helpers: list[str], header: list[str], jit: str):
    """The function ``helpers[-1]`` of ``source`` compiled from a module in ``kernel_cache_dir()`` (``helpers``:
    the source's functions to compile, each on its own, the last one returned; ``jit``: the decorator
    expression), with its file in ``__fluidfilm_file__``; ``None`` without a usable cache folder."""
    folder = kernel_cache_dir()
    if folder is None:
        return None
    jit_lines = [f"_jit = {jit}"] + [f"{name} = _jit({name})" for name in helpers]
    try:
        module, path = _import_kernel_module(kernel_module_source(source, header, jit_lines), folder, prefix)
    except OSError:  # a read-only or full disk: the caller compiles in this process instead
        return None
    fn = getattr(module, helpers[-1])
    fn.__fluidfilm_file__ = path
    return fn


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
