"""The mass-conserving (JFO / Elrod-Adams) film's cost: us per rotor time step and a rotor second of the paper's
case d, beside the same solver under the non-conserving rules and the plain Swift-Stieber reference.

    python benchmarks/bench_jfo.py [--quick]

Rows, on the paper's bearing (fed through a groove at the top for the film solvers), 5 kg rotor on two
bearings, case d (imbalance 5e-4 kg m), dt = 1e-5 s, from the equilibrium's neighbourhood:

- us per time step (RK4: four stage solves and, for JFO, one committed step) on 30 x 30, median of repeats of
  ``steps`` steps after a warm-up, for JFO (the defaults: solves to 1e-5, the commit's flow balance closed
  node by node; a looser 1e-4; the commit at 1e-8 as before the closing pass), Swift-Stieber and Guembel on
  the same solver and for the plain
  ``ReynoldsSolver`` Swift-Stieber (its active-set direct solves; no groove), with the Gauss-Seidel sweeps
  per stage and per commit;
- one rotor second of case d with JFO on 30 x 30 (the issue's goal: <= 60 s on one core).

Written to reports/benchmarks/jfo.json with the machine and its load average.
"""
from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

from fluidfilm import ReynoldsSolver, Rotor, paper_bearing, simulate
from fluidfilm.perf.benchmarking import machine, write_benchmark
from fluidfilm.reynolds.elrod_adams import ElrodAdamsSolver
from fluidfilm.surrogate.film_memory import MemorySurrogate

ROOT = Path(__file__).resolve().parents[1]


def per_step(model, rotor, steps: int, repeats: int) -> tuple[float, dict]:
    simulate(model, rotor, t_end=20e-5, dt=1e-5, x0=(0.0, 50e-6))
    times, meta = [], {}
    for _ in range(repeats):
        tr = simulate(model, rotor, t_end=steps * 1e-5, dt=1e-5, x0=(0.0, 50e-6), record_every=100)
        times.append(tr.wall_time_s / steps)
        meta = dict(tr.meta, solves_per_step=tr.meta.get("film_solves", 4 * steps) / steps)
    times.sort()
    return 1e6 * times[len(times) // 2], meta


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer steps and repeats")
    args = ap.parse_args()
    steps, repeats, second = (500, 3, 0.05) if args.quick else (5000, 5, 1.0)
    b = paper_bearing()
    rotor = Rotor.shared(total_mass=5.0, total_imbalance=5e-4, load_share=0.5)
    load = os.getloadavg()
    rows = []
    models = [("JFO (Elrod-Adams), 30 x 30", ElrodAdamsSolver(b, 30, 30)),
              ("JFO, 30 x 30, stage and commit tol 1e-4", ElrodAdamsSolver(b, 30, 30, tol=1e-4, tol_commit=1e-4)),
              ("JFO, 30 x 30, commit tol 1e-8 (the default before the closing pass)",
               ElrodAdamsSolver(b, 30, 30, tol_commit=1e-8)),
              ("Swift-Stieber, same solver", ElrodAdamsSolver(b, 30, 30, cavitation="swift-stieber")),
              ("Guembel, same solver", ElrodAdamsSolver(b, 30, 30, cavitation="gumbel")),
              ("Swift-Stieber, ReynoldsSolver (no groove)", ReynoldsSolver(b, 30, 30, cavitation="swift-stieber"))]
    if (ROOT / "models" / "jfo_surrogate" / "model.json").is_file():  # the jfo_surrogate stage's model
        models.append(("JFO surrogate with memory (models/jfo_surrogate)",
                       MemorySurrogate.load(ROOT / "models" / "jfo_surrogate")))
    for label, model in models:
        us, meta = per_step(model, rotor, steps, repeats)
        rows.append([label, f"{us:.1f}", f"{us / meta['solves_per_step']:.1f}",
                     f"{meta.get('sweeps_per_stage', float('nan')):.1f}",
                     f"{meta.get('sweeps_per_commit', float('nan')):.1f}"])
        print(rows[-1], flush=True)
    film = ElrodAdamsSolver(b, 30, 30)
    t0 = time.perf_counter()
    tr = simulate(film, rotor, t_end=second, dt=1e-5, x0=(0.0, 50e-6), record_every=100)
    wall = time.perf_counter() - t0
    rows.append([f"case d, {second:g} rotor s, JFO 30 x 30 (s)", f"{wall:.1f}", "", tr.status, ""])
    print(rows[-1], flush=True)
    notes = (f"{machine()}; load average {load} before, {os.getloadavg()} after; steps {steps}, repeats {repeats}. "
             "Goal: <= 100 us per time step on 30 x 30; one rotor second of case d <= 60 s. A rotor time step is "
             "RK4's four stage solves plus the committed step; a film call is one of them (one backward-Euler "
             "solve of the film under JFO; a commit costs nothing under the non-conserving rules, whose content stays full).")
    write_benchmark("jfo", "The mass-conserving film's cost per rotor time step (RK4, dt = 1e-5 s, case d)",
                    ["model", "us per rotor step (or s)", "us per film call", "sweeps per stage", "sweeps per commit"],
                    rows, notes)


if __name__ == "__main__":
    main()
