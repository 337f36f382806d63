"""Item 9: every argument of ``simulate`` validated by name; contact found inside the steps, not per output."""
from __future__ import annotations

import math

import numpy as np
import pytest

from fluidfilm import ReynoldsSolver, Rotor, paper_bearing, simulate
from fluidfilm.rotor.linear import LinearBearing

B = paper_bearing()
C = B.clearance


@pytest.fixture(scope="module")
def solver():
    return ReynoldsSolver(B, 30, 30)


@pytest.mark.parametrize("kwargs, name", [
    ({"max_substeps": -3}, "max_substeps"),
    ({"max_substeps": 0}, "max_substeps"),
    ({"max_substeps": 2.5}, "max_substeps"),
    ({"record_every": 0}, "record_every"),
    ({"t0": math.nan}, "t0"),
    ({"t0": math.inf}, "t0"),
    ({"t0": "0"}, "t0"),
    ({"dt": -1e-5}, "dt"),
    ({"dt": math.nan}, "dt"),
    ({"t_end": 0.0}, "t_end"),
    ({"t_end": "1"}, "t_end"),
    ({"eps_stop": 1.0}, "eps_stop"),
    ({"eps_stop": None}, "eps_stop"),
    ({"eps_substep": 0.0}, "eps_substep"),
    ({"x0": [0.0, 0.0, 0.0]}, "x0"),
    ({"v0": [np.nan, 0.0]}, "v0"),
])
def test_bad_argument_is_refused_naming_it(solver, kwargs, name):
    args = {"t_end": 1e-3, "dt": 1e-5, **kwargs}
    with pytest.raises(ValueError, match=name):
        simulate(solver, Rotor(mass=2.5), **args)


def test_coarse_output_step_reports_no_contact_that_does_not_happen(solver):
    """dt = 5 ms: the first RK stages of a start at rest land outside the clearance (gravity alone moves the
    journal 0.5 g dt^2 = 120 um); that is a step too long, not a contact.  The fine run (truth) never comes
    near eps_stop; the coarse one must not claim it did."""
    rotor = Rotor(mass=2.5, imbalance=5e-4)
    fine = simulate(solver, rotor, t_end=0.05, dt=1e-5)
    # 4 steps per revolution: the step check refuses it (test_integration_step.py); the retry is studied here
    coarse = simulate(solver, rotor, t_end=0.05, dt=5e-3, check_step=False)
    assert fine.ok and fine.eccentricity(C).max() < 0.8
    assert coarse.ok, coarse.status
    assert coarse.n_force_evals > 4 * 10  # it refined its steps
    assert np.isfinite(coarse.x).all()


def test_contact_between_recorded_outputs_is_found_at_its_time():
    """A journal thrown at the sleeve by a soft linear spring: the contact time is known analytically
    (free flight x = v t until |x| = eps_stop c); recording only every 1000th step must not delay it."""
    soft = LinearBearing(B, stiffness=0.0, damping=0.0)
    v = 0.05  # m/s: eps_stop c = 117.6 um is reached at t = 2.352 ms
    rotor = Rotor(mass=2.5, gravity=0.0)
    for every in (1, 1000):
        traj = simulate(soft, rotor, t_end=0.1, dt=1e-5, v0=[v, 0.0], record_every=every)
        assert traj.status.startswith("contact")
        assert traj.t_stop == pytest.approx(0.98 * C / v, abs=1e-5)
        assert np.hypot(*traj.x[-1]) >= 0.98 * C
