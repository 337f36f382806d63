"""The active-set Swift-Stieber solver (``kernels.active_set_field``, the default ``method``) against the
projected SOR it replaces, and against the complementarity conditions themselves (an independent numpy
assembly of the discrete Reynolds residual), on the plain and the grooved bearing."""
from __future__ import annotations

import math

import numpy as np
import pytest

from fluidfilm import JournalBearing, ReynoldsSolver, paper_bearing
from fluidfilm.reynolds import kernels
from fluidfilm.reynolds.feed import GroovedReynoldsSolver, grooved_field, grooved_force

C = 120e-6


def states(count, seed, eps_max=0.9):
    """Random (position, velocity) pairs: eccentricities up to eps_max, velocities up to 0.3 m/s (a third at rest)."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(count):
        e, a = rng.uniform(0.05, eps_max), rng.uniform(0.0, 2.0 * math.pi)
        v = rng.uniform(-0.3, 0.3, 2) if k % 3 else np.zeros(2)
        out.append((np.array([e * C * math.sin(a), e * C * math.cos(a)]), v))
    return out


def residual(bearing, n_theta, n_z, x, v, p):
    """A p - rhs of the discrete Reynolds equation (kernels' docstring), assembled here in numpy, at the
    interior nodes (n_theta, n_z - 2)."""
    r, c, mu = bearing.radius, bearing.clearance, bearing.viscosity
    dth = 2.0 * math.pi / n_theta
    dzeta = bearing.length / (n_z - 1) / r
    th = dth * np.arange(n_theta)
    H = 1.0 - x[0] / c * np.sin(th) - x[1] / c * np.cos(th)
    Hf = 1.0 - x[0] / c * np.sin(th + dth / 2) - x[1] / c * np.cos(th + dth / 2)
    Hb = np.roll(Hf, 1)
    rhs = (6 * mu * bearing.omega * r**2 / c**2 * (Hf - Hb) / dth
           + 12 * mu * r**2 / c**3 * (-v[0] * np.sin(th) - v[1] * np.cos(th)))
    q = p[:, 1:-1]
    res = (Hf[:, None] ** 3 * (np.roll(q, -1, 0) - q) - Hb[:, None] ** 3 * (q - np.roll(q, 1, 0))) / dth**2
    res += H[:, None] ** 3 * (p[:, 2:] - 2 * q + p[:, :-2]) / dzeta**2
    return res - rhs[:, None]


def check_complementarity(res, p, held=None):
    """p >= 0; the residual vanishes where p > 0 and is <= 0 where p = 0 (A p <= rhs: the Gauss-Seidel value
    there would be negative, no flow into the cavity), each to 1e-9 of the residual's scale; returns the
    cavitated fraction."""
    inner = p[:, 1:-1]
    keep = np.ones(inner.shape, dtype=bool) if held is None else ~held[:, None].repeat(inner.shape[1], 1)
    scale = np.abs(res[keep]).max()
    assert p.min() >= 0.0
    assert np.abs(res[keep & (inner > 0)]).max() <= 1e-9 * scale
    assert res[keep & (inner == 0)].max() <= 1e-9 * scale
    return (keep & (inner == 0)).sum() / keep.sum()


# --------------------------------------------------------------------------- against projected SOR
@pytest.mark.parametrize("n_theta, n_z, supply", [(30, 30, 0.0), (24, 15, 0.0), (36, 21, 2e5)])
def test_plain_bearing_forces_equal_projected_sor(n_theta, n_z, supply):
    """Even and odd interior row counts (the folded and the halved mid-plane of the symmetric half field) and a
    supply pressure (no symmetry: the whole field); PSOR converged to 1e-13, forces within 1e-8 of |F|."""
    b = paper_bearing(supply_pressure=supply)
    new = ReynoldsSolver(b, n_theta, n_z, cavitation="swift-stieber")
    ref = ReynoldsSolver(b, n_theta, n_z, cavitation="swift-stieber", method="psor", sor_tol=1e-13,
                         sor_max_iter=5_000_000)
    assert new.method == "active-set"
    for x, v in states(10, n_theta):
        F, Fr = new.forces(x, v), ref.forces(x, v)
        assert np.abs(F - Fr).max() <= 1e-8 * np.abs(Fr).max(), (x, v, F, Fr)
    # the batch kernel takes the same path
    X = np.array([x for x, _ in states(10, n_theta)])
    V = np.array([v for _, v in states(10, n_theta)])
    np.testing.assert_allclose(new.forces(X, V), ref.forces(X, V), rtol=1e-8, atol=1e-8 * np.abs(ref.forces(X, V)).max())


@pytest.mark.parametrize("cavitation", ["swift-stieber", "gumbel"])
def test_grooved_bearing_forces_equal_sor(cavitation):
    """Two 20-deg grooves (Lund & Thomsen's layout) and one line groove; SOR converged to 1e-13."""
    b = JournalBearing(length=0.05, diameter=0.1, clearance=C, speed_rpm=3000.0, viscosity=0.02)
    layouts = [dict(groove_angle=math.pi / 2, n_grooves=2, groove_width=math.radians(20.0)),
               dict(groove_angle=math.pi)]
    for lay in layouts:
        new = GroovedReynoldsSolver(b, 48, 17, cavitation=cavitation, **lay)
        ref = GroovedReynoldsSolver(b, 48, 17, cavitation=cavitation, method="psor", sor_tol=1e-13,
                                    sor_max_iter=5_000_000, **lay)
        for x, v in states(6, 5, eps_max=0.85):
            F, Fr = new.forces(x, v), ref.forces(x, v)
            assert np.abs(F - Fr).max() <= 1e-8 * np.abs(Fr).max(), (lay, x, v, F, Fr)


# --------------------------------------------------------------------------- the complementarity conditions
def test_plain_field_satisfies_the_complementarity_conditions():
    b = paper_bearing()
    for n_theta, n_z in ((30, 30), (40, 31)):
        s = ReynoldsSolver(b, n_theta, n_z, cavitation="swift-stieber")
        for x, v in states(8, 11):
            p = s.pressure(x, v)
            cavitated = check_complementarity(residual(b, n_theta, n_z, x, v, p), p)
            assert 0.1 < cavitated < 0.9  # the film did rupture, and carries load


def test_grooved_field_satisfies_the_complementarity_conditions():
    b = JournalBearing(length=0.05, diameter=0.1, clearance=C, speed_rpm=3000.0, viscosity=0.02)
    s = GroovedReynoldsSolver(b, 60, 21, cavitation="swift-stieber", groove_angle=math.pi / 2, n_grooves=2,
                              groove_width=math.radians(20.0))
    held = s.gparams.fixed
    for x, v in states(6, 12, eps_max=0.85):
        p = s.pressure(x, v)  # groove frame: the state turned into it
        assert np.all(p[held] == 0.0)
        check_complementarity(residual(b, 60, 21, s.to_groove_frame(x), s.to_groove_frame(v), p), p, held)


def edge_slope(p, dth):
    """Largest |dp/dtheta| across the film's edges (one-sided difference from the last film node to the
    first cavitated one, both directions), relative to the largest |dp/dtheta| in the field."""
    q = p[:, 1:-1]
    nxt = np.roll(q, -1, 0)
    prv = np.roll(q, 1, 0)
    edge = ((q > 0) & (nxt == 0)) | ((q > 0) & (prv == 0))
    return (q[edge].max() / dth) / (np.abs(nxt - q).max() / dth)


def test_pressure_gradient_vanishes_at_the_film_edge_to_first_order():
    """Swift-Stieber's edge condition dp/dn = 0 holds to the discretisation's order: the slope across the
    rupture and reformation edges falls about as dtheta (fitted order > 0.7 over 30..240 angles, measured
    0.9-1.0; a field with a finite slope at its edge would give order 0)."""
    b = paper_bearing()
    ns = np.array([30, 60, 120, 240])
    for x, v in ((np.array([0.3 * C, 0.55 * C]), np.array([0.02, -0.03])), (np.array([0.0, 0.6 * C]), np.zeros(2))):
        ss = [edge_slope(ReynoldsSolver(b, n, 21, cavitation="swift-stieber").pressure(x, v), 2 * math.pi / n)
              for n in ns]
        order = -np.polyfit(np.log(ns), np.log(ss), 1)[0]
        assert order > 0.7 and ss[-1] < 0.2, (ss, order)


# --------------------------------------------------------------------------- the iteration count
def iteration_counts(n_theta, n_z, count, seed):
    s = ReynoldsSolver(paper_bearing(), n_theta, n_z, cavitation="swift-stieber")
    out = []
    for x, v in states(count, seed, eps_max=0.95):
        p = s.linear_pressure(x, v)
        np.maximum(p, 0.0, out=p)
        out.append(kernels.swift_stieber_field(s.params, x[0], x[1], v[0], v[1], p))
    return np.array(out)


def test_active_set_iterations_are_few_and_grow_slowly_with_the_grid():
    """Linear solves per force (measured when written, eps up to 0.95: 30x30 40 states 4-5, median 4;
    60x60 20 states 5-7, median 6; 120x41 20 states 4-8, median 7; since the first guess is
    ``kernels.mode_one_film``'s: 30x30 2-4, median 3; 60x60 4-6, median 5): bounded, against PSOR's
    thousands of sweeps."""
    c30 = iteration_counts(30, 30, 40, 1)
    c60 = iteration_counts(60, 60, 20, 2)
    assert c30.min() >= 2 and c30.max() <= 8 and np.median(c30) <= 6, np.bincount(c30)
    assert c60.max() <= 12 and np.median(c60) <= 9, np.bincount(c60)


def test_centred_journal_at_rest_and_bad_method():
    s = ReynoldsSolver(paper_bearing(), 20, 12, cavitation="swift-stieber")
    assert np.all(s.forces([0.0, 0.0], [0.0, 0.0]) == 0.0)
    with pytest.raises(ValueError, match="'sor'"):
        ReynoldsSolver(paper_bearing(), 20, 12, cavitation="swift-stieber", method="sor")
    with pytest.raises(ValueError, match="'direct'"):
        GroovedReynoldsSolver(paper_bearing(), 20, 12, method="direct")


# --------------------------------------------------------------------------- the sine-transform solve, the warm start
def fields_both_ways(params, n_theta, x, v, fixed, project=True):
    """The field of one state by the active-set iteration with its linear solves by the sine transform and
    capacitance matrix (the default) and by the envelope Cholesky factorisation alone (a second method)."""
    out = []
    for transform in (True, False):
        p = np.empty((n_theta, params.full_basis.shape[0] + 2))
        kernels.linear_field(params, x[0], x[1], v[0], v[1], params.full_basis, params.p_supply, p)
        if project:
            np.maximum(p, 0.0, out=p)
        p[fixed] = params.p_supply
        it = kernels.active_set_field(params, (x[0], x[1], v[0], v[1]), p, fixed,
                                      kernels.ActiveSetOptions(project, 10_000, transform))
        assert it > 0
        out.append(p)
    return out


@pytest.mark.parametrize("n_theta, n_z", [(30, 30), (24, 15), (60, 31)])
def test_transform_solve_equals_the_envelope_factorisation(n_theta, n_z):
    """Even and odd interior row counts (folded and halved mid-plane): the same field to round-off."""
    s = ReynoldsSolver(paper_bearing(), n_theta, n_z, cavitation="swift-stieber")
    no_groove = np.zeros(n_theta, dtype=bool)
    for x, v in states(8, n_z, eps_max=0.95):
        fast, env = fields_both_ways(s.params, n_theta, x, v, no_groove)
        assert np.abs(fast - env).max() <= 1e-11 * env.max(), (x, v)


@pytest.mark.parametrize("cavitation", ["swift-stieber", "none"])
def test_grooved_transform_solve_equals_the_envelope_factorisation(cavitation):
    """Held groove columns (Lund & Thomsen's two 20-deg grooves), the complementarity problem and the plain
    linear solve (runs between the grooves, no active node)."""
    b = JournalBearing(length=0.05, diameter=0.1, clearance=C, speed_rpm=3000.0, viscosity=0.02)
    g = GroovedReynoldsSolver(b, 72, 31, cavitation=cavitation, groove_angle=math.pi / 2, n_grooves=2,
                              groove_width=math.radians(20.0))
    for x, v in states(6, 3, eps_max=0.9):
        fast, env = fields_both_ways(g.gparams.film, 72, g.to_groove_frame(x), g.to_groove_frame(v),
                                     g.gparams.fixed, project=cavitation == "swift-stieber")
        assert np.abs(fast - env).max() <= 1e-11 * np.abs(env).max(), (x, v)


def test_grooved_warm_start_gives_the_cold_solution():
    """``forces`` starts each solve from the last cavitation set: a sequence of nearby states (a difference
    quotient's) and far jumps give each state's cold-started force to round-off, in fewer solves."""
    b = JournalBearing(length=0.05, diameter=0.1, clearance=C, speed_rpm=3000.0, viscosity=0.02)
    g = GroovedReynoldsSolver(b, 96, 21, groove_angle=math.pi / 2, n_grooves=2, groove_width=math.radians(20.0))
    x0 = np.array([0.2 * C, 0.6 * C])
    seq = [(x0, np.zeros(2)), (x0 + [1e-4 * C, 0.0], np.zeros(2)), (x0, [0.0, 1e-3]), (x0, [0.0, -1e-3])]
    seq += [(x, v) for x, v in states(5, 9, eps_max=0.9)]
    cold = np.array([grooved_force(g.gparams, x[0], x[1], v[0], v[1]) for x, v in seq])
    warm = np.array([g.forces(x, v) for x, v in seq])
    assert np.abs(warm - cold).max() <= 1e-10 * np.abs(cold).max()
    X = np.array([np.asarray(x, float) for x, _ in seq])
    V = np.array([np.asarray(v, float) for _, v in seq])
    np.testing.assert_allclose(g.forces(X, V), cold, rtol=0, atol=1e-10 * np.abs(cold).max())
    # the nearby states need fewer solves from the warm set than from the widened Gumbel film
    p = np.empty((96, 21))
    warm = np.zeros_like(g._warm)
    assert grooved_field(g.gparams, *x0, 0.0, 0.0, p, warm, False) >= 2  # cold: writes x0's set into warm
    assert grooved_field(g.gparams, *(x0 + [1e-4 * C, 0.0]), 0.0, 0.0, p, warm, True) == 1
