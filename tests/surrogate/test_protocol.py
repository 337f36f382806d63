"""The paper's training protocol, piece by piece, against independent truth.

- the min-max map sends the data's extremes to -1 and +1 and its inverse gives the forces back;
- the 70/15/15 division has the tool's sizes, disjoint parts covering every row;
- the stopping rule on a synthetic validation curve stops exactly 6 epochs after its minimum;
- Levenberg-Marquardt reaches numpy's least-squares solution of a linear model and
  scipy.optimize.least_squares' solution of a nonlinear one;
- the network's analytical Jacobian equals finite differences, the block-structured J^T J the plain one;
- a paper network trained on a smooth function fits it and stops by the validation rule;
- J^T J accumulated by several threads is bitwise the one-thread sum; a run interrupted mid-way and
  started again from its checkpoint ends with the weights of an uninterrupted run, bitwise
  (the SIGKILL version: tests/faults/test_training_faults.py);
- a min-max map after the physics kinds' division with power 0 is the paper's map.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import least_squares

from fluidfilm.surrogate import protocol as protocol_module
from fluidfilm.surrogate.levenberg_marquardt import (LMSettings, init_nguyen_widrow, levenberg_marquardt,
                                                     mlp_forward, mlp_jacobian, mlp_sse, normal_equations,
                                                     normal_equations_dense)
from fluidfilm.surrogate.protocol import (NetworkData, ValidationStop, divide_random, load_lm_checkpoint,
                                          minmax_scaling, subsample, time_to_accuracy, train_network_adam,
                                          train_network_lm)
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


def test_threads_accumulate_the_normal_equations_bitwise_as_one_thread_does():
    rng = np.random.default_rng(5)
    Z = rng.uniform(-1, 1, (5000, 4))
    Y = rng.uniform(-1, 1, (5000, 2))
    th = init_nguyen_widrow(4, 50, 2, rng)
    one = normal_equations(th, Z, Y, 50, chunk=512, workers=1)
    for w in (2, 3, 8):
        many = normal_equations(th, Z, Y, 50, chunk=512, workers=w)
        for a, b in zip(one, many):
            np.testing.assert_array_equal(a, b)
        assert mlp_sse(th, Z, Y, 50, chunk=700, workers=w) == mlp_sse(th, Z, Y, 50, chunk=700, workers=1)
    # and it is the plain J^T J (independent truth, not only self-consistency)
    dense = normal_equations_dense(th, Z, Y, 50, chunk=1000)
    np.testing.assert_allclose(one[0], dense[0], rtol=1e-10, atol=1e-10 * np.abs(dense[0]).max())
    with pytest.raises(ValueError, match="-1"):
        normal_equations(th, Z, Y, 50, workers=-1)


class _Interrupt(Exception):
    pass


def _die_at_call(monkeypatch, n_call: int):
    """Make the NumPy normal equations raise (as Ctrl-C would) at their ``n_call``-th call, i.e. in the
    middle of that epoch after the previous epoch's checkpoint; returns the real function."""
    calls = {"n": 0}
    real = protocol_module.normal_equations

    def dies(*a, **k):
        calls["n"] += 1
        if calls["n"] == n_call:
            raise _Interrupt
        return real(*a, **k)

    monkeypatch.setattr(protocol_module, "normal_equations", dies)
    return real


def test_an_interrupted_lm_run_resumes_from_its_checkpoint_to_the_uninterrupted_weights(tmp_path, monkeypatch,
                                                                                         capsys):
    data = _toy_data(1500, seed=4)
    whole = train_network_lm(data, n_hidden=10, seed=1, workers=1)
    assert whole["stop_reason"] == "validation" and whole["epochs"] > 12
    # the same run, two threads, stopped (as by Ctrl-C) in the middle of epoch 9 after its checkpoints
    real = _die_at_call(monkeypatch, 9)
    ck = tmp_path / "net.npz"
    with pytest.raises(_Interrupt):
        train_network_lm(data, n_hidden=10, seed=1, workers=2, checkpoint=ck)
    state = load_lm_checkpoint(ck)
    assert state["epoch"] == 8 and state["reason"] is None and len(state["hist"]["val_mse"]) == 8
    monkeypatch.setattr(protocol_module, "normal_equations", real)
    capsys.readouterr()
    resumed = train_network_lm(data, n_hidden=10, seed=1, workers=2, checkpoint=ck, progress_every_s=0.0)
    out = capsys.readouterr().out
    assert "resuming at epoch 8" in out
    for (wa, ba), (wb, bb) in zip(whole["layers"], resumed["layers"]):
        np.testing.assert_array_equal(wa, wb)
        np.testing.assert_array_equal(ba, bb)
    for k in ("epochs", "best_epoch", "stop_reason", "val_mse", "test_mse"):
        assert resumed[k] == whole[k], k
    assert resumed["history"]["val_mse"] == whole["history"]["val_mse"]
    # a progress line per epoch after the resume, the last one saying why it stopped
    lines = [ln for ln in out.splitlines() if ": epoch " in ln]
    assert len(lines) == whole["epochs"] - 8 and lines[-1].endswith("stopped: validation")
    assert "rest: at least" in lines[0]
    # the finished checkpoint: the same call returns the same network without training
    again = train_network_lm(data, n_hidden=10, seed=1, workers=1, checkpoint=ck)
    np.testing.assert_array_equal(again["layers"][0][0], whole["layers"][0][0])
    assert again["epochs"] == whole["epochs"]
    # a checkpoint of other data is not used
    other = train_network_lm(_toy_data(1500, seed=5), n_hidden=10, seed=1, checkpoint=ck)
    assert "belongs to other data" in capsys.readouterr().out
    assert not np.array_equal(other["layers"][0][0], whole["layers"][0][0])


def test_the_torch_normal_equations_equal_the_numpy_ones_and_name_a_bad_device():
    import torch

    from fluidfilm.surrogate.levenberg_marquardt import TorchNormalEquations

    rng = np.random.default_rng(11)
    Z = rng.uniform(-1, 1, (3001, 4))
    Y = rng.uniform(-1, 1, (3001, 2))
    th = init_nguyen_widrow(4, 50, 2, rng)
    want = normal_equations_dense(th, Z, Y, 50, chunk=1000)  # the plain J^T J from the whole Jacobian
    got = TorchNormalEquations(Z, Y, 50, "cpu", chunk=700).normal_equations(th)  # uneven blocks on purpose
    for a, b in zip(got, want):
        np.testing.assert_allclose(a, b, rtol=1e-11, atol=1e-11 * np.abs(b).max())
    assert TorchNormalEquations(Z, Y, 50, "cpu", chunk=999).sse(th) == pytest.approx(mlp_sse(th, Z, Y, 50), rel=1e-12)
    with pytest.raises(ValueError, match="'gpu'"):
        TorchNormalEquations(Z, Y, 50, "gpu")
    if not torch.cuda.is_available():
        with pytest.raises(ValueError, match="'cuda'.*no CUDA device"):
            TorchNormalEquations(Z, Y, 50, "cuda")
    with pytest.raises(ValueError, match="chunk"):
        TorchNormalEquations(Z, Y, 50, "cpu", chunk=0)


def _torch_devices() -> list:
    """torch's CPU, and a CUDA device where torch sees one (the route the full scale takes on a GPU)."""
    import torch

    return ["cpu"] + (["cuda"] if torch.cuda.is_available() else [])


@pytest.mark.parametrize("device", _torch_devices())
def test_lm_on_a_torch_device_takes_the_numpy_paths_steps_and_continues_its_checkpoint(tmp_path, monkeypatch,
                                                                                        device):
    data = _toy_data(1500, seed=4)
    cpu = train_network_lm(data, n_hidden=10, seed=1, workers=1)
    dev = train_network_lm(data, n_hidden=10, seed=1, device=device)
    assert dev["device"] == device and cpu["device"] is None
    for k in ("epochs", "best_epoch", "stop_reason"):
        assert dev[k] == cpu[k], k
    for (wa, ba), (wb, bb) in zip(cpu["layers"], dev["layers"]):
        np.testing.assert_allclose(wb, wa, rtol=1e-7, atol=1e-9)
        np.testing.assert_allclose(bb, ba, rtol=1e-7, atol=1e-9)
    # a NumPy run stopped at epoch 9 continues on the device to the same end
    real = _die_at_call(monkeypatch, 9)
    ck = tmp_path / "net.npz"
    with pytest.raises(_Interrupt):
        train_network_lm(data, n_hidden=10, seed=1, checkpoint=ck)
    monkeypatch.setattr(protocol_module, "normal_equations", real)
    moved = train_network_lm(data, n_hidden=10, seed=1, checkpoint=ck, device=device)
    assert moved["epochs"] == cpu["epochs"] and moved["best_epoch"] == cpu["best_epoch"]
    np.testing.assert_allclose(moved["layers"][0][0], cpu["layers"][0][0], rtol=1e-7, atol=1e-9)


def test_the_recipe_version_still_describes_the_code_that_trains():
    # The records and LM checkpoints of studies.paper_scale (hours of training, committed) are keyed by
    # RECIPE_VERSION, not by the code's bytes. These are the results of this whole run made with the code of
    # 2026-12-04 (commit 4208c0e, the version's value): if the code now ends elsewhere, the weights a cached
    # record stands for are not what this code would train, and RECIPE_VERSION needs a new value (and this
    # test the new numbers).
    res = train_network_lm(_toy_data(1500, seed=4), n_hidden=10, seed=1, workers=1)
    assert (res["epochs"], res["best_epoch"]) == (302, 296)
    assert res["val_mse"] == pytest.approx(2.5582256552756333e-06, rel=1e-6)
    assert res["test_mse"] == pytest.approx(3.0911112339401146e-06, rel=1e-6)
    W1 = res["layers"][0][0]
    assert float(W1.sum()) == pytest.approx(-2.1643408021509445, rel=1e-6)
    assert float(np.abs(W1).sum()) == pytest.approx(15.756477940901302, rel=1e-6)


def test_min_max_map_after_a_constant_force_factor_is_the_papers_map():
    from fluidfilm import paper_bearing

    b = paper_bearing()
    rng = np.random.default_rng(0)
    r = rng.uniform(0, 0.9, 300) * b.clearance
    a = rng.uniform(0, 2 * np.pi, 300)
    X = np.stack([r * np.sin(a), r * np.cos(a)], 1)
    V = rng.uniform(-0.2, 0.2, (300, 2))
    F = rng.uniform(-1e3, 1e3, (300, 2))
    paper = minmax_scaling(X, V, F, b)
    physics = minmax_scaling(X, V, F, b, "physics", power=0.0)
    np.testing.assert_allclose(physics.inputs(X, V), paper.inputs(X, V), atol=1e-12)
    np.testing.assert_allclose(physics.targets(X, V, F), paper.targets(X, V, F), atol=1e-12)
    # every map sends the rows' extremes to -1 and +1, and gives the forces back
    for sc in (paper, physics, minmax_scaling(X, V, F, b, "physics_v", power=0.0),
               minmax_scaling(X, V, F, b, "physics", "whirl", power=0.0)):
        y = sc.targets(X, V, F)
        np.testing.assert_allclose([y.min(axis=0), y.max(axis=0)], [[-1, -1], [1, 1]], atol=1e-12)
        np.testing.assert_allclose(sc.forces(X, V, y), F, rtol=1e-9, atol=1e-9)


def _synthetic_frame(n=1500, seed=0):
    """Rows in the dataset's columns over eps 0-0.9 with a smooth force (not a film: the protocol's plumbing)."""
    import pandas as pd

    from fluidfilm import paper_bearing

    b = paper_bearing()
    rng = np.random.default_rng(seed)
    eps = rng.uniform(0.0, 0.9, n)
    a = rng.uniform(0, 2 * np.pi, n)
    X1, X2 = eps * b.clearance * np.sin(a), eps * b.clearance * np.cos(a)
    V1, V2 = rng.uniform(-0.2, 0.2, (2, n))
    F1 = 100 * np.sin(3 * eps) * np.cos(a) + 50 * V1 / (1 - eps ** 2)
    F2 = -100 * eps ** 2 * np.sin(a) + 50 * V2 / (1 - eps ** 2)
    frame = pd.DataFrame({"X1": X1, "X2": X2, "V1": V1, "V2": V2, "F1": F1, "F2": F2, "eps": eps})
    meta = {"bearing": b.to_dict(), "spec": {"velocity_sections": [{"eps_low": 0.0, "eps_high": 1.0, "v_max": 0.2}]}}
    return frame, meta


def test_a_second_arm_with_another_protocol_for_one_network_resumes_the_others_finished(tmp_path, capsys):
    """The full-scale plan: LM for every network (the last one to a time budget), then the same split with the
    last network by Adam; the LM networks below come back from their checkpoints, not retrained."""
    from fluidfilm.surrogate.protocol import train_protocol_model

    frame, meta = _synthetic_frame()
    proto = {"name": "paper", "max_epochs": 40, "workers": 2, "threads": 1}
    lm, rep_lm = train_protocol_model(frame, meta, proto, [0.5, 0.7], n_hidden=8, checkpoint_dir=tmp_path,
                                      network_protocol={2: {"max_time_s": 1e-9}})
    assert rep_lm["stop_reasons"][2] == "max_time" and not rep_lm["converged"]
    capsys.readouterr()
    adam, rep_adam = train_protocol_model(frame, meta, proto, [0.5, 0.7], n_hidden=8, checkpoint_dir=tmp_path,
                                          network_protocol={"2": {"name": "adam", "max_epochs": 3, "batch_size": 64}})
    out = capsys.readouterr().out
    assert out.count("resuming at epoch") == 2  # networks 0 and 1
    for r in (0, 1):
        a, b = rep_lm["networks"][r], rep_adam["networks"][r]
        assert (a["epochs"], a["stop_reason"], a["val_mse"]) == (b["epochs"], b["stop_reason"], b["val_mse"])
        assert b["train_time_s"] == a["train_time_s"]  # the time it took, not the second call's (a checkpoint read)
        np.testing.assert_array_equal(lm.networks[r][0][0], adam.networks[r][0][0])
    assert rep_adam["networks"][2]["protocol"] == "adam" and rep_adam["networks"][2]["epochs"] <= 3
    with pytest.raises(ValueError, match="'sgd'"):
        train_protocol_model(frame, meta, proto, [0.5, 0.7], n_hidden=8, network_protocol={0: {"name": "sgd"}})
