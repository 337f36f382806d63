"""The eight linearised stiffness and damping coefficients of a film at an equilibrium.

F(X0 + dX, dV) ~ F(X0, 0) - K dX - C dV,  i.e.  K_ij = -dF_i/dX_j,  C_ij = -dF_i/dV_j

(index 1, 2 = the workspace's X1, X2 axes; X2 along gravity, so with a
gravity load X2 is the load direction).  Dimensionless as is usual in the
field: Kbar = K c / W, Cbar = C c omega / W, with W the static load.

Derivatives by central differences of ``model.forces`` for every model:
position step ``h_rel * c``, velocity step ``h_rel * c * omega`` (the
velocity scale of a whirl at running speed, so both steps perturb the film
alike).  For the finite-difference reference the step must sit between the
truncation error (O(h^2)) and the solver's own noise (PSOR tolerance, the
discrete jumps of Gumbel clipping when a node changes sign): ``step_study``
shows the coefficients at a ladder of steps, and the default 1e-4 lies on
the plateau (tests and reports/characteristics.json record the spread).
For the surrogates (a smooth float64 network) the same central differences
with h_rel = 1e-5, near the optimum (machine eps)^(1/3) ~ 6e-6 of a
central difference, are accurate to ~1e-9 relative: derivatives of the
network itself, not of a fit to it; ``step_study`` confirms the plateau.
"""
from __future__ import annotations

import numpy as np

NAMES = ("Kxx", "Kxy", "Kyx", "Kyy", "Cxx", "Cxy", "Cyx", "Cyy")


def coefficients(model, x0, h_rel: float = 1e-4) -> dict:
    """K (2, 2) [N/m] and C (2, 2) [N s/m] of ``model`` at position ``x0`` [m] (journal at rest)."""
    if not (np.isfinite(h_rel) and 0.0 < h_rel < 0.05):
        raise ValueError(f"h_rel must lie in (0, 0.05), got {h_rel!r}")
    b = model.bearing
    c, om = b.clearance, b.omega
    x0 = np.asarray(x0, dtype=float).reshape(2)
    dx = h_rel * c
    dv = h_rel * c * om
    X = []
    V = []
    for j in range(2):
        e = np.zeros(2)
        e[j] = 1.0
        X += [x0 + dx * e, x0 - dx * e, x0, x0]
        V += [np.zeros(2), np.zeros(2), dv * e, -dv * e]
    F = np.asarray(model.forces(np.array(X), np.array(V)))
    K = np.empty((2, 2))
    C = np.empty((2, 2))
    for j in range(2):
        fp, fm, gp, gm = F[4 * j: 4 * j + 4]
        K[:, j] = -(fp - fm) / (2.0 * dx)
        C[:, j] = -(gp - gm) / (2.0 * dv)
    F0 = np.asarray(model.forces(x0, np.zeros(2)))
    return {"K": K, "C": C, "F0": F0, "load_N": float(np.hypot(*F0))}


def dimensionless(kc: dict, bearing, load: float | None = None) -> dict:
    """{Kxx: Kbar, ..., Cyy: Cbar} with Kbar = K c / W, Cbar = C c omega / W."""
    w = kc["load_N"] if load is None else float(load)
    c, om = bearing.clearance, bearing.omega
    k = kc["K"] * c / w
    cc = kc["C"] * c * om / w
    return {"Kxx": k[0, 0], "Kxy": k[0, 1], "Kyx": k[1, 0], "Kyy": k[1, 1],
            "Cxx": cc[0, 0], "Cxy": cc[0, 1], "Cyx": cc[1, 0], "Cyy": cc[1, 1]}


def step_study(model, x0, steps=(1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5)) -> list[dict]:
    """Dimensionless coefficients at a ladder of relative steps (to show the plateau)."""
    rows = []
    for h in steps:
        kc = coefficients(model, x0, h)
        rows.append({"h_rel": h, **dimensionless(kc, model.bearing)})
    return rows


def relative_errors(test: dict, ref: dict) -> dict:
    """Per-coefficient error relative to the reference, each normalised by the largest reference
    coefficient of its kind (stiffness or damping): a cross term passing through zero would make a
    plain ratio meaningless."""
    ks = max(abs(ref[n]) for n in NAMES[:4])
    cs = max(abs(ref[n]) for n in NAMES[4:])
    return {n: abs(test[n] - ref[n]) / (ks if n[0] == "K" else cs) for n in NAMES}
