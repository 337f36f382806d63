"""Surrogates: accuracy on the quick profile, one interface (Lightning = loaded = compiled), routing, domain."""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
import torch

from fluidfilm import Rotor, load_surrogate, paper_bearing, simulate
from fluidfilm.surrogate import Scaling, SurrogateForceModel
from fluidfilm.surrogate.fit import fit_surrogate, regions, held_out_errors
from fluidfilm.surrogate.inference import surrogate_force
from fluidfilm.surrogate.kernels import compiled_kernel, shape_key

C = 120e-6
TINY = dict(width=32, depth=2, activation="tanh", lr=1e-2, optimizer="adam", scheduler="cosine")
QUICK = dict(max_epochs=150, progress_bar=False)


@pytest.fixture(scope="module")
def trained(quick_data):
    dataset, _ = quick_data
    return fit_surrogate(dataset, TINY, {"boundaries": []}, {"kind": "physics", "power": 1.5}, QUICK, target=None,
                         seed=1, batch_size=128, val_fraction=0.2)


def _random_states(n, eps_max, v_max, seed):
    """n journal states: eps uniform below eps_max, any angle, velocities uniform in +-v_max."""
    rng = np.random.default_rng(seed)
    eps, ang = eps_max * rng.random(n), 2 * np.pi * rng.random(n)
    X = C * np.stack([eps * np.sin(ang), eps * np.cos(ang)], axis=1)
    return X, rng.uniform(-v_max, v_max, (n, 2)), eps


def _load_into(seq, layers):
    """Copy saved (W, b) layers into the Linear layers of a torch Sequential."""
    for lin, (W, b) in zip([m for m in seq if isinstance(m, torch.nn.Linear)], layers):
        lin.weight.data, lin.bias.data = torch.as_tensor(W), torch.as_tensor(b)


def test_small_network_beats_the_error_bound_on_the_quick_test_set(trained, quick_data):
    """Bound from real runs (median 0.15-0.21 over seeds, 150 epochs), with margin."""
    model, report = trained
    err = held_out_errors(model, quick_data[1])
    assert err["test_rel_err_median"] < 0.35
    assert report["networks"][0]["val_rel_rmse"] < 0.25


def test_loaded_model_equals_the_lightning_module_and_the_compiled_kernel(trained, quick_data, tmp_path):
    model, _ = trained
    model.save(tmp_path / "m")
    loaded = load_surrogate(tmp_path / "m")
    X, V, eps = _random_states(50, 0.85, 0.2, seed=0)
    F_loaded = loaded.forces(X, V)
    np.testing.assert_array_equal(F_loaded, model.forces(X, V))
    # the Lightning module: rebuild it from the saved layers and run it in torch (double precision)
    from fluidfilm.surrogate.training import ForceMLP

    scaling = loaded.scalings[0]
    module = ForceMLP(width=32, depth=2, activation="tanh").double()
    _load_into(module.net, loaded.networks[0])
    with torch.no_grad():
        y = module(torch.as_tensor(scaling.inputs(X, V))).numpy()
    np.testing.assert_allclose(F_loaded, scaling.forces(X, V, y), rtol=1e-9, atol=1e-9)
    kernel, params = loaded.force_kernel
    F_kernel = np.array([kernel(params, *x, *v) for x, v in zip(X, V)])
    np.testing.assert_allclose(F_kernel, F_loaded, rtol=1e-12)


def _constant_net(value: float):
    """A network whose output is the constant (value, -value): zero weights, biases carry it."""
    return [(np.zeros((4, 4)), np.zeros(4)), (np.zeros((2, 4)), np.array([value, -value]))]


def _identity_scaling():
    return Scaling("standard", C, 314.0, 1.0, 0.0, np.zeros(4), np.ones(4), np.zeros(2), np.ones(2))


def test_split_routing_sends_each_band_to_its_network():
    b = paper_bearing()
    m = SurrogateForceModel(b, [_constant_net(k) for k in range(3)], [_identity_scaling()] * 3, "relu",
                            boundaries=[0.5, 0.7])
    # (exactly at a boundary, |X|/c may round to either side: test just off it)
    for eps, k in [(0.0, 0), (0.3, 0), (0.4999, 0), (0.5001, 1), (0.65, 1), (0.7001, 2), (0.95, 2)]:
        F = m.forces([0.0, eps * C], [0.0, 0.0])
        assert F[0] == pytest.approx(k), eps


def test_blending_makes_the_force_continuous_across_a_boundary():
    b = paper_bearing()
    hard = SurrogateForceModel(b, [_constant_net(k) for k in range(3)], [_identity_scaling()] * 3, "relu",
                               boundaries=[0.5, 0.7])
    soft = SurrogateForceModel(b, [_constant_net(k) for k in range(3)], [_identity_scaling()] * 3, "relu",
                               boundaries=[0.5, 0.7], blend_width=0.04)
    eps = np.linspace(0.45, 0.55, 1001)
    X = np.stack([np.zeros_like(eps), eps * C], axis=1)
    jump_hard = np.abs(np.diff(hard.forces(X, np.zeros_like(X))[:, 0])).max()
    jump_soft = np.abs(np.diff(soft.forces(X, np.zeros_like(X))[:, 0])).max()
    assert jump_hard == pytest.approx(1.0)
    assert jump_soft < 0.01
    F = soft.forces(X, np.zeros_like(X))[:, 0]
    assert F[0] == 0.0 and F[-1] == 1.0 and np.all(np.diff(F) >= 0)
    np.testing.assert_allclose(regions([0.5, 0.7], 0.04), [(0.0, 0.52), (0.48, 0.72), (0.68, math.inf)])


def test_outside_the_training_domain_warns_every_call_and_the_trajectory_counts_it(trained):
    model, _ = trained
    for _ in range(2):  # not once per process: every call that leaves the domain says so
        with pytest.warns(RuntimeWarning, match="1 of 1 states lie outside the training domain"):
            model.forces([0.0, 0.99 * C], [0.0, 0.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model.forces([0.0, 0.5 * C], [0.0, 0.0])  # inside: silent
    with pytest.warns(RuntimeWarning):
        traj = simulate(model, Rotor(mass=2.5), t_end=0.01, x0=[0.0, 0.3 * C], v0=[0.0, 5.0])
    assert "outside the training domain" in traj.status
    assert traj.n_outside_domain > 0 and f"in {traj.n_outside_domain} force evaluations" in traj.status


def test_surrogate_runs_in_the_compiled_integrator(trained):
    model, _ = trained
    traj = simulate(model, Rotor(mass=2.5, imbalance=1e-4), t_end=0.05, record_every=10)
    assert traj.ok and np.isfinite(traj.x).all()
    # the integrator runs the kernel compiled for the model's shape, not the generic one
    assert model.force_kernel[0] is compiled_kernel(shape_key(model))
    assert model.force_kernel[0] is not surrogate_force


def test_training_resumes_from_its_checkpoint(quick_data, tmp_path):
    dataset, _ = quick_data
    kw = dict(seed=0, batch_size=128, val_fraction=0.2, ckpt_root=tmp_path / "ckpt", target=None)
    _, first = fit_surrogate(dataset, TINY, {"boundaries": []}, {"kind": "physics"}, dict(max_epochs=3,
                             progress_bar=False), **kw)
    assert (tmp_path / "ckpt" / "region0" / "last.ckpt").exists()
    _, second = fit_surrogate(dataset, TINY, {"boundaries": []}, {"kind": "physics"}, dict(max_epochs=5,
                              progress_bar=False), **kw)
    assert first["networks"][0]["epochs"] == 3 and second["networks"][0]["epochs"] == 5
    # the clock carries over: the resumed run's total includes the first three epochs
    assert second["train_time_s"] > first["train_time_s"]


def test_split_networks_trained_side_by_side_equal_those_trained_one_after_the_other(quick_data):
    """Each network of a split model trains with one torch thread wherever it runs, so training them in
    worker processes (``workers=2``) gives bit for bit the weights of training them in turn here."""
    dataset, _ = quick_data
    kw = dict(seed=3, batch_size=128, val_fraction=0.2, target=None)
    split, trainer = {"boundaries": [0.4, 0.7]}, dict(max_epochs=3, progress_bar=False)
    threads = torch.get_num_threads()
    m1, r1 = fit_surrogate(dataset, TINY, split, {"kind": "physics"}, trainer, workers=1, **kw)
    assert torch.get_num_threads() == threads  # the one-thread rule does not leak into the caller
    m2, r2 = fit_surrogate(dataset, TINY, split, {"kind": "physics"}, trainer, workers=2, **kw)
    assert (r1["workers"], r2["workers"]) == (1, 2)
    for a, b in zip(m1.networks, m2.networks, strict=True):
        for (wa, ba), (wb, bb) in zip(a, b, strict=True):
            np.testing.assert_array_equal(wa, wb)
            np.testing.assert_array_equal(ba, bb)
    assert [n["n_train"] for n in r1["networks"]] == [n["n_train"] for n in r2["networks"]]
    assert [n["eps_low"] for n in r2["networks"]] == [lo for lo, _ in regions([0.4, 0.7])]


def test_checkpoint_name_ignores_the_worker_count():
    from fluidfilm.surrogate.fit import training_digest

    parts = (TINY, {"boundaries": [0.5]}, {"kind": "physics"})
    assert training_digest(*parts, QUICK | {"workers": 1}, 0) == training_digest(*parts, QUICK | {"workers": 8}, 0)
    assert training_digest(*parts, QUICK | {"workers": 1}, 0) != training_digest(*parts, QUICK | {"max_epochs": 9}, 0)


@pytest.mark.parametrize("workers", [0, -1])
def test_bad_worker_count_is_named(quick_data, workers):
    with pytest.raises(ValueError, match=f"workers must be >= 1 or null.*{workers}"):
        fit_surrogate(quick_data[0], TINY, {"boundaries": [0.5]}, {"kind": "physics"}, QUICK, None, workers=workers)


@pytest.mark.parametrize("kwargs, match", [
    (dict(boundaries=[0.7, 0.5]), "boundaries must increase"),
    (dict(boundaries=[0.5, 0.7], blend_width=0.3), "blend_width"),
    (dict(activation="swish"), "unknown activation"),
])
def test_bad_surrogate_settings_raise(kwargs, match):
    nets = [_constant_net(k) for k in range(3)]
    args = dict(boundaries=[0.5, 0.7], blend_width=0.0, activation="relu") | kwargs
    with pytest.raises(ValueError, match=match):
        SurrogateForceModel(paper_bearing(), nets, [_identity_scaling()] * 3, args["activation"],
                            boundaries=args["boundaries"], blend_width=args["blend_width"])


def test_damping_structure_equals_its_module_and_rests_on_the_static_network(quick_data, tmp_path):
    """F = S(X) + C(X, V) v: the loaded kernel equals the torch module, and at V = 0 only S acts."""
    from fluidfilm.surrogate.training import ForceMLP

    dataset, _ = quick_data
    model_cfg = dict(TINY, width=8, structure="damping")
    model, _ = fit_surrogate(dataset, model_cfg, {"boundaries": []}, {"kind": "physics", "power": 1.5},
                             dict(max_epochs=2, progress_bar=False), target=None, seed=0, batch_size=128)
    model.save(tmp_path / "d")
    loaded = load_surrogate(tmp_path / "d")
    assert loaded.structure == "damping"
    sc = loaded.scalings[0]
    module = ForceMLP(width=8, depth=2, activation="tanh", structure="damping", v_mean=list(sc.in_mean[2:]),
                      v_std=list(sc.in_std[2:])).double()
    static, damping = loaded.networks[0]
    _load_into(module.static, static)
    _load_into(module.damping, damping)
    X, V, eps = _random_states(20, 0.8, 0.05, seed=1)
    with torch.no_grad():
        y = module(torch.as_tensor(sc.inputs(X, V))).numpy()
        y_rest = module.static(torch.as_tensor(sc.inputs(X, 0 * V))[:, :2]).numpy()
    # (the module keeps its velocity scaling in float32 buffers: agreement to ~1e-8)
    np.testing.assert_allclose(loaded.forces(X, V), sc.forces(X, V, y), rtol=1e-6)
    np.testing.assert_allclose(loaded.forces(X, 0 * V), sc.forces(X, 0 * V, y_rest), rtol=1e-12)


def test_polar_frame_makes_the_surrogate_exactly_rotation_equivariant(quick_data, tmp_path):
    """Learning in the journal's frame: F(R X, R V) = R F(X, V) for any rotation, to rounding."""
    from fluidfilm.surrogate.training import ForceMLP

    dataset, _ = quick_data
    model, _ = fit_surrogate(dataset, dict(TINY, width=8), {"boundaries": [0.5]},
                             {"kind": "physics", "power": 1.5, "frame": "polar"},
                             dict(max_epochs=2, progress_bar=False), target=None, seed=0, batch_size=128)
    model.save(tmp_path / "p")
    loaded = load_surrogate(tmp_path / "p")
    X, V, eps = _random_states(30, 0.9, 0.05, seed=2)
    F = loaded.forces(X, V)
    for a in (0.3, 2.0, -1.1):
        R = np.array([[np.cos(a), np.sin(a)], [-np.sin(a), np.cos(a)]])
        np.testing.assert_allclose(loaded.forces(X @ R.T, V @ R.T), F @ R.T, rtol=1e-9, atol=1e-9 * np.abs(F).max())
    # and the compiled kernel equals the torch module in that frame
    sc = loaded.scalings[0]
    rows = eps < 0.5
    module = ForceMLP(width=8, depth=2, activation="tanh", n_inputs=3).double()
    _load_into(module.net, loaded.networks[0])
    with torch.no_grad():
        y = module(torch.as_tensor(sc.inputs(X[rows], V[rows]))).numpy()
    np.testing.assert_allclose(F[rows], sc.forces(X[rows], V[rows], y), rtol=1e-9, atol=1e-9)


def test_training_layers_equal_torchs_own_in_value_and_gradient():
    """The training network's tanh (2 sigmoid(2x) - 1) and first layer (weight gradient as (x^T g)^T) are
    torch's nn.Tanh and nn.Linear to float32 round-off, values and every gradient, checked in float64
    against torch's own layers (a second method) on random inputs spanning the saturated tails."""
    from fluidfilm.surrogate.training import NarrowInputLinear, Tanh, _mlp

    torch.manual_seed(0)
    x = torch.cat([torch.linspace(-12.0, 12.0, 2001), 1e-3 * torch.randn(500)])
    for dtype, tol in ((torch.float32, 2e-7), (torch.float64, 4e-16)):
        xd = x.to(dtype).requires_grad_()
        y = Tanh()(xd)
        assert torch.max(torch.abs(y - torch.tanh(xd.detach()))) <= tol
        (g,) = torch.autograd.grad(y.sum(), xd)
        xt = x.to(dtype).requires_grad_()
        (g_torch,) = torch.autograd.grad(torch.tanh(xt).sum(), xt)  # autograd through torch's own tanh
        assert torch.max(torch.abs(g - g_torch)) <= 2 * tol
    # a whole network: the workspace's layers vs torch's stock ones with the same weights, float64
    net = _mlp(4, 2, 16, 2, "tanh").double()
    assert isinstance(net[0], NarrowInputLinear) and not isinstance(net[2], NarrowInputLinear)
    stock = torch.nn.Sequential(torch.nn.Linear(4, 16), torch.nn.Tanh(), torch.nn.Linear(16, 16), torch.nn.Tanh(),
                                torch.nn.Linear(16, 2)).double()
    stock.load_state_dict(net.state_dict())  # same parameter names: checkpoints load either way
    z = torch.randn(300, 4, dtype=torch.float64, requires_grad=True)
    out, out_stock = net(z), stock(z)
    assert torch.allclose(out, out_stock, rtol=0, atol=1e-14)
    w = torch.randn(300, 2, dtype=torch.float64)
    grads = torch.autograd.grad((out * w).sum(), [z, *net.parameters()])
    grads_stock = torch.autograd.grad((out_stock * w).sum(), [z, *stock.parameters()])
    for a, b in zip(grads, grads_stock):
        assert a.shape == b.shape and torch.allclose(a, b, rtol=1e-12, atol=1e-13)
