"""Benchmark of a rotor trajectory with the reference model: the paper's case e.

    python benchmarks/bench_rotor.py [--quick]

Prints the median wall time of case e (m_u d = 1e-3 kg m, 0.5 s of rotor
time, dt = 1e-5 s, RK4: 200,000 force evaluations) with the reference model
at 30x30, 55x55 and the paper's graded policy, and the cost per step and per
force evaluation.
"""
from __future__ import annotations

import argparse
import os
import time

import numpy as np

from fluidfilm import GradedReynoldsModel, ReynoldsSolver, Rotor, paper_bearing, simulate


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    t_end, repeats = (0.1, 2) if args.quick else (0.5, 5)
    b = paper_bearing()
    rotor = Rotor(mass=2.5, imbalance=1e-3)
    models = {"30x30": ReynoldsSolver(b, 30, 30), "55x55": ReynoldsSolver(b, 55, 55),
              "graded 30/55 @0.9": GradedReynoldsModel(b)}
    print(f"case e, t_end={t_end} s, dt=1e-5 s, {os.cpu_count()} cores (the integrator runs on one)")
    print(f"{'model':>18} {'median s':>9} {'us/step':>8} {'us/force':>9} {'steps':>7}")
    table = []
    for name, model in models.items():
        simulate(model, rotor, t_end=0.001, dt=1e-5)  # compile
        times = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            tr = simulate(model, rotor, t_end=t_end, dt=1e-5, record_every=10)
            times.append(time.perf_counter() - t0)
        med = float(np.median(times))
        steps = int(round(t_end / 1e-5))
        print(f"{name:>18} {med:9.3f} {1e6 * med / steps:8.2f} {1e6 * med / tr.n_force_evals:9.2f} {steps:7d}"
              f"  ({tr.status})")
        table.append([name, f"{med:.2f} s", f"{1e6 * med / steps:.1f} us", f"{1e6 * med / tr.n_force_evals:.1f} us",
                      tr.status])
    if not args.quick:
        from fluidfilm.perf.benchmarking import write_benchmark

        write_benchmark("rotor", f"Case e trajectory with the reference model ({t_end} s of rotor time, dt = 1e-5 s, "
                        f"RK4, median of {repeats})", ["model", "wall time", "per RK4 step", "per force evaluation",
                                                       "status"], table)


if __name__ == "__main__":
    main()
