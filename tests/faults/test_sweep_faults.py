"""Items 3, 4, 11: sweep jobs apart, MLflow runs ended honestly, Ctrl-C in one line."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import mlflow
import pytest

from fluidfilm import paper_bearing
from fluidfilm.data import DatasetSpec, generate_dataset, random_test_set

from .conftest import REFERENCE, ROOT, interruptible, quick_cfg, run_entry


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    root = tmp_path_factory.mktemp("sweep_data")
    spec = DatasetSpec.from_cfg(quick_cfg())
    generate_dataset(paper_bearing(), REFERENCE, spec, root / "dataset", scheduler="inline", progress=False)
    random_test_set(paper_bearing(), REFERENCE, spec, root / "testset", n=100)
    return root


def _args(data, tmp_path, *extra):
    return ["model=tiny", "trainer=quick", "trainer.max_epochs=1", "trainer.batch_size=512",
            f"dataset_dir={data / 'dataset'}", f"testset_dir={data / 'testset'}", f"out_dir={tmp_path / 'models'}",
            f"checkpoint_dir={tmp_path / 'ckpt'}", f"tracking.uri=sqlite:///{tmp_path / 'mlflow.db'}",
            "tracking.experiment=faults", f"hydra.sweep.dir={tmp_path / 'multirun'}", *extra]


def _runs(tmp_path):
    client = mlflow.tracking.MlflowClient(f"sqlite:///{tmp_path / 'mlflow.db'}")
    exp = client.get_experiment_by_name("faults")
    runs = client.search_runs([exp.experiment_id])
    parents = [r for r in runs if "sweep_dir" in r.data.tags]
    assert len(parents) == 1
    jobs = [r for r in runs if r.data.tags.get("mlflow.parentRunId") == parents[0].info.run_id]
    return parents[0], {r.data.tags.get("model_name"): r for r in jobs}


def test_sweep_over_a_plain_key_gives_each_job_its_own_folder_and_run_name(data, tmp_path):
    proc = run_entry("train_surrogate", "-m", "model.width=4,6", *_args(data, tmp_path))
    assert proc.returncode == 0, proc.stderr[-3000:]
    names = ["tiny-none-standard-s0-model.width=4", "tiny-none-standard-s0-model.width=6"]
    parent, jobs = _runs(tmp_path)
    assert sorted(jobs) == names and parent.info.status == "FINISHED"
    assert sorted(r.info.run_name for r in jobs.values()) == names
    import json

    for n, width in zip(names, (4, 6)):
        report = json.loads((tmp_path / "models" / n / "report.json").read_text())
        assert report["config"]["model"]["width"] == width  # not overwritten by the other job
        assert jobs[n].info.status == "FINISHED"


def test_failed_sweep_job_ends_its_run_and_the_parent_as_failed(data, tmp_path):
    # a value the schemas cannot judge (Lightning's accelerator names), so the job fails while it runs (an
    # unknown activation is now refused, with the whole sweep, before it starts: test_config_range_faults.py)
    proc = run_entry("train_surrogate", "-m", "trainer.accelerator=cpu,bogus", *_args(data, tmp_path))
    assert proc.returncode != 0
    parent, jobs = _runs(tmp_path)
    assert parent.info.status == "FAILED"
    by_acc = {r.data.params["trainer.accelerator"]: r.info.status for r in jobs.values()}
    assert by_acc == {"cpu": "FINISHED", "bogus": "FAILED"}
    assert (tmp_path / "models" / "tiny-none-standard-s0-trainer.accelerator=cpu" / "card.md").exists()


def test_sweep_refuses_to_write_a_dvc_tracked_output(data, tmp_path):
    target = ROOT / "models" / "best"
    before = sorted(p.name for p in target.iterdir()) if target.exists() else None
    args = [a for a in _args(data, tmp_path) if not a.startswith("out_dir=")]
    proc = run_entry("train_surrogate", "-m", "seed=0,1", "name=best", "out_dir=models", *args)
    assert proc.returncode != 0
    assert "output of the DVC pipeline" in proc.stderr + proc.stdout
    assert (sorted(p.name for p in target.iterdir()) if target.exists() else None) == before


def _ctrl_c_training(argv, ckpt_dir, checkpoints: int, settle_s: float = 0.0, group: bool = False) -> None:
    """Start ``train_surrogate.py argv``, Ctrl-C it once ``checkpoints`` epoch checkpoints exist, and check
    that it ends as an interrupted run must: exit 130, no traceback, one last line saying how to resume.
    ``group``: the SIGINT goes to the whole process group, workers included, as a terminal's Ctrl-C does."""
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    proc = subprocess.Popen([sys.executable, "experiments/train_surrogate.py", *argv], cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=interruptible,
                            start_new_session=group)
    deadline = time.time() + 300
    while time.time() < deadline and len(list(Path(ckpt_dir).rglob("last.ckpt"))) < checkpoints:
        time.sleep(0.05)
    time.sleep(settle_s)
    if group:
        os.killpg(proc.pid, signal.SIGINT)
    else:
        proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err[-3000:]
    assert "Traceback" not in err
    last = [line for line in err.splitlines() if line.strip()][-1]
    assert last.startswith("interrupted: surrogate training") and "run the same command again" in last


def test_ctrl_c_in_a_sweep_is_one_line_and_the_runs_end_killed(data, tmp_path):
    args = _args(data, tmp_path, "trainer.max_epochs=500")
    _ctrl_c_training(["-m", "seed=0,1", *args], tmp_path / "ckpt", checkpoints=1, settle_s=0.5)
    parent, jobs = _runs(tmp_path)
    assert parent.info.status == "KILLED"
    assert [r.info.status for r in jobs.values()] == ["KILLED"]
    assert not (tmp_path / "models").exists()  # no half-written model folder


def test_submitit_route_two_job_sweep_lands_as_one_parent_with_two_children(data, tmp_path):
    """Item 14: the SLURM launcher's family run locally (``submitit_local``): each job a separate process."""
    proc = run_entry("train_surrogate", "-m", "hydra/launcher=submitit_local", "hydra.launcher.timeout_min=20",
                     "seed=0,1", *_args(data, tmp_path), timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    parent, jobs = _runs(tmp_path)
    assert parent.info.status == "FINISHED"
    assert sorted(jobs) == ["tiny-none-standard-s0", "tiny-none-standard-s1"]
    assert all(r.info.status == "FINISHED" and "test_rel_err_median" in r.data.metrics for r in jobs.values())
    # each job ran in its own process with its own Hydra output folder, and wrote its own model
    job_dirs = sorted(p.parent.parent for p in (tmp_path / "multirun").rglob(".hydra/config.yaml"))
    assert [p.name for p in job_dirs] == ["0", "1"]
    assert list((tmp_path / "multirun" / ".submitit").iterdir())  # submitit's own job records
    for n in jobs:
        assert (tmp_path / "models" / n / "card.md").exists()


def test_ctrl_c_of_a_split_training_in_worker_processes_is_one_line_and_resumes_to_the_same_weights(data, tmp_path):
    """The split model's networks train in worker processes (``trainer.workers=2``); Ctrl-C reaches the
    job, which stops the workers, ends every MLflow run KILLED and says so in one line; the same command
    then resumes each network from its checkpoint and ends with the weights of a run never interrupted."""
    import numpy as np

    def args(root):
        return [*_args(data, root, "split=paper", "trainer.max_epochs=12", "trainer.workers=2"), "name=split"]

    stopped = tmp_path / "stopped"
    _ctrl_c_training(args(stopped), stopped / "ckpt", checkpoints=2)
    client = mlflow.tracking.MlflowClient(f"sqlite:///{stopped / 'mlflow.db'}")
    runs = client.search_runs([client.get_experiment_by_name("faults").experiment_id])
    job = [r for r in runs if "mlflow.parentRunId" not in r.data.tags]
    networks = [r for r in runs if "mlflow.parentRunId" in r.data.tags]
    assert [r.info.status for r in job] == ["KILLED"] and len(networks) == 3
    # a network that finished before the interrupt is FINISHED; the others, running or not yet started, KILLED
    statuses = [r.info.status for r in networks]
    assert set(statuses) <= {"KILLED", "FINISHED"} and "KILLED" in statuses
    assert not (stopped / "models").exists()
    resumed = run_entry("train_surrogate", *args(stopped))
    assert resumed.returncode == 0, resumed.stderr[-3000:]
    whole = run_entry("train_surrogate", *args(tmp_path / "whole"))
    assert whole.returncode == 0, whole.stderr[-3000:]
    a, b = (np.load(root / "models" / "split" / "surrogate.npz") for root in (stopped, tmp_path / "whole"))
    assert sorted(a.files) == sorted(b.files)
    for key in a.files:
        np.testing.assert_array_equal(a[key], b[key], err_msg=key)


def test_workers_of_a_killed_split_training_stop_with_it(data, tmp_path):
    """``kill -9`` of the job gives it no chance to stop its workers; they notice within seconds and end,
    instead of training on beside the rerun."""
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    proc = subprocess.Popen([sys.executable, "experiments/train_surrogate.py", "name=split",
                             *_args(data, tmp_path, "split=paper", "trainer.max_epochs=500", "trainer.workers=2")],
                            cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 300
    while time.time() < deadline and len(list((tmp_path / "ckpt").rglob("last.ckpt"))) < 2:
        time.sleep(0.05)
    try:
        workers = []
        for pid in subprocess.run(["pgrep", "-P", str(proc.pid)], capture_output=True, text=True).stdout.split():
            try:
                if "popen_loky" in Path(f"/proc/{pid}/cmdline").read_bytes().decode(errors="replace"):
                    workers.append(int(pid))
            except FileNotFoundError:  # a helper process that ended meanwhile
                pass
        assert len(workers) == 2
    finally:
        proc.kill()
        proc.wait()
    deadline = time.time() + 20
    while time.time() < deadline and any(Path(f"/proc/{pid}").exists() for pid in workers):
        time.sleep(0.2)
    alive = [pid for pid in workers if Path(f"/proc/{pid}").exists()]
    for pid in alive:  # do not leave them to the rest of the suite
        os.kill(pid, signal.SIGKILL)
    assert not alive
