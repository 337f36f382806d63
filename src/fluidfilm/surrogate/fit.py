"""Moved to ``fluidfilm.surrogate.training.fit``; this name stays an alias of that module."""
import sys

from fluidfilm.surrogate.training import fit as _moved

sys.modules[__name__] = _moved
