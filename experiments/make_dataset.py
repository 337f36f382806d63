"""Graded dataset (data/dataset/) and held-out test set (data/testset/) with the reference model.

    python experiments/make_dataset.py                      # the paper's layout
    python experiments/make_dataset.py dataset=quick        # seconds
    python experiments/make_dataset.py dask.scheduler=tcp://host:8786
Interrupt it at any time; running it again continues from the finished chunks.
The study is fluidfilm.studies.make_dataset; config conf/make_dataset.yaml.
"""
from fluidfilm.studies import make_dataset
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(make_dataset, "dataset generation", "run the same command again; it continues from the finished chunks")
