"""The batched integrator against the unbatched one (same trajectories, to the last bit).

- reference solver, linear bearing and a sleeve-input surrogate: every trajectory of a batch
  (different imbalance, load, initial state, sleeve) equals ``simulate``'s run of it alone;
- trajectories that stop (contact) stop at the same time with the same state, the others go on;
- the model's own control setting is restored after a batch; bad input raises a clear error.
"""
from __future__ import annotations

import numpy as np
import pytest
import yaml

from fluidfilm import ReynoldsSolver, Rotor, paper_bearing, simulate
from fluidfilm.core.bearing import bearing_from_dict
from fluidfilm.rotor import LinearBearing
from fluidfilm.rotor.batch import simulate_batch
from fluidfilm.surrogate.inference import SurrogateForceModel
from fluidfilm.surrogate.scaling import Scaling

from conftest import ROOT


def _assert_same(batch, p, single):
    tp = batch.trajectory(p)
    assert tp.status == single.status
    assert tp.n_force_evals == single.n_force_evals
    np.testing.assert_array_equal(tp.x, single.x)
    np.testing.assert_array_equal(tp.v, single.v)
    np.testing.assert_allclose(tp.t, single.t, rtol=0, atol=1e-15)


def test_batch_of_reference_trajectories_equals_simulate():
    b = paper_bearing()
    solver = ReynoldsSolver(b, 30, 30)
    c = b.clearance
    rotors = [Rotor(mass=2.5, imbalance=u, external_force=f) for u, f in
              [(0.0, (0.0, 0.0)), (5e-4, (0.0, 0.0)), (1e-3, (20.0, 0.0)), (2e-4, (-30.0, 10.0))]]
    x0 = np.array([[0.0, 0.0], [0.3 * c, 0.0], [0.0, 0.5 * c], [-0.2 * c, 0.6 * c]])
    v0 = np.array([[0.0, 0.0], [0.0, 0.01], [0.005, 0.0], [0.0, 0.0]])
    batch = simulate_batch(solver, rotors, 0.005, 1e-5, x0, v0, record_every=7)
    assert len(batch) == 4 and batch.ok.all()
    for p in range(4):
        _assert_same(batch, p, simulate(solver, rotors[p], 0.005, 1e-5, x0[p], v0[p], record_every=7))


def test_batch_with_contact_stops_only_that_trajectory():
    b = paper_bearing()
    lin = LinearBearing(b, stiffness=1e6, damping=50.0)
    # a soft spring and a heavy static load drive trajectory 1 into the sleeve; 0 stays inside
    rotors = [Rotor(mass=2.5), Rotor(mass=2.5, external_force=(0.0, 400.0))]
    batch = simulate_batch(lin, rotors, 0.12, 1e-5, record_every=5, t0=0.1)  # t_end: the end time
    assert batch.ok.tolist() == [True, False]
    for p in range(2):
        _assert_same(batch, p, simulate(lin, rotors[p], 0.12, 1e-5, record_every=5, t0=0.1))


def _random_active_surrogate(seed=0):
    """A sleeve-input surrogate with random weights: not a physical model, a kernel to compare paths on."""
    cone = bearing_from_dict(yaml.safe_load((ROOT / "conf" / "bearing" / "conical.yaml").read_text()))
    rng = np.random.default_rng(seed)
    n_in = 4
    sc = Scaling("physics", cone.clearance, cone.omega, 20.0, 1.5, np.zeros(n_in), np.ones(n_in),
                 np.array([-1.0, 0.3]), np.ones(2) * 0.2, "polar", ("S",),
                 (cone.clearance_at(1e-4) - cone.clearance) / 1e-4)
    layers = [(rng.normal(size=(16, n_in)), rng.normal(size=16)), (0.1 * rng.normal(size=(2, 16)), np.zeros(2))]
    return SurrogateForceModel(cone, [layers], [sc], "tanh", name="random_active")


def test_batch_with_per_trajectory_sleeve_equals_simulate_at_each_sleeve():
    model = _random_active_surrogate()
    sleeves = [-0.8e-3, 0.0, 0.4e-3]
    rotor = Rotor(mass=2.5, imbalance=5e-4)
    model.set_sleeve(0.0)
    c = model.clearance
    x0 = np.array([0.1 * c, 0.2 * c])
    batch = simulate_batch(model, rotor, 0.004, 1e-5, x0, settings=[model.setting_for(s) for s in sleeves])
    assert model.sleeve == 0.0 and model.clearance == c  # restored
    assert len({tuple(batch.x[p, batch.n_recorded[p] - 1]) for p in range(3)}) == 3  # the sleeve matters
    for p, s in enumerate(sleeves):
        model.set_sleeve(s)
        _assert_same(batch, p, simulate(model, rotor, 0.004, 1e-5, x0))


@pytest.mark.parametrize("kwargs, match", [
    ({"x0": np.zeros((3, 2))}, "3 rotors|rotors for a batch"),
    ({"x0": np.zeros((2, 3))}, "x0 must be"),
    ({"dt": -1.0}, "dt must be"),
    ({"settings": np.zeros((2, 2))}, "no per-trajectory settings"),
])
def test_bad_batch_input_raises(kwargs, match):
    lin = LinearBearing(paper_bearing(), 1e7, 100.0)
    args = {"rotors": [Rotor(mass=1.0), Rotor(mass=2.0)], "t_end": 0.001, "dt": 1e-5} | kwargs
    with pytest.raises(ValueError, match=match):
        simulate_batch(lin, **args)
