"""External-peer benchmark: ROSS (ross-rotordynamics 2.3.0, PlainJournal) vs our reference solver on
Lund & Thomsen's (1978) two-axial-groove bearing, L/D = 0.5: dynamic coefficients and time per set.

    make ross-peer                      (creates .venv-ross with ROSS, then runs this)
    ROSS_PYTHON=/path/to/python .venv/bin/python benchmarks/bench_ross_peer.py [--quick] [--ross-mesh 11x3 30x10]

Our side (this venv): ``study.lund_thomsen_table`` on grids 72x31 and 288x61 (grooved Swift-Stieber
solver, central differences), and the 72x31 grid with Gumbel cavitation (ROSS 2.3's condition: the
like-for-like row), timed with ``median_seconds``: the coefficient set alone at the
equilibrium, and equilibrium + coefficients.  ROSS side: ``benchmarks/ross_peer_ross_side.py`` run with
the interpreter in ROSS_PYTHON (default .venv-ross/bin/python); ROSS computes the equilibrium and the
coefficients in PlainJournal's constructor, so its time is that whole call (and, separately, its
``coefficients`` call alone).  Errors vs published: the ``*_err_pct`` measure of
``study.lund_thomsen_table`` (beyond the 0.005 print rounding, relative to max(|pub|, 0.1 x the largest
published term of that matrix)).  Writes reports/benchmarks/ross_peer.json unless --quick.
"""
from __future__ import annotations

import argparse
import functools
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

from fluidfilm import io
from fluidfilm.perf.benchmarking import median_seconds
from fluidfilm.characteristics import coefficients as coef
from fluidfilm.characteristics import published as pub
from fluidfilm.characteristics import static
from fluidfilm.studies import characteristics as study

NAMES = pub.LUND_THOMSEN_COEFFICIENTS
ROSS_SIDE = Path(__file__).with_name("ross_peer_ross_side.py")


def ours(grid, rows, repeats: int, cavitation: str = "swift-stieber") -> dict:
    """Per S: equilibrium and coefficients (``study.lund_thomsen_point``) and the two timings [s]."""
    solver = study.lund_thomsen_bearing(0.5, grid, cavitation=cavitation)
    out = {}
    for p in rows:
        load = study.load_at_sommerfeld(solver.bearing, p["S"])
        x0 = static.equilibrium(solver, (0.0, load))["X"]

        def eq_and_coef(load=load):
            return coef.reference_coefficients(solver, static.equilibrium(solver, (0.0, load))["X"])

        t_coef = median_seconds(functools.partial(coef.reference_coefficients, solver, x0), repeats)
        t_both = median_seconds(eq_and_coef, repeats)
        out[p["S"]] = {**study.lund_thomsen_point(solver, p["S"]), "coef_s": t_coef, "eq_coef_s": t_both,
                       "grid": f"{solver.n_theta}x{solver.n_z}", "cavitation": cavitation}
        print(f"ours {grid} {cavitation} S={p['S']}: coef {1e3 * t_coef:.1f} ms, eq+coef {1e3 * t_both:.1f} ms",
              flush=True)
    return out


def ross(python: str, meshes, rows, repeats: int, method: str) -> dict:
    cmd = [python, str(ROSS_SIDE), "--method", method, "--repeats", str(repeats), "--mesh", *meshes,
           "--rows", *[str(p["S"]) for p in rows]]
    print("running the ROSS side:", " ".join(cmd), flush=True)
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if proc.returncode != 0:
        tail = "\n".join(line for line in proc.stderr.splitlines() if "REFPROP" not in line)[-3000:]
        sys.exit(f"ROSS side failed (exit {proc.returncode}):\n{tail}")
    lines = [s for s in proc.stdout.splitlines() if s.startswith("{")]
    if not lines:
        sys.exit(f"ROSS side exited 0 without its JSON line; its stdout ended with: {proc.stdout[-500:]!r}")
    return json.loads(lines[-1])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="two rows, 72x31 and ROSS 11x3 only, 2 repeats, no file")
    ap.add_argument("--ross-mesh", nargs="+", default=["11x3", "30x10"],
                    help="ROSS elements_circumferential x elements_axial per pad (11x3 is ROSS 2.3's test mesh)")
    ap.add_argument("--ross-method", default="lund", choices=["lund", "perturbation"])
    ap.add_argument("--grids", nargs="+", default=["72x31", "288x61"])
    args = ap.parse_args()
    python = os.environ.get("ROSS_PYTHON", ".venv-ross/bin/python")
    if not (Path(python).is_file() and os.access(python, os.X_OK)):
        sys.exit(f"no ROSS interpreter at {python}: create it with `make ross-peer` (or set ROSS_PYTHON)")

    rows = [dict(zip(pub.LUND_THOMSEN_COLUMNS, v)) for v in pub.LUND_THOMSEN_1978[0.5]
            if (0.5, v[0]) in pub.LUND_THOMSEN_TWO_TYPINGS]
    grids, meshes, repeats = args.grids, args.ross_mesh, 7
    if args.quick:
        rows, grids, meshes, repeats = rows[::4], grids[:1], meshes[:1], 2

    # ROSS first (its own process), so our timings are not taken while it starts
    r = ross(python, meshes, rows, 3 if not args.quick else 1, args.ross_method)
    models = {}
    for g in grids:
        models[f"ours {g}"] = ours(tuple(int(v) for v in g.split("x")), rows, repeats)
    # the like-for-like row: ROSS 2.3 clips the linear pressure at zero (Gumbel), so our grooved solver with the
    # same condition should land on its equilibrium; its coefficients show what the cavitation condition does
    models[f"ours {grids[0]} Gumbel"] = ours(tuple(int(v) for v in grids[0].split("x")), rows, repeats, "gumbel")
    for res in r["results"]:
        models.setdefault(f"ROSS {res['mesh']}", {})[res["S"]] = {
            **{k: res[k] for k in ("eps", "phi", *NAMES)}, "coef_s": res["coef_seconds"],
            "eq_coef_s": res["seconds"], "timing": res["timing"], "nfev": res["nfev_equilibrium"]}

    base = [f"ours {g}" for g in grids]  # the Swift-Stieber rows: what the ratios are taken against
    header = ["S", "model", "eps", "phi [deg]", *NAMES, "worst err %", "coef set [ms]", "eq + coef [ms]",
              *[f"x {m} (eq + coef)" for m in base]]
    table, summary = [], {}
    for p in rows:
        table.append([f"{p['S']:.3f}", "published", f"{p['eps']:.3f}", f"{p['phi']:.2f}",
                      *[f"{p[n]:.2f}" for n in NAMES], "", "", "", *["" for _ in base]])
        for name, per_s in models.items():
            v = per_s[p["S"]]
            errs = {n: study.lund_thomsen_err_pct(v[n], p, n) for n in NAMES}
            v["err_pct"], v["worst_err_pct"] = errs, max(errs.values())
            ratios = [v["eq_coef_s"] / models[m][p["S"]]["eq_coef_s"] for m in base]
            summary.setdefault(name, []).append((v["worst_err_pct"], v["coef_s"], v["eq_coef_s"], ratios))
            table.append([f"{p['S']:.3f}", name, f"{v['eps']:.3f}", f"{v['phi']:.2f}",
                          *[f"{v[n]:.2f}" for n in NAMES], f"{v['worst_err_pct']:.1f}",
                          f"{1e3 * v['coef_s']:.1f}", f"{1e3 * v['eq_coef_s']:.1f}", *[f"{x:.3g}" for x in ratios]])
    for name, vals in summary.items():
        med = [statistics.median(c) for c in zip(*[v[:3] for v in vals])]
        rat = [statistics.median(c) for c in zip(*[v[3] for v in vals])]
        table.append(["median", name, "", "", *["" for _ in NAMES], f"{med[0]:.1f}", f"{1e3 * med[1]:.1f}",
                      f"{1e3 * med[2]:.1f}", *[f"{x:.3g}" for x in rat]])

    widths = [max(len(str(c)) for c in col) for col in zip(header, *table)]
    for line in [header, *table]:
        print("  ".join(str(c).rjust(w) for c, w in zip(line, widths)))

    ross_times = "; ".join(f"{m}: {v['timing']}" for m in models if m.startswith("ROSS")
                           for v in list(models[m].values())[:1])
    notes = (f"Lund & Thomsen (1978) two-axial-groove bearing, L/D = 0.5, the five rows both public typings share "
             f"(x along the load, y horizontal; K = k c/W, B = b c omega/W). Ours: grooved Swift-Stieber solver "
             f"(Lund & Thomsen's condition; the 'Gumbel' row clips at zero like ROSS 2.3, the like-for-like "
             f"comparison), central differences (9 force evaluations); times are medians of {repeats}; the 'x ours' "
             f"columns are against our Swift-Stieber rows. ROSS "
             f"{r['ross_version']} PlainJournal (n_pad=2, pad_arc_length=160, circular, preload 0, "
             f"method='{r['method']}', isoviscous lubricant dict, flooded), mesh = elements_circumferential x "
             f"elements_axial per pad; its pressure is the linear (Sommerfeld) solution clipped at zero "
             f"(half-Sommerfeld / Gumbel), not Swift-Stieber, and its equilibrium is Nelder-Mead with tol 0.8; "
             f"'eq + coef' is the whole PlainJournal constructor ({ross_times}), 'coef set' its coefficients() call "
             f"alone. Frames: Kxx = kyy(ROSS), Kxy = -kyx, Kyx = -kxy, Kyy = kxx (same for damping). "
             f"Worst err %: the largest *_err_pct of study.lund_thomsen_table's measure. "
             f"Both sides measured in one run (ROSS in its own venv, {r['python']}, numpy {r['numpy_version']}).")
    if not args.quick:
        from fluidfilm.perf.benchmarking import write_benchmark
        path = write_benchmark("ross_peer", "External peer: ROSS PlainJournal vs ours on Lund & Thomsen's "
                               "two-axial-groove bearing (L/D = 0.5), coefficients and time per set", header, table,
                               notes)
        # the full numbers (unrounded, per-sample ROSS times) beside the table, under a key render ignores
        data = json.loads(path.read_text())
        data["raw"] = {"published": rows, "models": {m: {f"{S:.3f}": v for S, v in per_s.items()}
                                                     for m, per_s in models.items()}, "ross_side": r}
        io.write_json(path, data)


if __name__ == "__main__":
    main()
