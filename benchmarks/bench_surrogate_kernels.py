"""ns per force of every surrogate shape and the reference, N = 1, 64, 1024, 65536 states, beside the
arithmetic floor of each network, and batched trajectories per second (``make bench``).

    python benchmarks/bench_surrogate_kernels.py [--quick] [--trajectories-only]

Part 1 (reports/benchmarks/surrogate_kernels.json), one process, one thread, the same states for every arm:

- reference: the graded Reynolds model (``GradedReynoldsModel`` on the paper bearing), its one-state kernel;
- paper single / paper split: the paper's network shapes (4 -> 50 -> 2 tanh, one region or three);
- best: the best model's shapes (five blended regions, whirl frame, 3 -> 64 -> 2 tanh): its one-state fast
  kernel (``surrogate.kernels.fast_force_kernel``; networks in float64, and in float32 as
  ``simulate(precision="float32")`` runs them) and its batched kernel;
- ensemble: three members of the best model's shapes, their mean through the members' batched kernel.

Each surrogate's batched kernel (what ``simulate_batch`` calls once per RK4 stage: the kernel generated for
its shape, ``surrogate.kernels.batch_kernel``) runs with its networks in float64 and in float32.  Where
``models/<name>`` holds a trained model (a DVC output) it is used; otherwise a model of the same shapes with
random weights (``perf.speed.best_shaped_surrogate``, ``perf.speed.paper_shaped_surrogate``: the cost does
not depend on the weights' values), and the output says so.  Every arm runs inside a compiled loop, repeated
until about 1e5 forces per sample (N = 1 measures the kernel, not Python's call overhead); medians.

The floor beside each network: its multiply-adds per force at the GEMM rate this machine measures (numpy,
one thread, float64 and float32) plus its tanh units at the measured cost of the rational tanh in a
vectorised loop; one region's network per force (a state in a blend zone costs two).

Part 2 (reports/benchmarks/batch_trajectories.json): N = 1024 Monte Carlo trajectories of 5 ms each through
``simulate_batch`` (``perf.throughput.trajectories_per_second``), the best-shaped surrogate (float32 and
float64 networks, and the per-trajectory lockstep loop) against the graded reference run the same way, at
one thread and at all cores; the load average is recorded around each part.
"""
from __future__ import annotations

import argparse
import os
import time
import warnings
from pathlib import Path

import numpy as np
from numba import njit
from threadpoolctl import threadpool_limits

from fluidfilm import GradedReynoldsModel, load_surrogate, paper_bearing
from fluidfilm.core.force_model import one_state_kernel
from fluidfilm.perf.benchmarking import machine, median_seconds, write_benchmark
from fluidfilm.perf.speed import best_shaped_surrogate, paper_shaped_surrogate, sample_states
from fluidfilm.perf.throughput import trajectories_per_second
from fluidfilm.surrogate.ensemble import EnsembleForceModel
from fluidfilm.rotor import LinearBearing
from fluidfilm.surrogate.kernels import tanh32, tanh64

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
def _batch_passes(fn, bp, x, v, out, passes):
    acc = 0.0
    for _ in range(passes):
        fn(bp, x, v, out)
        acc += out[0, 0]
    return acc


@njit(error_model="numpy", fastmath={"contract", "reassoc"})
def _tanh_loop(a, passes, f32):
    acc = a[0] - a[0]
    for _ in range(passes):
        for i in range(a.size):
            acc += tanh32(a[i]) if f32 else tanh64(a[i])
    return acc


def floors() -> dict:
    """GEMM rate [flop/s] (numpy, one thread) and ns per rational tanh in a vectorised loop, per precision."""
    out = {}
    rng = np.random.default_rng(0)
    for dt, f32 in (("float64", False), ("float32", True)):
        a = rng.normal(size=(4096, 64)).astype(dt)
        b = rng.normal(size=(64, 64)).astype(dt)
        with threadpool_limits(1):
            t = median_seconds(lambda a=a, b=b: a @ b, 9, calls=20)
        z = rng.normal(0, 3, 4096).astype(dt)
        _tanh_loop(z, 1, f32)
        tt = median_seconds(lambda z=z, f32=f32: _tanh_loop(z, 50, f32), 7, warmup=False)
        out[dt] = {"gemm_flops_per_s": 2 * 4096 * 64 * 64 / t, "ns_per_tanh": 1e9 * tt / (50 * z.size)}
    return out


def network_floor_ns(model, fl: dict) -> float:
    """Multiply-adds of one region's network at the GEMM rate plus its tanh units (module doc)."""
    layers = model.networks[0] if model.structure == "plain" else [layer for net in model.networks[0] for layer in net]
    macs = sum(np.size(W) for W, _ in layers)
    units = sum(np.shape(W)[0] for W, _ in layers[:-1])
    return 1e9 * 2 * macs / fl["gemm_flops_per_s"] + units * fl["ns_per_tanh"]


def models(bearing) -> tuple[dict, list]:
    """name -> surrogate (trained where models/<name> holds one, else random weights of its shapes)."""
    made = {"paper single": ("models/paper_single", lambda: paper_shaped_surrogate(bearing)),
            "paper split": ("models/paper_split", lambda: paper_shaped_surrogate(bearing, split=True)),
            "best": ("models/best", lambda: best_shaped_surrogate(bearing))}
    out, random = {}, []
    for name, (path, shaped) in made.items():
        if (Path(path) / "model.json").exists():
            out[name] = load_surrogate(path)
        else:
            out[name] = shaped()
            random.append(name)
    seeds = [Path(f"models/best{s}") for s in ("", "_s1", "_s2")]
    if all((p / "model.json").exists() for p in seeds):
        out["ensemble"] = EnsembleForceModel([load_surrogate(p) for p in seeds], name="ensemble of 3")
    else:
        out["ensemble"] = EnsembleForceModel([best_shaped_surrogate(bearing, seed=s) for s in range(3)],
                                             name="ensemble of 3")
        random.append("ensemble")
    return out, random


def _ns_per_force(run, n, passes, repeats):
    run(1)  # compile
    # the CPU time of this thread: on a machine shared with other processes the wall time mostly measures them
    return 1e9 * median_seconds(lambda: run(passes), repeats, warmup=False, clock=time.thread_time) / (n * passes)


def batch_trajectories(model, reference, label: str, quick: bool) -> None:
    """Trajectories per second of N = 1024 batched trajectories, surrogate vs reference, one thread and all
    cores (module doc); written unless ``quick``."""
    n = 64 if quick else N_TRAJECTORIES
    all_cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    arms = [("reference (graded)", reference, {"stage_batched": True}),
            ("surrogate f32", model, {"precision": "float32", "stage_batched": True}),
            ("surrogate f64", model, {"precision": "float64", "stage_batched": True}),
            ("surrogate lockstep (before)", model, {"stage_batched": False}),
            # a spring and a damper: a force costing ~0.4 ns, so its time per force is the integrator's own
            ("linear bearing (integrator)", LinearBearing(reference.bearing, 1e7, 1e3), {"stage_batched": True})]
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
                # one thread: the CPU time of this thread (the batch runs in it); all cores: wall time
                r = trajectories_per_second(m, n, T_END, repeats=repeats, threads=threads,
                                            clock=time.thread_time if threads == 1 else None, **kw)
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
            "(threads: contiguous chunks of the batch, one thread each); one thread timed by the thread's CPU "
            "time, all cores by wall time. "
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
    ap.add_argument("--quick", action="store_true", help="fewer forces per sample, no file written")
    ap.add_argument("--trajectories-only", action="store_true", help="only the batched trajectories")
    args = ap.parse_args()
    bearing = paper_bearing()
    surrogates, random = models(bearing)
    label = ("random weights of the trained models' shapes for " + ", ".join(random) + " (no trained model in "
             "models/ here)") if random else "the trained models of models/"
    print(f"machine: {machine()}; surrogates: {label}")
    reference = GradedReynoldsModel(bearing)
    if args.trajectories_only:
        batch_trajectories(surrogates["best"], reference, label, args.quick)
        return
    load0 = os.getloadavg()
    fl = floors()
    print("floors: " + ", ".join(f"{dt}: GEMM {v['gemm_flops_per_s'] / 1e9:.1f} Gflop/s, rational tanh "
                                 f"{v['ns_per_tanh']:.2f} ns" for dt, v in fl.items()))
    per_sample, repeats = (2e4, 3) if args.quick else (1e5, 5)
    states = {n: sample_states(bearing.clearance, n=n, eps_max=0.8, v_max=0.05, seed=1) for n in SIZES}
    # (model, kernel, instance, batched networks' dtype or None, one-state networks' precision or None)
    arms = [("reference (graded)", "one-state", reference, None, "float64")]
    for name, m in surrogates.items():
        if name == "best":
            arms.append((name, "one-state fast", m, None, "float64"))
            arms.append((name, "one-state float32", m, None, "float32"))
        for dt in ("float64", "float32"):
            arms.append((name, f"batched {dt}", m, dt, None))
    header = ["model", "kernel"] + [f"N = {n}" for n in SIZES] + ["floor", "ref/this at N = 1024"]
    rows = []
    ref_1024 = None
    print(("{:>20}{:>18}" + "{:>12}" * (len(SIZES) + 2)).format(*header[:-1], "ref/this"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        for name, kernel, m, dt, one_precision in arms:
            ns = []
            for n in SIZES:
                x, v = states[n]
                if dt is not None:  # the batched kernels take column-major states, as simulate_batch passes them
                    x, v = np.asfortranarray(x), np.asfortranarray(v)
                out = np.empty_like(x, order="K")
                passes = max(1, int(per_sample // n))
                if dt is None:
                    fn, params, _ = one_state_kernel(m, one_precision)
                    if m is reference:
                        passes = max(1, passes // 20)  # ~30x slower: fewer forces, same sampling
                else:
                    fn, params = m.batch_force_kernel(dt)

                def run(k, fn=fn, params=params, x=x, v=v, out=out, one=dt is None):
                    return _one_state_passes(fn, params, x, v, k) if one else _batch_passes(fn, params, x, v, out, k)

                ns.append(_ns_per_force(run, n, passes, repeats if n < 65536 or m is not reference else 1))
            if m is reference:
                ref_1024 = ns[SIZES.index(1024)]
            members = m.members if isinstance(m, EnsembleForceModel) else [m]
            floor = "" if m is reference else \
                f"{sum(network_floor_ns(mm, fl[dt or one_precision]) for mm in members):.0f}"
            row = [name, kernel] + [f"{t:.0f}" for t in ns] + [floor, f"{ref_1024 / ns[SIZES.index(1024)]:.1f}x"]
            rows.append(row)
            print(("{:>20}{:>18}" + "{:>12}" * (len(SIZES) + 2)).format(*row))
    load1 = os.getloadavg()
    note = (f"ns per force, medians. Surrogates: {label}. Floor: the network's multiply-adds at the measured "
            "one-thread GEMM rate (" + ", ".join(f"{dt} {v['gemm_flops_per_s'] / 1e9:.1f} Gflop/s"
                                                for dt, v in fl.items())
            + ") plus its tanh units at the measured rational tanh ("
            + ", ".join(f"{dt} {v['ns_per_tanh']:.2f} ns" for dt, v in fl.items())
            + "), one region's network per force (the one-state rows: their networks' precision). Every arm in a compiled loop, timed "
            "by this thread's CPU time (the wall time on a shared machine mostly measures the other processes). "
            f"Load average (1 min) before / after: {load0[0]:.1f} / {load1[0]:.1f} on {os.cpu_count()} cores: "
            "the machine was shared with other work, so absolute times are high bounds; the ratios are "
            "measured side by side.")
    print(note)
    if not args.quick:
        write_benchmark("surrogate_kernels", "ns per force by number of states N: the graded reference, the "
                        "surrogates' one-state and batched kernels, one process, one thread", header, rows,
                        notes=note)
    batch_trajectories(surrogates["best"], reference, label, args.quick)


if __name__ == "__main__":
    main()
