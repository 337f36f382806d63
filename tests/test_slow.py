"""Long checks, not in the default run: `make test-slow` (or `pytest -m slow`).

- the paper-scale dataset: the layout the pipeline trains on, generated whole, has the documented
  count, no repeated state, forces equal to the reference model's at random rows, and a film that
  only dissipates at the centre (pure squeeze);
- every benchmark script runs (`--quick`), so `make bench` cannot rot between full runs.
"""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from fluidfilm import paper_bearing
from fluidfilm.workflow.config import reference_from_cfg
from fluidfilm.data import DatasetSpec, generate_dataset, load_dataset

ROOT = Path(__file__).resolve().parents[1]
pytestmark = pytest.mark.slow


def test_paper_dataset_at_full_scale(tmp_path):
    spec = DatasetSpec.from_cfg(yaml.safe_load((ROOT / "conf" / "dataset" / "paper.yaml").read_text()))
    reference = yaml.safe_load((ROOT / "conf" / "reference" / "paper.yaml").read_text())
    meta = generate_dataset(paper_bearing(), reference, spec, tmp_path / "dataset", progress=True)
    assert meta["n_samples"] == spec.n_samples(paper_bearing().clearance) == 921 * 70 * 70
    frame, _ = load_dataset(tmp_path / "dataset")
    assert len(frame) == meta["n_samples"]
    keys = frame[["X1", "X2", "V1", "V2"]].round(15)
    assert not keys.duplicated().any(), "a state is repeated"
    assert np.isfinite(frame[["F1", "F2"]].to_numpy()).all()
    # a second method for some rows: the reference model evaluated directly
    rows = frame.sample(200, random_state=0)
    model = reference_from_cfg(paper_bearing(), reference)
    F = model.forces(rows[["X1", "X2"]].to_numpy(), rows[["V1", "V2"]].to_numpy())
    np.testing.assert_allclose(F, rows[["F1", "F2"]].to_numpy(), rtol=1e-9, atol=1e-9)
    # at the centre the film is uniform: no wedge, pure squeeze, so the film only dissipates (F . V < 0)
    centre = frame[(frame.X1 == 0) & (frame.X2 == 0)]
    assert len(centre) == 70 * 70
    assert (centre.F1 * centre.V1 + centre.F2 * centre.V2 < 0).all()


@pytest.mark.parametrize("script", sorted(p.name for p in (ROOT / "benchmarks").glob("bench_*.py")))
def test_benchmark_runs(script, tmp_path):
    if script == "bench_ross_peer.py":  # the optional external peer needs its own environment (make ross-peer)
        ross_python = Path(os.environ.get("ROSS_PYTHON", ROOT / ".venv-ross" / "bin" / "python"))
        if not ross_python.is_file():
            pytest.skip(f"no ROSS interpreter at {ross_python}: `make ross-peer` builds one")
    text = (ROOT / "benchmarks" / script).read_text()
    args = ["--quick"] if "--quick" in text else []
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / script), *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=3600, check=False)
    assert proc.returncode == 0, proc.stderr[-3000:]
