"""Evaluate no control, the DQN agent and MPC on the reference model of the active bearing (Fig. 5).

    python experiments/evaluate_control.py
Writes reports/control.json (amplitudes, friction, sleeve travel, time per decision, the
amplitude reduction) and reports/figures/fig5_*.png; logs to MLflow.
The study is fluidfilm.studies.evaluate_control; config conf/evaluate_control.yaml.
"""
from fluidfilm.studies import evaluate_control
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(evaluate_control, "the controller evaluation")
