"""Trajectories per second of the reference and the best surrogate, one by one and batched, side by side.

    python experiments/batch_speed.py
Writes reports/batch_speed.json: for each N in ``batch_sizes`` the trajectories per second of each
model run one at a time (``simulate``) and as one batch (``simulate_batch``), and the ratios;
``trajectories_per_s_batch_speedup`` is the surrogate's batched rate over the reference's batched
rate at the largest N, ``trajectories_per_s_single_speedup`` the same for one trajectory run alone.
The study is fluidfilm.studies.batch_speed; config conf/batch_speed.yaml.
"""
from fluidfilm.studies import batch_speed
from fluidfilm.workflow.entry import main

if __name__ == "__main__":
    main(batch_speed, "the batched-trajectory speed study")
