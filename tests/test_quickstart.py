"""The README's "Your bearing" quickstart runs as written in a fresh clone: no trained model, no DVC
outputs, from an empty folder; and what it prints is right.  Also the repository's citation and licence
files agree with pyproject.toml."""
from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import tomllib

import numpy as np
import yaml
from conftest import ROOT

from fluidfilm import JournalBearing, ReynoldsSolver

# appended to the README's block: what the test checks, written where the test can read it
PROBE = """
import json as _json
_json.dump({"W": list(W), "eq": {k: eq[k] for k in ("eps", "X1", "X2", "attitude_deg")},
            "threshold_rpm": threshold_speed(solver, mass=rotor.mass, load=W)["speed_rpm"],
            "status": traj.status, "eps_max": float(traj.eccentricity(bearing.clearance).max()),
            "eps_min": float(traj.eccentricity(bearing.clearance).min())}, open("probe.json", "w"))
"""


def quickstart_block() -> str:
    text = (ROOT / "README.md").read_text()
    section = text[text.index("## Your bearing"):]
    section = section[:section.index("\n## ", 4)]
    blocks = re.findall(r"```python\n(.*?)```", section, flags=re.S)
    assert len(blocks) == 1, "the README's 'Your bearing' section should have one python block"
    return blocks[0]


def test_quickstart_is_short():
    lines = [ln for ln in quickstart_block().splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    assert len(lines) <= 15, f"the quickstart has {len(lines)} lines of code; keep it about 10"


def test_quickstart_runs_in_an_empty_folder_and_its_answers_hold(tmp_path):
    code = quickstart_block()
    # a fresh clone after `make setup`: the package importable, nothing else; cwd an empty folder, so
    # neither models/ nor data/ nor conf/ can be found
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.run([sys.executable, "-c", code + PROBE], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, f"the README's quickstart failed:\n{proc.stderr[-3000:]}"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["probe.json"], "the quickstart wrote files"
    out = json.loads((tmp_path / "probe.json").read_text())
    assert "rpm: onset of oil whirl" in proc.stdout and out["status"] in proc.stdout

    # the equilibrium it prints carries the load: a solver built here, at the printed position
    eq = out["eq"]
    bearing = JournalBearing(length=0.025, diameter=0.050, clearance=50e-6, speed_rpm=6000.0, viscosity=0.02)
    residual = ReynoldsSolver(bearing, n_theta=30, n_z=30).forces([eq["X1"], eq["X2"]], [0.0, 0.0]) + out["W"]
    assert np.hypot(*residual) < 1e-6 * np.hypot(*out["W"])
    assert np.isclose(np.hypot(eq["X1"], eq["X2"]) / bearing.clearance, eq["eps"], rtol=1e-9)
    # the journal's surface turns from +X2 towards +X1 and drags the journal with it: the attitude,
    # positive in the direction of rotation (docs/conventions.md), is between 0 and 90 degrees, the centre
    # displaced towards +X1 under a load along +X2
    assert 0.0 < eq["attitude_deg"] < 90.0 and eq["X1"] > 0.0 and eq["X2"] > 0.0
    # the rotor runs below its whirl threshold, so the orbit about the equilibrium stays small: the
    # nonlinear trajectory agrees with the linear stability answer
    assert out["threshold_rpm"] > bearing.speed_rpm
    assert out["status"] == "ok" and out["eps_min"] > eq["eps"] - 0.05 and out["eps_max"] < eq["eps"] + 0.05


def test_citation_and_licence_agree_with_pyproject():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    assert cff["cff-version"] == "1.2.0" and cff["type"] == "software"
    assert cff["license"] == project["license"] == "MIT"
    assert cff["version"] == project["version"]
    assert (ROOT / "LICENSE").read_text().startswith("MIT License")
    paper = cff["references"][0]
    assert paper["doi"] == "10.1007/978-3-031-40455-9_18"
    assert [a["family-names"] for a in paper["authors"]] == ["Kazakov", "Stebakov", "Shutin", "Savin"]
    assert paper["doi"] in (ROOT / "README.md").read_text()


def test_the_wheel_check_runs_the_readme_library_blocks():
    """``.ci/wheel_check`` (run by ``.ci/run`` before ``make test``) runs the README's "Your bearing" and "Any
    plain bearing" blocks in a fresh Python 3.13 environment holding the core wheel alone; the script it extracts
    them with finds the same first block as this test, and the second."""
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as tmp:
        out = subprocess.run([sys.executable, str(ROOT / ".ci" / "readme_blocks.py"), tmp], capture_output=True,
                             text=True, timeout=60)
        assert out.returncode == 0, out.stderr
        assert (Path(tmp) / "your_bearing.py").read_text() == quickstart_block()
        assert "universal_bearing(" in (Path(tmp) / "any_plain_bearing.py").read_text()
    run = (ROOT / ".ci" / "run").read_text()
    assert run.index(".ci/wheel_check") < run.index("make test")
    check = (ROOT / ".ci" / "wheel_check").read_text()
    assert "universal_weights" in check and "3.13" in check
