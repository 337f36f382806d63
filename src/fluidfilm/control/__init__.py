"""Control of the active conical bearing: the gymnasium environment, DQN (stable-baselines3) and MPC."""
from fluidfilm.control.controllers import ConstantSleeve, DQNController, ModelPredictiveController, run_episode
from fluidfilm.control.env import ActiveBearingEnv, RewardWeights, Scenario, friction_power, orbit_amplitude

__all__ = ["ActiveBearingEnv", "Scenario", "RewardWeights", "friction_power", "orbit_amplitude",
           "ConstantSleeve", "DQNController", "ModelPredictiveController", "run_episode"]
