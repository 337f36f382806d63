"""Moved to ``fluidfilm.surrogate.training.levenberg_marquardt``; this name stays an alias of that module."""
import sys

from fluidfilm.surrogate.training import levenberg_marquardt as _moved

sys.modules[__name__] = _moved
