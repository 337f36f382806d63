"""The surrogate's evaluation: one network (input scaling, frame, MLP, gain, blend) in every form the library runs.

============================ ========================================================================
module                       what it holds
============================ ========================================================================
``reference``                the evaluation written once to be read: plain NumPy, vectorised over
                             states (``reference_forces``); every path below is tested against it
``generic``                  ``surrogate_force``: the generic one-state numba kernel (any shape, its
                             tables and codes read at run time); ``SurrogateParams``
``folding``                  the scalings folded into the networks; ``shape_key``: what a compiled
                             kernel depends on
``generated``                the one-state kernel generated per shape (``kernel_source``,
                             ``fast_force_kernel``): what ``simulate`` runs
``generic_batch``            ``forces_batch``: many states per call, any shape
``generated_batch``          the batched kernel generated per shape (``batch_kernel_source``,
                             ``batch_kernel``): what ``simulate_batch`` calls per RK4 stage
``cache``                    the generated kernels written as modules and cached by numba on disk
``jacobian``                 the exact Jacobian dF/d(X, V) by forward-mode dual numbers
============================ ========================================================================

Each reads a network's scaling row by the names of ``surrogate.contract`` and its activation from
``surrogate.activations`` (the registry of every activation's compiled, NumPy and torch forms).  The
generated kernels are Python source written for one model *shape* (regions, frames, scaling kinds, layer
widths, activation, blending, domain rows): to read one, write it to files with ``write_kernel_sources``
(``make kernel-source`` writes those of the universal model into ``build/kernels/``):

>>> import tempfile
>>> from fluidfilm import paper_bearing
>>> from fluidfilm.surrogate.universal import universal_bearing
>>> paths = write_kernel_sources(universal_bearing(paper_bearing()), tempfile.mkdtemp())
>>> sorted(p.name for p in paths)
['batched_float32.py', 'batched_float64.py', 'one_state_float32.py', 'one_state_float64.py']

Accuracy (tested): the fast float64 kernels equal the generic one to round-off (``tanh64`` is within
1.5e-15 relative of ``math.tanh``; one reciprocal per division); the float32 networks give forces within
1e-5 of float64 relative to the larger of |F| and the states' RMS force.  The training-domain counter keeps
its meaning in every kernel: every evaluation outside the domain adds one to the model's counter (a few
scalar compares per call, written without early exits).  Timings of each kernel are in
docs/fast_surrogates.md.
"""
from __future__ import annotations

from pathlib import Path

from fluidfilm.surrogate.activations import (pade_tanh32, pade_tanh64, sigmoid32, sigmoid64, silu32, silu64, tanh32,
                                             tanh64)
from fluidfilm.surrogate.kernels.cache import (KERNEL_CACHE_ENV, _import_kernel_module, batch_kernel_files,
                                               kernel_cache_dir, kernel_files, kernel_module_source)
from fluidfilm.surrogate.kernels.folding import RegionKey, ShapeKey, _folded_networks, power_form, shape_key
from fluidfilm.surrogate.kernels.generated import (_ONE_STATE_HEADER, BLEND, COUNTER, EPS_MAX, HEAD, SETTING, Layout,
                                                   _act_expr, _uniform, compile_seconds, compiled_kernel,
                                                   fast_force_kernel, float32_tail, kernel_source, one_state_function,
                                                   pack)
from fluidfilm.surrogate.kernels.generated_batch import (WORKSPACE_STATES, FastBatchParams, _relu, batch_kernel,
                                                         batch_kernel_source, batch_shape_key, fast_batch_params,
                                                         with_workspace)
from fluidfilm.surrogate.kernels.generic_batch import LANE, TILE, BatchParams, batch_params, forces_batch
from fluidfilm.surrogate.kernels.reference import reference_forces

__all__ = ["tanh64", "tanh32", "silu64", "silu32", "sigmoid64", "sigmoid32", "pade_tanh64", "pade_tanh32",
           "fast_force_kernel", "shape_key", "pack", "kernel_source", "one_state_function", "compiled_kernel",
           "compile_seconds", "BatchParams", "batch_params", "forces_batch", "TILE", "FastBatchParams",
           "batch_shape_key", "fast_batch_params", "batch_kernel_source", "batch_kernel", "with_workspace",
           "WORKSPACE_STATES", "reference_forces", "write_kernel_sources", "kernel_sources"]

# what the package re-exports for its earlier single-module users (tests, benchmarks) besides __all__
_REEXPORTED = (KERNEL_CACHE_ENV, _import_kernel_module, batch_kernel_files, kernel_cache_dir, kernel_files,
               kernel_module_source, RegionKey, ShapeKey, _folded_networks, power_form, _ONE_STATE_HEADER, BLEND,
               COUNTER, EPS_MAX, HEAD, SETTING, Layout, _act_expr, _uniform, float32_tail, _relu, LANE)


def kernel_sources(model) -> dict[str, str]:
    """The Python source of each kernel generated for ``model``'s shape, by name: ``one_state_float64``,
    ``one_state_float32`` and, where the shape has a generated batched kernel, ``batched_float64``,
    ``batched_float32`` (what numba compiles; ``write_kernel_sources`` writes them to files for reading)."""
    key = shape_key(model)
    out = {f"one_state_{p}": kernel_source(key, p) for p in ("float64", "float32")}
    batch_key = batch_shape_key(model)
    if batch_key is not None:
        out.update({f"batched_{p}": batch_kernel_source(batch_key, p) for p in ("float64", "float32")})
    return out


def write_kernel_sources(model, folder) -> list[Path]:
    """Write ``kernel_sources(model)`` into ``folder`` as ``<name>.py``, one file a kernel; returns the paths."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, text in kernel_sources(model).items():
        path = folder / f"{name}.py"
        path.write_text(f"# {name} kernel of {getattr(model, 'name', 'a surrogate')} (fluidfilm.surrogate.kernels."
                        f"write_kernel_sources): generated source, for reading\n" + text)
        paths.append(path)
    return paths
