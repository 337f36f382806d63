"""Rotor calibration: orbit spans of the imbalance cases over rotor mass, load share and imbalance sense.

    python experiments/rotor_calibration.py    # reports/rotor_calibration.csv

The study is fluidfilm.studies.rotor_calibration; config conf/rotor_calibration.yaml.
"""
from fluidfilm.studies import rotor_calibration
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(rotor_calibration, "the rotor-mass calibration")
