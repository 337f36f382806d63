"""Cost of one Levenberg-Marquardt epoch of the paper's 1x50 tanh network, per training sample.

    python benchmarks/bench_lm.py [--samples 30000] [--threads 1]

Prints medians (wall and CPU time) of J^T J + J^T e accumulation (the block-structured path used in
training and the plain full-Jacobian path), and of one whole LM epoch (normal equations, Cholesky solve,
trial error), in microseconds per training sample; this sets the subsample sizes of the paper stages.
"""
from __future__ import annotations

import argparse
import time

import numpy as np
from threadpoolctl import threadpool_limits

from fluidfilm.surrogate.training.levenberg_marquardt import (LMSettings, init_nguyen_widrow, levenberg_marquardt, mlp_sse,
                                                     normal_equations, normal_equations_dense)


def median_us(fn, n, repeats):
    fn()
    wall, cpu = [], []
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return 1e6 * np.median(wall) / n, 1e6 * np.median(cpu) / n


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--samples", type=int, default=30000)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--repeats", type=int, default=5)
    a = ap.parse_args()
    rng = np.random.default_rng(0)
    Z = rng.uniform(-1, 1, (a.samples, 4))
    Y = np.stack([np.sin(2 * Z[:, 0]) * Z[:, 2], np.tanh(Z[:, 1] + Z[:, 3])], axis=1)
    th = init_nguyen_widrow(4, 50, 2, rng)
    with threadpool_limits(a.threads):
        rows = {
            "J^T J, block (training path)": lambda: normal_equations(th, Z, Y, 50),
            "J^T J, full Jacobian": lambda: normal_equations_dense(th, Z, Y, 50),
            "one LM epoch": lambda: levenberg_marquardt(th, lambda t: normal_equations(t, Z, Y, 50),
                                                        lambda t: mlp_sse(t, Z, Y, 50), Y.size,
                                                        LMSettings(max_epochs=1)),
        }
        print(f"{a.samples:,} samples, {a.threads} BLAS thread(s)")
        for name, fn in rows.items():
            w, c = median_us(fn, a.samples, a.repeats)
            print(f"  {name:32s} {w:7.2f} us wall, {c:7.2f} us CPU per sample")


if __name__ == "__main__":
    main()
