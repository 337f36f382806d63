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
from fluidfilm.characteristics.static import (equilibrium, film_solver, load_along_gravity, sommerfeld_sweep,
                                              static_point)
from fluidfilm.characteristics.stability import lund, operating_point, threshold_speed


def bearing_characteristics(model, load, h_rel: float = 1e-4) -> dict:
    """Equilibrium under the load vector ``load`` = (W1, W2) [N], the eight coefficients (dimensional K, C
    and dimensionless Kxx..Cyy, x = X1, y = X2) and Lund's stability numbers there (``operating_point``).

    Parameters
    ----------
    model : force model
        Anything with ``.forces(X, V)`` and ``.bearing``.
    load : array_like, shape (2,)
        The load vector (W1, W2) [N]; ``load_along_gravity(W)`` for a magnitude along +X2.
    h_rel : float
        Relative finite-difference step where the model has no exact derivatives.

    Returns
    -------
    dict
        ``operating_point``'s: the equilibrium's keys, ``K`` [N/m] and ``C`` [N s/m] with
        K[i, j] = -dF_i/dX_j, the dimensionless ``Kxx``..``Cyy`` and Lund's ``K0``, ``whirl_ratio``,
        ``critical_mass_bar``.

    Examples
    --------
    >>> from fluidfilm import ReynoldsSolver, paper_bearing
    >>> out = bearing_characteristics(ReynoldsSolver(paper_bearing(), 30, 30), load_along_gravity(24.5))
    >>> round(out["eps"], 2), round(out["attitude_deg"])
    (0.59, 61)
    """
    return operating_point(model, load, h_rel)


__all__ = ["bearing_characteristics", "equilibrium", "load_along_gravity", "film_solver", "sommerfeld_sweep", "static_point", "lund",
           "operating_point", "threshold_speed", "COEFFICIENT_NAMES", "coefficients", "film", "published",
           "shortbearing", "stability", "static"]
