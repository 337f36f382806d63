"""The whole comparison pipeline on the quick profile, end to end, and the review notebook on its outputs.

The same entry points as `dvc repro`, with overrides that point them at the
quick dataset, tiny networks, short trajectories and a temporary directory.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient

ROOT = Path(__file__).resolve().parents[1]


def run(script, *overrides):
    proc = subprocess.run([sys.executable, f"experiments/{script}", *overrides], cwd=ROOT, capture_output=True,
                          text=True, timeout=900)
    assert proc.returncode == 0, f"{script} failed:\n{proc.stderr[-4000:]}"
    return proc.stdout


@pytest.fixture(scope="module")
def quick_pipeline(quick_data, tmp_path_factory):
    dataset, testset = quick_data
    tmp = tmp_path_factory.mktemp("pipeline")
    uri = f"sqlite:///{tmp / 'mlflow.db'}"
    common = [f"dataset_dir={dataset}", f"testset_dir={testset}", f"out_dir={tmp / 'models'}",
              f"checkpoint_dir={tmp / 'ckpt'}", f"tracking.uri={uri}", "trainer=quick", "trainer.max_epochs=20",
              "model=tiny"]
    for exp in ("paper_single", "paper_split", "best"):
        # (the quick grid has no positions in some of best's five regions: three regions there)
        extra = ["split=paper_blend"] if exp == "best" else []
        run("train_surrogate.py", f"experiment={exp}", *common, *extra)
    reports = tmp / "reports"
    run("train_time.py", f"dataset_dir={dataset}", "seeds=[0,1]", "trainer=quick", "trainer.max_epochs=5",
        "studies.paper_setup.target_val_rel_rmse=0.95", "studies.physics_scaling.target_val_rel_rmse=0.9", "model=tiny", f"out={reports / 'train_time.json'}", f"tracking.uri={uri}")
    models = tmp / "models"
    run("compare.py", f"models.single={models / 'paper_single'}", f"models.split={models / 'paper_split'}",
        f"models.best={models / 'best'}", "integrator.t_end=0.06", "integrator.t_settle=0.04", "timing_repeats=1",
        "force_eval_states=500", f"out_dir={tmp / 'traj'}", f"figure_dir={reports / 'figures'}",
        f"report_dir={reports}", f"tracking.uri={uri}")
    # the active conical bearing: sleeve dataset, surrogate, DQN on it, evaluation on the reference
    active_ds, active_ts = tmp / "active_dataset", tmp / "active_testset"
    run("make_dataset.py", "bearing=conical", "reference=conical", "dataset=active_quick", f"out_dir={active_ds}",
        f"test_dir={active_ts}", "dask.scheduler=inline", "progress=false")
    run("train_surrogate.py", "experiment=active", f"dataset_dir={active_ds}", f"testset_dir={active_ts}",
        f"out_dir={models}", f"checkpoint_dir={tmp / 'ckpt'}", f"tracking.uri={uri}", "trainer=quick",
        "trainer.max_epochs=10", "model=tiny")
    control = [f"surrogate_dir={models / 'active'}", f"agent_path={models / 'dqn_active.zip'}",
               "controller=quick", f"tracking.uri={uri}"]
    run("train_controller.py", *control, f"training_report={reports / 'dqn_training.json'}")
    run("evaluate_control.py", *control, f"out_json={reports / 'control.json'}", f"figures_dir={reports / 'figures'}")
    run("report.py", f"report_dir={reports}", f"models_dir={models}", f"dataset_dir={dataset}", f"tracking.uri={uri}",
        f"active_dataset_dir={active_ds}")
    return tmp, uri


def test_pipeline_writes_every_headline_number(quick_pipeline):
    tmp, _ = quick_pipeline
    metrics = json.loads((tmp / "reports" / "metrics.json").read_text())
    for key in ("train_time_single_s", "train_time_split_s", "train_time_reduction_pct", "speedup_trajectory_single",
                "speedup_trajectory_split", "speedup_force_eval"):
        assert isinstance(metrics[key], float), key
    for case in "abcdefg":
        assert f"orbit_rms_pct_single_{case}" in metrics and f"orbit_rms_pct_split_{case}" in metrics
    md = (tmp / "reports" / "paper_comparison.md").read_text()
    assert "| training time reduction, split vs single | 26 % |" in md
    assert (tmp / "reports" / "figures" / "fig4_comparison.png").stat().st_size > 10_000
    assert metrics["speedup_trajectory_split"] > 0
    assert isinstance(metrics["controller_amplitude_reduction_pct"], float)
    assert metrics["active_dataset_samples"] == (7 * 12 - 11) * 81 * 3  # 7 rings x 12 angles, the centre once; 81 pairs; 3 sleeves
    for panel in ("a_dqn", "b_none", "c_mpc"):
        assert (tmp / "reports" / "figures" / f"fig5_{panel}.png").stat().st_size > 10_000
    assert "Active conical bearing" in md


def test_review_notebook_runs_on_the_quick_profile(quick_pipeline):
    tmp, uri = quick_pipeline
    nb = nbformat.read(ROOT / "notebooks" / "review.ipynb", as_version=4)
    env = {"FLUIDFILM_REPORT_DIR": str(tmp / "reports"), "FLUIDFILM_MLFLOW_URI": uri}
    old = {k: os.environ.get(k) for k in env}
    os.environ.update(env)
    try:
        NotebookClient(nb, timeout=300, kernel_name="python3",
                       resources={"metadata": {"path": str(ROOT / "notebooks")}}).execute()
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])]
    assert not [o for o in outputs if o.get("output_type") == "error"]
    assert any("train_time_reduction_pct" in json.dumps(o) for o in outputs)
