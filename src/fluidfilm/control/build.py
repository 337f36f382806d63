"""Build the environment and controllers from plain mappings (config nodes); no Hydra here."""
from __future__ import annotations

from collections.abc import Mapping

from fluidfilm.rotor import Rotor
from fluidfilm.control.env import ActiveBearingEnv, RewardWeights, Scenario
from fluidfilm.control.vec_env import ActiveBearingVecEnv


def scenario_from_cfg(cfg: Mapping) -> Scenario:
    return Scenario(**dict(cfg))


def _rotor(rotor_cfg: Mapping) -> tuple[Rotor, float]:
    share = float(rotor_cfg.get("load_share", 1.0))
    rotor = Rotor.shared(rotor_cfg["mass"], 0.0, load_share=share, gravity=rotor_cfg.get("gravity", 9.81),
                         imbalance_direction=rotor_cfg.get("imbalance_direction", 1))
    return rotor, share


def env_from_cfg(model, rotor_cfg: Mapping, controller_cfg: Mapping) -> ActiveBearingEnv:
    """The environment on ``model`` (surrogate or reference) with the rotor and scenario of the configs."""
    rotor, share = _rotor(rotor_cfg)
    return ActiveBearingEnv(model, rotor, list(controller_cfg["sleeve_positions"]),
                            scenario_from_cfg(controller_cfg["scenario"]),
                            RewardWeights(**dict(controller_cfg["reward"])), load_share=share)


def vec_env_from_cfg(model, rotor_cfg: Mapping, controller_cfg: Mapping, n_envs: int | None = None,
                     threads: int | None = 1) -> ActiveBearingVecEnv:
    """``n_envs`` environments as ``env_from_cfg`` builds, stepped by one batched integration
    (``ActiveBearingVecEnv``); None: ``controller_cfg["dqn"]["n_envs"]`` (1 where absent)."""
    rotor, share = _rotor(rotor_cfg)
    if n_envs is None:
        n_envs = int(controller_cfg.get("dqn", {}).get("n_envs", 1))
    return ActiveBearingVecEnv(model, rotor, list(controller_cfg["sleeve_positions"]),
                               scenario_from_cfg(controller_cfg["scenario"]),
                               RewardWeights(**dict(controller_cfg["reward"])), load_share=share, n_envs=n_envs,
                               threads=threads)
