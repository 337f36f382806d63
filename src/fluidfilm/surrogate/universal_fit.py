"""Moved to ``fluidfilm.surrogate.training.universal_fit``; this name stays an alias of that module."""
import sys

from fluidfilm.surrogate.training import universal_fit as _moved

sys.modules[__name__] = _moved
