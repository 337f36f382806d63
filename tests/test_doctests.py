"""The Examples of the public docstrings run as doctests, in the default suite.

Why this module rather than ``--doctest-modules`` over ``src/``: collecting every module would import the
workflow (Hydra, MLflow), the studies (matplotlib, every plot module) and the Lightning trainer only to find
that they have no examples, and a module that needs an optional package would fail the whole collection.
Here the modules are those that define a public name (``public_api.public_objects``: the ``__all__`` of
``fluidfilm`` and its subpackages), so every documented public name is run, a new public name brings its
module in without editing this file, and nothing else is imported.  Every docstring of such a module
(methods and private helpers too) runs.

Examples print numbers rounded (``round(x, 3)``, ``f"{x:.3g}"``) so that they do not depend on the last bits
of a machine's floating point; NORMALIZE_WHITESPACE and ELLIPSIS are on.
"""
from __future__ import annotations

import doctest
import importlib

import pytest
from public_api import public_objects

FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


def _doctests() -> list[doctest.DocTest]:
    modules = sorted({obj.__module__ for obj in public_objects().values()})
    finder = doctest.DocTestFinder(exclude_empty=True)
    tests = []
    for name in modules:
        tests += [t for t in finder.find(importlib.import_module(name), name) if t.examples]
    return sorted(tests, key=lambda t: t.name)


DOCTESTS = _doctests()


def test_there_are_examples():
    # the collection itself can go wrong (a finder that sees nothing would pass every parametrised case)
    assert len(DOCTESTS) >= 40, [t.name for t in DOCTESTS]


@pytest.mark.parametrize("test", DOCTESTS, ids=[t.name for t in DOCTESTS])
def test_docstring_examples(test: doctest.DocTest):
    report: list[str] = []
    result = doctest.DocTestRunner(optionflags=FLAGS).run(test, out=report.append)
    assert result.failed == 0, "".join(report)
