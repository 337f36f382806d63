"""Neural surrogates of the bearing forces.

Training (torch, Lightning) lives in ``training`` and ``fit``; inference
(numpy, numba) in ``inference``, so a saved model loads and runs without
torch.  Surrogates learn from the dataset (``fluidfilm.data``'s Parquet
columns) and never import the solver's internals.
"""
from fluidfilm.surrogate.inference import ACTIVATIONS, SurrogateForceModel, load_surrogate
from fluidfilm.surrogate.scaling import SCALINGS, Scaling

__all__ = ["SurrogateForceModel", "load_surrogate", "Scaling", "SCALINGS", "ACTIVATIONS"]
