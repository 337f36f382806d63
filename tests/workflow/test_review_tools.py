"""The review side: a portable MLflow store, the experiment shown as a model-training experiment, and
the one-command MLflow server (`make mlflow`)."""
from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import mlflow

from fluidfilm.workflow import tracking


def _log_one_run(workspace: Path) -> str:
    cwd = os.getcwd()
    os.chdir(workspace)
    try:
        # an absolute URI: MLflow caches one store per URI string in a process
        cfg = {"uri": f"sqlite:///{workspace / 'mlflow.db'}", "experiment": "fluidfilm", "enabled": True}
        with tracking.run(cfg, "probe") as run:
            Path("note.txt").write_text("artifact")
            mlflow.log_artifact("note.txt")
            return run.info.run_id
    finally:
        os.chdir(cwd)


def test_experiment_is_a_model_training_experiment_with_a_description(tmp_path):
    _log_one_run(tmp_path)
    client = mlflow.tracking.MlflowClient(f"sqlite:///{tmp_path / 'mlflow.db'}")
    exp = client.get_experiment_by_name("fluidfilm")
    assert exp.tags["mlflow.experimentKind"] == "custom_model_development"
    assert "fractions" in exp.tags["mlflow.note.content"]
    assert Path(exp.artifact_location) == (tmp_path / "mlartifacts" / "fluidfilm").resolve()


def test_artifacts_follow_the_workspace_when_it_moves(tmp_path):
    old = tmp_path / "clone"
    old.mkdir()
    run_id = _log_one_run(old)
    new = tmp_path / "moved"
    shutil.move(str(old), str(new))
    uri = f"sqlite:///{new / 'mlflow.db'}"
    assert tracking.relocate_artifacts(uri, new) >= 2  # the experiment and its run
    client = mlflow.tracking.MlflowClient(uri)
    run = client.get_run(run_id)
    assert run.info.artifact_uri.startswith(str(new.resolve()))
    assert [f.path for f in client.list_artifacts(run_id)] == ["note.txt"]
    local = client.download_artifacts(run_id, "note.txt", str(tmp_path))
    assert Path(local).read_text() == "artifact"
    assert tracking.relocate_artifacts(uri, new) == 0  # idempotent


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_mlflow_serve_answers_and_stops_cleanly_on_ctrl_c(tmp_path):
    _log_one_run(tmp_path)
    port = _free_port()
    # SIGINT at its default action in the child, as in a user's terminal: a suite started in the background
    # inherits it ignored, and the server then outlived the Ctrl-C whenever it came before the child's own
    # imports had installed a handler (seen once in a background `make time-tests`; tests/faults/conftest.py)
    proc = subprocess.Popen([sys.executable, "-m", "fluidfilm.workflow.pipeline", "serve", "--port", str(port)], cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        deadline = time.time() + 120
        while time.time() < deadline:
            try:
                body = urllib.request.urlopen(f"http://127.0.0.1:{port}/health", timeout=2).read().decode()
                break
            except OSError:
                time.sleep(1)
        else:
            raise AssertionError("MLflow did not answer within 120 s")
        assert "OK" in body
        api = urllib.request.urlopen(f"http://127.0.0.1:{port}/api/2.0/mlflow/experiments/get-by-name"
                                     "?experiment_name=fluidfilm", timeout=10).read().decode()
        assert "custom_model_development" in api
    finally:
        proc.send_signal(signal.SIGINT)
        out, _ = proc.communicate(timeout=60)
    assert proc.returncode == 0, out[-2000:]
    assert f"http://127.0.0.1:{port}" in out and "MLflow stopped" in out
