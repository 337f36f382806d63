"""Train the DQN sleeve controller of the active conical bearing on the surrogate (models/dqn_active.zip).

    python experiments/train_controller.py
    python experiments/train_controller.py controller=quick surrogate_dir=...   # seconds
The learning curve (episode returns, SB3's losses, exploration rate) goes to MLflow.
"""
import time

import hydra
from omegaconf import DictConfig, OmegaConf

from fluidfilm import io, load_surrogate
from fluidfilm.workflow import tracking
from fluidfilm.control.build import env_from_cfg
from fluidfilm.control.dqn import save_agent, train_dqn
from fluidfilm.workflow.config_check import check_config


@hydra.main(config_path="../conf", config_name="control", version_base="1.3")
def main(cfg: DictConfig) -> dict:
    check_config(cfg)  # a mistyped value or an unknown key is refused here, before any work
    c = OmegaConf.to_container(cfg, resolve=True)
    surrogate = load_surrogate(cfg.surrogate_dir)
    env = env_from_cfg(surrogate, c["rotor"], c["controller"])
    with tracking.run(cfg.tracking, "dqn_controller", c, tags={"stage": "train_controller"}):
        t0 = time.perf_counter()
        agent, returns = train_dqn(env, c["controller"]["dqn"], seed=cfg.controller.seed,
                  callback=tracking.sb3_learning_curves())
        wall = time.perf_counter() - t0
        save_agent(agent, cfg.agent_path)
    n = c["controller"]["dqn"]["total_timesteps"]
    report = {"total_timesteps": n, "train_time_s": wall, "surrogate": cfg.surrogate_dir,
              "episodes": len(returns), "episode_returns": [[int(t), float(r)] for t, r in returns],
              "env_steps_per_s": n / wall}
    io.write_json(cfg.training_report, report)
    print(f"DQN: {n} steps ({len(returns)} episodes) on the surrogate in {wall:.0f} s -> {cfg.agent_path}")
    return report


if __name__ == "__main__":
    io.run_interruptible(main, "the controller training", "run the same command again")
