"""Graded dataset (data/dataset/) and held-out test set (data/testset/) with the reference model
(``experiments/make_dataset.py``)."""
from __future__ import annotations

from fluidfilm.data import DatasetSpec, generate_dataset, random_test_set
from fluidfilm.data.spec import check_reference
from fluidfilm.workflow.config import bearing_from_cfg
from fluidfilm.workflow.entry import plain

OUTPUTS = {"out_dir": [""], "test_dir": [""]}


def run(cfg) -> None:
    # the whole config is checked, naming a bad key, before any output is touched
    spec = DatasetSpec.from_cfg(cfg.dataset)
    bearing = bearing_from_cfg(cfg.bearing)
    reference = plain(cfg)["reference"]
    check_reference(reference)
    print(f"dataset {cfg.dataset.name}: {spec.n_samples(bearing.clearance):,} samples planned")
    meta = generate_dataset(bearing, reference, spec, cfg.out_dir, scheduler=cfg.dask.scheduler,
                            n_workers=cfg.dask.n_workers, progress=cfg.progress, config=plain(cfg))
    print(f"{meta['n_samples']:,} samples in {cfg.out_dir} ({meta['seconds_this_run']:.1f} s in this run for "
          f"{meta['chunks_computed_this_run']} of {meta['n_chunks']} chunks; "
          f"{meta['generation_seconds_total']:.1f} s over all runs)")
    test = random_test_set(bearing, reference, spec, cfg.test_dir)
    print(f"{test['n_samples']:,} held-out samples in {cfg.test_dir}")
