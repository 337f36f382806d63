"""The paper's controller-training claim, measured: DQN training on the reference model vs on the surrogate
(``experiments/controller_training_speed.py``, reports/controller_training_speed.json).

Both models are run the same way: the same vector environment (``ActiveBearingVecEnv``, ``n_envs``
environments stepped by one batched integration per step), the same DQN (seed, hyperparameters) and the
same number of environment steps.  Excluded from the timing, and said so in the output: numba's
compilation and the settling run (one step of each vector environment first), torch's first gradient
steps (a throwaway DQN of a few steps) and building the agent.  With ``repeats`` > 1 the two models are
timed alternately and the medians compared.  Each trained policy is then evaluated greedily on the
reference model (one episode of the configured scenario), so the speed-up is read beside what the
policies do on the reference.  A full training on the reference is extrapolated from the measured time
per environment step.
"""
from __future__ import annotations

import os
import time

import numpy as np

from fluidfilm import io, load_surrogate
from fluidfilm.control import DQNController, run_episode
from fluidfilm.control.build import env_from_cfg, vec_env_from_cfg
from fluidfilm.control.dqn import make_dqn, train_dqn
from fluidfilm.workflow import tracking
from fluidfilm.workflow.config import bearing_from_cfg, reference_from_cfg
from fluidfilm.workflow.entry import plain

INPUTS = ("surrogate_dir",)
OUTPUTS = {"training_speed.out_json": [""]}


def tracking_run(cfg):
    return "controller_training_speed", {"stage": "controller_training_speed"}


def _loadavg() -> list[float] | None:
    return list(os.getloadavg()) if hasattr(os, "getloadavg") else None


def run(cfg) -> tracking.Logged:
    c = plain(cfg)
    ts = c["training_speed"]
    dqn = dict(c["controller"]["dqn"], total_timesteps=int(ts["budget_steps"]),
               learning_starts=int(ts["learning_starts"]))
    n_envs = int(ts.get("n_envs") or dqn.get("n_envs", 1))
    repeats = int(ts.get("repeats", 1))
    if repeats < 1:
        raise ValueError(f"training_speed.repeats must be >= 1, got {repeats!r}")
    reference = reference_from_cfg(bearing_from_cfg(cfg.bearing), cfg.reference)
    models = {"surrogate": load_surrogate(cfg.surrogate_dir), "reference": reference}
    venvs = {name: vec_env_from_cfg(model, c["rotor"], c["controller"], n_envs) for name, model in models.items()}
    seed = cfg.controller.seed
    # warm-up, not timed: compile each vector env's loop and settle (one step), torch's first gradient steps
    for venv in venvs.values():
        venv.reset()
        venv.step(np.full(n_envs, venv.envs[0].initial_action))
    train_dqn(venvs["surrogate"], dict(dqn, total_timesteps=4 * n_envs, learning_starts=n_envs,
                                       batch_size=min(int(dqn.get("batch_size", 32)), n_envs)), seed=seed)
    out: dict = {"budget_steps": dqn["total_timesteps"], "learning_starts": dqn["learning_starts"], "n_envs": n_envs,
                 "gradient_steps": dqn.get("gradient_steps", 1), "train_freq": dqn.get("train_freq", 4),
                 "repeats": repeats, "full_training_steps": c["controller"]["dqn"]["total_timesteps"],
                 "loadavg_before": _loadavg()}
    walls: dict[str, list[float]] = {name: [] for name in models}
    agents: dict = {}
    for rep in range(repeats):
        for name, venv in venvs.items():
            agent = make_dqn(venv, dqn, seed)  # built outside the timing
            t0 = time.perf_counter()
            train_dqn(venv, dqn, seed=seed, agent=agent)  # timed: nothing logged during it
            walls[name].append(time.perf_counter() - t0)
            steps = int(agent.num_timesteps)
            agents[name] = agent
            print(f"{name} (repeat {rep + 1}/{repeats}): {steps} DQN steps on {n_envs} environments in "
                  f"{walls[name][-1]:.1f} s, {1e3 * walls[name][-1] / steps:.2f} ms per env step", flush=True)
    out["loadavg_after"] = _loadavg()
    for name, agent in agents.items():
        steps = int(agent.num_timesteps)
        wall = float(np.median(walls[name]))
        per_step = wall / steps
        out[name] = {"env_steps": steps, "wall_s": wall, "wall_s_each": walls[name], "s_per_env_step": per_step,
                     "batched_integrations": venvs[name].n_batches,
                     "full_training_s_extrapolated": per_step * out["full_training_steps"]}
    out["controller_training_speedup"] = out["reference"]["s_per_env_step"] / out["surrogate"]["s_per_env_step"]
    # both policies on the reference model (what the paper's "maintaining the accuracy" is about)
    plant = env_from_cfg(reference, c["rotor"], c["controller"])
    for name, agent in agents.items():
        res = run_episode(plant, DQNController(agent), keep_trajectory=False)
        out[name]["on_reference"] = {k: res[k] for k in ("return", "n_decisions", "contact", "max_amplitude_m",
                                                          "mean_friction_power_W", "sleeve_travel_m")}
        print(f"policy trained on the {name}, on the reference: return {res['return']:.1f}, "
              f"max amplitude {res['max_amplitude_m'] * 1e6:.1f} um, contact {res['contact']}")
    out["note"] = (f"same vector env ({n_envs} environments, one batched integration per step for the surrogate, "
                   "one per sleeve position in use for the reference), DQN, seed and environment steps on both "
                   "models; not timed: compilation, settling, torch warm-up, building the agent; medians over "
                   f"{repeats} alternating repeat(s); machine load (1, 5, 15 min) before and after in loadavg_*; "
                   "full-length training times extrapolated from the measured time per environment step")
    io.write_json(cfg.training_speed.out_json, out)
    print(f"controller training speed-up (reference / surrogate time per env step, {n_envs} environments): "
          f"{out['controller_training_speedup']:.1f}x; load {out['loadavg_before']} -> {out['loadavg_after']}")
    return tracking.Logged({"controller_training_speedup": out["controller_training_speedup"],
                            "reference_s_per_env_step": out["reference"]["s_per_env_step"],
                            "surrogate_s_per_env_step": out["surrogate"]["s_per_env_step"]},
                           [cfg.training_speed.out_json], value=out)
