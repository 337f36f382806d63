"""The public names of the library: every function and class in the ``__all__`` of ``fluidfilm`` and of
its subpackages (shared by test_docstrings.py and test_doctests.py)."""
from __future__ import annotations

import importlib
import inspect

#: the packages whose ``__all__`` is the public API (studies, workflow and reporting are the workspace's
#: own machinery, called by the entry points, not by users)
PACKAGES = ("fluidfilm", "fluidfilm.core", "fluidfilm.reynolds", "fluidfilm.rotor", "fluidfilm.characteristics",
            "fluidfilm.data", "fluidfilm.surrogate", "fluidfilm.control", "fluidfilm.perf",
            "fluidfilm.perf.speed", "fluidfilm.perf.throughput")


def public_objects() -> dict[str, object]:
    """``{"module.qualname": obj}`` of every public function and class, each once (a name re-exported
    by ``fluidfilm`` and by its subpackage is one object)."""
    out: dict[str, object] = {}
    for package in PACKAGES:
        mod = importlib.import_module(package)
        names = getattr(mod, "__all__", None)
        if names is None:
            raise AssertionError(f"{package} has no __all__: its public names are not declared")
        for name in names:
            obj = getattr(mod, name)
            if inspect.isfunction(obj) or inspect.isclass(obj):
                out.setdefault(f"{obj.__module__}.{obj.__qualname__}", obj)
    return out
