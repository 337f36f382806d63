"""Finite-difference Reynolds solver (private package; public names are re-exported by ``fluidfilm``).

One responsibility per module:

- ``mesh``       nodes of the (theta, z) grid and Simpson integration weights
- ``kernels``    the numba kernels: separable fast solve, Gumbel clipping and
                 force integration, projected SOR for Swift-Stieber cavitation
- ``solver``     ``ReynoldsSolver``: validation, the public API, batching
- ``conical``    the adjustable conical bearing: eigenbasis fast path, general
                 h(theta, z) path, axial force, sleeve displacement
- ``policy``     the paper's grid policy (coarse grid at low, dense at high eccentricity)
- ``params``     the kernels' named parameters (``FilmParams``, ``GeneralParams``) and ``Cavitation``
- ``elrod_adams`` mass-conserving cavitation (JFO / Elrod-Adams p-theta film): kernels and
                 ``ElrodAdamsSolver`` (the same grid and feed under Guembel or Swift-Stieber too)
- ``jfo_cases``  published mass-conserving test cases with exact solutions (Ausas et al. 2009)
"""
from fluidfilm.reynolds.conical import ConicalReynoldsSolver
from fluidfilm.reynolds.elrod_adams import ElrodAdamsSolver
from fluidfilm.reynolds.params import Cavitation, FilmParams, GeneralParams
from fluidfilm.reynolds.policy import GradedReynoldsModel, make_solver
from fluidfilm.reynolds.solver import CAVITATION_MODELS, ReynoldsSolver

__all__ = ["ReynoldsSolver", "ConicalReynoldsSolver", "ElrodAdamsSolver", "GradedReynoldsModel", "CAVITATION_MODELS", "make_solver",
           "Cavitation", "FilmParams", "GeneralParams"]
