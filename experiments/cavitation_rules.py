"""Guembel and Swift-Stieber cavitation against the mass-conserving (JFO / Elrod-Adams) film, like for like.

    python experiments/cavitation_rules.py                          # the DVC stage
    python experiments/cavitation_rules.py cavitation_rules=quick   # the small profile

The study is fluidfilm.studies.cavitation_rules; config conf/cavitation_rules.yaml.
"""
from fluidfilm.studies import cavitation_rules
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(cavitation_rules, "the cavitation-rules study")
