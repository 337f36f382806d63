"""Run-ups through the whirl threshold: onset from the transient against Lund's linear threshold, hysteresis
on the run-down, the cascade plot.

    python experiments/runup.py                     # the DVC stage
    python experiments/runup.py runup=quick         # the small profile

The study is fluidfilm.studies.runup; config conf/runup.yaml.
"""
from fluidfilm.studies import runup
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(runup, "the run-up study")
