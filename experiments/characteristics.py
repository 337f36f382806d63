"""Static characteristics, K/C coefficients and the whirl threshold: reference vs surrogates.

    python experiments/characteristics.py                 # the DVC stage
    python experiments/characteristics.py characteristics=quick models.best=/path/to/best ...

The study is fluidfilm.studies.characteristics_study; config conf/characteristics.yaml.
"""
from fluidfilm.studies import characteristics_study
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(characteristics_study, "the bearing-characteristics study", name="characteristics")
