"""Train the DQN sleeve controller with stable-baselines3, logging its learning curve to MLflow."""
from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np


def _mlflow_callback(log_every: int = 1):
    from stable_baselines3.common.callbacks import BaseCallback

    class MlflowCurves(BaseCallback):
        """Episode returns (from the Monitor wrapper) and SB3's training scalars, logged to the active MLflow run."""

        def __init__(self):
            super().__init__()
            self.returns: list[tuple[int, float]] = []

        def _on_step(self) -> bool:
            import mlflow

            for info in self.locals.get("infos", []):
                ep = info.get("episode")
                if ep is not None:
                    self.returns.append((self.num_timesteps, float(ep["r"])))
                    if mlflow.active_run() is not None:
                        mlflow.log_metric("episode_return", float(ep["r"]), step=self.num_timesteps)
            return True

        def _on_rollout_end(self) -> None:
            import mlflow

            if mlflow.active_run() is None:
                return
            vals = {k.replace("/", "_"): float(v) for k, v in self.model.logger.name_to_value.items()
                    if isinstance(v, (int, float, np.floating))}
            if vals:
                mlflow.log_metrics(vals, step=self.num_timesteps)

    return MlflowCurves()


def train_dqn(env, cfg: Mapping, seed: int = 0, progress: bool = False):
    """A DQN agent (stable-baselines3, MLP Q-network) trained on ``env`` for ``cfg['total_timesteps']``.

    Returns (agent, episode returns [(timestep, return)]).
    """
    from stable_baselines3 import DQN
    from stable_baselines3.common.monitor import Monitor

    keys = ("learning_rate", "buffer_size", "learning_starts", "batch_size", "gamma", "train_freq",
            "target_update_interval", "exploration_fraction", "exploration_final_eps", "gradient_steps")
    kwargs = {k: cfg[k] for k in keys if k in cfg}
    total = int(cfg["total_timesteps"])
    if total < 1:
        raise ValueError(f"total_timesteps must be >= 1, got {total}")
    agent = DQN("MlpPolicy", Monitor(env), seed=seed, verbose=0, device="cpu",
                policy_kwargs={"net_arch": list(cfg.get("net_arch", [64, 64]))}, **kwargs)
    cb = _mlflow_callback()
    agent.learn(total_timesteps=total, callback=cb, progress_bar=progress)
    return agent, cb.returns


def save_agent(agent, path) -> Path:
    """Save atomically (SB3 writes a zip; we write to a temporary name and rename)."""
    from .. import io

    path = Path(path)
    # the temporary name ends in .zip, so SB3 writes it as given (it appends .zip otherwise)
    with io.atomic_path(path, suffix=".zip") as tmp:
        agent.save(tmp)
    return path


def load_agent(path):
    from stable_baselines3 import DQN

    path = Path(path)
    if not path.exists():
        raise ValueError(f"no saved DQN agent at {path}")
    return DQN.load(path, device="cpu")
