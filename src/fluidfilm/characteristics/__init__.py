"""What a bearing engineer computes first: static characteristics, the eight K/C coefficients, the whirl threshold.

Any force model with ``.forces(X, V)`` and ``.bearing`` plugs in (the reference
solvers, the grooved solver, the surrogates, the short-bearing model)::

    from fluidfilm.characteristics import bearing_characteristics, load_along_gravity
    out = bearing_characteristics(model, load_along_gravity(24.5))   # the load vector (0, 24.5) N, +X2 = gravity
    out["eps"], out["attitude_deg"], out["Kxx"], ..., out["critical_mass_bar"], out["whirl_ratio"]

Conventions (one for the whole workspace): a load is a vector (W1, W2) [N];
the attitude angle [deg] runs from the load line to the line of centres,
positive in the direction of rotation (from +X2 towards +X1); K[i, j] =
-dF_i/dX_j with i, j = 0, 1 for X1, X2, and Kxx..Cyy name the same axes,
x = X1, y = X2 (``coefficients`` module doc; Lund & Thomsen's x is along the
load, ``published.LUND_THOMSEN_INDEX``).

Modules: ``static`` (equilibrium, eps/attitude/friction/flows vs Sommerfeld,
feed options), ``film`` (friction, power loss, side and feed flow from a
pressure field), ``coefficients`` (K/C), ``stability`` (Lund's criterion,
threshold speed, nonlinear check), ``shortbearing`` (Ocvirk, the
independent check), ``published`` (typed-in tables with sources).
"""
from fluidfilm.characteristics import coefficients, film, published, shortbearing, stability, static
from fluidfilm.characteristics.coefficients import NAMES as COEFFICIENT_NAMES
from fluidfilm.characteristics.static import (equilibrium, equilibrium_locus, film_solver, load_along_gravity,
                                              sommerfeld_sweep, static_point)
from fluidfilm.characteristics.stability import lund, operating_point, threshold_speed


#: the engineer's name for it: equilibrium under a load vector, the eight coefficients and Lund's stability
#: numbers there (one function, ``stability.operating_point``)
bearing_characteristics = operating_point


__all__ = ["bearing_characteristics", "equilibrium", "equilibrium_locus", "load_along_gravity", "film_solver", "sommerfeld_sweep", "static_point", "lund",
           "operating_point", "threshold_speed", "COEFFICIENT_NAMES", "coefficients", "film", "published",
           "shortbearing", "stability", "static"]
