"""fluidfilm: reference models and machine-learned surrogates of fluid film bearings.

Public API (kept stable for scripts, notebooks and outside checks)::

    from fluidfilm import JournalBearing, ReynoldsSolver
    solver = ReynoldsSolver(bearing, n_theta=30, n_z=30, cavitation="gumbel")
    F = solver.forces(X, V)      # (..., 2) m, (..., 2) m/s -> (..., 2) N

Every force model (reference solver, graded reference, surrogates) offers
``.forces(X, V)``, ``.bearing`` and ``.force_kernel`` (a compiled function
and its parameters), so the rotor integrator and controllers never care
which one they run.  ``universal_bearing(bearing, cavitation)`` is a trained
surrogate for any plain journal bearing (L/D 0.2-2, no supply pressure), shipped
with the package: no dataset, training or DVC pull.
"""
from importlib import metadata as _metadata

from fluidfilm.core.bearing import ConicalBearing, JournalBearing, bearing_from_dict, paper_bearing
from fluidfilm.reynolds import CAVITATION_MODELS, ConicalReynoldsSolver, GradedReynoldsModel, ReynoldsSolver
from fluidfilm.characteristics.static import equilibrium, equilibrium_locus, load_along_gravity
from fluidfilm.rotor import LinearBearing, Rotor, SpeedSchedule, Trajectory, simulate
from fluidfilm.surrogate import SurrogateForceModel, load_surrogate
from fluidfilm.surrogate.universal import universal_bearing

try:  # one place for the version: pyproject.toml, read from the installed package's metadata
    __version__ = _metadata.version("fluidfilm")
except _metadata.PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"

__all__ = [
    "JournalBearing",
    "ConicalBearing",
    "bearing_from_dict",
    "ConicalReynoldsSolver",
    "paper_bearing",
    "ReynoldsSolver",
    "GradedReynoldsModel",
    "CAVITATION_MODELS",
    "Rotor",
    "SpeedSchedule",
    "simulate",
    "Trajectory",
    "LinearBearing",
    "equilibrium",
    "equilibrium_locus",
    "load_along_gravity",
    "load_surrogate",
    "SurrogateForceModel",
    "universal_bearing",
    "__version__",
]
