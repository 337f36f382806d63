"""Items 11, 13: Ctrl-C of the dataset run; the Dask route as a cluster user runs it, with a worker lost."""
from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

from fluidfilm import paper_bearing
from fluidfilm.data import DatasetSpec, generate_dataset, verify_dataset

from .conftest import REFERENCE, ROOT, interruptible, quick_cfg

ENV = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
DASK = str(Path(sys.executable).parent / "dask")


def _frame(path):
    return pd.read_parquet(path).sort_values(["X1", "X2", "V1", "V2"], kind="stable").reset_index(drop=True)


@pytest.fixture(scope="module")
def inline(tmp_path_factory):
    """The quick dataset made inline, in this process: the truth the other routes must equal."""
    out = tmp_path_factory.mktemp("inline") / "dataset"
    generate_dataset(paper_bearing(), REFERENCE, DatasetSpec.from_cfg(quick_cfg()), out, scheduler="inline",
                     progress=False)
    return _frame(out)


def _make_dataset(tmp_path, *overrides, **kw):
    return subprocess.Popen([sys.executable, "experiments/make_dataset.py", "dataset=quick", "progress=false",
                             "dataset.positions_per_chunk=1", "dataset.n_test=50", f"out_dir={tmp_path / 'dataset'}",
                             f"test_dir={tmp_path / 'testset'}", *overrides], cwd=ROOT, env=ENV,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=interruptible, **kw)


def _wait_parts(directory: Path, n: int, proc, timeout=300):
    deadline = time.time() + timeout
    while time.time() < deadline and proc.poll() is None and len(list(directory.glob("part-*.parquet"))) < n:
        time.sleep(0.01)


def test_ctrl_c_of_the_dataset_run_is_one_line_and_resumes_to_the_same_data(tmp_path, inline):
    proc = _make_dataset(tmp_path, "dask.scheduler=inline")
    _wait_parts(tmp_path / "dataset", 3, proc)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err[-2000:]
    assert "Traceback" not in err
    lines = [line for line in err.splitlines() if line.strip()]
    assert lines[-1].startswith("interrupted: dataset generation") and "run the same command again" in lines[-1]
    ds = tmp_path / "dataset"
    assert not (ds / "_metadata.json").exists() and not list(ds.glob(".part-*"))  # complete parts or none
    n_done = len(list(ds.glob("part-*.parquet")))
    # a part is trusted once its checksum is in _state.json; Ctrl-C between writing the last part and
    # recording it leaves that one part to be recomputed (said in one line), never trusted unchecked
    n_recorded = len(json.loads((ds / "_state.json").read_text())["parts"])
    assert n_done - n_recorded in (0, 1)
    proc = _make_dataset(tmp_path, "dask.scheduler=inline")
    out, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err[-2000:]
    n = len(DatasetSpec.from_cfg(quick_cfg()).positions(120e-6)[0])  # one position per chunk here
    assert f"for {n - n_recorded} of {n} chunks" in out  # only what was missing, and the time of this run
    assert ("have no recorded checksum" in out) == (n_done > n_recorded)
    verify_dataset(ds)
    pd.testing.assert_frame_equal(_frame(ds), inline, check_exact=True)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def cluster(tmp_path):
    """A `dask scheduler` and two `dask worker` processes started separately, as on a cluster."""
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    logs = open(tmp_path / "cluster.log", "w")
    procs = [subprocess.Popen([DASK, "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
                              env=ENV, stdout=logs, stderr=logs, cwd=tmp_path)]
    time.sleep(2)
    for k in range(2):
        # no nanny: killing the worker's process loses the worker for good (nothing restarts it)
        procs.append(subprocess.Popen([DASK, "worker", address, "--nthreads", "1", "--no-nanny", "--no-dashboard",
                                       "--name", f"w{k}"], env=ENV, stdout=logs, stderr=logs, cwd=tmp_path))
    from dask.distributed import Client

    with Client(address, timeout=120) as client:
        client.wait_for_workers(2, timeout=120)
    yield address, procs
    for p in reversed(procs):  # workers first, so none waits to reconnect to a scheduler that is gone
        if p.poll() is None:
            p.terminate()
        try:
            p.wait(timeout=10)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait()
    logs.close()


@pytest.mark.parametrize("kill_a_worker", [False, True], ids=["two_workers", "one_worker_killed"])
def test_dask_route_on_a_separately_started_cluster_equals_the_inline_run(tmp_path, inline, cluster, kill_a_worker):
    address, procs = cluster
    proc = _make_dataset(tmp_path, f"dask.scheduler={address}")
    if kill_a_worker:
        _wait_parts(tmp_path / "dataset", 5, proc)
        assert proc.poll() is None, "the run ended before the kill; make it longer"
        os.kill(procs[1].pid, signal.SIGKILL)  # lost mid-run: Dask reschedules its tasks on the other
    out, err = proc.communicate(timeout=600)
    assert proc.returncode == 0, err[-3000:]
    ds = tmp_path / "dataset"
    verify_dataset(ds)
    assert len(list(ds.glob("part-*.parquet"))) == len(DatasetSpec.from_cfg(quick_cfg()).positions(120e-6)[0])
    # nothing lost, nothing duplicated: the very same rows as the inline run
    pd.testing.assert_frame_equal(_frame(ds), inline, check_exact=True)
    if kill_a_worker:
        assert procs[1].poll() is not None and procs[2].poll() is None
