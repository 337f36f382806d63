"""The paper's training protocol, piece by piece, against independent truth.

- the min-max map sends the data's extremes to -1 and +1 and its inverse gives the forces back;
- the 70/15/15 division has the tool's sizes, disjoint parts covering every row;
- the stopping rule on a synthetic validation curve stops exactly 6 epochs after its minimum;
- Levenberg-Marquardt reaches numpy's least-squares solution of a linear model and
  scipy.optimize.least_squares' solution of a nonlinear one;
- the network's analytical Jacobian equals finite differences, the block-structured J^T J the plain one;
- a paper network trained on a smooth function fits it and stops by the validation rule.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import least_squares

from fluidfilm.surrogate.levenberg_marquardt import (LMSettings, init_nguyen_widrow, levenberg_marquardt,
                                                     mlp_forward, mlp_jacobian, normal_equations,
                                                     normal_equations_dense)
from fluidfilm.surrogate.protocol import (NetworkData, ValidationStop, divide_random, subsample,
                                          time_to_accuracy, train_network_adam, train_network_lm)
from fluidfilm.surrogate.scaling import Scaling


def test_minmax_map_sends_extremes_to_minus_one_and_one_and_inverts():
    rng = np.random.default_rng(3)
    X = rng.uniform(-2e-4, 3e-4, (500, 2))
    V = rng.uniform(-0.5, 0.2, (500, 2))
    F = rng.uniform(-5e4, 7e5, (500, 2))
    s = Scaling.fit("minmax", X, V, F, 3e-4, 300.0, 1.0, power=0.0)
    z = s.inputs(X, V)
    y = s.targets(X, V, F)
    raw = np.concatenate([X, V], axis=1)
    for a, m in ((z, raw), (y, F)):
        np.testing.assert_allclose(a.min(axis=0), -1.0, atol=1e-12)
        np.testing.assert_allclose(a.max(axis=0), 1.0, atol=1e-12)
        # the row holding a column's minimum maps to exactly -1
        np.testing.assert_allclose(a[m.argmin(axis=0), np.arange(m.shape[1])], -1.0, atol=1e-12)
    np.testing.assert_allclose(s.forces(X, V, y), F, rtol=1e-12, atol=1e-9)
    # the map is affine: the midpoint of the range goes to 0
    mid = 0.5 * (F.min(axis=0) + F.max(axis=0))
    np.testing.assert_allclose(s.targets(X[:1], V[:1], mid[None, :]), 0.0, atol=1e-12)
    # saved and loaded: same map
    s2 = Scaling.from_dict(s.to_dict())
    np.testing.assert_allclose(s2.inputs(X, V), z)


@pytest.mark.parametrize("n", [3, 20, 1001, 100_000])
def test_division_has_the_tools_sizes_and_disjoint_parts(n):
    d = divide_random(n, (0.70, 0.15, 0.15), seed=1)
    assert len(d.val) == round(0.15 * n) and len(d.test) == round(0.15 * n)
    assert len(d.train) + len(d.val) + len(d.test) == n
    allrows = np.concatenate([d.train, d.val, d.test])
    assert len(np.unique(allrows)) == n and allrows.min() == 0 and allrows.max() == n - 1
    if n >= 1000:  # random, not a block: the validation rows spread over the whole table
        assert d.val.min() < 0.05 * n and d.val.max() > 0.95 * n
    d2 = divide_random(n, seed=2)
    if n >= 20:
        assert not np.array_equal(d.val, d2.val)


def test_division_rejects_bad_shares():
    with pytest.raises(ValueError, match="fractions"):
        divide_random(100, (0.7, 0.2, 0.2))
    with pytest.raises(ValueError, match="cannot divide"):
        divide_random(2)


def test_subsample_is_without_replacement():
    rows = subsample(1000, 300, seed=4)
    assert len(np.unique(rows)) == 300 and rows.max() < 1000
    assert np.array_equal(subsample(50, None, 0), np.arange(50))


def test_stopping_rule_on_a_synthetic_validation_curve():
    # falls to a minimum at epoch 10, then noisy but never below it
    curve = [1.0 / (1 + e) if e <= 10 else 1 / 11 + 0.01 * (1 + math.sin(e)) for e in range(0, 40)]
    curve[13] = 1 / 11  # equal to the best: not an improvement
    stop = ValidationStop(6)
    fired = None
    for e, v in enumerate(curve):
        r = stop.update(e, v, np.array([e]))
        if r:
            fired = (e, r)
            break
    assert fired == (16, "validation")
    assert stop.best_epoch == 10 and stop.best_weights[0] == 10
    # an improvement resets the count
    stop = ValidationStop(3)
    seq = [5, 4, 4.5, 4.6, 3.9, 4.0, 4.1, 4.2]
    out = [stop.update(e, v) for e, v in enumerate(seq)]
    assert out.index("validation") == 7 and stop.best_epoch == 4
    assert ValidationStop(6).update(0, float("nan")) == "non_finite"
    with pytest.raises(ValueError, match="max_fail"):
        ValidationStop(0)


def test_levenberg_marquardt_reaches_the_linear_least_squares_solution():
    rng = np.random.default_rng(0)
    A = rng.standard_normal((200, 6))
    b = A @ rng.standard_normal(6) + 0.1 * rng.standard_normal(200)
    exact = np.linalg.lstsq(A, b, rcond=None)[0]

    def ne(t):
        e = A @ t - b
        return A.T @ A, A.T @ e, float(e @ e)

    res = levenberg_marquardt(np.zeros(6), ne, lambda t: float(((A @ t - b) ** 2).sum()), 200,
                              LMSettings(max_epochs=100, min_grad=1e-12))
    np.testing.assert_allclose(res.theta, exact, rtol=1e-8, atol=1e-10)
    assert res.stop_reason in ("min_grad", "mu_max")


def test_levenberg_marquardt_matches_scipy_on_a_nonlinear_fit():
    rng = np.random.default_rng(1)
    t = np.linspace(0, 4, 80)
    y = 2.5 * np.exp(-1.3 * t) + 0.4 * np.sin(2.0 * t) + 0.01 * rng.standard_normal(80)

    def resid(p):
        return p[0] * np.exp(-p[1] * t) + p[2] * np.sin(p[3] * t) - y

    def jac(p):
        return np.stack([np.exp(-p[1] * t), -p[0] * t * np.exp(-p[1] * t), np.sin(p[3] * t),
                         p[2] * t * np.cos(p[3] * t)], axis=1)

    def ne(p):
        J, e = jac(p), resid(p)
        return J.T @ J, J.T @ e, float(e @ e)

    p0 = np.array([1.0, 1.0, 0.2, 1.8])
    ref = least_squares(resid, p0, jac=jac, method="lm", xtol=1e-14, ftol=1e-14, gtol=1e-14)
    res = levenberg_marquardt(p0, ne, lambda p: float((resid(p) ** 2).sum()), 80,
                              LMSettings(max_epochs=500, min_grad=1e-13))
    np.testing.assert_allclose(res.theta, ref.x, rtol=1e-6)
    assert res.sse == pytest.approx(2 * ref.cost, rel=1e-9)


def test_network_jacobian_equals_finite_differences_and_block_normal_equations_the_plain_ones():
    rng = np.random.default_rng(2)
    th = init_nguyen_widrow(4, 7, 2, rng)
    Z = rng.uniform(-1, 1, (9, 4))
    _, H = mlp_forward(th, Z, 7)
    J = mlp_jacobian(th, Z, H)
    fd = np.empty_like(J)
    for p in range(th.size):
        d = np.zeros_like(th)
        d[p] = 1e-6
        fd[:, p] = ((mlp_forward(th + d, Z, 7)[0] - mlp_forward(th - d, Z, 7)[0]) / 2e-6).ravel()
    np.testing.assert_allclose(J, fd, atol=1e-8)
    Z = rng.uniform(-1, 1, (1000, 4))
    Y = rng.uniform(-1, 1, (1000, 2))
    th = init_nguyen_widrow(4, 50, 2, rng)
    a = normal_equations(th, Z, Y, 50, chunk=300)  # uneven chunks on purpose
    b = normal_equations_dense(th, Z, Y, 50, chunk=1000)
    for x, y in zip(a, b):
        np.testing.assert_allclose(x, y, rtol=1e-10, atol=1e-10 * np.abs(y).max())


def _toy_data(n=1000, seed=0):
    """A smooth two-output function of four inputs in [-1, 1], divided 70/15/15."""
    rng = np.random.default_rng(seed)
    z = rng.uniform(-1, 1, (n, 4))
    y = np.stack([np.sin(1.5 * z[:, 0]) * z[:, 2] + 0.3 * z[:, 1], np.tanh(z[:, 1] + z[:, 3]) - 0.5 * z[:, 0] ** 2],
                 axis=1) + 0.001 * rng.standard_normal((n, 2))
    d = divide_random(n, seed=seed)
    sc = Scaling("minmax", 1.0, 1.0, 1.0, 0.0, np.zeros(4), np.ones(4), np.zeros(2), np.ones(2))
    parts = {"train": d.train, "val": d.val, "test": d.test}
    return NetworkData(sc, {k: z[v] for k, v in parts.items()}, {k: y[v] for k, v in parts.items()},
                       {k: y[v] for k, v in parts.items()})


def test_paper_network_fits_a_smooth_function_and_stops_by_validation():
    data = _toy_data()
    res = train_network_lm(data, n_hidden=12, seed=0)
    assert res["stop_reason"] == "validation" and res["converged"]
    assert res["epochs"] == res["best_epoch"] + 6
    # noise is 0.001: a converged fit is close to it on unseen rows
    assert res["test_mse"] < 1e-4
    assert res["val_mse"] == pytest.approx(min(res["history"]["val_mse"]))
    # the same data with Adam: stops by the same rule, worse in as many epochs
    adam = train_network_adam(data, n_hidden=12, seed=0, max_epochs=100, batch_size=128)
    assert adam["stop_reason"] in ("validation", "max_epochs")
    assert adam["test_mse"] < 0.05


def test_adam_progress_lines_say_the_epoch_and_the_best_epoch_and_none_means_silent(capsys):
    data = _toy_data(400)
    res = train_network_adam(data, n_hidden=8, seed=0, max_epochs=30, batch_size=128, progress_every_s=0.0)
    lines = [ln for ln in capsys.readouterr().out.splitlines() if "adam: epoch" in ln]
    assert len(lines) == res["epochs"]  # a zero interval: a line after every epoch
    assert lines[-1].startswith(f"    adam: epoch {res['epochs']},") and f"at epoch {res['best_epoch']};" in lines[-1]
    train_network_adam(data, n_hidden=8, seed=0, max_epochs=3, batch_size=128, progress_every_s=None)
    assert "adam: epoch" not in capsys.readouterr().out


def test_time_to_accuracy_takes_the_first_epoch_at_the_target():
    rep = {"networks": [{"history": {"wall_s": [1.0, 2.0, 3.0], "val_sq_N2": [9.0, 4.0, 1.0]}},
                        {"history": {"wall_s": [0.5, 1.0], "val_sq_N2": [3.0, 2.0]}}]}
    assert time_to_accuracy(rep, [4.0, 3.0]) == pytest.approx(2.0 + 0.5)
    assert time_to_accuracy(rep, [0.5, 3.0]) is None
