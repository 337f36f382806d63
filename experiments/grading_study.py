"""The grading study: generate (or reuse) the dataset of one grading, train a surrogate on it, evaluate it.

    python experiments/grading_study.py -m grading.n_per_side=8,16,24 grading.n_angle=24,48
    python experiments/grading_study.py -m scaling=physics_whirl,standard split=five_blend,none
Each job writes result.json in its Hydra output folder and logs a run to MLflow (nested under the
sweep's run); when the multirun ends, fluidfilm.studies.grading_study.SweepSummaryCallback writes the sweep's
summary.json, table.csv and figure.png (to summary_dir, or the sweep's folder).
"""
import os
import shutil
from pathlib import Path

import hydra
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig, OmegaConf

from fluidfilm import io
from fluidfilm.workflow import sweeps
from fluidfilm.workflow import tracking
from fluidfilm.workflow.config import bearing_from_cfg, reference_from_cfg
from fluidfilm.workflow.config_check import check_config
from fluidfilm.data import DatasetSpec, load_test_set
from fluidfilm.data.spec import check_reference
from fluidfilm.studies.grading_study import (SWEEP_ID_ENV, Judges, OrbitBenchmark, StiffnessBenchmark, apply_grading, cached_dataset,
                               flat_metrics)
from fluidfilm.reynolds import ReynoldsSolver
from fluidfilm.surrogate.fit import fit_surrogate, training_digest


@hydra.main(config_path="../conf", config_name="grading_study", version_base="1.3")
def main(cfg: DictConfig) -> dict:
    check_config(cfg)  # a mistyped value or an unknown key is refused here, before any work
    hc = HydraConfig.get()
    keys = os.environ.get(sweeps.SWEEP_KEYS_ENV)  # set by the sweep callback in the launching process
    swept = sweeps.swept_values(hc.overrides.task, keys.split(",") if keys else [])
    name = ",".join(f"{k}={v}" for k, v in swept.items()) or "single"
    c = OmegaConf.to_container(cfg, resolve=True)
    # everything is checked, and what the surrogate is judged on is read or computed, before the long work
    bearing = bearing_from_cfg(cfg.bearing)
    reference_policy = check_reference(c["reference"])
    spec = DatasetSpec.from_cfg(apply_grading(c["dataset"], c["grading"]))
    cases = {k: cfg.cases[k] for k in sorted(cfg.cases)}
    judges = Judges(held_out=load_test_set(cfg.testset_dir),
                    orbits=OrbitBenchmark.from_dir(reference_from_cfg(bearing, cfg.reference),
                                                   cfg.reference_trajectories_dir, cases),
                    stiffness=(StiffnessBenchmark.from_reference(ReynoldsSolver(bearing, *cfg.kc_reference_grid),
                                                                 cfg.kc_eps) if cfg.kc_eps else None),
                    rotor=cfg.rotor, cases=cases, integrator=cfg.integrator, threshold_pct=cfg.metrics.threshold_pct,
                    floor_N=cfg.error_floor_N, evaluate_cases=cfg.evaluate_cases)
    print(f"job {name}: {spec.n_samples(bearing.clearance):,} samples planned", flush=True)
    with tracking.run(cfg.tracking, f"grading {name}", c, tags={"study": cfg.title}):
        path, meta, reused = cached_dataset(bearing, reference_policy, spec, cfg.cache_dir, scheduler=cfg.dask.scheduler,
                                            n_workers=cfg.dask.n_workers, progress=cfg.progress)
        digest = training_digest(c["model"], c["split"], c["scaling"], c["trainer"], c["seed"], path.name)
        model, report = fit_surrogate(path, c["model"], c["split"], c["scaling"], c["trainer"], None, seed=cfg.seed,
                                      name=name, ckpt_root=Path(cfg.checkpoint_dir) / digest,
                                      val_fraction=cfg.trainer.val_fraction, batch_size=cfg.trainer.batch_size,
                                      workers=cfg.trainer.workers)
        result = {
            "job": name, "swept": swept, "sweep_id": os.environ.get(SWEEP_ID_ENV), "grading": c["grading"],
            "dataset": {"n_samples": int(meta["n_samples"]), "generation_s": float(meta["generation_seconds_total"]),
                        "reused": reused, "path": str(path), "spec": spec.to_dict()},
            "training": {"train_time_s": report["train_time_s"], "epochs": c["trainer"]["max_epochs"],
                         "networks": report["networks"]},
            **judges.judge(model),
            "config": {k: c[k] for k in ("model", "split", "scaling", "trainer", "seed")},
        }
        io.write_json(Path(hc.runtime.output_dir) / "result.json", result)
        # the checkpoint is there to resume an interrupted job, not to skip the training of a later one
        shutil.rmtree(Path(cfg.checkpoint_dir) / digest, ignore_errors=True)
        row = flat_metrics(result)
        tracking.log_metrics({k: float(v) for k, v in row.items() if v is not None})
    print(f"job {name}: {row['n_samples']:,} samples ({'cached' if reused else 'made'} in {row['generation_s']:.1f} s), "
          f"trained {row['train_time_s']:.0f} s; held-out median {100 * row['held_out_rel_err_median']:.2f} %, "
          f"p99 {100 * row['held_out_rel_err_p99']:.1f} %; along the orbits median "
          f"{100 * row['orbit_states_rel_err_median']:.2f} %, p99 {100 * row['orbit_states_rel_err_p99']:.1f} %"
          + (f", {row['n_satisfactory']}/7 cases" if "n_satisfactory" in row else ""), flush=True)
    return row


if __name__ == "__main__":
    io.run_interruptible(main, "the grading study", "run the same command again; cached datasets are reused and "
                         "each network resumes from its last epoch checkpoint (checkpoint_dir)")
