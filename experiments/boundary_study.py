"""Hard switch vs smoothstep blend at the split boundaries (reports/boundary_study.json).

    python experiments/boundary_study.py

The study is fluidfilm.studies.boundary_study; config conf/boundary_study.yaml.
"""
from fluidfilm.studies import boundary_study
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(boundary_study, "the split-boundary study")
