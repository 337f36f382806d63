"""Run-ups: the integrator at a scheduled shaft speed against independent truth.

- a constant schedule reproduces the constant-speed loop to the bit (same arithmetic);
- a ramp on a linear spring-damper matches scipy's solve_ivp at tight tolerance on the same ODE, written
  independently (the rotation angle as a state, the imbalance from the kinematics of a mass on a turning
  shaft);
- the speed-scaled forces: the Reynolds solver through its own speed parameter against a solver built for
  that speed; the film's exact scaling s F(X, V/s); a 'whirl'-frame surrogate against the same network with
  its scaling row set to the new speed;
- refusals, naming the speed.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp

from fluidfilm import (ConicalBearing, ConicalReynoldsSolver, LinearBearing, ReynoldsSolver, Rotor, SpeedSchedule,
                       SurrogateForceModel, paper_bearing, simulate)
from fluidfilm.core import SpeedScalableModel
from fluidfilm.reynolds.solver import with_k_omega
from fluidfilm.surrogate import Scaling

RPM = 2.0 * math.pi / 60.0


@pytest.fixture(scope="module")
def bearing():
    return paper_bearing()


def _random_surrogate(bearing, frame: str, seed: int = 0, omega=None, force_scale=None) -> SurrogateForceModel:
    """An untrained 3-8-2 (journal frames) network with a physics scaling fitted on reference forces; the
    scaling's speed and force scale replaced where given (the same network at another speed)."""
    rng = np.random.default_rng(seed)
    ref = paper_bearing()  # the scaling is fitted at the paper's speed whatever the model's bearing
    c = ref.clearance
    x = rng.uniform(-0.6, 0.6, (300, 2)) * c
    v = rng.uniform(-1.0, 1.0, (300, 2)) * c * ref.omega * 0.3
    f = ReynoldsSolver(ref, 16, 8).forces(x, v)
    scaling = Scaling.fit("physics", x, v, f, c, ref.omega, ref.force_scale, frame=frame)
    if omega is not None:
        scaling = dataclasses.replace(scaling, omega=omega, force_scale=force_scale)
    layers = [(0.7 * rng.normal(size=(8, 3)), 0.1 * rng.normal(size=8)),
              (0.7 * rng.normal(size=(2, 8)), 0.1 * rng.normal(size=2))]
    return SurrogateForceModel(bearing, [layers], [scaling], "tanh", name=f"random-{frame}")


# ----------------------------------------------------------------------------- the schedule itself
def test_schedule_angle_is_the_integral_of_the_speed():
    sch = SpeedSchedule.table([0.5, 1.0, 1.5, 3.0], [3000.0, 6000.0, 6000.0, 1000.0])
    for t in (-0.3, 0.0, 0.2, 0.5, 0.8, 1.2, 2.0, 3.0, 4.5):
        pts = [p for p in (0.5, 1.0, 1.5, 3.0) if min(0.0, t) < p < max(0.0, t)]
        exact = quad(lambda s: float(sch.omega_at(s)), 0.0, t, points=pts or None, epsabs=1e-12, epsrel=1e-13)[0]
        assert float(sch.angle(t)) == pytest.approx(exact, rel=1e-12, abs=1e-9)
    assert float(sch.speed_rpm(0.75)) == pytest.approx(4500.0)
    assert float(sch.acceleration(2.0)) == pytest.approx(-5000.0 / 1.5 * RPM)
    assert float(sch.acceleration(4.0)) == 0.0


@pytest.mark.parametrize("times, speeds, match", [
    ([0.0, 1.0], [3000.0, 0.0], "speeds must be finite and > 0, got 0 rpm at t=1.0 s"),
    ([0.0, 1.0], [3000.0, float("nan")], "speeds must be finite and > 0, got nan rpm"),
    ([0.0, 0.0], [3000.0, 4000.0], "increase strictly, got 0.0 s then 0.0 s"),
    ([0.0, float("inf")], [3000.0, 4000.0], "times must be finite, got inf s"),
    ([0.0, 1.0], [3000.0], "as many times as speeds"),
])
def test_schedule_refuses_bad_tables(times, speeds, match):
    with pytest.raises(ValueError, match=match):
        SpeedSchedule.table(times, speeds)


def test_ramp_needs_a_duration():
    with pytest.raises(ValueError, match="duration > 0 s, got 0.0"):
        SpeedSchedule.ramp(3000.0, 4000.0, duration=0.0)


# ----------------------------------------------------------------------------- constant schedule: bit-identical
@pytest.mark.parametrize("kind", ["reference", "swift-stieber", "linear", "whirl"])
def test_constant_schedule_is_the_constant_speed_loop_to_the_bit(bearing, kind):
    """The scheduled loop at the bearing's own speed gives the constant-speed trajectory bit for bit, with
    an imbalance ramp and a start time t0 != 0 (the imbalance phase runs on absolute time in both)."""
    model = {"reference": lambda: ReynoldsSolver(bearing, 16, 8),
             "swift-stieber": lambda: ReynoldsSolver(bearing, 16, 8, cavitation="swift-stieber"),
             "linear": lambda: LinearBearing(bearing, stiffness=2e6, damping=2e3),
             "whirl": lambda: _random_surrogate(bearing, "whirl")}[kind]()
    assert isinstance(model, SpeedScalableModel) and model.speed_kernel() is not None
    rotor = Rotor(mass=2.5, imbalance=2e-5, imbalance_final=6e-5, ramp_time=0.003)
    kw = dict(t_end=0.0042, t0=0.0011, x0=[1e-5, 4e-5], v0=[0.002, -0.001], record_every=3)
    plain = simulate(model, rotor, **kw)
    scheduled = simulate(model, rotor, speed=SpeedSchedule.constant(bearing.speed_rpm), **kw)
    assert plain.ok and scheduled.ok
    assert np.array_equal(plain.t, scheduled.t)
    assert np.array_equal(plain.x, scheduled.x)
    assert np.array_equal(plain.v, scheduled.v)
    assert "speed" in scheduled.meta and "speed" not in plain.meta


# ----------------------------------------------------------------------------- a ramp against solve_ivp
def _reference_ramp(k, c_damp, m, u, g, sch: SpeedSchedule, x0, t_end, t_eval, sign=1.0, angular_term=True):
    """m x'' = -K x - C x' + m_u d (phi'^2 e(phi) + phi'' e'(phi)) + m g, with the rotation angle phi a state
    (phi' = omega(t)) and the imbalance from differentiating d (cos phi, sign sin phi) twice."""
    def rhs(t, y):
        x1, x2, v1, v2, phi = y
        w = float(sch.omega_at(t))
        a = float(sch.acceleration(t)) if angular_term else 0.0
        # the imbalance mass sits at d (cos phi, sign sin phi): its reaction -m_u r'' on the shaft
        i1 = u * (w * w * math.cos(phi) + a * math.sin(phi))
        i2 = sign * u * (w * w * math.sin(phi) - a * math.cos(phi))
        return [v1, v2, (-k * x1 - c_damp * v1 + i1) / m, (-k * x2 - c_damp * v2 + i2 + m * g) / m, w]

    knots = [float(t) for t in sch.times if 0.0 < t < t_end]
    out = np.empty((len(t_eval), 4))
    y = np.array([x0[0], x0[1], 0.0, 0.0, 0.0])
    t_prev = 0.0
    # integrate piece by piece between the schedule's corners (the right-hand side has a kink there)
    for j, t_next in enumerate(knots + [t_end]):
        sel = (t_eval >= t_prev) & ((t_eval <= t_next) | (j == len(knots)))
        sol = solve_ivp(rhs, (t_prev, max(t_next, t_eval[sel].max(initial=t_next))), y, method="DOP853",
                        rtol=1e-12, atol=1e-16, t_eval=t_eval[sel])
        assert sol.success
        out[sel] = sol.y[:4].T
        y = solve_ivp(rhs, (t_prev, t_next), y, method="DOP853", rtol=1e-12, atol=1e-16).y[:, -1]
        t_prev = t_next
    return out


@pytest.mark.parametrize("sign", [1, -1])
def test_ramp_on_a_linear_bearing_matches_solve_ivp(bearing, sign):
    """A fast run-up through the rotor's critical speed (sqrt(K/m) = 894 rad/s = 8,540 rpm): RK4 at
    dt = 1e-5 s against DOP853 at rtol 1e-12 on the same ODE, within 1e-7 of the response.  Dropping the
    angular-acceleration term, or taking the angle as omega(t) t, moves the answer by far more (the test
    can fail)."""
    k, c_damp, m, u, g = 2e6, 1500.0, 2.5, 5e-5, 9.81
    sch = SpeedSchedule.table([-0.01, 0.07], [300.0, 14000.0])  # no corner inside the run
    model = LinearBearing(bearing, stiffness=k, damping=c_damp)
    rotor = Rotor(mass=m, imbalance=u, gravity=g, imbalance_direction=sign)
    x0 = [0.0, m * g / k]
    traj = simulate(model, rotor, t_end=0.06, dt=1e-5, x0=x0, record_every=50, speed=sch)
    assert traj.ok
    ref = _reference_ramp(k, c_damp, m, u, g, sch, x0, 0.06, traj.t, sign)
    scale = np.abs(ref[:, :2] - x0).max()
    assert scale > 1e-5  # the imbalance response is real [m]
    assert np.abs(traj.x - ref[:, :2]).max() < 1e-7 * scale
    assert np.abs(traj.v - ref[:, 2:]).max() < 1e-7 * np.abs(ref[:, 2:]).max()
    # the same ODE without the angular-acceleration term, or with the angle omega(t) t, is far off
    no_alpha = _reference_ramp(k, c_damp, m, u, g, sch, x0, 0.06, traj.t, sign, angular_term=False)
    assert np.abs(traj.x - no_alpha[:, :2]).max() > 1e-3 * scale
    omega_t = simulate(model, rotor, t_end=0.06, dt=1e-5, x0=x0, record_every=50,
                       speed=SpeedSchedule.constant(float(sch.speed_rpm(0.06))))
    assert np.abs(omega_t.x - ref[:, :2]).max() > 0.1 * scale


def test_a_table_with_corners_matches_solve_ivp(bearing):
    """Ramps and holds: at a corner the angular acceleration jumps and one RK4 step straddles it (a local error
    of first order in dt there, once per corner), so the match is 1e-4 of the response instead of 1e-7."""
    k, c_damp, m, u, g = 2e6, 1500.0, 2.5, 5e-5, 9.81
    sch = SpeedSchedule.table([0.01, 0.05, 0.07], [500.0, 12000.0, 12000.0])
    model = LinearBearing(bearing, stiffness=k, damping=c_damp)
    x0 = [0.0, m * g / k]
    traj = simulate(model, Rotor(mass=m, imbalance=u, gravity=g), t_end=0.08, dt=1e-5, x0=x0, record_every=50,
                    speed=sch)
    ref = _reference_ramp(k, c_damp, m, u, g, sch, x0, 0.08, traj.t)
    scale = np.abs(ref[:, :2] - x0).max()
    assert np.abs(traj.x - ref[:, :2]).max() < 1e-4 * scale


# ----------------------------------------------------------------------------- speed-scaled forces
@pytest.mark.parametrize("cavitation", ["gumbel", "swift-stieber", "none"])
def test_reference_speed_kernel_is_the_solver_at_that_speed(bearing, cavitation):
    """Through the film's own speed parameter: a solver built for 5,000 rpm gives the same forces (to
    round-off), and so does the exact scaling s F(X, V/s) of the 3,000 rpm solver."""
    solver = ReynoldsSolver(bearing, 24, 10, cavitation=cavitation)
    fast = ReynoldsSolver(dataclasses.replace(bearing, speed_rpm=5000.0), 24, 10, cavitation=cavitation)
    fn, params = solver.speed_kernel()
    rng = np.random.default_rng(3)
    x = rng.uniform(-0.6, 0.6, (6, 2)) * bearing.clearance
    v = rng.normal(size=(6, 2)) * 0.01
    s = 5000.0 / 3000.0
    for xi, vi in zip(x, v):
        got = np.array(fn(params, 5000.0 * RPM, xi[0], xi[1], vi[0], vi[1]))
        want = fast.forces(xi, vi)
        scaled = s * solver.forces(xi, vi / s)
        assert np.allclose(got, want, rtol=1e-11, atol=1e-11 * np.abs(want).max())
        assert np.allclose(scaled, want, rtol=1e-10, atol=1e-10 * np.abs(want).max())
        # and at the bearing's own speed, the force kernel's value to the bit
        own = fn(params, bearing.omega, xi[0], xi[1], vi[0], vi[1])
        assert own == solver.force_kernel[0](solver.params, xi[0], xi[1], vi[0], vi[1])


def test_with_k_omega_copies_every_other_field(bearing):
    p = ReynoldsSolver(bearing, 16, 8).params
    q = with_k_omega.py_func(p, 2.5 * p.k_omega)
    for name in p._fields:
        a, b = getattr(p, name), getattr(q, name)
        if name == "k_omega":
            assert b == 2.5 * a
        else:
            assert a is b, name


def test_supply_pressure_is_kept_at_another_speed():
    """The speed parameter is K_omega alone: a film with supply pressure at 5,000 rpm is the solver built for it
    (no homogeneity is assumed)."""
    b = dataclasses.replace(paper_bearing(), supply_pressure=2e4)
    fn, params = ReynoldsSolver(b, 20, 10).speed_kernel()
    want = ReynoldsSolver(dataclasses.replace(b, speed_rpm=5000.0), 20, 10).forces([2e-5, 5e-5], [0.003, -0.002])
    got = fn(params, 5000.0 * RPM, 2e-5, 5e-5, 0.003, -0.002)
    assert np.allclose(got, want, rtol=1e-11)


def test_whirl_surrogate_speed_scaling_is_its_own_speed_parameter(bearing):
    """The 'whirl' frame's exact speed scaling: the network at 3000 rpm evaluated by ``speed_kernel`` at
    4,700 rpm equals the same network whose scaling row says 4,700 rpm (omega and the force scale)."""
    model = _random_surrogate(bearing, "whirl")
    w2 = 4700.0 * RPM
    b2 = dataclasses.replace(bearing, speed_rpm=4700.0)
    same_net = _random_surrogate(b2, "whirl", omega=w2, force_scale=b2.force_scale)
    fn, params = model.speed_kernel()
    rng = np.random.default_rng(5)
    for _ in range(8):
        x = rng.uniform(-0.7, 0.7, 2) * bearing.clearance
        v = rng.normal(size=2) * 0.01
        got = np.array(fn(params, w2, x[0], x[1], v[0], v[1]))
        want = same_net.forces(x, v)
        assert np.allclose(got, want, rtol=1e-11, atol=1e-12 * np.abs(want).max())


# ----------------------------------------------------------------------------- refusals
def test_a_surrogate_trained_at_one_speed_refuses_another(bearing):
    model = _random_surrogate(bearing, "polar")
    assert model.speed_kernel() is None
    with pytest.raises(ValueError, match=r"random-polar gives forces at its bearing's speed only, 3000 rpm, and the "
                                         r"speed schedule asks 3000-6000 rpm"):
        simulate(model, Rotor(mass=2.5), t_end=0.001, speed=SpeedSchedule.ramp(3000.0, 6000.0, 1.0))
    with pytest.raises(ValueError, match="asks 4500 rpm"):
        simulate(model, Rotor(mass=2.5), t_end=0.001, speed=SpeedSchedule.constant(4500.0))
    # its own speed is no change of speed: it runs, as without a schedule
    plain = simulate(model, Rotor(mass=2.5), t_end=0.001, x0=[0.0, 3e-5])
    same = simulate(model, Rotor(mass=2.5), t_end=0.001, x0=[0.0, 3e-5], speed=SpeedSchedule.constant(3000.0))
    assert np.array_equal(plain.x, same.x)


def test_a_conical_solver_refuses_a_run_up():
    cone = ConicalBearing(length=0.05, diameter_small=0.04, diameter_large=0.05, clearance=100e-6, speed_rpm=3000,
                          viscosity=6.53e-4)
    with pytest.raises(ValueError, match="ConicalReynoldsSolver gives forces at its bearing's speed only"):
        simulate(ConicalReynoldsSolver(cone, 16, 8), Rotor(mass=2.5), t_end=0.001,
                 speed=SpeedSchedule.ramp(3000.0, 3500.0, 0.5))


def test_speed_must_be_a_schedule(bearing):
    with pytest.raises(ValueError, match="speed must be a SpeedSchedule .*got float"):
        simulate(ReynoldsSolver(bearing, 16, 8), Rotor(mass=2.5), t_end=0.001, speed=5000.0)


# ----------------------------------------------------------------------------- the study's analysis
def _synthetic_run(sigma_slope: float, onset_rpm: float, ratio: float = 0.47, sync: float = 0.02,
                   a0: float = 1e-2, rate_rpm_s: float = 1000.0):
    """An orbit with a known answer: a forward whirl at ``ratio`` x the shaft speed whose log amplitude grows at
    sigma = sigma_slope (omega - omega_onset) [1/s], beside a backward 1x line of ``sync`` c, on a ramp."""
    from fluidfilm.rotor.integrate import Trajectory

    sch = SpeedSchedule.ramp(0.85 * onset_rpm, 1.2 * onset_rpm, duration=0.35 * onset_rpm / rate_rpm_s)
    t = np.arange(0.0, float(sch.times[-1]), 5e-5)
    w = sch.omega_at(t)
    phi = sch.angle(t)
    sigma = sigma_slope * (w - onset_rpm * RPM)
    log_a = np.log(a0) + np.concatenate([[0.0], np.cumsum(0.5 * (sigma[1:] + sigma[:-1]) * np.diff(t))])
    z = np.exp(log_a) * np.exp(1j * ratio * phi) + sync * np.exp(-1j * phi) + 0.3 + 0.01 * t
    c = 1e-4
    x = np.c_[z.imag, z.real] * c  # z = X2 + i X1
    return Trajectory(t=t, x=x, v=np.zeros_like(x), status="ok"), sch, c


def test_order_cascade_reads_orders_and_amplitudes_of_a_known_orbit():
    from fluidfilm.studies.runup import order_cascade

    traj, sch, c = _synthetic_run(0.0, 6000.0, ratio=0.4375, a0=0.05, sync=0.02)  # 7/16: on a bin
    cas = order_cascade(traj, sch, c, samples_per_rev=32, window_revs=16, hop_revs=4)
    sub, order = cas.band(0.3, 0.7)
    assert np.allclose(order, 0.4375, atol=1e-3)
    assert np.allclose(sub, 0.05, rtol=1e-3)
    one = cas.amplitude[:, np.isclose(cas.orders, -1.0)][:, 0]
    assert np.allclose(one, 0.02, rtol=1e-3)
    # off the bins, the parabola through three bins still finds the order
    traj, sch, c = _synthetic_run(0.0, 6000.0, ratio=0.47, a0=0.05)
    _, order = order_cascade(traj, sch, c, 32, 16, 4).band(0.3, 0.7)
    assert np.allclose(order, 0.47, atol=0.01)


@pytest.mark.parametrize("onset_rpm", [5500.0, 6700.0])
def test_onset_is_where_the_amplitude_starts_to_grow(onset_rpm):
    """A whirl whose growth rate crosses zero at a known speed: the onset within 0.3 % (the analysis' own error),
    the established-whirl level later (the ramp's delay), and no onset where the amplitude never grows."""
    from fluidfilm.studies.runup import analyse, order_cascade

    traj, sch, c = _synthetic_run(0.27, onset_rpm, a0=0.5)
    res = analyse(order_cascade(traj, sch, c, 32, 16, 2), (0.3, 0.7), whirl_level=0.05, fit_nepers=1.0)
    assert res["onset_rpm"] == pytest.approx(onset_rpm, rel=3e-3)
    assert res["whirl_ratio_at_onset"] == pytest.approx(0.47, abs=0.01)
    assert res["established_rpm"] > res["onset_rpm"] * 1.02
    traj, sch, c = _synthetic_run(-0.27, 6000.0)  # grows, then decays: no onset on this run-up
    res = analyse(order_cascade(traj, sch, c, 32, 16, 2), (0.3, 0.7), whirl_level=0.05, fit_nepers=1.0)
    assert math.isnan(res["onset_rpm"])


def test_level_speed_on_the_way_up_and_down():
    from fluidfilm.studies.runup import level_speed

    s = np.array([1.0, 2.0, 3.0, 4.0])
    assert level_speed(s, [1e-3, 1e-3, 1e-1, 1.0], 1e-2, rising=True) == pytest.approx(2.5)
    down = np.array([4.0, 3.0, 2.0, 1.0])
    assert level_speed(down, [1.0, 1e-1, 1e-3, 1e-4], 1e-2, rising=False) == pytest.approx(2.5)
    assert math.isnan(level_speed(s, [1e-3] * 4, 1e-2, rising=True))


def test_schedule_of_the_study_refuses_a_window_without_the_threshold():
    from fluidfilm.studies.runup import runup_schedule

    sch = runup_schedule(6000.0, 0.9, 1.1, 0.85, rate_rpm_s=1000.0, hold_s=0.2)
    assert sch.speed_rpm(0.0) == pytest.approx(5400.0) and sch.speed_rpm(1.2) == pytest.approx(6600.0)
    assert float(sch.times[-1]) == pytest.approx(1.2 + 0.2 + 1.5)
    with pytest.raises(ValueError, match="rise above it: start=1.05"):
        runup_schedule(6000.0, 1.05, 1.1, 0.85, 1000.0, 0.0)


def test_run_up_figures_draw(tmp_path):
    from fluidfilm.studies.runup import order_cascade, plot_amplitude, plot_cascade, subsync_table

    traj, sch, c = _synthetic_run(0.27, 6000.0)
    cas = order_cascade(traj, sch, c, 32, 16, 4)
    plot_cascade(cas, 6000.0, title="synthetic").savefig(tmp_path / "c.png")
    plot_amplitude({"synthetic": subsync_table(cas, (0.3, 0.7))}, 6000.0, {"synthetic": {"onset_rpm": 6000.0}},
                   0.47).savefig(tmp_path / "a.png")
    assert (tmp_path / "c.png").stat().st_size > 10_000
