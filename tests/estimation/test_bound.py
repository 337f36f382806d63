"""The information bound of a probe record (fluidfilm.estimation.bound), checked by second methods: the scatter of
the batch maximum a posteriori fit over noise draws (Monte Carlo), the extended Kalman filter's own covariance
when its parameters may not drift, and the confounding the rotor's mass breaks (docs/online_assessment.md,
"Observability")."""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from fluidfilm import JournalBearing, universal_bearing
from fluidfilm.estimation import EstimatorSettings, estimate
from fluidfilm.estimation.bound import batch_fit, information_bound
from fluidfilm.estimation.estimator import shaft_angle
from fluidfilm.estimation.plant import Scenario, plant_orbit, probe_record, runout_signal

warnings.filterwarnings("ignore", message="First-class function type feature is experimental")

BEARING = JournalBearing(length=0.03, diameter=0.06, clearance=80e-6, speed_rpm=6000.0, viscosity=0.02)
MASS = 50.0
W = MASS * 9.81
VALUES = (0.0, W, 1e-3 * math.cos(0.6), 1e-3 * math.sin(0.6), 1.0)
T_END = 0.15
SLOW_ROLL = 0.05e-6


@pytest.fixture(scope="module")
def model():
    return universal_bearing(BEARING)


@pytest.fixture(scope="module")
def orbit(model):
    # the estimator's own model as the plant: the bound assumes an exact model, and so does this check of it
    sc = Scenario(name="steady", times=(0.0, 1.0), values=(VALUES, VALUES), speed_rpm=6000.0, mass=MASS,
                  t_end=T_END, runout_known_error=0.0)
    return plant_orbit(model, sc, dt=2e-5)


def _bound(model, orbit, err, mass=MASS, values=VALUES):
    return information_bound(model, 6000.0, mass, values, orbit.x_true[0, :2], orbit.x_true[0, 2:], T_END, 1e4,
                             1e-6, 0.1e-6, err, times=[T_END])


def test_the_batch_fits_scatter_over_noise_draws_is_the_bound(model, orbit):
    b = _bound(model, orbit, SLOW_ROLL)
    errs = []
    for seed in range(12):
        rec = probe_record(orbit, seed)
        rng = np.random.default_rng(1000 + seed)
        known = tuple(tuple((c + rng.normal(0.0, SLOW_ROLL), s + rng.normal(0.0, SLOW_ROLL)) for c, s in axis)
                      for axis in orbit.scenario.runout)
        t = rec.frame["time"].to_numpy()
        y = rec.frame[["x", "y"]].to_numpy() - runout_signal(known, shaft_angle(t, rec.frame["speed"].to_numpy()))
        start = np.concatenate([orbit.x_true[0], np.asarray(VALUES) * np.array([1.0, 1.05, 0.9, 1.1, 1.05])])
        fit = batch_fit(t, y, model, 6000.0, MASS, start, 1e-6, 0.1e-6, SLOW_ROLL)
        th = fit["theta"]
        errs.append((math.hypot(th[4] - VALUES[0], th[5] - VALUES[1]) / W, th[8] - 1.0))
    rms = np.sqrt(np.mean(np.square(errs), axis=0))
    # 12 draws: the RMS over sigma lies within [0.52, 1.48] with 99 % probability (chi-square, 12 dof)
    for got, sigma in zip(rms, (b["load_rel"][-1], b["viscosity_rel"][-1])):
        assert 0.52 < got / sigma < 1.48, (got, sigma)


def test_the_filter_held_to_constant_parameters_reaches_the_bound(model, orbit):
    # with exact runout and no drift allowed, the filter's own covariance is the same information counted
    # recursively: its end viscosity sigma equals the bound (a weak start prior and a small velocity noise aside)
    b = _bound(model, orbit, 0.0)
    rec = probe_record(orbit, 3)
    st = EstimatorSettings(q_v=1e-5, q_load=0.0, q_imbalance=0.0, q_viscosity=0.0, inflate_threshold=0.0,
                           smooth=False)
    est = estimate(rec.frame, model, MASS, runout=orbit.scenario.runout, settings=st)
    assert est.sd[-1, 8] == pytest.approx(b["viscosity_rel"][-1], rel=0.25)


def test_the_rotors_mass_is_what_resolves_the_viscosity(model, orbit):
    # m -> 0: the equation of motion divided by s holds W/s and u/s alone (the confounding of docs/online_assessment.md):
    # where the film outweighs the inertia (m w^2 << |Z|) the s-information scales as the inertia ratio: a tenth of
    # the mass, on its own settled orbit, about ten times the standard deviation
    sc = orbit.scenario
    light_orbit = plant_orbit(model, Scenario(name="light", times=sc.times, values=sc.values, speed_rpm=6000.0,
                                              mass=MASS / 10.0, t_end=T_END, runout_known_error=0.0), dt=2e-5)
    heavy = _bound(model, orbit, 0.0)["viscosity_rel"][-1]
    light = _bound(model, light_orbit, 0.0, mass=MASS / 10.0)["viscosity_rel"][-1]
    assert 6.0 < light / heavy < 15.0, (light, heavy)


def test_a_longer_record_does_not_beat_the_slow_roll_vectors_error_at_a_steady_speed(model, orbit):
    # the runout error's prior sets a floor: at one speed a 1x runout error and the imbalance response are one signal
    kw = dict(values=VALUES, x0=orbit.x_true[0, :2], v0=orbit.x_true[0, 2:], fs=1e4, noise=1e-6, lsb=0.1e-6)
    short_exact, long_exact = (information_bound(model, 6000.0, MASS, t_end=t, **kw)["viscosity_rel"][-1]
                               for t in (0.2, 0.8))
    short, long_ = (information_bound(model, 6000.0, MASS, t_end=t, slow_roll_error=SLOW_ROLL, **kw)["viscosity_rel"][-1]
                    for t in (0.2, 0.8))
    assert long_exact < 0.6 * short_exact        # exact runout: information grows with the record (~ 1/sqrt(t))
    assert long_ > 0.75 * short                  # with the slow-roll error: it levels off


@pytest.mark.parametrize("bad, named", [({"t_end": -0.1}, "t_end"), ({"noise": 0.0}, "noise"),
                                        ({"slow_roll_error": float("nan")}, "slow_roll_error"),
                                        ({"values": (0.0, W, 0.0, 0.0, 1.0)}, "values")])
def test_bad_input_is_refused_naming_it(model, orbit, bad, named):
    kw = dict(values=VALUES, x0=orbit.x_true[0, :2], v0=orbit.x_true[0, 2:], t_end=0.1, fs=1e4, noise=1e-6)
    kw.update(bad)
    with pytest.raises(ValueError, match=named):
        information_bound(model, 6000.0, MASS, **kw)
