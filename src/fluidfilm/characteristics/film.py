"""Friction (power loss) and flows of a film from its pressure field.

Given the pressure field p(theta, z) of a state (from ``ReynoldsSolver.pressure``
or ``GroovedReynoldsSolver.pressure``, SI units) and the film thickness
h(theta) = c - X1 sin(theta) - X2 cos(theta) in the same frame:

- friction force on the journal (the shear stress of the Couette and
  Poiseuille flows on the moving surface, integrated over the whole surface)

      F_f = int int ( mu omega R / h + (h / (2 R)) dp/dtheta ) R dtheta dz,

  torque T = R F_f, power loss P = T omega.  As in Raimondi & Boyd's tables
  the Couette shear is counted all the way round (the cavitated region is
  taken as filled with lubricant); ``full_shear=False`` counts it only where
  p > 0.  The pressure-gradient term vanishes where the film is cavitated.
- side flow out of both axial ends (second-order one-sided dp/dz)

      Q_s = int (h^3 / (12 mu)) ( dp/dz|_{z=0} - dp/dz|_{z=L} ) R dtheta,

- circumferential flow through the axial line theta_k (downstream one-sided
  dp/dtheta), used as the flow entering the film at the feed (Raimondi &
  Boyd's Q):  Q(theta_k) = int ( omega R h / 2 - h^3/(12 mu R) dp/dtheta ) dz.

Integrals by the same Simpson weights the force uses.
"""
from __future__ import annotations

import numpy as np


def film_thickness(theta: np.ndarray, x, clearance: float) -> np.ndarray:
    return clearance - x[0] * np.sin(theta) - x[1] * np.cos(theta)


def film_flows_and_friction(p: np.ndarray, mesh, bearing, x, feed_index: int | None = None,
                            full_shear: bool = True) -> dict:
    """Friction force [N], torque [N m], power loss [W], side flow [m^3/s] and feed flow [m^3/s] of field ``p``.

    ``x``: journal position [m] in the frame of ``p``'s grid; ``feed_index``:
    node column of the feed (default: the node of maximum film thickness).
    """
    p = np.asarray(p, dtype=float)
    if p.shape != (mesh.n_theta, mesh.n_z):
        raise ValueError(f"pressure field must have shape {(mesh.n_theta, mesh.n_z)}, got {p.shape}")
    r = bearing.radius
    mu = bearing.viscosity
    omega = bearing.omega
    h = film_thickness(mesh.theta, x, bearing.clearance)
    if np.any(h <= 0.0):
        raise ValueError(f"position {tuple(x)} m touches the sleeve (clearance {bearing.clearance} m)")
    dth = mesh.dtheta
    dz = mesh.dz
    w_t, w_z = mesh.w_theta, mesh.w_z
    dp_dth = (np.roll(p, -1, axis=0) - np.roll(p, 1, axis=0)) / (2.0 * dth)
    couette = mu * omega * r / h
    if full_shear:
        couette_field = np.repeat(couette[:, None], mesh.n_z, axis=1)
    else:
        couette_field = np.where(p > 0.0, couette[:, None], 0.0)
    tau = couette_field + (h[:, None] / (2.0 * r)) * dp_dth
    friction = float(r * w_t @ tau @ w_z)
    torque = friction * r
    dp_dz0 = (-3.0 * p[:, 0] + 4.0 * p[:, 1] - p[:, 2]) / (2.0 * dz)
    dp_dzL = (3.0 * p[:, -1] - 4.0 * p[:, -2] + p[:, -3]) / (2.0 * dz)
    q_side = float(r * w_t @ (h**3 / (12.0 * mu) * (dp_dz0 - dp_dzL)))
    k = int(np.argmax(h)) if feed_index is None else int(feed_index)
    n = mesh.n_theta
    dp_feed = (-3.0 * p[k] + 4.0 * p[(k + 1) % n] - p[(k + 2) % n]) / (2.0 * dth)
    q_feed = float(w_z @ (omega * r * h[k] / 2.0 - h[k] ** 3 / (12.0 * mu * r) * dp_feed))
    return {"friction_N": friction, "torque_Nm": torque, "power_W": torque * omega,
            "side_flow_m3s": q_side, "feed_flow_m3s": q_feed}


def raimondi_boyd_variables(bearing, load: float, friction: float, feed_flow: float, side_flow: float) -> dict:
    """Raimondi & Boyd's dimensionless groups: S, (R/c) f, Q/(R c N L), Q_s/Q."""
    r, c, length = bearing.radius, bearing.clearance, bearing.length
    n_rps = bearing.speed_rpm / 60.0
    return {"sommerfeld": bearing.sommerfeld(load),
            "friction_variable": (r / c) * friction / load,
            "flow_variable": feed_flow / (r * c * n_rps * length),
            "side_flow_ratio": side_flow / feed_flow}
