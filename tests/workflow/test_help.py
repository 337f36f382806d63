"""Every entry point's --help (``experiments/*.py``, run through ``workflow.entry``) says what its study does,
its main options and an example."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
ENTRY_POINTS = sorted(p.name for p in (ROOT / "experiments").glob("*.py"))


@pytest.mark.parametrize("script", ENTRY_POINTS)
def test_help_describes_the_study(script):
    proc = subprocess.run([sys.executable, f"experiments/{script}", "--help"], cwd=ROOT, capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    text = proc.stdout
    # the study's own header, not only Hydra's generic text
    assert "Powered by Hydra" not in text
    assert "Main options:" in text and "Example:" in text, text[:500]
    example = next(line for line in text.splitlines() if line.startswith("Example:"))
    assert f"experiments/{script}" in example or script.startswith(("train_controller", "evaluate_control", "controller_training_speed"))
    assert "== Config groups" in text
