"""The worked example of docs/adding_a_model.md runs and is right; every name, link and test the README and
docs/ cite exists."""
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


# ------------------------------------------------------------------ every name and link a reader follows
# README.md and docs/ describe the workspace as it is (CHANGELOG.md names what things were called before).
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
_PACKAGE = ROOT / "src" / "fluidfilm"
# first components of a name written without the `fluidfilm.` prefix (`surrogate.kernels.forces_batch`)
_SHORT = {p.name for p in _PACKAGE.iterdir() if (p / "__init__.py").exists()} | {"io", "progress", "_conformance"}
_FILE_ENDINGS = (".py", ".md", ".yaml", ".json", ".csv", ".png", ".npz", ".zip", ".ckpt", ".parquet")


def _resolves(dotted: str) -> bool:
    import importlib

    parts = dotted.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for part in parts[i:]:
            if not hasattr(obj, part):
                return False
            obj = getattr(obj, part)
        return True
    return False


def _names(text: str) -> set[str]:
    full = {m.rstrip(".") for m in re.findall(r"(?<![\w./-])fluidfilm(?:\.[A-Za-z_]\w*)+", text)}
    # a backticked name of the package without its prefix, alone or called: `characteristics.static.equilibrium`
    short = {"fluidfilm." + m for m in re.findall(r"`([A-Za-z_]\w*(?:\.[A-Za-z_]\w*)+)(?:\([^`]*\))?`", text)
             if m.split(".")[0] in _SHORT}
    imported = {f"{mod}.{name.strip()}" for mod, names in
                re.findall(r"^\s*from (fluidfilm[\w.]*) import ([\w, ]+)$", text, flags=re.M)
                for name in names.split(",")}
    return {n for n in full | short | imported if not n.endswith(_FILE_ENDINGS)}


def test_every_fluidfilm_name_in_the_readme_and_docs_exists():
    missing = [(page.name, name) for page in PAGES for name in sorted(_names(page.read_text()))
               if not _resolves(name)]
    assert not missing, missing


def test_the_name_check_finds_a_stale_name():
    # the check above can fail: a name of the old flat layout does not resolve, today's does
    assert "fluidfilm.speed" in _names("see `fluidfilm.speed` and `perf.speed.best_shaped_surrogate`")
    assert not _resolves("fluidfilm.speed") and not _resolves("fluidfilm.characteristics.shortbearing.attitude_angle")
    assert _resolves("fluidfilm.perf.speed.best_shaped_surrogate")


def _headings(page) -> set[str]:
    """GitHub's anchors of a page's headings: lower case, punctuation dropped, spaces to hyphens."""
    return {re.sub(r"[^\w\- ]", "", h.strip().lower()).replace(" ", "-")
            for h in re.findall(r"^#+ (.*)$", page.read_text(), flags=re.M)}


def test_every_relative_link_and_anchor_in_the_readme_docs_and_changelog_exists():
    bad = []
    for page in [*PAGES, ROOT / "CHANGELOG.md"]:
        for target in re.findall(r"\]\(([^)\s]+)\)", page.read_text()):
            if re.match(r"[a-z]+:", target):
                continue
            path, _, anchor = target.partition("#")
            dest = (page.parent / path) if path else page
            if not dest.exists():
                bad.append((page.name, target))
            elif anchor and dest.suffix == ".md" and anchor not in _headings(dest):
                bad.append((page.name, target))
    assert not bad, bad


def test_every_test_the_docs_cite_exists():
    tests: dict[str, set[str]] = {}
    for f in (ROOT / "tests").rglob("test_*.py"):
        tests.setdefault(f.name, set()).update(re.findall(r"^\s*def (test_\w+)", f.read_text(), flags=re.M))
    bad = []
    for page in PAGES:
        current = None  # `file.py::test_a`, `::test_b`: a bare `::test_b` belongs to the file named last
        for m in re.finditer(r"((?:[\w.-]+/)*)(test_\w+\.py)(?:::(test_\w+))?|(?<![\w/])::(test_\w+)", page.read_text()):
            if m.group(2):
                if m.group(1) and not m.group(1).startswith("tests/"):
                    current = None  # another project's test file (ROSS's literature tests)
                    continue
                current = m.group(2)
                # a path (`tests/rotor/test_batch.py`) must be where the file is, a bare name anywhere in tests/
                if current not in tests or (m.group(1) and not (ROOT / m.group(1) / current).exists()):
                    bad.append((page.name, m.group(1) + current))
                    current = None
                    continue
            name = m.group(3) or m.group(4)
            if name and current and name not in tests[current]:
                bad.append((page.name, f"{current}::{name}"))
    assert not bad, bad


def test_every_test_path_the_workspace_cites_exists():
    """A path into tests/ (``tests/rotor/test_batch.py``) named in the code, the docs, the Makefile, CI or the
    configs is where that file is (the changelog keeps the paths of its time)."""
    files = [ROOT / "README.md", ROOT / "Makefile", ROOT / "pyproject.toml", ROOT / "dvc.yaml",
             *sorted((ROOT / "docs").glob("*.md")), *sorted((ROOT / ".ci").iterdir()),
             *sorted((ROOT / "src").rglob("*.py")), *sorted((ROOT / "benchmarks").glob("*.py")),
             *sorted((ROOT / "tests").rglob("*.py")), *sorted((ROOT / "conf").rglob("*.yaml"))]
    bad = [(f.relative_to(ROOT).as_posix(), path) for f in files if f.is_file()
           for path in re.findall(r"(?<![\w/.-])(tests/[\w/]+\.(?:py|npz))", f.read_text())
           if not (ROOT / path).exists()]
    assert not bad, bad
