"""Train a surrogate (single or split by eccentricity) and save it under models/<name>/.

    python experiments/train_surrogate.py experiment=paper_single
    python experiments/train_surrogate.py experiment=paper_split
    python experiments/train_surrogate.py -m hydra/launcher=joblib model=paper_single,mlp_2x64 split=none,paper
Logs the config, per-epoch losses (one nested run per network), training
times, test-set accuracy and speed to MLflow.  An interrupted run resumes
from the last checkpoint of each network.
The study is fluidfilm.studies.train_surrogate; config conf/train_surrogate.yaml.
"""
from fluidfilm.studies import train_surrogate
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(train_surrogate, "surrogate training", "run the same command again; each network resumes from its "
         "last epoch checkpoint (checkpoint_dir)")
