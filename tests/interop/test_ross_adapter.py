"""fluidfilm force models inside ROSS rotors (``fluidfilm.interop.ross``), checked in the ROSS environment.

ROSS 3.1 needs Python >= 3.13, so these tests run in ``.venv-ross`` (``make test-ross``; ``make test-slow``
runs them there when it exists). In the workspace's own environment they are skipped, with the reason.

- frames: fluidfilm's K, C mapped into ROSS's frame agree with ROSS's own fluid-film engine on the same
  bearing (Lund & Thomsen's two-groove bearing), signs and magnitudes;
- a linearised film through the callback == ROSS's BearingElement with the same K, C (the whole force in the
  callback: to the integrator's error, falling at second order with the step; the implicit split: exactly);
- the nonlinear film's small orbits converge to the linear response;
- the whirl onset of nonlinear runs around the threshold agrees with ROSS's stability analysis fed
  fluidfilm's K and C within 2 %.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from fluidfilm.interop import ross as fr

ross = pytest.importorskip("ross", reason="ROSS 3.1 is not installed here (it needs Python >= 3.13): "
                                          "run these with `make test-ross` (builds .venv-ross)")

pytestmark = pytest.mark.slow

BEARING = dict(length=0.025, diameter=0.05, clearance=50e-6, viscosity=0.02)


def _solver(rpm):
    from fluidfilm import JournalBearing, ReynoldsSolver

    return ReynoldsSolver(JournalBearing(speed_rpm=rpm, **BEARING), 30, 30)


@pytest.fixture(scope="module")
def setup():
    rotor = fr.jeffcott_rotor()
    w = float(rotor.m) * 9.80665 / 2.0
    return rotor, {0: (0.0, -w), 4: (0.0, -w)}


def _push(rotor, t, amplitude):
    F = np.zeros((t.size, rotor.ndof))
    F[t < 1e-3, rotor.number_dof * 2] = amplitude
    return F


def _rel(a, b):
    return float(np.abs(a - b).max() / np.abs(b).max())


def test_frame_maps_are_their_own_inverse_and_keep_the_sense_of_rotation():
    """x = X1, y = -X2: a reflection (det -1) that maps fluidfilm's rotation X2 -> X1 onto ROSS's x -> y."""
    v = np.array([[0.3, -1.2], [2.0, 0.5]])
    assert np.array_equal(fr.to_ross(fr.to_ross(v)), v)
    K = np.array([[1.0, 2.0], [3.0, 4.0]])
    assert np.array_equal(fr.matrix_to_ross(fr.matrix_to_ross(K)), K)
    # fluidfilm's +X2 -> +X1 quarter turn is ROSS's -y -> +x, i.e. a turn from +x towards +y by +90 deg
    a, b = fr.to_ross([0.0, 1.0]), fr.to_ross([1.0, 0.0])
    assert np.cross(np.append(a, 0), np.append(b, 0))[2] > 0
    with pytest.raises(ValueError, match="2 components"):
        fr.to_ross([1.0, 2.0, 3.0])


def test_coefficients_in_ross_frame_agree_with_ross_own_engine():
    """Lund & Thomsen's two-groove bearing (L/D 0.5, S = 0.917): our grooved solver's K, C mapped by
    ``matrix_to_ross`` against ROSS's FixedGeometryBearing (Swift-Stieber, its own mesh) - an independent
    check of the frame and signs: every term within 8 % of its matrix's scale, cross terms of the same sign."""
    from ross.bearings.fixed_geometry import FixedGeometryBearing
    from ross.units import Q_

    from fluidfilm.characteristics import coefficients as coef
    from fluidfilm.characteristics import static
    from fluidfilm.studies import characteristics_study as study

    s = study.lund_thomsen_bearing(0.5, (72, 31))
    load = study.load_at_sommerfeld(s.bearing, 0.917)
    x0 = static.equilibrium(s, (0.0, load))["X"]
    kc = coef.coefficients(s, x0)
    ours = {"k": fr.matrix_to_ross(kc["K"]), "c": fr.matrix_to_ross(kc["C"])}
    b = FixedGeometryBearing(
        n=0, speed=Q_([s.bearing.speed_rpm], "RPM"), journal_diameter=s.bearing.diameter,
        radial_clearance=s.bearing.clearance, pad_thickness=0.02, pivot_angle=Q_([90.0, 270.0], "deg"),
        pad_arc=Q_([160.0, 160.0], "deg"), pad_axial_length=[s.bearing.length] * 2, preload=[0.0, 0.0],
        offset=[0.5, 0.5], oil_supply_temperature=Q_(40.0, "degC"), oil_flow_v=Q_(20.0, "l/min"),
        lubricant={"liquid_viscosity1": s.bearing.viscosity, "temperature1": 313.15,
                   "liquid_viscosity2": s.bearing.viscosity, "temperature2": 373.15, "liquid_density": 860.0,
                   "liquid_specific_heat": 1951.0, "liquid_thermal_conductivity": 0.13},
        fys_load=-load, thermal_type=None)
    for m in ("k", "c"):
        theirs = np.array([[float(getattr(b, f"{m}{i}{j}")[0]) for j in "xy"] for i in "xy"])
        scale = np.abs(theirs).max()
        assert np.abs(ours[m] - theirs).max() < 0.08 * scale, (m, ours[m], theirs)
        assert np.sign(ours[m][0, 1]) == np.sign(theirs[0, 1]) and np.sign(ours[m][1, 0]) == np.sign(theirs[1, 0])


def test_linearised_film_through_the_callback_equals_ross_bearing_element(setup):
    """The whole linear force in the callback (explicit, predicted to the step's end) against ROSS's
    BearingElement with the same K, C: the difference is the integrator's, below 1e-5 and falling by ~4 when
    the step halves; with the linear part in ROSS's element (the default) it is round-off."""
    from fluidfilm.characteristics import static

    rotor, loads = setup
    s = _solver(6000.0)
    lin = fr.LinearisedFilm(s, static.equilibrium(s, (0.0, -loads[0][1]))["X"])
    models = {0: lin, 4: lin}
    errs = []
    for dt in (2e-6, 1e-6):
        t = np.arange(int(round(0.005 / dt)) + 1) * dt
        F = _push(rotor, t, 200.0)
        film = fr.FilmBearings(rotor, models, loads, linear_part="none")
        ref = fr.FilmBearings(rotor, models, loads, linear_part="implicit")
        y_ross = np.asarray(ref.rotor.run_time_response(s.bearing.omega, F, t, method="newmark").yout)
        out = fr.run_time_response(film, s.bearing.omega, t, F)
        errs.append(max(_rel(out["orbits_ross"][n], y_ross[:, film.dofs[n]]) for n in (0, 4)))
        split = fr.run_time_response(ref, s.bearing.omega, t, F)
        assert max(_rel(split["orbits_ross"][n], y_ross[:, ref.dofs[n]]) for n in (0, 4)) < 1e-12
    assert errs[-1] < 1e-5, errs
    assert 3.0 < errs[0] / errs[1] < 5.0, errs  # second order in the step


def test_small_orbits_of_the_nonlinear_film_converge_to_the_linear_response(setup):
    rotor, loads = setup
    s = _solver(6000.0)
    film = fr.FilmBearings(rotor, {0: s, 4: s}, loads)
    dt = 2e-5
    t = np.arange(1001) * dt
    diffs = []
    for amplitude in (200.0, 2.0):
        F = _push(rotor, t, amplitude)
        lin = np.asarray(film.rotor.run_time_response(s.bearing.omega, F, t, method="newmark").yout)[:, film.dofs[0]]
        non = fr.run_time_response(film, s.bearing.omega, t, F)["orbits_ross"][0]
        diffs.append(_rel(non, lin))
    assert diffs[0] > 0.02, diffs        # a 3 %-of-clearance orbit is visibly nonlinear
    assert diffs[1] < 2e-3, diffs        # a 0.03 % one is linear
    # the origin is the film's equilibrium: ROSS's zero state is at rest there (no drift without a push)
    rest = fr.run_time_response(film, s.bearing.omega, t[:200], None)
    assert np.abs(rest["orbits_ross"][0]).max() < 1e-12


def test_whirl_onset_of_nonlinear_runs_agrees_with_ross_stability_analysis(setup):
    rotor, loads = setup
    th = fr.stability_threshold(rotor, lambda rpm: {0: _solver(rpm), 4: _solver(rpm)}, loads, (6000.0, 10000.0))
    period = 2 * math.pi / th["whirl_frequency"]
    speeds, rates = [], []
    for f in (0.98, 1.02):
        rpm = f * th["speed_rpm"]
        s = _solver(rpm)
        film = fr.FilmBearings(rotor, {0: s, 4: s}, loads)
        dt = 1e-4
        t = np.arange(int(0.6 / dt) + 1) * dt
        res = fr.run_time_response(film, s.bearing.omega, t, _push(rotor, t, 2.0))
        speeds.append(rpm)
        rates.append(fr.growth_rate(t, res["orbits_ross"][0], period, 0.15))
    assert rates[0] < 0 < rates[1], rates          # decays below, grows above
    onset = speeds[0] - rates[0] * (speeds[1] - speeds[0]) / (rates[1] - rates[0])
    assert abs(onset / th["speed_rpm"] - 1.0) < 0.02, (onset, th)


def test_bad_input_is_refused_with_the_value(setup):
    rotor, loads = setup
    s = _solver(6000.0)
    with pytest.raises(ValueError, match="linear_part"):
        fr.FilmBearings(rotor, {0: s}, None, linear_part="explicit")
    with pytest.raises(ValueError, match="not shaft nodes"):
        fr.FilmBearings(rotor, {9: s}, None)
    film = fr.FilmBearings(rotor, {0: s, 4: s}, loads)
    with pytest.raises(ValueError, match="turns at"):
        fr.run_time_response(film, 100.0, np.arange(10) * 1e-4)


def _network_shaped(bearing):
    """An untrained 4-16-2 tanh network with fitted scalings (its kernel writes scratch arrays held in its
    parameters): a second kind of compiled kernel, not an accurate film."""
    from fluidfilm import ReynoldsSolver, SurrogateForceModel
    from fluidfilm.perf.speed import sample_states
    from fluidfilm.surrogate import Scaling

    x, v = sample_states(bearing.clearance, n=200, v_max=0.01)
    sc = Scaling.fit("standard", x, v, ReynoldsSolver(bearing, 16, 8).forces(x, v), bearing.clearance,
                     bearing.omega, bearing.force_scale)
    rng = np.random.default_rng(0)
    layers = [(rng.normal(size=(o, i)) / np.sqrt(i), np.zeros(o)) for i, o in ((4, 16), (16, 2))]
    return SurrogateForceModel(bearing, [layers], [sc], "tanh")


def test_compiled_callback_equals_the_python_loop(setup):
    """The compiled callback (every node on a compiled kernel: the default) returns the Python loop's forces
    to round-off, with and without the prediction to the step's end, linear part implicit or not, with the
    reference solver at one node and a network at the other; a journal at the sleeve is refused by both
    with the same message."""
    rotor, loads = setup
    s = _solver(6000.0)
    net = _network_shaped(s.bearing)
    rng = np.random.default_rng(5)
    for linear_part in ("implicit", "none"):
        film = fr.FilmBearings(rotor, {0: s, 4: net}, None, linear_part=linear_part)
        assert all(p[6] is not None for p in film._plan)  # every node on a compiled kernel
        c = s.bearing.clearance
        for _ in range(5):
            q, v, a = (rng.normal(0.0, 0.1 * c * f, film.ndof) for f in (1.0, 2e3, 4e6))
            for dt in (None, 1e-4):
                film.compiled = True
                fast = film(1, time_step=dt, disp_resp=q, velc_resp=v, accl_resp=a)
                film.compiled = False
                slow = film(1, time_step=dt, disp_resp=q, velc_resp=v, accl_resp=a)
                assert np.any(fast != 0.0)
                np.testing.assert_allclose(fast, slow, rtol=1e-12, atol=1e-12 * np.abs(slow).max())
        q = np.zeros(film.ndof)
        q[film.dofs[4][1]] = 2.0 * c  # node 4 pushed through the sleeve
        messages = []
        for compiled in (True, False):
            film.compiled = compiled
            with pytest.raises(ValueError, match="touches the sleeve") as err:
                film(1, disp_resp=q, velc_resp=np.zeros(film.ndof))
            messages.append(str(err.value))
        assert messages[0] == messages[1] and "node 4" in messages[0]


# ------------------------------------------------------------------ the ROSS bearing element
G_ROSS = 9.8065  # ROSS's gravity (Rotor.gravitational_force)


@pytest.fixture(scope="module")
def element_rotor():
    """The Jeffcott rotor on two FluidFilmBearingElements (reference solver, 6000 rpm) carrying ROSS's static
    reactions of its own gravity."""
    base = fr.jeffcott_rotor()
    loads = fr.static_loads(base)
    model = _solver(6000.0)
    elements = [fr.FluidFilmBearingElement(n=n, model=model, load=loads[n]) for n in (0, 4)]
    return base, loads, model, ross.Rotor(base.shaft_elements, base.disk_elements, elements)


def test_static_loads_are_ross_own_reactions_of_its_gravity(element_rotor):
    base, loads, _, _ = element_rotor
    w = float(base.m) * G_ROSS / 2.0
    assert sorted(loads) == [0, 4]
    for n in (0, 4):
        assert loads[n][0] == 0.0 and math.isclose(loads[n][1], -w, rel_tol=1e-9)


def test_the_element_is_a_ross_bearing_element_with_the_films_k_and_c_at_equilibrium(element_rotor):
    """A ``ross.BearingElement`` placed in ``rs.Rotor``; its coefficients are the film's K, C at the static
    equilibrium under its load, mapped into ROSS's frame; the film carries the load there."""
    from fluidfilm.characteristics import coefficients as coef
    from fluidfilm.characteristics import static

    _, loads, model, rotor = element_rotor
    for el in rotor.bearing_elements:
        assert isinstance(el, ross.BearingElement) and isinstance(el, fr.FluidFilmBearingElement)
        assert type(el).__name__ == "FluidFilmBearingElement" and el.tag == f"fluidfilm_{el.n}"
        x0 = static.equilibrium(model, tuple(fr.to_ross(loads[el.n])))["X"]
        assert np.array_equal(el.x0, x0) and np.array_equal(el.equilibrium_position, fr.to_ross(x0))
        kc = coef.coefficients(model, x0)
        for m, mat in (("k", kc["K"]), ("c", kc["C"])):
            ours = np.array([[float(np.ravel(getattr(el, f"{m}{i}{j}"))[0]) for j in "xy"] for i in "xy"])
            assert np.array_equal(ours, fr.matrix_to_ross(mat)), m
        # the film force at the equilibrium, in ROSS's frame, balances the load on the journal
        f = fr.to_ross(model.forces(el.x0, np.zeros(2)))
        assert np.abs(f + el.load).max() < 1e-6 * np.abs(el.load).max()
    assert not isinstance(object(), fr.FluidFilmBearingElement)


@pytest.mark.parametrize("weight", [500.0, 2000.0])
def test_the_element_agrees_with_ross_cylindrical_bearing_and_sinks_along_gravity(weight):
    """An independent check of the frame and of the load's direction: ROSS's own plain bearing element
    (``CylindricalBearing``, short-bearing theory, gravity along -y) on the same bearing and weight. Every one
    of the eight coefficients has ROSS's sign and lies within 20 % of its matrix's scale (finite length against
    the short-bearing limit at L/D 0.5); the journal sits below the centre (y < 0), displaced from -y towards +x,
    the way ROSS's shaft turns (+x towards +y)."""
    model = _solver(6000.0)
    b = model.bearing
    el = fr.FluidFilmBearingElement(n=0, model=model, load=(0.0, -weight))
    cyl = ross.CylindricalBearing(n=0, speed=[b.omega], weight=weight, bearing_length=b.length,
                                  journal_diameter=b.diameter, radial_clearance=b.clearance, oil_viscosity=b.viscosity)
    for m in "kc":
        ours = np.array([[float(np.ravel(getattr(el, f"{m}{i}{j}"))[0]) for j in "xy"] for i in "xy"])
        theirs = np.array([[float(np.ravel(getattr(cyl, f"{m}{i}{j}"))[0]) for j in "xy"] for i in "xy"])
        assert np.array_equal(np.sign(ours), np.sign(theirs)), (m, ours, theirs)
        assert np.abs(ours - theirs).max() < 0.2 * np.abs(theirs).max(), (m, ours, theirs)
    x, y = el.equilibrium_position
    assert y < 0.0 < x
    assert abs(el.eccentricity - float(np.ravel(cyl.eccentricity)[0])) < 0.1


def test_ross_linear_analyses_run_on_the_element(element_rotor):
    """ROSS's modal analysis of the rotor on the elements equals ``min_log_dec`` (the films' K, C at the same
    equilibria through plain BearingElements), to round-off."""
    base, loads, model, rotor = element_rotor
    modal = rotor.run_modal(model.bearing.omega, num_modes=12)
    ref = fr.min_log_dec(base, {0: model, 4: model}, loads)
    assert math.isclose(float(np.min(modal.log_dec)), ref["log_dec"], rel_tol=1e-9)
    # ROSS deep-copies elements in some analyses: the copy keeps its coefficients and shares the model
    import copy

    el = rotor.bearing_elements[0]
    twin = copy.deepcopy(el)
    assert twin == el and twin.model is el.model and np.array_equal(twin.equilibrium_position, el.equilibrium_position)


def test_nonlinear_response_honours_ross_gravity_the_journal_sinks_along_it(element_rotor):
    """From the bearing centres with ROSS's weight on, the journals first fall along -y (gravity in ROSS's frame),
    then settle at the films' static equilibria; without the weight they stay at the centre."""
    _, _, model, rotor = element_rotor
    t = np.arange(3001) * 2e-5
    out = fr.run_nonlinear_response(rotor, model.bearing.omega, t)
    c = model.bearing.clearance
    for n in (0, 4):
        p = out["positions_ross"][n]
        assert np.array_equal(p, out["orbits_ross"][n])  # start="centre": ROSS's displacements are the positions
        k = int(np.argmax(np.hypot(*p.T) > 0.02 * c))
        assert k > 0 and p[k, 1] < 0.0 and abs(p[k, 0]) < 0.5 * abs(p[k, 1]), p[k]  # first motion: down
        eq = rotor.bearing_elements[[b.n for b in rotor.bearing_elements].index(n)].equilibrium_position
        assert np.hypot(*(p[-1] - eq)) < 0.02 * c, (p[-1], eq)
    still = fr.run_nonlinear_response(rotor, model.bearing.omega, t[:501], weight=False)
    assert max(np.abs(still["positions_ross"][n]).max() for n in (0, 4)) < 1e-9 * c


def test_nonlinear_response_from_equilibrium_beside_ross_linear_response(element_rotor):
    """Started at the equilibria with ROSS's weight on and a push on the disc: the same run as ``FilmBearings``
    measured from the equilibria without ROSS's gravity, fed the weight and the films' static forces as external
    forces (to round-off); and within 5 % of ROSS's own linear response of the same rotor (its elements' K, C) to
    the same forces (the orbits reach about 3 % of c: ROSS applies the weight at once and the disc falls onto its
    static sag)."""
    base, loads, model, rotor = element_rotor
    t = np.arange(1001) * 2e-5
    F = _push(rotor, t, 2.0)
    out = fr.run_nonlinear_response(rotor, model.bearing.omega, t, F, start="equilibrium")
    statics = fr.film_static_forces(rotor, t)
    linear = np.asarray(rotor.run_time_response(model.bearing.omega, F + statics, t, method="newmark",
                                                weight=True).yout)
    film = fr.FilmBearings(base, {0: model, 4: model}, loads)
    same = fr.run_time_response(film, model.bearing.omega, t, F + statics + rotor.gravitational_force()[None, :])
    for n in (0, 4):
        dofs = out["film"].dofs[n]
        assert _rel(out["orbits_ross"][n], same["orbits_ross"][n]) < 1e-10
        assert np.allclose(out["positions_ross"][n], out["orbits_ross"][n] + fr.to_ross(out["film"].origin[n]))
        assert _rel(out["orbits_ross"][n], linear[:, dofs]) < 0.05
        assert np.abs(out["orbits_ross"][n]).max() < 0.05 * model.bearing.clearance
    assert np.array_equal(statics[:, 1], -np.full(t.size, loads[0][1]))


def test_the_element_and_its_response_refuse_bad_input(element_rotor):
    base, loads, model, rotor = element_rotor
    for bad in ([0.0, 0.0], [1.0, 2.0, 3.0], "heavy", [np.nan, -1.0]):
        with pytest.raises(ValueError, match="load must be"):
            fr.FluidFilmBearingElement(n=0, model=model, load=bad)
    with pytest.raises(ValueError, match="load"):  # beyond the film's capacity: the equilibrium names it
        fr.FluidFilmBearingElement(n=0, model=model, load=(0.0, -1e9))
    with pytest.raises(TypeError, match="coefficients"):
        fr.FluidFilmBearingElement(n=0, model=model, load=loads[0], kxx=1e8)
    with pytest.raises(TypeError, match="force model"):
        fr.FluidFilmBearingElement(n=0, model=object(), load=loads[0])
    t = np.arange(11) * 2e-5
    with pytest.raises(ValueError, match="start"):
        fr.run_nonlinear_response(rotor, model.bearing.omega, t, start="top")
    with pytest.raises(ValueError, match="weight=True"):
        fr.run_nonlinear_response(rotor, model.bearing.omega, t, start="equilibrium", weight=False)
    with pytest.raises(ValueError, match="no FluidFilmBearingElement"):
        fr.run_nonlinear_response(base, model.bearing.omega, t)
    with pytest.raises(ValueError, match="turns at"):  # the adapter's speed check
        fr.run_nonlinear_response(rotor, 2.0 * model.bearing.omega, t)


def test_the_element_tabulated_over_speed_for_ross_analyses_over_speed():
    """With ``speeds`` (a model with ``with_speed``: the universal surrogate), the element holds at each speed the
    film's K, C at that speed's equilibrium: equal to an element made at that speed, for ROSS's Campbell and the
    other analyses over speed; refused for a model without ``with_speed`` or bad speeds."""
    from fluidfilm import JournalBearing, universal_bearing

    model = universal_bearing(JournalBearing(speed_rpm=6000.0, **BEARING))
    rpms = (3000.0, 6000.0, 9000.0)
    speeds = [r * math.pi / 30.0 for r in rpms]
    el = fr.FluidFilmBearingElement(n=0, model=model, load=(0.0, -500.0), speeds=speeds)
    assert np.allclose(el.speed, speeds, rtol=0, atol=0)
    for rpm, omega in zip(rpms, speeds):
        single = fr.FluidFilmBearingElement(n=0, model=model.with_speed(rpm), load=(0.0, -500.0))
        assert np.allclose(el.K(omega)[:2, :2], single.K(omega)[:2, :2], rtol=1e-12, atol=0)
        assert np.allclose(el.C(omega)[:2, :2], single.C(omega)[:2, :2], rtol=1e-12, atol=0)
    # the element itself (equilibrium, nonlinear model) is at the model's speed
    assert np.array_equal(el.x0, fr.FluidFilmBearingElement(n=0, model=model, load=(0.0, -500.0)).x0)
    with pytest.raises(TypeError, match="with_speed"):
        fr.FluidFilmBearingElement(n=0, model=_solver(6000.0), load=(0.0, -500.0), speeds=speeds)
    for bad in ([600.0], [600.0, 300.0], [0.0, 300.0], [np.nan, 300.0]):
        with pytest.raises(ValueError, match="speeds must be"):
            fr.FluidFilmBearingElement(n=0, model=model, load=(0.0, -500.0), speeds=bad)
    with pytest.raises(TypeError, match="coefficients"):
        fr.FluidFilmBearingElement(n=0, model=model, load=(0.0, -500.0), speed=speeds)
