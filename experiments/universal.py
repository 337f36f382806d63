"""The universal plain-bearing surrogate: dataset, training and held-out evaluation.

    python experiments/universal.py part=dataset     # data/universal_dataset (Dask, resumable)
    python experiments/universal.py part=train       # models/universal
    python experiments/universal.py part=evaluate    # reports/universal.json, figures
The study is fluidfilm.studies.universal_study; config conf/universal.yaml.
"""
from fluidfilm.studies import universal_study
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(universal_study, "the universal surrogate", "run the same command again; the dataset continues from its finished parts", name="universal")
