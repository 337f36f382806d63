"""Issue 51, item 4: a value outside the range its config group's schema states is refused in one line before
any work (no MLflow run is created), and a multirun says where its jobs wrote and ends with a summary table."""
from __future__ import annotations

import csv

import pytest
from omegaconf import OmegaConf

from .conftest import run_entry

# the cheapest study with a solver group and an MLflow run per job
CHEAP_GRID = ("converged.n_theta=40", "converged.n_z=21", "timing_calls=1", "timing_repeats=1",
              "eccentricities=[0.5]")


@pytest.mark.parametrize("override, named", [
    ("solver.n_theta=2", "'solver.n_theta=2': must be >= 8"),
    ("solver.n_theta=-5", "'solver.n_theta=-5': must be >= 8"),
    ("solver.n_z=1", "'solver.n_z=1': must be >= 4"),
    ("solver.cavitation=gumble", "'solver.cavitation=gumble': must be one of gumbel, swift-stieber, none"),
    ("bearing.viscosity=-0.01", "viscosity must be a positive finite number, got -0.01"),
])
def test_a_value_out_of_range_is_one_line_before_any_mlflow_run(tmp_path, override, named):
    db = tmp_path / "mlflow.db"
    proc = run_entry("grid_sweep", override, *CHEAP_GRID, f"tracking.uri=sqlite:///{db}",
                     f"hydra.run.dir={tmp_path / 'run'}")
    assert proc.returncode == 2, proc.stderr[-2000:]
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr  # one line, no traceback
    assert lines[0].startswith("error: configuration refused before any work: ")
    assert named in lines[0]
    assert not db.exists()  # no MLflow store opened, so no run created (FAILED or otherwise)
    assert "force_error" not in proc.stdout  # the study never ran


@pytest.mark.parametrize("group, node, named", [
    ("solver", {"n_theta": 30, "n_z": 30, "cavitation": "gumbel"}, None),
    ("solver", {"n_theta": 30, "n_z": 30, "cavitation": "${oc.env:X}"}, None),  # resolved later: not judged
    ("reference", {"coarse": [30, 3], "dense": [60, 60], "eps_threshold": 0.5, "cavitation": "gumbel"},
     "'reference.coarse=[30, 3]': n_z=3 is below the scheme's minimum 4"),
    ("reference", {"coarse": [30, 30], "dense": [60, 60], "eps_threshold": 1.5, "cavitation": "gumbel"},
     "'reference.eps_threshold=1.5': must be < 1"),
    ("rotor", {"mass": -5.0, "load_share": 0.5, "gravity": 9.81, "imbalance_direction": 1},
     "'rotor.mass=-5.0': must be > 0"),
    ("rotor", {"mass": 5.0, "load_share": 0.5, "gravity": 9.81, "imbalance_direction": 2},
     "'rotor.imbalance_direction=2': must be one of 1, -1"),
    ("integrator", {"dt": 0.0, "t_end": 0.5, "t_settle": 0.4, "eps_stop": 0.98, "eps_substep": 0.8,
                    "record_every": 10}, "'integrator.dt=0.0': must be > 0"),
    ("split", {"boundaries": [0.5, 1.2], "blend_width": 0.0}, "'split.boundaries=[0.5, 1.2]': element 1 (1.2)"),
    ("model", {"width": 64, "depth": 1, "activation": "tahn", "optimizer": "adam", "lr": 1e-3,
               "weight_decay": 0.0, "scheduler": "cosine"}, "'model.activation=tahn': must be one of tanh"),
    ("trainer", {"max_epochs": 0, "max_time": None, "batch_size": 128, "val_fraction": 0.1,
                 "target_val_rel_rmse": None, "accelerator": "cpu", "progress_bar": False, "workers": None},
     "'trainer.max_epochs=0': must be >= 1"),
    ("trainer", {"max_epochs": 1, "max_time": None, "batch_size": 128, "val_fraction": float("nan"),
                 "target_val_rel_rmse": None, "accelerator": "cpu", "progress_bar": False, "workers": None},
     "'trainer.val_fraction=nan': must be a finite number"),
])
def test_schema_ranges_name_the_key_and_the_value(group, node, named):
    from fluidfilm.workflow.config_schema import SchemaError, validate_group

    if named is None:
        assert validate_group(group, OmegaConf.create(node)) is not None
    else:
        with pytest.raises(SchemaError) as err:
            validate_group(group, node)
        assert named in str(err.value)
        assert "\n" not in str(err.value)


def test_a_dataset_section_out_of_range_names_its_index():
    from fluidfilm.workflow.config_schema import SchemaError, validate_group

    pos = {"name": "a", "eps_start": 0.0, "eps_stop": 0.9, "endpoint": False, "n_eps": 0, "n_angle": 8}
    vel = {"eps_low": 0.0, "eps_high": 1.0, "v_max": 0.1, "core": 0.03, "core_fraction": 0.6, "n_per_side": 4}
    node = {"name": "d", "position_sections": [pos], "velocity_sections": [vel], "combine": "product",
            "positions_per_chunk": 4, "n_test": 10, "test_seed": 0}
    with pytest.raises(SchemaError, match=r"'dataset.position_sections\[0\].n_eps=0': must be >= 1"):
        validate_group("dataset", node)


def test_the_schema_names_are_the_libraries():
    """The choices the schema states are exactly what the code accepts (written twice only where the
    library's module imports torch)."""
    from fluidfilm.reynolds.solver import CAVITATION_MODELS
    from fluidfilm.surrogate import training
    from fluidfilm.workflow import config_schema as cs

    assert cs.MODEL_ACTIVATIONS == tuple(training._ACT)
    assert cs.MODEL_STRUCTURES == tuple(training.STRUCTURES)
    assert cs._CAVITATION == tuple(CAVITATION_MODELS)


def test_a_multirun_says_where_its_jobs_wrote_and_writes_one_summary_row_per_job(tmp_path):
    db, sweep = tmp_path / "mlflow.db", tmp_path / "sweep"
    proc = run_entry("grid_sweep", "-m", "solver.n_theta=20,24", "solver.n_z=9", *CHEAP_GRID,
                     f"tracking.uri=sqlite:///{db}", f"hydra.sweep.dir={sweep}", check=True)
    assert f"each job writes under {sweep}/<job number>/" in proc.stdout
    assert f"job 0: {sweep / '0'}" in proc.stdout and f"job 1: {sweep / '1'}" in proc.stdout
    assert f"summary (overrides and metrics per job): {sweep / 'summary.csv'}" in proc.stdout
    with open(sweep / "summary.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [r["job"] for r in rows] == ["0", "1"]
    assert [r["solver.n_theta"] for r in rows] == ["20", "24"]
    assert all(r["solver.n_z"] == "9" and r["tracking.uri"] == f"sqlite:///{db}" for r in rows)
    # the metrics each job logged to MLflow, in its row
    import mlflow

    client = mlflow.tracking.MlflowClient(f"sqlite:///{db}")
    runs = client.search_runs([client.get_experiment_by_name("fluidfilm").experiment_id])
    logged = {r.data.tags["mlflow.runName"]: r.data.metrics for r in runs if "mlflow.parentRunId" in r.data.tags}
    for row, name in zip(rows, ("grid_20x9", "grid_24x9")):
        assert float(row["force_error_pct_eps_0.5"]) == logged[name]["force_error_pct_eps_0.5"]
        assert float(row["time_per_eval_us"]) > 0


def test_a_sweep_with_one_bad_job_is_refused_before_its_parent_run(tmp_path):
    """Every job of a multirun is checked before the sweep's MLflow parent run is created or any job starts."""
    db, sweep = tmp_path / "mlflow.db", tmp_path / "sweep"
    proc = run_entry("grid_sweep", "-m", "solver.n_theta=30,2", *CHEAP_GRID, f"tracking.uri=sqlite:///{db}",
                     f"hydra.sweep.dir={sweep}")
    assert proc.returncode == 2, proc.stderr[-2000:]
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "'solver.n_theta=2': must be >= 8" in lines[0], proc.stderr
    assert "sweep job: solver.n_theta=2" in lines[0]
    assert not db.exists() and "Launching" not in proc.stdout  # no parent run, no job started
