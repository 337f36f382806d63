"""The mass-conserving (JFO / Elrod-Adams) film against independent truth.

- conservation: the committed step's flow balance (every node's equation summed) closes to round-off;
- equivalence: the steady film equals the Swift-Stieber complementarity field of the grooved solver (another
  code, another algorithm: direct sparse active-set solves) where the groove feeds the pressure zone full, and
  a full film's transient force equals the linear Reynolds solver's with the same squeeze velocity;
- a published case with an exact solution: Ausas, Jai & Buscaglia (J. Tribol. 131 031702, 2009), the
  oscillatory squeeze film: the full-film pressure and the cavity's edge during rupture;
- convergence: force and cavity boundary under grid refinement, the rotor's orbit under dt refinement;
- the rotor: ``simulate`` carries the film content; a full film's orbit equals the Reynolds solver's.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from fluidfilm import JournalBearing, Rotor, paper_bearing, simulate
from fluidfilm.core import TransientFilmModel
from fluidfilm.reynolds import elrod_adams as ea
from fluidfilm.reynolds.elrod_adams import ElrodAdamsSolver
from fluidfilm.reynolds.feed import GroovedReynoldsSolver
from fluidfilm.reynolds.jfo_cases import (AUSAS_P0, AUSAS_SIGMA_MAX, AUSAS_T_RUPTURE, ausas_errors, ausas_exact,
                                          ausas_gap, ausas_squeeze)


def test_steady_film_equals_swift_stieber_where_the_groove_feeds_the_pressure_zone():
    b = paper_bearing()
    film = ElrodAdamsSolver(b, 30, 30, tol_commit=1e-13, tol_steady=1e-13)
    ss = GroovedReynoldsSolver(b, 30, 30, cavitation="swift-stieber", groove_angle=math.pi)
    # the thickest film at or past the groove (theta = pi) in the sense of rotation: the cavity runs into the
    # groove, which refills the film, so the liquid reaching the pressure zone is full
    for x in ([0.0, 60e-6], [20e-6, 80e-6], [30e-6, 96e-6]):
        f = film.forces(x, [0.0, 0.0])
        g = ss.forces(x, [0.0, 0.0])
        assert np.abs(f - g).max() <= 1e-8 * np.abs(g).max(), (x, f, g)
    # the thickest film before the groove: the film reforms in the converging gap ahead of it, and only the
    # mass-conserving rule sees the starved inlet (a real difference, not round-off)
    x = [-30e-6, 96e-6]
    f, g = film.forces(x, [0.0, 0.0]), ss.forces(x, [0.0, 0.0])
    assert np.abs(f - g).max() > 1e-5 * np.abs(g).max()
    p, th = film.steady_field([0.0, 60e-6])
    assert th.min() < 0.5                      # a real cavity, partly filled
    assert (th[p > 0.0] == 1.0).all()          # complementarity: full wherever pressurised
    assert (p[th < 1.0] == 0.0).all()


def test_full_film_transient_force_equals_the_linear_reynolds_solver_with_the_squeeze_velocity():
    """Supply pressure high enough that nothing cavitates: the stage's film step must give the Reynolds
    equation with dH/dt = -V.(sin, cos) / c exactly (the lagged-gap content)."""
    b = JournalBearing(length=0.064, diameter=0.040, clearance=120e-6, speed_rpm=3000.0, viscosity=6.53e-4,
                       supply_pressure=2e6)
    film = ElrodAdamsSolver(b, 30, 30, tol_commit=1e-13, tol_steady=1e-13)
    lin = GroovedReynoldsSolver(b, 30, 30, cavitation="none", groove_angle=math.pi)
    ep = film.params
    x, v = (10e-6, 30e-6), (0.02, -0.03)
    p, th = film.steady_field(x)
    assert p[~ep.fixed][:, 1:-1].min() > 0.0
    content = np.empty_like(p)
    f1, f2, _, status = ea.stage_film(ep, ep.k_omega, *x, *v, 1e-5, 1e-13, th.copy(), content, p, th)
    g = lin.forces(x, v)
    assert status == ea.EA_CONVERGED
    assert abs(f1 - g[0]) + abs(f2 - g[1]) <= 1e-7 * np.hypot(*g), ((f1, f2), g)


@pytest.mark.parametrize("tol_commit", [1e-13, 1e-5, 1e-3])
def test_the_committed_step_conserves_mass_to_round_off_along_a_whirl(tol_commit):
    # at any tolerance of the commit's solve: close_content derives the content from each node's balance
    b = paper_bearing()
    film = ElrodAdamsSolver(b, 30, 30, tol_commit=tol_commit, tol_steady=1e-13)
    ep = film.params
    dt, r, w = 1e-5, 50e-6, 150.0

    def x(t):
        return r * math.sin(w * t) + 10e-6, r * math.cos(w * t) + 20e-6

    p, th = film.steady_field(x(0.0))
    th_n = th.copy()
    content = np.empty_like(th)
    h = np.empty(ep.n_theta)
    hf = np.empty(ep.n_theta)
    worst = 0.0
    total_change = total_inflow = 0.0
    for k in range(200):
        xo, xn = x(k * dt), x((k + 1) * dt)
        _, status = ea.commit_film(ep, ep.k_omega, *xo, *xn, dt, th_n, content, p, th)
        assert status == ea.EA_CONVERGED
        ea.journal_gap(ep, xn[0] / b.clearance, xn[1] / b.clearance, h, hf)
        change, inflow, scale = ea.flow_balance(ep, ep.k_omega, h, hf, 1.0 / dt, content, p, th)
        worst = max(worst, abs(change - inflow) / scale)
        total_change += change
        total_inflow += inflow
        th_n[:] = th
    assert th.min() < 0.9                 # the whirl runs through a cavity
    assert worst < 1e-10, worst            # round-off of ~1e3 nodes; unclosed, tol 1e-5 leaves ~1e-6
    assert abs(total_change - total_inflow) < 1e-9 * abs(total_inflow), (total_change, total_inflow)


def test_ausas_squeeze_film_pressure_and_cavity_edge_against_the_exact_solution():
    run = ausas_squeeze(nx=151, dt=6.6e-4)
    dx = 1.0 / 150
    dt = 6.6e-4
    t = run[:, 0]
    for tq in (0.0625, 0.125, 0.1875):
        k = int(np.argmin(abs(t - tq)))
        # the full film's parabola is exact on the grid (second differences of a quadratic), with backward Euler's
        # secant (h_{n+1} - h_n)/dt in place of h' and h at the step's end: equal to round-off
        h1, h0 = ausas_gap(t[k]), ausas_gap(t[k] - dt)
        discrete = AUSAS_P0 - (h1 - h0) / dt / (4.0 * h1**3)
        assert abs(run[k, 2] - discrete) < 1e-8 * discrete, (tq, run[k, 2], discrete)
        # and the continuous exact solution within backward Euler's O(dt) error
        exact = ausas_exact(t[k])[0]
        assert abs(run[k, 2] - exact) < 5e-3 * exact, (tq, run[k, 2], exact)
    assert np.isnan(run[t < AUSAS_T_RUPTURE - dt, 1]).all()       # no cavity before rupture
    for tq in (0.26, 0.28, 0.30):
        k = int(np.argmin(abs(t - tq)))
        exact = ausas_exact(t[k])[1]
        assert abs(run[k, 1] - exact) <= 1.5 * dx, (tq, run[k, 1], exact)
    assert abs(np.nanmax(run[:, 1]) - AUSAS_SIGMA_MAX) <= 1.5 * dx
    errors = ausas_errors(run)
    assert max(errors.values()) < 1.0, errors


def test_force_and_cavity_boundary_converge_with_the_grid():
    b = paper_bearing()
    x = [0.0, 84e-6]  # eps 0.7
    forces, ruptures = [], []
    for n, nz in ((24, 13), (48, 25), (96, 49)):
        film = ElrodAdamsSolver(b, n, nz, tol_commit=1e-12, tol_steady=1e-12)
        forces.append(film.forces(x, [0.0, 0.0]))
        p, th = film.steady_field(x)
        mid = th[:, nz // 2]
        ang = (film.theta_nodes - math.pi) % (2.0 * math.pi)   # from the groove
        ruptures.append(ang[np.flatnonzero(mid < 1.0).min()])  # first cavitated node of the mid-plane
    d1 = np.linalg.norm(forces[1] - forces[0])
    d2 = np.linalg.norm(forces[2] - forces[1])
    assert d2 < 0.4 * d1, (d1, d2)                       # at least ~1.3th order: halving the grid cuts it > 2.5x
    assert d2 < 5e-3 * np.linalg.norm(forces[2])
    assert abs(ruptures[2] - ruptures[1]) <= 2.0 * 2.0 * math.pi / 48


def test_simulate_carries_the_film_and_a_full_film_orbit_equals_the_reynolds_solvers():
    b = JournalBearing(length=0.064, diameter=0.040, clearance=120e-6, speed_rpm=3000.0, viscosity=6.53e-4,
                       supply_pressure=3e6)
    film = ElrodAdamsSolver(b, 30, 30, tol=1e-10, tol_commit=1e-12, tol_steady=1e-12)
    assert isinstance(film, TransientFilmModel)
    lin = GroovedReynoldsSolver(b, 30, 30, cavitation="none", groove_angle=math.pi)
    rotor = Rotor(mass=2.5, imbalance=1e-4)
    # the groove's 3 MPa pushes the journal across the clearance: 2 ms of that flight, ~0.3 c
    a = simulate(film, rotor, t_end=0.002, dt=1e-5, record_every=10)
    g = simulate(lin, rotor, t_end=0.002, dt=1e-5, record_every=10)
    assert a.ok and g.ok
    assert np.ptp(g.x, axis=0).max() > 0.1 * b.clearance
    assert np.abs(a.x - g.x).max() < 1e-8 * b.clearance
    # full everywhere: the content is 1 up to the commit's residual (close_content)
    assert np.abs(a.meta["film_content"] - 1.0).max() < 1e-9


def test_orbit_converges_in_dt_at_first_order_or_better():
    b = paper_bearing()
    film = ElrodAdamsSolver(b, 24, 13, tol=1e-9, tol_commit=1e-11, tol_steady=1e-11)
    rotor = Rotor(mass=2.5, imbalance=2.5e-4)
    ends = [simulate(film, rotor, t_end=0.01, dt=dt, x0=(0.0, 40e-6)).x[-1] for dt in (4e-5, 2e-5, 1e-5)]
    e1 = np.linalg.norm(ends[1] - ends[0])
    e2 = np.linalg.norm(ends[2] - ends[1])
    assert e2 < 0.6 * e1, (e1, e2)    # observed order log2(e1/e2) >= 0.74
    assert e2 < 1e-3 * b.clearance


def test_a_film_without_feed_and_bad_settings_are_refused_naming_them():
    with pytest.raises(ValueError, match="needs a feed"):
        ElrodAdamsSolver(paper_bearing(), 30, 30, groove_angle=None)
    with pytest.raises(ValueError, match="sor_omega"):
        ElrodAdamsSolver(paper_bearing(), 30, 30, sor_omega=2.5)
    with pytest.raises(ValueError, match="n_grooves"):
        ElrodAdamsSolver(paper_bearing(), 30, 30, n_grooves=7)
    with pytest.raises(ValueError, match="tol"):
        ElrodAdamsSolver(paper_bearing(), 30, 30, tol=0.0)
    film = ElrodAdamsSolver(paper_bearing(), 16, 8)
    with pytest.raises(ValueError, match="simulate_batch does not carry"):
        from fluidfilm.rotor.batch import simulate_batch
        simulate_batch(film, [Rotor(mass=1.0)], t_end=1e-3)
    with pytest.raises(ValueError, match="eccentricity"):
        film.forces([0.0, 120e-6], [0.0, 0.0])
    from fluidfilm import ReynoldsSolver
    with pytest.raises(ValueError, match="film_content is the state of a film with memory"):
        simulate(ReynoldsSolver(paper_bearing(), 16, 8), Rotor(mass=1.0), t_end=1e-3, film_content=np.ones((16, 8)))


@pytest.mark.parametrize("rule", ["swift-stieber", "gumbel"])
def test_the_non_conserving_rules_on_the_same_grid_equal_the_grooved_solver(rule):
    """The like-for-like comparison's other arms: the same solver with the content held full is the grooved
    finite-difference solver's Swift-Stieber or Guembel film (direct sparse solves), moving journal included."""
    b = paper_bearing()
    film = ElrodAdamsSolver(b, 30, 30, tol_commit=1e-13, tol_steady=1e-13, cavitation=rule)
    ref = GroovedReynoldsSolver(b, 30, 30, cavitation=rule, groove_angle=math.pi)
    for x, v in (([0.0, 60e-6], [0.0, 0.0]), ([-30e-6, 96e-6], [0.0, 0.0]), ([20e-6, 70e-6], [0.01, -0.02])):
        f, g = film.forces(x, v), ref.forces(x, v)
        assert np.abs(f - g).max() <= 1e-7 * np.abs(g).max(), (rule, x, v, f, g)


def test_side_flow_balances_the_groove_in_a_steady_film_and_friction_matches_petroff_when_centred():
    b = paper_bearing()
    film = ElrodAdamsSolver(b, 30, 31, tol_commit=1e-13, tol_steady=1e-13)
    p, th = film.steady_field([0.0, 1e-12])       # centred: no pressure, a full film
    q, power = film.flows([0.0, 1e-12], p, th)
    petroff = b.viscosity * b.omega * b.radius / b.clearance * b.omega * b.radius * 2.0 * math.pi * b.radius * b.length
    assert abs(power / petroff - 1.0) < 1e-8 and abs(q) < 1e-12
    # eccentric: the groove supplies what leaks out of the ends (steady: the flow balance, module doc)
    ep = film.params
    x = [0.0, 70e-6]
    p, th = film.steady_field(x)
    h = np.empty(ep.n_theta)
    hf = np.empty(ep.n_theta)
    ea.journal_gap(ep, 0.0, x[1] / b.clearance, h, hf)
    change, inflow, scale = ea.flow_balance(ep, ep.k_omega, h, hf, 0.0, np.zeros_like(p), p, th)
    assert change == 0.0 and abs(inflow) < 1e-9 * scale
    q, power = film.flows(x, p, th)
    full = ElrodAdamsSolver(b, 30, 31, tol_commit=1e-13, tol_steady=1e-13, cavitation="swift-stieber")
    q_ss, power_ss = full.flows(x, *full.steady_field(x))
    # the same pressure zone (the groove feeds it full), so the same leakage; the cavity's striated film shears
    # less than the full film the non-conserving rule assumes
    assert q > 0.0 and abs(q / q_ss - 1.0) < 1e-6
    assert power < 0.95 * power_ss


def test_a_film_solve_that_does_not_converge_ends_the_run_as_diverged_never_ok():
    film = ElrodAdamsSolver(paper_bearing(), 16, 9, max_sweeps=2, tol=1e-12, tol_commit=1e-12, tol_steady=1e-12)
    # the steady start already needs more than two sweeps: refused with the position named
    with pytest.raises(RuntimeError, match="did not converge"):
        simulate(film, Rotor(mass=2.5, imbalance=5e-4), t_end=1e-3, dt=1e-5, x0=(0.0, 50e-6))
    traj = simulate(film, Rotor(mass=2.5, imbalance=5e-4), t_end=1e-3, dt=1e-5, x0=(0.0, 50e-6),
                    film_content=np.ones((16, 9)))
    assert not traj.ok and traj.status.startswith("diverged: the film solve did not converge")
