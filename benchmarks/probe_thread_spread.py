"""Why the batched surrogate's two-thread runs spread: CPU accounting and the host's vector scaling per run.

    python benchmarks/probe_thread_spread.py [--pairs 25]

``batch_speed`` alternates one-thread and all-thread runs of the best surrogate's batch (N = 1024, 5 ms of
rotor time each). On the project's VM the two-thread runs spread from ~56 to ~100 ms while a loop of
back-to-back two-thread batches stays near 56 ms. This probe takes ``--pairs`` such pairs and records, per
run, from ``/proc/stat``: each CPU's busy, idle and steal ticks (a slow run whose CPUs idle was held back by a
wait; one whose CPUs were busy throughout did more work or ran slower), and before each pair the cores' own
two-thread scaling (``fluidfilm.perf.cores``: a vectorised FMA loop and a scalar latency chain, 0.03 s each).
Writes reports/benchmarks/thread_spread.json (a table and, under ``runs``, every run).
"""
from __future__ import annotations

import argparse
import json
import os

import numpy as np

from fluidfilm.io import write_json
from fluidfilm.perf import write_benchmark
from fluidfilm.perf.cores import core_scaling
from fluidfilm.perf.throughput import trajectories_per_second
from fluidfilm.perf.speed import best_shaped_surrogate
from fluidfilm import paper_bearing


def cpu_ticks() -> dict[str, dict[str, int]]:
    """Per-CPU busy (user + nice + system), idle and steal ticks from /proc/stat."""
    out = {}
    with open("/proc/stat") as f:
        for line in f:
            if line.startswith("cpu") and line[3].isdigit():
                v = line.split()
                out[v[0]] = {"busy": int(v[1]) + int(v[2]) + int(v[3]), "idle": int(v[4]), "steal": int(v[8])}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=25, help="one-thread / all-thread pairs (>= 2)")
    args = ap.parse_args()
    if args.pairs < 2:
        ap.error(f"--pairs must be >= 2, got {args.pairs}")
    if not os.path.exists("/proc/stat"):
        raise SystemExit("error: /proc/stat is missing: this probe reads Linux's CPU accounting")
    threads = len(os.sched_getaffinity(0))
    if threads < 2:
        raise SystemExit(f"error: this process may run on {threads} CPU: nothing to spread across")
    model = best_shaped_surrogate(paper_bearing())
    n, t_end, dt = 1024, 5e-3, 1e-5
    for th in (1, None):  # compile both paths
        trajectories_per_second(model, n, t_end, dt, batched=True, threads=th)
    runs = []
    for _ in range(args.pairs):
        probe = core_scaling(threads=threads, seconds=0.03, repeats=1)
        for arm, th in (("one", 1), ("all", None)):
            a = cpu_ticks()
            wall = trajectories_per_second(model, n, t_end, dt, batched=True, threads=th)["wall_s"]
            b = cpu_ticks()
            d = {k: sum(b[c][k] - a[c][k] for c in a) for k in ("busy", "idle", "steal")}
            runs.append({"arm": arm, "wall_s": wall, **{f"{k}_ticks": val for k, val in d.items()},
                         "vector_fma_before": probe["vector_fma"], "scalar_chain_before": probe["scalar_chain"]})
    hz = os.sysconf("SC_CLK_TCK")
    one = [r for r in runs if r["arm"] == "one"]
    every = [r for r in runs if r["arm"] == "all"]
    scaling = np.array([o["wall_s"] / e["wall_s"] for o, e in zip(one, every)])
    fma = np.array([e["vector_fma_before"] for e in every])
    chain = np.array([e["scalar_chain_before"] for e in every])
    med = float(np.median([e["wall_s"] for e in every]))
    slow, fast = [e for e in every if e["wall_s"] > med], [e for e in every if e["wall_s"] <= med]

    def cpu_ms(rs):
        return 1e3 * float(np.mean([r["busy_ticks"] for r in rs])) / hz

    def row(label, rs):
        w = [1e3 * r["wall_s"] for r in rs]
        return [label, str(len(rs)), f"{np.median(w):.1f} ({min(w):.1f}-{max(w):.1f})", f"{cpu_ms(rs):.0f}",
                f"{1e3 * np.mean([r['idle_ticks'] for r in rs]) / hz:.0f}", f"{sum(r['steal_ticks'] for r in rs)}"]

    rows = [row("one thread", one), row("all threads", every), row("all threads, slower half", slow),
            row("all threads, faster half", fast)]
    notes = (f"{threads} threads, {hz} ticks/s (busy and idle: CPU ms summed over the CPUs, mean per run; steal: ticks summed over all runs). "
             f"Pair scaling (one / all) median {np.median(scaling):.2f} ({scaling.min():.2f}-{scaling.max():.2f}); "
             f"the vector FMA probe before each pair median {np.median(fma):.2f} ({fma.min():.2f}-{fma.max():.2f}), "
             f"the scalar chain {np.median(chain):.2f} ({chain.min():.2f}-{chain.max():.2f}); correlation of the pair "
             f"scaling with the FMA probe {np.corrcoef(scaling, fma)[0, 1]:.2f}.")
    path = write_benchmark("thread_spread", "Batched best-shaped surrogate, N = 1024, 5 ms: one thread vs all, "
                           "with the CPUs' accounting per run", ["runs", "n", "wall ms, median (range)",
                                                                 "busy CPU ms per run", "idle CPU ms per run",
                                                                 "steal ticks"], rows, notes=notes)
    table = json.loads(path.read_text())
    table["runs"] = runs
    write_json(path, table)


if __name__ == "__main__":
    main()
