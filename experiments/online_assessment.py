"""On-line assessment from measured orbits: journal position, static load, imbalance and oil viscosity from two
probes and a speed signal (an EKF with the universal surrogate), against the centreline baseline.

    python experiments/online_assessment.py                          # the DVC stage (synthetic plant records)
    python experiments/online_assessment.py input=record.csv assess.out_dir=out   # a recorded probe file

The study is fluidfilm.studies.online_assessment; config conf/online_assessment.yaml.
"""
from fluidfilm.studies import online_assessment
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(online_assessment, "the on-line assessment study")
