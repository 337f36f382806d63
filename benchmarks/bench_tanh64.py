"""What a float64 tanh (and the universal networks' pade_tanh) costs in the one-state kernels (#29).

    python benchmarks/bench_tanh64.py [--repeats 7]

The float64 one-state kernel (``surrogate.kernels.kernel_source``: what ``simulate`` runs by default) of a
tanh network spends about half of a force in ``tanh64``. This benchmark times, interleaved in one process, one thread:

1. ns per unit of each tanh in a vectorised loop over 64 units (a hidden layer), independent evaluations:
   ``tanh64`` ([9/8] Pade approximant at x/4 doubled twice), the form it replaced ([7/6] at x/8 doubled three
   times), the ratio p/q of ``tanh64``'s [9/8] approximant alone (its clamp and doublings left out: what they
   cost; not a tanh, no error given), ``tanh32`` (float32), and ``math.tanh`` (libm: scalar, does not
   vectorise); beside each tanh, its largest relative error against mpmath on |x| <= 19.5.
   Beside them ``pade_tanh64``, the universal networks' activation (tanh's [5/4] Pade approximant taken as the
   activation itself: the function itself, with no approximation error to give).
2. ns per force of the one-state float64 kernel of the universal model (Gumbel, the paper's bearing) and of
   the best model (``models/best`` where trained, else its shape with random weights), compiled from the same
   generated source with each unit in place of the model's own activation, and with the identity (not a
   model: what the rest of the kernel costs). Only the model's own activation gives the model; the other
   rows show what each unit costs in that kernel. States: eps uniform in 0-0.9, the universal evaluation's
   timing states.

Writes reports/benchmarks/tanh64.json (docs/fast_surrogates.md shows it).
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import mpmath
import numpy as np
from numba import njit

from bench_universal_cost import states  # this folder: the script's own (python adds it to sys.path)
from fluidfilm import load_surrogate, paper_bearing, universal_bearing
from fluidfilm.perf import write_benchmark
from fluidfilm.perf.speed import _kernel_loop, best_shaped_surrogate, median_seconds
from fluidfilm.surrogate import kernels
from fluidfilm.surrogate.activations import _P1, _P3, _P5, _P7, _P9, _Q0, _Q2, _Q4, _Q6, _Q8, pade_tanh64, tanh32, tanh64

FLAGS = {"error_model": "numpy", "fastmath": {"contract"}}


@njit(cache=True, inline="always", **FLAGS)
def tanh64_pade76(x):
    """The previous tanh64: the [7/6] Pade approximant at x/8, doubled three times."""
    x = min(max(x, -19.5), 19.5)
    u = 0.125 * x
    u2 = u * u
    p = u * (1.0 + u2 * (17325.0 / 135135.0 + u2 * (378.0 / 135135.0 + u2 * (1.0 / 135135.0))))
    q = 1.0 + u2 * (62370.0 / 135135.0 + u2 * (3150.0 / 135135.0 + u2 * (28.0 / 135135.0)))
    p, q = 2.0 * p * q, p * p + q * q
    p, q = 2.0 * p * q, p * p + q * q
    p, q = 2.0 * p * q, p * p + q * q
    return p / q


@njit(cache=True, inline="always", **FLAGS)
def pade98_only(x):
    """The ratio p/q of tanh64's [9/8] approximant, its clamp and doublings left out (not a tanh: its cost)."""
    u2 = x * x
    p = x * (_P1 + u2 * (_P3 + u2 * (_P5 + u2 * (_P7 + u2 * _P9))))
    q = _Q0 + u2 * (_Q2 + u2 * (_Q4 + u2 * (_Q6 + u2 * _Q8)))
    return p / q


@njit(cache=True, inline="always", **FLAGS)
def libm_tanh(x):
    return math.tanh(x)


@njit(cache=True, inline="always", **FLAGS)
def identity(x):
    return x


def _unit_loop(f, dtype):
    as_dtype = np.float32 if dtype == np.float32 else np.float64  # float32 units stay in float32

    @njit(**FLAGS)
    def loop(a, out, passes):
        for r in range(passes):
            shift = as_dtype(r * 1e-20)  # a new argument each pass: nothing to hoist
            for o in range(a.size):
                out[o] += f(a[o] + shift)
        return out
    return loop


def max_rel_error(f, dtype) -> float:
    """Largest relative error of ``f`` against mpmath's tanh on 4,001 points of (0, 19.5] and 400 small ones."""
    x = np.concatenate([np.linspace(19.5 / 4000, 19.5, 4000), np.geomspace(1e-12, 1e-2, 400)]).astype(dtype)
    mpmath.mp.dps = 30
    got = np.array([float(f(t)) for t in x])
    ref = np.array([float(mpmath.tanh(mpmath.mpf(float(t)))) for t in x])
    return float(np.max(np.abs(got - ref) / ref))


def compiled_with(model, act):
    """The model's generated one-state float64 kernel (``kernels.kernel_source``) with ``act`` in place of its
    activation unit (``tanh64``, or ``pade_tanh64`` for the universal networks), compiled as
    ``kernels.compiled_kernel`` compiles it."""
    unit = {"tanh": "tanh64", "pade_tanh": "pade_tanh64"}[model.activation]
    return kernels.one_state_function(kernels.kernel_source(model._fast_key), "<bench kernel>", {unit: act})


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7, help="interleaved rounds (medians)")
    args = ap.parse_args(argv)
    if args.repeats < 1:
        raise SystemExit(f"--repeats must be >= 1, got {args.repeats}")
    rng = np.random.default_rng(0)
    units = {"tanh64 ([9/8] at x/4, two doublings)": (tanh64, np.float64),
             "previous tanh64 ([7/6] at x/8, three doublings)": (tanh64_pade76, np.float64),
             "tanh64's p/q alone (no clamp, no doubling; not a tanh)": (pade98_only, np.float64),
             "pade_tanh64 (the universal networks' activation; not tanh)": (pade_tanh64, np.float64),
             "tanh32 (Eigen's rational, float32)": (tanh32, np.float32),
             "math.tanh (libm, scalar)": (libm_tanh, np.float64)}
    loops = {}
    for name, (f, dt) in units.items():
        a, out = (3.0 * rng.standard_normal(64)).astype(dt), np.zeros(64, dt)
        loops[name] = (_unit_loop(f, dt), a, out)
        loops[name][0](a, out, 2)
    passes = 20000
    t_unit: dict = {k: [] for k in loops}

    bearing = paper_bearing()
    best = (load_surrogate("models/best"), "best (trained)") if Path("models/best").exists() else \
        (best_shaped_surrogate(bearing), "best shape (random weights)")
    models = {"universal (Gumbel)": universal_bearing(bearing, "gumbel"), best[1]: best[0]}
    acts = {"tanh64": tanh64, "previous tanh64": tanh64_pade76, "pade_tanh64": pade_tanh64,
            "identity (no activation)": identity}
    n = 5000
    x, v = states(bearing.clearance, 0.0, 0.9, n, 0)  # the universal model's timing states
    fns = {}
    for mname, m in models.items():
        for aname, act in acts.items():
            fn = compiled_with(m, act)
            w = m._fast_weights.copy()  # a private copy: the kernel counts states outside the domain in it
            _kernel_loop(fn, w, x[:2], v[:2])
            fns[(mname, aname)] = (fn, w)
    t_force: dict = {k: [] for k in fns}
    for _ in range(args.repeats):
        for name, (loop, a, out) in loops.items():
            t_unit[name].append(median_seconds(lambda loop=loop, a=a, out=out: loop(a, out, passes), 3,
                                               warmup=False) / (passes * a.size))
        for k, (fn, w) in fns.items():
            t_force[k].append(median_seconds(lambda fn=fn, w=w: _kernel_loop(fn, w, x, v), 3, warmup=False) / n)

    rows = []
    for name, (f, dt) in units.items():
        err = "" if f in (pade98_only, pade_tanh64) else f"{max_rel_error(f, dt):.1e}"
        rows.append([name, f"{1e9 * float(np.median(t_unit[name])):.3f}", err, "", ""])
    for mname in models:
        base = float(np.median(t_force[(mname, "tanh64")]))
        for aname in acts:
            t = float(np.median(t_force[(mname, aname)]))
            own = " (the model)" if aname == {"tanh": "tanh64", "pade_tanh": "pade_tanh64"}[models[mname].activation] else ""
            rows.append([f"one-state float64 force, {mname}, {aname}{own}", "", "", f"{1e9 * t:.1f}",
                         f"{t / base:.3f}"])
    for r in rows:
        print(" | ".join(r), flush=True)
    write_benchmark("tanh64", "float64 tanh and pade_tanh: ns per unit in a vectorised 64-unit loop, and ns per "
                    "one-state force with each unit in the generated kernel",
                    ["arm", "ns per unit", "largest relative error (mpmath, |x| <= 19.5)", "ns per force",
                     "force time / with tanh64"], rows,
                    notes=f"Medians of {args.repeats} interleaved rounds; one thread. States eps uniform in 0-0.9, "
                          "velocities within +-0.05 m/s. tanh64's p/q alone and the identity are not tanh: they "
                          "show what the clamp and doublings, and the tanh, cost. pade_tanh64 is the universal "
                          "networks' own activation (no approximation error: it is the function); '(the model)' marks the row that "
                          "runs each model as trained.")


if __name__ == "__main__":
    main()
