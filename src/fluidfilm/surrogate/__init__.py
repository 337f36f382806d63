"""Neural surrogates of the bearing forces, by role.

- ``model``: the force model (``SurrogateForceModel``), its files (save, ``load_surrogate``, schema and
  checksums); ``universal`` and ``ensemble``: force models built on it;
- ``contract`` (the scaling row's fields), ``scaling`` and ``transforms`` (the inputs' and outputs'
  scaling), ``activations`` (the registry of every activation's forms): what every evaluation reads;
- ``kernels``: the evaluation itself, a NumPy reference and the compiled kernels (generic, generated per
  shape, batched), and the exact Jacobian;
- ``training``: Lightning, Levenberg-Marquardt, the paper's protocol and the universal fit (torch).

A saved model loads and runs without torch (``model`` and ``kernels`` import numpy and numba only).
Surrogates learn from the dataset (``fluidfilm.data``'s Parquet columns) and never import the solver's
internals.  ``inference``, ``jacobian``, ``fit``, ``protocol``, ``levenberg_marquardt`` and
``universal_fit`` are the earlier addresses of these modules, kept as aliases.
"""
from fluidfilm.surrogate.activations import ACTIVATIONS
from fluidfilm.surrogate.model import SurrogateForceModel, load_surrogate
from fluidfilm.surrogate.scaling import SCALINGS, Scaling

__all__ = ["SurrogateForceModel", "load_surrogate", "Scaling", "SCALINGS", "ACTIVATIONS"]
