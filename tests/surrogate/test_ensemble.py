"""Ensembles and the hybrid model, checked against what the members and the fallback give on their own.

Independent truths: the mean of linear bearings is the linear bearing of the mean coefficients (so an
ensemble's trajectory must equal that bearing's); the spread of two members has a closed form; a hybrid
that flags every state must reproduce its fallback, one that flags none its members' mean.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from fluidfilm import Rotor, paper_bearing, simulate
from fluidfilm.surrogate.ensemble import EnsembleForceModel, HybridForceModel
from fluidfilm.core.force_model import ForceModel
from fluidfilm.reynolds import ReynoldsSolver
from fluidfilm.rotor import LinearBearing

from golden_models import _net, _scaling


def _states(c, n=50, seed=3):
    rng = np.random.default_rng(seed)
    eps = 0.85 * rng.random(n)
    ang = 2 * np.pi * rng.random(n)
    X = c * np.stack([eps * np.sin(ang), eps * np.cos(ang)], axis=1)
    return X, rng.uniform(-0.05, 0.05, (n, 2))


def _surrogates(k=3):
    from fluidfilm.surrogate import SurrogateForceModel

    jb = paper_bearing()
    out = []
    for seed in range(k):
        rng = np.random.default_rng(seed)
        out.append(SurrogateForceModel(jb, [_net(rng, 4, 8, 2)], [_scaling(np.random.default_rng(99), "standard",
                                                                             jb.clearance, jb.omega, "cartesian")],
                                       "tanh", name=f"s{seed}"))
    return out


def test_ensemble_is_the_members_mean_and_its_spread_the_sample_deviation():
    members = _surrogates(3)
    X, V = _states(members[0].clearance)
    each = np.stack([m.forces(X, V) for m in members])            # (3, n, 2), each member on its own
    mean = each.mean(axis=0)
    s = np.sqrt(((each - mean) ** 2).sum(axis=(0, 2)) / 2)
    tol = float(np.median(s / np.maximum(np.hypot(mean[:, 0], mean[:, 1]), 0.5)))  # flags about half
    ens = EnsembleForceModel(members, rel_tol=tol, floor_N=0.5)
    assert isinstance(ens, ForceModel)
    np.testing.assert_allclose(ens.forces(X, V), mean, rtol=1e-13, atol=1e-12)
    got_mean, got_s = ens.spread(X, V)
    np.testing.assert_allclose(got_mean, mean, rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(got_s, s, rtol=1e-12, atol=1e-12)
    expect = s > tol * np.maximum(np.hypot(mean[:, 0], mean[:, 1]), 0.5)
    assert 0 < expect.sum() < len(expect)  # the test states exercise both outcomes
    np.testing.assert_array_equal(ens.flagged(X, V), expect)
    ens.reset_domain_counter()
    ens.forces(X, V)
    assert (ens.n_evaluations, ens.n_flagged) == (len(X), int(expect.sum()))


def test_identical_members_agree_everywhere():
    m = _surrogates(1)[0]
    ens = EnsembleForceModel([m, m, m], rel_tol=1e-9, floor_N=1e-9)
    X, V = _states(m.clearance)
    np.testing.assert_allclose(ens.forces(X, V), m.forces(X, V), rtol=1e-14, atol=1e-13)
    assert not ens.flagged(X, V).any() and ens.n_flagged == 0


def test_hybrid_answers_with_the_fallback_exactly_where_the_members_disagree():
    members = _surrogates(3)
    fallback = ReynoldsSolver(paper_bearing(), 16, 16)
    X, V = _states(fallback.clearance)
    mean, s = EnsembleForceModel(members).spread(X, V)
    tol = float(np.median(s / np.maximum(np.hypot(mean[:, 0], mean[:, 1]), 0.5)))
    ens = EnsembleForceModel(members, rel_tol=tol, floor_N=0.5)
    hyb = HybridForceModel(members, fallback, rel_tol=tol, floor_N=0.5)
    assert isinstance(hyb, ForceModel)
    flag = ens.flagged(X, V)
    expect = np.where(flag[:, None], fallback.forces(X, V), ens.forces(X, V))
    hyb.reset_domain_counter()
    np.testing.assert_allclose(hyb.forces(X, V), expect, rtol=1e-12, atol=1e-12)
    assert 0 < hyb.n_fallbacks == int(flag.sum()) < len(X)


def test_mean_of_linear_bearings_is_the_linear_bearing_of_the_mean_in_a_trajectory():
    jb = paper_bearing()
    a, b = LinearBearing(jb, 2.0e5, 300.0), LinearBearing(jb, 3.0e5, 500.0)
    mean = LinearBearing(jb, 2.5e5, 400.0)
    rotor = Rotor(mass=0.5, imbalance=2e-6)
    # the relative spread of the two is constant where the damping force is small: flag nothing ...
    ens = EnsembleForceModel([a, b], rel_tol=10.0, floor_N=1e-6)
    t_ens = simulate(ens, rotor, t_end=0.05, dt=1e-4)
    t_mean = simulate(mean, rotor, t_end=0.05, dt=1e-4)
    np.testing.assert_allclose(t_ens.x, t_mean.x, rtol=1e-10, atol=1e-16)
    assert ens.n_evaluations == t_ens.n_force_evals and ens.n_flagged == 0
    # ... and a hybrid that flags every state (any spread beats a zero tolerance) is its fallback
    other = LinearBearing(jb, 4.0e5, 250.0)
    hyb = HybridForceModel([a, b], other, rel_tol=1e-12, floor_N=1e-12)
    t_hyb = simulate(hyb, rotor, t_end=0.05, dt=1e-4, x0=(1e-6, 0.0))
    t_other = simulate(other, rotor, t_end=0.05, dt=1e-4, x0=(1e-6, 0.0))
    np.testing.assert_allclose(t_hyb.x, t_other.x, rtol=1e-12, atol=1e-18)
    assert hyb.n_fallbacks == t_hyb.n_force_evals


def test_two_member_spread_has_its_closed_form():
    jb = paper_bearing()
    a, b = LinearBearing(jb, 2.0e5, 0.0), LinearBearing(jb, 3.0e5, 0.0)
    ens = EnsembleForceModel([a, b], rel_tol=0.5, floor_N=1e-9)
    X, V = _states(jb.clearance)
    mean, s = ens.spread(X, V)
    # s = |F_a - F_b| / sqrt(2), and relative to |mean| it is sqrt(2) (k_b - k_a) / (k_a + k_b) everywhere
    np.testing.assert_allclose(s / np.hypot(mean[:, 0], mean[:, 1]), math.sqrt(2) * 1e5 / 5e5, rtol=1e-12)
    assert not ens.flagged(X, V).any()  # 0.28 < 0.5
    assert EnsembleForceModel([a, b], rel_tol=0.25, floor_N=1e-9).flagged(X, V).all()


@pytest.mark.parametrize("kwargs, match", [
    (dict(rel_tol=0.0), "rel_tol must be a positive number, got 0.0"),
    (dict(floor_N=float("nan")), "floor_N must be a positive number, got nan"),
    (dict(rel_tol=True), "rel_tol must be a positive number, got True"),
])
def test_bad_tolerances_are_refused_by_name(kwargs, match):
    with pytest.raises(ValueError, match=match):
        EnsembleForceModel(_surrogates(2), **kwargs)


def test_bad_members_are_refused():
    jb = paper_bearing()
    with pytest.raises(ValueError, match="at least 2 members, got 1"):
        EnsembleForceModel(_surrogates(1))
    with pytest.raises(ValueError, match="share one force kernel"):
        EnsembleForceModel([_surrogates(1)[0], LinearBearing(jb, 1e5, 1.0)])
    with pytest.raises(ValueError, match="not a force model"):
        EnsembleForceModel([object(), object()])
    with pytest.raises(ValueError, match="needs a fallback"):
        HybridForceModel(_surrogates(2), None)



def test_ensembles_take_the_uncached_compiled_loops():
    """Parameters holding compiled functions go to the integrator's uncached loop (see
    ``rotor.integrate._holds_functions``); the library's plain models keep the cached one.  A surrogate's
    own kernel is generated per model shape at run time (``surrogate.kernels``), which numba cannot cache:
    it takes the uncached loop too."""
    from fluidfilm.rotor.integrate import _library_types

    members = _surrogates(2)
    assert _library_types(*ReynoldsSolver(paper_bearing(), 16, 16).force_kernel)
    assert not _library_types(*members[0].force_kernel)
    assert not _library_types(*EnsembleForceModel(members).force_kernel)
    assert not _library_types(*HybridForceModel(members, ReynoldsSolver(paper_bearing(), 16, 16)).force_kernel)


def test_flag_calibration_counts_what_the_flag_catches():
    """Two linear members around a known truth: the members' mean errs by a known ratio everywhere, and the
    flag fires everywhere (the spread ratio is constant), so recall and precision are 1 or the shares 0."""
    from fluidfilm.surrogate.ensemble import flag_calibration

    jb = paper_bearing()
    a, b = LinearBearing(jb, 2.0e5, 0.0), LinearBearing(jb, 3.0e5, 0.0)   # mean 2.5e5
    X, V = _states(jb.clearance)
    truth = LinearBearing(jb, 2.0e5, 0.0).forces(X, V)                    # the mean errs by 25 % everywhere
    # spread / |mean| = sqrt(2) * 0.2 = 0.283 and error 0.5e5 / 2e5 = 0.25: both above 0.2, both below 0.3
    cal = flag_calibration(EnsembleForceModel([a, b], rel_tol=0.2, floor_N=1e-9), X, V, truth)
    assert cal["flagged_share"] == 1.0 and cal["wrong_share"] == 1.0
    assert cal["recall"] == 1.0 and cal["precision"] == 1.0
    assert cal["median_err_flagged"] == pytest.approx(0.25) and cal["median_err_unflagged"] is None
    cal = flag_calibration(EnsembleForceModel([a, b], rel_tol=0.3, floor_N=1e-9), X, V, truth)
    assert cal["flagged_share"] == 0.0 and cal["wrong_share"] == 0.0
    assert cal["recall"] is None and cal["precision"] is None
    # the truth at the mean: nothing is wrong, whatever the flag says
    cal = flag_calibration(EnsembleForceModel([a, b], rel_tol=0.2, floor_N=1e-9), X, V,
                           LinearBearing(jb, 2.5e5, 0.0).forces(X, V))
    assert cal["wrong_share"] == 0.0 and cal["precision"] == 0.0
    with pytest.raises(ValueError, match="F must have the shape"):
        flag_calibration(EnsembleForceModel([a, b]), X, V, truth[:3])


# --- through the batched kernels (simulate_batch's stage-batched loop) ------------------------------------
def test_the_batched_ensemble_and_hybrid_kernels_equal_the_one_state_ones_and_count_alike():
    members = _surrogates(3)
    fallback = ReynoldsSolver(paper_bearing(), 16, 16)
    X, V = _states(fallback.clearance, n=300)
    mean, s = EnsembleForceModel(members).spread(X, V)
    tol = float(np.median(s / np.maximum(np.hypot(mean[:, 0], mean[:, 1]), 0.5)))  # flags about half
    for model in (EnsembleForceModel(members, rel_tol=tol, floor_N=0.5),
                  HybridForceModel(members, fallback, rel_tol=tol, floor_N=0.5)):
        model.reset_domain_counter()
        expect = model.forces(X, V)
        counts = (model.n_evaluations, model.n_flagged, model.n_outside_domain)
        assert 0 < counts[1] < len(X)
        model.reset_domain_counter()
        fn, bp = model.batch_force_kernel()
        got = np.empty_like(X)
        fn(bp, np.ascontiguousarray(X), np.ascontiguousarray(V), got)
        np.testing.assert_allclose(got, expect, rtol=1e-12, atol=1e-12)
        assert (model.n_evaluations, model.n_flagged, model.n_outside_domain) == counts
        # private parameters count apart until merged
        model.reset_domain_counter()
        fn, bp = model.batch_force_kernel(private=True)
        fn(bp, np.ascontiguousarray(X), np.ascontiguousarray(V), got)
        assert (model.n_evaluations, model.n_flagged) == (0, 0)
        model.merge_counts(bp)
        assert (model.n_evaluations, model.n_flagged, model.n_outside_domain) == counts


def _linear_hybrid(fallback=None):
    jb = paper_bearing()
    a, b = LinearBearing(jb, 2.0e5, 300.0), LinearBearing(jb, 3.0e5, 500.0)
    # the spread relative to the mean force is ~0.28 where the spring dominates, more where damping does
    return HybridForceModel([a, b], fallback or LinearBearing(jb, 4.0e5, 250.0), rel_tol=0.3, floor_N=1e-3)


class _NoBatchKernel:
    """A force model without a batched kernel (a user's model): the linear bearing's one-state kernel only."""

    def __init__(self, inner):
        self._inner = inner
        self.name, self.bearing, self.clearance = "user", inner.bearing, inner.clearance
        self.force_kernel, self.validity = inner.force_kernel, inner.validity
        self.n_outside_domain = 0

    def forces(self, X, V):
        return self._inner.forces(X, V)

    def reset_domain_counter(self):
        pass

    def domain_report(self):
        return None


@pytest.mark.parametrize("batched_fallback", [True, False])
def test_a_batch_of_hybrid_trajectories_equals_simulate_to_the_last_bit(batched_fallback):
    """Linear members and fallback: every force of the stage-batched path is the one-state kernel's to the
    last bit, so the batch must equal ``simulate`` run by run, flags and fallbacks counted alike.  A fallback
    without a batched kernel sends the hybrid to the per-trajectory loop, with the same result."""
    from fluidfilm.core.force_model import BatchForceModel
    from fluidfilm.rotor.batch import simulate_batch

    jb = paper_bearing()
    other = LinearBearing(jb, 4.0e5, 250.0)
    hyb = _linear_hybrid(other if batched_fallback else _NoBatchKernel(other))
    assert isinstance(hyb, BatchForceModel) and (hyb.batch_force_kernel() is not None) == batched_fallback
    c = jb.clearance
    rotors = [Rotor(mass=0.5, imbalance=u) for u in (2e-6, 5e-6, 1e-5)]
    x0 = np.array([[1e-6, 0.0], [0.0, 0.2 * c], [0.3 * c, 0.0]])
    batch = simulate_batch(hyb, rotors, 0.02, 1e-4, x0, threads=2, stage_batched=True)
    n_eval, n_fb = hyb.n_evaluations, hyb.n_fallbacks
    total = [0, 0]
    for p in range(3):
        single = simulate(hyb, rotors[p], 0.02, 1e-4, x0[p])
        np.testing.assert_array_equal(batch.trajectory(p).x, single.x)
        assert batch.n_force_evals[p] == single.n_force_evals
        total[0] += hyb.n_evaluations
        total[1] += hyb.n_fallbacks
    assert [n_eval, n_fb] == total and 0 < n_fb < n_eval  # both answers occur
