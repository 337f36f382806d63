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
    """Span per axis (peak-to-peak / c), mean position / c and largest eccentricity of the settled orbit.

    Parameters
    ----------
    traj : Trajectory
        A rotor trajectory (``simulate``).
    clearance : float
        Radial clearance c [m] the lengths are divided by.
    t_settle : float
        Samples at t >= ``t_settle`` [s] form the settled orbit.

    Returns
    -------
    dict
        ``span1``, ``span2`` (peak-to-peak along X1, X2, / c), ``span`` (the larger), ``mean1``,
        ``mean2`` (mean position / c), ``eps_max`` and ``settled``.  A run that stopped or has fewer
        than two settled samples gives NaN spans and means, ``settled`` False and ``eps_max`` over
        the whole run.

    Examples
    --------
    >>> import numpy as np
    >>> from fluidfilm.rotor import Trajectory, orbit_stats
    >>> t = np.linspace(0.0, 0.1, 1001)                         # a circle of radius 0.2 c about (0, 0.3 c)
    >>> x = np.stack([2e-5 * np.cos(200 * np.pi * t), 3e-5 + 2e-5 * np.sin(200 * np.pi * t)], axis=1)
    >>> s = orbit_stats(Trajectory(t, x, np.zeros_like(x), "ok"), clearance=1e-4, t_settle=0.05)
    >>> round(s["span1"], 3), round(s["span2"], 3), round(s["mean2"], 3), round(s["eps_max"], 3)
    (0.4, 0.4, 0.3, 0.5)
    """
    mask = settled(traj, t_settle)
    if not traj.completed or mask.sum() < 2:
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
    - ``mean_offset_pct``: distance between the orbits' mean positions;
    - ``shape_pct``: the Hausdorff distance after each orbit is moved to its
      own mean position (shape and size only, not where the orbit sits).
    A model whose run stopped (contact, divergence) where the reference's
    did not gets infinite distances.

    Parameters
    ----------
    model_traj : Trajectory
        The model's trajectory.
    ref_traj : Trajectory
        The reference's, from the same initial state and rotor.
    clearance : float
        Radial clearance c [m].
    t_settle : float
        Samples at t >= ``t_settle`` [s] form the settled orbits.

    Returns
    -------
    dict
        ``rms_pct``, ``span_err_pct``, ``hausdorff_pct``, ``mean_offset_pct``, ``shape_pct`` [% of c].

    Raises
    ------
    ValueError
        When the reference trajectory did not finish (its status is named).

    Examples
    --------
    >>> import numpy as np
    >>> from fluidfilm.rotor import Trajectory, compare_orbits
    >>> t = np.linspace(0.0, 0.1, 1001)
    >>> x = np.stack([2e-5 * np.cos(200 * np.pi * t), 3e-5 + 2e-5 * np.sin(200 * np.pi * t)], axis=1)
    >>> ref = Trajectory(t, x, np.zeros_like(x), "ok")
    >>> shifted = Trajectory(t, x + [1e-6, 0.0], np.zeros_like(x), "ok")   # 1 % of c along X1
    >>> d = compare_orbits(shifted, ref, clearance=1e-4, t_settle=0.05)
    >>> {k: round(v, 3) for k, v in d.items()}
    {'rms_pct': 1.0, 'span_err_pct': 0.0, 'hausdorff_pct': 1.0, 'mean_offset_pct': 1.0, 'shape_pct': 0.0}
    """
    if not ref_traj.ok:
        raise ValueError(f"reference trajectory did not finish: {ref_traj.status}")
    mask = settled(ref_traj, t_settle)
    if not model_traj.completed or model_traj.t[-1] < ref_traj.t[mask][-1] - 1e-12:
        inf = math.inf
        return {"rms_pct": inf, "span_err_pct": inf, "hausdorff_pct": inf, "mean_offset_pct": inf, "shape_pct": inf}
    t = ref_traj.t[mask]
    xr = ref_traj.x[mask] / clearance
    xm = np.stack([np.interp(t, model_traj.t, model_traj.x[:, k]) for k in range(2)], axis=1) / clearance
    rms = float(np.sqrt(np.mean(np.sum((xm - xr) ** 2, axis=1))))
    span_r = xr.max(axis=0) - xr.min(axis=0)
    span_m = xm.max(axis=0) - xm.min(axis=0)
    haus = _hausdorff(xm, xr)
    centred = _hausdorff(xm - xm.mean(axis=0), xr - xr.mean(axis=0))
    return {"rms_pct": 100 * rms, "span_err_pct": float(100 * np.abs(span_m - span_r).max()),
            "hausdorff_pct": float(100 * haus),
            "mean_offset_pct": float(100 * np.hypot(*(xm.mean(axis=0) - xr.mean(axis=0)))),
            "shape_pct": float(100 * centred)}


def _hausdorff(a: np.ndarray, b: np.ndarray) -> float:
    return max(directed_hausdorff(a, b)[0], directed_hausdorff(b, a)[0])


def is_satisfactory(distances: dict, threshold_pct: float) -> bool:
    """The rule the comparisons use: RMS and Hausdorff distance both within the threshold."""
    return distances["rms_pct"] <= threshold_pct and distances["hausdorff_pct"] <= threshold_pct


def is_satisfactory_paper_reading(distances: dict, threshold_pct: float) -> bool:
    """The paper's own reading: amplitude and shape right, wherever the orbit sits.

    The paper calls a model satisfactory when it "provides correct information about both the
    steady-state amplitudes of rotor oscillations and the shape of trajectories and transients": the
    span error and the shape distance after removing the mean offset (``shape_pct``) both within the
    threshold; the mean position is not judged.  A shifted copy of the reference orbit passes it and
    fails ``is_satisfactory``; a scaled copy fails both.
    """
    return distances["span_err_pct"] <= threshold_pct and distances["shape_pct"] <= threshold_pct
