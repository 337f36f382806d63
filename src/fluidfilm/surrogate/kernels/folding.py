"""The networks with their scalings folded in, and what a compiled kernel depends on (its shape key).

The fast kernels (``generated``, ``generic_batch``, ``generated_batch``) fold each region's input
standardisation into its first layer and the output un-standardisation into its last (``_folded_networks``),
and compile one function per model *shape* (``shape_key``: regions, frames, scaling kinds, layer widths,
activation, blending, domain rows), so every model of one shape (an ensemble's members) shares one compiled
function.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from fluidfilm.surrogate.contract import (ROW_FRAME, ROW_IN_MEAN,
                                         ROW_IN_STD, ROW_KIND, ROW_N_EXTRA, ROW_OUT_MEAN, ROW_OUT_STD,
                                         ROW_POWER, ROW_SLEEVE, SLEEVE_AWARE)


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


