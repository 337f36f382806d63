"""The universal model's cost per force against the best model's shape: its units and its blend zones (#29).

    python benchmarks/bench_universal_cost.py [--repeats 5]

The shipped universal model (Gumbel, on the paper's bearing) and the best model's shape (five regions,
3 -> 64 -> 2 tanh, random weights: ``perf.speed.best_shaped_surrogate``) run the same generated kernels
(``surrogate.kernels``). They differ in two ways:

- the units: the universal networks' ``pade_tanh`` (6 vector operations and a division per 8 units) against
  tanh (19 and a division in float64). A third arm, the universal networks with tanh in place of their own
  units (not a model: the shape alone), separates the two;
- the regions: the universal model has one more, five boundaries against four, each with a blend zone 0.04
  wide where a state evaluates both neighbouring networks. On states drawn uniformly over eps 0-0.9
  (``universal_evaluate``'s timing states) 22 % of them evaluate two networks against 18 %: a predicted
  cost ratio of (1 + 0.222) / (1 + 0.178) = 1.038 for the networks of the same units. On states inside the
  first region of both models (eps 0.02-0.26, no blend zone) they do the same work.

Times the one-state kernel in the integrator's loop and the batched kernel (1024 states per call, one
thread, float32 networks) for the three arms on both sets of states, interleaved, medians of ``--repeats``
rounds. Writes reports/benchmarks/universal_cost.json.
"""
from __future__ import annotations

import argparse

import numpy as np

from fluidfilm import paper_bearing, universal_bearing
from fluidfilm.perf import write_benchmark
from fluidfilm.perf.speed import best_shaped_surrogate, time_per_force_eval, time_per_force_eval_batched
from fluidfilm.surrogate import SurrogateForceModel


def states(clearance: float, lo: float, hi: float, n: int, seed: int):
    """n states with eps uniform in [lo, hi], angles uniform, velocities within +-0.05 m/s."""
    rng = np.random.default_rng(seed)
    eps, ang = lo + (hi - lo) * rng.random(n), 2 * np.pi * rng.random(n)
    x = clearance * np.stack([eps * np.sin(ang), eps * np.cos(ang)], axis=1)
    return x, 0.05 * (2 * rng.random((n, 2)) - 1)


def blend_fraction(model, eps: np.ndarray) -> float:
    """Share of the states that lie in a blend zone (two networks evaluated)."""
    b, half = np.asarray(model.boundaries, dtype=float), 0.5 * model.blend_width
    return float(np.mean((np.abs(eps[:, None] - b[None, :]) < half).any(axis=1)))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5, help="interleaved rounds (medians)")
    args = ap.parse_args(argv)
    if args.repeats < 1:
        raise SystemExit(f"--repeats must be >= 1, got {args.repeats}")
    bearing = paper_bearing()
    shipped = universal_bearing(bearing, "gumbel")
    # the same networks with tanh units: not a model, the universal shape with the best model's units
    as_tanh = SurrogateForceModel(shipped.bearing, shipped.networks, shipped.scalings, "tanh",
                                  boundaries=shipped.boundaries, blend_width=shipped.blend_width,
                                  domain=shipped.domain, eps_max=shipped.eps_max, name="universal, tanh units")
    models = {"universal": shipped, "universal_tanh": as_tanh, "best_shape": best_shaped_surrogate(bearing)}
    arms = {"universal": f"universal ({shipped.activation}, shipped)", "universal_tanh": "universal networks, tanh units (not a model)"}
    rows = []
    for band, (lo, hi) in {"eps 0-0.9 (uniform)": (0.0, 0.9), "eps 0.02-0.26 (no blend zone)": (0.02, 0.26)}.items():
        x, v = states(bearing.clearance, lo, hi, 5000, 0)
        xb, vb = states(bearing.clearance, lo, hi, 1024, 1)
        eps = np.hypot(x[:, 0], x[:, 1]) / bearing.clearance
        t: dict = {(name, arm): [] for name in models for arm in ("one", "batched")}
        for _ in range(args.repeats):
            for name, model in models.items():
                t[(name, "one")].append(time_per_force_eval(model, x, v))
                t[(name, "batched")].append(time_per_force_eval_batched(model, xb, vb, "float32"))
        ns = {k: 1e9 * float(np.median(val)) for k, val in t.items()}
        fu, fb = blend_fraction(models["universal"], eps), blend_fraction(models["best_shape"], eps)
        for arm, label in arms.items():
            rows.append([band, label, f"{100 * fu:.1f} % / {100 * fb:.1f} %", f"{(1 + fu) / (1 + fb):.3f}",
                         f"{ns[(arm, 'one')]:.1f} / {ns[('best_shape', 'one')]:.1f}",
                         f"{ns[(arm, 'one')] / ns[('best_shape', 'one')]:.3f}",
                         f"{ns[(arm, 'batched')]:.1f} / {ns[('best_shape', 'batched')]:.1f}",
                         f"{ns[(arm, 'batched')] / ns[('best_shape', 'batched')]:.3f}"])
            print(" | ".join(rows[-1]), flush=True)
    write_benchmark("universal_cost", "Universal model vs the best model's shape: cost per force by eccentricity band",
                    ["states", "universal arm", "in a blend zone, universal / best shape",
                     "predicted network cost ratio (same units)", "one-state ns, universal / best shape", "ratio",
                     "batched ns (1024, float32), universal / best shape", "ratio"], rows,
                    notes=f"Medians of {args.repeats} interleaved rounds; one thread. The universal model has five "
                          "region boundaries (blend zones 0.04 wide) against the best shape's four; the best "
                          "shape's units are tanh.")


if __name__ == "__main__":
    main()
