"""The eight linearised stiffness and damping coefficients of a film at an equilibrium.

F(X0 + dX, dV) ~ F(X0, 0) - K dX - C dV,  i.e.  K[i, j] = -dF_i/dX_j,  C[i, j] = -dF_i/dV_j

The frame, once for the whole workspace: the arrays ``K`` [N/m] and ``C``
[N s/m] are indexed i, j = 0, 1 for X1, X2 (X1 horizontal, X2 along gravity,
so with a gravity load X2 is the load direction; the journal turns from +X2
towards +X1).  The dimensionless names follow the same axes, **x = X1
(horizontal), y = X2 (along gravity and the load)**: ``Kxy`` = K[0, 1] c / W =
-dF1/dX2 c / W, ``Cyx`` = C[1, 0] c omega / W, and so on
(Kbar = K c / W, Cbar = C c omega / W, with W the static load).  Beware that
the literature often puts x ALONG the load: Lund & Thomsen's tables
(``published.LUND_THOMSEN_1978``) do, so their Kxy is our Kyx (K[1, 0]);
``published.LUND_THOMSEN_INDEX`` maps their names to our K, C and the
Lund & Thomsen comparison (``studies.characteristics_study.lund_thomsen_point``)
reports in their frame under their names.

Derivatives by central differences of ``model.forces`` for every model:
position step ``h_rel * c``, velocity step ``h_rel * c * omega`` (the
velocity scale of a whirl at running speed, so both steps perturb the film
alike).  For the finite-difference reference the step must sit between the
truncation error (O(h^2)) and the solver's own noise (PSOR tolerance, the
discrete jumps of Gumbel clipping when a node changes sign): ``step_study``
shows the coefficients at a ladder of steps, and the default 1e-4 lies on
the plateau (tests and reports/characteristics.json record the spread).
For the surrogates ``reference_coefficients`` uses the exact Jacobian of the
network (forward-mode differentiation, ``jacobian.surrogate_jacobian``);
central differences with h_rel = 1e-5 (near the optimum (machine
eps)^(1/3) of a central difference) agree with it to ~1e-9 relative except
within a step of a hard split boundary, where the force jumps.
"""
from __future__ import annotations

import numpy as np

from fluidfilm.core.force_model import LinearPressureModel

NAMES = ("Kxx", "Kxy", "Kyx", "Kyy", "Cxx", "Cxy", "Cyx", "Cyy")


def coefficients(model, x0, h_rel: float = 1e-4) -> dict:
    """K (2, 2) [N/m] and C (2, 2) [N s/m] of ``model`` at position ``x0`` [m] (journal at rest), by central
    differences; K[i, j] = -dF_i/dX_j, C[i, j] = -dF_i/dV_j, i, j = 0, 1 for X1, X2 (module doc)."""
    if not (np.isfinite(h_rel) and 0.0 < h_rel < 0.05):
        raise ValueError(f"h_rel must lie in (0, 0.05), got {h_rel!r}")
    b = model.bearing
    c, om = b.clearance, _turning(b)
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
    """{Kxx: Kbar, ..., Cyy: Cbar} with Kbar = K c / W, Cbar = C c omega / W; x = X1, y = X2 (so Kxy =
    K[0, 1] c / W: the X1 force per X2 displacement; module doc).  ``load``: the magnitude W [N]
    (default: that of the film force at the point)."""
    w = kc["load_N"] if load is None else float(load)
    if not (np.isfinite(w) and w > 0.0):
        raise ValueError(f"the load scaling the coefficients must be a positive finite magnitude in N, got {w!r}")
    c, om = bearing.clearance, _turning(bearing)
    k = kc["K"] * c / w
    cc = kc["C"] * c * om / w
    return {"Kxx": k[0, 0], "Kxy": k[0, 1], "Kyx": k[1, 0], "Kyy": k[1, 1],
            "Cxx": cc[0, 0], "Cxy": cc[0, 1], "Cyx": cc[1, 0], "Cyy": cc[1, 1]}


def _turning(bearing) -> float:
    """The shaft speed [rad/s], refused if zero: the velocity step and Cbar scale with it."""
    if not bearing.omega > 0.0:
        raise ValueError(f"K and C need a turning shaft; the bearing's speed_rpm={bearing.speed_rpm!r}")
    return bearing.omega


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


def coefficients_gumbel_field(solver, x0, h_rel: float = 1e-4) -> dict:
    """K and C of a Gumbel-clipped ``ReynoldsSolver`` from its linear (pre-clipping) field, the film region frozen.

    With the Gumbel condition F = -int_{p>0} p_lin u dA, and since p_lin = 0
    on the edge of the film region the edge's motion does not change F to
    first order: dF/dq = -int_{p>0} dp_lin/dq u dA.  On a grid, central
    differences of the clipped force instead see nodes switching in and out
    of the film, an O(dtheta) error that does not fall smoothly with the grid
    (the node count near the edge jumps).  So here: dp_lin/dV_j exactly (p_lin is
    linear in V), dp_lin/dX_j by a central difference of the smooth linear
    field, both integrated over the nodes where p_lin(x0) > 0.
    """
    if not (isinstance(solver, LinearPressureModel) and solver.cavitation == "gumbel"):
        raise ValueError("coefficients_gumbel_field needs a ReynoldsSolver with cavitation='gumbel'")
    b = solver.bearing
    c, om = b.clearance, b.omega
    x0 = np.asarray(x0, dtype=float).reshape(2)
    zero = np.zeros(2)
    p0 = solver.linear_pressure(x0, zero)
    theta = solver.theta
    w_z = solver.mesh.w_z
    r = b.radius
    dx = h_rel * c
    dv = c * om  # p_lin is affine in V: any step is exact
    K = np.empty((2, 2))
    C = np.empty((2, 2))
    for j in range(2):
        e = np.zeros(2)
        e[j] = 1.0
        dp = (solver.linear_pressure(x0 + dx * e, zero) - solver.linear_pressure(x0 - dx * e, zero)) / (2.0 * dx)
        # F = -R int p u dA, so K = -dF/dX = +R int dp/dX u dA over the film
        K[:, j] = film_region_integral(p0, dp, theta, w_z, r)
        dq = (solver.linear_pressure(x0, dv * e) - p0) / dv
        C[:, j] = film_region_integral(p0, dq, theta, w_z, r)
    F0 = -film_region_integral(p0, p0, theta, w_z, r)
    return {"K": K, "C": C, "F0": F0, "load_N": float(np.hypot(*F0))}


def film_region_integral(p0: np.ndarray, g: np.ndarray, theta: np.ndarray, w_z: np.ndarray, radius: float):
    """R int int_{p0 > 0} g (sin(theta), cos(theta)) dtheta dz with the film edge located between nodes.

    The integrand of a derivative does not vanish at the film edge, so a
    node-masked Simpson sum is only first-order accurate there (and jumps as
    the edge crosses nodes).  Here each theta cell is integrated by the
    trapezoidal rule up to the edge, found by linear interpolation of p0 (the
    edge is where p0 changes sign): second order, smooth in the position.
    z by the Simpson weights of the grid.
    """
    dth = theta[1] - theta[0]
    a = p0
    b_ = np.roll(p0, -1, axis=0)
    ga = g
    gb = np.roll(g, -1, axis=0)
    th_a = theta[:, None] * np.ones_like(p0)
    both = (a > 0) & (b_ > 0)
    only_a = (a > 0) & ~(b_ > 0)
    only_b = ~(a > 0) & (b_ > 0)
    out = np.zeros(2)
    for k, fn in enumerate((np.sin, np.cos)):
        ua = fn(th_a)
        ub = fn(th_a + dth)
        cell = np.where(both, 0.5 * dth * (ga * ua + gb * ub), 0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            f = np.where(only_a, a / (a - b_), np.where(only_b, b_ / (b_ - a), 0.0))
        # film from node a to the edge at a + f dtheta
        te = th_a + f * dth
        ge = ga + f * (gb - ga)
        cell += np.where(only_a, 0.5 * f * dth * (ga * ua + ge * fn(te)), 0.0)
        # film from the edge at b - f dtheta to node b
        te_b = th_a + (1.0 - f) * dth
        ge_b = gb + f * (ga - gb)
        cell += np.where(only_b, 0.5 * f * dth * (ge_b * fn(te_b) + gb * ub), 0.0)
        out[k] = radius * float(cell.sum(axis=0) @ w_z)
    return out


def reference_coefficients(model, x0, h_rel: float = 1e-4) -> dict:
    """K/C of any model by its best method: the exact (forward-mode) Jacobian of a surrogate network,
    the film-region derivative of a Gumbel ``ReynoldsSolver``, central differences of the force
    otherwise (Swift-Stieber, grooved bearings, other models)."""
    # a model that knows its exact derivatives says so (the surrogates: ``exact_coefficients``, None where
    # it has none); physics does not import the surrogates to ask
    exact = getattr(model, "exact_coefficients", None)
    if exact is not None:
        out = exact(x0)
        if out is not None:
            return out
    if isinstance(model, LinearPressureModel) and model.cavitation == "gumbel":
        return coefficients_gumbel_field(model, x0, h_rel)
    return coefficients(model, x0, h_rel)
