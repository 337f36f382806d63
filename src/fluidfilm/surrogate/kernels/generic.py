"""The generic one-state kernel ``surrogate_force``: every model shape, its layer tables and codes read at run time.

Same signature as the reference solver's kernels, ``fn(params, x1, x2, v1, v2) -> (F1, F2)`` (``params``: a
``SurrogateParams``, built by the force model from its networks and scalings).  It standardises the inputs,
evaluates the activations in their forms exact to rounding (``activations.exact64``: tanh through one
scalar ``exp``) and checks every division (numba's default ``error_model="python"``): the specification the
fast kernels (``generated``, ``generic_batch``, ``generated_batch``) are tested against, with the NumPy
``reference``.  Routing (split models): region r holds eps in [b_{r-1}, b_r); with ``blend_width`` w > 0
the forces of the two neighbouring networks are mixed with a smoothstep weight over eps in [b - w/2,
b + w/2].  Every evaluation outside the training domain adds one to the model's counter.
"""
from __future__ import annotations

import math
from enum import IntEnum
from typing import NamedTuple

import numpy as np
from numba import njit

from fluidfilm.surrogate.activations import exact64
from fluidfilm.surrogate.contract import (FRAME_POLAR, FRAME_WHIRL, KIND_PHYSICS, KIND_PHYSICS_V, ROW_CLEARANCE,
                                         ROW_FORCE_SCALE, ROW_FRAME, ROW_IN_MEAN, ROW_IN_STD, ROW_KIND, ROW_N_EXTRA,
                                         ROW_OMEGA, ROW_OUT_MEAN, ROW_OUT_STD, ROW_POWER, ROW_SLEEVE, SLEEVE_AWARE)
from fluidfilm.surrogate.transforms import (eps2_nb, film_gain_nb, from_polar_nb, radial_axis_nb, sleeve_force_scale_nb, speed_nb,
                         standardise_nb, to_polar_nb, unstandardise_nb, velocity_factor_nb, whirl_direction_nb)


class Structure(IntEnum):
    """PLAIN: the network gives the force; DAMPING: y = S(position) + C(position, velocity) v."""

    PLAIN = 0
    DAMPING = 1


# plain ints for the compiled code
_DAMPING = int(Structure.DAMPING)


class SurrogateParams(NamedTuple):
    """Parameters of ``surrogate_force``: R networks (regions) and their routing, scaling and domain."""

    # Every region's weights sit in ONE flat array and the layer tables in one (R, L, 4) array: a
    # tuple of per-region arrays indexed by a runtime region number cost ~0.5 us per call in numba
    # (the tuple is materialised and every member reference-counted), more than the network itself.
    weights: np.ndarray       # flat weights of all regions' networks (each W stored transposed)
    tables: np.ndarray        # (R, L, 4) int: per region and layer [weight offset, bias offset, n_in, n_out]
    n_layers: np.ndarray      # (R,) int
    activation: int           # the activation's code (``surrogate.activations.ACTIVATIONS``)
    scalings: np.ndarray      # (R, ROW_LENGTH) ``Scaling.kernel_row()`` of each region (``surrogate.contract``)
    boundaries: np.ndarray    # (R-1,) eccentricity ratios between regions
    blend_width: float        # smoothstep blend across each boundary (0: hard switch)
    domain: np.ndarray        # (S, 3) [eps_low, eps_high, v_max] of the training data
    eps_max: float            # largest eccentricity ratio of the training data
    counter: np.ndarray       # (1,) float64: evaluations outside the domain (mutable; a view of the fast kernel's vector)
    setting: np.ndarray       # (2,) [1/c^2 of the current clearance, sleeve] (mutable)
    max_width: int            # widest layer
    scratch: np.ndarray       # (3, max_width) work rows: two layer buffers and the inputs
    structure: int            # a ``Structure`` value
    damping_tables: np.ndarray  # (R, L, 4) layer tables of the damping-matrix networks (same flat weights)
    damping_n_layers: np.ndarray  # (R,) int


@njit(cache=True, fastmath={"reassoc", "contract"}, inline="always")
def _dense(w, b, src, dst, n_in, n_out):
    """dst = W src + b with W stored transposed (n_in, n_out): axpy updates, vectorised over outputs."""
    for o in range(n_out):
        dst[o] = b[o]
    for i in range(n_in):
        ci = src[i]
        base = i * n_out
        for o in range(n_out):
            dst[o] += w[base + o] * ci


@njit(cache=True, inline="always")
def _activate(buf, n, act):
    """The activation ``act`` (a registry code) over a layer, in its form exact to rounding (``exact64``)."""
    for o in range(n):
        buf[o] = exact64(act, buf[o])


@njit(cache=True, inline="always")
def _mlp(weights, table, n_layers, act, z, buf_a, buf_b):
    """Evaluate one network on the first n_in scaled inputs ``z``; returns the buffer holding its outputs.

    Weights are stored transposed (n_in, n_out) so each layer is a sum of
    axpy updates whose inner loop over outputs is independent and vectorises.
    """
    for k in range(table[0, 2]):
        buf_a[k] = z[k]
    for layer in range(n_layers):
        w_off, b_off, n_in, n_out = table[layer, 0], table[layer, 1], table[layer, 2], table[layer, 3]
        # even layers read buf_a and write buf_b, odd ones the other way round
        src = buf_a if layer % 2 == 0 else buf_b
        dst = buf_b if layer % 2 == 0 else buf_a
        _dense(weights[w_off:b_off], weights[b_off:b_off + n_out], src, dst, n_in, n_out)
        if layer < n_layers - 1:
            _activate(dst, n_out, act)
    return buf_b if n_layers % 2 == 1 else buf_a


@njit(cache=True, inline="always")
def _region_force(params, r, x1, x2, v1, v2, e2, buf_a, buf_b):
    weights, tables, n_layers, act, scal = (params.weights, params.tables, params.n_layers, params.activation,
                                            params.scalings)
    s = scal[r]
    physics = s[ROW_KIND] >= KIND_PHYSICS  # physics or physics_v
    c, omega, fscale, power = s[ROW_CLEARANCE], s[ROW_OMEGA], s[ROW_FORCE_SCALE], s[ROW_POWER]
    if s[ROW_SLEEVE] == SLEEVE_AWARE:
        # sleeve-aware: normalise by the current clearance c_r; forces scale as (c/c_r)^2
        inv_c2 = params.setting[0]
        fscale = sleeve_force_scale_nb(fscale, c, inv_c2)
        c = 1.0 / math.sqrt(inv_c2)
    polar = s[ROW_FRAME] >= FRAME_POLAR  # polar, or whirl (polar with the drive's direction as input)
    z = params.scratch[2]
    er1, er2 = 0.0, 1.0
    drive = 1.0
    if polar:
        # the journal's frame: along (e_r) and across (e_t) the line of centres
        er1, er2 = radial_axis_nb(x1, x2)
        cw = c * omega
        vr, vt = to_polar_nb(er1, er2, v1, v2)
        z[0] = speed_nb(x1, x2) / c  # |X| / c
        z[1] = vr / cw
        z[2] = vt / cw
        if s[ROW_FRAME] == FRAME_WHIRL:
            # the film is homogeneous in its drive u: the network sees u's direction, |u| scales the force
            drive, z[1], z[2] = whirl_direction_nb(z[0], z[1], z[2])
        n_in = 3
    else:
        if physics:
            z[0], z[1], z[2], z[3] = x1 / c, x2 / c, v1 / (c * omega), v2 / (c * omega)
        else:
            z[0], z[1], z[2], z[3] = x1, x2, v1, v2
        n_in = 4
    # extra inputs (the sleeve displacement of an active bearing) come from the control array
    for k in range(int(s[ROW_N_EXTRA])):
        z[n_in] = params.setting[1 + k]
        n_in += 1
    for k in range(n_in):
        z[k] = standardise_nb(z[k], s[ROW_IN_MEAN + k], s[ROW_IN_STD + k])
    out = _mlp(weights, tables[r], n_layers[r], act, z, buf_a, buf_b)
    y1 = out[0]
    y2 = out[1]
    if params.structure == _DAMPING:
        # damping structure: y = S(position) + C(position, velocity) v, v the velocity in units of c omega
        out = _mlp(weights, params.damping_tables[r], params.damping_n_layers[r], act, z, buf_a, buf_b)
        vo = n_in - 2
        w1 = z[vo] * s[ROW_IN_STD + vo] + s[ROW_IN_MEAN + vo]
        w2 = z[vo + 1] * s[ROW_IN_STD + 1 + vo] + s[ROW_IN_MEAN + 1 + vo]
        y1 += out[0] * w1 + out[1] * w2
        y2 += out[2] * w1 + out[3] * w2
    f1 = unstandardise_nb(y1, s[ROW_OUT_MEAN], s[ROW_OUT_STD])
    f2 = unstandardise_nb(y2, s[ROW_OUT_MEAN + 1], s[ROW_OUT_STD + 1])
    if physics:
        g = film_gain_nb(fscale, e2, power)
        if s[ROW_KIND] == KIND_PHYSICS_V:
            g *= velocity_factor_nb(speed_nb(v1, v2), c, omega)
        g *= drive
        f1 *= g
        f2 *= g
    if polar:
        # back to (X1, X2): F = f_r e_r + f_t e_t
        return from_polar_nb(er1, er2, f1, f2)
    return f1, f2


@njit(cache=True)
def surrogate_force(params, x1, x2, v1, v2):
    """Force kernel of a (possibly split) network: same signature as the reference solver's
    (``params``: a ``SurrogateParams``)."""
    bounds = params.boundaries
    blend = params.blend_width
    domain = params.domain
    eps_max = params.eps_max
    counter = params.counter
    inv_c2 = params.setting[0]
    e2 = eps2_nb(x1, x2, inv_c2)
    eps = math.sqrt(e2)
    # training-domain check (counted, never fatal)
    outside = eps > eps_max
    if not outside:
        for s in range(domain.shape[0]):
            if domain[s, 0] <= eps < domain[s, 1] or (s == domain.shape[0] - 1 and eps >= domain[s, 1]):
                if abs(v1) > domain[s, 2] or abs(v2) > domain[s, 2]:
                    outside = True
                break
    if outside:
        counter[0] += 1
    # preallocated scratch rows (the integrator and the batch loop are serial)
    buf_a = params.scratch[0]
    buf_b = params.scratch[1]
    nb = bounds.shape[0]
    r = 0
    while r < nb and eps >= bounds[r]:
        r += 1
    if blend > 0.0:
        # nearest boundary within half the blend width mixes the two neighbours
        for b in range(nb):
            lo = bounds[b] - 0.5 * blend
            hi = bounds[b] + 0.5 * blend
            if lo <= eps < hi:
                t = (eps - lo) / blend
                w = t * t * (3.0 - 2.0 * t)
                fa1, fa2 = _region_force(params, b, x1, x2, v1, v2, e2, buf_a, buf_b)
                fb1, fb2 = _region_force(params, b + 1, x1, x2, v1, v2, e2, buf_a, buf_b)
                return (1.0 - w) * fa1 + w * fb1, (1.0 - w) * fa2 + w * fb2
    return _region_force(params, r, x1, x2, v1, v2, e2, buf_a, buf_b)


@njit(cache=True)
def _surrogate_batch(params, x, v, out):
    # serial: numba's parallel loops take no nested parameter tuples (and a
    # network evaluation costs well under a microsecond anyway)
    for p in range(x.shape[0]):
        f1, f2 = surrogate_force(params, x[p, 0], x[p, 1], v[p, 0], v[p, 1])
        out[p, 0] = f1
        out[p, 1] = f2


# not cached: its parameters hold a compiled kernel (numba's cache must not see such types)
@njit
def speed_scaled_force(sparams, omega, x1, x2, v1, v2):
    """A speed kernel from the exact speed scaling: F(X, V; omega) = s F(X, V/s; omega_ref), s = omega/omega_ref.

    ``sparams``: (the one-state kernel, its parameters, omega_ref [rad/s]).  For a network whose inputs are
    dimensionless (X/c, V/(c omega)) and whose force scale is mu omega R L (R/c)^2, this is exactly the
    network with omega and the force scale of its scaling row set to the new speed (the 'whirl' frame:
    u = (eps - 2 v_t, 2 v_r) in units of c omega, |u| and the force scale, both linear in 1/omega and omega);
    at omega = omega_ref it is the kernel's own force to the bit.
    """
    kernel, params, w_ref = sparams
    s = omega / w_ref
    f1, f2 = kernel(params, x1, x2, v1 / s, v2 / s)
    return s * f1, s * f2


def pack_network(layers: list[tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    """[(W (out, in), b (out,)), ...] -> flat weights (each W stored transposed) and a
    (n_layers, 4) table of [weight offset, bias offset, n_in, n_out]."""
    flat, table, off = [], [], 0
    for W, b in layers:
        W = np.asarray(W, dtype=np.float64)
        b = np.asarray(b, dtype=np.float64)
        table.append([off, off + W.size, W.shape[1], W.shape[0]])
        flat += [W.T.ravel(), b.ravel()]
        off += W.size + b.size
    return np.concatenate(flat), np.asarray(table, dtype=np.int64)


def _stack_tables(tables: list[np.ndarray]) -> np.ndarray:
    """Per-region (n_layers, 4) tables -> one (R, max n_layers, 4) array (short ones zero-padded)."""
    out = np.zeros((len(tables), max(t.shape[0] for t in tables), 4), dtype=np.int64)
    for r, t in enumerate(tables):
        out[r, :t.shape[0]] = t
    return out


