"""Every compiled evaluation of a surrogate against the readable NumPy reference (``surrogate.kernels.reference``).

On random states of every shipped (the universal networks), trained (``models/**/model.json``) and test
model (``tests/golden_models.py``: every frame, scaling kind, structure and activation the kernels know):
the generic one-state kernel, the generated one-state kernel, the generic and the generated batched kernels
and the exact Jacobian's value equal the reference to round-off in float64; the float32 networks are within
1e-4 of it relative to the larger of |F| and the states' RMS force (the states reach beyond the trained
models' domains, where float32's rounding grows; inside them tests/surrogate/test_surrogate_kernels.py holds float32 to
1e-5).  The paper's trained min-max networks (affine scalings: raw inputs in metres and m/s, the
standardisation folded into the first layer) lose far more in float32: up to 1e-2 relative even inside their
training domain (measured 2026-12-06 on the models under models/); their float32 bound here is a regression
guard at 5e-2, not a claim of accuracy.
"""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from golden_models import models as golden_models

from fluidfilm import paper_bearing
from fluidfilm.surrogate import load_surrogate
from fluidfilm.surrogate.kernels import batch_params, forces_batch, reference_forces
from fluidfilm.surrogate.kernels.jacobian import surrogate_jacobian
from fluidfilm.surrogate.universal import UNIVERSAL_RULES, universal_bearing

ROOT = Path(__file__).resolve().parents[2]
SAVED = sorted(ROOT.glob("models/**/model.json"))


def _model(name: str):
    if name.startswith("universal_"):
        return universal_bearing(paper_bearing(), name.removeprefix("universal_")), None
    if name.startswith("saved:"):
        return load_surrogate(ROOT / name.removeprefix("saved:")), None
    return golden_models()[name]


NAMES = ([n for n in golden_models() if n.startswith("surrogate")] + [f"universal_{r}" for r in UNIVERSAL_RULES]
         + [f"saved:{p.parent.relative_to(ROOT)}" for p in SAVED])


def _states(model, n=64, seed=5):
    rng = np.random.default_rng(seed)
    c = model.clearance
    eps = 0.02 + 0.9 * rng.random(n)
    ang = 2 * np.pi * rng.random(n)
    x = np.stack([eps * c * np.cos(ang), eps * c * np.sin(ang)], axis=1)
    return x, rng.normal(0.0, 0.3 * c * model.bearing.omega, (n, 2))


@pytest.mark.parametrize("name", NAMES)
def test_every_compiled_path_equals_the_reference(name):
    model, sleeve = _model(name)
    if sleeve is not None:
        model.set_sleeve(sleeve)
    x, v = _states(model)
    ref = reference_forces(model, x, v)
    rms = float(np.sqrt(np.mean(ref ** 2)))
    paths = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # states outside the training domain are legal here
        paths["generic"] = model.forces(x, v)
    for precision in ("float64", "float32"):
        fn, p = model.force_kernel_at(precision)
        paths[f"one-state {precision}"] = np.array([fn(p, *x[i], *v[i]) for i in range(len(x))])
        fn, bp = model.batch_force_kernel(precision)
        out = np.empty_like(x)
        fn(bp, x, v, out)
        paths[f"batched {precision}"] = out
        out = np.empty_like(x)
        forces_batch(batch_params(model, precision), x, v, out)
        paths[f"generic batched {precision}"] = out
    if not model.scalings[0].extras:
        paths["jacobian"] = np.array([surrogate_jacobian(model, x[i], v[i])[0] for i in range(len(x))])
    for path, F in paths.items():
        err = np.abs(F - ref)
        if path.endswith("float32"):
            affine = model.scalings[0].kind in ("standard", "minmax")
            bound = (5e-2 if affine and name.startswith("saved:") else 1e-4) * np.maximum(np.abs(ref), rms)
        else:
            bound = 1e-9 * np.maximum(np.abs(ref), rms)
        assert np.all(err <= bound), (name, path, float((err / np.maximum(np.abs(ref), rms)).max()))


def test_the_reference_sees_a_wrong_network():
    """It can fail: one weight changed moves the reference's forces far beyond round-off."""
    model, _ = _model("surrogate_std")  # built afresh: its weights are its own
    x, v = _states(model)
    before = reference_forces(model, x, v)
    model.networks[0][0][0][0, 0] += 0.1
    after = reference_forces(model, x, v)
    assert np.abs(after - before).max() > 1e-6 * np.sqrt(np.mean(before ** 2))


def test_there_are_trained_models():
    assert SAVED, "no models/**/model.json: the trained models are not checked"
