"""Static equilibrium of the journal: where the film carries a given constant load.

``equilibrium`` is ``fluidfilm.characteristics.static.equilibrium`` (one
solver, one load type: the vector (W1, W2) in N, one sign of the attitude
angle, one set of keys); ``load_along_gravity(W)`` gives the vector (0, W)
of a magnitude along +X2.  ``equilibrium_locus`` follows it over a range of
load magnitudes.
"""
from __future__ import annotations

import math

import pandas as pd

from fluidfilm.characteristics.static import check_magnitude, equilibrium, load_along_gravity

#: the columns of ``equilibrium_locus`` (the scalar keys of ``equilibrium``)
LOCUS_COLUMNS = ("eps", "X1", "X2", "attitude_deg", "residual", "load_N", "sommerfeld")


def equilibrium_locus(model, loads, direction_deg: float = 0.0) -> pd.DataFrame:
    """Equilibrium positions for load magnitudes ``loads`` [N] along ``direction_deg``.

    Parameters
    ----------
    model : force model
        Anything with ``.forces(X, V)`` and ``.bearing``.
    loads : sequence of float
        Load magnitudes [N], each positive and finite; solved by continuation
        from the smallest.
    direction_deg : float
        Direction of the load [deg] from +X2 towards +X1 (0 = gravity).

    Returns
    -------
    pandas.DataFrame
        One row per load, columns ``LOCUS_COLUMNS`` (as ``equilibrium``).

    Examples
    --------
    >>> from fluidfilm import ReynoldsSolver, paper_bearing
    >>> locus = equilibrium_locus(ReynoldsSolver(paper_bearing(), 30, 30), [5.0, 50.0])
    >>> bool(locus.eps.is_monotonic_increasing)
    True
    """
    a = math.radians(direction_deg)
    rows = []
    guess = None
    c = model.bearing.clearance
    for load in sorted(check_magnitude("load", v, "N") for v in loads):
        r = equilibrium(model, (load * math.sin(a), load * math.cos(a)), guess=guess)
        guess = (r["eps"], math.atan2(r["X1"] / c, r["X2"] / c))
        rows.append({k: r[k] for k in LOCUS_COLUMNS})
    return pd.DataFrame(rows, columns=list(LOCUS_COLUMNS))


__all__ = ["equilibrium", "equilibrium_locus", "load_along_gravity", "LOCUS_COLUMNS"]
