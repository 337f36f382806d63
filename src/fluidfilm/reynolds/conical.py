"""The adjustable conical bearing: Reynolds equation on a cone, with an axially sliding sleeve.

Geometry (``bearing.ConicalBearing``): journal radius R(z) = r0 + z tan(alpha)
for z in [0, L]; surfaces of the journal and the sleeve are coaxial cones.
In the surface coordinates (theta, xi), xi = z / cos(alpha) the distance
along a generatrix, the thin-film equation on a surface of revolution is

    (1/R) d/dtheta(h^3/(12 mu R) dp/dtheta) + (1/R) d/dxi(R h^3/(12 mu) dp/dxi)
        = (omega/2) dh/dtheta + dh/dt,

h the film thickness normal to the surfaces.  A radial displacement X of the
journal and a radial clearance c_r change the normal gap by cos(alpha):
h = cos(alpha) (c_r - X1 sin(theta) - X2 cos(theta)) =: cos(alpha) c_ref H.
Multiplying by 12 mu R / (cos^3(alpha) c_ref^3) and writing d/dxi = cos(alpha) d/dz,

    d/dtheta(H^3 dp/dtheta) + cos^2(alpha) R d/dz(R H^3 dp/dz)
        = R^2 [K_omega dH/dtheta + K_v (-V1 sin(theta) - V2 cos(theta))],
    K_omega = 6 mu omega / (cos^2(alpha) c_ref^2),  K_v = 12 mu / (cos^2(alpha) c_ref^3).

With alpha = 0 and R constant this is the cylindrical equation of
``kernels`` exactly.  The sleeve's own axial speed is not a squeeze term
here: the sleeve is moved between control steps and held (quasi-static).

Forces on the journal: the pressure acts along the cone's normal, whose
radial part carries the factor cos(alpha) that the area element dz/cos(alpha)
cancels, so

    (F1, F2) = -int int p (sin(theta), cos(theta)) R(z) dtheta dz,
    F3 = tan(alpha) int int p R(z) dtheta dz   (towards the cone's large end).

Two solution paths:

- fast (matched cones, h independent of z): dividing out H^3 leaves the axial
  operator cos^2(alpha) R d/dz(R d/dz), the same for every angle.  Its
  discrete matrix M = D S (D = diag(cos^2(alpha) R_j/dz^2) > 0, S symmetric)
  is similar to the symmetric D^1/2 S D^1/2, so it has a real eigenbasis
  Phi computed once per grid; in that basis every mode is one periodic
  tridiagonal system in theta, exactly like the sine modes of the
  cylindrical bearing.  ``build_conical_params`` fills the cylindrical
  kernels' parameter tuple with this basis, so ``kernels.film_force`` runs
  the cone unchanged.
- general (h depends on z, ``clearance_taper`` != 0, or on request):
  ``kernels.general_linear_field``, a direct block-cyclic solve.

The sleeve displacement s only changes c_r(s) = c + s tan(alpha), so a new
sleeve position costs a few scalars, not a new eigenbasis.
"""
from __future__ import annotations

import numpy as np

from fluidfilm.core.bearing import ConicalBearing
from fluidfilm.core.states import as_state_pairs
from fluidfilm.reynolds import kernels
from fluidfilm.reynolds.mesh import FilmMesh
from fluidfilm.reynolds.params import Cavitation, FilmParams, GeneralParams
from fluidfilm.reynolds.solver import _GridSolver

METHODS = ("auto", "fast", "general")


def _axial_geometry(bearing: ConicalBearing, mesh: FilmMesh):
    z = mesh.z
    zh = 0.5 * (z[1:] + z[:-1])
    r_node = bearing.radius_small + z * bearing.tan_half_angle
    r_half = bearing.radius_small + zh * bearing.tan_half_angle
    cos2 = 1.0 / (1.0 + bearing.tan_half_angle**2)
    return z, zh, r_node, r_half, cos2


def axial_eigenbasis(bearing: ConicalBearing, mesh: FilmMesh):
    """Eigen-decomposition M = Phi diag(lam) Phi^-1 of the discrete axial operator
    cos^2(alpha) R d/dz(R d/dz) on the interior nodes (Dirichlet ends)."""
    _, _, r_node, r_half, cos2 = _axial_geometry(bearing, mesh)
    m = mesh.n_z - 2
    d = cos2 * r_node[1:-1] / mesh.dz**2
    S = np.zeros((m, m))
    idx = np.arange(m)
    S[idx, idx] = -(r_half[1:] + r_half[:-1])
    S[idx[:-1], idx[:-1] + 1] = r_half[1:-1]
    S[idx[:-1] + 1, idx[:-1]] = r_half[1:-1]
    sq = np.sqrt(d)
    lam, W = np.linalg.eigh(sq[:, None] * S * sq[None, :])
    phi = sq[:, None] * W
    phi_inv = W.T / sq[None, :]
    return lam, phi, phi_inv


def _cone_cavitation(cavitation: str | Cavitation) -> Cavitation:
    if cavitation not in ("gumbel", "none", Cavitation.GUMBEL, Cavitation.NONE):
        raise ValueError(f"the conical bearing supports cavitation 'gumbel' or 'none', got {cavitation!r}")
    return Cavitation.parse(cavitation)


def build_conical_params(bearing: ConicalBearing, mesh: FilmMesh, sleeve: float, cavitation: str | Cavitation,
                         basis=None) -> FilmParams:
    """Parameters of the fast path in the cylindrical kernels' layout (``solver.build_params``).

    Differences from the cylinder: the modes are the axial operator's
    eigenvectors, the right-hand-side transforms carry R(z)^2, the
    Simpson z-weights carry R(z) (so the theta weights do not), every
    axial node is reconstructed (no mid-length symmetry on a cone).
    Swift-Stieber cavitation (PSOR) is not offered on the cone.
    """
    cav = _cone_cavitation(cavitation)
    if bearing.clearance_taper != 0.0:
        raise ValueError("the fast conical path needs matched cones (clearance_taper = 0); use method='general'")
    c_r = bearing.clearance_at(sleeve)
    _, _, r_node, r_half, cos2 = _axial_geometry(bearing, mesh)
    lam, phi, phi_inv = basis if basis is not None else axial_eigenbasis(bearing, mesh)
    mu = bearing.viscosity
    p_s = bearing.supply_pressure
    n = mesh.n_theta
    theta_f = mesh.theta + 0.5 * mesh.dtheta
    w_zr = mesh.w_z * r_node
    sig = phi_inv @ (r_node[1:-1] ** 2)
    tau = phi_inv[:, 0].copy()
    supply_coef = cos2 * r_node[1] * r_half[0] / mesh.dz**2
    full = np.ascontiguousarray(phi)
    return FilmParams(
        n_theta=n, cavitation=int(cav),
        sin_node=np.sin(mesh.theta), cos_node=np.cos(mesh.theta),
        sin_face=np.sin(theta_f), cos_face=np.cos(theta_f),
        inv_c=1.0 / c_r,
        inv_dtheta2=1.0 / mesh.dtheta**2, inv_dtheta=1.0 / mesh.dtheta,
        lam=np.ascontiguousarray(lam), sig=np.ascontiguousarray(sig), tau=np.ascontiguousarray(tau),
        inv_dzeta2=0.0,  # only PSOR reads it, not offered here
        radius=bearing.radius,
        k_omega=6.0 * mu * bearing.omega / (cos2 * c_r**2),
        k_v=12.0 * mu / (cos2 * c_r**3),
        supply_term=-supply_coef * p_s,
        a_sin=mesh.w_theta * np.sin(mesh.theta), a_cos=mesh.w_theta * np.cos(mesh.theta),
        basis=full, w_rec=np.ascontiguousarray(w_zr[1:-1]),
        boundary=w_zr[0] * p_s,
        w_z=np.ascontiguousarray(w_zr),
        sor_omega=1.0, sor_tol=1e-10, sor_max_iter=1,
        full_basis=full,
        p_supply=float(p_s),
    )


def build_general_params(bearing: ConicalBearing, mesh: FilmMesh, sleeve: float,
                         cavitation: str | Cavitation) -> GeneralParams:
    """Parameters of ``kernels.general_linear_field`` (``params.GeneralParams``)."""
    cav = _cone_cavitation(cavitation)
    c_r = bearing.clearance_at(sleeve)
    z, zh, r_node, r_half, cos2 = _axial_geometry(bearing, mesh)
    taper = bearing.clearance_taper / bearing.length
    theta_f = mesh.theta + 0.5 * mesh.dtheta
    mu = bearing.viscosity
    return GeneralParams(
        n_theta=mesh.n_theta, cavitation=int(cav),
        sin_node=np.sin(mesh.theta), cos_node=np.cos(mesh.theta),
        sin_face=np.sin(theta_f), cos_face=np.cos(theta_f),
        c_node=c_r + taper * z, c_half=c_r + taper * zh, r_node=r_node, r_half=r_half,
        inv_c_ref=1.0 / c_r, inv_dtheta2=1.0 / mesh.dtheta**2, inv_dtheta=1.0 / mesh.dtheta,
        axial_coef=cos2 / mesh.dz**2,
        k_omega=6.0 * mu * bearing.omega / (cos2 * c_r**2), k_v=12.0 * mu / (cos2 * c_r**3),
        p_supply=float(bearing.supply_pressure),
        a_sin=mesh.w_theta * np.sin(mesh.theta), a_cos=mesh.w_theta * np.cos(mesh.theta),
        w_zr=mesh.w_z * r_node, w_theta=mesh.w_theta.copy(),
    )


class ConicalReynoldsSolver(_GridSolver):
    """Finite-difference Reynolds solver of the conical bearing at a settable sleeve position.

    The same ``forces``/``force_kernel`` interface as ``ReynoldsSolver`` (positions X [m],
    velocities V [m/s], forces [N], (X1, X2) frame with +X2 along gravity), so the rotor integrator
    and the controllers run it unchanged; ``forces_axial`` adds the axial force (..., 3), and
    ``set_sleeve(s)`` moves the sleeve [m] (eccentricities are then relative to c_r(s)).

    Parameters
    ----------
    bearing : ConicalBearing
        Geometry, lubricant, speed and sleeve travel.
    n_theta : int, default 40
        Circumferential nodes.
    n_z : int, default 40
        Axial nodes, both ends included.
    cavitation : {"gumbel", "none"}, default "gumbel"
        Cavitation rule (Swift-Stieber is not available for the cone).
    method : {"auto", "fast", "general"}, default "auto"
        ``"fast"`` (axial eigenbasis, matched cones), ``"general"`` (direct block solve, any
        h(theta, z)) or ``"auto"`` (fast when ``clearance_taper`` is 0).
    sleeve : float, default 0.0
        Initial sleeve displacement [m], inside the bearing's travel.

    Raises
    ------
    ValueError
        For a bearing that is not a ``ConicalBearing``, an unknown method or cavitation rule,
        ``"fast"`` with tapered cones, or a sleeve outside the travel (each named).

    Examples
    --------
    >>> from fluidfilm import ConicalBearing, ConicalReynoldsSolver
    >>> cone = ConicalBearing(length=0.05, diameter_small=0.04, diameter_large=0.05, clearance=100e-6,
    ...                       speed_rpm=3000, viscosity=6.53e-4, sleeve_min=-0.5e-3, sleeve_max=0.5e-3)
    >>> solver = ConicalReynoldsSolver(cone, 16, 8)
    >>> solver.forces([0.0, 50e-6], [0.0, 0.0]).round(2).tolist()          # [N]
    [19.08, -9.55]
    >>> solver.forces_axial([0.0, 50e-6], [0.0, 0.0]).round(2).tolist()    # (F1, F2, Fz) [N]
    [19.08, -9.55, 2.63]
    >>> solver.set_sleeve(-0.2e-3)            # 0.2 mm towards the large end: the clearance closes
    >>> f"{solver.clearance:.3g}", solver.forces([0.0, 50e-6], [0.0, 0.0]).round(2).tolist()
    ('8e-05', [43.68, -30.21])
    """

    def __init__(self, bearing: ConicalBearing, n_theta: int = 40, n_z: int = 40, cavitation: str = "gumbel",
                 method: str = "auto", sleeve: float = 0.0):
        if not isinstance(bearing, ConicalBearing):
            raise ValueError(f"bearing must be a ConicalBearing, got {type(bearing).__name__}")
        if method not in METHODS:
            raise ValueError(f"unknown method {method!r}; choose one of {METHODS}")
        if method == "auto":
            method = "fast" if bearing.clearance_taper == 0.0 else "general"
        if method == "fast" and bearing.clearance_taper != 0.0:
            raise ValueError(f"method 'fast' needs matched cones, but clearance_taper = {bearing.clearance_taper!r}")
        self._bearing = bearing
        self.mesh = FilmMesh(n_theta, n_z, bearing.length)
        self.cavitation = _cone_cavitation(cavitation).label
        self.method = method
        self._basis = axial_eigenbasis(bearing, self.mesh) if method == "fast" else None
        # Simpson weights of the force integrals: R(z) sits in the axial weights
        self._w_zr = self.mesh.w_z * _axial_geometry(bearing, self.mesh)[2]
        self._a_sin = self.mesh.w_theta * np.sin(self.mesh.theta)
        self._a_cos = self.mesh.w_theta * np.cos(self.mesh.theta)
        self._cache: dict[float, tuple] = {}
        self.set_sleeve(sleeve)

    # --- sleeve (the control input) ---------------------------------------------
    def set_sleeve(self, sleeve: float) -> None:
        """Move the sleeve to ``sleeve`` [m]; parameters are cached per position."""
        s = float(sleeve)
        c_r = self._bearing.clearance_at(s)  # validates the travel
        if s not in self._cache:
            if self.method == "fast":
                self._cache[s] = build_conical_params(self._bearing, self.mesh, s, self.cavitation, self._basis)
            else:
                self._cache[s] = build_general_params(self._bearing, self.mesh, s, self.cavitation)
        self._sleeve = s
        self.params = self._cache[s]
        self._c = c_r

    @property
    def adjustable(self) -> bool:
        return True

    @property
    def sleeve(self) -> float:
        return self._sleeve

    @property
    def clearance(self) -> float:
        """Radial clearance at the supply end at the current sleeve position [m]."""
        return self._c

    @property
    def force_kernel(self):
        fn = kernels.film_force if self.method == "fast" else kernels.general_force
        return fn, self.params

    def __repr__(self) -> str:
        return (f"ConicalReynoldsSolver({self.n_theta}x{self.n_z}, {self.method}, sleeve={self._sleeve:g} m, "
                f"cavitation={self.cavitation!r})")

    def _state_limit(self) -> float:
        # the film closes where X reaches the smallest radial clearance along z
        return self._c + min(0.0, self._bearing.clearance_taper)

    # --- evaluation --------------------------------------------------------------
    def forces(self, X, V) -> np.ndarray:
        """Radial film force on the journal [N], shape (..., 2)."""
        x, v, shape = as_state_pairs(X, V, self._state_limit())
        out = np.empty_like(x)
        if x.shape[0]:
            if self.method == "fast":
                kernels.forces_batch(self.params, x, v, out)
            else:
                for k in range(x.shape[0]):
                    out[k] = kernels.general_force(self.params, x[k, 0], x[k, 1], v[k, 0], v[k, 1])
        return out.reshape(shape + (2,))

    def _separable(self) -> bool:
        return self.method == "fast"

    def linear_pressure(self, x, v) -> np.ndarray:
        """Pressure [Pa] before cavitation, (n_theta, n_z)."""
        xa, va, _ = as_state_pairs(x, v, self._state_limit())
        if xa.shape[0] != 1:
            raise ValueError("linear_pressure takes one state")
        out = np.empty((self.n_theta, self.n_z))
        if self.method == "fast":
            kernels.linear_field(self.params, xa[0, 0], xa[0, 1], va[0, 0], va[0, 1],
                                 self.params.full_basis, self.params.p_supply, out)
        else:
            kernels.general_linear_field(self.params, xa[0, 0], xa[0, 1], va[0, 0], va[0, 1], out)
        return out

    def pressure(self, x, v) -> np.ndarray:
        """Pressure [Pa] after the cavitation model, (n_theta, n_z)."""
        p = self.linear_pressure(x, v)
        if self.cavitation == "gumbel":
            np.maximum(p, 0.0, out=p)
        return p

    def forces_axial(self, X, V) -> np.ndarray:
        """Radial and axial film force (F1, F2, F3) [N], shape (..., 3).

        F3 = tan(alpha) int int p R dtheta dz > 0 pushes the journal towards the
        cone's large end; a planar rotor model ignores it, a thrust bearing or
        the sleeve actuator has to carry it.
        """
        x, v, shape = as_state_pairs(X, V, self._state_limit())
        out = np.empty((x.shape[0], 3))
        for k in range(x.shape[0]):
            f1, f2, total = kernels.film_integrals(self._a_sin, self._a_cos, self.mesh.w_theta, self._w_zr,
                                                   self.pressure(x[k], v[k]), False)
            out[k] = f1, f2, self._bearing.tan_half_angle * total
        return out.reshape(shape + (3,))

    def sweep_sleeve(self, sleeves, X, V) -> np.ndarray:
        """Forces at each sleeve position in ``sleeves`` (S,) for states X, V (N, 2) -> (S, N, 2)."""
        keep = self._sleeve
        try:
            out = []
            for s in np.asarray(sleeves, dtype=float).ravel():
                self.set_sleeve(s)
                out.append(self.forces(X, V))
            return np.stack(out)
        finally:
            self.set_sleeve(keep)
