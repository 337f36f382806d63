"""Fault-injection suite: shared helpers (the quick dataset profile, a subprocess runner)."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[2]
REFERENCE = {"coarse": [30, 30], "dense": [55, 55], "eps_threshold": 0.9, "cavitation": "gumbel"}


def quick_cfg() -> dict:
    return yaml.safe_load((ROOT / "conf" / "dataset" / "quick.yaml").read_text())


def run_entry(script: str, *overrides, timeout: float = 300, check: bool = False, env: dict | None = None):
    """Run an entry point as a user does (``python experiments/<script>.py overrides...``)."""
    full_env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "HYDRA_FULL_ERROR": "0", **(env or {})}
    proc = subprocess.run([sys.executable, f"experiments/{script}.py", *overrides], cwd=ROOT, capture_output=True,
                          text=True, timeout=timeout, env=full_env)
    if check:
        assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-4000:]
    return proc


def snapshot(directory: Path) -> dict:
    """{relative path: bytes} of every file under ``directory``."""
    return {str(p.relative_to(directory)): p.read_bytes() for p in sorted(directory.rglob("*")) if p.is_file()}


@pytest.fixture
def saved(tmp_path):
    """A split surrogate saved to a fresh directory: (model, directory)."""
    from .models import paper_split

    m = paper_split()
    m.save(tmp_path / "m")
    return m, tmp_path / "m"


@pytest.fixture(scope="session")
def quick_spec():
    from fluidfilm.data import DatasetSpec

    return DatasetSpec.from_cfg(quick_cfg())


def interruptible() -> None:
    """``preexec_fn`` for a child that the test will Ctrl-C: SIGINT back to its default action.

    A test suite started in the background (``make test &``, nohup, some CI runners) inherits SIGINT
    ignored, and Python then never turns SIGINT into KeyboardInterrupt, so the child would not see the
    test's Ctrl-C at all. A user's terminal has it at the default.
    """
    signal.signal(signal.SIGINT, signal.SIG_DFL)
