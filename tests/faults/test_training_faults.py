"""Item 2: a training run killed mid-way resumes from its last checkpoint to the uninterrupted result."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

from fluidfilm import paper_bearing
from fluidfilm.data import generate_dataset

from .conftest import REFERENCE, ROOT

TRAIN = textwrap.dedent("""
    import json, sys
    import numpy as np
    from fluidfilm.surrogate.training import ForceDataModule, train_network
    dataset, ckpt, out = sys.argv[1:4]
    dm = ForceDataModule(dataset, scaling="physics", val_fraction=0.2, batch_size=64, seed=3)
    r = train_network(dm, dict(width=16, depth=2, activation="tanh", lr=1e-2), dict(max_epochs=10, progress_bar=False),
                      None, ckpt_dir=ckpt, seed=3)
    np.savez(out, *[a for W, b in r["layers"] for a in (W, b)])
    json.dump({"val_rel_rmse": r["val_rel_rmse"], "epochs": r["epochs"]}, open(out + ".json", "w"))
""")


def _run(script, *args, **kw):
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    return subprocess.Popen([sys.executable, str(script), *map(str, args)], env=env, **kw)


@pytest.fixture(scope="module")
def dataset(tmp_path_factory, quick_spec):
    out = tmp_path_factory.mktemp("train_data") / "dataset"
    generate_dataset(paper_bearing(), REFERENCE, quick_spec, out, scheduler="inline", progress=False)
    return out


def test_killed_training_resumes_to_the_weights_and_metrics_of_an_uninterrupted_run(dataset, tmp_path):
    script = tmp_path / "train.py"
    script.write_text(TRAIN)
    whole = _run(script, dataset, tmp_path / "ck_whole", tmp_path / "whole.npz")
    # the run to kill: SIGKILL (no clean-up at all) once it has checkpointed 3 epochs
    victim = _run(script, dataset, tmp_path / "ck", tmp_path / "resumed.npz")
    last = tmp_path / "ck" / "last.ckpt"
    seen, stamp, deadline = 0, None, time.time() + 300
    while time.time() < deadline and seen < 3 and victim.poll() is None:
        if last.exists() and last.stat().st_mtime_ns != stamp:
            stamp, seen = last.stat().st_mtime_ns, seen + 1
        time.sleep(0.01)
    os.kill(victim.pid, signal.SIGKILL)
    victim.wait()
    assert not (tmp_path / "resumed.npz").exists(), "the run finished before the kill; make it longer"
    import torch

    epoch_at_kill = torch.load(last, weights_only=False)["epoch"]  # the checkpoint is whole (atomic write)
    assert 1 <= epoch_at_kill < 9
    assert _run(script, dataset, tmp_path / "ck", tmp_path / "resumed.npz").wait(timeout=300) == 0
    assert whole.wait(timeout=300) == 0
    a, b = np.load(tmp_path / "whole.npz"), np.load(tmp_path / "resumed.npz")
    for k in a.files:
        np.testing.assert_array_equal(a[k], b[k])
    ma = json.loads((tmp_path / "whole.npz.json").read_text())
    mb = json.loads((tmp_path / "resumed.npz.json").read_text())
    assert ma == mb and ma["epochs"] == 10


LM = textwrap.dedent("""
    import json, sys, time
    import numpy as np
    from fluidfilm.surrogate import protocol
    from fluidfilm.surrogate.protocol import NetworkData, divide_random, train_network_lm
    from fluidfilm.surrogate.scaling import Scaling
    ckpt, out, workers, slow = sys.argv[1], sys.argv[2], int(sys.argv[3]), float(sys.argv[4])
    rng = np.random.default_rng(0)
    z = rng.uniform(-1, 1, (1500, 4))
    y = np.stack([np.sin(1.5 * z[:, 0]) * z[:, 2] + 0.3 * z[:, 1], np.tanh(z[:, 1] + z[:, 3])], 1)
    d = divide_random(len(z), seed=0)
    parts = {"train": d.train, "val": d.val, "test": d.test}
    sc = Scaling("minmax", 1.0, 1.0, 1.0, 0.0, np.zeros(4), np.ones(4), np.zeros(2), np.ones(2))
    data = NetworkData(sc, {k: z[v] for k, v in parts.items()}, {k: y[v] for k, v in parts.items()},
                       {k: y[v] for k, v in parts.items()})
    real = protocol.normal_equations
    def slowed(*a, **k):  # the victim is slowed down so that the kill lands mid-run; the maths are the same
        time.sleep(slow)
        return real(*a, **k)
    protocol.normal_equations = slowed
    r = train_network_lm(data, n_hidden=10, seed=1, workers=workers, checkpoint=None if ckpt == "-" else ckpt,
                         progress_every_s=0.0)
    np.savez(out, *[a for W, b in r["layers"] for a in (W, b)])
    json.dump({k: r[k] for k in ("epochs", "best_epoch", "stop_reason", "val_mse")}, open(out + ".json", "w"))
""")


def test_killed_levenberg_marquardt_run_resumes_to_the_weights_of_an_uninterrupted_run(tmp_path):
    """The paper protocol's trainer: SIGKILL mid-run, the same command again, the same weights bitwise
    (and the killed run used two J^T J threads, the uninterrupted one a single thread)."""
    script = tmp_path / "lm.py"
    script.write_text(LM)
    whole = _run(script, "-", tmp_path / "whole.npz", 1, 0.0)
    ck = tmp_path / "ck" / "net.npz"
    victim = _run(script, ck, tmp_path / "resumed.npz", 2, 0.05, stdout=subprocess.PIPE, text=True)
    for line in victim.stdout:  # a progress line per epoch: kill after the 5th
        if ": epoch 5," in line:
            break
    os.kill(victim.pid, signal.SIGKILL)
    victim.wait()
    assert not (tmp_path / "resumed.npz").exists(), "the run finished before the kill; make it longer"
    from fluidfilm.surrogate.protocol import load_lm_checkpoint

    state = load_lm_checkpoint(ck)  # whole: written atomically
    assert state["reason"] is None and 5 <= state["epoch"] < 12
    assert _run(script, ck, tmp_path / "resumed.npz", 2, 0.0).wait(timeout=300) == 0
    assert whole.wait(timeout=300) == 0
    a, b = np.load(tmp_path / "whole.npz"), np.load(tmp_path / "resumed.npz")
    for k in a.files:
        np.testing.assert_array_equal(a[k], b[k])
    ma = json.loads((tmp_path / "whole.npz.json").read_text())
    assert ma == json.loads((tmp_path / "resumed.npz.json").read_text()) and ma["stop_reason"] == "validation"
    assert ma["epochs"] > state["epoch"]
