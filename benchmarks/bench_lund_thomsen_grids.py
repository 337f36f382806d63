"""Lund & Thomsen's two-groove bearing on a ladder of grids: accuracy, time per operating point, observed order of
convergence and Richardson extrapolation.

    python benchmarks/bench_lund_thomsen_grids.py [--quick]

Every row of both tables (21; ``--quick``: three L/D 0.5 rows on the three coarsest grids, no file) through
``studies.characteristics_study.lund_thomsen_point`` (equilibrium + central-difference coefficients, grooved
Swift-Stieber solver) on the doubling ladder 36x16, 72x31, 144x61, 288x121 (the mesh width halves in both
directions from one grid to the next, and the 20 deg grooves cover whole node spans on each) and on 288x61, the
grid ``bench_ross_peer.py`` quotes.  Per grid: the largest coefficient error over the rows
(``lund_thomsen_err_pct``, beyond half a printed unit) and the median time per operating point.  Per three
consecutive grids of the ladder and per quantity (eps, phi and the seven coefficients of every row): the
observed order log2(|q_h - q_2h| / |q_h/2 - q_h|) where the differences keep their sign (a monotone sequence),
and how many sequences are not monotone.  Per two consecutive grids: the largest error of the Richardson
extrapolation (4 q_h/2 - q_h) / 3, which assumes the O(h^2) error of the scheme's smooth part.  The machine's
load average is recorded.  Writes reports/benchmarks/lund_thomsen_grids.json.
"""
from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

from fluidfilm.characteristics import published as pub
from fluidfilm.io import write_json
from fluidfilm.perf.benchmarking import machine, write_benchmark
from fluidfilm.studies import characteristics_study as study

LADDER = [(36, 16), (72, 31), (144, 61), (288, 121)]
QUOTED = (288, 61)
NAMES = list(pub.LUND_THOMSEN_COEFFICIENTS)


def worst_err(result: dict, published: dict) -> float:
    return max(study.lund_thomsen_err_pct(result[n], published, n) for n in NAMES)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="three rows, the three coarsest grids, no file")
    args = ap.parse_args()
    rows = [(ld, dict(zip(pub.LUND_THOMSEN_COLUMNS, v))) for ld, t in pub.LUND_THOMSEN_1978.items() for v in t]
    ladder = LADDER[:3] if args.quick else LADDER
    grids = ladder if args.quick else ladder + [QUOTED]
    if args.quick:
        rows = rows[:3]
    print(machine())
    load0 = os.getloadavg()
    results: dict[str, list[dict]] = {}
    seconds: dict[str, list[float]] = {}
    for g in grids:
        key = f"{g[0]}x{g[1]}"
        solvers = {ld: study.lund_thomsen_bearing(ld, g) for ld in sorted({r[0] for r in rows})}
        for s in solvers.values():
            study.lund_thomsen_point(s, rows[0][1]["S"])  # compiles, warms the cavitation set
        results[key], seconds[key] = [], []
        for ld, p in rows:
            t0 = time.perf_counter()
            r = study.lund_thomsen_point(solvers[ld], p["S"])
            seconds[key].append(time.perf_counter() - t0)
            results[key].append({k: float(v) for k, v in r.items()})
        print(f"{key}: largest error {max(worst_err(r, p) for r, (_, p) in zip(results[key], rows)):.2f} %, "
              f"{1e3 * np.median(seconds[key]):.1f} ms per point", flush=True)
    quantities = ["eps", "phi", *NAMES]
    order_rows, orders = [], {}
    for a, b, c in zip(ladder[:-2], ladder[1:-1], ladder[2:]):
        ka, kb, kc = (f"{g[0]}x{g[1]}" for g in (a, b, c))
        o = []
        for ra, rb, rc in zip(results[ka], results[kb], results[kc]):
            for q in quantities:
                d1, d2 = rb[q] - ra[q], rc[q] - rb[q]
                o.append(float(np.log2(abs(d1 / d2))) if d1 * d2 > 0.0 else float("nan"))
        arr = np.array(o)
        mono = arr[np.isfinite(arr)]
        orders[f"{ka},{kb},{kc}"] = o
        order_rows.append([f"observed order {ka} -> {kb} -> {kc}",
                           f"median {np.median(mono):.2f}, quartiles {np.percentile(mono, 25):.2f} .. "
                           f"{np.percentile(mono, 75):.2f}; {np.isnan(arr).sum()} of {arr.size} sequences not monotone"])
    rich_rows, rich = [], {}
    for a, b in zip(ladder[:-1], ladder[1:]):
        ka, kb = (f"{g[0]}x{g[1]}" for g in (a, b))
        ext = [{q: (4.0 * rb[q] - ra[q]) / 3.0 for q in quantities} for ra, rb in zip(results[ka], results[kb])]
        errs = [worst_err(r, p) for r, (_, p) in zip(ext, rows)]
        rich[f"{ka}+{kb}"] = errs
        rich_rows.append([f"Richardson {ka} + {kb}", f"largest error {max(errs):.2f} %, "
                          f"{sum(e > 3.0 for e in errs)} rows above 3 %"])
    load1 = os.getloadavg()
    header = ["grid or combination", "result"]
    table = [[f"grid {k}", f"largest error {max(worst_err(r, p) for r, (_, p) in zip(v, rows)):.2f} %, "
              f"{sum(worst_err(r, p) > 3.0 for r, (_, p) in zip(v, rows))} rows above 3 %, "
              f"{1e3 * np.median(seconds[k]):.1f} ms per operating point (median)"] for k, v in results.items()]
    table += order_rows + rich_rows
    for line in table:
        print(" | ".join(line))
    if args.quick:
        return
    notes = (f"{len(rows)} rows (both L/D), equilibrium + seven printed coefficients per row by "
             f"studies.characteristics_study.lund_thomsen_point; error: lund_thomsen_err_pct (beyond half a printed unit). "
             f"Observed order over the quantities eps, phi and the seven coefficients of every row (a sequence whose "
             f"differences change sign has none). Load average {load0[0]:.1f} before, {load1[0]:.1f} after "
             f"(2 cores shared with other work).")
    path = write_benchmark("lund_thomsen_grids", "Lund & Thomsen's two-groove bearing on a grid ladder: accuracy, "
                           "time, observed order, Richardson extrapolation", header, table, notes)
    doc = json.loads(path.read_text())
    doc["raw"] = {"results": results, "seconds": seconds, "observed_order": orders, "richardson_worst_err_pct": rich,
                  "loadavg_before": list(load0), "loadavg_after": list(load1)}
    write_json(path, doc)


if __name__ == "__main__":
    main()
