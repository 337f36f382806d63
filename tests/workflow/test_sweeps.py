"""A Hydra multirun in parallel (joblib) logs its jobs under one MLflow parent run."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import mlflow

ROOT = Path(__file__).resolve().parents[2]


def test_two_job_joblib_multirun_nests_both_runs_under_one_parent(quick_data, tmp_path):
    dataset, testset = quick_data
    uri = f"sqlite:///{tmp_path / 'mlflow.db'}"
    cmd = [sys.executable, "experiments/train_surrogate.py", "-m", "hydra/launcher=joblib", "hydra.launcher.n_jobs=2",
           "seed=0,1", "model=tiny", "trainer=quick", "trainer.max_epochs=2", f"dataset_dir={dataset}",
           f"testset_dir={testset}", f"out_dir={tmp_path / 'models'}", f"checkpoint_dir={tmp_path / 'ckpt'}",
           f"tracking.uri={uri}", "tracking.experiment=sweep-test", f"hydra.sweep.dir={tmp_path / 'multirun'}"]
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    client = mlflow.tracking.MlflowClient(uri)
    exp = client.get_experiment_by_name("sweep-test")
    runs = client.search_runs([exp.experiment_id])
    parents = [r for r in runs if "sweep_dir" in r.data.tags]
    assert len(parents) == 1
    jobs = [r for r in runs if r.data.tags.get("mlflow.parentRunId") == parents[0].info.run_id]
    assert sorted(r.data.tags["model_name"] for r in jobs) == ["tiny-none-standard-s0", "tiny-none-standard-s1"]
    for job in jobs:
        assert "test_rel_err_median" in job.data.metrics
        assert job.data.params["seed"] in ("0", "1")
        networks = [r for r in runs if r.data.tags.get("mlflow.parentRunId") == job.info.run_id]
        assert len(networks) == 1  # one network, its per-epoch losses in a nested run
        assert client.get_metric_history(networks[0].info.run_id, "val_rel_rmse")
    assert (tmp_path / "models" / "tiny-none-standard-s1" / "card.md").exists()


def test_grid_density_sweep_logs_error_and_time_per_evaluation(tmp_path):
    uri = f"sqlite:///{tmp_path / 'mlflow.db'}"
    cmd = [sys.executable, "experiments/grid_sweep.py", "-m", "solver.n_theta=20,40", "solver.n_z=21",
           "converged.n_theta=80", "converged.n_z=81", "timing_calls=20", "timing_repeats=3",
           f"tracking.uri={uri}", "tracking.experiment=grid", f"hydra.sweep.dir={tmp_path / 'multirun'}"]
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    client = mlflow.tracking.MlflowClient(uri)
    runs = client.search_runs([client.get_experiment_by_name("grid").experiment_id])
    jobs = {r.data.tags["mlflow.runName"]: r.data.metrics for r in runs if "mlflow.parentRunId" in r.data.tags}
    assert set(jobs) == {"grid_20x21", "grid_40x21"}
    # the finer grid is closer to the converged one, and both report a time per evaluation
    assert jobs["grid_40x21"]["force_error_pct_eps_0.9"] < jobs["grid_20x21"]["force_error_pct_eps_0.9"]
    assert all(m["time_per_eval_us"] > 0 for m in jobs.values())


def test_swept_values_are_the_jobs_values_of_the_swept_keys_groups_included():
    from fluidfilm.workflow.sweeps import swept_values

    task = ["scaling=standard", "grading.n_per_side=12", "+extra.key=3", "title=ablation", "split=none"]
    assert swept_values(task, ["scaling", "split", "extra.key"]) == {"scaling": "standard", "extra.key": "3",
                                                                     "split": "none"}
    assert swept_values(task, []) == {}
