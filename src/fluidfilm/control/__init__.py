"""Control of the active conical bearing: the gymnasium environment and its batched vector form, DQN
(stable-baselines3) and MPC."""
from fluidfilm.control.controllers import ConstantSleeve, DQNController, ModelPredictiveController, run_episode
from fluidfilm.control.env import ActiveBearingEnv, RewardWeights, Scenario, friction_power, orbit_amplitude
from fluidfilm.control.vec_env import ActiveBearingVecEnv

__all__ = ["ActiveBearingEnv", "ActiveBearingVecEnv", "Scenario", "RewardWeights", "friction_power",
           "orbit_amplitude", "ConstantSleeve", "DQNController", "ModelPredictiveController", "run_episode"]
