"""The paper's training-time comparison: single vs three split networks, same rows, same protocol, many seeds.

    python experiments/train_time.py                       # reports/train_time.json
    python experiments/train_time.py protocol=adam         # the second protocol
    python experiments/train_time.py samples_per_seed=40000 ranking_check.enabled=false

Per seed: one random subsample of the dataset, one 70/15/15 division; the
single network and the three split networks (eps 0-0.5, 0.5-0.7, > 0.7, each
with its own min-max map) train on it to the validation stopping rule.
Reported (src/fluidfilm/studies/train_time.py): the reduction of the
mean training time 100 (1 - mean T_split / mean T_single) with a paired
bootstrap 95 % confidence interval (seeds are added, up to ``seeds_max`` or
the time budget, until its half-width is at most the target), the seeds the
target would need, the mean of the per-seed reductions, the time the
split networks need to reach the single network's final validation error
on the same rows, every network's epochs / stop reason / errors / time, and
a ranking check at twice the subsample size.  Every finished seed is kept
under ``cache_dir``: run the same command again after an interruption and it
resumes at the next seed (delete the folder to measure afresh).  Seeds run as parallel
processes (``n_jobs``), each single-threaded; single and split of one seed
run in the same process, one after the other.
The study is fluidfilm.studies.train_time; config conf/train_time.yaml.
"""
from fluidfilm.studies import train_time
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(train_time, "the training-time study")
