"""The MLflow UI as a researcher meets it: ``serve`` prints the runs-table address, and that page, rendered
by a real (headless) browser, shows one row per model with its metrics, and nothing else.

The browser is Debian's ``chromium`` (``.ci/run`` installs it); without it the browser test is skipped
and says why.
"""
from __future__ import annotations

import json
import queue
import re
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import mlflow
import pytest

from fluidfilm.workflow import tracking

MODELS = {"best": {"test_rel_err_median": 0.0125, "test_rel_err_p99": 0.875, "train_time_s": 42.5,
                   "speedup_force_eval_vs_reference": 5.25},
          "paper_single": {"test_rel_err_median": 4.625, "test_rel_err_p99": 210.5, "train_time_s": 17.75,
                           "speedup_force_eval_vs_reference": 8.5}}
HEADLINE = {"speedup_trajectory_best": 7.75, "satisfactory_cases_best": 7, "speedup_trajectory_single": 3.5,
            "satisfactory_cases_single": 0}


def _store(workspace: Path) -> dict:
    """A store with a training run and the per-model summaries, as ``publish_workspace`` writes them."""
    cfg = {"uri": f"sqlite:///{workspace / 'mlflow.db'}", "experiment": "fluidfilm", "enabled": True}
    for name, metrics in MODELS.items():
        folder = workspace / "models" / name
        folder.mkdir(parents=True)
        (folder / "report.json").write_text(json.dumps({"metrics": metrics}))
    with tracking.run(cfg, "training run not in the summary"):
        tracking.log_metric("test_rel_err_median", 0.5)
    tracking.log_model_summaries(cfg, HEADLINE, workspace / "models", ("best", "paper_single", "absent"))
    return cfg


def test_summary_runs_hold_each_models_columns_and_a_new_publish_supersedes_the_old(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the experiment's artifact folder is made in the working directory
    cfg = _store(tmp_path)
    client = mlflow.tracking.MlflowClient(cfg["uri"])
    exp = client.get_experiment_by_name("fluidfilm")
    shown = f"tags.`{tracking.VIEW_TAG}` = '{tracking.SUMMARY_VIEW}'"
    rows = {r.info.run_name: r.data.metrics for r in client.search_runs([exp.experiment_id], shown)}
    assert set(rows) == {"summary/best", "summary/paper_single"}  # no report.json: no row
    assert rows["summary/best"] == {**MODELS["best"], "speedup_trajectory": 7.75, "satisfactory_cases": 7.0}
    assert rows["summary/paper_single"]["speedup_trajectory"] == 3.5
    # the stored view filters on exactly that tag and shows every summary column
    view = json.loads(exp.tags[f"mlflow.sharedViewState.{tracking.SUMMARY_VIEW}"])
    assert view["searchFilter"] == shown
    assert {f"metrics.`{k}`" for k in tracking.SUMMARY_COLUMNS} <= set(view["selectedColumns"])
    first = {r.info.run_id for r in client.search_runs([exp.experiment_id], shown)}
    tracking.log_model_summaries(cfg, HEADLINE, tmp_path / "models", ("best", "paper_single"))
    second = {r.info.run_id for r in client.search_runs([exp.experiment_id], shown)}
    assert len(second) == 2 and not first & second
    old = client.search_runs([exp.experiment_id], f"tags.`{tracking.VIEW_TAG}` = 'superseded'")
    assert {r.info.run_id for r in old} == first  # kept, out of the first view


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _lines(stream, out: queue.Queue) -> None:
    for line in stream:
        out.put(line)


def test_the_printed_runs_table_address_shows_each_model_and_its_metrics_in_a_browser(tmp_path, monkeypatch):
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    if browser is None:
        reason = "chromium not installed (apt-get install chromium; .ci/run installs it): browser check skipped"
        print(reason, file=sys.stderr)
        pytest.skip(reason)
    monkeypatch.chdir(tmp_path)
    _store(tmp_path)
    port = _free_port()
    proc = subprocess.Popen([sys.executable, "-m", "fluidfilm.workflow.pipeline", "serve", "--port", str(port)],
                            cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            start_new_session=True)
    lines: queue.Queue = queue.Queue()
    threading.Thread(target=_lines, args=(proc.stdout, lines), daemon=True).start()
    seen = []
    try:
        deadline = time.time() + 150
        url = None
        while url is None and time.time() < deadline and proc.poll() is None:
            try:
                line = lines.get(timeout=1)
            except queue.Empty:
                continue
            seen.append(line)
            m = re.search(r"one row per model.*?(http://\S+)", line)
            url = m.group(1) if m else None
        assert url is not None, "serve printed no runs-table address:\n" + "".join(seen)[-3000:]
        assert url == f"http://127.0.0.1:{port}/#/experiments/1/runs?viewStateShareKey=summary"
        assert lines.get(timeout=10).rstrip().endswith(f"http://127.0.0.1:{port}/#/experiments/1/runs")  # all runs
        profile = tmp_path / "chromium-profile"
        dom = subprocess.run([browser, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                              "--disable-component-update", "--disable-sync", "--no-first-run",
                              f"--user-data-dir={profile}", "--window-size=2400,1000", "--virtual-time-budget=30000", "--dump-dom", url],
                             capture_output=True, text=True, timeout=180).stdout
        text = re.sub(r"<[^>]+>", " ", dom)  # the rendered text, cells apart
        assert "summary/best" in text and "summary/paper_single" in text, dom[-3000:]
        assert "training run not in the summary" not in text  # the view shows the summaries only
        for column in ("test_rel_err_median", "train_time_s", "speedup_trajectory"):
            assert column in text
        for value in ("0.0125", "42.5", "7.75", "4.625"):
            assert re.search(rf"(?<![\d.]){re.escape(value)}(?![\d.])", text), f"metric value {value} not rendered"
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=60)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
