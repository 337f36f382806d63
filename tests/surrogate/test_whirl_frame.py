"""The 'whirl' frame: the film's homogeneity in its drive u = (eps - 2 v_t, 2 v_r), made exact in a surrogate.

Truth checked independently of the surrogate: the reference Reynolds solver itself gives no force for a
half-speed whirl and scales with u (the structure of the Reynolds equation in the journal's frame).
"""
from __future__ import annotations

import numpy as np
import pytest

from fluidfilm import ReynoldsSolver, load_surrogate, paper_bearing
from fluidfilm.surrogate import Scaling, SurrogateForceModel
from fluidfilm.surrogate import transforms as tf
from fluidfilm.surrogate.fit import fit_surrogate

B = paper_bearing()
C, OM = B.clearance, B.omega


def _state(eps, angle, vr, vt):
    """Position at (eps, angle) and the velocity with components (vr, vt) in units of c omega along
    e_r and e_t = (e_r2, -e_r1), the frame of ``transforms.to_polar``."""
    er = np.array([np.sin(angle), np.cos(angle)])
    et = np.array([er[1], -er[0]])
    return eps * C * er, (vr * er + vt * et) * C * OM


@pytest.mark.parametrize("cavitation", ["gumbel", "swift-stieber"])
def test_reference_film_is_homogeneous_in_its_drive(cavitation):
    """F(eps, k u) = k F(eps, u) for k > 0 and F = 0 at a half-speed whirl, from the finite-difference
    solver (not from the surrogate): the premise of the frame."""
    s = ReynoldsSolver(B, 30, 30, cavitation=cavitation)
    for eps, angle in [(0.3, 0.4), (0.6, 2.5), (0.85, -1.0)]:
        x, v_half = _state(eps, angle, 0.0, eps / 2)
        F0 = s.forces(x, np.zeros(2))
        assert np.hypot(*s.forces(x, v_half)) < 5e-3 * np.hypot(*F0)
        for vr, vt in [(0.2, 0.1), (-0.3, 0.6), (0.05, -0.4)]:
            x, v = _state(eps, angle, vr, vt)
            a = eps - 2 * vt
            for k in (0.5, 2.0):
                # the state whose drive is k u: v_r' = k v_r, v_t' = (eps - k a) / 2
                _, vk = _state(eps, angle, k * vr, (eps - k * a) / 2)
                np.testing.assert_allclose(s.forces(x, vk), k * s.forces(x, v), rtol=2e-3,
                                           atol=2e-3 * np.hypot(*F0))


def test_whirl_direction_is_the_unit_drive_and_neutral_at_zero():
    rng = np.random.default_rng(3)
    eps, vr, vt = rng.uniform(0, 0.9, 200), rng.normal(size=200), rng.normal(size=200)
    m, d1, d2 = tf.whirl_direction(eps, vr, vt)
    np.testing.assert_allclose(m * d1, eps - 2 * vt, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(m * d2, 2 * vr, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(np.hypot(d1, d2), 1.0, rtol=1e-14)
    assert tf.whirl_direction(0.4, 0.0, 0.2) == (0.0, 1.0, 0.0)


def test_whirl_scaling_needs_physics_and_no_extras():
    X, V, F = np.ones((4, 2)) * 1e-5, np.zeros((4, 2)), np.ones((4, 2))
    with pytest.raises(ValueError, match="whirl.*standard"):
        Scaling.fit("standard", X, V, F, C, OM, B.force_scale, frame="whirl")
    with pytest.raises(ValueError, match="frame"):
        Scaling.fit("physics", X, V, F, C, OM, B.force_scale, frame="journal")
    # built directly (or loaded from a model file) as well: the kernel would drop |u| for an affine kind
    for kind, extras in (("minmax", ()), ("physics", ("S",))):
        n = 3 + len(extras)
        with pytest.raises(ValueError, match="whirl"):
            Scaling(kind, C, OM, B.force_scale, 1.5, np.zeros(n), np.ones(n), np.zeros(2), np.ones(2), "whirl", extras)


def test_whirl_jacobian_refuses_a_vanished_drive_and_the_centre():
    """Where u vanishes (to rounding) or at eps = 0 the derivative does not exist: an error, not noise or NaN."""
    from fluidfilm.surrogate.jacobian import surrogate_jacobian
    rng = np.random.default_rng(1)
    sc = Scaling("physics", C, OM, B.force_scale, 1.5, np.zeros(3), np.ones(3), np.zeros(2), np.ones(2), "whirl")
    m = SurrogateForceModel(B, [[(rng.normal(size=(8, 3)), rng.normal(size=8)), (rng.normal(size=(2, 8)),
                                                                                  rng.normal(size=2))]], [sc], "tanh")
    x, v_half = _state(0.5, 1.1, 0.0, 0.25)  # |u| ~ 1e-16 after the rotation, not exactly 0
    with pytest.raises(ValueError, match="drive vanishes"):
        surrogate_jacobian(m, x, v_half)
    with pytest.raises(ValueError, match="centre"):
        surrogate_jacobian(m, np.zeros(2), np.array([0.01, 0.0]))
    F, J = surrogate_jacobian(m, x, np.zeros(2))  # at rest away from the centre: fine
    assert np.all(np.isfinite(J))


def test_whirl_frame_refuses_a_supply_pressure():
    """With a supply pressure the film force is not homogeneous in its drive (force at u = 0): refused."""
    sc = Scaling("physics", C, OM, B.force_scale, 1.5, np.zeros(3), np.ones(3), np.zeros(2), np.ones(2), "whirl")
    net = [(np.ones((4, 3)), np.zeros(4)), (np.ones((2, 4)), np.zeros(2))]
    with pytest.raises(ValueError, match="supply_pressure=20000"):
        SurrogateForceModel(paper_bearing(supply_pressure=2e4), [net], [sc], "tanh")
    # and the premise: with the supply end pressurised the reference is no longer homogeneous in u
    # (1.7 % here, against 0.1 % without supply pressure in the test above)
    s = ReynoldsSolver(paper_bearing(supply_pressure=2e4), 30, 30, cavitation="gumbel")
    x, v = _state(0.5, 0.3, 0.1, 0.1)
    _, v2 = _state(0.5, 0.3, 0.2, (0.5 - 2 * (0.5 - 0.2)) / 2)  # drive doubled
    F, F2 = s.forces(x, v), s.forces(x, v2)
    assert np.hypot(*(F2 - 2 * F)) > 0.01 * np.hypot(*(2 * F))


def test_damping_structure_refuses_the_whirl_frame():
    rng = np.random.default_rng(0)
    sc = Scaling("physics", C, OM, B.force_scale, 1.5, np.zeros(3), np.ones(3), np.zeros(2), np.ones(2), "whirl")
    net = lambda i, o: [(rng.normal(size=(4, i)), rng.normal(size=4)), (rng.normal(size=(o, 4)), rng.normal(size=o))]  # noqa: E731
    with pytest.raises(ValueError, match="whirl"):
        SurrogateForceModel(B, [(net(1, 2), net(3, 4))], [sc], "tanh", structure="damping")


def test_trained_whirl_surrogate_has_the_symmetries_exactly(quick_data, tmp_path):
    """A trained surrogate in the whirl frame: no force at a half-speed whirl, F(k u) = k F(u), rotation
    equivariance, all to rounding whatever the training reached; and its force tracks the reference."""
    dataset, testset = quick_data
    tiny = dict(width=16, depth=1, activation="tanh", lr=1e-2, optimizer="adam", scheduler="cosine")
    model, _ = fit_surrogate(dataset, tiny, {"boundaries": []}, {"kind": "physics", "power": 1.5, "frame": "whirl"},
                             dict(max_epochs=10, progress_bar=False), target=None, seed=0, batch_size=128)
    model.save(tmp_path / "w")
    m = load_surrogate(tmp_path / "w")
    for eps, angle in [(0.2, 0.3), (0.55, 2.0), (0.8, -2.2)]:
        x, v_half = _state(eps, angle, 0.0, eps / 2)
        # (u vanishes to rounding: eps - 2 v_t of the rotated state is ~1e-16, not 0)
        assert np.hypot(*m.forces(x, v_half)) < 1e-12 * np.hypot(*m.forces(x, np.zeros(2)))
        x, v = _state(eps, angle, 0.1, -0.2)
        a = eps - 2 * -0.2
        _, v3 = _state(eps, angle, 0.3, (eps - 3 * a) / 2)
        np.testing.assert_allclose(m.forces(x, v3), 3 * m.forces(x, v), rtol=1e-10)
        R = np.array([[np.cos(1.3), np.sin(1.3)], [-np.sin(1.3), np.cos(1.3)]])
        np.testing.assert_allclose(m.forces(R @ x, R @ v), R @ m.forces(x, v), rtol=1e-10,
                                   atol=1e-10 * np.abs(m.forces(x, v)).max())
    # it learned something: the static load at eps 0.5 within 30 % after 10 epochs of a 16-wide net
    ref = ReynoldsSolver(B, 30, 30, cavitation="gumbel")
    x, _ = _state(0.5, 0.0, 0.0, 0.0)
    F, Fr = m.forces(x, np.zeros(2)), ref.forces(x, np.zeros(2))
    assert np.hypot(*(F - Fr)) < 0.3 * np.hypot(*Fr)
