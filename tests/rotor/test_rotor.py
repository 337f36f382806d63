"""Rotor dynamics against independent truth: static balance, analytic responses, step halving."""
from __future__ import annotations

import math

import numpy as np
import pytest

from fluidfilm import (JournalBearing, LinearBearing, ReynoldsSolver, Rotor, equilibrium, equilibrium_locus,
                       paper_bearing, simulate)
from fluidfilm.rotor.integrate import Trajectory
from fluidfilm.rotor.metrics import compare_orbits, is_satisfactory, is_satisfactory_paper_reading, orbit_stats

C = 120e-6


@pytest.fixture(scope="module")
def bearing():
    return paper_bearing()


@pytest.fixture(scope="module")
def solver(bearing):
    return ReynoldsSolver(bearing, 30, 30)


@pytest.mark.parametrize("external", [(0.0, 0.0), (30.0, 0.0), (-40.0, 0.0)])
def test_constant_load_settles_where_the_film_balances_it(solver, external):
    """Cases a, f, g: no imbalance, the journal comes to rest where F_film + m g + F_ext = 0."""
    rotor = Rotor(mass=2.5, external_force=external)
    traj = simulate(solver, rotor, t_end=0.3, dt=1e-5, record_every=100)
    assert traj.ok
    x_end, v_end = traj.x[-1], traj.v[-1]
    assert np.hypot(*v_end) < 1e-6  # m/s: at rest
    load = np.array(rotor.static_load())
    balance = solver.forces(x_end, [0.0, 0.0]) + load
    assert np.hypot(*balance) < 1e-3 * np.hypot(*load)
    eq = equilibrium(solver, load)
    assert np.hypot(eq["X1"] - x_end[0], eq["X2"] - x_end[1]) < 1e-3 * C


def test_settled_imbalance_orbit_has_the_shaft_frequency(solver, bearing):
    traj = simulate(solver, Rotor(mass=2.5, imbalance=1e-4), t_end=0.4, dt=1e-5, record_every=10)
    assert traj.ok
    keep = traj.t >= 0.2
    x = traj.x[keep, 0] - traj.x[keep, 0].mean()
    dt = traj.t[1] - traj.t[0]
    spec = np.abs(np.fft.rfft(x * np.hanning(len(x))))
    freqs = np.fft.rfftfreq(len(x), dt)
    f_shaft = bearing.omega / (2 * np.pi)
    assert abs(freqs[np.argmax(spec)] - f_shaft) <= freqs[1]
    # and it is periodic with the shaft period
    period = int(round(2 * np.pi / bearing.omega / dt))
    assert np.max(np.abs(traj.x[keep][period:] - traj.x[keep][:-period])) < 1e-3 * C


def test_free_imbalance_response_matches_the_analytic_one():
    """No film, no gravity: m x'' = u w^2 (cos wt, sin wt) from rest at the centre."""
    # a wide clearance (c/R = 0.08, inside the thin-film bound) so the free journal stays inside it
    b = JournalBearing(length=0.064, diameter=0.25, clearance=0.01, speed_rpm=3000.0, viscosity=6.53e-4)
    rotor = Rotor(mass=2.0, imbalance=1e-4, gravity=0.0)
    traj = simulate(LinearBearing(b, 0.0, 0.0), rotor, t_end=0.05, dt=1e-5)
    w = b.omega
    A = rotor.imbalance * w**2 / rotor.mass
    t = traj.t
    exact = np.stack([A / w**2 * (1 - np.cos(w * t)), A / w * t - A / w**2 * np.sin(w * t)], axis=1)
    assert np.max(np.abs(traj.x - exact)) < 1e-8 * np.max(np.abs(exact))


def test_linear_bearing_steady_state_amplitude_matches_the_analytic_one():
    """Spring-damper bearing: circular orbit of radius u w^2 / |K - m w^2 + i C w|."""
    b = JournalBearing(length=0.064, diameter=0.040, clearance=1e-3, speed_rpm=3000.0, viscosity=6.53e-4)
    K, Cd, m, u = 2e6, 2e3, 2.0, 1e-4
    traj = simulate(LinearBearing(b, K, Cd), Rotor(mass=m, imbalance=u, gravity=0.0), t_end=0.2, dt=1e-5)
    w = b.omega
    radius = u * w**2 / abs(K - m * w**2 + 1j * Cd * w)
    r = np.hypot(*traj.x[traj.t > 0.15].T)
    np.testing.assert_allclose(r, radius, rtol=1e-4)


@pytest.mark.parametrize("rotor", [
    Rotor(mass=2.5, imbalance=1e-3),               # case e: the largest orbit
    Rotor(mass=2.5, external_force=(0.0, 200.0)),  # pushed to eps ~ 0.9: substeps engaged
])
def test_step_halving_leaves_the_settled_orbit_unchanged(solver, rotor):
    coarse = simulate(solver, rotor, t_end=0.3, dt=1e-5, record_every=10)
    fine = simulate(solver, rotor, t_end=0.3, dt=5e-6, record_every=20)
    assert coarse.ok and fine.ok
    np.testing.assert_allclose(coarse.t, fine.t, atol=1e-12)
    d = compare_orbits(coarse, fine, C, t_settle=0.2)
    assert d["rms_pct"] < 0.05  # % of clearance
    if rotor.external_force[1] > 0:
        assert orbit_stats(fine, C, 0.2)["eps_max"] > 0.85


def test_contact_stops_cleanly(solver):
    traj = simulate(solver, Rotor(mass=2.5, external_force=(0.0, 3000.0)), t_end=0.1, dt=1e-5, eps_stop=0.98)
    assert traj.status.startswith("contact")
    assert "t=" in traj.status and traj.t_stop is not None and 0 < traj.t_stop < 0.1
    assert np.isfinite(traj.x).all() and np.isfinite(traj.v).all()
    assert traj.t[-1] == pytest.approx(traj.t_stop)
    assert np.hypot(*traj.x[-1]) / C < 1.0


def test_equilibrium_matches_the_short_bearing_attitude_angle():
    """Ocvirk: tan(attitude) = pi sqrt(1 - eps^2) / (4 eps), at L/D = 0.05."""
    b = JournalBearing(length=0.002, diameter=0.040, clearance=C, speed_rpm=3000.0, viscosity=6.53e-4)
    s = ReynoldsSolver(b, 240, 13)
    locus = equilibrium_locus(s, [0.2, 1.0, 5.0])
    for _, row in locus.iterrows():
        eps = row["eps"]
        expected = math.degrees(math.atan(math.pi * math.sqrt(1 - eps**2) / (4 * eps)))
        # positive: the line of centres leads the load line in the direction of rotation (+X2 towards +X1)
        assert row["attitude_deg"] == pytest.approx(expected, abs=0.5)
        assert row["X1"] > 0
        assert row["residual"] < 1e-8
    assert locus["eps"].is_monotonic_increasing


def test_equilibrium_locus_of_the_paper_bearing(solver):
    locus = equilibrium_locus(solver, [2.0, 10.0, 25.0, 60.0, 150.0])
    assert (locus["residual"] < 1e-8).all()
    assert locus["eps"].is_monotonic_increasing
    assert (locus["attitude_deg"] > 0).all()
    assert locus["attitude_deg"].is_monotonic_decreasing  # the journal swings towards the load line


def test_orbit_metrics_on_known_orbits():
    t = np.linspace(0, 0.1, 1001)
    w = 2 * np.pi * 50
    ref = Trajectory(t=t, x=0.3 * C * np.stack([np.cos(w * t), np.sin(w * t)], 1), v=np.zeros((t.size, 2)), status="ok")
    shifted = Trajectory(t=t, x=ref.x + np.array([0.05 * C, 0.0]), v=ref.v, status="ok")
    d = compare_orbits(shifted, ref, C, t_settle=0.0)
    assert d["rms_pct"] == pytest.approx(5.0, rel=1e-9)
    assert d["hausdorff_pct"] == pytest.approx(5.0, rel=1e-3)
    assert d["span_err_pct"] == pytest.approx(0.0, abs=1e-9)
    lagging = Trajectory(t=t, x=0.3 * C * np.stack([np.cos(w * t + 0.5), np.sin(w * t + 0.5)], 1),
                         v=ref.v, status="ok")
    d = compare_orbits(lagging, ref, C, t_settle=0.0)
    assert d["rms_pct"] > 10.0 and d["hausdorff_pct"] < 0.2  # same orbit, other phase
    assert orbit_stats(ref, C, 0.0)["span"] == pytest.approx(0.6, rel=1e-3)
    stopped = Trajectory(t=t[:10], x=ref.x[:10], v=ref.v[:10], status="contact: ...")
    assert compare_orbits(stopped, ref, C, 0.0)["rms_pct"] == math.inf


def test_paper_reading_judges_amplitude_and_shape_and_the_position_rule_judges_position_too():
    t = np.linspace(0, 0.1, 2001)
    w = 2 * np.pi * 50
    centre = np.array([0.1 * C, 0.4 * C])  # an elliptic orbit off the bearing's centre, like a loaded journal's
    x = centre + C * np.stack([0.2 * np.cos(w * t), 0.1 * np.sin(w * t + 0.3)], 1)
    ref = Trajectory(t=t, x=x, v=np.zeros_like(x), status="ok")
    # shifted by 10 % of c: same span and shape, wrong place
    shifted = Trajectory(t=t, x=x + np.array([0.06 * C, -0.08 * C]), v=ref.v, status="ok")
    d = compare_orbits(shifted, ref, C, t_settle=0.0)
    assert d["mean_offset_pct"] == pytest.approx(10.0, rel=1e-9)
    assert d["shape_pct"] == pytest.approx(0.0, abs=1e-9) and d["span_err_pct"] == pytest.approx(0.0, abs=1e-9)
    assert is_satisfactory_paper_reading(d, 2.0) and not is_satisfactory(d, 2.0)
    # scaled by 1.3 about its own mean position: same place, amplitude 30 % too large
    m = x.mean(axis=0)
    scaled = Trajectory(t=t, x=m + 1.3 * (x - m), v=ref.v, status="ok")
    d = compare_orbits(scaled, ref, C, t_settle=0.0)
    assert d["mean_offset_pct"] < 1e-9
    assert d["span_err_pct"] == pytest.approx(0.3 * 40.0, rel=1e-3)  # 30 % of the 0.4 c span along X1
    assert d["shape_pct"] > 2.0
    assert not is_satisfactory_paper_reading(d, 2.0) and not is_satisfactory(d, 2.0)
    # the reference itself passes both; a run that stopped fails both
    d = compare_orbits(ref, ref, C, t_settle=0.0)
    assert is_satisfactory_paper_reading(d, 2.0) and is_satisfactory(d, 2.0)
    stopped = Trajectory(t=t[:10], x=x[:10], v=ref.v[:10], status="contact: ...")
    d = compare_orbits(stopped, ref, C, 0.0)
    assert not is_satisfactory_paper_reading(d, 2.0) and not is_satisfactory(d, 2.0)


@pytest.mark.parametrize("kwargs, match", [
    (dict(mass=0.0), "mass"),
    (dict(mass=1.0, imbalance=-1e-4), "imbalance"),
    (dict(mass=1.0, external_force=(np.nan, 0.0)), "external_force"),
    (dict(mass=1.0, imbalance_direction=2), "imbalance_direction"),
])
def test_bad_rotor_raises(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Rotor(**kwargs)


@pytest.mark.parametrize("kwargs, match", [
    (dict(t_end=-1.0), "t_end"),
    (dict(t_end=0.1, dt=0.0), "dt"),
    (dict(t_end=0.1, x0=[0.0, 0.99 * C]), "initial eccentricity"),
    (dict(t_end=0.1, eps_stop=1.2), "eps_stop"),
])
def test_bad_simulation_settings_raise(solver, kwargs, match):
    with pytest.raises(ValueError, match=match):
        simulate(solver, Rotor(mass=1.0), **kwargs)


def test_a_cache_write_that_numba_cannot_do_falls_back_to_the_uncached_loop(monkeypatch):
    """Numba raises ReferenceError when it cannot re-pickle its cache index (a kernel type whose dispatcher this
    process does not hold); the integrator must then run the same loop uncompiled-from-cache, not fail."""
    from fluidfilm.rotor import batch, integrate

    from fluidfilm import paper_bearing

    model = LinearBearing(paper_bearing(), stiffness=2e6, damping=2e3)
    rotor = Rotor(mass=2.0, imbalance=1e-5)
    expected = integrate.simulate(model, rotor, t_end=0.01, dt=1e-5)
    real_batch = batch._rk4_batch
    expected_batch = batch.simulate_batch(model, rotor, t_end=0.01, dt=1e-5)

    class Vanishing:
        """A cached loop whose cache write fails the way numba's does."""

        def __call__(self, *args):
            raise ReferenceError("underlying object has vanished")

    monkeypatch.setattr(integrate, "_rk4_run", Vanishing())
    with pytest.warns(RuntimeWarning, match="could not update its on-disk cache"):
        got = integrate.simulate(model, rotor, t_end=0.01, dt=1e-5)
    np.testing.assert_array_equal(got.x, expected.x)
    assert got.status == expected.status
    monkeypatch.setattr(batch, "_rk4_batch", Vanishing())
    with pytest.warns(RuntimeWarning, match="could not update its on-disk cache"):
        got_b = batch.simulate_batch(model, rotor, t_end=0.01, dt=1e-5)
    np.testing.assert_array_equal(got_b.x, expected_batch.x)
    assert real_batch is not batch._rk4_batch  # the batch really went through the failing "cached" loop
