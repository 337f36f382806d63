"""Issue #26 item 5: one convention. One equilibrium (a load vector, one sign of the attitude angle, one set
of keys), degrees for the angles users read, ``t_end`` an end time, coefficient names that say their frame."""
from __future__ import annotations

import math

import numpy as np
import pytest

import fluidfilm
from fluidfilm import JournalBearing, ReynoldsSolver, Rotor, load_along_gravity, paper_bearing, simulate
from fluidfilm.characteristics import bearing_characteristics, coefficients as coef, published as pub
from fluidfilm.characteristics import shortbearing as sb
from fluidfilm.characteristics import static
from fluidfilm.rotor import LinearBearing
from fluidfilm.rotor.batch import simulate_batch

# the new user's bearing of the trial: L/D 0.5, c 50 um, 6000 rpm, 0.02 Pa s
USER = JournalBearing(length=0.025, diameter=0.05, clearance=50e-6, speed_rpm=6000.0, viscosity=0.02)


@pytest.fixture(scope="module")
def user_solver():
    return ReynoldsSolver(USER, 30, 30)


# --- one equilibrium -------------------------------------------------------------------------------
def test_every_equilibrium_name_is_the_one_solver():
    from fluidfilm import characteristics, rotor
    assert fluidfilm.equilibrium is characteristics.equilibrium is static.equilibrium
    # one address: the rotor (below the characteristics) does not re-export it
    assert not hasattr(rotor, "equilibrium") and fluidfilm.equilibrium_locus is static.equilibrium_locus


def test_the_two_routes_of_the_trial_agree_on_the_users_bearing(user_solver):
    """The issue's probe: fluidfilm.equilibrium and bearing_characteristics once gave -60.59 and +60.59 deg."""
    eq = fluidfilm.equilibrium(user_solver, (0.0, 1000.0))
    op = bearing_characteristics(user_solver, load_along_gravity(1000.0))
    assert set(static.EQUILIBRIUM_KEYS) <= set(eq) and set(static.EQUILIBRIUM_KEYS) - {"short_bearing_start_eps"} <= set(op)
    for k in ("eps", "X1", "X2", "attitude_deg", "load_N", "sommerfeld"):
        assert op[k] == eq[k], k
    # independent of the solver's own bookkeeping: the angle of the position from the load line (+X2),
    # measured towards +X1 (the direction of rotation)
    assert eq["attitude_deg"] == pytest.approx(math.degrees(math.atan2(eq["X1"], eq["X2"])), abs=1e-9)
    assert 30.0 < eq["attitude_deg"] < 90.0
    assert eq["X1"] == eq["X"][0] and eq["X2"] == eq["X"][1]
    assert eq["residual"] < 1e-8 and eq["load_N"] == 1000.0


def test_attitude_sign_against_the_independent_short_bearing_force():
    """The short-bearing force integrated by quadrature (an independent model): its equilibrium leads the load
    line in the direction of rotation, by Ocvirk's closed-form angle, positive."""
    b = JournalBearing(length=0.001, diameter=0.040, clearance=120e-6, speed_rpm=3000.0, viscosity=6.53e-4)
    model = sb.ShortBearingModel(b)
    for eps in (0.3, 0.7):
        eq = fluidfilm.equilibrium(model, load_along_gravity(sb.load_capacity(b, eps)))
        assert eq["eps"] == pytest.approx(eps, abs=1e-8)
        assert eq["X1"] > 0.0  # the journal moves towards +X1, the way its surface turns from +X2
        assert eq["attitude_deg"] == pytest.approx(math.degrees(math.atan(math.pi * math.sqrt(1 - eps**2) / (4 * eps))),
                                                   abs=1e-6)


def test_attitude_is_measured_from_the_load_line_whatever_its_direction(user_solver):
    """A cylindrical bearing is symmetric under rotation: a load turned by 120 deg towards +X1 (ten cells of the
    30-point grid, so the grid is symmetric too) turns the equilibrium by 120 deg and leaves eps and the
    attitude unchanged."""
    down = fluidfilm.equilibrium(user_solver, (0.0, 800.0))
    a = math.radians(120.0)
    turned = fluidfilm.equilibrium(user_solver, (800.0 * math.sin(a), 800.0 * math.cos(a)))
    assert turned["eps"] == pytest.approx(down["eps"], rel=1e-7)
    assert turned["attitude_deg"] == pytest.approx(down["attitude_deg"], abs=1e-5)
    psi_down = math.atan2(down["X1"], down["X2"])
    psi_turned = math.atan2(turned["X1"], turned["X2"])
    assert math.degrees(psi_turned - psi_down) % 360.0 == pytest.approx(120.0, abs=1e-5)


def test_load_along_gravity_is_the_weight_of_a_rotor():
    """+X2 is gravity: the helper's vector is what a Rotor of that weight puts on the bearing."""
    rotor = Rotor(mass=2.5)
    assert load_along_gravity(2.5 * rotor.gravity) == rotor.static_load() == (0.0, 2.5 * 9.81)


def test_locus_and_equilibrium_give_the_same_point(user_solver):
    locus = fluidfilm.equilibrium_locus(user_solver, [300.0, 1000.0])
    eq = fluidfilm.equilibrium(user_solver, load_along_gravity(1000.0))
    assert list(locus.columns) == ["eps", "X1", "X2", "attitude_deg", "residual", "load_N", "sommerfeld"]
    assert locus.attitude_deg.iloc[1] == pytest.approx(eq["attitude_deg"], abs=1e-7)
    assert locus.eps.iloc[1] == pytest.approx(eq["eps"], abs=1e-9)


# --- degrees ---------------------------------------------------------------------------------------
def test_short_bearing_attitude_is_in_degrees():
    assert sb.attitude_angle_deg(0.5) == pytest.approx(math.degrees(math.atan(math.pi * math.sqrt(0.75) / 2.0)))
    assert 89.0 < sb.attitude_angle_deg(1e-3) < 90.0  # Ocvirk: 90 deg at the centre
    assert not hasattr(sb, "attitude_angle")  # the old name, whose unit was radians, is gone


# --- t_end is an end time --------------------------------------------------------------------------
def _free_imbalance(t, t0, a, w):
    """m x'' = m a (cos wt, sin wt) from rest at the centre at t0 (no film, no gravity), integrated by hand."""
    s0, c0 = math.sin(w * t0), math.cos(w * t0)
    x1 = a / w * (-(np.cos(w * t) - c0) / w - (t - t0) * s0)
    x2 = a / w * (-(np.sin(w * t) - s0) / w + (t - t0) * c0)
    return np.stack([x1, x2], axis=1)


@pytest.mark.parametrize("batched", [False, True])
def test_t_end_is_the_end_time_of_a_run_started_at_t0(batched):
    b = JournalBearing(length=0.064, diameter=0.25, clearance=0.01, speed_rpm=3000.0, viscosity=6.53e-4)
    rotor = Rotor(mass=2.0, imbalance=1e-4, gravity=0.0)
    model = LinearBearing(b, 0.0, 0.0)
    t0, t_end, dt = 0.013, 0.053, 1e-5
    if batched:
        out = simulate_batch(model, rotor, t_end, dt, t0=t0)
        t, x = out.t[: out.n_recorded[0]], out.x[0, : out.n_recorded[0]]
    else:
        tr = simulate(model, rotor, t_end, dt, t0=t0)
        t, x = tr.t, tr.x
    assert t[0] == pytest.approx(t0) and t[-1] == pytest.approx(t_end)  # not t0 + t_end
    assert len(t) == round((t_end - t0) / dt) + 1
    exact = _free_imbalance(t, t0, rotor.imbalance * b.omega**2 / rotor.mass, b.omega)
    assert np.max(np.abs(x - exact)) < 1e-8 * np.max(np.abs(exact))


def test_t_end_before_t0_is_refused_saying_it_is_an_end_time():
    model = LinearBearing(paper_bearing(), 1e6, 50.0)
    with pytest.raises(ValueError, match="t_end must be a finite end time .* after t0=0.5"):
        simulate(model, Rotor(mass=2.5), 0.1, 1e-5, t0=0.5)


# --- coefficient frame -----------------------------------------------------------------------------
def test_k01_is_minus_dF1_dX2_and_kxy_names_it(user_solver):
    """K[i, j] = -dF_i/dX_j (i, j = 0, 1 for X1, X2), checked by a difference taken here; Kxy = K[0, 1] c/W."""
    eq = fluidfilm.equilibrium(user_solver, load_along_gravity(1000.0))
    x0, h = eq["X"], 1e-4 * USER.clearance
    kc = coef.coefficients(user_solver, x0, 1e-4)
    dF_dX2 = (user_solver.forces(x0 + [0.0, h], [0.0, 0.0]) - user_solver.forces(x0 - [0.0, h], [0.0, 0.0])) / (2 * h)
    assert kc["K"][0, 1] == pytest.approx(-dF_dX2[0], rel=1e-9)
    assert kc["K"][1, 1] == pytest.approx(-dF_dX2[1], rel=1e-9)
    d = coef.dimensionless(kc, USER, 1000.0)
    assert d["Kxy"] == pytest.approx(kc["K"][0, 1] * USER.clearance / 1000.0, rel=1e-12)
    assert d["Kyx"] == pytest.approx(kc["K"][1, 0] * USER.clearance / 1000.0, rel=1e-12)


def test_lund_thomsen_names_are_their_axes_x_along_the_load():
    """Their Kxx (x along the load = our X2) is our Kyy; the two differ by 14 % in their table at S = 0.917,
    so the comparison can tell the frames apart."""
    from fluidfilm.studies import characteristics_study as study
    row = dict(zip(pub.LUND_THOMSEN_COLUMNS, next(r for r in pub.LUND_THOMSEN_1978[0.5] if r[0] == 0.917)))
    solver = study.lund_thomsen_bearing(0.5, (144, 31))
    ours = study.lund_thomsen_point(solver, row["S"])
    eq = fluidfilm.equilibrium(solver, load_along_gravity(study.load_at_sommerfeld(solver.bearing, row["S"])))
    d = coef.dimensionless(coef.reference_coefficients(solver, eq["X"]), solver.bearing, eq["load_N"])
    assert ours["Kxx"] == pytest.approx(d["Kyy"], rel=1e-12) and ours["Kyy"] == pytest.approx(d["Kxx"], rel=1e-12)
    assert ours["Kxy"] == pytest.approx(d["Kyx"], rel=1e-12)
    assert abs(ours["Kxx"] - row["Kxx"]) < 0.05 * row["Kxx"] < abs(ours["Kxx"] - row["Kyy"])
    assert abs(ours["Kyy"] - row["Kyy"]) < 0.05 * row["Kyy"] < abs(ours["Kyy"] - row["Kxx"])
