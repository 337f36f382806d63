"""Train the DQN sleeve controller of the active conical bearing on the surrogate (models/dqn_active.zip).

    python experiments/train_controller.py
    python experiments/train_controller.py controller=quick surrogate_dir=...   # seconds
The learning curve (episode returns, SB3's losses, exploration rate) goes to MLflow.
The study is fluidfilm.studies.train_controller; config conf/train_controller.yaml.
"""
from fluidfilm.studies import train_controller
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(train_controller, "the controller training")
