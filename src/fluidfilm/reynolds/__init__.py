"""Finite-difference Reynolds solver (private package; public names are re-exported by ``fluidfilm``).

One responsibility per module:

- ``mesh``       nodes of the (theta, z) grid and Simpson integration weights
- ``kernels``    the numba kernels: separable fast solve, Gumbel clipping and
                 force integration, projected SOR for Swift-Stieber cavitation
- ``solver``     ``ReynoldsSolver``: validation, the public API, batching
- ``policy``     the paper's grid policy (coarse grid at low, dense at high eccentricity)
"""
from .policy import GradedReynoldsModel
from .solver import CAVITATION_MODELS, ReynoldsSolver

__all__ = ["ReynoldsSolver", "GradedReynoldsModel", "CAVITATION_MODELS"]
