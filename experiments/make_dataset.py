"""Graded dataset (data/dataset/) and held-out test set (data/testset/) with the reference model.

    python experiments/make_dataset.py                      # the paper's layout
    python experiments/make_dataset.py dataset=quick        # seconds
    python experiments/make_dataset.py dask.scheduler=tcp://host:8786
Interrupt it at any time; running it again continues from the finished chunks.
"""
import hydra
from omegaconf import DictConfig, OmegaConf

from fluidfilm import io
from fluidfilm.workflow.config import bearing_from_cfg
from fluidfilm.data import DatasetSpec, generate_dataset, random_test_set
from fluidfilm.data.spec import check_reference
from fluidfilm.workflow.config_check import check_config


@hydra.main(config_path="../conf", config_name="make_dataset", version_base="1.3")
def main(cfg: DictConfig) -> None:
    check_config(cfg)  # a mistyped value or an unknown key is refused here, before any work
    # the whole config is checked, naming a bad key, before any output is touched
    spec = DatasetSpec.from_cfg(cfg.dataset)
    bearing = bearing_from_cfg(cfg.bearing)
    reference = OmegaConf.to_container(cfg.reference, resolve=True)
    check_reference(reference)
    print(f"dataset {cfg.dataset.name}: {spec.n_samples(bearing.clearance):,} samples planned")
    meta = generate_dataset(bearing, reference, spec, cfg.out_dir, scheduler=cfg.dask.scheduler,
                            n_workers=cfg.dask.n_workers, progress=cfg.progress,
                            config=OmegaConf.to_container(cfg, resolve=True))
    print(f"{meta['n_samples']:,} samples in {cfg.out_dir} ({meta['seconds_this_run']:.1f} s in this run for "
          f"{meta['chunks_computed_this_run']} of {meta['n_chunks']} chunks; "
          f"{meta['generation_seconds_total']:.1f} s over all runs)")
    test = random_test_set(bearing, reference, spec, cfg.test_dir)
    print(f"{test['n_samples']:,} held-out samples in {cfg.test_dir}")


if __name__ == "__main__":
    io.run_interruptible(main, "dataset generation", "run the same command again; it continues from the "
                         "finished chunks")
