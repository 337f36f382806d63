"""Moved to ``fluidfilm.surrogate.training.protocol``; this name stays an alias of that module."""
import sys

from fluidfilm.surrogate.training import protocol as _moved

sys.modules[__name__] = _moved
