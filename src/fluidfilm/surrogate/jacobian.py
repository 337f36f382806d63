"""Moved to ``fluidfilm.surrogate.kernels.jacobian``; this name stays an alias of that module."""
import sys

from fluidfilm.surrogate.kernels import jacobian as _moved

sys.modules[__name__] = _moved
