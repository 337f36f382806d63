"""The surrogate at inference time, under its earlier address: the force model and its generic kernel.

The force model (``SurrogateForceModel``, ``load_surrogate``, the saved files' schema and checksums) lives in
``surrogate.model``, the compiled evaluation in ``surrogate.kernels`` (``surrogate.kernels.generic``: the
generic one-state kernel ``surrogate_force``); this module re-exports both for the code and documents that
import them from here.
"""
from __future__ import annotations

from fluidfilm.surrogate.activations import ACTIVATIONS
from fluidfilm.surrogate.kernels.generic import (Structure, SurrogateParams, _region_force, _surrogate_batch,
                                                 pack_network, speed_scaled_force, surrogate_force)
from fluidfilm.surrogate.model import (MODEL_JSON_SCHEMA, SurrogateFileError, SurrogateForceModel, load_surrogate)

__all__ = ["ACTIVATIONS", "Structure", "SurrogateParams", "pack_network", "speed_scaled_force", "surrogate_force",
           "MODEL_JSON_SCHEMA", "SurrogateFileError", "SurrogateForceModel", "load_surrogate"]
_REEXPORTED = (_region_force, _surrogate_batch)
