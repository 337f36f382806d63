"""The paper's controller-training claim, measured: DQN training on the reference model vs on the surrogate
(``experiments/controller_training_speed.py``, reports/controller_training_speed.json).

The same DQN (same seed, same hyperparameters) trains for the same budget of environment steps on each
model; a full training on the reference is extrapolated from the measured time per step.
"""
from __future__ import annotations

import time

from fluidfilm import io, load_surrogate
from fluidfilm.control.build import env_from_cfg
from fluidfilm.control.dqn import train_dqn
from fluidfilm.workflow import tracking
from fluidfilm.workflow.config import bearing_from_cfg, reference_from_cfg
from fluidfilm.workflow.entry import plain

INPUTS = ("surrogate_dir",)
OUTPUTS = {"training_speed.out_json": [""]}


def tracking_run(cfg):
    return "controller_training_speed", {"stage": "controller_training_speed"}


def run(cfg) -> tracking.Logged:
    c = plain(cfg)
    ts = c["training_speed"]
    dqn = dict(c["controller"]["dqn"], total_timesteps=int(ts["budget_steps"]),
               learning_starts=int(ts["learning_starts"]))
    models = {"surrogate": load_surrogate(cfg.surrogate_dir),
              "reference": reference_from_cfg(bearing_from_cfg(cfg.bearing), cfg.reference)}
    out = {"budget_steps": dqn["total_timesteps"], "learning_starts": dqn["learning_starts"],
           "full_training_steps": c["controller"]["dqn"]["total_timesteps"]}
    for name, model in models.items():
        env = env_from_cfg(model, c["rotor"], c["controller"])
        env.reset()
        env.step(env.initial_action)  # compile and settle outside the timing
        t0 = time.perf_counter()
        # nothing logged while timed (the run opened by the wrapper gets the speeds at the end)
        train_dqn(env, dqn, seed=cfg.controller.seed)  # timed: nothing logged during it
        wall = time.perf_counter() - t0
        per_step = wall / dqn["total_timesteps"]
        out[name] = {"wall_s": wall, "s_per_env_step": per_step,
                     "full_training_s_extrapolated": per_step * out["full_training_steps"]}
        print(f"{name}: {dqn['total_timesteps']} DQN steps in {wall:.1f} s, {1e3 * per_step:.1f} ms per env step")
    out["controller_training_speedup"] = out["reference"]["s_per_env_step"] / out["surrogate"]["s_per_env_step"]
    out["note"] = ("same DQN, seed and step budget on both models; full-length training times extrapolated "
                   "from the measured time per environment step")
    io.write_json(cfg.training_speed.out_json, out)
    print(f"controller training speed-up (reference / surrogate time per step): {out['controller_training_speedup']:.1f}x")
    return tracking.Logged({"controller_training_speedup": out["controller_training_speedup"],
                            "reference_s_per_env_step": out["reference"]["s_per_env_step"],
                            "surrogate_s_per_env_step": out["surrogate"]["s_per_env_step"]},
                           [cfg.training_speed.out_json], value=out)
