"""The reference Reynolds solver against independent truth.

Two kinds of test, as in ROSS: published/analytical values (Ocvirk's short
bearing, Sommerfeld's long bearing, Raimondi & Boyd, the public sanity values
of CONVENTIONS.md) and a second method (a sparse direct solve of the same
finite-difference system, scipy's Simpson rule), plus symmetry, linearity and
grid-convergence properties the discretisation must have.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.integrate as si
import scipy.optimize as so
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from fluidfilm import GradedReynoldsModel, JournalBearing, ReynoldsSolver, paper_bearing
from fluidfilm.reynolds.mesh import simpson_weights

C = 120e-6


@pytest.fixture(scope="module")
def bearing():
    return paper_bearing()


def polar(eps, angle, c=C):
    """Position at eccentricity ratio eps, angle measured like theta (from +X2 towards +X1)."""
    return np.array([eps * c * math.sin(angle), eps * c * math.cos(angle)])


# --------------------------------------------------------------------------- public values
@pytest.mark.parametrize("eps, expected", [(0.5, 18.63), (0.9, 123.9)])
def test_public_sanity_values_grid_converged(bearing, eps, expected):
    """CONVENTIONS.md: grid-converged |F| at rest with X along +X2 (two solvers agree within 0.1 %)."""
    f = [np.hypot(*ReynoldsSolver(bearing, n, n).forces([0.0, eps * C], [0.0, 0.0])) for n in (120, 240)]
    richardson = f[1] + (f[1] - f[0]) / 3.0  # second order: error ~ h^2
    assert richardson == pytest.approx(expected, rel=1e-3)


def test_coarse_grid_error_grows_towards_the_sleeve(bearing):
    """The paper's Fig. 2: 30x30 is within ~0.3 % up to eps 0.6, off by a few % at 0.9."""
    coarse = ReynoldsSolver(bearing, 30, 30)
    fine = ReynoldsSolver(bearing, 160, 160)
    err = {}
    for eps in (0.3, 0.6, 0.9, 0.95):
        x = [0.0, eps * C]
        err[eps] = abs(np.hypot(*coarse.forces(x, [0, 0])) / np.hypot(*fine.forces(x, [0, 0])) - 1)
    assert err[0.3] < 2e-3 and err[0.6] < 5e-3  # measured: 0.08 % and 0.34 %
    assert 0.01 < err[0.9] < 0.06
    assert err[0.95] > err[0.9]


# --------------------------------------------------------------------------- second method
def sparse_reference_field(bearing, n_theta, n_z, x, v):
    """Assemble the same finite-difference system with scipy.sparse and solve it directly."""
    r, c, mu = bearing.radius, bearing.clearance, bearing.viscosity
    dth = 2 * np.pi / n_theta
    dzeta = bearing.length / (n_z - 1) / r
    th = dth * np.arange(n_theta)
    thf = th + 0.5 * dth
    e1, e2 = x[0] / c, x[1] / c
    H = 1 - e1 * np.sin(th) - e2 * np.cos(th)
    Hf = 1 - e1 * np.sin(thf) - e2 * np.cos(thf)
    m = n_z - 2
    idx = lambda i, j: (i % n_theta) * m + (j - 1)  # noqa: E731
    A = sp.lil_matrix((n_theta * m, n_theta * m))
    b = np.zeros(n_theta * m)
    k_om = 6 * mu * bearing.omega * r**2 / c**2
    k_v = 12 * mu * r**2 / c**3
    for i in range(n_theta):
        aw, ae = Hf[i - 1] ** 3 / dth**2, Hf[i] ** 3 / dth**2
        an = H[i] ** 3 / dzeta**2
        rhs = k_om * (Hf[i] - Hf[i - 1]) / dth + k_v * (-v[0] * np.sin(th[i]) - v[1] * np.cos(th[i]))
        for j in range(1, n_z - 1):
            row = idx(i, j)
            A[row, row] = -(aw + ae + 2 * an)
            A[row, idx(i - 1, j)] += aw
            A[row, idx(i + 1, j)] += ae
            b[row] = rhs
            for jj in (j - 1, j + 1):
                if jj == 0:
                    b[row] -= an * bearing.supply_pressure
                elif jj == n_z - 1:
                    pass  # ambient
                else:
                    A[row, idx(i, jj)] += an
    p_int = spla.spsolve(A.tocsr(), b).reshape(n_theta, m)
    p = np.zeros((n_theta, n_z))
    p[:, 0] = bearing.supply_pressure
    p[:, 1:-1] = p_int
    return p


@pytest.mark.parametrize("supply", [0.0, 2.0e5])
@pytest.mark.parametrize("n_theta, n_z", [(30, 30), (55, 55), (17, 12)])
def test_fast_solve_equals_sparse_direct_solve(supply, n_theta, n_z):
    b = paper_bearing(supply_pressure=supply)
    x, v = polar(0.7, 1.1), np.array([0.03, -0.05])
    solver = ReynoldsSolver(b, n_theta, n_z, cavitation="none")
    ref = sparse_reference_field(b, n_theta, n_z, x, v)
    fast = solver.pressure(x, v)
    assert np.max(np.abs(fast - ref)) <= 1e-9 * np.max(np.abs(ref))
    # and the force is the Simpson integral of that field
    np.testing.assert_allclose(solver.forces(x, v), solver.integrate(ref), rtol=1e-9)
    gumbel = ReynoldsSolver(b, n_theta, n_z, cavitation="gumbel")
    np.testing.assert_allclose(gumbel.forces(x, v), gumbel.integrate(np.maximum(ref, 0.0)), rtol=1e-9)


@pytest.mark.parametrize("n_intervals", [2, 3, 4, 5, 9, 28, 54])
def test_simpson_weights_match_scipy_and_are_exact_for_cubics(n_intervals):
    xs = np.linspace(0.0, 1.3, n_intervals + 1)
    w = simpson_weights(n_intervals, xs[1] - xs[0])
    cubic = 2 * xs**3 - xs**2 + 3 * xs - 1
    exact = 2 * 1.3**4 / 4 - 1.3**3 / 3 + 3 * 1.3**2 / 2 - 1.3
    assert w @ cubic == pytest.approx(exact, rel=1e-12)
    smooth = np.exp(xs) * np.sin(3 * xs)
    if n_intervals % 2 == 0:  # scipy uses the same composite 1/3 rule for an odd node count
        assert w @ smooth == pytest.approx(si.simpson(smooth, x=xs), rel=1e-12)


# --------------------------------------------------------------------------- analytical limits
def ocvirk_force(bearing, x, v):
    """Short-bearing (Ocvirk) half-Sommerfeld force including squeeze, by adaptive quadrature.

    d/dz(h^3 dp/dz) = G(theta) = 6 mu omega dh/dtheta + 12 mu dh/dt with p = 0 at both
    ends gives p = G z (z - L) / (2 h^3); Gumbel keeps it where G < 0.
    """
    r, c, mu, L, om = bearing.radius, bearing.clearance, bearing.viscosity, bearing.length, bearing.omega
    h = lambda t: c - x[0] * np.sin(t) - x[1] * np.cos(t)  # noqa: E731
    G = lambda t: 6 * mu * om * (-x[0] * np.cos(t) + x[1] * np.sin(t)) + 12 * mu * (-v[0] * np.sin(t) - v[1] * np.cos(t))  # noqa: E731
    pint = lambda t: max(0.0, -G(t) * L**3 / (12 * h(t) ** 3))  # integral of p over z  # noqa: E731
    grid = np.linspace(0, 2 * np.pi, 721)
    g = np.array([G(t) for t in grid])
    roots = [so.brentq(G, grid[k], grid[k + 1]) for k in range(720) if g[k] * g[k + 1] < 0]
    pts = sorted(roots)
    f1 = -r * si.quad(lambda t: pint(t) * np.sin(t), 0, 2 * np.pi, points=pts, limit=400, epsabs=0, epsrel=1e-11)[0]
    f2 = -r * si.quad(lambda t: pint(t) * np.cos(t), 0, 2 * np.pi, points=pts, limit=400, epsabs=0, epsrel=1e-11)[0]
    return np.array([f1, f2])


def test_ocvirk_quadrature_matches_closed_form():
    """The quadrature reference reproduces Ocvirk's closed form for pure rotation."""
    b = JournalBearing(length=0.002, diameter=0.040, clearance=C, speed_rpm=3000, viscosity=6.53e-4)
    for eps in (0.2, 0.5, 0.8):
        F = ocvirk_force(b, [0.0, eps * C], [0.0, 0.0])
        W = (b.viscosity * b.omega * b.radius * b.length**3 / (4 * C**2)) * eps / (1 - eps**2) ** 2 * math.sqrt(
            16 * eps**2 + math.pi**2 * (1 - eps**2))
        assert np.hypot(*F) == pytest.approx(W, rel=1e-8)
        attitude = math.atan2(abs(F[0]), abs(F[1]))
        assert attitude == pytest.approx(math.atan(math.pi * math.sqrt(1 - eps**2) / (4 * eps)), rel=1e-8)


@pytest.mark.parametrize("eps, angle, v", [
    (0.3, 0.4, (0.0, 0.0)),
    (0.5, 2.0, (0.02, -0.01)),
    (0.7, -1.0, (-0.05, 0.03)),
    (0.6, 3.0, (0.0, 0.08)),   # squeeze-dominated
])
def test_short_bearing_limit_matches_ocvirk(eps, angle, v):
    """L/D = 0.05: the finite bearing is within 1 % of Ocvirk's solution, squeeze included."""
    b = JournalBearing(length=0.002, diameter=0.040, clearance=C, speed_rpm=3000, viscosity=6.53e-4)
    x = polar(eps, angle)
    F = ReynoldsSolver(b, 240, 13).forces(x, v)
    ref = ocvirk_force(b, x, v)
    assert np.hypot(*(F - ref)) <= 0.01 * np.hypot(*ref)


def test_long_bearing_midplane_approaches_sommerfeld():
    """L/D = 10: the mid-plane pressure is Sommerfeld's; after Gumbel clipping, half-Sommerfeld's."""
    b = JournalBearing(length=0.4, diameter=0.040, clearance=C, speed_rpm=3000, viscosity=6.53e-4)
    eps = 0.6
    n_z = 81
    full = ReynoldsSolver(b, 360, n_z, cavitation="none").pressure([0.0, eps * C], [0.0, 0.0])[:, n_z // 2]
    half = ReynoldsSolver(b, 360, n_z, cavitation="gumbel").pressure([0.0, eps * C], [0.0, 0.0])[:, n_z // 2]
    th = np.linspace(0, 2 * np.pi, 360, endpoint=False)
    tp = th - np.pi  # Sommerfeld's angle from the thickest film: h = c (1 + eps cos tp)
    somm = (6 * b.viscosity * b.omega * b.radius**2 / C**2) * eps * np.sin(tp) * (2 + eps * np.cos(tp)) / (
        (2 + eps**2) * (1 + eps * np.cos(tp)) ** 2)
    peak = somm.max()
    assert np.max(np.abs(full - somm)) <= 0.005 * peak
    assert np.max(np.abs(half - np.maximum(somm, 0))) <= 0.005 * peak


@pytest.mark.parametrize("cavitation", ["none", "gumbel"])
def test_second_order_grid_convergence_by_richardson(bearing, cavitation):
    x, v = polar(0.6, 0.3), [0.01, 0.0]
    F = [np.hypot(*ReynoldsSolver(bearing, n, n + 1, cavitation=cavitation).forces(x, v)) for n in (40, 80, 160)]
    order = math.log2((F[0] - F[1]) / (F[1] - F[2]))
    assert 1.7 < order < 2.3
    # the extrapolated value is closer to a much finer solution than the finest grid itself
    extrapolated = F[2] + (F[2] - F[1]) / (2**order - 1)
    finest = np.hypot(*ReynoldsSolver(bearing, 400, 401, cavitation=cavitation).forces(x, v))
    assert abs(extrapolated - finest) < abs(F[2] - finest)


@pytest.mark.parametrize("eps, S, phi_deg", [(0.6, 0.121, 50.58), (0.8, 0.0446, 36.24), (0.9, 0.0188, 26.45)])
def test_swift_stieber_matches_raimondi_boyd(eps, S, phi_deg):
    """Raimondi & Boyd (1958), L/D = 1, Reynolds (Swift-Stieber) boundary condition."""
    b = JournalBearing(length=0.04, diameter=0.04, clearance=C, speed_rpm=3000, viscosity=6.53e-4)
    F = ReynoldsSolver(b, 90, 61, cavitation="swift-stieber").forces([0.0, eps * C], [0.0, 0.0])
    assert b.sommerfeld(np.hypot(*F)) == pytest.approx(S, rel=0.02)
    assert math.degrees(math.atan2(abs(F[0]), abs(F[1]))) == pytest.approx(phi_deg, abs=2.0)
    # Gumbel carries less load at the same eccentricity: higher S by 5-25 % (CONVENTIONS.md)
    Fg = ReynoldsSolver(b, 90, 61, cavitation="gumbel").forces([0.0, eps * C], [0.0, 0.0])
    ratio = b.sommerfeld(np.hypot(*Fg)) / b.sommerfeld(np.hypot(*F))
    assert 1.05 < ratio < 1.25


def test_swift_stieber_solves_the_complementarity_problem(bearing):
    x, v = polar(0.7, 0.5), np.array([0.02, -0.03])
    s = ReynoldsSolver(bearing, 40, 31, cavitation="swift-stieber")
    p = s.pressure(x, v)
    assert p.min() >= 0.0
    # residual of the discrete Reynolds equation: zero where p > 0, of the right sign where p = 0
    lin = ReynoldsSolver(bearing, 40, 31, cavitation="none")
    p_lin = lin.pressure(x, v)
    n = 40
    i = np.arange(n)
    # residual operator applied via the linear solution: A p - rhs = A (p - p_lin)
    dth = 2 * np.pi / n
    dz = bearing.length / 30 / bearing.radius
    th = dth * i
    H = 1 - x[0] / C * np.sin(th) - x[1] / C * np.cos(th)
    Hf = 1 - x[0] / C * np.sin(th + dth / 2) - x[1] / C * np.cos(th + dth / 2)
    d = p - p_lin
    res = (Hf[:, None] ** 3 * (np.roll(d, -1, 0) - d) - np.roll(Hf, 1)[:, None] ** 3 * (d - np.roll(d, 1, 0))) / dth**2
    res[:, 1:-1] += H[:, None] ** 3 * (d[:, 2:] - 2 * d[:, 1:-1] + d[:, :-2]) / dz**2
    res = res[:, 1:-1]
    inner = p[:, 1:-1]
    scale = np.abs(res).max()
    assert np.abs(res[inner > 0]).max() <= 1e-6 * scale
    assert res[inner == 0].max() <= 1e-6 * scale  # A p <= rhs where the film has ruptured
    assert (inner == 0).sum() > 0.2 * inner.size  # and it did rupture


# --------------------------------------------------------------------------- symmetry and consistency
def rot(angle):
    """Rotation of vectors written as (sin, cos) components: angle advances theta."""
    ca, sa = math.cos(angle), math.sin(angle)
    return np.array([[ca, sa], [-sa, ca]])


def test_rotating_the_journal_rotates_the_force(bearing):
    s = ReynoldsSolver(bearing, 60, 40)
    x, v = polar(0.6, 0.7), np.array([0.01, -0.02])
    F = s.forces(x, v)
    # a shift by two grid nodes maps the grid and its Simpson weights onto themselves: exact
    a = 2 * 2 * np.pi / 60
    Fr = s.forces(rot(a) @ x, rot(a) @ v)
    np.testing.assert_allclose(Fr, rot(a) @ F, rtol=1e-10, atol=1e-10 * np.abs(F).max())
    # any other angle: equal up to the discretisation error
    for a in (0.123, 1.0, 2.5):
        Fr = s.forces(rot(a) @ x, rot(a) @ v)
        assert np.hypot(*(Fr - rot(a) @ F)) < 5e-3 * np.hypot(*F)


def test_gumbel_pressure_is_never_negative_and_is_the_clipped_linear_field(bearing):
    s = ReynoldsSolver(bearing, 30, 30)
    rng = np.random.default_rng(3)
    for _ in range(20):
        x = polar(rng.uniform(0, 0.95), rng.uniform(0, 2 * np.pi))
        v = rng.uniform(-0.3, 0.3, 2)
        p = s.pressure(x, v)
        assert p.min() >= 0.0
        np.testing.assert_array_equal(p, np.maximum(s.linear_pressure(x, v), 0.0))


def test_centred_journal_at_rest_carries_no_load(bearing):
    for cav in ("gumbel", "swift-stieber", "none"):
        F = ReynoldsSolver(bearing, 30, 30, cavitation=cav).forces([0.0, 0.0], [0.0, 0.0])
        assert np.all(F == 0.0)


def test_supply_pressure_alone_gives_linear_axial_profile_and_no_force():
    b = paper_bearing(supply_pressure=1.5e5)
    s = ReynoldsSolver(b, 24, 21, cavitation="gumbel")
    p = s.pressure([0.0, 0.0], [0.0, 0.0])
    np.testing.assert_allclose(p, np.tile(1.5e5 * (1 - s.z / b.length), (24, 1)), rtol=1e-10, atol=1e-6)
    assert np.abs(s.forces([0.0, 0.0], [0.0, 0.0])).max() < 1e-9


def test_linear_in_velocity_without_cavitation(bearing):
    s = ReynoldsSolver(bearing, 30, 30, cavitation="none")
    x = polar(0.4, 1.0)
    va, vb = np.array([0.03, -0.01]), np.array([-0.02, 0.05])
    lhs = s.forces(x, va + vb)
    rhs = s.forces(x, va) + s.forces(x, vb) - s.forces(x, [0.0, 0.0])
    np.testing.assert_allclose(lhs, rhs, rtol=1e-9, atol=1e-9)


def test_squeeze_film_resists_the_motion(bearing):
    """Pure squeeze (no rotation): the film force opposes the journal's velocity."""
    b = JournalBearing(length=0.064, diameter=0.040, clearance=C, speed_rpm=0.0, viscosity=6.53e-4)
    s = ReynoldsSolver(b, 40, 30, cavitation="none")
    for v in ([0.01, 0.0], [0.0, -0.02], [0.01, 0.01]):
        F = s.forces(polar(0.3, 0.5), v)
        assert np.dot(F, v) < 0


def test_batch_equals_one_by_one_and_product_equals_batch(bearing):
    s = ReynoldsSolver(bearing, 30, 30)
    rng = np.random.default_rng(0)
    X = np.stack([polar(e, a) for e, a in zip(rng.uniform(0, 0.95, 7), rng.uniform(0, 6.3, 7))])
    V = rng.uniform(-0.2, 0.2, (5, 2))
    single = np.array([[s.forces(x, v) for v in V] for x in X])
    prod = s.forces_product(X, V)
    batch = s.forces(X[:, None, :], V[None, :, :])
    assert batch.shape == (7, 5, 2)
    np.testing.assert_array_equal(prod, single)
    np.testing.assert_array_equal(batch, single)


def test_graded_model_uses_the_dense_grid_above_the_threshold(bearing):
    g = GradedReynoldsModel(bearing, coarse=(30, 30), dense=(55, 55), eps_threshold=0.9)
    coarse, dense = ReynoldsSolver(bearing, 30, 30), ReynoldsSolver(bearing, 55, 55)
    X = np.stack([polar(0.5, 1.0), polar(0.93, 2.0)])
    V = np.array([[0.01, 0.0], [0.0, 0.02]])
    F = g.forces(X, V)
    np.testing.assert_array_equal(F[0], coarse.forces(X[0], V[0]))
    np.testing.assert_array_equal(F[1], dense.forces(X[1], V[1]))


def test_api_shapes_and_nodes(bearing):
    s = ReynoldsSolver(bearing, n_theta=55, n_z=30)
    assert s.bearing is bearing
    assert s.theta.shape == (55,) and s.z.shape == (30,)
    assert s.z[0] == 0.0 and s.z[-1] == pytest.approx(bearing.length)
    assert s.pressure(polar(0.5, 0.0), [0.0, 0.0]).shape == (55, 30)
    assert s.forces(np.zeros((3, 4, 2)), np.zeros(2)).shape == (3, 4, 2)


# --------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("X, V, match", [
    ([0.0, 1.0 * C], [0.0, 0.0], "eccentricity ratio 1 "),
    ([0.0, 1.2 * C], [0.0, 0.0], "eccentricity ratio 1.2"),
    ([np.nan, 0.0], [0.0, 0.0], "position X must be finite"),
    ([0.0, 0.0], [np.inf, 0.0], "velocity V must be finite"),
    ([[0.0, 0.0], [0.0, 0.99 * C], [2 * C, 0.0]], [0.0, 0.0], "eccentricity ratio 2"),
    ([[0.0, 0.0], [0.0, np.nan]], [0.0, 0.0], "nan"),
])
def test_bad_states_raise_value_error_naming_the_value(bearing, X, V, match):
    s = ReynoldsSolver(bearing, 30, 30)
    with pytest.raises(ValueError, match=match):
        s.forces(X, V)


@pytest.mark.parametrize("kwargs, match", [
    (dict(length=0.0), "length"),
    (dict(diameter=-0.04), "diameter"),
    (dict(clearance=float("nan")), "clearance"),
    (dict(viscosity=0.0), "viscosity"),
    (dict(speed_rpm=-1.0), "speed_rpm"),
    (dict(supply_pressure=-1.0), "supply_pressure"),
])
def test_bad_bearing_raises_value_error_naming_the_key(kwargs, match):
    base = dict(length=0.064, diameter=0.040, clearance=C, speed_rpm=3000.0, viscosity=6.53e-4)
    base.update(kwargs)
    with pytest.raises(ValueError, match=match):
        JournalBearing(**base)


@pytest.mark.parametrize("kwargs, match", [
    (dict(n_theta=4), "n_theta=4 is too small"),
    (dict(n_z=3), "n_z=3 is too small"),
    (dict(n_theta=30.5), "n_theta must be an integer"),
    (dict(cavitation="reynolds"), "unknown cavitation model 'reynolds'"),
])
def test_bad_solver_settings_raise(bearing, kwargs, match):
    with pytest.raises(ValueError, match=match):
        ReynoldsSolver(bearing, **kwargs)
