"""Force models and states for the golden-value test (tests/core/test_force_model.py).

``python tests/golden_models.py`` writes ``tests/core/golden_forces.npz``; it was run once on the
code before the force-model interface and the named kernel parameters were introduced, so the
test compares today's forces with that earlier implementation (a second, independent version of
the same code), not with themselves.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from fluidfilm import (ConicalReynoldsSolver, GradedReynoldsModel, ReynoldsSolver, Rotor, bearing_from_dict,
                       paper_bearing, simulate)
from fluidfilm.rotor import LinearBearing
from fluidfilm.surrogate import Scaling, SurrogateForceModel

ROOT = Path(__file__).resolve().parents[1]
GOLDEN = Path(__file__).resolve().parent / "core" / "golden_forces.npz"
CONICAL = dict(name="conical", kind="conical", length=0.064, diameter_small=0.03665, diameter_large=0.04335,
               clearance=120.0e-6, speed_rpm=3000.0, viscosity=6.53e-4, density=992.0, supply_pressure=0.0,
               clearance_taper=0.0, sleeve_min=-0.8e-3, sleeve_max=0.8e-3)


def _net(rng, n_in, width, n_out, depth=2):
    sizes = [n_in] + [width] * depth + [n_out]
    return [(rng.normal(0, 1 / np.sqrt(a), (b, a)), rng.normal(0, 0.1, b)) for a, b in zip(sizes[:-1], sizes[1:])]


def _scaling(rng, kind, c, omega, frame, extras=(), gain=0.0):
    n = (4 if frame == "cartesian" else 3) + len(extras)
    return Scaling(kind, c, omega, 50.0, 1.5, rng.normal(0, 0.1, n), 1 + rng.random(n), rng.normal(0, 1, 2),
                   1 + rng.random(2), frame, tuple(extras), gain)


def models() -> dict:
    """name -> (model, sleeve or None): every kind of force model the library offers."""
    jb = paper_bearing()
    cb = bearing_from_dict(CONICAL)
    cb_taper = bearing_from_dict({**CONICAL, "clearance_taper": 10e-6})
    rng = np.random.default_rng(2024)
    c, om = jb.clearance, jb.omega
    out = {
        "linear": (LinearBearing(jb, 2e6, 3e3), None),
        "gumbel_30": (ReynoldsSolver(jb, 30, 30, "gumbel"), None),
        "none_20": (ReynoldsSolver(jb, 20, 24, "none"), None),
        # the golden values are projected SOR's (converged to 1e-10): pinned to it; the default active-set
        # solver agrees with it to PSOR's convergence (tests/reynolds/test_active_set.py)
        "swift_stieber_12": (ReynoldsSolver(jb, 12, 12, "swift-stieber", method="psor"), None),
        "pressurised_16": (ReynoldsSolver(bearing_from_dict({**jb.to_dict(), "supply_pressure": 2e4}), 16, 17),
                           None),
        "graded": (GradedReynoldsModel(jb, (16, 16), (24, 24), 0.8), None),
        "conical_fast": (ConicalReynoldsSolver(cb, 20, 20), -0.3e-3),
        "conical_general": (ConicalReynoldsSolver(cb, 16, 14, method="general"), 0.2e-3),
        "conical_taper": (ConicalReynoldsSolver(cb_taper, 16, 14), 0.0),
        "graded_conical": (GradedReynoldsModel(cb, (16, 16), (20, 20), 0.8), 0.4e-3),
        "surrogate_std": (SurrogateForceModel(jb, [_net(rng, 4, 8, 2)], [_scaling(rng, "standard", c, om,
                                                                                     "cartesian")], "tanh"), None),
        "surrogate_split": (SurrogateForceModel(
            jb, [_net(rng, 3, 8, 2) for _ in range(3)],
            [_scaling(rng, k, c, om, "polar") for k in ("physics", "physics_v", "physics")], "relu",
            boundaries=(0.4, 0.7), blend_width=0.1, domain=[[0.0, 0.5, 0.1], [0.5, 1.0, 0.05]], eps_max=0.9),
            None),
        "surrogate_damping": (SurrogateForceModel(
            jb, [(_net(rng, 4, 6, 2), _net(rng, 4, 6, 4))], [_scaling(rng, "physics", c, om, "cartesian")],
            "silu", structure="damping"), None),
        "surrogate_sleeve": (SurrogateForceModel(
            cb, [_net(rng, 4, 8, 2, depth=1)], [_scaling(rng, "physics", cb.clearance, cb.omega, "polar", ("S",),
                                                         cb.tan_half_angle)], "sigmoid"), -0.5e-3),
    }
    return out


def states(model, n=40, seed=7):
    rng = np.random.default_rng(seed)
    c = model.clearance if hasattr(model, "clearance") else model.bearing.clearance
    eps = 0.95 * rng.random(n)
    ang = 2 * np.pi * rng.random(n)
    X = c * np.stack([eps * np.sin(ang), eps * np.cos(ang)], axis=1)
    V = rng.uniform(-0.08, 0.08, (n, 2))
    return X, V


def evaluate(name, model, sleeve) -> dict:
    if sleeve is not None:
        model.set_sleeve(sleeve)
    X, V = states(model)
    kernel, params = model.force_kernel
    out = {f"{name}/X": X, f"{name}/V": V, f"{name}/batch": model.forces(X, V),
           f"{name}/single": np.array([model.forces(x, v) for x, v in zip(X[:5], V[:5])]),
           f"{name}/kernel": np.array([kernel(params, *x, *v) for x, v in zip(X[:5], V[:5])])}
    if hasattr(model, "forces_axial"):
        out[f"{name}/axial"] = model.forces_axial(X[:4], V[:4])
    if hasattr(model, "pressure") and not name.startswith("graded"):
        out[f"{name}/pressure"] = model.pressure(X[0], V[0])
    tr = simulate(model, Rotor(mass=2.5, imbalance=5e-4 * 2.5), t_end=2e-3, dt=1e-5, x0=0.3 * X[1])
    out[f"{name}/orbit"] = tr.x
    return out


def compute() -> dict:
    import warnings

    res = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        for name, (model, sleeve) in models().items():
            res.update(evaluate(name, model, sleeve))
    return res


if __name__ == "__main__":
    if "--write" not in sys.argv:
        sys.exit("pass --write to overwrite the golden values (only ever from the pre-refactor code)")
    GOLDEN.parent.mkdir(exist_ok=True)
    np.savez_compressed(GOLDEN, **compute())
    print(f"wrote {GOLDEN}")
