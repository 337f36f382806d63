"""The library's layering: surrogates depend on the dataset, never on the solver; the solver never on surrogates.

Checked on the static import graph (every import statement, module level and inside functions),
without the top-level ``fluidfilm/__init__.py``, which re-exports everything for users, and
without the lazy re-exports of a package's module ``__getattr__``.
"""
from __future__ import annotations

import ast

import pytest
from test_dvc_deps import SRC, _module_file


def _deps_of(module: str) -> set[str]:
    path = _module_file(module)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    tree = ast.parse(path.read_text())
    lazy = {id(n) for f in tree.body if isinstance(f, ast.FunctionDef) and f.name == "__getattr__"
            for n in ast.walk(f)}
    out = set()
    for node in ast.walk(tree):
        if id(node) in lazy:
            continue
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names if a.name.startswith("fluidfilm.")}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[:len(parts) - node.level + 1])
                target = f"{base}.{node.module}" if node.module else base
            else:
                target = node.module or ""
            if not target.startswith("fluidfilm."):
                continue
            out.add(target)
            out |= {f"{target}.{a.name}" for a in node.names if _module_file(f"{target}.{a.name}")}
    # parents run first (not the top-level package)
    return {".".join(m.split(".")[:k]) for m in out for k in range(2, m.count(".") + 2)}


def closure(module: str) -> set[str]:
    seen, todo = set(), {module}
    while todo:
        m = todo.pop()
        if m in seen or _module_file(m) is None:
            continue
        seen.add(m)
        todo |= _deps_of(m) - seen
    return seen


def _modules(package: str) -> list[str]:
    root = SRC / "fluidfilm" / package
    return sorted(f"fluidfilm.{package}." + p.relative_to(root).with_suffix("").as_posix().replace("/", ".")
                  for p in root.rglob("*.py") if p.name != "__init__.py")


@pytest.mark.parametrize("module", _modules("surrogate"))
def test_surrogates_do_not_import_the_solver(module):
    assert not {m for m in closure(module) if m.startswith("fluidfilm.reynolds")}, module


@pytest.mark.parametrize("module", _modules("reynolds") + _modules("data"))
def test_solver_and_data_do_not_import_surrogates(module):
    assert not {m for m in closure(module) if m.startswith("fluidfilm.surrogate")}, module


def test_the_layering_check_sees_a_real_dependency():
    """It can fail: the generator does import the solver, the scaling module's user does import scaling."""
    assert "fluidfilm.reynolds.policy" in closure("fluidfilm.data.generate")
    assert "fluidfilm.surrogate.scaling" in closure("fluidfilm.surrogate.fit")


def test_only_the_tracking_module_imports_mlflow():
    """MLflow is reached through fluidfilm.tracking alone (library and entry points)."""
    root = SRC.parent
    offenders = []
    for path in sorted(list((SRC / "fluidfilm").rglob("*.py")) + list((root / "experiments").glob("*.py"))):
        if path == SRC / "fluidfilm" / "tracking.py":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                [node.module or ""] if isinstance(node, ast.ImportFrom) else []
            if any(n.split(".")[0] == "mlflow" for n in names):
                offenders.append(str(path.relative_to(root)))
    assert not offenders, f"import mlflow through fluidfilm.tracking instead: {sorted(set(offenders))}"
