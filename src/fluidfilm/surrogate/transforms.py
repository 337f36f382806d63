"""The scaling transforms of the force networks, written once for both execution paths.

Each function uses only arithmetic and ``np.sqrt``, so the same source runs

- on NumPy arrays (``Scaling``: fitting, training targets, the validation metric), and
- compiled by numba on scalars inside the force kernel (``inference._region_force``: the
  ``_nb`` twins below are these very functions, jitted).

A test (tests/surrogate/test_surrogate.py) checks the two paths agree to round-off on random states.
"""
from __future__ import annotations

import numpy as np
from numba import njit


def eps2(x1, x2, inv_c2):
    """Squared eccentricity ratio (x1^2 + x2^2) / c^2, with inv_c2 = 1/c^2."""
    return (x1 * x1 + x2 * x2) * inv_c2


def speed(v1, v2):
    """|V| [m/s]."""
    return np.sqrt(v1 * v1 + v2 * v2)


def sleeve_force_scale(force_scale, c_nominal, inv_c2):
    """Force scale at a sleeve position of clearance c_r (inv_c2 = 1/c_r^2): F_scale (c / c_r)^2."""
    return force_scale * c_nominal * c_nominal * inv_c2


def film_gain(force_scale, e2, power):
    """Physics scaling: force per unit of network target, F_scale / (1 - eps^2)^power.

    (1 - eps^2)^1.5, the squeeze-film growth law, is written d sqrt(d): twice as fast as a power.
    """
    d = 1.0 - e2
    return force_scale / (d * np.sqrt(d) if power == 1.5 else d**power)


def velocity_factor(speed_, c, omega):
    """The physics_v scaling's extra factor 1 + |V| / (c omega)."""
    return 1.0 + speed_ / (c * omega)


def radial_axis(x1, x2):
    """Unit vector e_r along the line of centres; (0, 1) (= +X2) at the centre. Branch-free."""
    r = np.sqrt(x1 * x1 + x2 * x2)
    at_centre = r == 0.0
    safe = r + at_centre
    return x1 / safe, x2 / safe + at_centre


def to_polar(er1, er2, a1, a2):
    """Components of a vector (a1, a2) along e_r and e_t = (e_r2, -e_r1)."""
    return a1 * er1 + a2 * er2, a1 * er2 - a2 * er1


def from_polar(er1, er2, g1, g2):
    """Back from (along e_r, along e_t) to (X1, X2)."""
    return g1 * er1 + g2 * er2, g1 * er2 - g2 * er1


def whirl_direction(eps, vr, vt):
    """The film's drive u = (eps - 2 v_t, 2 v_r) (velocities in units of c omega, v_t along e_t), as
    (|u|, u1/|u|, u2/|u|); the direction is (1, 0) where u = 0.  Branch-free.

    In the journal's frame the Reynolds equation's right-hand side is
    eps (omega - 2 dphi/dt) (wedge) plus 2 deps/dt (squeeze), i.e. omega times u, over pressure
    fields that depend on eps alone; the film force (Gumbel or Swift-Stieber) is therefore
    positively homogeneous of degree 1 in u: F(eps, k u) = k F(eps, u) for k >= 0.  A whirl at
    half the shaft speed (v_t = eps / 2, v_r = 0) gives u = 0 and no film force.  With the
    frame ``whirl`` a network learns F / |u| as a function of eps and the direction of u alone.
    """
    a = eps - 2.0 * vt
    b = 2.0 * vr
    m = np.sqrt(a * a + b * b)
    zero = m == 0.0
    safe = m + zero
    return m, a / safe + zero, b / safe


def standardise(raw, mean, std):
    return (raw - mean) / std


def unstandardise(y, mean, std):
    return y * std + mean


# the compiled twins used inside the force kernel
eps2_nb = njit(inline="always")(eps2)
speed_nb = njit(inline="always")(speed)
sleeve_force_scale_nb = njit(inline="always")(sleeve_force_scale)
film_gain_nb = njit(inline="always")(film_gain)
velocity_factor_nb = njit(inline="always")(velocity_factor)
radial_axis_nb = njit(inline="always")(radial_axis)
to_polar_nb = njit(inline="always")(to_polar)
from_polar_nb = njit(inline="always")(from_polar)
whirl_direction_nb = njit(inline="always")(whirl_direction)
standardise_nb = njit(inline="always")(standardise)
unstandardise_nb = njit(inline="always")(unstandardise)
