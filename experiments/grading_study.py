"""The grading study: generate (or reuse) the dataset of one grading, train a surrogate on it, evaluate it.

    python experiments/grading_study.py -m grading.n_per_side=8,16,24 grading.n_angle=24,48
    python experiments/grading_study.py -m scaling=physics_whirl,standard split=five_blend,none
Each job writes result.json in its Hydra output folder and logs a run to MLflow (nested under the
sweep's run); when the multirun ends, fluidfilm.studies.grading_study.SweepSummaryCallback writes the sweep's
summary.json, table.csv and figure.png (to summary_dir, or the sweep's folder).
The study is fluidfilm.studies.grading_study; config conf/grading_study.yaml.
"""
from fluidfilm.studies import grading_study
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(grading_study, "the grading study", "run the same command again; cached datasets are reused and "
         "each network resumes from its last epoch checkpoint (checkpoint_dir)")
