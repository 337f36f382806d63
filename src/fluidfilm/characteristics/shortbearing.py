"""Short-bearing (Ocvirk) theory with the Gumbel condition: the independent check of the finite-length solver.

For L/D -> 0 the circumferential pressure flow drops out of the Reynolds
equation, d/dz(h^3 dp/dz) = 6 mu omega dh/dtheta + 12 mu dh/dt =: G(theta),
with p = 0 at both ends, so p = G/(2 h^3) (z^2 - L z).  In this workspace's
frame (theta from +X2 towards +X1, h = c - X1 sin(theta) - X2 cos(theta))

    G = A sin(theta) + B cos(theta),  A = 6 mu omega X2 - 12 mu V1,
                                       B = -6 mu omega X1 - 12 mu V2,

a pure sinusoid: the Gumbel film (p > 0 where G < 0) is exactly half the
circumference, also with squeeze velocities.  The force on the journal is

    F = -(R L^3 / 12) int_{G<0} (-G / h^3) (sin(theta), cos(theta)) dtheta,

evaluated here by adaptive quadrature over the known half-circle (error
~1e-12 relative): the "short-bearing force" used for the dynamic
coefficients.  The static closed forms (Ocvirk 1952; e.g. Hamrock,
*Fundamentals of Fluid Film Lubrication*, ch. 11) are

    W = mu omega R L^3 / (4 c^2) * eps / (1 - eps^2)^2 * sqrt(16 eps^2 + pi^2 (1 - eps^2)),
    tan(phi) = pi sqrt(1 - eps^2) / (4 eps).
"""
from __future__ import annotations

import math
import warnings

import numpy as np
from scipy.integrate import IntegrationWarning, quad


def load_capacity(bearing, eps: float) -> float:
    """Ocvirk's load [N] at eccentricity ratio ``eps`` (Gumbel condition)."""
    _check_eps(eps)
    r, c, length = bearing.radius, bearing.clearance, bearing.length
    return (bearing.viscosity * bearing.omega * r * length**3 / (4.0 * c**2) * eps / (1.0 - eps**2) ** 2
            * math.sqrt(16.0 * eps**2 + math.pi**2 * (1.0 - eps**2)))


def attitude_angle_deg(eps: float) -> float:
    """Ocvirk's attitude angle [deg] at eccentricity ratio ``eps``.

    From the load line to the line of centres, positive in the direction of
    rotation (the convention of every ``attitude_deg`` in the workspace).

    Examples
    --------
    >>> round(attitude_angle_deg(0.5), 2)
    53.68
    """
    return math.degrees(attitude_angle_rad(eps))


def attitude_angle_rad(eps: float) -> float:
    """Ocvirk's attitude angle in radians (for solvers: the start of ``static.equilibrium``); users read
    ``attitude_angle_deg``."""
    _check_eps(eps)
    return math.atan2(math.pi * math.sqrt(1.0 - eps**2), 4.0 * eps)


def sommerfeld(bearing, eps: float) -> float:
    return bearing.sommerfeld(load_capacity(bearing, eps))


def eccentricity_at_sommerfeld(bearing, s: float) -> float:
    """Inverse of ``sommerfeld`` (monotone in eps) by bisection-type root finding."""
    from scipy.optimize import brentq
    if not (math.isfinite(s) and s > 0.0):
        raise ValueError(f"Sommerfeld number must be positive and finite, got {s!r}")
    return brentq(lambda e: math.log(sommerfeld(bearing, e) / s), 1e-9, 1.0 - 1e-9, xtol=1e-14)


def _check_eps(eps):
    if not (0.0 < eps < 1.0):
        raise ValueError(f"eccentricity ratio must lie in (0, 1), got {eps!r}")


def force(bearing, x, v) -> np.ndarray:
    """Short-bearing Gumbel force [N] on the journal at position ``x`` [m], velocity ``v`` [m/s]."""
    x1, x2 = float(x[0]), float(x[1])
    v1, v2 = float(v[0]), float(v[1])
    c, r, length, mu, om = bearing.clearance, bearing.radius, bearing.length, bearing.viscosity, bearing.omega
    if math.hypot(x1, x2) >= c:
        raise ValueError(f"position {(x1, x2)} m lies outside the clearance {c} m")
    a = 6.0 * mu * om * x2 - 12.0 * mu * v1
    b = -6.0 * mu * om * x1 - 12.0 * mu * v2
    if a == 0.0 and b == 0.0:
        return np.zeros(2)
    alpha = math.atan2(b, a)
    lo, hi = math.pi - alpha, 2.0 * math.pi - alpha

    def integrand(th, k):
        g = a * math.sin(th) + b * math.cos(th)
        h = c - x1 * math.sin(th) - x2 * math.cos(th)
        return -g / h**3 * (math.sin(th) if k == 0 else math.cos(th))

    out = np.empty(2)
    with warnings.catch_warnings():
        # quad flags round-off when it reaches machine precision on this smooth integrand (harmless here)
        warnings.simplefilter("ignore", IntegrationWarning)
        for k in range(2):
            out[k] = -(r * length**3 / 12.0) * quad(integrand, lo, hi, args=(k,), epsabs=0.0, epsrel=1e-12,
                                                   limit=200)[0]
    return out


class ShortBearingModel:
    """The short-bearing force as a force model (``.forces``, ``.bearing``); not compiled, for checks only."""

    def __init__(self, bearing):
        self._bearing = bearing

    @property
    def bearing(self):
        return self._bearing

    def forces(self, X, V) -> np.ndarray:
        X = np.asarray(X, dtype=float)
        V = np.asarray(V, dtype=float)
        xs, vs = np.broadcast_arrays(X, V)
        flat_x, flat_v = xs.reshape(-1, 2), vs.reshape(-1, 2)
        out = np.array([force(self._bearing, a, b) for a, b in zip(flat_x, flat_v)])
        return out.reshape(xs.shape)
