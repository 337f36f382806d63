"""Static equilibrium of the journal: where the film carries a given constant load."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy.optimize import least_squares


def _polar(eps: float, phi: float, c: float) -> np.ndarray:
    """Position at eccentricity ratio eps and angle phi (from +X2 towards +X1)."""
    return c * eps * np.array([math.sin(phi), math.cos(phi)])


def equilibrium(model, load, guess: tuple[float, float] | None = None, eps_max: float = 0.995) -> dict:
    """Journal position at which the film force balances ``load`` = (W1, W2) [N] at rest.

    Solves F_film(X, 0) + W = 0 in polar unknowns (eps, phi) with eps bounded
    below ``eps_max``.  Returns eps, the position X1, X2 [m], the attitude
    angle [deg] between the load line and the line of centres, the residual
    relative to |W| and the Sommerfeld number.
    """
    W = np.asarray(load, dtype=float).reshape(2)
    w = float(np.hypot(*W))
    if not math.isfinite(w) or w <= 0.0:
        raise ValueError(f"load must be a finite non-zero vector in N, got {tuple(W)}")
    c = model.bearing.clearance
    phi_load = math.atan2(W[0], W[1])
    zero = np.zeros(2)

    def residual(q):
        return (model.forces(_polar(q[0], q[1], c), zero) + W) / w

    starts = [guess] if guess is not None else [(e, phi_load + a) for e in (0.3, 0.6, 0.85)
                                                for a in (math.radians(-60), math.radians(-30), 0.0)]
    best = None
    for e0, p0 in starts:
        sol = least_squares(residual, x0=[e0, p0], bounds=([0.0, -np.inf], [eps_max, np.inf]),
                            xtol=1e-14, ftol=1e-14, gtol=1e-14)
        if best is None or sol.cost < best.cost:
            best = sol
        if best.cost < 1e-20:
            break
    assert best is not None  # starts is never empty
    eps, phi = float(best.x[0]), float(best.x[1])
    X = _polar(eps, phi, c)
    attitude = math.degrees((phi_load - phi + math.pi) % (2 * math.pi) - math.pi)
    return {"eps": eps, "X1": float(X[0]), "X2": float(X[1]), "attitude_deg": attitude,
            "residual": float(np.hypot(*residual(best.x))), "load_N": w,
            "sommerfeld": model.bearing.sommerfeld(w)}


def equilibrium_locus(model, loads, direction_deg: float = 0.0) -> pd.DataFrame:
    """Equilibrium positions for load magnitudes ``loads`` [N] along ``direction_deg``
    (from +X2 towards +X1; 0 = gravity), by continuation from the smallest load."""
    a = math.radians(direction_deg)
    rows = []
    guess = None
    for load in sorted(float(v) for v in loads):
        r = equilibrium(model, (load * math.sin(a), load * math.cos(a)), guess=guess)
        c = model.bearing.clearance
        guess = (r["eps"], math.atan2(r["X1"] / c, r["X2"] / c))
        rows.append(r)
    return pd.DataFrame(rows)
