"""The activation registry (``surrogate.activations``): every entry's forms agree with each other.

For each registered activation, on random inputs: the compiled exact float64 form, the fast float64 and
float32 units, the NumPy value, the torch modules, and the derivatives (against central differences);
and every code reaches its own forms through the numba dispatchers.  A new entry is checked here
without a line added.
"""
from __future__ import annotations

import numpy as np
import pytest

from fluidfilm.surrogate import activations as act
from fluidfilm.surrogate.activations import REGISTRY

NAMES = tuple(REGISTRY)
RNG = np.random.default_rng(50)
X = np.concatenate([RNG.normal(0.0, 3.0, 400), RNG.uniform(-30.0, 30.0, 100), [0.0, 1e-8, -1e-8, 0.5, -0.5]])
# away from a kink (ReLU at 0) for the difference quotients
XD = X[np.abs(X) > 1e-3]


def _scalar(fn, x, dtype=np.float64):
    return np.array([fn(dtype(v)) for v in x], dtype=np.float64)


def test_codes_are_distinct_and_ordered():
    assert [a.code for a in REGISTRY.values()] == list(range(len(REGISTRY)))
    assert act.ACTIVATIONS == {name: a.code for name, a in REGISTRY.items()}
    assert act.HIDDEN_ACTIVATIONS == ("tanh", "pade_tanh")


@pytest.mark.parametrize("name", NAMES)
def test_compiled_forms_agree_with_the_numpy_value(name):
    a = REGISTRY[name]
    f = np.asarray(a.derivatives(X)[0], dtype=np.float64)
    scale = np.maximum(np.abs(f), 1e-300)
    # exact64 and unit64: float64 round-off (tanh64's bound, 1.5e-15, is the widest; the sigmoid's through
    # tanh is absolute where 1 + tanh cancels)
    for fn in (a.exact64, a.unit64):
        err = np.abs(_scalar(fn, X) - f)
        assert np.all(err <= 4e-15 * np.maximum(scale, 1.0)), (name, fn, err.max())
    # unit32: float32 precision (Eigen's tanh: 4e-7 relative; a few roundings around it); the sigmoid through
    # tanh32 is within 1.2e-7 absolute (its clamp, and 1 + tanh cancelling), SiLU that times |x|
    x32 = X.astype(np.float32).astype(np.float64)
    f32 = _scalar(a.unit32, X, np.float32)
    ref32 = np.asarray(a.derivatives(x32)[0], dtype=np.float64)
    err = np.abs(f32 - ref32)
    assert np.all(err <= 2e-6 * np.maximum(np.abs(ref32), 1.0) + 1.2e-7 * np.abs(x32)), (name, err.max())


@pytest.mark.parametrize("name", NAMES)
def test_dispatchers_reach_each_codes_own_forms(name):
    a = REGISTRY[name]
    for x in X[:50]:
        assert act.exact64(a.code, x) == a.exact64(x)
        assert act.unit64(a.code, x) == a.unit64(x)
        assert act.unit32(a.code, np.float32(x)) == a.unit32(np.float32(x))


@pytest.mark.parametrize("name", NAMES)
def test_derivatives_agree_with_central_differences(name):
    a = REGISTRY[name]
    h = 1e-6
    f, d1, d2 = (np.asarray(v, dtype=float) for v in a.derivatives(XD))
    fp, d1p, _ = (np.asarray(v, dtype=float) for v in a.derivatives(XD + h))
    fm, d1m, _ = (np.asarray(v, dtype=float) for v in a.derivatives(XD - h))
    np.testing.assert_allclose(d1, (fp - fm) / (2 * h), rtol=1e-6, atol=1e-8, err_msg=name)
    np.testing.assert_allclose(d2, (d1p - d1m) / (2 * h), rtol=1e-5, atol=1e-7, err_msg=name)


@pytest.mark.parametrize("name", NAMES)
def test_torch_forms_agree_with_the_numpy_value(name):
    torch = pytest.importorskip("torch")
    a = REGISTRY[name]
    f = np.asarray(a.derivatives(X)[0], dtype=np.float64)
    with torch.no_grad():
        y = a.torch_module()()(torch.as_tensor(X)).numpy()
        np.testing.assert_allclose(y, f, rtol=1e-14, atol=1e-15, err_msg=name)
        if a.torch_training:  # the Lightning networks' float32 form
            y32 = a.torch_module(training=True)()(torch.as_tensor(X, dtype=torch.float32)).double().numpy()
            np.testing.assert_allclose(y32, f, rtol=0, atol=3e-7, err_msg=name)


def test_tanh_derivatives_take_torch_tensors_too():
    torch = pytest.importorskip("torch")
    for name in act.HIDDEN_ACTIVATIONS:
        for got, want in zip(REGISTRY[name].derivatives(torch.as_tensor(X)), REGISTRY[name].derivatives(X)):
            np.testing.assert_allclose(got.numpy(), want, rtol=1e-15, atol=1e-15)  # torch and numpy round apart


def test_generated_kernels_name_every_unit():
    from fluidfilm.surrogate import kernels

    names = act.unit_names()
    for a in REGISTRY.values():
        assert names[act.unit_name(a.name)] is a.unit64 and names[act.unit_name(a.name, True)] is a.unit32
        assert kernels._act_expr(a.name, "x") == f"{a.name}64(x)"
    header = "\n".join(kernels._ONE_STATE_HEADER)
    assert all(f"import {n}" in header for n in names)


def test_the_lightning_and_config_activations_are_the_registry_s():
    from fluidfilm.workflow import config_schema

    assert config_schema.MODEL_ACTIVATIONS == act.TRAINABLE_ACTIVATIONS
