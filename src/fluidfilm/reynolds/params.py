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


# Swift-Stieber solvers (``FilmParams.ss_method``; the names are ``SS_METHODS``' entries)
SS_ACTIVE_SET = 0
SS_PSOR = 1
SS_METHODS = ("active-set", "psor")


class Cavitation(IntEnum):
    """Cavitation rule of the film (the kernels read the integer value).

    ``NONE``: full Sommerfeld, negative pressures kept (for verification);
    ``GUMBEL``: half-Sommerfeld, negative pressures set to zero after the linear solve;
    ``SWIFT_STIEBER``: Reynolds condition as a complementarity problem (active-set iteration, or projected SOR).

    Examples
    --------
    >>> from fluidfilm.reynolds import Cavitation
    >>> Cavitation.parse("swift-stieber") is Cavitation.SWIFT_STIEBER, Cavitation.GUMBEL.label
    (True, 'gumbel')
    >>> Cavitation.parse("half-sommerfeld")
    Traceback (most recent call last):
    ...
    ValueError: unknown cavitation model 'half-sommerfeld'; choose one of ('none', 'gumbel', 'swift-stieber')
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
    place of the sine modes).  ``modes`` are the axial modes the kernels use.  Built by the
    solvers, read by the kernels; not meant to be filled in by hand.

    Parameters
    ----------
    n_theta : int
        Circumferential nodes.
    cavitation : int
        A ``Cavitation`` value.
    sin_node, cos_node : ndarray
        sin/cos theta at the nodes.
    sin_face, cos_face : ndarray
        sin/cos at the faces theta_{i+1/2}.
    inv_c : float
        1/c [1/m].
    inv_dtheta2, inv_dtheta : float
        1/dtheta^2, 1/dtheta.
    lam : ndarray
        Eigenvalue of each axial mode (lambda_k / dzeta^2, negative).
    sig : ndarray
        Transform of a z-constant right-hand side, per mode.
    tau : ndarray
        Transform of the row next to the supply end, per mode.
    inv_dzeta2 : float
        1/dzeta^2 (only the projected SOR reads it).
    radius : float
        R [m].
    k_omega : float
        6 mu omega R^2 / c^2 (cylinder) or its conical form.
    k_v : float
        12 mu R^2 / c^3 (cylinder) or its conical form.
    supply_term : float
        -p_supply / dzeta^2 (or the cone's supply coefficient times p_supply).
    a_sin, a_cos : ndarray
        theta-weights of the force integral.
    basis : ndarray
        (n_reconstructed, n_modes) mode values at the reconstructed axial nodes.
    w_rec : ndarray
        Their (folded) Simpson z-weights.
    boundary : float
        The end rows' contribution w_z[0] p_supply.
    w_z : ndarray
        Simpson z-weights of every node.
    sor_omega, sor_tol : float
        Projected SOR relaxation and tolerance.
    sor_max_iter : int
        Projected SOR iteration limit.
    full_basis : ndarray
        Mode values at every interior axial node.
    p_supply : float
        Supply pressure [Pa].
    ss_method : int, default 0
        Swift-Stieber solver: ``SS_ACTIVE_SET`` (0, direct solves in an active-set iteration) or
        ``SS_PSOR`` (1, projected SOR with the ``sor_*`` settings).

    Examples
    --------
    >>> from fluidfilm import ReynoldsSolver, paper_bearing
    >>> params = ReynoldsSolver(paper_bearing(), 16, 8).params
    >>> type(params).__name__, params.n_theta, params.radius
    ('FilmParams', 16, 0.02)
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
    ss_method: int = 0          # Swift-Stieber solver: SS_ACTIVE_SET (0) or SS_PSOR (1)


class GeneralParams(NamedTuple):
    """Parameters of the general path (``kernels.general_linear_field``): any film h(theta, z)
    on a surface of revolution R(z); built by ``conical.build_general_params``.

    Parameters
    ----------
    n_theta : int
        Number of angles of the periodic grid.
    cavitation : int
        The cavitation rule's code (``Cavitation``).
    sin_node, cos_node, sin_face, cos_face : ndarray
        sin/cos theta at the nodes and at the faces.
    c_node, c_half : ndarray
        Radial clearance c(z) at the axial nodes and half nodes [m].
    r_node, r_half : ndarray
        Journal radius R(z) at the axial nodes and half nodes [m].
    inv_c_ref : float
        1/c_ref [1/m].
    inv_dtheta2, inv_dtheta : float
        1/dtheta^2, 1/dtheta.
    axial_coef : float
        cos^2(alpha) / dz^2.
    k_omega, k_v : float
        Coefficients of the rotation and squeeze terms.
    p_supply : float
        Supply pressure [Pa].
    a_sin, a_cos : ndarray
        w_theta sin/cos theta.
    w_zr : ndarray
        w_z R(z).
    w_theta : ndarray
        Circumferential integration weights.

    Examples
    --------
    >>> from fluidfilm import ConicalBearing, ConicalReynoldsSolver
    >>> tapered = ConicalBearing(length=0.05, diameter_small=0.04, diameter_large=0.05, clearance=100e-6,
    ...                          speed_rpm=3000, viscosity=6.53e-4, clearance_taper=10e-6)
    >>> params = ConicalReynoldsSolver(tapered, 16, 8).params
    >>> type(params).__name__, params.c_node.shape
    ('GeneralParams', (8,))
    """

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
