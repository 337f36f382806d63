"""The conical bearing's solver against independent truth.

Limits (zero cone angle is the cylindrical bearing; a small angle tends to
the equivalent cylinder at second order), an exact similarity law of the
sleeve displacement, a second linear-algebra method for the general
h(theta, z) path (scipy's sparse direct solve of an independently assembled
system), and the cone's axial force from the surface geometry itself.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from fluidfilm import JournalBearing, ReynoldsSolver
from fluidfilm.core.bearing import ConicalBearing, bearing_from_dict
from fluidfilm.reynolds.conical import ConicalReynoldsSolver

MU, RPM, L, C = 6.53e-4, 3000.0, 0.064, 120e-6
STATES_X = np.array([[30e-6, 50e-6], [-70e-6, 50e-6], [0.0, 0.0], [10e-6, -90e-6]])
STATES_V = np.array([[0.01, -0.02], [0.0, 0.05], [0.1, 0.0], [-0.03, 0.0]])


def cone(d_small=0.03665, d_large=0.04335, **kw):
    kw.setdefault("sleeve_min", -0.8e-3)
    kw.setdefault("sleeve_max", 0.8e-3)
    return ConicalBearing(L, d_small, d_large, C, RPM, MU, **kw)


@pytest.mark.parametrize("supply", [0.0, 2.0e4])
@pytest.mark.parametrize("method", ["fast", "general"])
def test_zero_cone_angle_is_the_cylindrical_bearing(supply, method):
    cyl = ReynoldsSolver(JournalBearing(L, 0.040, C, RPM, MU, supply_pressure=supply), 30, 30)
    con = ConicalReynoldsSolver(cone(0.040, 0.040, supply_pressure=supply), 30, 30, method=method)
    a, b = cyl.forces(STATES_X, STATES_V), con.forces(STATES_X, STATES_V)
    np.testing.assert_allclose(b, a, rtol=1e-11, atol=1e-11 * np.abs(a).max())
    assert np.all(con.forces_axial(STATES_X, STATES_V)[..., 2] == 0.0)


@pytest.mark.parametrize("sleeve", [-0.8e-3, 0.0, 0.5e-3])
def test_general_path_equals_fast_path_for_matched_cones(sleeve):
    b = cone(supply_pressure=1e4)
    fast = ConicalReynoldsSolver(b, 24, 20, sleeve=sleeve)
    gen = ConicalReynoldsSolver(b, 24, 20, method="general", sleeve=sleeve)
    x = STATES_X * 0.6
    np.testing.assert_allclose(gen.forces(x, STATES_V), fast.forces(x, STATES_V), rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(gen.linear_pressure(x[1], STATES_V[1]), fast.linear_pressure(x[1], STATES_V[1]),
                               rtol=1e-9, atol=1e-6)


def test_small_cone_angle_tends_to_the_equivalent_cylinder_at_second_order():
    """A cone of mean diameter D and spread d tends to the cylinder of diameter D as d -> 0, error ~ d^2."""
    cyl = ReynoldsSolver(JournalBearing(L, 0.040, C, RPM, MU), 30, 30)
    x, v = np.array([20e-6, 60e-6]), np.array([0.01, 0.02])
    ref = cyl.forces(x, v)
    errs = []
    for spread in (2e-3, 1e-3, 0.5e-3):
        f = ConicalReynoldsSolver(cone(0.040 - spread / 2, 0.040 + spread / 2), 30, 30).forces(x, v)
        errs.append(np.linalg.norm(f - ref) / np.linalg.norm(ref))
    assert errs[0] < 0.01
    for a, b in zip(errs, errs[1:]):
        assert 3.0 < a / b < 5.0, errs


def test_sleeve_similarity_law():
    """With p_supply = 0 the film depends on X/c_r and V/(c_r omega) only and scales as c_r^-2:
    F(X, V; s) = (c/c_r)^2 F(X c/c_r, V c/c_r; 0), exactly (the discretisation does not see c_r)."""
    b = cone()
    solver = ConicalReynoldsSolver(b, 30, 30)
    for s in (-0.8e-3, 0.3e-3):
        k = C / b.clearance_at(s)
        solver.set_sleeve(0.0)
        expected = k**2 * solver.forces(STATES_X * 0.5 * k, STATES_V * k)
        solver.set_sleeve(s)
        np.testing.assert_allclose(solver.forces(STATES_X * 0.5, STATES_V), expected, rtol=1e-12, atol=1e-12)
    # closing the sleeve stiffens the film: the same displacement gives a larger force
    f = ConicalReynoldsSolver(b, 30, 30).sweep_sleeve([-0.8e-3, 0.0, 0.8e-3], STATES_X[:1] * 0.5, STATES_V[:1] * 0)
    mags = np.linalg.norm(f[:, 0], axis=-1)
    assert mags[0] > mags[1] > mags[2]


def _sparse_general(b: ConicalBearing, n_theta, n_z, sleeve, x, v):
    """Independent assembly of the tapered-cone system, solved by scipy's sparse LU."""
    th = 2 * np.pi * np.arange(n_theta) / n_theta
    dth = 2 * np.pi / n_theta
    z = np.linspace(0.0, b.length, n_z)
    dz = z[1] - z[0]
    ta = b.tan_half_angle
    cos2 = math.cos(math.atan(ta)) ** 2
    c_r = b.clearance_at(sleeve)

    def R(zz):
        return b.radius_small + ta * zz

    def H(t, zz):  # radial gap in units of c_r
        return (c_r + b.clearance_taper * zz / b.length - x[0] * np.sin(t) - x[1] * np.cos(t)) / c_r

    m = n_z - 2
    idx = lambda i, j: (i % n_theta) * m + (j - 1)  # noqa: E731
    A = sp.lil_matrix((n_theta * m, n_theta * m))
    rhs = np.zeros(n_theta * m)
    k_om = 6 * b.viscosity * b.omega / (cos2 * c_r**2)
    k_v = 12 * b.viscosity / (cos2 * c_r**3)
    for i in range(n_theta):
        for j in range(1, n_z - 1):
            row = idx(i, j)
            e = H(th[i] + dth / 2, z[j]) ** 3 / dth**2
            w = H(th[i] - dth / 2, z[j]) ** 3 / dth**2
            nn = cos2 * R(z[j]) * R(z[j] + dz / 2) * H(th[i], z[j] + dz / 2) ** 3 / dz**2
            ss = cos2 * R(z[j]) * R(z[j] - dz / 2) * H(th[i], z[j] - dz / 2) ** 3 / dz**2
            A[row, row] = -(e + w + nn + ss)
            A[row, idx(i + 1, j)] = e
            A[row, idx(i - 1, j)] = w
            r = R(z[j]) ** 2 * (k_om * (H(th[i] + dth / 2, z[j]) - H(th[i] - dth / 2, z[j])) / dth
                                + k_v * (-v[0] * np.sin(th[i]) - v[1] * np.cos(th[i])))
            if j + 1 < n_z - 1:
                A[row, idx(i, j + 1)] = nn
            if j - 1 > 0:
                A[row, idx(i, j - 1)] = ss
            else:
                r -= ss * b.supply_pressure
            rhs[row] = r
    p = np.zeros((n_theta, n_z))
    p[:, 0] = b.supply_pressure
    p[:, 1:-1] = spla.spsolve(A.tocsr(), rhs).reshape(n_theta, m)
    return p


@pytest.mark.parametrize("taper", [-40e-6, 30e-6])
def test_general_path_with_a_tapered_film_matches_a_sparse_direct_solve(taper):
    """h depends on z (sleeve cone off the journal's): the block-cyclic solve equals scipy's sparse LU."""
    b = cone(clearance_taper=taper, supply_pressure=5e3)
    gen = ConicalReynoldsSolver(b, 16, 12, sleeve=0.2e-3)
    assert gen.method == "general"
    x, v = np.array([15e-6, 25e-6]), np.array([0.02, -0.01])
    p_ref = _sparse_general(b, 16, 12, 0.2e-3, x, v)
    np.testing.assert_allclose(gen.linear_pressure(x, v), p_ref, rtol=1e-9, atol=1e-9 * np.abs(p_ref).max())
    # a wedge along z changes the load: the taper is not ignored
    matched = ConicalReynoldsSolver(cone(supply_pressure=5e3), 16, 12, sleeve=0.2e-3)
    assert np.linalg.norm(gen.forces(x, v) - matched.forces(x, v)) > 0.02 * np.linalg.norm(matched.forces(x, v))


def test_forces_including_the_axial_one_match_the_surface_integral_of_pressure():
    """-int p n dA over the journal's cone, normal and area from the surface parametrisation, trapezoid rule."""
    b = cone(0.030, 0.050, sleeve_min=-0.5e-3)  # a wide cone so the axial force is large
    solver = ConicalReynoldsSolver(b, 60, 61)
    x, v = np.array([30e-6, 60e-6]), np.array([0.0, 0.0])
    f = solver.forces_axial(x, v)
    p = solver.pressure(x, v)
    th = np.append(solver.mesh.theta, 2 * np.pi)
    pp = np.vstack([p, p[:1]])
    z = solver.mesh.z
    T, Z = np.meshgrid(th, z, indexing="ij")
    Rz = b.radius_small + b.tan_half_angle * Z
    # S(theta, z) = (R sin, R cos, z); dS/dtheta x dS/dz points out of the journal
    s_t = np.stack([Rz * np.cos(T), -Rz * np.sin(T), 0 * T], -1)
    s_z = np.stack([b.tan_half_angle * np.sin(T), b.tan_half_angle * np.cos(T), np.ones_like(T)], -1)
    n_da = np.cross(s_z, s_t)  # outward normal times the area element
    assert np.all(n_da[..., 0] * np.sin(T) + n_da[..., 1] * np.cos(T) > 0)
    integrand = -pp[..., None] * n_da
    surf = np.trapezoid(np.trapezoid(integrand, z, axis=1), th, axis=0)
    np.testing.assert_allclose(f, surf, rtol=0.01)
    assert f[2] > 0  # pushed towards the large end


def test_bad_conical_input_names_the_value():
    with pytest.raises(ValueError, match="0.002"):
        cone().clearance_at(2e-3)
    with pytest.raises(ValueError, match="diameter_large"):
        cone(0.045, 0.035)
    with pytest.raises(ValueError, match="closes the film"):
        cone(sleeve_min=-3e-3)
    with pytest.raises(ValueError, match="clearance_taper"):
        ConicalReynoldsSolver(cone(clearance_taper=1e-5), 20, 20, method="fast")
    with pytest.raises(ValueError, match="cavitation"):
        ConicalReynoldsSolver(cone(), 20, 20, cavitation="swift-stieber")
    with pytest.raises(ValueError, match="kind"):
        bearing_from_dict({"kind": "tilting-pad"})
    solver = ConicalReynoldsSolver(cone(), 20, 20, sleeve=-0.8e-3)
    with pytest.raises(ValueError):
        solver.forces([0.0, 100e-6], [0.0, 0.0])  # inside c but outside the closed sleeve's c_r
