"""The scaling row's contract (``surrogate.contract``): its layout in one place, no bare index elsewhere."""
from __future__ import annotations

import ast
import re
from pathlib import Path

import numpy as np
import pytest

from fluidfilm.surrogate import contract
from fluidfilm.surrogate.scaling import Scaling

SRC = Path(__file__).resolve().parents[2] / "src"
CONTRACT = SRC / "fluidfilm" / "surrogate" / "contract.py"
NAMES = {n for n in contract.__all__ if n.startswith(("ROW_", "REGION_"))}


def _is_source(node: ast.AST) -> bool:
    """An expression that is a scaling row or a table of them: ``x.kernel_row()``, a ``SurrogateParams``'
    ``params.scalings`` or a ``BatchParams``' ``bp.regions``."""
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "kernel_row":
        return True
    if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
        return (node.attr, node.value.id) in {("scalings", "params"), ("regions", "bp")}
    return False


def _rowish(node, rows: set[str]) -> bool:
    if _is_source(node):
        return True
    if isinstance(node, ast.Name):
        return node.id in rows
    if isinstance(node, ast.Subscript):
        return _rowish(node.value, rows)
    if isinstance(node, (ast.ListComp, ast.SetComp, ast.GeneratorExp)):
        return _rowish(node.elt, rows)
    return False


def _targets(target, value, rows: set[str]) -> set[str]:
    if isinstance(target, ast.Name):
        return {target.id} if _rowish(value, rows) else set()
    if isinstance(target, ast.Tuple) and isinstance(value, ast.Tuple) and len(target.elts) == len(value.elts):
        return set().union(*(_targets(t, v, rows) for t, v in zip(target.elts, value.elts)))
    return set()


def _row_names(scope: ast.AST) -> set[str]:
    """The names that hold a scaling row (or a table of rows) within ``scope``, followed through
    assignments, loops and comprehensions until nothing changes."""
    rows: set[str] = set()
    while True:
        before = set(rows)
        for node in ast.walk(scope):
            if isinstance(node, ast.Assign):
                for t in node.targets:
                    rows |= _targets(t, node.value, rows)
            elif isinstance(node, (ast.For, ast.comprehension)):
                if isinstance(node.target, ast.Name) and _rowish(node.iter, rows):
                    rows.add(node.target.id)
        if rows == before:
            return rows


def _bare(index: ast.AST) -> bool:
    """An index that holds an integer literal and none of the contract's names."""
    parts = index.elts if isinstance(index, ast.Tuple) else [index]
    for part in parts:
        nodes = list(ast.walk(part))
        has_int = any(isinstance(n, ast.Constant) and type(n.value) is int for n in nodes)
        named = any(isinstance(n, ast.Name) and n.id in NAMES for n in nodes)
        # a table's row number (bp.regions[r, X]) is not a field: only the last part names one
        if has_int and not named and part is parts[-1]:
            return True
    return False


def bare_indices(text: str, filename: str = "<src>") -> list[str]:
    """``file:line`` of every bare integer index into a scaling row in the module ``text``."""
    tree = ast.parse(text)
    scopes = [tree] + [n for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))]
    found = set()
    for scope in scopes:
        rows = _row_names(scope)
        for node in ast.walk(scope):
            if isinstance(node, ast.Subscript) and _rowish(node.value, rows) and _bare(node.slice):
                found.add(f"{filename}:{node.lineno}")
    return sorted(found)


def test_no_bare_index_into_a_scaling_row_outside_the_contract():
    offenders = []
    for path in sorted((SRC / "fluidfilm").rglob("*.py")):
        if path != CONTRACT:
            offenders += bare_indices(path.read_text(), str(path.relative_to(SRC)))
    assert not offenders, ("index a scaling row with the names of fluidfilm.surrogate.contract "
                           f"(ROW_FRAME, ROW_IN_MEAN + k, ...), not a bare integer: {offenders}")


@pytest.mark.parametrize("snippet", [
    "def f(sc):\n    s = sc.kernel_row()\n    return s[19]\n",
    "def f(params, r):\n    scal = params.scalings\n    s = scal[r]\n    return s[5 + r]\n",
    "def f(model):\n    rows = [sc.kernel_row() for sc in model.scalings]\n    return {r[21] for r in rows}\n",
    "def f(sc):\n    return sc.kernel_row()[0]\n",
    "def f(bp, r):\n    return bp.regions[r, 7]\n",
])
def test_the_scan_finds_a_bare_index(snippet):
    assert bare_indices(snippet)


@pytest.mark.parametrize("snippet", [
    "def f(sc):\n    s = sc.kernel_row()\n    return s[ROW_FRAME], s[ROW_IN_MEAN + 1], s[ROW_IN_STD:ROW_IN_STD + 2]\n",
    "def f(bp, r):\n    return bp.regions[r, REGION_POWER]\n",
    "def f(model):\n    return model.scalings[0].extras, model.networks[0]\n",
])
def test_the_scan_passes_named_indices(snippet):
    assert not bare_indices(snippet)


def test_the_row_is_laid_out_as_documented():
    """Every field at its documented index, the length once, the documented table in step with the names."""
    sc = Scaling("physics_v", 1e-4, 300.0, 50.0, 1.5, np.array([0.1, 0.2, 0.3]), np.array([1.1, 1.2, 1.3]),
                 np.array([0.4, 0.5]), np.array([2.0, 3.0]), "polar", ("S",), 0.25)
    row = sc.kernel_row()
    assert row.shape == (contract.ROW_LENGTH,) == (22,)
    assert row[contract.ROW_KIND] == contract.KIND_PHYSICS_V
    assert (row[contract.ROW_CLEARANCE], row[contract.ROW_OMEGA], row[contract.ROW_FORCE_SCALE],
            row[contract.ROW_POWER]) == (1e-4, 300.0, 50.0, 1.5)
    n = contract.MAX_INPUTS
    assert row[contract.ROW_IN_MEAN:contract.ROW_IN_MEAN + n].tolist() == [0.1, 0.2, 0.3, 0.0, 0.0]
    assert row[contract.ROW_IN_STD:contract.ROW_IN_STD + n].tolist() == [1.1, 1.2, 1.3, 1.0, 1.0]
    assert row[contract.ROW_OUT_MEAN:contract.ROW_OUT_MEAN + 2].tolist() == [0.4, 0.5]
    assert row[contract.ROW_OUT_STD:contract.ROW_OUT_STD + 2].tolist() == [2.0, 3.0]
    assert row[contract.ROW_FRAME] == contract.FRAME_POLAR
    assert row[contract.ROW_N_EXTRA] == 1.0 and row[contract.ROW_SLEEVE] == contract.SLEEVE_AWARE
    # the module doc's table names each field at its index
    doc = contract.__doc__
    for name in sorted(n for n in NAMES if n.startswith("ROW_") and n != "ROW_LENGTH"):
        first = getattr(contract, name)
        m = re.search(rf"^(\d+)(?:-(\d+))?\s+``{name}``", doc, flags=re.M)
        assert m and int(m.group(1)) == first, name
    assert f"``ROW_LENGTH`` = {contract.ROW_LENGTH}" in doc
