"""The paper's controller-training claim, measured: DQN training on the reference model vs on the surrogate.

    python experiments/controller_training_speed.py
Trains the same DQN (same seed, same hyperparameters, conf/controller) for the same budget of
environment steps (``training_speed.budget_steps``) on the environment driven by the reference
model and by the surrogate, and reports the wall time per environment step of each and their ratio
(``controller_training_speedup``).  A full training on the reference (``dqn.total_timesteps``
steps) would take longer than the whole rest of the pipeline, so its time is extrapolated from the
measured time per step (the cost per step does not depend on the step count: one control interval
of the rotor plus one gradient step); the report says so.  Writes reports/controller_training_speed.json.
"""
import time

import hydra
from omegaconf import DictConfig, OmegaConf

from fluidfilm import io, load_surrogate
from fluidfilm.workflow import tracking
from fluidfilm.workflow.config import bearing_from_cfg, reference_from_cfg
from fluidfilm.control.build import env_from_cfg
from fluidfilm.control.dqn import train_dqn
from fluidfilm.workflow.config_check import check_config


@hydra.main(config_path="../conf", config_name="control", version_base="1.3")
def main(cfg: DictConfig) -> dict:
    check_config(cfg)  # a mistyped value or an unknown key is refused here, before any work
    c = OmegaConf.to_container(cfg, resolve=True)
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
        train_dqn(env, dqn, seed=cfg.controller.seed,
                  callback=tracking.sb3_learning_curves())
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
    with tracking.run(cfg.tracking, "controller_training_speed", c, tags={"stage": "controller_training_speed"}):
        tracking.log_metrics({"controller_training_speedup": out["controller_training_speedup"],
                              "reference_s_per_env_step": out["reference"]["s_per_env_step"],
                              "surrogate_s_per_env_step": out["surrogate"]["s_per_env_step"]})
        tracking.log_artifact(str(cfg.training_speed.out_json))
    return out


if __name__ == "__main__":
    io.run_interruptible(main, "the controller-training speed study", "run the same command again")
