"""Train the DQN sleeve controller with stable-baselines3.

The library records the episode returns; logging them to MLflow is the workflow's business
(``fluidfilm.workflow.tracking.learning_curve_hooks`` passed as ``on_episode``/``on_rollout``).
"""
from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path


def episode_returns_callback(on_episode=None, on_rollout=None):
    """A stable-baselines3 callback that keeps the episode returns (from the Monitor wrapper) in ``.returns``.

    ``on_episode(timestep, ret)`` is called with each finished episode's return and ``on_rollout(scalars,
    timestep)`` with SB3's training scalars (a dict of floats, names with ``/`` replaced by ``_``) after each
    rollout: the workflow's MLflow curves (``fluidfilm.workflow.tracking.learning_curve_hooks``) plug in there,
    so this module imports no tracking code.
    """
    import numpy as np
    from stable_baselines3.common.callbacks import BaseCallback

    class EpisodeReturns(BaseCallback):
        def __init__(self):
            super().__init__()
            self.returns: list[tuple[int, float]] = []

        def _on_step(self) -> bool:
            for info in self.locals.get("infos", []):
                ep = info.get("episode")
                if ep is not None:
                    self.returns.append((self.num_timesteps, float(ep["r"])))
                    if on_episode is not None:
                        on_episode(self.num_timesteps, float(ep["r"]))
            return True

        def _on_rollout_end(self) -> None:
            if on_rollout is None:
                return
            vals = {k.replace("/", "_"): float(v) for k, v in self.model.logger.name_to_value.items()
                    if isinstance(v, (int, float, np.floating))}
            if vals:
                on_rollout(vals, self.num_timesteps)

    return EpisodeReturns()


def make_dqn(env, cfg: Mapping, seed: int = 0):
    """A stable-baselines3 DQN (MLP Q-network) on ``env`` with the hyperparameters of ``cfg``, untrained.

    ``env``: a gymnasium environment (wrapped in SB3's ``Monitor``) or an SB3 ``VecEnv`` such as
    ``ActiveBearingVecEnv`` (wrapped in ``VecMonitor``), so that finished episodes report their returns.
    With N environments SB3 counts ``total_timesteps``, ``learning_starts`` and ``target_update_interval``
    in environment steps, ``train_freq`` in vector steps (N transitions each); ``gradient_steps=-1`` does
    one gradient step per transition collected, as ``gradient_steps=1`` does with one environment.
    ``cfg["torch_threads"]`` (default 1): torch's threads for the whole process (``torch.set_num_threads``).
    """
    import torch
    from stable_baselines3 import DQN
    from stable_baselines3.common.monitor import Monitor
    from stable_baselines3.common.vec_env import VecEnv, VecMonitor

    # the Q-network is tiny: torch's intra-op threads only spin (measured on the loaded 2-core machine:
    # 75 -> 11 ms CPU per environment step with one thread); cfg["torch_threads"], default 1
    threads = int(cfg.get("torch_threads", 1))
    if threads < 1:
        raise ValueError(f"torch_threads must be >= 1, got {threads!r}")
    torch.set_num_threads(threads)

    keys = ("learning_rate", "buffer_size", "learning_starts", "batch_size", "gamma", "train_freq",
            "target_update_interval", "exploration_fraction", "exploration_final_eps", "gradient_steps")
    kwargs = {k: cfg[k] for k in keys if k in cfg}
    wrapped = VecMonitor(env) if isinstance(env, VecEnv) else Monitor(env)
    return DQN("MlpPolicy", wrapped, seed=seed, verbose=0, device="cpu",
               policy_kwargs={"net_arch": list(cfg.get("net_arch", [64, 64]))}, **kwargs)


def train_dqn(env, cfg: Mapping, seed: int = 0, progress: bool = False, on_episode=None, on_rollout=None,
              agent=None):
    """A DQN agent (stable-baselines3, MLP Q-network) trained on ``env`` for ``cfg['total_timesteps']``.

    ``env``: one environment or a vector of them (``make_dqn``). ``on_episode``, ``on_rollout``: hooks called
    with each episode's return and SB3's training scalars (``episode_returns_callback``). ``agent``: one made
    by ``make_dqn`` on ``env`` (None: made here). Returns (agent, episode returns [(timestep, return)]).
    """
    total = int(cfg["total_timesteps"])
    if total < 1:
        raise ValueError(f"total_timesteps must be >= 1, got {total}")
    if agent is None:
        agent = make_dqn(env, cfg, seed)
    cb = episode_returns_callback(on_episode, on_rollout)
    agent.learn(total_timesteps=total, callback=cb, progress_bar=progress)
    return agent, cb.returns


def save_agent(agent, path) -> Path:
    """Save atomically (SB3 writes a zip; we write to a temporary name and rename)."""
    from fluidfilm import io

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
