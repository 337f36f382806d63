"""Train the DQN sleeve controller of the active conical bearing on the surrogate (models/dqn_active.zip;
``experiments/train_controller.py``, config conf/train_controller.yaml)."""
from __future__ import annotations

import time

from fluidfilm import io, load_surrogate
from fluidfilm.control.build import vec_env_from_cfg
from fluidfilm.control.dqn import save_agent, train_dqn
from fluidfilm.workflow import tracking
from fluidfilm.workflow.entry import plain

INPUTS = ("surrogate_dir",)
OUTPUTS = {"agent_path": [""], "training_report": [""]}


def tracking_run(cfg):
    return "dqn_controller", {"stage": "train_controller"}


def run(cfg) -> tracking.Logged:
    c = plain(cfg)
    surrogate = load_surrogate(cfg.surrogate_dir)
    # controller.dqn.n_envs environments stepped by one batched integration per step (ActiveBearingVecEnv)
    env = vec_env_from_cfg(surrogate, c["rotor"], c["controller"])
    t0 = time.perf_counter()
    # the learning curve (episode returns, SB3's losses) goes to the run the entry wrapper opened
    agent, returns = train_dqn(env, c["controller"]["dqn"], seed=cfg.controller.seed,
                               **tracking.learning_curve_hooks())
    wall = time.perf_counter() - t0
    save_agent(agent, cfg.agent_path)
    n = int(agent.num_timesteps)  # total_timesteps rounded up to whole vector steps
    report = {"total_timesteps": n, "n_envs": env.num_envs, "train_time_s": wall, "surrogate": cfg.surrogate_dir,
              "episodes": len(returns), "episode_returns": [[int(t), float(r)] for t, r in returns],
              "env_steps_per_s": n / wall}
    io.write_json(cfg.training_report, report)
    print(f"DQN: {n} steps ({len(returns)} episodes, {env.num_envs} environments) on the surrogate in {wall:.0f} s -> {cfg.agent_path}")
    return tracking.Logged(value=report)
