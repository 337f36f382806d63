"""Speed of force models measured the way the integrator uses them: the compiled kernel in a compiled loop.

Every model's kernel runs through the same loop over the same states, so
the ratio of two timings is the ratio of the models' costs and nothing else.
"""
from __future__ import annotations

import math
import time

import numpy as np
from numba import njit

from fluidfilm.core.force_model import one_state_kernel
from fluidfilm.perf.benchmarking import median_seconds

__all__ = ["sample_states", "time_per_force_eval", "time_per_force_eval_batched", "best_shaped_surrogate",
           "paper_shaped_surrogate"]

#: the least time [s] one timed sample of ``time_per_force_eval_batched`` spans (back-to-back calls)
SAMPLE_MIN_S = 0.005


@njit  # not cached: numba's on-disk cache cannot always pickle a specialisation on a function argument
def _kernel_loop(kernel, params, x, v):
    acc = 0.0
    for p in range(x.shape[0]):
        f1, f2 = kernel(params, x[p, 0], x[p, 1], v[p, 0], v[p, 1])
        acc += f1 + f2
    return acc


def sample_states(clearance: float, n: int = 5000, eps_max: float = 0.8, v_max: float = 0.05, seed: int = 0):
    """States typical of a trajectory: eps uniform in [0, eps_max], velocities within +-v_max.

    Parameters
    ----------
    clearance : float
        Radial clearance c [m].
    n : int, default 5000
        Number of states.
    eps_max : float, default 0.8
        Largest eccentricity ratio.
    v_max : float, default 0.05
        Bound of each velocity component [m/s].
    seed : int, default 0
        Seed of the random generator (the same states on every call).

    Returns
    -------
    x, v : ndarray, shape (n, 2)
        Positions [m] and velocities [m/s], (X1, X2) frame; angles uniform over the circle.

    Examples
    --------
    >>> import numpy as np
    >>> from fluidfilm.perf.speed import sample_states
    >>> x, v = sample_states(clearance=1e-4, n=100)
    >>> x.shape, bool(np.hypot(*x.T).max() <= 0.8e-4), bool(np.abs(v).max() <= 0.05)
    ((100, 2), True, True)
    """
    rng = np.random.default_rng(seed)
    eps = eps_max * rng.random(n)
    ang = 2 * np.pi * rng.random(n)
    x = clearance * np.stack([eps * np.sin(ang), eps * np.cos(ang)], axis=1)
    v = v_max * (2 * rng.random((n, 2)) - 1)
    return x, v


def time_per_force_eval(model, x, v, repeats: int = 7, precision: str = "float64") -> float:
    """Median seconds per force evaluation of ``model.force_kernel`` (or ``force_kernel_at("float32")``)
    over the states (x, v).

    The compiled kernel runs in a compiled loop (as ``simulate`` calls it); compiling is done before
    the timing.

    Parameters
    ----------
    model : ForceModel
        Any force model (its ``force_kernel`` is timed).
    x, v : ndarray, shape (n, 2)
        States [m], [m/s] (e.g. from ``sample_states``).
    repeats : int, default 7
        Timed samples of the whole loop (``median_seconds``).
    precision : {"float64", "float32"}, default "float64"
        "float32": the kernel with float32 networks (``force_kernel_at``) where the model has one
        (``core.force_model.PrecisionKernelModel``), as ``simulate(precision="float32")`` runs it.

    Returns
    -------
    float
        Time per force evaluation [s].

    Examples
    --------
    >>> from fluidfilm import ReynoldsSolver, paper_bearing
    >>> from fluidfilm.perf.speed import sample_states, time_per_force_eval
    >>> solver = ReynoldsSolver(paper_bearing(), 16, 8)
    >>> x, v = sample_states(solver.bearing.clearance, n=200)
    >>> 0.0 < time_per_force_eval(solver, x, v, repeats=3) < 0.01
    True
    """
    kernel, params, _ = one_state_kernel(model, precision)
    _kernel_loop(kernel, params, x[:2], v[:2])  # compile
    return median_seconds(lambda: _kernel_loop(kernel, params, x, v), repeats, warmup=False) / len(x)


def time_per_force_eval_batched(model, x, v, precision: str = "float32", repeats: int = 7) -> float:
    """Median seconds per force of ``model.batch_force_kernel(precision)`` on all the states (x, v) in one
    call, in the calling thread: what ``simulate_batch`` does once per RK4 stage (states passed column-major,
    as it passes them).

    A surrogate gains with the number of states (it runs its networks on tiles of them); compiling is
    done before the timing.

    Parameters
    ----------
    model : ForceModel
        Any force model with a ``batch_force_kernel`` (a reference solver or a surrogate).
    x, v : ndarray, shape (n, 2)
        States [m], [m/s] (e.g. from ``sample_states``), all evaluated in one call.
    precision : {"float32", "float64"}, default "float32"
        Arithmetic of a surrogate's networks (``simulate_batch``'s default is float32); a reference
        solver computes in float64 whatever it is given.
    repeats : int, default 7
        Timed samples (``median_seconds``), each of back-to-back calls adding up to at least
        ``SAMPLE_MIN_S`` (one call where that is longer).

    Returns
    -------
    float
        Time per force evaluation [s].

    Examples
    --------
    >>> from fluidfilm import paper_bearing
    >>> from fluidfilm.perf.speed import best_shaped_surrogate, sample_states, time_per_force_eval_batched
    >>> model = best_shaped_surrogate(paper_bearing())
    >>> x, v = sample_states(model.clearance, n=256)
    >>> 0.0 < time_per_force_eval_batched(model, x, v, "float64", repeats=3) < 1e-4
    True
    """
    fn, params = model.batch_force_kernel(precision, private=True)
    # column-major (n, 2), as ``simulate_batch`` passes them: a surrogate's per-state loops vectorise on
    # contiguous components (interleaved rows cost the best-shaped kernel ~9 ns per force more)
    x, v = np.asfortranarray(x, dtype=np.float64), np.asfortranarray(v, dtype=np.float64)
    out = np.empty_like(x, order="F")
    fn(params, x[:2], v[:2], out[:2])  # compile
    fn(params, x, v, out)
    # each sample at least ~5 ms of calls: one call of a surrogate on 1024 states takes ~50 us, and medians
    # of single calls that short moved a ratio of two models by 10 % between runs on the shared machine
    t0 = time.perf_counter()
    fn(params, x, v, out)
    calls = max(1, min(1000, math.ceil(SAMPLE_MIN_S / max(time.perf_counter() - t0, 1e-9))))
    return median_seconds(lambda: fn(params, x, v, out), repeats, calls=calls, warmup=False) / len(x)


def best_shaped_surrogate(bearing, seed: int = 0, restoring: bool = True):
    """An untrained surrogate with the best model's shapes (conf/experiment/best.yaml): five eccentricity
    regions (boundaries 0.3, 0.5, 0.7, 0.85) blended over 0.04, the whirl frame, physics scaling
    ((1 - eps^2)^1.5), 3 -> 64 -> 2 tanh networks with random weights.  What the speed of the best model
    depends on, where no trained one is at hand (its cost does not depend on the weights' values).

    Parameters
    ----------
    bearing : JournalBearing
        The bearing (no supply pressure: the whirl frame needs the film's homogeneity).
    seed : int, default 0
        Seed of the random weights and scalings.
    restoring : bool, default True
        Make the force mostly a restoring one along the line of centres (output centre (-20, 0), the
        output layer's weights scaled by 0.01), so that an orbit stays inside the clearance (trajectory
        timings); False: output layers of full-size random weights (tests of the arithmetic).

    Returns
    -------
    SurrogateForceModel

    Examples
    --------
    >>> from fluidfilm import paper_bearing
    >>> from fluidfilm.perf.speed import best_shaped_surrogate
    >>> best_shaped_surrogate(paper_bearing())
    SurrogateForceModel('best-shaped (random weights)', 5 network(s), boundaries=[0.3, 0.5, 0.7, 0.85], 1930 parameters)
    """
    from fluidfilm.surrogate import Scaling, SurrogateForceModel

    rng = np.random.default_rng(seed)
    nets, scalings = [], []
    for _ in range(5):
        gain = 0.01 if restoring else 1.0
        nets.append([(rng.normal(0, 1 / np.sqrt(3), (64, 3)), rng.normal(0, 0.1, 64)),
                     (gain * rng.normal(0, 1 / 8, (2, 64)), gain * rng.normal(0, 0.1, 2))])
        out_mean = np.array([-20.0, 0.0]) if restoring else rng.normal(0, 1, 2)
        scalings.append(Scaling("physics", bearing.clearance, bearing.omega, bearing.force_scale, 1.5,
                                rng.normal(0, 0.1, 3), 1 + rng.random(3), out_mean, 1 + rng.random(2), "whirl"))
    return SurrogateForceModel(bearing, nets, scalings, "tanh", boundaries=(0.3, 0.5, 0.7, 0.85), blend_width=0.04,
                               domain=[[0.0, 0.95, 0.2]], eps_max=0.95, name="best-shaped (random weights)")


def paper_shaped_surrogate(bearing, split: bool = False, seed: int = 0):
    """An untrained surrogate with the shapes of the paper's networks (conf/model/paper_single.yaml): one
    4 -> 50 -> 2 tanh network on the standardised Cartesian state, or (``split``) one per eccentricity
    region at 0.5 and 0.7 without blending (conf/split/paper.yaml); random weights.  What the speed of the
    paper's models depends on, where no trained one is at hand.

    Parameters
    ----------
    bearing : JournalBearing
        The bearing.
    split : bool, default False
        Three regions (the paper's split model) instead of one.
    seed : int, default 0
        Seed of the random weights and scalings.

    Returns
    -------
    SurrogateForceModel

    Examples
    --------
    >>> from fluidfilm import paper_bearing
    >>> from fluidfilm.perf.speed import paper_shaped_surrogate
    >>> paper_shaped_surrogate(paper_bearing(), split=True)
    SurrogateForceModel('paper-split-shaped (random weights)', 3 network(s), boundaries=[0.5, 0.7], 1056 parameters)
    """
    from fluidfilm.surrogate import Scaling, SurrogateForceModel

    rng = np.random.default_rng(seed)
    n_regions = 3 if split else 1
    c, omega = bearing.clearance, bearing.omega
    nets, scalings = [], []
    for _ in range(n_regions):
        nets.append([(rng.normal(0, 1 / 2, (50, 4)), rng.normal(0, 0.1, 50)),
                     (rng.normal(0, 1 / np.sqrt(50), (2, 50)), rng.normal(0, 0.1, 2))])
        scalings.append(Scaling("standard", c, omega, bearing.force_scale, 0.0, np.zeros(4),
                                np.array([0.5 * c, 0.5 * c, 0.02, 0.02]) * (1 + rng.random(4)),
                                rng.normal(0, 10, 2), 100 * (1 + rng.random(2)), "cartesian"))
    name = "paper-split-shaped (random weights)" if split else "paper-single-shaped (random weights)"
    return SurrogateForceModel(bearing, nets, scalings, "tanh", boundaries=(0.5, 0.7) if split else (),
                               blend_width=0.0, name=name)
