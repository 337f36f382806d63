"""Named parameters of the Reynolds kernels, and the cavitation rule as an enum.

The kernels are numba-compiled and take their parameters as one argument.  A
``typing.NamedTuple`` of arrays and scalars is what numba compiles to a plain
struct (attribute access costs nothing at run time), so the layout has names
here, in one place, instead of positions documented in docstrings.  Being a
tuple, a parameter set is immutable: a new sleeve position or grid builds a
new one.
"""
from __future__ import annotations

from enum import IntEnum
from typing import NamedTuple

import numpy as np


class Cavitation(IntEnum):
    """Cavitation rule of the film (the kernels read the integer value).

    ``NONE``: full Sommerfeld, negative pressures kept (for verification);
    ``GUMBEL``: half-Sommerfeld, negative pressures set to zero after the linear solve;
    ``SWIFT_STIEBER``: Reynolds condition as a complementarity problem (projected SOR).
    """

    NONE = 0
    GUMBEL = 1
    SWIFT_STIEBER = 2

    @property
    def label(self) -> str:
        """The name used in configs and reprs: "none", "gumbel", "swift-stieber"."""
        return self.name.lower().replace("_", "-")

    @classmethod
    def parse(cls, value: str | int | Cavitation) -> Cavitation:
        """From a config label ("gumbel"), a code or a member; a clear error otherwise."""
        if isinstance(value, str):
            for member in cls:
                if member.label == value:
                    return member
            raise ValueError(f"unknown cavitation model {value!r}; choose one of {tuple(m.label for m in cls)}")
        return cls(value)


class FilmParams(NamedTuple):
    """Parameters of the separable fast path (``kernels.film_force`` and friends).

    Built by ``solver.build_params`` (cylindrical bearing) and
    ``conical.build_conical_params`` (matched cones: the axial eigenbasis in
    place of the sine modes).  ``modes`` are the axial modes the kernels use.
    """

    n_theta: int
    cavitation: int             # a ``Cavitation`` value
    sin_node: np.ndarray        # sin/cos theta at the nodes
    cos_node: np.ndarray
    sin_face: np.ndarray        # sin/cos at the faces theta_{i+1/2}
    cos_face: np.ndarray
    inv_c: float                # 1/c [1/m]
    inv_dtheta2: float
    inv_dtheta: float
    lam: np.ndarray             # eigenvalue of each axial mode (lambda_k / dzeta^2, negative)
    sig: np.ndarray             # transform of a z-constant right-hand side, per mode
    tau: np.ndarray             # transform of the row next to the supply end, per mode
    inv_dzeta2: float           # 1/dzeta^2 (only PSOR reads it)
    radius: float               # R [m]
    k_omega: float              # 6 mu omega R^2 / c^2 (cylinder) or its conical form
    k_v: float                  # 12 mu R^2 / c^3 (cylinder) or its conical form
    supply_term: float          # -p_supply / dzeta^2 (or the cone's supply coefficient times p_supply)
    a_sin: np.ndarray           # theta-weights of the force integral, sin/cos
    a_cos: np.ndarray
    basis: np.ndarray           # (n_reconstructed, n_modes) mode values at the reconstructed axial nodes
    w_rec: np.ndarray           # their (folded) Simpson z-weights
    boundary: float             # end rows' contribution w_z[0] p_supply
    w_z: np.ndarray             # Simpson z-weights of every node
    sor_omega: float            # projected SOR: relaxation, tolerance, iteration limit
    sor_tol: float
    sor_max_iter: int
    full_basis: np.ndarray      # mode values at every interior axial node
    p_supply: float             # supply pressure [Pa]


class GeneralParams(NamedTuple):
    """Parameters of the general path (``kernels.general_linear_field``): any film h(theta, z)
    on a surface of revolution R(z); built by ``conical.build_general_params``."""

    n_theta: int
    cavitation: int             # a ``Cavitation`` value
    sin_node: np.ndarray
    cos_node: np.ndarray
    sin_face: np.ndarray
    cos_face: np.ndarray
    c_node: np.ndarray          # radial clearance c(z) at the axial nodes [m]
    c_half: np.ndarray          # ... at the half nodes
    r_node: np.ndarray          # journal radius R(z) at the axial nodes [m]
    r_half: np.ndarray          # ... at the half nodes
    inv_c_ref: float            # 1/c_ref
    inv_dtheta2: float
    inv_dtheta: float
    axial_coef: float           # cos^2(alpha) / dz^2
    k_omega: float
    k_v: float
    p_supply: float
    a_sin: np.ndarray           # w_theta sin/cos theta
    a_cos: np.ndarray
    w_zr: np.ndarray            # w_z R(z)
    w_theta: np.ndarray
