"""The generated one-state kernel: Python source written for one model shape and compiled by numba.

``fast_force_kernel(model)`` -> ``(fn, params)`` with the generic kernel's signature ``fn(params, x1, x2, v1,
v2) -> (F1, F2)`` (``generic.surrogate_force``).  ``fn`` is compiled from source generated for the model's
shape (``folding.shape_key``): widths and offsets are literal constants, the regions' bodies are written out
one by one, ``error_model="numpy"``.  The weights sit in one flat parameter vector (``Layout``, ``pack``)
with the scalings folded in.  ``fast_force_kernel(model, "float32")`` is the same source with the networks
in float32 (inputs rounded, weights and scratch read from the parameter vector's float32 copy, ``tanh32``,
outputs widened back): forces within 1e-5 of float64 relative to the larger of |F| and the RMS force of the
states (tested).  To read a model's source: ``kernel_source(shape_key(model))``, or ``write_kernel_sources``
(``fluidfilm.surrogate.kernels``).
"""
from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
from numba import njit, types
from numba.extending import intrinsic

from fluidfilm.core.force_model import check_precision
from fluidfilm.surrogate.activations import (unit_name,
                                             unit_names)
from fluidfilm.surrogate.contract import (FRAME_POLAR, FRAME_WHIRL, KIND_PHYSICS, KIND_PHYSICS_V)
from fluidfilm.surrogate.kernels.cache import _cached_module_function, kernel_files
from fluidfilm.surrogate.kernels.folding import _folded_networks, _power_source, shape_key


# ---------------------------------------------------------------------------------------------- one state

#: the parameter vector's head: [1/c^2, sleeve] (the model's setting), the domain counter, eps_max, blend
SETTING, COUNTER, EPS_MAX, BLEND, HEAD = 0, 2, 3, 4, 5


class Layout:
    """Where each part sits in the one-state kernel's parameter vector (the same for every model of a shape).

    One float64 vector holds everything the kernel reads, the model's mutable setting and domain counter
    included (the model's ``setting_array`` and counter are views of it): numba passes an array argument
    without reference counting, while each array taken out of a tuple costs an atomic increment and
    decrement per call (what the 16 of them cost: docs/fast_surrogates.md).
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
    (docs/fast_surrogates.md has its cost); the pointer borrows ``w``'s memory, which the caller holds.
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




_ONE_STATE_HEADER = ["import math", "", "import numpy as np", "from numba import njit", "",
                     "from fluidfilm.surrogate.kernels.generated import float32_tail"] + [
    f"from fluidfilm.surrogate.activations import {name}" for name in sorted(unit_names())]


