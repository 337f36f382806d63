"""Build the environment and controllers from plain mappings (config nodes); no Hydra here."""
from __future__ import annotations

from collections.abc import Mapping

from fluidfilm.rotor import Rotor
from fluidfilm.control.env import ActiveBearingEnv, RewardWeights, Scenario


def scenario_from_cfg(cfg: Mapping) -> Scenario:
    return Scenario(**dict(cfg))


def env_from_cfg(model, rotor_cfg: Mapping, controller_cfg: Mapping) -> ActiveBearingEnv:
    """The environment on ``model`` (surrogate or reference) with the rotor and scenario of the configs."""
    share = float(rotor_cfg.get("load_share", 1.0))
    rotor = Rotor.shared(rotor_cfg["mass"], 0.0, load_share=share, gravity=rotor_cfg.get("gravity", 9.81),
                         imbalance_direction=rotor_cfg.get("imbalance_direction", 1))
    return ActiveBearingEnv(model, rotor, list(controller_cfg["sleeve_positions"]),
                            scenario_from_cfg(controller_cfg["scenario"]),
                            RewardWeights(**dict(controller_cfg["reward"])), load_share=share)
