"""Every public function and class (``public_api.public_objects``) has a NumPy-style docstring whose
documented parameters are the signature's.

Checked, with a small parser of NumPy sections (a title underlined with dashes):

- a "Parameters" section whose names equal the signature's, in order (``self`` aside; ``*args`` and
  ``**kwargs`` only where documented); a class is checked against its constructor;
- a "Returns" (or "Yields") section for a function that returns a value (a return annotation other
  than None, or a ``return <value>`` in its own body);
- an "Examples" section with at least one ``>>>`` line (test_doctests.py runs them).
"""
from __future__ import annotations

import ast
import enum
import inspect
import re
import textwrap

import pytest
from public_api import public_objects

PUBLIC = public_objects()

_UNDERLINE = re.compile(r"^-{3,}$")


def sections(doc: str) -> dict[str, list[str]]:
    """{title: lines} of a NumPy docstring (``inspect.cleandoc``'d), the text before the first title aside."""
    lines = inspect.cleandoc(doc).splitlines()
    out: dict[str, list[str]] = {}
    title = None
    i = 0
    while i < len(lines):
        if i + 1 < len(lines) and lines[i].strip() and _UNDERLINE.match(lines[i + 1].strip()) \
                and len(lines[i + 1].strip()) == len(lines[i].strip()):
            title = lines[i].strip()
            out[title] = []
            i += 2
            continue
        if title is not None:
            out[title].append(lines[i])
        i += 1
    return out


def documented_parameters(lines: list[str]) -> list[str]:
    """The names of a Parameters section: its unindented lines ``name : type`` (or ``a, b : type``)."""
    names = []
    for line in lines:
        if line.strip() and not line[0].isspace():
            names += [n.strip().lstrip("*") for n in line.split(" :")[0].split(",")]
    return names


def own_doc(obj) -> str | None:
    # a class's own docstring (getdoc would inherit the base's; a dataclass's default is its signature)
    doc = obj.__dict__.get("__doc__") if inspect.isclass(obj) else obj.__doc__
    if inspect.isclass(obj) and doc and doc.startswith(f"{obj.__name__}("):
        return None
    return doc


def expected_parameters(obj, documented: list[str]) -> list[str]:
    if inspect.isclass(obj) and issubclass(obj, (enum.Enum, BaseException)):
        return []  # an enum is called with a member's value, an exception with its message
    try:
        sig = inspect.signature(obj)
    except ValueError:  # no signature (a builtin's constructor)
        return []
    variadic = (inspect.Parameter.VAR_POSITIONAL, inspect.Parameter.VAR_KEYWORD)
    return [p.name for p in sig.parameters.values()
            if p.name != "self" and (p.kind not in variadic or p.name in documented)]


def returns_value(func) -> bool:
    """Whether a function returns something: by its annotation, else by a ``return <value>`` of its own."""
    ann = inspect.signature(func).return_annotation
    if ann is not inspect.Signature.empty:
        return ann not in (None, "None")
    tree = ast.parse(textwrap.dedent(inspect.getsource(func)))
    body = tree.body[0]

    def walk(node):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)):
                continue
            yield child
            yield from walk(child)

    return any(isinstance(n, (ast.Yield, ast.YieldFrom)) or (isinstance(n, ast.Return) and n.value is not None
               and not (isinstance(n.value, ast.Constant) and n.value.value is None)) for n in walk(body))


def problems(obj) -> list[str]:
    """What is missing or wrong in ``obj``'s docstring (empty when it is complete)."""
    doc = own_doc(obj)
    if not doc:
        return ["no docstring"]
    secs = sections(doc)
    out = []
    documented = documented_parameters(secs.get("Parameters", []))
    expected = expected_parameters(obj, documented)
    if expected and "Parameters" not in secs:
        out.append(f"no Parameters section (signature: {expected})")
    elif documented != expected:
        out.append(f"documented parameters {documented} differ from the signature's {expected}")
    if inspect.isfunction(obj) and returns_value(obj) and not ({"Returns", "Yields"} & secs.keys()):
        out.append("returns a value but has no Returns section")
    if not any(line.lstrip().startswith(">>>") for line in secs.get("Examples", [])):
        out.append("no Examples section with a >>> line")
    return out


def test_public_names_found():
    # the list itself: names from several subpackages, each module-qualified once
    assert {"fluidfilm.core.bearing.JournalBearing", "fluidfilm.rotor.integrate.simulate",
            "fluidfilm.perf.benchmarking.median_seconds", "fluidfilm.core.force_model.ForceModel"} <= PUBLIC.keys()


def _good(a, b=1.0, *args, **kwargs):
    """Add.

    Parameters
    ----------
    a : float
        First.
    b : float, default 1.0
        Second.

    Returns
    -------
    float

    Examples
    --------
    >>> _good(1.0)
    2.0
    """
    return a + b


def _bad(a, c, b=1.0):
    """Add.

    Parameters
    ----------
    a, b : float
        Two of them.

    Examples
    --------
    Nothing runs here.
    """
    return a + b


def test_checker_accepts_a_complete_docstring_and_names_each_fault():
    assert problems(_good) == []
    assert problems(_bad) == ["documented parameters ['a', 'b'] differ from the signature's ['a', 'c', 'b']",
                              "returns a value but has no Returns section",
                              "no Examples section with a >>> line"]


@pytest.mark.parametrize("name", sorted(PUBLIC))
def test_docstring_matches_signature(name: str):
    found = problems(PUBLIC[name])
    assert not found, f"{name}: " + "; ".join(found)
