"""Every force model against values computed by the code before the interface refactor.

``tests/data/golden_forces.npz`` was written by ``tests/golden_models.py`` on the earlier
implementation (positional kernel tuples, duck-typed models); the forces, pressures, axial forces
and short orbits of every model must agree with it to 1e-12 relative.
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import golden_models as gm

GOLD = np.load(gm.GOLDEN)


@pytest.fixture(scope="module")
def computed():
    return gm.compute()


@pytest.mark.parametrize("name", sorted(gm.models()))
def test_forces_equal_the_pre_refactor_values(name, computed):
    keys = [k for k in GOLD.files if k.startswith(name + "/")]
    assert {"batch", "kernel", "orbit"} <= {k.split("/")[1] for k in keys}
    for k in keys:
        np.testing.assert_allclose(computed[k], GOLD[k], rtol=1e-12, atol=0.0, err_msg=k)
