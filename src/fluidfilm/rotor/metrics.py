"""Orbit metrics: what a settled orbit looks like, and how far a model's orbit is from the reference's.

All lengths are reported relative to the radial clearance c (in % where the
name says so).  "Settled" means t >= t_settle.
"""
from __future__ import annotations

import math

import numpy as np
from scipy.spatial.distance import directed_hausdorff


def settled(traj, t_settle: float) -> np.ndarray:
    """Boolean mask of the settled samples."""
    return traj.t >= t_settle


def orbit_stats(traj, clearance: float, t_settle: float) -> dict:
    """Span per axis (peak-to-peak / c), mean position / c and largest eccentricity of the settled orbit."""
    mask = settled(traj, t_settle)
    if not traj.ok or mask.sum() < 2:
        return {"span1": math.nan, "span2": math.nan, "span": math.nan, "mean1": math.nan, "mean2": math.nan,
                "eps_max": float(np.max(traj.eccentricity(clearance))), "settled": False}
    x = traj.x[mask] / clearance
    span = x.max(axis=0) - x.min(axis=0)
    return {"span1": float(span[0]), "span2": float(span[1]), "span": float(span.max()),
            "mean1": float(x[:, 0].mean()), "mean2": float(x[:, 1].mean()),
            "eps_max": float(np.hypot(x[:, 0], x[:, 1]).max()), "settled": True}


def compare_orbits(model_traj, ref_traj, clearance: float, t_settle: float) -> dict:
    """Distances of a model's settled orbit from the reference's, in % of clearance.

    - ``rms_pct``: RMS of the point-to-point distance at equal times (the
      model's orbit interpolated onto the reference's time samples);
    - ``span_err_pct``: largest error of the per-axis span;
    - ``hausdorff_pct``: phase-insensitive shape distance between the two
      closed orbits (symmetric Hausdorff distance of their point sets);
    - ``mean_offset_pct``: distance between the orbits' mean positions.
    A model whose run stopped (contact, divergence) where the reference's
    did not gets infinite distances.
    """
    if not ref_traj.ok:
        raise ValueError(f"reference trajectory did not finish: {ref_traj.status}")
    mask = settled(ref_traj, t_settle)
    if not model_traj.ok or model_traj.t[-1] < ref_traj.t[mask][-1] - 1e-12:
        inf = math.inf
        return {"rms_pct": inf, "span_err_pct": inf, "hausdorff_pct": inf, "mean_offset_pct": inf}
    t = ref_traj.t[mask]
    xr = ref_traj.x[mask] / clearance
    xm = np.stack([np.interp(t, model_traj.t, model_traj.x[:, k]) for k in range(2)], axis=1) / clearance
    rms = float(np.sqrt(np.mean(np.sum((xm - xr) ** 2, axis=1))))
    span_r = xr.max(axis=0) - xr.min(axis=0)
    span_m = xm.max(axis=0) - xm.min(axis=0)
    haus = max(directed_hausdorff(xm, xr)[0], directed_hausdorff(xr, xm)[0])
    return {"rms_pct": 100 * rms, "span_err_pct": float(100 * np.abs(span_m - span_r).max()),
            "hausdorff_pct": float(100 * haus),
            "mean_offset_pct": float(100 * np.hypot(*(xm.mean(axis=0) - xr.mean(axis=0))))}


def is_satisfactory(distances: dict, threshold_pct: float) -> bool:
    """The rule the comparisons use: RMS and Hausdorff distance both within the threshold."""
    return distances["rms_pct"] <= threshold_pct and distances["hausdorff_pct"] <= threshold_pct
