"""The JFO film's force surrogate with memory: training paths, the fit, the seven cases against the reference.

    python experiments/jfo_surrogate.py                        # the DVC stage
    python experiments/jfo_surrogate.py jfo_surrogate=quick    # the small profile

The study is fluidfilm.studies.jfo_surrogate; config conf/jfo_surrogate.yaml.
"""
from fluidfilm.studies import jfo_surrogate
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(jfo_surrogate, "the JFO surrogate with memory")
