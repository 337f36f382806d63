"""Every force model against values computed by the code before the interface refactor.

``tests/core/golden_forces.npz`` was written by ``tests/golden_models.py`` on the earlier
implementation (positional kernel tuples, duck-typed models); the forces, pressures, axial forces
and short orbits of every model must agree with it to 1e-12 relative.
"""
from __future__ import annotations

import golden_models as gm
import numpy as np
import pytest

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


def test_every_model_implements_the_contract_and_only_active_ones_the_sleeve():
    from fluidfilm.core.force_model import AdjustableForceModel, ForceModel, as_adjustable

    for name, (model, sleeve) in gm.models().items():
        assert isinstance(model, ForceModel), name
        if sleeve is not None:
            assert isinstance(model, AdjustableForceModel) and model.adjustable, name
            assert as_adjustable(model) is model
        else:
            with pytest.raises(ValueError, match="no sleeve input"):
                as_adjustable(model)


def test_the_validity_domain_counts_what_the_kernel_counts():
    """A surrogate's declared domain and its compiled kernel's out-of-domain counter agree state by state."""
    model, _ = gm.models()["surrogate_split"]
    X, V = gm.states(model, n=400, seed=3)
    inside = model.validity.contains(X, V, model.clearance)
    assert 0 < inside.sum() < len(inside)  # the states straddle the domain's edges
    kernel, params = model.force_kernel
    for x, v, ok in zip(X, V, inside):
        model.reset_domain_counter()
        kernel(params, *x, *v)
        assert (model.domain_report() is None) == ok


def test_simulate_rejects_an_object_that_is_not_a_force_model():
    from fluidfilm import Rotor, simulate

    class NoKernel:
        def forces(self, X, V):
            return X

    with pytest.raises(ValueError, match="NoKernel is not a force model"):
        simulate(NoKernel(), Rotor(mass=1.0), t_end=1e-3)


def test_the_linear_pressure_fast_path_is_offered_by_the_grid_solvers_only():
    """``LinearPressureModel`` (the film-region K/C path) holds for the Reynolds solvers and no other model;
    ``reference_coefficients`` takes that path only with Gumbel cavitation, otherwise central differences."""
    from fluidfilm.characteristics.coefficients import (coefficients, coefficients_gumbel_field,
                                                        reference_coefficients)
    from fluidfilm.core.force_model import LinearPressureModel
    from fluidfilm.reynolds import ConicalReynoldsSolver, ReynoldsSolver

    for name, (model, _) in gm.models().items():
        grid = isinstance(model, (ReynoldsSolver, ConicalReynoldsSolver))
        assert isinstance(model, LinearPressureModel) == grid, name
        if not grid:
            with pytest.raises(ValueError, match="cavitation='gumbel'"):
                coefficients_gumbel_field(model, np.zeros(2))
    models = gm.models()
    x0 = np.array([0.2, 0.5]) * models["gumbel_30"][0].clearance
    gumbel = models["gumbel_30"][0]
    np.testing.assert_array_equal(reference_coefficients(gumbel, x0)["K"], coefficients_gumbel_field(gumbel, x0)["K"])
    ss = models["swift_stieber_12"][0]
    np.testing.assert_array_equal(reference_coefficients(ss, x0)["K"], coefficients(ss, x0)["K"])


def test_the_batched_mpc_needs_an_active_model_and_batches_only_a_settable_one():
    from fluidfilm.control.mpc import BatchedMPC
    from fluidfilm.core.force_model import BatchSettable

    models = gm.models()
    with pytest.raises(ValueError, match="no sleeve input"):
        BatchedMPC(models["surrogate_std"][0])
    assert isinstance(models["surrogate_sleeve"][0], BatchSettable)
    assert BatchedMPC(models["surrogate_sleeve"][0]).batched
    assert not BatchedMPC(models["conical_fast"][0]).batched
