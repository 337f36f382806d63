"""ns per force of the surrogate's kernels and the reference, side by side, for N = 1, 64, 1024, 65536 states.

    python benchmarks/bench_surrogate_kernels.py [--model models/best] [--quick] [--trajectories-only]

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

Last, batched trajectories (``perf.throughput.trajectories_per_second``, ``simulate_batch``): N = 1024 Monte
Carlo trajectories of 5 ms each, the surrogate (float64 and float32 networks, and the per-trajectory lockstep
loop it had before) and the graded reference run the same way (one batched-kernel call per RK4 stage), at one
thread and at all cores; trajectories per second and the ratios (reports/benchmarks/batch_trajectories.json;
``--trajectories-only`` runs just this part).
"""
from __future__ import annotations

import argparse
import os
import time
import warnings
from pathlib import Path

import numpy as np
from numba import njit

from fluidfilm import GradedReynoldsModel, Rotor, load_surrogate, paper_bearing, simulate
from fluidfilm.perf.benchmarking import machine, median_seconds, write_benchmark
from fluidfilm.perf.speed import best_shaped_surrogate, sample_states
from fluidfilm.perf.throughput import trajectories_per_second
from fluidfilm.surrogate.inference import surrogate_force
from fluidfilm.surrogate.kernels import batch_params, compile_seconds, forces_batch

SIZES = (1, 64, 1024, 65536)
#: batched trajectories: how many, and the rotor time of each [s]
N_TRAJECTORIES, T_END = 1024, 0.005


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


def batch_trajectories(model, reference, label: str, quick: bool) -> None:
    """Trajectories per second of N = 1024 batched trajectories, surrogate vs reference, one thread and all
    cores (module doc); written unless ``quick``."""
    n = 64 if quick else N_TRAJECTORIES
    all_cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    arms = [("reference (graded)", reference, {"stage_batched": True}), ("surrogate f64", model, {"stage_batched": True}),
            ("surrogate f32", model, {"precision": "float32", "stage_batched": True}),
            ("surrogate lockstep (before)", model, {"stage_batched": False})]
    header = ["arm", "threads", "trajectories/s", "ns per force", "n_ok", "vs reference"]
    rows = []
    ref_rate = {}
    load = os.getloadavg()
    print(f"batched trajectories: N = {n}, {T_END * 1e3:g} ms each at dt = 1e-5 s (simulate_batch)")
    print(("{:>28}{:>9}{:>16}{:>14}{:>11}{:>14}").format(*header))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        for threads in sorted({1, all_cores}):
            for name, m, kw in arms:
                if threads > 1 and kw.get("stage_batched") is False:
                    continue  # the lockstep loop runs in one thread
                repeats = 1 if m is reference else 3
                r = trajectories_per_second(m, n, T_END, repeats=repeats, threads=threads, **kw)
                rate = r["trajectories_per_s"]
                if m is reference:
                    ref_rate[threads] = rate
                row = [name, threads, f"{rate:.1f}", f"{1e9 * r['wall_s'] / r['n_force_evals']:.0f}",
                       f"{r['n_ok']}/{n}", f"{rate / ref_rate[threads]:.1f}x"]
                rows.append(row)
                print(("{:>28}{:>9}{:>16}{:>14}{:>11}{:>14}").format(*row))
    scaling = {name: float(rows[i + len(arms)][2]) / float(rows[i][2]) for i, (name, _, _) in enumerate(arms[:3])
               } if all_cores > 1 else {}
    note = ("Ratios at equal threads, both models through the same stage-batched simulate_batch "
            "(threads: contiguous chunks of the batch, one thread each). "
            + (f"Scaling {all_cores} threads / 1: " + ", ".join(f"{k} {v:.2f}x" for k, v in scaling.items()) + ". "
               if scaling else "")
            + f"Load average before / after: {load[0]:.2f} / {os.getloadavg()[0]:.2f} on {all_cores} cores; on a "
            "shared machine absolute rates and above all the thread scaling are low bounds; the ratios at equal "
            "threads are measured side by side.")
    print(note)
    if not quick:
        write_benchmark("batch_trajectories", f"trajectories per second, N = {n} batched trajectories of "
                        f"{T_END * 1e3:g} ms, surrogate ({label}) vs the graded reference, medians", header, rows,
                        notes=note)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--model", default="models/best")
    ap.add_argument("--quick", action="store_true", help="fewer forces per sample, no file written")
    ap.add_argument("--trajectories-only", action="store_true", help="only the batched trajectories")
    args = ap.parse_args()
    bearing = paper_bearing()
    if (Path(args.model) / "model.json").exists():
        model, label = load_surrogate(args.model), args.model
    else:
        model, label = best_shaped_surrogate(bearing), "best-shaped, random weights (no trained model here)"
    reference = GradedReynoldsModel(bearing)
    if args.trajectories_only:
        print(f"machine: {machine()}; surrogate: {label}")
        batch_trajectories(model, reference, label, args.quick)
        return
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
    batch_trajectories(model, reference, label, args.quick)


if __name__ == "__main__":
    main()
