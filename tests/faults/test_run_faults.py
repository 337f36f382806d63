"""Items 22-24: a run that cannot resolve its film is refused or stopped, the adaptive integrator needs no
dt, a run outside a model's domain is not "ok", a coarse reference grid says so."""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from fluidfilm import JournalBearing, LinearBearing, ReynoldsSolver, Rotor, equilibrium, paper_bearing, simulate
from fluidfilm.rotor import integrate
from fluidfilm.rotor.batch import simulate_batch
from fluidfilm.rotor.integrate import OutsideDomainError

from . import models

#: a 200 kg rotor in a stable bearing (eps 0.51 at rest, the film's fastest rate ~2.7e3 1/s, 3000 rpm)
HEAVY = JournalBearing(length=0.08, diameter=0.1, clearance=1e-4, speed_rpm=3000.0, viscosity=0.005)
MASS = 200.0


@pytest.fixture(scope="module")
def heavy():
    solver = ReynoldsSolver(HEAVY, 30, 30)
    eq = equilibrium(solver, (0.0, MASS * 9.81))  # the independent truth: the static solve
    x_eq = np.array([eq["X1"], eq["X2"]])
    return solver, x_eq, x_eq + np.array([0.05 * HEAVY.clearance, 0.0])


# --------------------------------------------------------------------------- item 22
@pytest.mark.parametrize("dt", [1e-3, 1e-2])
def test_a_step_that_cannot_resolve_the_film_is_refused_naming_dt_and_the_safe_step(heavy, dt):
    solver, x_eq, x0 = heavy
    with pytest.raises(ValueError, match=rf"dt={dt!r} s cannot resolve this run: the largest safe step is "
                                         r"0\.000\d+ s") as err:
        simulate(solver, Rotor(mass=MASS), t_end=0.5, dt=dt, x0=x0)
    # the safe step it names really is safe: the run lands on the static equilibrium
    safe = float(str(err.value).split("largest safe step is ")[1].split(" s")[0])
    assert 1e-4 < safe < 1e-3
    with pytest.raises(ValueError, match="cannot resolve this batch"):
        simulate_batch(solver, Rotor(mass=MASS), t_end=0.5, dt=dt, x0=x0)


def test_the_step_the_check_refuses_is_really_wrong_and_the_safe_one_is_right(heavy):
    """dt = 1e-2 (2 steps per revolution) without the check: not the equilibrium; the largest safe step:
    within 1e-3 c of the static solve."""
    solver, x_eq, x0 = heavy
    c = HEAVY.clearance
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        bad = simulate(solver, Rotor(mass=MASS), t_end=0.5, dt=1e-2, x0=x0, check_step=False)
    assert not (bad.ok and np.hypot(*(bad.x[-1] - x_eq)) < 1e-3 * c), bad.status
    lim = integrate.rk4_step_limit(lambda *s: solver.force_kernel[0](solver.params, *s), x0, np.zeros(2),
                                   1.0 / MASS, c, HEAVY.omega)
    good = simulate(solver, Rotor(mass=MASS), t_end=0.5, dt=0.5 / math.ceil(0.5 / lim.dt_max), x0=x0,
                    record_every=50)
    assert good.ok and np.hypot(*(good.x[-1] - x_eq)) < 1e-3 * c


@pytest.mark.parametrize("dt", [1e-3, 1e-2])
def test_a_film_with_memory_gets_the_step_check_at_the_start(heavy, dt):
    """The mass-conserving film is refused the step the Reynolds film is refused, with the safe step of its own
    quasi-static force; check_step=False lets an expert through."""
    from fluidfilm.reynolds.elrod_adams import ElrodAdamsSolver

    _, _, x0 = heavy
    film = ElrodAdamsSolver(HEAVY, 16, 9)
    with pytest.raises(ValueError, match=rf"dt={dt!r} s cannot resolve this run: the largest safe step is "
                                         r"0\.000\d+ s") as err:
        simulate(film, Rotor(mass=MASS), t_end=0.5, dt=dt, x0=x0)
    safe = float(str(err.value).split("largest safe step is ")[1].split(" s")[0])
    fn, params = film.force_kernel
    lim = integrate.rk4_step_limit(lambda *s: fn(params, *s), x0, np.zeros(2), 1.0 / MASS, HEAVY.clearance,
                                   HEAVY.omega)
    assert safe == pytest.approx(lim.dt_max, rel=1e-3)
    run = simulate(film, Rotor(mass=MASS), t_end=3 * dt, dt=dt, x0=x0, check_step=False)
    assert run.t.size >= 2   # it ran (what it ran into is the expert's to read in its status)


def test_the_adaptive_run_needs_no_dt_and_lands_on_the_equilibrium(heavy):
    solver, x_eq, x0 = heavy
    traj = simulate(solver, Rotor(mass=MASS), t_end=0.5, dt=None, x0=x0, rtol=1e-7)
    assert traj.ok, traj.status
    assert np.hypot(*(traj.x[-1] - x_eq)) < 1e-3 * HEAVY.clearance
    assert traj.t[-1] == 0.5 and len(traj.t) == 1001  # records at the output times, landed on exactly
    assert traj.meta["method"] == "dormand-prince-5(4)" and traj.meta["n_accepted"] > 0


def test_the_adaptive_run_matches_the_closed_form_damped_oscillator():
    """m x'' + C x' + K x = m g from rest at the centre: x2(t) = x_s (1 - e^{-z w t}(cos w_d t + z w/w_d sin w_d t))."""
    m, k, cd = 2.0, 2e6, 400.0
    model = LinearBearing(paper_bearing(), stiffness=k, damping=cd)
    traj = simulate(model, Rotor(mass=m), t_end=0.02, dt=None, rtol=1e-9, record_dt=1e-4)
    wn = math.sqrt(k / m)
    z = cd / (2.0 * math.sqrt(k * m))
    wd = wn * math.sqrt(1.0 - z * z)
    xs = m * 9.81 / k
    t = traj.t
    exact = xs * (1.0 - np.exp(-z * wn * t) * (np.cos(wd * t) + z * wn / wd * np.sin(wd * t)))
    assert traj.ok and np.abs(traj.x[:, 1] - exact).max() < 1e-6 * xs
    assert np.abs(traj.x[:, 0]).max() == 0.0


def test_the_adaptive_run_refuses_a_bad_tolerance_naming_it():
    model = LinearBearing(paper_bearing(), stiffness=2e6, damping=400.0)
    for kwargs, name in (({"rtol": 0.0}, "rtol"), ({"atol": -1.0}, "atol"), ({"record_dt": math.nan}, "record_dt"),
                         ({"rtol": True}, "rtol")):
        with pytest.raises(ValueError, match=name):
            simulate(model, Rotor(mass=2.0), t_end=0.01, dt=None, **kwargs)


def test_a_step_that_stops_resolving_the_film_along_the_run_stops_it():
    """Resolved at the centre (dt 4e-5 s is a tenth of the safe step there), the journal is pushed to eps ~0.9
    where the film's rate needs dt < 2e-5 s (no substeps below eps_substep=0.95): "unresolved", not ok."""
    solver = ReynoldsSolver(paper_bearing(), 30, 30)
    rotor = Rotor(mass=0.5, external_force=(0.0, 150.0))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # the 30x30 grid at eps 0.9
        traj = simulate(solver, rotor, t_end=0.2, dt=4e-5, eps_substep=0.95, record_every=10)
    assert traj.status.startswith("unresolved: at t=") and "largest safe step" in traj.status, traj.status
    assert not traj.ok and not traj.completed and traj.t[-1] < 0.2


@pytest.mark.parametrize("adaptive", [False, True])
def test_a_run_in_chunks_equals_one_run_to_the_bit(monkeypatch, adaptive):
    """The progress bar's chunks (and the along-the-run check) must not change the trajectory."""
    model = ReynoldsSolver(paper_bearing(), 16, 8)
    rotor = Rotor(mass=2.0, imbalance=5e-5)
    kw = {"dt": None, "record_dt": 1e-4} if adaptive else {"dt": 1e-5, "record_every": 7}
    monkeypatch.setattr(integrate, "CHUNK_MIN_STEPS", 10**9)
    monkeypatch.setattr(integrate, "MAX_CHUNKS", 1)
    whole = simulate(model, rotor, t_end=0.02, **kw)
    monkeypatch.setattr(integrate, "CHUNK_MIN_STEPS", 13)
    monkeypatch.setattr(integrate, "MAX_CHUNKS", 10**6)
    chunked = simulate(model, rotor, t_end=0.02, progress=True, **kw)
    assert whole.ok and chunked.ok
    np.testing.assert_array_equal(chunked.t, whole.t)
    np.testing.assert_array_equal(chunked.x, whole.x)
    np.testing.assert_array_equal(chunked.v, whole.v)
    with pytest.raises(ValueError, match="progress must be True, False or None, got 'yes'"):
        simulate(model, rotor, t_end=0.02, progress="yes", **kw)


# --------------------------------------------------------------------------- item 23
def test_a_run_outside_the_training_domain_is_not_ok_and_warns_once_naming_share_and_eps():
    model = models.single()
    c = models.C
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        # |V| = 0.6 m/s against the data's 0.5: every force outside; 3 steps of the (untrained) net, no contact
        fast = simulate(model, Rotor(mass=2.5), t_end=3e-5, dt=1e-5, x0=[0.0, 0.3 * c], v0=[0.0, 0.6])
    ours = [w for w in caught if "during the simulation" in str(w.message)]
    assert len(ours) == 1
    share = 100.0 * fast.n_outside_domain / fast.n_force_evals
    eps = fast.eccentricity(c).max()  # recorded every step: the largest eccentricity reached after a step
    assert fast.status.startswith("outside-domain: reached the end time; ")
    assert f"({share:.3g} % of {fast.n_force_evals})" in fast.status and f"largest eccentricity {eps:.4g}" in fast.status
    assert str(ours[0].message).endswith(f"largest eccentricity {eps:.4g} (domain eps <= "
                                         f"{model.validity.eps_max:g}) during the simulation")
    assert not fast.ok and fast.completed and not fast.in_domain
    with pytest.raises(OutsideDomainError, match=rf"\({share:.3g} % of {fast.n_force_evals}\), largest eccentricity"):
        simulate(model, Rotor(mass=2.5), t_end=3e-5, dt=1e-5, x0=[0.0, 0.3 * c], v0=[0.0, 0.6], strict=True)
    inside = simulate(model, Rotor(mass=2.5), t_end=3e-5, dt=1e-5, x0=[0.0, 0.3 * c], strict=True)
    assert inside.status == "ok" and inside.ok and inside.in_domain


@pytest.mark.parametrize("stage_batched", [False, True])
def test_a_batch_counts_the_domain_per_trajectory_as_simulate_does(stage_batched):
    """Each trajectory its own count, status and largest eccentricity (as ``simulate``'s run of it alone), one
    warning naming how many left and the share; ``strict=True`` raises."""
    model = models.single()
    c = models.C
    x0 = np.array([[0.0, 0.3 * c], [0.0, 0.3 * c]])
    v0 = np.array([[0.0, 0.0], [0.0, 0.6]])  # the second: |V| beyond the data's 0.5 m/s, every force outside
    singles = [simulate(model, Rotor(mass=2.5), t_end=3e-5, dt=1e-5, x0=x0[p], v0=v0[p]) for p in range(2)]
    with pytest.warns(RuntimeWarning, match=r"1 of 2 trajectories outside the training domain, in 12 force "
                                             r"evaluations \(50 % of 24\); largest eccentricity"):
        batch = simulate_batch(model, Rotor(mass=2.5), t_end=3e-5, dt=1e-5, x0=x0, v0=v0,
                               stage_batched=stage_batched, precision="float64")
    assert batch.n_outside_domain.tolist() == [s.n_outside_domain for s in singles] == [0, 12]
    assert batch.status == [s.status for s in singles]
    assert batch.status[1].startswith("outside-domain: reached the end time; outside the training domain in 12 "
                                      "force evaluations (100 % of 12), largest eccentricity")
    assert batch.ok.tolist() == [True, False] and batch.completed.tolist() == [True, True]
    assert batch.trajectory(1).n_outside_domain == 12 and not batch.trajectory(1).in_domain
    assert batch.eps_reached[1] == pytest.approx(singles[1].eccentricity(c).max(), rel=1e-12)
    with pytest.raises(OutsideDomainError, match="1 of 2 trajectories outside the training domain"):
        simulate_batch(model, Rotor(mass=2.5), t_end=3e-5, dt=1e-5, x0=x0, v0=v0, strict=True,
                       stage_batched=stage_batched)
    inside = simulate_batch(model, Rotor(mass=2.5), t_end=3e-5, dt=1e-5, x0=x0, strict=True,
                            stage_batched=stage_batched)
    assert inside.ok.all() and inside.n_outside_domain.tolist() == [0, 0]


@pytest.mark.parametrize("stage_batched", [False, True])
def test_a_batch_step_that_stops_resolving_the_film_along_the_run_ends_that_trajectory(stage_batched):
    """``simulate``'s along-the-run case in a batch beside a trajectory that stays resolved: the pushed one
    ends "unresolved" where ``simulate`` stops it, naming dt and the largest safe step; the other runs on."""
    solver = ReynoldsSolver(paper_bearing(), 30, 30)
    rotors = [Rotor(mass=0.5, external_force=(0.0, 150.0)), Rotor(mass=0.5)]
    kw = {"t_end": 0.2, "dt": 4e-5, "eps_substep": 0.95, "record_every": 10}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        batch = simulate_batch(solver, rotors, stage_batched=stage_batched, **kw)
        single = simulate(solver, rotors[0], **kw)
    assert any("1 of 2 trajectories ended unresolved" in str(w.message) for w in caught)
    assert batch.status[0].startswith("unresolved: at t=") and "dt=4e-05 s is longer than the largest safe step" \
        in batch.status[0], batch.status[0]
    assert batch.status[0].split("; rerun")[0] == single.status.split("; rerun")[0]
    tp = batch.trajectory(0)
    np.testing.assert_array_equal(tp.x, single.x)
    np.testing.assert_array_equal(tp.t, single.t)
    assert not batch.ok[0] and not batch.completed[0] and batch.t_stop[0] == single.t_stop
    assert batch.ok[1] and batch.n_recorded[1] == 5000 // 10 + 1  # every row to the end


@pytest.mark.parametrize("stage_batched", [False, True])
def test_a_batch_in_chunks_equals_one_run_to_the_bit(monkeypatch, stage_batched):
    """The chunks of the progress bar and the along-the-run check do not change a trajectory: chunks of 13
    steps against one chunk, a contact among the trajectories; the bar counts every step."""
    from fluidfilm.rotor import batch as batch_module

    model = ReynoldsSolver(paper_bearing(), 16, 8)
    c = model.clearance
    rotors = [Rotor(mass=2.0, imbalance=5e-5), Rotor(mass=2.0, external_force=(0.0, 2000.0)),
              Rotor(mass=3.0, imbalance=2e-5)]
    x0 = np.array([[0.0, 0.0], [0.0, 0.5 * c], [0.2 * c, 0.85 * c]])
    kw = {"t_end": 0.01, "dt": 1e-5, "record_every": 7, "x0": x0, "stage_batched": stage_batched, "threads": 2}
    monkeypatch.setattr(integrate, "CHUNK_MIN_STEPS", 10**9)
    monkeypatch.setattr(integrate, "MAX_CHUNKS", 1)
    whole = simulate_batch(model, rotors, **kw)
    monkeypatch.setattr(integrate, "CHUNK_MIN_STEPS", 13)
    monkeypatch.setattr(integrate, "MAX_CHUNKS", 10**6)
    bars = []

    def recording_bar(progress, total, what):
        bar = integrate._progress_bar(progress, total, what)
        bars.append((bar, total))
        return bar
    monkeypatch.setattr(batch_module, "_progress_bar", recording_bar)
    chunked = simulate_batch(model, rotors, progress=True, **kw)
    assert chunked.status == whole.status and "contact" in whole.status[1]
    for name in ("x", "v", "t", "n_recorded", "t_stop", "n_force_evals", "n_outside_domain", "eps_reached"):
        np.testing.assert_array_equal(getattr(chunked, name), getattr(whole, name), err_msg=name)
    (bar, total), = bars
    assert total == 1000 and bar is not None and bar.n == 1000
    with pytest.raises(ValueError, match="progress must be True, False or None, got 'yes'"):
        simulate_batch(model, rotors, progress="yes", **kw)


# --------------------------------------------------------------------------- item 24
def _converged_force(bearing, eps):
    """Richardson extrapolation (order 2) of the 120 and 240 grids: the independent truth."""
    f = {n: ReynoldsSolver(bearing, n, n).forces([0.0, eps * bearing.clearance], [0.0, 0.0]) for n in (120, 240)}
    return f[240] + (f[240] - f[120]) / 3.0


def test_a_coarse_reference_grid_warns_once_and_converged_meets_its_tolerance():
    b = paper_bearing()
    coarse = ReynoldsSolver(b, 30, 30)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        coarse.forces([0.0, 0.5 * b.clearance], [0.0, 0.0])  # 0.2 % off there: not a word
    with pytest.warns(RuntimeWarning, match=r"ReynoldsSolver\(30x30.*eccentricity 0\.95, where this grid's force "
                                            r"is up to \d\.?\d* % off a converged grid"):
        f30 = coarse.forces([0.0, 0.95 * b.clearance], [0.0, 0.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        coarse.forces([0.0, 0.96 * b.clearance], [0.0, 0.0])  # once per solver
    truth = _converged_force(b, 0.95)
    err30 = np.hypot(*(f30 - truth)) / np.hypot(*truth)
    assert 0.02 < err30 <= coarse.grid_error(0.95)  # the envelope bounds the real error and it is real
    fine = ReynoldsSolver.converged(b, tol=0.01, eps_max=0.95)
    assert fine.n_theta > 30
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        f_fine = fine.forces([0.0, 0.95 * b.clearance], [0.0, 0.0])
    assert np.hypot(*(f_fine - truth)) / np.hypot(*truth) <= 0.01
    for kwargs, name in (({"tol": 0.0}, "tol"), ({"eps_max": 1.0}, "eps_max"), ({"cavitation": "x"}, "cavitation")):
        with pytest.raises(ValueError, match=name):
            ReynoldsSolver.converged(b, **kwargs)


def test_the_grid_envelope_bounds_every_measured_square_grid_error():
    """The rule adds a circumferential and an axial part measured on n x 120 and 120 x n grids; the square
    grids' errors, measured apart (the same Richardson truth), must lie below it wherever n >= 30."""
    from fluidfilm.reynolds.grid import grid_error
    from fluidfilm.reynolds.grid_table import GRID_ERROR

    for cav, by_ld in GRID_ERROR.items():
        for ld, rows in by_ld.items():
            for eps, by_n in rows.items():
                for n, (e1, e2) in by_n.items():
                    if n >= 30:
                        assert math.hypot(e1, e2) <= grid_error(n, n, eps, ld, cav) + 1e-6, (cav, ld, eps, n)


def test_with_speed_gives_the_model_built_at_that_speed():
    from fluidfilm import GradedReynoldsModel
    from fluidfilm.reynolds.feed import GroovedReynoldsSolver

    b = paper_bearing()
    x, v = [0.0, 0.6 * b.clearance], [0.001, -0.002]
    fast = JournalBearing(**{**b.__dict__, "speed_rpm": 6000.0})
    for model, rebuilt in ((ReynoldsSolver(b, 16, 8, cavitation="swift-stieber"),
                            ReynoldsSolver(fast, 16, 8, cavitation="swift-stieber")),
                           (GradedReynoldsModel(b, coarse=(16, 8), dense=(24, 12)),
                            GradedReynoldsModel(fast, coarse=(16, 8), dense=(24, 12))),
                           (GroovedReynoldsSolver(b, 16, 8), GroovedReynoldsSolver(fast, 16, 8)),
                           (LinearBearing(b, 1e6, 1e3), LinearBearing(fast, 1e6, 1e3))):
        moved = model.with_speed(6000.0)
        assert moved.bearing == fast and type(moved) is type(model)
        np.testing.assert_array_equal(moved.forces(x, v), rebuilt.forces(x, v))
    # a journal at rest in the film without cavitation: the force is linear in the speed
    plain = ReynoldsSolver(b, 16, 8, cavitation="none")
    np.testing.assert_allclose(plain.with_speed(6000.0).forces(x, [0.0, 0.0]), 2.0 * plain.forces(x, [0.0, 0.0]),
                               rtol=1e-12)
    with pytest.raises(ValueError, match="speed_rpm"):
        plain.with_speed(-1.0)
