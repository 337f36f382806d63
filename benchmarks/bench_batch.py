"""Trajectories per second, one at a time and batched, reference vs the best surrogate, side by side.

    python benchmarks/bench_batch.py [--model models/best] [--t-end 0.005] [--quick] [--json out.json]

N = 1, 64, 1024 Monte Carlo trajectories (imbalance, side load, initial
state; ``fluidfilm.perf.throughput``), each ``t_end`` of rotor time at dt = 1e-5 s.
The reference is the paper's graded policy (30x30 below eps 0.9, 55x55
above), driven the same way as the surrogate: ``simulate`` per trajectory
and ``simulate_batch`` for the batch.  Unbatched runs of N = 1024 are
skipped for the reference (minutes; per-trajectory cost is the N = 64 one).
Prints trajectories per second and the ratios surrogate / reference.
"""
from __future__ import annotations

import argparse
import json
import os

from fluidfilm import GradedReynoldsModel, load_surrogate, paper_bearing
from fluidfilm.perf.throughput import trajectories_per_second


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--model", default="models/best")
    ap.add_argument("--t-end", type=float, default=0.005)
    ap.add_argument("--quick", action="store_true", help="N = 1, 16, 64")
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    sizes = (1, 16, 64) if args.quick else (1, 64, 1024)
    models = {"reference (graded)": GradedReynoldsModel(paper_bearing()), "surrogate": load_surrogate(args.model)}
    print(f"{len(sizes)} batch sizes, t_end={args.t_end} s per trajectory, dt=1e-5 s, {os.cpu_count()} cores "
          "(serial loops)")
    print(f"{'model':>20} {'N':>5} {'traj/s one by one':>18} {'traj/s batched':>15}")
    rows = []
    for n in sizes:
        for name, model in models.items():
            single = None
            if n <= 64 or name == "surrogate":
                single = trajectories_per_second(model, n, args.t_end, batched=False, repeats=3 if n == 1 else 1)
            batch = trajectories_per_second(model, n, args.t_end, batched=True, repeats=3 if n == 1 else 1)
            rows.append({"model": name, "n": n, "one_by_one": single and single["trajectories_per_s"],
                         "batched": batch["trajectories_per_s"], "n_ok": batch["n_ok"]})
            print(f"{name:>20} {n:5d} {single['trajectories_per_s'] if single else float('nan'):18.1f} "
                  f"{batch['trajectories_per_s']:15.1f}  ({batch['n_ok']}/{n} ok)")
    by = {(r["model"], r["n"]): r for r in rows}
    print("surrogate / reference, trajectories per second:")
    ratios = {}
    for n in sizes:
        s, r = by[("surrogate", n)], by[("reference (graded)", n)]
        ratios[n] = {"batched": s["batched"] / r["batched"],
                     "one_by_one": (s["one_by_one"] / r["one_by_one"]) if r["one_by_one"] else None,
                     "surrogate_batch_vs_reference_single": s["batched"] / by[("reference (graded)", 1)]["one_by_one"]}
        print(f"  N={n:5d}: batched {ratios[n]['batched']:.1f}x, surrogate batched vs reference one at a time "
              f"(N=1) {ratios[n]['surrogate_batch_vs_reference_single']:.1f}x"
              + (f", one by one {ratios[n]['one_by_one']:.1f}x" if ratios[n]["one_by_one"] else ""))
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"rows": rows, "ratios": {str(k): v for k, v in ratios.items()}, "t_end_s": args.t_end}, f,
                      indent=1)


if __name__ == "__main__":
    main()
