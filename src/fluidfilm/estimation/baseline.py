"""The plants' baseline: the static load from the shaft's centreline position through the bearing's Sommerfeld curve.

What a plant's monitoring system does today: average the two probes over whole revolutions (the centreline:
the 1x orbit and the runout average out), read the eccentricity and attitude angle, and take the load that
the bearing's *static* curve gives there at an *assumed* viscosity. The curve here is the same force model the
estimator runs, at rest (W = -(mu_assumed/mu0) F0(X_mean, 0)): the baseline's errors are then its own -
the viscosity assumption and ignoring the journal's motion - and not a worse curve.
"""
from __future__ import annotations

import math

import numpy as np


def centreline(t, xy, speed_rpm, revolutions: float = 2.0) -> np.ndarray:
    """(N, 2) [m]: the mean position over the last ``revolutions`` revolutions at every sample (fewer at the
    start, where less data is there)."""
    t = np.asarray(t, dtype=float)
    xy = np.asarray(xy, dtype=float)
    dt = float(np.median(np.diff(t)))
    n_win = max(1, int(round(revolutions * 60.0 / float(np.median(speed_rpm)) / dt)))
    c = np.vstack([np.zeros((1, 2)), np.cumsum(xy, axis=0)])
    idx = np.arange(1, t.size + 1)
    lo = np.maximum(idx - n_win, 0)
    return (c[idx] - c[lo]) / (idx - lo)[:, None]


def centreline_load(model, t, xy, speed_rpm, viscosity_ratio: float = 1.0,
                    revolutions: float = 2.0) -> dict:
    """The baseline's static load estimate [N] at every sample: ``{"W": (N, 2), "X": (N, 2) centreline,
    "eps": (N,)}``. ``viscosity_ratio``: the assumed mu / mu0 (the plant's oil-temperature guess; 1: the
    description's viscosity). The model's speed kernel gives the curve at the measured speed."""
    X = centreline(t, xy, speed_rpm, revolutions)
    fn, params = model.speed_kernel()
    omega = np.asarray(speed_rpm, dtype=float) * 2.0 * math.pi / 60.0 * np.ones(len(X))
    W = np.empty_like(X)
    c = model.clearance
    for k, (x1, x2) in enumerate(X):
        r = math.hypot(x1, x2)
        if r > 0.98 * c:
            x1, x2 = x1 * 0.98 * c / r, x2 * 0.98 * c / r
        f1, f2 = fn(params, omega[k], x1, x2, 0.0, 0.0)
        W[k] = (-viscosity_ratio * f1, -viscosity_ratio * f2)
    return {"W": W, "X": X, "eps": np.hypot(X[:, 0], X[:, 1]) / c}
