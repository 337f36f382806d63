"""Exact derivatives of a surrogate's force: forward-mode differentiation of the network, in numpy.

``surrogate_jacobian(model, x, v)`` returns F (2,) and dF/d(x1, x2, v1, v2)
(2, 4) of a ``SurrogateForceModel``.  It re-evaluates the same network, with
the same input scaling, frame and output scaling as the compiled kernel
(``surrogate.kernels.generic._region_force``, including the damping structure and
the smoothstep blend of split models).  Every quantity is carried as a value
plus its four partial derivatives (dual numbers), so the derivatives are
those of the network itself, exact to rounding, with no step to choose.
The tests check the value against the compiled kernel and the derivatives
against central differences.  Surrogates with extra inputs (the active
bearing's sleeve) are not covered.
"""
from __future__ import annotations

import math

import numpy as np

from fluidfilm.surrogate.activations import REGISTRY
from fluidfilm.surrogate.contract import (FRAME_POLAR, FRAME_WHIRL, KIND_PHYSICS, KIND_PHYSICS_V, ROW_CLEARANCE,
                                         ROW_FORCE_SCALE, ROW_FRAME, ROW_IN_MEAN, ROW_IN_STD, ROW_KIND, ROW_N_EXTRA,
                                         ROW_OMEGA, ROW_OUT_MEAN, ROW_OUT_STD, ROW_POWER, ROW_SLEEVE, SLEEVE_AWARE)

# a dual number is an array (5,): value, d/dx1, d/dx2, d/dv1, d/dv2


def _const(a):
    out = np.zeros(5)
    out[0] = a
    return out


def _var(a, k):
    out = _const(a)
    out[1 + k] = 1.0
    return out


def _mul(a, b):
    return np.concatenate([[a[0] * b[0]], a[0] * b[1:] + b[0] * a[1:]])


def _div(a, b):
    return np.concatenate([[a[0] / b[0]], (a[1:] * b[0] - a[0] * b[1:]) / b[0] ** 2])


def _fn(a, f, df):
    return np.concatenate([[f(a[0])], df(a[0]) * a[1:]])


def _sqrt(a):
    r = math.sqrt(a[0])
    return np.concatenate([[r], a[1:] / (2.0 * r)])


def _speed(v1, v2):
    """|V| as a dual number.  At rest |V| has no derivative (a kink); its symmetric derivative, the limit of
    central differences (how the reference's K and C are taken), is zero in every direction: used there."""
    if v1[0] == 0.0 and v2[0] == 0.0:
        return _const(0.0)
    return _sqrt(_mul(v1, v1) + _mul(v2, v2))


def _activate(z, act):
    """Activation on a layer of duals z (n, 5): its value and first derivative (``activations.REGISTRY``)."""
    if act not in REGISTRY:
        raise ValueError(f"unknown activation {act!r}")
    y, d, _ = REGISTRY[act].derivatives(z[:, 0])
    out = np.empty_like(z)
    out[:, 0] = y
    out[:, 1:] = d[:, None] * z[:, 1:]
    return out


def _mlp(layers, z, act):
    """z (n_in, 5) duals through [(W (out, in), b)], activation between layers."""
    for k, (W, b) in enumerate(layers):
        z = W @ z
        z[:, 0] += b
        if k < len(layers) - 1:
            z = _activate(z, act)
    return z


def _region(model, r, x1, x2, v1, v2):
    s = model.scalings[r].kernel_row()
    if s[ROW_N_EXTRA] != 0.0 or s[ROW_SLEEVE] == SLEEVE_AWARE:
        raise ValueError("surrogate_jacobian does not cover surrogates with extra (sleeve) inputs")
    physics = s[ROW_KIND] >= KIND_PHYSICS
    c, omega, fscale, power = s[ROW_CLEARANCE], s[ROW_OMEGA], s[ROW_FORCE_SCALE], s[ROW_POWER]
    polar = s[ROW_FRAME] >= FRAME_POLAR
    drive = None
    if polar:
        if x1[0] == 0.0 and x2[0] == 0.0:
            # the journal's frame has no direction at the centre: the force is defined there, its derivative not
            raise ValueError("a polar- or whirl-frame surrogate has no derivative at the bearing centre (eps = 0)")
        rr = _sqrt(_mul(x1, x1) + _mul(x2, x2))
        er1, er2 = _div(x1, rr), _div(x2, rr)
        cw = c * omega
        z = [rr / c, (_mul(v1, er1) + _mul(v2, er2)) / cw, (_mul(v1, er2) - _mul(v2, er1)) / cw]
        if s[ROW_FRAME] == FRAME_WHIRL:  # frame 'whirl': the drive u = (eps - 2 v_t, 2 v_r), its direction in, |u| out
            ua, ub = z[0] - 2.0 * z[2], 2.0 * z[1]
            # |u| ~ 1e-16 is a vanished drive up to rounding: its direction is noise there
            if math.hypot(ua[0], ub[0]) <= 1e-12 * max(z[0][0], 1.0):
                raise ValueError("the force of a 'whirl'-frame surrogate has no derivative where its drive vanishes "
                                 "(a whirl at half the shaft speed, or the centred journal at rest)")
            drive = _sqrt(_mul(ua, ua) + _mul(ub, ub))
            z = [z[0], _div(ua, drive), _div(ub, drive)]
    elif physics:
        z = [x1 / c, x2 / c, v1 / (c * omega), v2 / (c * omega)]
    else:
        z = [x1, x2, v1, v2]
    n_in = len(z)
    raw = [zk.copy() for zk in z]
    zs = np.array([(z[k] - _const(s[ROW_IN_MEAN + k])) / s[ROW_IN_STD + k] for k in range(n_in)])
    if model.structure == "plain":
        static, damping = model.networks[r], None
    else:
        static, damping = model.networks[r]
    # the damping structure's static network sees the position inputs only (the first layer says how many)
    out = _mlp(static, zs[:static[0][0].shape[1]].copy(), model.activation)
    y1, y2 = out[0], out[1]
    if damping is not None:
        d = _mlp(damping, zs.copy(), model.activation)
        w1, w2 = raw[n_in - 2], raw[n_in - 1]
        y1 = y1 + _mul(d[0], w1) + _mul(d[1], w2)
        y2 = y2 + _mul(d[2], w1) + _mul(d[3], w2)
    f1 = y1 * s[ROW_OUT_STD] + _const(s[ROW_OUT_MEAN])
    f2 = y2 * s[ROW_OUT_STD + 1] + _const(s[ROW_OUT_MEAN + 1])
    if physics:
        e2 = (_mul(x1, x1) + _mul(x2, x2)) / c**2
        dd = _const(1.0) - e2
        g = _fn(dd, lambda u: fscale * u ** (-power), lambda u: -power * fscale * u ** (-power - 1.0))
        if s[ROW_KIND] == KIND_PHYSICS_V:
            g = _mul(g, _const(1.0) + _speed(v1, v2) / (c * omega))
        if drive is not None:
            g = _mul(g, drive)
        f1, f2 = _mul(f1, g), _mul(f2, g)
    if polar:
        return _mul(f1, er1) + _mul(f2, er2), _mul(f1, er2) - _mul(f2, er1)
    return f1, f2


def surrogate_jacobian(model, x, v):
    """(F (2,), J (2, 4)) of a surrogate at position ``x`` [m], velocity ``v`` [m/s]; J = dF/d(x1, x2, v1, v2)."""
    x = np.asarray(x, dtype=float).reshape(2)
    v = np.asarray(v, dtype=float).reshape(2)
    x1, x2, v1, v2 = _var(x[0], 0), _var(x[1], 1), _var(v[0], 2), _var(v[1], 3)
    c = model.bearing.clearance
    eps = math.hypot(x[0], x[1]) / c
    bounds = model.boundaries
    r = int(np.searchsorted(bounds, eps, side="right"))
    f = None
    if model.blend_width > 0.0:
        for b in range(len(bounds)):
            lo, hi = bounds[b] - 0.5 * model.blend_width, bounds[b] + 0.5 * model.blend_width
            if lo <= eps < hi:
                ep = _sqrt(_mul(x1, x1) + _mul(x2, x2)) / c
                t = (ep - _const(lo)) / model.blend_width
                w = _mul(_mul(t, t), _const(3.0) - 2.0 * t)
                fa = _region(model, b, x1, x2, v1, v2)
                fb = _region(model, b + 1, x1, x2, v1, v2)
                one_w = _const(1.0) - w
                f = (_mul(one_w, fa[0]) + _mul(w, fb[0]), _mul(one_w, fa[1]) + _mul(w, fb[1]))
                break
    if f is None:
        f = _region(model, r, x1, x2, v1, v2)
    return np.array([f[0][0], f[1][0]]), np.array([f[0][1:], f[1][1:]])


def surrogate_coefficients(model, x0) -> dict:
    """K and C of a surrogate at ``x0`` (journal at rest) from the exact Jacobian (same dict as
    ``coefficients.coefficients``)."""
    F0, J = surrogate_jacobian(model, x0, np.zeros(2))
    return {"K": -J[:, :2], "C": -J[:, 2:], "F0": F0, "load_N": float(np.hypot(*F0))}
