"""Fig. 4 reference: the seven trajectory cases with the reference model.

    python experiments/trajectories.py       # data/trajectories/reference/<case>.npz, reports/figures/fig4_reference.png

The study is fluidfilm.studies.trajectories; config conf/trajectories.yaml.
"""
from fluidfilm.studies import trajectories
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(trajectories, "the reference trajectories")
