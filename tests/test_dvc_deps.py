"""DVC's deps cannot go stale: every stage lists every source module and config file it uses.

For each stage of dvc.yaml:
- modules: the fluidfilm modules its entry point imports, traced statically through every import
  statement (module level and inside functions, so lazy imports count), must lie in a listed dep
  (a file, or a directory above it); a second test checks the static trace against what Python
  really loads (``sys.modules`` of a subprocess that imports the entry point);
- configs: the config files Hydra composes for the stage's command line (its primary config and
  every group option chosen, as recorded in ``hydra.runtime.choices``) must be deps, or params
  entries that list all of the file's keys (DVC watches only the listed keys of a params file).
"""
from __future__ import annotations

import ast
import json
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"


def _stages() -> dict:
    """dvc.yaml's stages, a ``foreach`` stage expanded as DVC does (``name@item``, ``${item}`` filled in)."""
    out = {}
    for name, stage in yaml.safe_load((ROOT / "dvc.yaml").read_text())["stages"].items():
        if "foreach" not in stage:
            out[name] = stage
            continue
        for item in stage["foreach"]:
            out[f"{name}@{item}"] = yaml.safe_load(yaml.safe_dump(stage["do"]).replace("${item}", str(item)))
    return out


STAGES = _stages()
PROFILE = yaml.safe_load((ROOT / "conf" / "pipeline" / "full.yaml").read_text())


def _expand(cmd: str) -> str:
    """A stage command as DVC runs it on the full profile: ${python} and ${args.<stage>} filled in."""
    return re.sub(r"\$\{([a-z_.0-9]+)\}",
                  lambda m: str(PROFILE[m.group(1)] if "." not in m.group(1)
                                else PROFILE["args"][m.group(1).split(".", 1)[1]]), cmd)


def _entry_point(stage: dict) -> tuple[Path, list[str]]:
    """(script, Hydra overrides) of a stage's command: the experiments/*.py token and the key=value tokens after it."""
    tokens = shlex.split(_expand(stage["cmd"]))
    idx = next(i for i, t in enumerate(tokens) if t.startswith("experiments/") and t.endswith(".py"))
    return ROOT / tokens[idx], [t for t in tokens[idx + 1:] if "=" in t and not t.startswith("-")]


def _module_file(name: str) -> Path | None:
    base = SRC / Path(*name.split("."))
    for p in (base / "__init__.py", base.with_suffix(".py")):
        if p.exists():
            return p
    return None


def _imports(path: Path, module: str | None) -> set[str]:
    """fluidfilm modules named by the import statements of one file (``module``: its dotted name, for relative imports)."""
    package = None
    if module is not None:
        package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.split(".")[0] == "fluidfilm"}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                assert package is not None, f"relative import in {path}"
                parts = package.split(".")
                base = ".".join(parts[:len(parts) - node.level + 1])
                target = f"{base}.{node.module}" if node.module else base
            else:
                target = node.module or ""
            if target.split(".")[0] != "fluidfilm":
                continue
            found.add(target)
            # `from package import submodule`
            found |= {f"{target}.{a.name}" for a in node.names if _module_file(f"{target}.{a.name}")}
    # importing a.b.c runs a/__init__ and a/b/__init__ first
    return {".".join(m.split(".")[:k]) for m in found for k in range(1, m.count(".") + 2)}


def static_closure(script: Path) -> set[str]:
    todo = _imports(script, None)
    seen: set[str] = set()
    while todo:
        m = todo.pop()
        if m in seen:
            continue
        f = _module_file(m)
        if f is None:  # a name imported from a module, not a module
            continue
        seen.add(m)
        todo |= _imports(f, m) - seen
    return seen


def _deps(stage: dict) -> list[Path]:
    return [ROOT / d for d in stage.get("deps", [])]


def _covered(path: Path, deps: list[Path]) -> bool:
    return any(path == d or d in path.parents for d in deps)


def _composed_configs(script: Path, overrides: list[str]) -> set[Path]:
    from hydra import compose, initialize_config_dir
    from hydra.core.global_hydra import GlobalHydra

    name = script.stem  # the entry point, its config and its study share one name (fluidfilm.workflow.entry)
    assert (ROOT / "conf" / f"{name}.yaml").exists(), f"{script.name}: no conf/{name}.yaml"
    GlobalHydra.instance().clear()
    with initialize_config_dir(config_dir=str(ROOT / "conf"), version_base="1.3"):
        cfg = compose(config_name=name, overrides=overrides, return_hydra_config=True)
    files = {ROOT / "conf" / f"{name}.yaml"}
    # a primary config that composes another primary config (the controller's three entry points)
    files |= {ROOT / "conf" / f"{d}.yaml" for d in (yaml.safe_load(files.copy().pop().read_text()) or {})
              .get("defaults", []) if isinstance(d, str) and (ROOT / "conf" / f"{d}.yaml").exists()}
    for group, choice in cfg.hydra.runtime.choices.items():
        if choice is None:
            continue
        f = ROOT / "conf" / group.split("@")[0] / f"{choice}.yaml"
        if f.exists():  # hydra's own groups (job_logging, ...) live in its package
            files.add(f)
    return files


def _param_files_complete(stage: dict) -> set[Path]:
    """params files whose listed keys are all of the file's top-level keys."""
    out = set()
    for entry in stage.get("params", []):
        if isinstance(entry, dict):
            for fname, keys in entry.items():
                data = yaml.safe_load((ROOT / fname).read_text()) or {}
                if set(data) <= set(keys or []):
                    out.add(ROOT / fname)
    return out


@pytest.mark.parametrize("name", sorted(STAGES))
def test_stage_deps_cover_every_imported_module(name):
    stage = STAGES[name]
    script, _ = _entry_point(stage)
    deps = _deps(stage)
    assert _covered(script, deps), f"{name}: the entry point {script.relative_to(ROOT)} is not a dep"
    missing = sorted(str(_module_file(m).relative_to(ROOT)) for m in static_closure(script)
                     if not _covered(_module_file(m), deps))
    assert not missing, f"stage {name} imports modules that are not in its deps: {missing}"


@pytest.mark.parametrize("name", sorted(STAGES))
def test_stage_deps_cover_every_composed_config(name):
    stage = STAGES[name]
    script, overrides = _entry_point(stage)
    deps = _deps(stage)
    complete = _param_files_complete(stage)
    missing = sorted(str(f.relative_to(ROOT)) for f in _composed_configs(script, overrides)
                     if not _covered(f, deps) and f not in complete)
    assert not missing, f"stage {name} composes config files that are not deps: {missing}"


def test_static_trace_contains_what_python_loads():
    """The static trace is a superset of the modules a real import of an entry point loads."""
    script = ROOT / "experiments" / "fig3_velocity.py"
    code = ("import importlib.util, json, sys\n"
            f"spec = importlib.util.spec_from_file_location('entry', {str(script)!r})\n"
            "spec.loader.exec_module(importlib.util.module_from_spec(spec))\n"
            "print(json.dumps(sorted(m for m in sys.modules if m.split('.')[0] == 'fluidfilm')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         env={"PYTHONPATH": str(SRC), "PATH": "/usr/bin:/bin"})
    loaded = set(json.loads(out.stdout.strip().splitlines()[-1]))
    assert "fluidfilm.studies.plots" in loaded  # the trace saw the entry point's own imports
    assert loaded <= static_closure(script), sorted(loaded - static_closure(script))


def test_the_trace_finds_a_module_missing_from_a_stage():
    """The check can fail: a stage that omits a module its entry point imports is caught."""
    stage = {"cmd": "python experiments/fig3_velocity.py", "deps": ["experiments/fig3_velocity.py",
                                                                     "src/fluidfilm/reynolds"]}
    script, _ = _entry_point(stage)
    uncovered = {m for m in static_closure(script) if not _covered(_module_file(m), _deps(stage))}
    assert {"fluidfilm.studies.plots", "fluidfilm.core.bearing", "fluidfilm.workflow.config"} <= uncovered


def test_committed_reports_are_the_outputs_dvc_lock_records():
    """Every report file committed to git is the one dvc.lock records for its stage: copying reports and
    the lock from two different states (a checkout in between) would make `dvc status` lie."""
    import hashlib

    root = Path(__file__).resolve().parents[1]
    lock = yaml.safe_load((root / "dvc.lock").read_text())
    checked = 0
    for stage, entry in lock["stages"].items():
        for out in entry.get("outs", []):
            path = root / out["path"]
            if not out["path"].startswith("reports/") or not path.is_file() or "md5" not in out:
                continue
            assert hashlib.md5(path.read_bytes()).hexdigest() == out["md5"], (stage, out["path"])
            checked += 1
    assert checked >= 10


def test_resumable_work_survives_dvc_repro():
    """DVC deletes a stage's outputs before it runs it, unless they are ``persist``: every study's resumable
    work (``cache_dir`` in conf/*.yaml: finished fits, checkpoints) must lie in no output that is not
    persistent, or `dvc repro` after an interruption would start it over (universal_train kept its finished
    regions inside models/universal until 2026-12-02)."""
    outs = []  # (path, persist)
    for stage in _stages().values():
        for entry in stage.get("outs", []):
            path, opts = (entry, {}) if isinstance(entry, str) else next(iter(entry.items()))
            outs.append((Path(path), bool(opts.get("persist", False))))
    caches = {f.name: Path(yaml.safe_load(f.read_text())["cache_dir"]) for f in sorted((ROOT / "conf").glob("*.yaml"))
              if "cache_dir" in (yaml.safe_load(f.read_text()) or {})}
    assert "universal.yaml" in caches and "paper_scale.yaml" in caches, sorted(caches)
    for name, cache in caches.items():
        inside = [str(p) for p, persist in outs if not persist and (cache == p or p in cache.parents)]
        assert not inside, f"conf/{name}: cache_dir {cache} lies in the non-persistent output(s) {inside}"
