"""ns per force of the surrogate's kernels and the reference, side by side, for N = 1, 64, 1024, 65536 states.

    python benchmarks/bench_surrogate_kernels.py [--model models/best] [--quick]

Arms (one run, one process, the same states for all):

- reference: the graded Reynolds model (``GradedReynoldsModel`` on the paper bearing), its one-state kernel;
- generic: ``inference.surrogate_force``, the surrogate kernel before issue #27;
- fast: the one-state kernel generated for the model's shape (``surrogate.kernels.fast_force_kernel``);
- batch f64 / batch f32: ``surrogate.kernels.forces_batch`` on all N states at once, the network in float64
  or float32.

Every arm runs inside a compiled loop (the one-state kernels over the N states, the batched kernel once per
pass), repeated until about 2e5 forces were evaluated per sample, so N = 1 measures the kernel and not
Python's call overhead; the figure is the median over the samples (``median_seconds``).  Then one trajectory
(``simulate``, 20 ms of rotor time at dt = 1e-5 s) of the fast surrogate and of the reference.  The
surrogate is ``--model`` where that folder holds a saved model, else one with the best model's shapes and
random weights (``perf.speed.best_shaped_surrogate``: the cost does not depend on the weights' values).
"""
from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import numpy as np
from numba import njit

from fluidfilm import GradedReynoldsModel, Rotor, load_surrogate, paper_bearing, simulate
from fluidfilm.perf.benchmarking import machine, median_seconds, write_benchmark
from fluidfilm.perf.speed import best_shaped_surrogate, sample_states
from fluidfilm.surrogate.inference import surrogate_force
from fluidfilm.surrogate.kernels import batch_params, compile_seconds, forces_batch

SIZES = (1, 64, 1024, 65536)


@njit
def _one_state_passes(kernel, params, x, v, passes):
    acc = 0.0
    for _ in range(passes):
        for p in range(x.shape[0]):
            f1, f2 = kernel(params, x[p, 0], x[p, 1], v[p, 0], v[p, 1])
            acc += f1 + f2
    return acc


@njit
def _batch_passes(bp, x, v, out, passes):
    acc = 0.0
    for _ in range(passes):
        forces_batch(bp, x, v, out)
        acc += out[0, 0]
    return acc


def _ns_per_force(run, n, passes, repeats):
    run(1)  # compile
    return 1e9 * median_seconds(lambda: run(passes), repeats, warmup=False) / (n * passes)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--model", default="models/best")
    ap.add_argument("--quick", action="store_true", help="fewer forces per sample, no file written")
    args = ap.parse_args()
    bearing = paper_bearing()
    if (Path(args.model) / "model.json").exists():
        model, label = load_surrogate(args.model), args.model
    else:
        model, label = best_shaped_surrogate(bearing), "best-shaped, random weights (no trained model here)"
    reference = GradedReynoldsModel(bearing)
    per_sample, repeats = (2e4, 3) if args.quick else (2e5, 7)
    t0 = time.perf_counter()
    fast_kernel, fast_params = model.force_kernel
    compile_fast = compile_seconds.get(model._fast_key, time.perf_counter() - t0)
    bp64, bp32 = batch_params(model, "float64"), batch_params(model, "float32")
    print(f"machine: {machine()}; surrogate: {label}")
    header = ["N", "reference (graded)", "generic", "fast", "batch f64", "batch f32",
              "ref/fast", "ref/batch f64", "ref/batch f32"]
    rows = []
    print(("{:>7}" + "{:>20}" + "{:>10}" * 4 + "{:>15}" * 3).format(*header))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        for n in SIZES:
            x, v = sample_states(model.clearance, n=max(n, 1), eps_max=0.8, v_max=0.05, seed=1)
            out = np.empty_like(x)
            passes = max(1, int(per_sample // n))
            ref_passes = max(1, passes // 20)  # the reference is ~30x slower: fewer forces, same sampling
            ns = {
                "reference": _ns_per_force(lambda k: _one_state_passes(*reference.force_kernel, x, v, k), n,
                                           ref_passes, repeats if n < 65536 else 3),
                "generic": _ns_per_force(lambda k: _one_state_passes(surrogate_force, model.params, x, v, k), n,
                                         passes, repeats),
                "fast": _ns_per_force(lambda k: _one_state_passes(fast_kernel, fast_params, x, v, k), n, passes,
                                      repeats),
                "batch64": _ns_per_force(lambda k: _batch_passes(bp64, x, v, out, k), n, passes, repeats),
                "batch32": _ns_per_force(lambda k: _batch_passes(bp32, x, v, out, k), n, passes, repeats),
            }
            row = [n, f"{ns['reference']:.0f}", f"{ns['generic']:.0f}", f"{ns['fast']:.0f}", f"{ns['batch64']:.0f}",
                   f"{ns['batch32']:.0f}", f"{ns['reference'] / ns['fast']:.1f}x",
                   f"{ns['reference'] / ns['batch64']:.1f}x", f"{ns['reference'] / ns['batch32']:.1f}x"]
            rows.append(row)
            print(("{:>7}" + "{:>20}" + "{:>10}" * 4 + "{:>15}" * 3).format(*row))
        # one trajectory, the same integrator and start for both models; the time per force evaluation inside
        # it (a random-weight surrogate's orbit is not the reference's and may stop early)
        rotor = Rotor(mass=2.5, imbalance=5e-4 * 2.5)
        x0 = [0.0, 0.3 * model.clearance]
        per_eval, status = {}, {}
        for name, m in (("fast", model), ("reference", reference)):
            traj = simulate(m, rotor, t_end=0.02, x0=x0)  # compiles the (uncached) loop for the surrogate
            wall = median_seconds(lambda m=m: simulate(m, rotor, t_end=0.02, x0=x0), 5 if name == "fast" else 3,
                                  warmup=False)
            per_eval[name] = wall / traj.n_force_evals
            status[name] = f"{traj.status}, {traj.n_force_evals} force evaluations"
    ratio = per_eval["reference"] / per_eval["fast"]
    traj_note = (f"one trajectory (simulate, 20 ms at dt = 1e-5 s), time per force evaluation inside it: surrogate "
                 f"{per_eval['fast'] * 1e9:.0f} ns ({status['fast']}), reference {per_eval['reference'] * 1e9:.0f} ns "
                 f"({status['reference']}): {ratio:.1f}x")
    print(traj_note + f"; fast kernel compiled in {compile_fast:.2f} s")
    if not args.quick:
        write_benchmark(
            "surrogate_kernels", f"ns per force of the surrogate ({label}) and the graded reference, by number of "
            "states N, medians, one process, one thread", header, rows,
            notes=(traj_note[0].upper() + traj_note[1:] + ". The fast kernel of this shape "
                   f"compiled in {compile_fast:.2f} s. Every arm in a compiled loop; the machine was shared with "
                   "other work while measured, so absolute times vary from run to run; the ratios are measured "
                   "side by side."))


if __name__ == "__main__":
    main()
