"""Benchmark: time per set of eight stiffness and damping coefficients, reference vs surrogates.

    python benchmarks/bench_characteristics.py [--quick] [--models models/paper_single models/best ...]

At the paper rotor's equilibrium (24.5 N, eps ~ 0.59), prints the median wall
time of one coefficient set (equilibrium given) for the reference solver on
the paper's coarse grid (30x30, the linear-field derivative), a converged
grid (120x120), Swift-Stieber (60x31, central differences of the PSOR
force), the grooved bearing (60x31) and every saved surrogate given
(the exact forward-mode Jacobian of the network), and the ratios to the
30x30 reference, measured side by side in one process.
"""
from __future__ import annotations

import argparse
import functools
import math
from pathlib import Path


from fluidfilm import ReynoldsSolver, load_surrogate, paper_bearing
from fluidfilm.perf.benchmarking import median_seconds
from fluidfilm.characteristics import coefficients as coef
from fluidfilm.characteristics.stability import operating_point
from fluidfilm.characteristics.static import load_along_gravity
from fluidfilm.reynolds.feed import GroovedReynoldsSolver


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--models", nargs="*", default=["models/paper_single", "models/paper_split", "models/best"])
    args = ap.parse_args()
    repeats = 3 if args.quick else 15
    b = paper_bearing()
    ref = ReynoldsSolver(b, 30, 30)
    x0 = operating_point(ref, load_along_gravity(24.5))["X"]
    models = {"reference 30x30 (gumbel)": (ref, 1e-4), "reference 120x120 (gumbel)": (ReynoldsSolver(b, 120, 120), 1e-4),
              "swift-stieber 60x31": (ReynoldsSolver(b, 60, 31, "swift-stieber"), 1e-4),
              "grooved 60x31 (swift-stieber)": (GroovedReynoldsSolver(b, 60, 31, groove_angle=math.pi), 1e-4)}
    for path in args.models:
        if (Path(path) / "model.json").exists():
            models[Path(path).name + " (exact Jacobian)"] = (load_surrogate(path), 0.0)
        else:
            print(f"(skipping {path}: no saved surrogate there)")
    print(f"{'model':>32} {'median ms':>10} {'x vs 30x30':>11}")
    base = None
    for name, (model, h) in models.items():
        # the first (untimed) call compiles
        med = 1e3 * median_seconds(functools.partial(coef.reference_coefficients, model, x0, h), repeats)
        base = med if base is None else base
        print(f"{name:>32} {med:10.3f} {base / med:11.2f}")


if __name__ == "__main__":
    main()
