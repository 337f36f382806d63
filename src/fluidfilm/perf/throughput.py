"""Trajectories per second: force models run one trajectory at a time (``simulate``) and as a batch
(``simulate_batch``), measured side by side on the same trajectories.

The trajectories are a Monte Carlo over what a sweep varies: imbalance,
static load and initial state (position and velocity within the orbits of
the paper's cases), each ``t_end`` of rotor time with the workspace's RK4
step.  Every model integrates exactly the same set, so ratios compare the
models and the way they are driven, nothing else.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from fluidfilm.perf.benchmarking import median_seconds
from fluidfilm.rotor import Rotor, simulate
from fluidfilm.rotor.batch import simulate_batch

__all__ = ["monte_carlo_batch", "trajectories_per_second"]


def monte_carlo_batch(clearance: float, n: int, mass: float = 2.5, seed: int = 0):
    """(rotors, x0, v0) of n trajectories: imbalance 0-1e-3 kg m, side load +-30 N, eps0 < 0.5, |v0| < 0.01 m/s.

    Parameters
    ----------
    clearance : float
        Radial clearance c [m].
    n : int
        Number of trajectories.
    mass : float, default 2.5
        Rotor mass per bearing [kg].
    seed : int, default 0
        Seed of the random generator.

    Returns
    -------
    rotors : list of Rotor
        Imbalance uniform in [0, 1e-3] kg m, a horizontal (X1) external force uniform in [-30, 30] N.
    x0, v0 : ndarray, shape (n, 2)
        Initial positions [m] (eps < 0.5) and velocities [m/s] (each component within +-0.01).

    Examples
    --------
    >>> from fluidfilm.perf.throughput import monte_carlo_batch
    >>> rotors, x0, v0 = monte_carlo_batch(clearance=1e-4, n=4)
    >>> len(rotors), x0.shape, rotors[0].mass
    (4, (4, 2), 2.5)
    """
    rng = np.random.default_rng(seed)
    rotors = [Rotor(mass=mass, imbalance=float(u), external_force=(float(f), 0.0))
              for u, f in zip(1e-3 * rng.random(n), 30.0 * (2 * rng.random(n) - 1))]
    eps = 0.5 * rng.random(n)
    ang = 2 * np.pi * rng.random(n)
    x0 = clearance * np.stack([eps * np.sin(ang), eps * np.cos(ang)], axis=1)
    v0 = 0.01 * (2 * rng.random((n, 2)) - 1)
    return rotors, x0, v0


def trajectories_per_second(model, n: int, t_end: float, dt: float = 1e-5, batched: bool = True,
                            repeats: int = 1, seed: int = 0, threads: int | None = 1, precision: str = "float32",
                            stage_batched: bool | None = None, clock=None) -> dict:
    """Median trajectories per second of ``model`` over ``repeats`` runs of n Monte Carlo trajectories.

    Parameters
    ----------
    model : ForceModel
        The force model integrated.
    n : int
        Trajectories per run (``monte_carlo_batch``).
    t_end : float
        Rotor time of each trajectory [s], from t = 0.
    dt : float, default 1e-5
        RK4 step [s].
    batched : bool, default True
        One ``simulate_batch`` call for all n, or n ``simulate`` calls.
    repeats : int, default 1
        Timed runs (median).
    seed : int, default 0
        Seed of the Monte Carlo.
    threads, precision, stage_batched
        ``simulate_batch``'s (batched runs only): threads across the batch (default 1; None: all cores),
        the surrogate networks' arithmetic (default: ``simulate_batch``'s, float32), and the loop (None:
        ``simulate_batch``'s choice by batch size).
    clock : callable, optional
        ``median_seconds``'s clock (default: wall time); ``time.thread_time`` for the CPU time of a run in
        the calling thread (one thread) on a shared machine.

    Returns
    -------
    dict
        ``n``, ``batched``, ``t_end_s``, ``wall_s`` (median wall time of a run [s]),
        ``trajectories_per_s``, ``n_ok`` (trajectories that reached ``t_end``) and ``n_force_evals`` (of a
        run, all trajectories); batched runs add ``threads``, ``precision`` and ``stage_batched``.

    Examples
    --------
    >>> from fluidfilm import LinearBearing, paper_bearing
    >>> from fluidfilm.perf.throughput import trajectories_per_second
    >>> spring = LinearBearing(paper_bearing(), stiffness=1e6, damping=1e3)
    >>> out = trajectories_per_second(spring, n=4, t_end=2e-3, batched=False)
    >>> out["n_ok"], out["trajectories_per_s"] > 0
    (4, True)
    """
    rotors, x0, v0 = monte_carlo_batch(model.bearing.clearance, n, seed=seed)
    # compile outside the timing
    kw: dict[str, Any] = {"threads": threads, "precision": precision, "stage_batched": stage_batched}
    if batched:
        # the whole batch for two steps: simulate_batch picks its loop by the batch's size (the stage-batched
        # one from STAGE_BATCHED_MIN_N trajectories), so one trajectory would compile the other loop only
        simulate_batch(model, rotors, 2 * dt, dt, x0, v0, record_every=10, **kw)
    else:
        simulate(model, rotors[0], 2 * dt, dt, x0[0], v0[0], record_every=10)
    n_ok = [0]
    n_evals = [0]

    def run() -> None:
        if batched:
            out = simulate_batch(model, rotors, t_end, dt, x0, v0, record_every=10, **kw)
            n_ok[0], n_evals[0] = int(out.completed.sum()), int(out.n_force_evals.sum())
        else:
            runs = [simulate(model, r, t_end, dt, a, b, record_every=10) for r, a, b in zip(rotors, x0, v0)]
            n_ok[0], n_evals[0] = sum(tr.completed for tr in runs), sum(tr.n_force_evals for tr in runs)

    wall = median_seconds(run, repeats, warmup=False, **({} if clock is None else {"clock": clock}))
    out: dict[str, Any] = {"n": n, "batched": batched, "t_end_s": t_end, "wall_s": wall, "trajectories_per_s": n / wall,
           "n_ok": n_ok[0], "n_force_evals": n_evals[0]}
    if batched:
        out.update(kw)
    return out
