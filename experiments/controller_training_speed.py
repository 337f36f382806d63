"""The paper's controller-training claim, measured: DQN training on the reference model vs on the surrogate.

    python experiments/controller_training_speed.py
Trains the same DQN (same seed, same hyperparameters, conf/controller) for the same budget of
environment steps (``training_speed.budget_steps``) on the same vector environment (``n_envs``
environments, one batched integration per step) driven by the reference model and by the surrogate,
and reports the wall time per environment step of each and their ratio (``controller_training_speedup``);
compilation, settling and torch's warm-up are not timed, and both trained policies are evaluated on the
reference model.  A full training on the reference (``dqn.total_timesteps`` steps) would take longer
than the whole rest of the pipeline, so its time is extrapolated from the measured time per step; the
report says so.  Writes reports/controller_training_speed.json.
The study is fluidfilm.studies.controller_training_speed; config conf/controller_training_speed.yaml.
"""
from fluidfilm.studies import controller_training_speed
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(controller_training_speed, "the controller-training speed study")
