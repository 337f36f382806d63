"""The worked example of docs/adding_a_model.md runs and is right."""
from __future__ import annotations

import re
import runpy
import subprocess
import sys

import numpy as np
from conftest import ROOT

from fluidfilm.core.force_model import ForceModel


def _run_doc(tmp_path) -> dict:
    text = (ROOT / "docs" / "adding_a_model.md").read_text()
    section = text[text.index("## Example"):]
    blocks = re.findall(r"```python\n(.*?)```", section, flags=re.S)
    assert len(blocks) == 1
    model = blocks[0][:blocks[0].index("# use it like any other model")]
    assert 20 <= len(model.strip().splitlines()) <= 60  # the model itself: a short example
    # a real file, as a user would save it
    script = tmp_path / "adding_a_model.py"
    script.write_text(blocks[0])
    return runpy.run_path(str(script))


def test_the_documented_model_implements_the_interface_and_matches_the_solver_to_second_order(tmp_path):
    ns = _run_doc(tmp_path)
    lin, solver, eq, traj = ns["lin"], ns["solver"], ns["eq"], ns["traj"]
    assert isinstance(lin, ForceModel)
    x0 = np.array([eq["X1"], eq["X2"]])
    c = solver.clearance
    errs = []
    for h in (0.02, 0.01):
        d = h * c * np.array([0.6, -0.8])
        v = h * c * solver.bearing.omega * np.array([0.3, 0.5])
        errs.append(np.linalg.norm(lin.forces(x0 + d, v) - solver.forces(x0 + d, v)))
    # the linearisation's error is second order: halving the offset quarters it (within a margin)
    assert errs[1] < 0.35 * errs[0]
    # the kernel and forces() are one model
    kernel, params = lin.force_kernel
    np.testing.assert_allclose(kernel(params, *(x0 + 1e-6), 0.01, -0.02), lin.forces(x0 + 1e-6, [0.01, -0.02]),
                               rtol=1e-12)
    # started at the equilibrium of a rotor without imbalance, the journal stays there
    assert traj.ok and np.abs(traj.x - x0).max() < 1e-3 * c


def test_a_model_from_a_script_leaves_the_integrators_cache_readable(tmp_path):
    """numba caches the integrator per argument type; a type from a script other processes cannot
    import must not end up in that cache (a later simulate() anywhere would fail to read it)."""
    ns = _run_doc(tmp_path)
    assert ns["traj"].ok
    code = ("from fluidfilm import LinearBearing, Rotor, paper_bearing, simulate\n"
            "print(simulate(LinearBearing(paper_bearing(), 1e6, 1e3), Rotor(mass=1.0), t_end=1e-3).status)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env={"PYTHONPATH": str(ROOT / "src"), "PATH": "/usr/bin:/bin"})
    assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr[-2000:]
