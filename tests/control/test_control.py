"""The active bearing's data, surrogate and controllers.

- the sleeve dataset holds the reference forces at each sleeve position, on grids relative to c_r(s);
- the surrogate with a sleeve input: compiled kernel == torch module on the saved layers;
- the gymnasium environment passes gymnasium's checker, and with a constant action its trajectory
  is ``simulate``'s with the same force model and imbalance ramp;
- a short DQN run (stable-baselines3) completes, saves a policy that loads and acts the same;
- MPC with a perfect model (the reference) does no worse than no control;
- the imbalance ramp of the rotor model.
"""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import torch
import yaml
from gymnasium.utils.env_checker import check_env

from fluidfilm import GradedReynoldsModel, Rotor, load_surrogate, simulate
from fluidfilm.core.bearing import bearing_from_dict
from fluidfilm.control import ActiveBearingEnv, ConstantSleeve, DQNController, ModelPredictiveController, run_episode
from fluidfilm.control.build import env_from_cfg
from fluidfilm.control.dqn import load_agent, save_agent, train_dqn
from fluidfilm.data import DatasetSpec, generate_dataset, random_test_set
from fluidfilm.surrogate.fit import fit_surrogate, held_out_errors

from conftest import ROOT

REFERENCE = {"coarse": [30, 30], "dense": [55, 55], "eps_threshold": 0.9, "cavitation": "gumbel"}


def _yaml(*parts):
    return yaml.safe_load((ROOT.joinpath("conf", *parts)).read_text())


@pytest.fixture(scope="module")
def conical():
    return bearing_from_dict(_yaml("bearing", "conical.yaml"))


@pytest.fixture(scope="module")
def reference(conical):
    return GradedReynoldsModel(conical, **{k: tuple(v) if isinstance(v, list) else v for k, v in REFERENCE.items()})


@pytest.fixture(scope="module")
def controller_cfg():
    quick = _yaml("controller", "quick.yaml")
    cfg = _yaml("controller", "default.yaml")
    for key in ("scenario", "dqn"):
        cfg[key].update(quick[key])
    return cfg


@pytest.fixture(scope="module")
def rotor_cfg():
    return _yaml("rotor", "paper.yaml")


@pytest.fixture(scope="module")
def active_data(conical, tmp_path_factory):
    spec = DatasetSpec.from_cfg(_yaml("dataset", "active_quick.yaml"))
    out = tmp_path_factory.mktemp("active")
    meta = generate_dataset(conical, REFERENCE, spec, out / "dataset", scheduler="inline", progress=False)
    random_test_set(conical, REFERENCE, spec, out / "testset")
    return out / "dataset", out / "testset", spec, meta


@pytest.fixture(scope="module")
def active_surrogate(active_data):
    model_cfg = {"width": 32, "depth": 2, "activation": "tanh", "optimizer": "adam", "lr": 3e-3,
                 "weight_decay": 0.0, "scheduler": "cosine"}
    trainer = {"max_epochs": 30, "max_time": None, "accelerator": "cpu", "progress_bar": False}
    model, _ = fit_surrogate(active_data[0], model_cfg, {"boundaries": []},
                             {"kind": "physics", "power": 1.5, "frame": "polar"}, trainer, None, batch_size=256,
                             val_fraction=0.2, name="active_test")
    return model


def test_sleeve_dataset_holds_the_reference_force_at_each_sleeve_position(active_data, reference, conical):
    ds, _, spec, meta = active_data
    df = pd.read_parquet(ds)
    assert meta["n_samples"] == len(df) == spec.n_samples(conical.clearance)
    assert sorted(df["S"].unique()) == list(spec.sleeve_positions)
    rng = np.random.default_rng(0)
    rows = df.iloc[rng.choice(len(df), 40, replace=False)]
    for s, grp in rows.groupby("S"):
        reference.set_sleeve(s)
        X, V = grp[["X1", "X2"]].to_numpy(), grp[["V1", "V2"]].to_numpy()
        # each row on the grid the dataset records: the nominal eccentricity decides it, and a row on a
        # section boundary (eps = 0.9 exactly) can have |X|/c a hair below it, which `forces` would
        # put on the other grid
        dense = (grp["n_theta"] == reference.dense.n_theta).to_numpy()
        F = np.where(dense[:, None], reference.dense.forces(X, V), reference.coarse.forces(X, V))
        np.testing.assert_allclose(F, grp[["F1", "F2"]].to_numpy(), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(grp["eps"] >= reference.eps_threshold, dense)
        # the eccentricity grid is relative to the clearance at that sleeve position
        np.testing.assert_allclose(np.hypot(X[:, 0], X[:, 1]) / conical.clearance_at(s), grp["eps"], atol=1e-12)
    reference.set_sleeve(0.0)


def test_sleeve_surrogate_kernel_equals_the_torch_network_and_learns_the_sleeve(active_surrogate, active_data,
                                                                                   tmp_path):
    from fluidfilm.surrogate.training import ForceMLP

    active_surrogate.save(tmp_path / "m")
    model = load_surrogate(tmp_path / "m")
    sc = model.scalings[0]
    assert sc.extras == ("S",) and sc.n_inputs == 4
    rng = np.random.default_rng(1)
    X = 40e-6 * (rng.random((20, 2)) - 0.5)
    V = 0.02 * (rng.random((20, 2)) - 0.5)
    module = ForceMLP(width=32, depth=2, activation="tanh", n_inputs=4).double()
    for seq_layer, (W, b) in zip([m for m in module.net if isinstance(m, torch.nn.Linear)], model.networks[0]):
        seq_layer.weight.data, seq_layer.bias.data = torch.as_tensor(W), torch.as_tensor(b)
    for s in (-0.8e-3, 0.3e-3):
        model.set_sleeve(s)
        E = np.full((20, 1), s)
        with torch.no_grad():
            y = module(torch.as_tensor(sc.inputs(X, V, E))).numpy()
        np.testing.assert_allclose(model.forces(X, V), sc.forces(X, V, y, E), rtol=1e-9, atol=1e-9)
    # it has learnt the sleeve: a closed sleeve carries more load at the same displacement (the reference's trend)
    x = np.array([[0.0, 40e-6]])
    model.set_sleeve(-0.8e-3)
    f_closed = np.linalg.norm(model.forces(x, np.zeros((1, 2))))
    model.set_sleeve(0.8e-3)
    f_open = np.linalg.norm(model.forces(x, np.zeros((1, 2))))
    assert f_closed > 1.5 * f_open
    err = held_out_errors(model, active_data[1])
    assert err["test_rel_err_median"] < 0.2  # a 30-epoch network on 20k samples: a smoke bound


def test_environment_follows_the_gymnasium_api(reference, rotor_cfg, controller_cfg):
    env = env_from_cfg(reference, rotor_cfg, controller_cfg)
    check_env(env, skip_render_check=True)


@pytest.mark.parametrize("action", [0, 3])
def test_constant_action_trajectory_equals_simulate(reference, rotor_cfg, controller_cfg, action):
    env = env_from_cfg(reference, rotor_cfg, controller_cfg)
    env.reset()
    x0, v0 = env.x.copy(), env.v.copy()
    xs = [x0[None, :]]
    done = False
    while not done:
        _, _, term, trunc, _ = env.step(action)
        xs.append(env.last_trajectory.x[1:])
        done = term or trunc
    x_env = np.concatenate(xs)
    reference.set_sleeve(env.sleeve_positions[action])
    sc = env.scenario
    tr = simulate(reference, env.ramp_rotor(), sc.t_end, sc.dt, x0=x0, v0=v0, eps_stop=sc.eps_stop,
                  record_every=sc.record_every)
    assert tr.ok and len(tr.x) == len(x_env)
    np.testing.assert_allclose(x_env, tr.x, rtol=0, atol=1e-9 * env.c0)
    reference.set_sleeve(0.0)


def test_short_dqn_run_saves_a_policy_that_loads(active_surrogate, rotor_cfg, controller_cfg, tmp_path):
    env = env_from_cfg(active_surrogate, rotor_cfg, controller_cfg)
    agent, returns = train_dqn(env, controller_cfg["dqn"], seed=0)
    assert len(returns) >= 2 and all(np.isfinite(r) for _, r in returns)
    path = save_agent(agent, tmp_path / "dqn.zip")
    loaded = load_agent(path)
    obs = np.random.default_rng(0).normal(size=(10, 7)).astype(np.float32)
    a1 = [DQNController(agent)(o, env) for o in obs]
    a2 = [DQNController(loaded)(o, env) for o in obs]
    assert a1 == a2 and all(0 <= a < env.action_space.n for a in a1)
    res = run_episode(env, DQNController(loaded))
    assert res["n_decisions"] == env.scenario.n_decisions or res["contact"]


def test_mpc_with_a_perfect_model_does_no_worse_than_no_control(conical, reference, rotor_cfg, controller_cfg):
    env = env_from_cfg(reference, rotor_cfg, controller_cfg)
    none = run_episode(env, ConstantSleeve(env.initial_action))
    perfect = GradedReynoldsModel(conical)
    mpc = run_episode(env, ModelPredictiveController(perfect, horizon_intervals=1))
    assert mpc["return"] >= none["return"] - 1e-9
    assert not mpc["contact"]
    # and it acts: the growing imbalance makes it move the sleeve away from the nominal position
    assert mpc["sleeve_travel_m"] > 0


def test_imbalance_ramp():
    r = Rotor(mass=2.0, imbalance=1e-4, imbalance_final=5e-4, ramp_time=2.0)
    assert r.imbalance_at(-1) == 1e-4 and r.imbalance_at(1.0) == pytest.approx(3e-4) and r.imbalance_at(9) == 5e-4
    with pytest.raises(ValueError, match="ramp_time"):
        Rotor(mass=2.0, imbalance=1e-4, imbalance_final=5e-4)
    with pytest.raises(ValueError, match="imbalance_final"):
        Rotor(mass=2.0, imbalance=1e-4, imbalance_final=-1.0, ramp_time=1.0)


def test_ramped_imbalance_drives_a_free_mass_as_the_integral_of_its_force():
    """No bearing (zero stiffness and damping), no gravity: m dV/dt = u(t) w^2 (cos wt, sin wt) with u ramping;
    the velocity is the closed-form integral of that force."""
    from fluidfilm import LinearBearing, paper_bearing

    b = paper_bearing()
    w = b.omega
    rotor = Rotor(mass=5.0, imbalance=1e-4, imbalance_final=3e-4, ramp_time=0.05, gravity=0.0)
    tr = simulate(LinearBearing(b, 0.0, 0.0), rotor, 0.03, 1e-5, record_every=100)
    t = tr.t
    u0, k = 1e-4, (3e-4 - 1e-4) / 0.05
    # int_0^t (u0 + k s) cos(ws) ds and the sine counterpart
    ic = u0 * np.sin(w * t) / w + k * (t * np.sin(w * t) / w + (np.cos(w * t) - 1) / w**2)
    is_ = u0 * (1 - np.cos(w * t)) / w + k * (-t * np.cos(w * t) / w + np.sin(w * t) / w**2)
    v_exact = w**2 / rotor.mass * np.stack([ic, is_], axis=1)
    np.testing.assert_allclose(tr.v, v_exact, rtol=0, atol=1e-6 * np.abs(v_exact).max())


def test_bad_controller_input_names_the_value(reference, rotor_cfg, controller_cfg):
    env = env_from_cfg(reference, rotor_cfg, controller_cfg)
    env.reset()
    with pytest.raises(ValueError, match="7"):
        env.step(7)
    with pytest.raises(ValueError, match="sleeve_positions"):
        ActiveBearingEnv(reference, Rotor(mass=2.5), [0.0])
    with pytest.raises(ValueError, match="0.002"):
        ActiveBearingEnv(reference, Rotor(mass=2.5), [0.0, 2e-3])
    from fluidfilm.control import Scenario

    with pytest.raises(ValueError, match="control_interval"):
        Scenario(control_interval=0.01005)


def test_batched_mpc_predicts_every_candidate_as_simulate_does(active_surrogate, rotor_cfg, controller_cfg):
    """BatchedMPC's one-batch prediction equals a per-candidate ``simulate`` loop (same step), and its
    coarser step predicts the costs of the plant's step (dt = 1e-5 s) closely enough to rank them."""
    from fluidfilm.control.mpc import BatchedMPC

    env = env_from_cfg(active_surrogate, rotor_cfg, controller_cfg)
    env.reset()
    for _ in range(3):
        env.step(1)  # away from the settled start, so the candidates differ
    batched = BatchedMPC(active_surrogate, 1.0, dt=5e-5, eps_substep=0.6, record_every=2)
    looped = BatchedMPC(active_surrogate, 1.0, dt=5e-5, eps_substep=0.6, record_every=2)
    looped.batched = False
    sleeve = active_surrogate.sleeve
    c_batch = batched.predicted_costs(env)
    assert active_surrogate.sleeve == sleeve  # the plant's sleeve is left where it was
    np.testing.assert_array_equal(c_batch, looped.predicted_costs(env))
    # the vectorised cost is the environment's own, candidate by candidate
    sc = env.scenario
    for a, s in enumerate(env.sleeve_positions):
        active_surrogate.set_sleeve(s)
        tr = simulate(active_surrogate, env.rotor_with(env.present_imbalance()), env.t + sc.control_interval, 5e-5,
                      x0=env.x, v0=env.v, eps_stop=sc.eps_stop, record_every=2, eps_substep=0.6, t0=env.t)
        move = abs(s - env.sleeve_positions[env.action]) / env.travel
        assert c_batch[a] == pytest.approx(env.interval_cost(tr.x, active_surrogate.clearance, move)[0], rel=1e-12)
    active_surrogate.set_sleeve(sleeve)
    fine = BatchedMPC(active_surrogate, 1.0, dt=env.scenario.dt, eps_substep=0.8, record_every=10)
    c_fine = fine.predicted_costs(env)
    np.testing.assert_allclose(c_batch, c_fine, rtol=2e-3)
    assert np.argmin(c_batch) == np.argmin(c_fine)
    env.model.set_sleeve(env.sleeve_positions[env.action])


def test_batched_mpc_picks_the_one_by_one_action_on_given_states(active_surrogate, rotor_cfg, controller_cfg):
    """The configured MPC (one ``simulate_batch`` for all candidates) and the same MPC one candidate at a time
    (``simulate`` each) take the same action at states along episodes of different sleeve schedules."""
    from fluidfilm.control.mpc import BatchedMPC

    env = env_from_cfg(active_surrogate, rotor_cfg, controller_cfg)
    batched = BatchedMPC(active_surrogate, **controller_cfg["mpc"])
    looped = BatchedMPC(active_surrogate, **controller_cfg["mpc"])
    looped.batched = False
    n_states = 0
    for schedule in ([2, 2, 2, 2], [0, 1, 4, 3], [4, 4, 0, 0]):
        env.reset()
        for a in schedule:
            c_batch, c_loop = batched.predicted_costs(env), looped.predicted_costs(env)
            np.testing.assert_allclose(c_batch, c_loop, rtol=1e-12)
            assert batched(None, env) == looped(None, env) == int(np.argmin(c_loop))
            n_states += 1
            if env.step(a)[2]:
                break
    assert n_states >= 8
    env.model.set_sleeve(0.0)


def _vec_pair(model, rotor_cfg, controller_cfg, n_envs, **scenario):
    """The batched vector env and SB3's DummyVecEnv over single environments, on the same model and configs."""
    from stable_baselines3.common.vec_env import DummyVecEnv

    from fluidfilm.control.build import vec_env_from_cfg

    cfg = dict(controller_cfg, scenario=dict(controller_cfg["scenario"], **scenario))
    venv = vec_env_from_cfg(model, rotor_cfg, cfg, n_envs)
    dummy = DummyVecEnv([lambda: env_from_cfg(model, rotor_cfg, cfg) for _ in range(n_envs)])
    return venv, dummy


def _assert_same_transitions(venv, dummy, actions_per_step, rtol=1e-9):
    """Both vector envs from reset through the action rows: observations, rewards, dones, truncation flags,
    terminal observations equal to round-off; returns the dones seen and which of them were contacts."""
    np.testing.assert_allclose(venv.reset(), dummy.reset(), rtol=rtol, atol=1e-7)
    seen, contacts = [], []
    for actions in actions_per_step:
        o1, r1, d1, i1 = venv.step(np.asarray(actions))
        o2, r2, d2, i2 = dummy.step(np.asarray(actions))
        np.testing.assert_allclose(o1, o2, rtol=rtol, atol=1e-7)
        np.testing.assert_allclose(r1, r2, rtol=rtol, atol=1e-7)
        np.testing.assert_array_equal(d1, d2)
        for a, b, done in zip(i1, i2, d1):
            assert a["TimeLimit.truncated"] == b["TimeLimit.truncated"] == (done and not a["terminated"])
            assert a["terminated"] == b["terminated"]
            np.testing.assert_allclose(a["amplitude"], b["amplitude"], rtol=rtol, atol=1e-15)
            assert ("terminal_observation" in a) == ("terminal_observation" in b)
            if "terminal_observation" in a:
                np.testing.assert_allclose(a["terminal_observation"], b["terminal_observation"], rtol=rtol, atol=1e-7)
        seen.append(d1.copy())
        contacts.append([a["terminated"] for a in i1])
        venv.distinct_times = max(getattr(venv, "distinct_times", 1), len({e.t for e in venv.envs}))
    return np.array(seen), np.array(contacts)


def test_vector_env_transitions_equal_the_single_envs(active_surrogate, rotor_cfg, controller_cfg):
    """ActiveBearingVecEnv (one batched integration per step, each environment at its own sleeve) against
    SB3's DummyVecEnv stepping single environments: the same transitions through contacts under a large
    imbalance and their autoresets (those environments then run at their own times, behind the others: the
    shifted-ramp batch), and through the time limit of the quick scenario."""
    venv, dummy = _vec_pair(active_surrogate, rotor_cfg, controller_cfg, 4, imbalance_end=4e-2, ramp_time=0.1,
                            t_end=0.2)
    rng = np.random.default_rng(3)
    rows = [[0, 4, 2, rng.integers(5)] for _ in range(3)] + [list(rng.integers(0, 5, 4)) for _ in range(10)]
    dones, contacts = _assert_same_transitions(venv, dummy, rows)
    assert venv.n_batches == len(rows)  # one batch per step for a surrogate, whatever the sleeves and times
    assert contacts.sum() >= 2 and not (contacts & ~dones).any()  # contacts ended episodes
    assert venv.distinct_times > 1  # the environments ran at different times after the autoresets
    # the quick scenario (5 decisions): every environment reaches the time limit and restarts at t = 0
    venv, dummy = _vec_pair(active_surrogate, rotor_cfg, controller_cfg, 4)
    n = venv.envs[0].scenario.n_decisions
    dones, contacts = _assert_same_transitions(venv, dummy, [[1, 2, 3, 2]] * (n + 1))
    assert not contacts.any()
    assert dones[n - 1].all() and not dones[:n - 1].any() and not dones[n].any()
    assert all(e.t == e.scenario.control_interval for e in venv.envs)
    active_surrogate.set_sleeve(0.0)


def test_vector_env_on_a_model_without_per_trajectory_settings(conical, rotor_cfg, controller_cfg):
    """The reference solver re-solves when the sleeve moves: one batch per sleeve position in use, the same
    transitions as single environments; an environment reset by hand runs behind the others."""
    from fluidfilm import ConicalReynoldsSolver

    solver = ConicalReynoldsSolver(conical, 16, 8)
    venv, dummy = _vec_pair(solver, rotor_cfg, controller_cfg, 3)
    rows = [[1, 1, 3], [0, 2, 2], [4, 4, 4]]
    _assert_same_transitions(venv, dummy, rows)
    assert venv.n_batches == 2 + 2 + 1  # the sleeve positions in use per step
    o1 = venv.env_method("reset", indices=[1])[0][0]
    o2 = dummy.env_method("reset", indices=[1])[0][0]
    np.testing.assert_array_equal(o1, o2)
    assert venv.envs[1].t == 0.0 < venv.envs[0].t
    for actions in ([2, 2, 2], [1, 3, 0]):
        r1, r2 = venv.step(np.array(actions)), dummy.step(np.array(actions))
        for a, b in zip(r1[:3], r2[:3]):
            np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-7)
    with pytest.raises(ValueError, match="n_envs"):
        from fluidfilm.control import ActiveBearingVecEnv

        ActiveBearingVecEnv(solver, Rotor(mass=2.5), [0.0, 1e-4], n_envs=0)
    solver.set_sleeve(0.0)


def test_dqn_trains_on_the_vector_env(active_surrogate, rotor_cfg, controller_cfg):
    """SB3's DQN with n_envs > 1 on the batched vector env: it counts environment steps, sees episodes end."""
    from fluidfilm.control.build import vec_env_from_cfg

    venv = vec_env_from_cfg(active_surrogate, rotor_cfg, controller_cfg, 4)
    cfg = dict(controller_cfg["dqn"], gradient_steps=-1)
    agent, returns = train_dqn(venv, cfg, seed=0)
    assert agent.num_timesteps >= cfg["total_timesteps"] and agent.num_timesteps % 4 == 0
    assert len(returns) >= 4 and all(np.isfinite(r) for _, r in returns)
    assert venv.n_batches == agent.num_timesteps // 4
