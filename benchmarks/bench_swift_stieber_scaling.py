"""How the Swift-Stieber solver's cost grows on long bearings with fine grids (docs/reference_model.md).

    python benchmarks/bench_swift_stieber_scaling.py [--states 30]

Each active-set step solves the free nodes' equations by the axial sine transform with a capacitance system
(``kernels.capacitance_field``) whose unknowns ("sources") are the cavitated nodes of partly cavitated node
columns, or, where its operation count says that costs more, by the envelope Cholesky factorisation. The
capacitance system's factorisation grows with the cube of the number of sources, and on a long bearing the
cavitation boundary slants across many columns. Rows: the plain bearing (D 50 mm, c 75 um, 5000 rpm,
0.02 Pa s: the universal evaluation's timing bearing) at L/D 0.75, 1.3 and 1.8 on the ladder's 96- and
144-node grids (``data.universal._n_z`` axial nodes). States: eps uniform in 0-0.9, velocities within
+-0.05 m/s (``perf.speed.sample_states``). Per row, medians over the states of: the time of one force's
solve (``kernels.active_set_field`` called directly, one state at a time), the same with the envelope
factorisation only (``transform=False``), the linear solves per force, and the sources of the final
cavitation set as ``capacitance_field`` counts them; and the share of states whose final set the operation
count sends to the envelope factorisation (earlier steps of a solve may go there too).

Writes reports/benchmarks/swift_stieber_scaling.json (docs/reference_model.md shows it).
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from fluidfilm import JournalBearing, ReynoldsSolver
from fluidfilm.data.universal import _n_z
from fluidfilm.perf.benchmarking import write_benchmark
from fluidfilm.perf.speed import sample_states
from fluidfilm.reynolds import kernels


def capacitance_count(free: np.ndarray, n_modes: int) -> tuple[int, bool]:
    """Sources of a free set (``active_set_field``'s ``warm`` output, shape (n_theta, rows solved + 2); no
    held columns) and whether ``capacitance_field``'s operation count, copied here, picks the envelope."""
    mh = free.shape[1] - 2
    c = free[:, 1:mh + 1].sum(axis=1)
    run = c > 0                         # a column with a free node: inside a run; else a boundary column
    s_tot = int((mh - c)[run].sum())
    n_part = int(((c < mh) & run).sum())
    env = float((0.5 * c * mh * mh).sum())
    cap = s_tot ** 2 * (0.5 * n_modes + s_tot / 6.0) + n_part ** 2 * n_modes + int(run.sum()) * n_modes * (0.5 * mh + 12.0)
    return s_tot, bool(run.all() or cap > env)


def row(ld: float, n_theta: int, n_states: int) -> list[str]:
    b = JournalBearing(length=0.05 * ld, diameter=0.05, clearance=75e-6, speed_rpm=5000.0, viscosity=0.02)
    nz = _n_z(n_theta, ld)
    solver = ReynoldsSolver(b, n_theta, nz, cavitation="swift-stieber")
    x, v = sample_states(b.clearance, n=n_states, eps_max=0.9, v_max=0.05)
    fixed = np.zeros(n_theta, dtype=np.bool_)
    t = {True: [], False: []}
    solves, sources, envelope = [], [], []
    for i in range(n_states):
        for transform in (True, False):
            p = np.zeros((n_theta, nz))
            # the final free set, written by the kernel (warm_in False: its start is its own); the field alone
            # would not tell a free node at p = 0 from a cavitated one
            final = np.zeros((n_theta, (nz - 1) // 2 + 2), dtype=np.bool_)
            t0 = time.perf_counter()
            it = kernels.active_set_field(solver.params, (x[i, 0], x[i, 1], v[i, 0], v[i, 1]), p, fixed,
                                          kernels.ActiveSetOptions(True, n_theta * nz, transform), final, False)
            t[transform].append(time.perf_counter() - t0)
            if it < 0:
                raise RuntimeError(f"the active-set iteration did not settle at L/D {ld}, {n_theta} x {nz}, state {i}")
            if transform:
                solves.append(it)
                s, env = capacitance_count(final, solver.params.lam.shape[0])
                sources.append(s)
                envelope.append(env)
    return [f"{ld:g}", f"{n_theta} x {nz}", f"{np.median(sources):.0f}", f"{100 * np.mean(envelope):.0f} %",
            f"{np.median(solves):.0f}", f"{1e3 * np.median(t[True]):.2f}", f"{1e3 * np.median(t[False]):.2f}"]


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--states", type=int, default=30, help="states per row (medians over them)")
    args = ap.parse_args(argv)
    if args.states < 1:
        raise SystemExit(f"--states must be >= 1, got {args.states}")
    row(0.75, 96, 2)  # compile the kernels outside the timing
    rows = []
    for ld in (0.75, 1.3, 1.8):
        for n_theta in (96, 144):
            rows.append(row(ld, n_theta, args.states))
            print(" | ".join(rows[-1]), flush=True)
    write_benchmark("swift_stieber_scaling", "Swift-Stieber active-set solver on the plain bearing: cost per force "
                    "against L/D and grid, with the capacitance system's size",
                    ["L/D", "grid", "sources (median)", "final set solved by the envelope", "linear solves (median)",
                     "ms per force", "ms per force, envelope only"], rows,
                    notes=f"Medians over {args.states} states (eps 0-0.9, |v| <= 0.05 m/s), one at a time; "
                          "sources: cavitated nodes of partly cavitated columns in the final cavitation set, "
                          "as kernels.capacitance_field counts them.")


if __name__ == "__main__":
    main()
