"""Benchmark of the conical bearing's solver paths and of the controllers' model evaluations.

    python benchmarks/bench_conical.py

Medians per force evaluation through the compiled kernels (what the rotor integrator calls), side
by side: the cylindrical fast path, the conical fast path (eigenbasis), the conical general path
(block-cyclic direct solve, any h(theta, z)), a tapered film on the general path, and the active
surrogate (models/active, if trained); ratios against the conical fast path.
"""
from __future__ import annotations

import os
import platform
from pathlib import Path

import yaml

from fluidfilm import ReynoldsSolver, paper_bearing
from fluidfilm.core.bearing import bearing_from_dict
from fluidfilm.perf.benchmarking import median_seconds
from fluidfilm.reynolds.conical import ConicalReynoldsSolver

ROOT = Path(__file__).resolve().parents[1]


def kernel_time(model, repeats=7, calls=200) -> float:
    fn, params = model.force_kernel
    x1, x2, v1, v2 = 20e-6, 45e-6, 0.01, -0.005
    return median_seconds(lambda: fn(params, x1, x2, v1, v2), repeats, calls)


def main() -> None:
    cfg = yaml.safe_load((ROOT / "conf" / "bearing" / "conical.yaml").read_text())
    cone = bearing_from_dict(cfg)
    tapered = bearing_from_dict({**cfg, "clearance_taper": 20e-6})
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores; medians of 7 x N calls")
    table = {}
    for n in (30, 55):
        rows = {
            "cylinder, fast path": kernel_time(ReynoldsSolver(paper_bearing(), n, n)),
            "cone, fast path (eigenbasis)": kernel_time(ConicalReynoldsSolver(cone, n, n)),
            "cone, general path": kernel_time(ConicalReynoldsSolver(cone, n, n, method="general"), calls=10),
            "tapered cone, general path": kernel_time(ConicalReynoldsSolver(tapered, n, n), calls=10),
        }
        base = rows["cone, fast path (eigenbasis)"]
        print(f"\n{n}x{n} grid")
        for name, t in rows.items():
            print(f"  {name:32s} {t * 1e6:10.1f} us   {t / base:8.1f} x the cone's fast path")
            table.setdefault(name, {})[n] = f"{t * 1e6:,.1f} us ({t / base:.1f}x)"
    active = ROOT / "models" / "active"
    if (active / "model.json").exists():
        from fluidfilm import load_surrogate

        t = kernel_time(load_surrogate(active), calls=20000)
        t_ref = kernel_time(ConicalReynoldsSolver(cone, 30, 30))
        print(f"\nactive surrogate (models/active): {t * 1e6:.2f} us per force, {t_ref / t:.1f}x faster than "
              f"the conical fast path at 30x30")
        table["active surrogate (models/active)"] = {30: f"{t * 1e6:.2f} us ({t / t_ref:.2f}x)", 55: "-"}
    from fluidfilm.perf.benchmarking import write_benchmark

    write_benchmark("conical", "Conical bearing, per force evaluation through the compiled kernels (medians; ratio to "
                    "the cone's fast path)", ["path", "30x30", "55x55"],
                    [[name, cells[30], cells[55]] for name, cells in table.items()])


if __name__ == "__main__":
    main()
