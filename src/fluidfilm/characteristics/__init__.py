"""What a bearing engineer computes first: static characteristics, the eight K/C coefficients, the whirl threshold.

Any force model with ``.forces(X, V)`` and ``.bearing`` plugs in (the reference
solvers, the grooved solver, the surrogates, the short-bearing model)::

    from fluidfilm.characteristics import bearing_characteristics
    out = bearing_characteristics(model, load=24.5)        # N along +X2 (gravity)
    out["eps"], out["attitude_deg"], out["Kxx"], ..., out["critical_mass_bar"], out["whirl_ratio"]

Modules: ``static`` (equilibrium, eps/attitude/friction/flows vs Sommerfeld,
feed options), ``film`` (friction, power loss, side and feed flow from a
pressure field), ``coefficients`` (K/C), ``stability`` (Lund's criterion,
threshold speed, nonlinear check), ``shortbearing`` (Ocvirk, the
independent check), ``published`` (typed-in tables with sources).
"""
from fluidfilm.characteristics import coefficients, film, published, shortbearing, stability, static
from fluidfilm.characteristics.coefficients import NAMES as COEFFICIENT_NAMES
from fluidfilm.characteristics.static import equilibrium, film_solver, sommerfeld_sweep, static_point
from fluidfilm.characteristics.stability import lund, operating_point, threshold_speed


def bearing_characteristics(model, load: float, h_rel: float = 1e-4) -> dict:
    """Equilibrium under ``load`` [N] along +X2, the eight coefficients (dimensional K, C and
    dimensionless Kxx..Cyy) and Lund's stability numbers there."""
    return operating_point(model, load, h_rel)


__all__ = ["bearing_characteristics", "equilibrium", "film_solver", "sommerfeld_sweep", "static_point", "lund",
           "operating_point", "threshold_speed", "COEFFICIENT_NAMES", "coefficients", "film", "published",
           "shortbearing", "stability", "static"]
