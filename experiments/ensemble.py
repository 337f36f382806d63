"""The best surrogate's seeds, their ensemble and the hybrid with the reference, through the seven cases.

    python experiments/ensemble.py

The study is fluidfilm.studies.ensemble; config conf/ensemble.yaml.
"""
from fluidfilm.studies import ensemble
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(ensemble, "the ensemble study")
