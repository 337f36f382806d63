"""Training the surrogates (torch, Lightning, Levenberg-Marquardt): everything that fits weights, nothing that runs them.

============================ ========================================================================
module                       what it holds
============================ ========================================================================
``lightning``                the Lightning force networks (``ForceMLP``, ``ForceDataModule``,
                             ``train_network``, ``read_dataset``) and their fast torch layers
``fit``                      ``fit_surrogate``: one network per eccentricity region, trained side by
                             side, saved as a ``SurrogateForceModel``; ``held_out_errors``
``levenberg_marquardt``      Levenberg-Marquardt for one-hidden-layer networks (the paper's optimiser)
``protocol``                 the paper's training protocol (``train_protocol_model``)
``universal_fit``            the universal bearing's networks (``train_universal``, ``write_weights``)
============================ ========================================================================

A trained model runs without torch: ``surrogate.model`` and ``surrogate.kernels``.  The names of
``lightning`` are reachable from this package too (``fluidfilm.surrogate.training.ForceMLP``, the address
they had when this package was one module); importing the package imports no torch until one is asked for.
"""
from __future__ import annotations

import importlib

_MODULES = ("lightning", "fit", "levenberg_marquardt", "protocol", "universal_fit")


def __getattr__(name: str):
    # a module of the package (``from ... import fit`` asks here first), else a name of the Lightning networks
    # under the package's name (their address before the package), imported on first use: the users of fit,
    # the protocol or Levenberg-Marquardt do not import Lightning through this package
    if name in _MODULES:
        return importlib.import_module(f"{__name__}.{name}")
    if not name.startswith("__"):
        lightning = importlib.import_module(f"{__name__}.lightning")
        if hasattr(lightning, name):
            return getattr(lightning, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
