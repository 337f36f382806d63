"""us per Swift-Stieber force: the active-set solver (the default) beside projected SOR, in one run.

    python benchmarks/bench_swift_stieber.py [--quick]

The same 32 states (paper bearing, eps 0.05-0.9, a third at rest, else |v| up to 0.3 m/s) through each
solver's compiled one-state kernel inside a compiled loop (so Python's call overhead is not timed), median
of repeats (``median_seconds``) and, for the plain rows, the fastest of 3x as many passes (on a shared, loaded
machine a pass of milliseconds waits for a core in most repeats); the Gumbel direct solve beside them for scale.  Rows: the plain bearing
on 30 x 30 (key ``swift_stieber_force_us_30x30``, also written at the top level of the file) and 60 x 60, and
Lund & Thomsen's two-groove bearing (L/D 0.5) on 72 x 31.  PSOR runs at the solvers' default tolerances
(1e-10 plain, 1e-11 grooved); the largest force difference between the two is printed with the times.  Last
row: one Lund & Thomsen operating point (equilibrium and the eight coefficients, ``lund_thomsen_point``,
median over four of their L/D 0.5 rows, ms) on 288 x 61 by the grooved solver (warm-started from call to call);
PSOR is not run there (minutes per point).  The machine's load average is recorded before and after.
"""
from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np
from numba import njit

from fluidfilm import ReynoldsSolver, paper_bearing
from fluidfilm.characteristics import published as pub
from fluidfilm.io import write_json
from fluidfilm.perf.benchmarking import machine, median_seconds, write_benchmark
from fluidfilm.reynolds import kernels
from fluidfilm.reynolds.feed import GroovedReynoldsSolver
from fluidfilm.studies import characteristics_study as study


@njit
def _passes(kernel, params, x, v, out):
    for p in range(x.shape[0]):
        f1, f2 = kernel(params, x[p, 0], x[p, 1], v[p, 0], v[p, 1])
        out[p, 0] = f1
        out[p, 1] = f2


def _states(c, n=32, seed=0):
    rng = np.random.default_rng(seed)
    e, a = rng.uniform(0.05, 0.9, n), rng.uniform(0, 2 * np.pi, n)
    x = np.stack([e * c * np.sin(a), e * c * np.cos(a)], axis=1)
    v = rng.uniform(-0.3, 0.3, (n, 2))
    v[::3] = 0.0
    return np.ascontiguousarray(x), np.ascontiguousarray(v)


def _us(model, x, v, repeats):
    fn, params = model.force_kernel
    out = np.empty_like(x)
    t = median_seconds(lambda: _passes(fn, params, x, v, out), repeats)
    return 1e6 * t / x.shape[0], out.copy()


def _us_fastest(model, x, v, repeats):
    """The fastest of ``repeats`` passes, us per force: on a machine shared with other work the median of
    a pass that lasts milliseconds includes waits for a core, the fastest pass the fewest."""
    fn, params = model.force_kernel
    out = np.empty_like(x)
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        _passes(fn, params, x, v, out)
        best = min(best, time.perf_counter() - t0)
    return 1e6 * best / x.shape[0]


def _solves(model, x, v) -> float:
    """Mean number of linear solves of the active-set iteration per force, from a cold start (as
    ``film_force_ss`` starts: ``mode_one_film``'s guess for these symmetric fields)."""
    params = model.params
    counts = []
    for k in range(x.shape[0]):
        p = np.zeros((params.n_theta, params.full_basis.shape[0] + 2))
        counts.append(kernels.swift_stieber_field(params, x[k, 0], x[k, 1], v[k, 0], v[k, 1], p))
    return float(np.mean(counts))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="fewer repeats (smoke run)")
    args = ap.parse_args()
    repeats = 3 if args.quick else 9
    print(machine())
    load_before = os.getloadavg()
    print("load average", load_before)
    b = paper_bearing()
    rows = []
    header = ["case", "active-set us/force", "PSOR us/force", "speed-up", "Gumbel direct us/force",
              "max |dF| / max |F|", "fastest pass: active-set / PSOR / Gumbel us/force"]
    solves: dict[str, float] = {}
    for n in (30, 60):
        x, v = _states(b.clearance)
        new = ReynoldsSolver(b, n, n, cavitation="swift-stieber")
        old = ReynoldsSolver(b, n, n, cavitation="swift-stieber", method="psor")
        gum = ReynoldsSolver(b, n, n, cavitation="gumbel")
        t_new, f_new = _us(new, x, v, repeats)
        t_old, f_old = _us(old, x, v, repeats)
        t_gum, _ = _us(gum, x, v, repeats)
        fastest = " / ".join(f"{_us_fastest(m, x, v, 3 * repeats):.1f}" for m in (new, old, gum))
        solves[f"{n}x{n}"] = _solves(new, x, v)
        rows.append([f"plain {n}x{n}", f"{t_new:.1f}", f"{t_old:.1f}", f"{t_old / t_new:.1f}x", f"{t_gum:.1f}",
                     f"{np.abs(f_new - f_old).max() / np.abs(f_old).max():.1e}", fastest])
        print(" | ".join(rows[-1]), flush=True)
    lt = study.lund_thomsen_bearing(0.5, (72, 31))
    lt_psor = GroovedReynoldsSolver(lt.bearing, 72, 31, cavitation="swift-stieber", groove_angle=lt.groove_angle,
                                    n_grooves=2, groove_width=np.radians(20.0), method="psor")
    x, v = _states(lt.bearing.clearance, n=16, seed=1)
    t_new, f_new = _us(lt, x, v, repeats)
    t_old, f_old = _us(lt_psor, x, v, repeats)
    rows.append(["Lund & Thomsen 2-groove 72x31", f"{t_new:.1f}", f"{t_old:.1f}", f"{t_old / t_new:.1f}x", "-",
                 f"{np.abs(f_new - f_old).max() / np.abs(f_old).max():.1e}", "-"])
    print(" | ".join(rows[-1]), flush=True)
    grid = (72, 31) if args.quick else (288, 61)
    lt = study.lund_thomsen_bearing(0.5, grid)
    sommerfeld = [row[0] for row in pub.LUND_THOMSEN_1978[0.5]][:4]
    study.lund_thomsen_point(lt, sommerfeld[0])  # compiles
    per_point = []
    for s in sommerfeld:
        t0 = time.perf_counter()
        study.lund_thomsen_point(lt, s)
        per_point.append(time.perf_counter() - t0)
    rows.append([f"Lund & Thomsen operating point {grid[0]}x{grid[1]} (ms)", f"{1e3 * np.median(per_point):.1f}",
                 "-", "-", "-", "-", "-"])
    print(" | ".join(rows[-1]), flush=True)
    load_after = os.getloadavg()
    print("load average", load_after)
    if not args.quick:
        notes = ("PSOR at the solvers' default tolerances; the active-set solve is exact up to round-off. "
                        "Plain: 32 states of the paper bearing, eps 0.05-0.9; grooved: 16 states; operating point: "
                        "equilibrium + K and C by central differences. Linear solves per plain force from a cold "
                        "start, mean over the 32 states: "
                        + ", ".join(f"{k} {v:.2f}" for k, v in solves.items()) + ". Load average (1, 5, 15 min) before "
                        f"{tuple(round(a, 1) for a in load_before)}, after {tuple(round(a, 1) for a in load_after)} "
                        "on a machine shared with other work: ratios in one run are what compare.")
        path = write_benchmark("swift_stieber", "Swift-Stieber force, us per force: active-set solver vs projected SOR "
                               "(compiled kernels, medians of 9 repeats over the same states)", header, rows, notes)
        doc = json.loads(path.read_text())
        doc["swift_stieber_force_us_30x30"] = float(rows[0][1])
        doc["swift_stieber_force_us_30x30_fastest_pass"] = float(rows[0][-1].split(" / ")[0])
        doc["lund_thomsen_point_ms"] = float(rows[-1][1])
        doc["active_set_solves_per_force_mean"] = solves
        doc["load_average_before"] = list(load_before)
        doc["load_average_after"] = list(load_after)
        write_json(path, doc)


if __name__ == "__main__":
    main()
