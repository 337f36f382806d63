"""``reporting/readme.py`` cites only what exists: every module or name it writes (into the pages it
generates, its help and its docstrings) resolves, and every file path it names is in the workspace."""
from __future__ import annotations

import re
from pathlib import Path

import pytest
from test_docs import _SHORT, _resolves

ROOT = Path(__file__).resolve().parents[2]
README_PY = ROOT / "src" / "fluidfilm" / "reporting" / "readme.py"


def _cited_names(text: str) -> set[str]:
    full = set(re.findall(r"(?<![\w./-])fluidfilm(?:\.[A-Za-z_]\w*)+", text))
    # a name without the package prefix, between double backticks or backticks: ``studies.x.y``
    short = {"fluidfilm." + m for m in re.findall(r"`+([A-Za-z_]\w*(?:\.[A-Za-z_]\w*)+)`+", text)
             if m.split(".")[0] in _SHORT}
    return {n.rstrip(".") for n in full | short if not n.endswith((".json", ".md", ".py", ".png", ".yaml"))}


def _cited_files(text: str) -> set[str]:
    return set(re.findall(r"(?<![\w/])((?:src|tests|experiments|benchmarks|docs|conf)/[\w/.-]+\.(?:py|md|yaml))", text))


def test_every_name_readme_py_cites_exists():
    missing = sorted(n for n in _cited_names(README_PY.read_text()) if not _resolves(n))
    assert not missing, f"reporting/readme.py cites names that do not exist: {missing}"


def test_every_file_readme_py_cites_exists():
    missing = sorted(f for f in _cited_files(README_PY.read_text()) if not (ROOT / f).exists())
    assert not missing, f"reporting/readme.py cites files that do not exist: {missing}"


@pytest.mark.parametrize("text", ["the tables (``fluidfilm.reporting.tables``)", "see ``studies.nowhere.f``",
                                  "in src/fluidfilm/nowhere.py"])
def test_the_citation_checks_see_a_missing_one(text):
    names = [n for n in _cited_names(text) if not _resolves(n)]
    files = [f for f in _cited_files(text) if not (ROOT / f).exists()]
    assert names or files
