"""Numba kernels of the finite-difference Reynolds solver, gathered in one place.

The discrete problem (CONVENTIONS.md): on the grid of ``mesh.FilmMesh``, with
H = h/c = 1 - e1 sin(theta) - e2 cos(theta) (e = X/c) and zeta = z/R,

    d/dtheta(H^3 dp/dtheta) + H^3 d2p/dzeta2
        = K_omega dH/dtheta + K_v (-V1 sin(theta) - V2 cos(theta)),

    K_omega = 6 mu omega R^2 / c^2,   K_v = 12 mu R^2 / c^3,

discretised conservatively with second-order central differences (H^3 taken
at the cell faces theta_{i+1/2}, the Couette term as a difference of face
values), periodic in theta, p = p_supply at z = 0 and p = 0 at z = L.

Why it is fast: H does not depend on z, so the discrete z-operator is the
plain second difference, which the discrete sine transform (DST-I)
diagonalises exactly.  In sine space every axial mode k is one periodic
tridiagonal system in theta,

    (A_theta + lambda_k diag(H^3)) p_k = rhs_k,

and the right-hand sides do not depend on z either, so they transform to a
scalar per mode times one theta-vector.  Before cavitation the pressure is
linear in (omega, V1, V2, p_supply): one factorisation per position serves
every velocity.  With p_supply = 0 the field is symmetric about mid-length,
so only odd modes appear and half the axial nodes need reconstructing.  The
result is the exact solution of the finite-difference system (tests compare
it with a sparse direct solve), not an approximation of it.

Kernels:

- ``film_coefficients``      the film H and the theta-difference coefficients
                             of one position (both solvers assemble from them)
- ``position_modes``         per position: the periodic tridiagonal systems of
                             all axial modes solved together (vectorised over
                             modes), scaled so that p_hat = Q0 + V1*Qs + V2*Qc
- ``integrate_modes``        per velocity: reconstruct the field from the
                             modes, apply Gumbel clipping (or not), Simpson-
                             integrate the force
- ``film_force``             one force evaluation (position, velocity) ->
                             (F1, F2); the compiled force kernel the rotor
                             integrator calls
- ``forces_batch``           many (X, V) pairs, parallel over pairs
- ``forces_serial``          the same in one thread (a rotor batch's stage kernel,
                             whose threads run over chunks of trajectories)
- ``forces_product``         every velocity at every position, one
                             factorisation per position, parallel over positions
- ``pressure_field``         the full (n_theta, n_z) field of one state
- ``sor_sweeps``             (projected) SOR of the discrete equation with
                             chosen node columns held (the grooved bearing's too)
- ``psor_swift_stieber``     Swift-Stieber (Reynolds) cavitation as a linear
                             complementarity problem solved by projected SOR
- ``active_set_field``       the same problem (and the grooved bearing's) by a
                             primal-dual active-set iteration of direct sparse
                             Cholesky solves (``envelope_cholesky``,
                             ``envelope_solve``): the default
- ``capacitance_field``      the active-set iteration's linear solve by the axial
                             sine transform on runs of node columns and a
                             capacitance matrix on the active nodes inside them
                             (``mode_tridiag_green``: its Green's function from
                             the semi-separable inverse of each mode's matrix)
- ``mode_one_film``          the active-set iteration's first guess: the film of
                             the first axial mode's 1-D complementarity problem
- ``swift_stieber_field``    either of them, by ``params.ss_method``
- ``film_force_ss``          force with Swift-Stieber cavitation
- ``general_linear_field``   the general path: film thickness h(theta, z)
                             and radius R(z) (conical bearings, tapered or
                             misfit sleeves), one block-cyclic-tridiagonal
                             direct solve (theta blocks of axial lines)
- ``general_force``          force of the general path (same signature)
- ``film_integrals``         (F1, F2) and sum w_theta w_z R(z) p of a field,
                             optionally Gumbel-clipped: the general path's
                             force and the cone's axial force (tan(alpha)
                             times the sum)

The conical bearing's fast path reuses ``film_force`` unchanged: with
matched cones h does not depend on z, and the axial operator
R(z) d/dz(R(z) d/dz) is diagonalised by a precomputed eigenbasis instead of
the sine transform (``conical.build_conical_params``).

``params`` is a ``params.FilmParams`` (built by ``solver.build_params`` or
``conical.build_conical_params``), ``gp`` a ``params.GeneralParams``: named
fields, compiled by numba to a plain struct.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit, prange

from fluidfilm.reynolds.params import SS_PSOR, Cavitation

# cavitation codes used inside kernels (plain ints: the values of ``params.Cavitation``)
CAV_NONE = int(Cavitation.NONE)
CAV_GUMBEL = int(Cavitation.GUMBEL)
CAV_SWIFT_STIEBER = int(Cavitation.SWIFT_STIEBER)

# Let LLVM reassociate sums so the inner loops over axial modes vectorise; no
# finite-math assumptions (NaN/inf checks must keep working).
_FAST = {"reassoc", "contract", "arcp"}


@njit(cache=True)
def film_thickness(params, e1, e2, h_node, h3_node, h3_face, h_face):
    """Dimensionless film H = h/c at the nodes and faces theta_{i+1/2}."""
    sin_n = params.sin_node
    cos_n = params.cos_node
    sin_f = params.sin_face
    cos_f = params.cos_face
    n = sin_n.shape[0]
    for i in range(n):
        h = 1.0 - e1 * sin_n[i] - e2 * cos_n[i]
        h_node[i] = h
        h3_node[i] = h * h * h
        hf = 1.0 - e1 * sin_f[i] - e2 * cos_f[i]
        h_face[i] = hf
        h3_face[i] = hf * hf * hf



@njit(cache=True, inline="always")
def film_coefficients(params, e1, e2):
    """(H^3 at the nodes, H at the faces, west, east): the film (``film_thickness``) and the coefficients
    H^3_{i-1/2} / dtheta^2, H^3_{i+1/2} / dtheta^2 of p_{i-1}, p_{i+1} in the conservative theta-difference
    of node i, periodic.  Inlined: the callers compile it under their own fastmath settings, as when they
    were written apart (``film_thickness`` stays a call, its arithmetic strict)."""
    n = params.n_theta
    inv_dth2 = params.inv_dtheta2
    h = np.empty(n)
    h3 = np.empty(n)
    h3f = np.empty(n)
    hf = np.empty(n)
    film_thickness(params, e1, e2, h, h3, h3f, hf)
    west = np.empty(n)
    east = np.empty(n)
    for i in range(n):
        im = i - 1 if i > 0 else n - 1
        west[i] = h3f[im] * inv_dth2
        east[i] = h3f[i] * inv_dth2
    return h3, hf, west, east


@njit(cache=True, fastmath=_FAST)
def position_modes(params, e1, e2):
    """Solve every used axial mode at one position, all modes at once.

    Returns ``q0, qs, qc`` (n_theta, n_modes) so that the sine coefficients of
    the pressure at velocity (V1, V2) are ``q0 + V1*qs + V2*qc`` (q0 holds the
    Couette and supply-pressure parts).

    Each mode is a periodic tridiagonal system; they share the off-diagonals
    and right-hand sides and differ only in the diagonal, so the Thomas
    recurrences run over theta with the modes as the inner, vectorised loop
    (Sherman-Morrison for the periodic corners, Numerical Recipes' ``cyclic``).
    The systems are strictly diagonally dominant, so no pivoting is needed.
    """
    n = params.n_theta
    sin_n = params.sin_node
    cos_n = params.cos_node
    inv_dth = params.inv_dtheta
    lam = params.lam  # lambda_k / dzeta^2, negative
    sig = params.sig  # transform of the z-constant right-hand side
    tau = params.tau  # transform of the supply-pressure row (j = 1)
    k_omega = params.k_omega
    k_v = params.k_v
    supply_term = params.supply_term  # -p_supply / dzeta^2
    nk = lam.shape[0]
    with_supply = supply_term != 0.0
    q0 = np.empty((n, nk))
    qs = np.empty((n, nk))
    qc = np.empty((n, nk))
    h3, hf, lo, up = film_coefficients(params, e1, e2)
    r_w = np.empty(n)
    for i in range(n):
        r_w[i] = (hf[i] - hf[i - 1 if i > 0 else n - 1]) * inv_dth
    alpha = up[n - 1]  # coefficient of x[0] in the last row
    beta = lo[0]  # coefficient of x[n-1] in the first row
    cp = np.empty((n, nk))
    zz = np.empty((n, nk))
    xp = np.empty((n, nk)) if with_supply else np.empty((1, 1))
    gamma = np.empty(nk)
    bn = np.empty(nk)
    d0 = -(lo[0] + up[0])
    dn = -(lo[n - 1] + up[n - 1])
    for k in range(nk):
        dk = d0 + lam[k] * h3[0]
        gamma[k] = -dk
        bn[k] = dn + lam[k] * h3[n - 1] + alpha * beta / dk
    # forward elimination, all right-hand sides and the correction vector together
    for k in range(nk):
        inv = 1.0 / (2.0 * (d0 + lam[k] * h3[0]))
        cp[0, k] = up[0] * inv
        zz[0, k] = gamma[k] * inv
        q0[0, k] = r_w[0] * inv
        qs[0, k] = -sin_n[0] * inv
        qc[0, k] = -cos_n[0] * inv
        if with_supply:
            xp[0, k] = h3[0] * inv
    for i in range(1, n):
        di = -(lo[i] + up[i])
        li = lo[i]
        ui = alpha if i == n - 1 else 0.0
        last = i == n - 1
        for k in range(nk):
            bi = bn[k] if last else di + lam[k] * h3[i]
            inv = 1.0 / (bi - li * cp[i - 1, k])
            cp[i, k] = up[i] * inv
            zz[i, k] = (ui - li * zz[i - 1, k]) * inv
            q0[i, k] = (r_w[i] - li * q0[i - 1, k]) * inv
            qs[i, k] = (-sin_n[i] - li * qs[i - 1, k]) * inv
            qc[i, k] = (-cos_n[i] - li * qc[i - 1, k]) * inv
            if with_supply:
                xp[i, k] = (h3[i] - li * xp[i - 1, k]) * inv
    for i in range(n - 2, -1, -1):
        for k in range(nk):
            c = cp[i, k]
            zz[i, k] -= c * zz[i + 1, k]
            q0[i, k] -= c * q0[i + 1, k]
            qs[i, k] -= c * qs[i + 1, k]
            qc[i, k] -= c * qc[i + 1, k]
            if with_supply:
                xp[i, k] -= c * xp[i + 1, k]
    # Sherman-Morrison correction, then the per-mode scaling of the transforms
    f0 = np.empty(nk)
    fs = np.empty(nk)
    fc = np.empty(nk)
    fp = np.zeros(nk)
    for k in range(nk):
        g = beta / gamma[k]
        zden = 1.0 / (1.0 + zz[0, k] + g * zz[n - 1, k])
        f0[k] = (q0[0, k] + g * q0[n - 1, k]) * zden
        fs[k] = (qs[0, k] + g * qs[n - 1, k]) * zden
        fc[k] = (qc[0, k] + g * qc[n - 1, k]) * zden
        if with_supply:
            fp[k] = (xp[0, k] + g * xp[n - 1, k]) * zden
    for i in range(n):
        for k in range(nk):
            z = zz[i, k]
            a = sig[k] * k_omega * (q0[i, k] - f0[k] * z)
            if with_supply:
                a += tau[k] * supply_term * (xp[i, k] - fp[k] * z)
            q0[i, k] = a
            qs[i, k] = sig[k] * k_v * (qs[i, k] - fs[k] * z)
            qc[i, k] = sig[k] * k_v * (qc[i, k] - fc[k] * z)
    return q0, qs, qc


@njit(cache=True, fastmath=_FAST)
def integrate_modes(params, q0, qs, qc, v1, v2, cavitation, phat):
    """Force (F1, F2) from the mode solutions at velocity (V1, V2).

    Reconstructs the pressure at the axial nodes that matter (half of them
    when the field is symmetric), clips it for Gumbel cavitation, and sums
    with the Simpson weights: F = -R * sum w_theta w_z p (sin, cos).
    """
    n = params.n_theta
    a_sin = params.a_sin  # R * w_theta * sin(theta)
    a_cos = params.a_cos  # R * w_theta * cos(theta)
    basis = params.basis  # (n_rec, n_modes) sine basis at reconstructed nodes
    w_rec = params.w_rec  # folded Simpson z-weights of reconstructed nodes
    boundary = params.boundary  # contribution of the prescribed end rows per unit (sum of w_z p there)
    nk = q0.shape[1]
    nj = basis.shape[0]
    f1 = 0.0
    f2 = 0.0
    for i in range(n):
        for k in range(nk):
            phat[k] = q0[i, k] + v1 * qs[i, k] + v2 * qc[i, k]
        col = boundary
        for j in range(nj):
            acc = 0.0
            for k in range(nk):
                acc += phat[k] * basis[j, k]
            if cavitation == CAV_GUMBEL:
                if acc > 0.0:
                    col += w_rec[j] * acc
            else:
                col += w_rec[j] * acc
        f1 -= a_sin[i] * col
        f2 -= a_cos[i] * col
    return f1, f2


@njit(cache=True)
def film_force(params, x1, x2, v1, v2):
    """One force evaluation: journal at (x1, x2) [m] moving at (v1, v2) [m/s] -> (F1, F2) [N].

    Gumbel or no cavitation (``params.cavitation``).  This is the compiled force
    kernel that ``fluidfilm.rotor`` integrates; a surrogate provides a kernel
    of the same signature.
    """
    q0, qs, qc = position_modes(params, x1 * params.inv_c, x2 * params.inv_c)
    phat = np.empty(q0.shape[1])
    return integrate_modes(params, q0, qs, qc, v1, v2, params.cavitation, phat)


@njit(cache=True, inline="always")
def kernel_row(kernel, params, x, v, out, p):
    """out[p] = the one-state ``kernel``'s force at row p of x, v (the batched kernels' loop body)."""
    f1, f2 = kernel(params, x[p, 0], x[p, 1], v[p, 0], v[p, 1])
    out[p, 0] = f1
    out[p, 1] = f2


@njit(cache=True, inline="always")
def kernel_rows(kernel, params, x, v, out):
    """``kernel_row`` for every row, in the calling thread."""
    for p in range(x.shape[0]):
        kernel_row(kernel, params, x, v, out, p)


@njit(cache=True, parallel=True)
def forces_batch(params, x, v, out):
    """Forces for N (position, velocity) pairs, parallel over pairs, by the kernel of ``params.cavitation``
    (``film_force_ss`` for Swift-Stieber, else ``film_force``)."""
    ss = params.cavitation == CAV_SWIFT_STIEBER
    for p in prange(x.shape[0]):
        if ss:
            kernel_row(film_force_ss, params, x, v, out, p)
        else:
            kernel_row(film_force, params, x, v, out, p)


@njit(cache=True)
def forces_serial(params, x, v, out):
    """``forces_batch`` in the calling thread: each row exactly the one-state kernel's force (``simulate_batch``
    calls it per RK4 stage; its own threads run over chunks of trajectories, numba's pool is not nested)."""
    if params.cavitation == CAV_SWIFT_STIEBER:
        kernel_rows(film_force_ss, params, x, v, out)
    else:
        kernel_rows(film_force, params, x, v, out)


@njit(cache=True, parallel=True)
def forces_product(params, x, v, out):
    """Forces for every velocity v[q] at every position x[p] -> out[p, q, :].

    One factorisation per position (the pressure is linear in the velocity
    before cavitation), parallel over positions.
    """
    cav = params.cavitation
    for p in prange(x.shape[0]):
        q0, qs, qc = position_modes(params, x[p, 0] * params.inv_c, x[p, 1] * params.inv_c)
        phat = np.empty(q0.shape[1])
        for q in range(v.shape[0]):
            f1, f2 = integrate_modes(params, q0, qs, qc, v[q, 0], v[q, 1], cav, phat)
            out[p, q, 0] = f1
            out[p, q, 1] = f2


@njit(cache=True, fastmath=_FAST)
def linear_field(params, x1, x2, v1, v2, full_basis, p_supply, out, rows=-1):
    """Pressure before cavitation on the whole (n_theta, n_z) grid, boundaries included.

    ``rows`` >= 0: only the interior rows 1..rows are reconstructed, the rest of the interior set to 0 (the
    Swift-Stieber solvers' start needs the lower half of a symmetric field only: they solve the rest).  The
    sums over modes are reassociated (vectorised); the field is the same to round-off."""
    n = params.n_theta
    nk = params.lam.shape[0]
    q0, qs, qc = position_modes(params, x1 * params.inv_c, x2 * params.inv_c)
    nz = out.shape[1]
    last = nz - 2 if rows < 0 else min(rows, nz - 2)
    phat = np.empty(nk)
    for i in range(n):
        out[i, 0] = p_supply
        out[i, nz - 1] = 0.0
        for k in range(nk):
            phat[k] = q0[i, k] + v1 * qs[i, k] + v2 * qc[i, k]
        for j in range(1, last + 1):
            acc = 0.0
            bj = full_basis[j - 1]
            for k in range(nk):
                acc += phat[k] * bj[k]
            out[i, j] = acc
        for j in range(last + 1, nz - 1):
            out[i, j] = 0.0


@njit(cache=True, inline="always")
def node_equations(params, x1, x2, v1, v2):
    """(aw, ae, an, ap, rhs) per angle: node (i, j)'s equation aw p[i-1, j] + ae p[i+1, j]
    + an (p[i, j-1] + p[i, j+1]) - ap p[i, j] = rhs (the same for every axial row j: H does not depend on z);
    what the SOR and the active-set solver assemble from."""
    n = params.n_theta
    inv_dth, inv_dz2, k_omega, k_v = params.inv_dtheta, params.inv_dzeta2, params.k_omega, params.k_v
    sin_n, cos_n = params.sin_node, params.cos_node
    h3, hf, aw, ae = film_coefficients(params, x1 * params.inv_c, x2 * params.inv_c)
    an = np.empty(n)
    ap = np.empty(n)
    rhs = np.empty(n)
    for i in range(n):
        im = i - 1 if i > 0 else n - 1
        an[i] = h3[i] * inv_dz2
        ap[i] = aw[i] + ae[i] + 2.0 * an[i]
        rhs[i] = k_omega * (hf[i] - hf[im]) * inv_dth + k_v * (-v1 * sin_n[i] - v2 * cos_n[i])
    return aw, ae, an, ap, rhs


@njit(cache=True, inline="always")
def sor_sweeps(params, x1, x2, v1, v2, p, fixed, project, omega_sor, tol, max_iter):
    """(Projected) SOR of the discrete Reynolds equation, the node columns ``fixed`` held.

    The one SOR of the library: ``psor_swift_stieber`` (no column held,
    projected) and the grooved bearing (``feed``: the groove columns held,
    projected for Swift-Stieber only) run it.  ``p``: the full
    (n_theta, n_z) field with the boundary rows (and held columns) set and a
    starting guess elsewhere; updated in place.  ``project``: keep p >= 0
    (Cryer's PSOR), else solve the linear system.  Returns the number of
    sweeps, or -1 if ``max_iter`` sweeps did not reach ``tol`` (max change
    relative to the largest |p|).  Inlined into its callers, so each compiles
    the sweep with its own constants, as when they were written apart.
    """
    n, nz = params.n_theta, p.shape[1]
    aw, ae, an, ap, rhs = node_equations(params, x1, x2, v1, v2)
    inv_ap = 1.0 / ap
    for it in range(max_iter):
        dmax = 0.0
        pmax = 0.0
        for i in range(n):
            if fixed[i]:
                continue
            im = i - 1 if i > 0 else n - 1
            ip = i + 1 if i < n - 1 else 0
            for j in range(1, nz - 1):
                gs = (ae[i] * p[ip, j] + aw[i] * p[im, j] + an[i] * (p[i, j + 1] + p[i, j - 1]) - rhs[i]) * inv_ap[i]
                new = p[i, j] + omega_sor * (gs - p[i, j])
                if project and new < 0.0:
                    new = 0.0
                d = abs(new - p[i, j])
                if d > dmax:
                    dmax = d
                # the size of new: |new| in the linear system; projected, new >= 0 (that sweep compiles without abs)
                a = new if project else abs(new)
                if a > pmax:
                    pmax = a
                p[i, j] = new
        if dmax <= tol * pmax or pmax == 0.0:
            return it + 1
    return -1


@njit(cache=True)
def psor_swift_stieber(params, x1, x2, v1, v2, p, omega_sor, tol, max_iter):
    """Swift-Stieber (Reynolds) cavitation as a linear complementarity problem.

    Writing the discrete Reynolds equation as ``G(p) = A p - rhs = 0`` (A the
    negative-definite operator), the solution satisfies p >= 0, G(p) <= 0
    where p = 0 and G(p) = 0 where p > 0: in the grid limit the film-rupture
    conditions p = 0 and dp/dn = 0 at the cavitation boundary.
    Projected SOR (Cryer 1971, ``sor_sweeps``) from the initial field in ``p``
    (the Gumbel field is a good start).  ``p`` is the full (n_theta, n_z)
    array with the boundary rows set; updated in place.  Returns the number
    of sweeps, or -1 if ``max_iter`` sweeps did not reach ``tol`` (max change
    relative to the largest pressure).
    """
    no_column_held = np.zeros(params.n_theta, dtype=np.bool_)
    return sor_sweeps(params, x1, x2, v1, v2, p, no_column_held, True, omega_sor, tol, max_iter)


# --- Swift-Stieber by a primal-dual active-set iteration ---------------------------------------------------
# Decisions of the active-set iteration are made up to this fraction of the largest pressure (a node whose
# solved pressure is above -AS_TOL * p_max stays in the film; an active node is released only if its Gauss-Seidel
# value exceeds AS_TOL * p_max): without it, round-off at nodes where p and the residual both vanish could flip
# a node back and forth.
AS_TOL = 1e-12
AS_WIDEN = 0.13


@njit(cache=True, error_model="numpy", fastmath=_FAST)
def envelope_cholesky(first, start, env, inv_diag, r0, n_unknowns):
    """In place: rows r0.. of the Cholesky factor L (K = L L^T) of a symmetric positive definite matrix in
    envelope storage (rows before r0 already factored).

    Row r holds columns first[r]..r at env[start[r] : start[r] + r - first[r] + 1] (the diagonal last).
    Fill-in stays inside the envelope, so the factor needs no more storage; the work is about the sum over
    rows of (row length)^2 / 2.  A row depends only on the rows before it, so when a matrix differs from
    the last one only from row r0 on, the rows before r0 are kept.  ``inv_diag`` receives 1 / L[r, r].
    """
    for r in range(r0, n_unknowns):
        fr = first[r]
        sr = start[r] - fr  # env[sr + c] = L[r, c]
        for c in range(fr, r):
            fc = first[c]
            sc = start[c] - fc
            k0 = fr if fr > fc else fc
            acc = 0.0
            for k in range(k0, c):
                acc += env[sr + k] * env[sc + k]
            env[sr + c] = (env[sr + c] - acc) * inv_diag[c]
        acc = 0.0
        for k in range(fr, r):
            acc += env[sr + k] * env[sr + k]
        d = np.sqrt(env[sr + r] - acc)
        env[sr + r] = d
        inv_diag[r] = 1.0 / d


@njit(cache=True, error_model="numpy", fastmath=_FAST)
def envelope_solve(first, start, env, inv_diag, r0, n_unknowns, y, x):
    """Solve L L^T x = b with the factor of ``envelope_cholesky``: ``y`` holds b on entry and L^{-1} b on
    return (its rows before r0 already reduced, as ``envelope_cholesky``'s), ``x`` receives the solution."""
    for r in range(r0, n_unknowns):
        fr = first[r]
        sr = start[r] - fr
        acc = 0.0
        for k in range(fr, r):
            acc += env[sr + k] * y[k]
        y[r] = (y[r] - acc) * inv_diag[r]
    for r in range(n_unknowns):
        x[r] = y[r]
    for r in range(n_unknowns - 1, -1, -1):
        fr = first[r]
        sr = start[r] - fr
        xr = x[r] * inv_diag[r]
        x[r] = xr
        for k in range(fr, r):
            x[k] -= env[sr + k] * xr


# --- the active-set iteration's linear solve by the axial sine transform and a capacitance matrix ------------
@njit(cache=True, error_model="numpy", fastmath=_FAST)
def mode_tridiag_factor(params, cols, nc, aw, ae, an):
    """1 / pivots of the LDL^T factors of one symmetric tridiagonal system per axial mode on the theta run
    ``cols[:nc]`` (ends held at known values): the run's discrete operator -A in the sine basis, where row r
    (node column cols[r]) reads (aw + ae - an mu_k) x_r - ae[cols[r-1]] x_{r-1} - ae[cols[r]] x_{r+1}, mu_k
    the second difference's eigenvalue of mode k.  Diagonally dominant: no pivoting.  Returns (nc, n_modes)."""
    lam = params.lam
    nk = lam.shape[0]
    scale = 1.0 / params.inv_dzeta2
    dinv = np.empty((nc, nk))
    for r in range(nc):
        i = cols[r]
        base = aw[i] + ae[i]
        ani = an[i] * scale
        if r == 0:
            for k in range(nk):
                dinv[0, k] = 1.0 / (base - ani * lam[k])
        else:
            e = ae[cols[r - 1]]
            e2 = e * e
            for k in range(nk):
                dinv[r, k] = 1.0 / (base - ani * lam[k] - e2 * dinv[r - 1, k])
    return dinv


@njit(cache=True, error_model="numpy", fastmath=_FAST)
def mode_tridiag_solve(cols, nc, ae, dinv, x, r_first):
    """In place: x (nc, n_modes) <- T_k^{-1} x for every mode, with the factors of ``mode_tridiag_factor``;
    rows before ``r_first`` of x must be zero (a unit right-hand side: the forward sweep starts there)."""
    nk = x.shape[1]
    for r in range(max(r_first, 1), nc):
        e = ae[cols[r - 1]]
        for k in range(nk):
            x[r, k] += e * dinv[r - 1, k] * x[r - 1, k]
    for r in range(r_first, nc):
        for k in range(nk):
            x[r, k] *= dinv[r, k]
    for r in range(nc - 2, -1, -1):
        e = ae[cols[r]]
        for k in range(nk):
            x[r, k] += e * dinv[r, k] * x[r + 1, k]


@njit(cache=True, error_model="numpy", fastmath=_FAST)
def mode_tridiag_green(params, cols, nc, aw, ae, an, dinv, pc, npc):
    """The entries (T_k^{-1})[pc[q], pc[q2]] of every mode's inverse between the rows ``pc[:npc]``
    (ascending), as (npc, npc, n_modes), with the factors of ``mode_tridiag_factor`` and no solve per row.

    The inverse of a symmetric tridiagonal matrix is semi-separable: its diagonal is 1 / (D_r + E_r - a_r)
    (D the forward pivots, E the backward ones, a the diagonal), and above it column b is
    x_r = x_{r+1} e_r / D_r (the homogeneous rows of the forward sweep; e_r the coupling of r and r + 1),
    so the entries between the rows follow from products of these ratios between consecutive rows
    (all below 1: the matrix is diagonally dominant).  O((nc + npc^2) n_modes)."""
    lam = params.lam
    nk = lam.shape[0]
    scale = 1.0 / params.inv_dzeta2
    # backward pivots E_r, only as far down as the first row asked for
    r_lo = pc[0]
    e_piv = np.empty((nc, nk))
    for r in range(nc - 1, r_lo - 1, -1):
        i = cols[r]
        base = aw[i] + ae[i]
        ani = an[i] * scale
        if r == nc - 1:
            for k in range(nk):
                e_piv[r, k] = base - ani * lam[k]
        else:
            e = ae[i]
            e2 = e * e
            for k in range(nk):
                e_piv[r, k] = base - ani * lam[k] - e2 / e_piv[r + 1, k]
    gp = np.empty((npc, npc, nk))
    seg = np.empty(nk)
    for q in range(npc):
        rq = pc[q]
        i = cols[rq]
        base = aw[i] + ae[i]
        ani = an[i] * scale
        for k in range(nk):
            gp[q, q, k] = 1.0 / (1.0 / dinv[rq, k] + e_piv[rq, k] - (base - ani * lam[k]))
    for q in range(npc - 1):
        # seg = prod over rows pc[q] .. pc[q + 1] - 1 of e_r / D_r
        for k in range(nk):
            seg[k] = 1.0
        for r in range(pc[q], pc[q + 1]):
            e = ae[cols[r]]
            for k in range(nk):
                seg[k] *= e * dinv[r, k]
        # gp[a, q + 1] = gp[a, q] * seg * diag[q + 1] / diag[q] for a < q + 1: build from the ratios instead
        for a in range(q + 1):
            for k in range(nk):
                # the ratio product from pc[a] to pc[q + 1], kept in the lower triangle until written
                prev = 1.0 if a == q else gp[q, a, k]
                gp[q + 1, a, k] = prev * seg[k]
    for b in range(1, npc):
        for a in range(b):
            for k in range(nk):
                v = gp[b, a, k] * gp[b, b, k]
                gp[a, b, k] = v
                gp[b, a, k] = v
    return gp


@njit(cache=True, error_model="numpy", fastmath=_FAST)
def transform_column(params, values, m, out, coef):
    """out[k] += coef * (2 / (m + 1)) * sum_j basis[j, k] values[j + 1]: the sine coefficients of one node
    column's interior values (rows 1..m of a field column), scaled."""
    basis = params.full_basis
    f = coef * 2.0 / (m + 1)
    for j in range(m):
        vj = values[j + 1] * f
        if vj != 0.0:
            for k in range(out.shape[0]):
                out[k] += vj * basis[j, k]


@njit(cache=True, error_model="numpy", fastmath=_FAST)
def capacitance_run(params, cols, nc, aw, ae, an, rhs, free, fixed, p, m, mh, symmetric):
    """Solve the free nodes' equations on one run of node columns ``cols[:nc]`` (its neighbours on both
    sides held or wholly cavitated) by the axial sine transform and a capacitance matrix; writes p on the
    run (active nodes at 0, mirrored onto the upper half when ``symmetric``).

    On the whole run the operator -A is one symmetric tridiagonal system per axial mode (the film thickness
    does not depend on z), solved in O(nc n_modes).  The active nodes inside the run (those of partly
    cavitated columns) are held at zero by a source mu at each, found from the capacitance system
    G mu = -p0 on them (G the run's Green's function between active nodes, p0 the field without sources):
    with s active nodes the extra work is O(s^2 n_modes + s^3).  In the symmetric half field each node
    stands for itself and its mirror (odd modes only), which the same formulas cover."""
    n = params.n_theta
    nz = m + 2
    basis = params.full_basis
    sig = params.sig
    nk = sig.shape[0]
    two_m1 = 2.0 / (m + 1)
    dinv = mode_tridiag_factor(params, cols, nc, aw, ae, an)
    # right-hand side of -A p = -rhs (+ known neighbours) in the sine basis
    bh = np.empty((nc, nk))
    for r in range(nc):
        i = cols[r]
        for k in range(nk):
            bh[r, k] = -rhs[i] * sig[k]
        if p[i, 0] != 0.0:
            f = an[i] * p[i, 0] * two_m1
            for k in range(nk):
                bh[r, k] += f * basis[0, k]
        if p[i, nz - 1] != 0.0:
            f = an[i] * p[i, nz - 1] * two_m1
            for k in range(nk):
                bh[r, k] += f * basis[m - 1, k]
    il = cols[0] - 1 if cols[0] > 0 else n - 1
    if fixed[il]:
        transform_column(params, p[il], m, bh[0], aw[cols[0]])
    ir = cols[nc - 1] + 1 if cols[nc - 1] < n - 1 else 0
    if fixed[ir]:
        transform_column(params, p[ir], m, bh[nc - 1], ae[cols[nc - 1]])
    # the active nodes of the run and the columns holding them
    s = 0
    for r in range(nc):
        for j in range(1, mh + 1):
            if not free[cols[r], j]:
                s += 1
    if s > 0:
        b_src = bh.copy()
    else:
        b_src = bh
    mode_tridiag_solve(cols, nc, ae, dinv, bh, 0)
    if s > 0:
        sr = np.empty(s, dtype=np.int64)
        sj = np.empty(s, dtype=np.int64)
        sq = np.empty(s, dtype=np.int64)
        pc = np.empty(nc, dtype=np.int64)
        npc = 0
        a = 0
        for r in range(nc):
            had = False
            for j in range(1, mh + 1):
                if not free[cols[r], j]:
                    if not had:
                        pc[npc] = r
                        npc += 1
                        had = True
                    sr[a] = r
                    sj[a] = j - 1
                    sq[a] = npc - 1
                    a += 1
        # the run's Green's function between the partly cavitated columns, per mode
        gp = mode_tridiag_green(params, cols, nc, aw, ae, an, dinv, pc, npc)
        # capacitance matrix (symmetric positive definite) and its right-hand side, block by block of
        # partly cavitated columns (the active nodes of a column are consecutive in the list)
        a_lo = np.zeros(npc + 1, dtype=np.int64)
        for a in range(s):
            a_lo[sq[a] + 1] = a + 1
        g = np.empty((s, s))
        y = np.empty(s)
        t = np.empty(nk)
        for q in range(npc):
            for a in range(a_lo[q], a_lo[q + 1]):
                ba = basis[sj[a]]
                for q2 in range(q + 1):
                    w = gp[q, q2]
                    for k in range(nk):
                        t[k] = ba[k] * w[k]
                    for b in range(a_lo[q2], min(a_lo[q2 + 1], a + 1)):
                        bb = basis[sj[b]]
                        acc = 0.0
                        for k in range(nk):
                            acc += t[k] * bb[k]
                        g[a, b] = acc
                        g[b, a] = acc
                acc = 0.0
                for k in range(nk):
                    acc += ba[k] * bh[sr[a], k]
                y[a] = -acc / two_m1
        # Cholesky factor (lower): LAPACK for the larger systems, else in place; then two triangular solves
        if s > 24:
            g = np.linalg.cholesky(g)
        else:
            for a in range(s):
                for b in range(a + 1):
                    acc = g[a, b]
                    for k in range(b):
                        acc -= g[a, k] * g[b, k]
                    if b == a:
                        g[a, a] = np.sqrt(acc)
                    else:
                        g[a, b] = acc / g[b, b]
        for a in range(s):
            acc = y[a]
            for k in range(a):
                acc -= g[a, k] * y[k]
            y[a] = acc / g[a, a]
        for a in range(s - 1, -1, -1):
            acc = y[a]
            for k in range(a + 1, s):
                acc -= g[k, a] * y[k]
            y[a] = acc / g[a, a]
        # the sources at the active nodes, and the field once more
        for a in range(s):
            f = two_m1 * y[a]
            ba = basis[sj[a]]
            for k in range(nk):
                b_src[sr[a], k] += f * ba[k]
        mode_tridiag_solve(cols, nc, ae, dinv, b_src, 0)
        bh = b_src
    # back to the nodes: one matrix product (BLAS) for the whole run, then the active nodes at 0
    vals = np.dot(bh, basis[:mh].T)
    for r in range(nc):
        i = cols[r]
        for j in range(1, mh + 1):
            val = vals[r, j - 1] if free[i, j] else 0.0
            p[i, j] = val
            if symmetric:
                p[i, m + 1 - j] = val


@njit(cache=True, error_model="numpy")
def capacitance_field(params, aw, ae, an, rhs, free, fixed, p, m, mh, symmetric):
    """The free nodes' equations solved run by run (``capacitance_run``) if that is cheaper than the envelope
    Cholesky factorisation: needs a wholly cavitated or held node column (else the runs close into a ring),
    and is chosen by an operation count against the factorisation's.  Returns whether it solved."""
    n = params.n_theta
    nk = params.lam.shape[0]
    boundary = np.empty(n, dtype=np.bool_)
    b0 = -1
    env_cost = 0.0
    s_tot = 0
    n_part = 0
    n_run = 0
    for i in range(n):
        c = 0
        if not fixed[i]:
            for j in range(1, mh + 1):
                if free[i, j]:
                    c += 1
        boundary[i] = fixed[i] or c == 0
        if boundary[i]:
            b0 = i
        else:
            n_run += 1
            s_tot += mh - c
            if c < mh:
                n_part += 1
        env_cost += 0.5 * c * mh * mh
    if b0 < 0:
        return False
    # capacitance matrix and its Cholesky factor, the Green's function between partly cavitated columns,
    # the tridiagonal factor and solves and the field (a BLAS product)
    cap_cost = (s_tot * s_tot * (0.5 * nk + s_tot / 6.0) + n_part * n_part * nk + n_run * nk * (0.5 * mh + 12.0))
    if cap_cost > env_cost:
        return False
    cols = np.empty(n, dtype=np.int64)
    t = 0
    while t < n:
        i = (b0 + 1 + t) % n
        if boundary[i]:
            if not fixed[i]:
                for j in range(1, m + 1):
                    p[i, j] = 0.0
            t += 1
            continue
        nc = 0
        while t < n and not boundary[(b0 + 1 + t) % n]:
            cols[nc] = (b0 + 1 + t) % n
            nc += 1
            t += 1
        capacitance_run(params, cols, nc, aw, ae, an, rhs, free, fixed, p, m, mh, symmetric)
    return True


@njit(cache=True, error_model="numpy")
def mode_one_film(params, aw, ae, an, rhs, fixed):
    """The film's columns as the first axial mode alone predicts them: the first guess of the active-set
    iteration (``active_set_field``) for a field symmetric about mid-length.

    Projected onto the lowest sine mode (positive at every axial node) the discrete Reynolds equation is
    one tridiagonal system in theta, T x = b (T = ``mode_tridiag_factor``'s operator of mode 1, b its
    right-hand side); its complementarity problem x >= 0, T x - b >= 0, x (T x - b) = 0 is solved by the
    same primal-dual active-set iteration in 1-D (a Thomas solve per run of free columns, held columns at
    0), from the columns where b > 0 (the converging film).  The columns with x > 0 are returned (bool,
    (n_theta,)): on the plain bearing the 2-D film to within a partly cavitated column at each end, so the
    2-D iteration starts next to its answer.  A guess only: the 2-D iteration settles from any start."""
    n = params.n_theta
    lam0 = params.lam[0] / params.inv_dzeta2
    sig0 = params.sig[0]
    d = np.empty(n)
    b = np.empty(n)
    bmax = 0.0
    for i in range(n):
        d[i] = aw[i] + ae[i] - an[i] * lam0
        b[i] = -rhs[i] * sig0
        if abs(b[i]) > bmax:
            bmax = abs(b[i])
    free = np.empty(n, dtype=np.bool_)
    for i in range(n):
        free[i] = b[i] > 0.0 and not fixed[i]
    x = np.zeros(n)
    cp = np.empty(n)
    cols = np.empty(n, dtype=np.int64)
    for _ in range(2 * n):
        b0 = -1
        for i in range(n):
            if not free[i]:
                b0 = i
        if b0 < 0:
            break  # the whole ring (no held column): keep the last set, a guess anyway
        # Thomas on each run of free columns, its neighbours at 0
        t = 0
        while t < n:
            i = (b0 + 1 + t) % n
            if not free[i]:
                x[i] = 0.0
                t += 1
                continue
            nc = 0
            while t < n and free[(b0 + 1 + t) % n]:
                cols[nc] = (b0 + 1 + t) % n
                nc += 1
                t += 1
            for r in range(nc):
                i = cols[r]
                if r == 0:
                    piv = d[i]
                    x[i] = b[i] / piv
                else:
                    w = aw[i]
                    piv = d[i] - w * cp[r - 1]
                    x[i] = (b[i] + w * x[cols[r - 1]]) / piv
                cp[r] = ae[i] / piv
            for r in range(nc - 2, -1, -1):
                x[cols[r]] += cp[r] * x[cols[r + 1]]
        xmax = 0.0
        for i in range(n):
            if x[i] > xmax:
                xmax = x[i]
        thr = AS_TOL * xmax
        changed = False
        for i in range(n):
            if fixed[i]:
                continue
            if free[i]:
                if x[i] < -thr:
                    free[i] = False
                    changed = True
            else:
                im = i - 1 if i > 0 else n - 1
                ip = i + 1 if i < n - 1 else 0
                if aw[i] * x[im] + ae[i] * x[ip] + b[i] > thr * d[i] + AS_TOL * bmax:
                    free[i] = True
                    changed = True
        if not changed:
            break
    for i in range(n):
        free[i] = free[i] and x[i] > 0.0
    return free


class ActiveSetOptions(NamedTuple):
    """What ``active_set_field`` solves: the complementarity problem (``project``: Swift-Stieber) or one
    linear solve, in at most ``max_iter`` linear solves, each by the axial sine transform where that is
    cheaper (``transform``; else the envelope Cholesky factorisation alone)."""

    project: bool
    max_iter: int
    transform: bool


@njit(cache=True, error_model="numpy")
def _first_free_set(params, eqs, p, fixed, project, warm, warm_in, mh, symmetric):
    """The first free (solved, uncavitated) node set of ``active_set_field``, (n_theta, mh + 2): every node
    without ``project``; else the earlier state's set (``warm`` with ``warm_in``), the first axial mode's film
    (a symmetric field), or the clipped Gumbel film of ``p`` widened by ``AS_WIDEN`` of the circumference.
    ``eqs``: the node equations (aw, ae, an, ap, rhs)."""
    aw, ae, an, _, rhs = eqs
    n = params.n_theta
    # free[i, j]: node solved for (j = 1..mh); held columns are never free
    free = np.zeros((n, mh + 2), dtype=np.bool_)
    for i in range(n):
        if fixed[i]:
            continue
        for j in range(1, mh + 1):
            free[i, j] = (not project) or p[i, j] > 0.0
    # widen the first film by AS_WIDEN of the circumference both ways in theta (not across a held column):
    # nodes it takes in wrongly go back in one step (every free node with p < 0 becomes active at once), while
    # cavitated nodes are released only a layer per step (one must see its neighbour's pressure first), so
    # starting wide costs fewer solves: on 30..288 angles about 3-5 .. 8-16 instead of 7 .. 33-53
    warm_start = False
    if warm is not None:
        if warm.shape[0] != n or warm.shape[1] != mh + 2:
            raise ValueError("the warm-start free set must have shape (n_theta, rows solved + 2)")
        if project and warm_in:
            # the free set of an earlier, nearby state (a caller's continuation): usually right or nearly so
            warm_start = True
            for i in range(n):
                if not fixed[i]:
                    for j in range(1, mh + 1):
                        free[i, j] = warm[i, j]
    predicted = project and not warm_start and symmetric
    if predicted:
        # the film of the first axial mode's 1-D problem, every row (``mode_one_film``); p is not read
        film = mode_one_film(params, aw, ae, an, rhs, fixed)
        for i in range(n):
            if not fixed[i]:
                for j in range(1, mh + 1):
                    free[i, j] = film[i]
    for _ in range(int(round(AS_WIDEN * n)) if project and not warm_start and not predicted else 0):
        f2 = free.copy()
        for i in range(n):
            if fixed[i]:
                continue
            for j in range(1, mh + 1):
                if f2[(i + 1) % n, j] or f2[(i - 1) % n, j]:
                    free[i, j] = True
    return free


@njit(cache=True, error_model="numpy")
def _field_max(p, fixed, mh):
    """The largest pressure of the solved rows (held columns aside)."""
    pmax = 0.0
    for i in range(p.shape[0]):
        if not fixed[i]:
            for j in range(1, mh + 1):
                if p[i, j] > pmax:
                    pmax = p[i, j]
    return pmax


@njit(cache=True, error_model="numpy")
def _update_active_set(eqs, p, free, fixed, mh, thr):
    """One primal-dual update of the free set in place: free nodes with p < -thr become active, active nodes
    where the film would push pressure in (G > thr ap) are released.  Returns whether the set changed."""
    aw, ae, an, ap, rhs = eqs
    n = free.shape[0]
    changed = False
    for i in range(n):
        if fixed[i]:
            continue
        im = i - 1 if i > 0 else n - 1
        ip = i + 1 if i < n - 1 else 0
        for j in range(1, mh + 1):
            if free[i, j]:
                if p[i, j] < -thr:
                    free[i, j] = False
                    changed = True
            else:
                g = aw[i] * p[im, j] + ae[i] * p[ip, j] + an[i] * (p[i, j - 1] + p[i, j + 1]) - rhs[i]
                if g > thr * ap[i]:
                    free[i, j] = True
                    changed = True
    return changed


class EnvelopeWork(NamedTuple):
    """The envelope Cholesky solve's arrays (``_envelope_solve``), kept from one solve of an active-set
    iteration to the next so that an unchanged start of the ordering reuses its factor rows."""

    idx: np.ndarray       # (n_theta, mh + 2) int64: each node's unknown number (-1: not free)
    first: np.ndarray     # lowest-numbered coupled unknown of each row (the envelope)
    start: np.ndarray     # each row's first entry in the envelope storage
    node_i: np.ndarray    # each unknown's node
    node_j: np.ndarray
    y: np.ndarray         # right-hand side
    x: np.ndarray         # solution
    inv_diag: np.ndarray  # the factor's inverse diagonal
    col_count: np.ndarray  # free nodes per column
    order: np.ndarray     # int64 [nu_old, c0]: the last ordering's unknowns and the column it starts after


@njit(cache=True, error_model="numpy")
def _envelope_work(n, mh):
    """``EnvelopeWork`` for an (n, mh) node set (``_envelope_work(0, 0)``: empty, not yet needed)."""
    cap = n * mh
    return EnvelopeWork(np.empty((n, mh + 2) if n else (0, 0), dtype=np.int64), np.empty(cap, dtype=np.int64),
                        np.empty(cap + 1 if n else 0, dtype=np.int64), np.empty(cap, dtype=np.int64),
                        np.empty(cap, dtype=np.int64), np.empty(cap), np.empty(cap), np.empty(cap),
                        np.empty(n, dtype=np.int64), np.array([0, -1], dtype=np.int64))


@njit(cache=True, error_model="numpy")
def _envelope_solve(eqs, p, free, fixed, dims, work, env):
    """One linear solve of ``active_set_field`` by the envelope Cholesky factorisation: the free nodes ordered
    column by column after a column with the fewest of them, their equations assembled (active nodes at
    p = 0, held columns and end rows known), factorised from the first node whose place changed, solved and
    written back into ``p`` (mirrored onto the upper half of a symmetric field).  ``dims``: (n, m, mh, nz,
    symmetric, centre, folded); returns the envelope storage (grown where it had to)."""
    aw, ae, an, ap, rhs = eqs
    n, m, mh, nz, symmetric, centre, folded = dims
    idx, first, start, node_i, node_j = work.idx, work.first, work.start, work.node_i, work.node_j
    y, x, inv_diag, count = work.y, work.x, work.inv_diag, work.col_count
    nu_old, c0 = work.order[0], work.order[1]
    # order: the columns after one with the fewest free nodes (held columns have none), that one last
    best = mh + 1
    for i in range(n):
        cnt = 0
        for j in range(1, mh + 1):
            if free[i, j]:
                cnt += 1
        count[i] = cnt
        if cnt < best:
            best = cnt
    if c0 < 0 or count[c0] > best:
        for i in range(n):
            if count[i] == best:
                c0 = i
                break
        nu_old = 0  # a new ordering: nothing to reuse
    # number the free nodes; r0 = the first whose node differs from the last ordering's
    nu = 0
    r0 = -1
    for t in range(n):
        i = (c0 + 1 + t) % n
        for j in range(mh + 2):
            if 1 <= j <= mh and free[i, j]:
                if r0 < 0 and (nu >= nu_old or node_i[nu] != i or node_j[nu] != j):
                    r0 = nu
                idx[i, j] = nu
                node_i[nu] = i
                node_j[nu] = j
                nu += 1
            else:
                idx[i, j] = -1
    if r0 < 0:
        r0 = nu
    nu_old = nu
    # envelope from r0 on: the lowest-numbered coupled unknown of each row
    total = start[r0] if r0 > 0 else 0
    for r in range(r0, nu):
        i, j = node_i[r], node_j[r]
        im = i - 1 if i > 0 else n - 1
        ip = i + 1 if i < n - 1 else 0
        f = r
        for q in (idx[im, j], idx[ip, j], idx[i, j - 1], idx[i, j + 1]):
            if 0 <= q < f:
                f = q
        first[r] = f
        start[r] = total
        total += r - f + 1
    start[nu] = total
    if env.shape[0] < total:
        grown = np.empty(2 * total)
        grown[: env.shape[0]] = env
        env = grown
    # assemble K = -(rows of A) on the free nodes (scaled by 1/2 on a centre row) and its right-hand side
    for r in range(r0, nu):
        i, j = node_i[r], node_j[r]
        im = i - 1 if i > 0 else n - 1
        ip = i + 1 if i < n - 1 else 0
        s = 0.5 if (centre and j == mh) else 1.0
        sr = start[r] - first[r]
        for k in range(start[r], start[r + 1]):
            env[k] = 0.0
        env[sr + r] = s * (ap[i] - an[i] if (folded and j == mh) else ap[i])
        br = -rhs[i]
        # theta neighbours: free (matrix), held (known value), active (p = 0)
        q = idx[im, j]
        if q >= 0:
            if q < r:
                env[sr + q] -= s * aw[i]
        elif fixed[im]:
            br += aw[i] * p[im, j]
        q = idx[ip, j]
        if q >= 0:
            if q < r:
                env[sr + q] -= s * ae[i]
        elif fixed[ip]:
            br += ae[i] * p[ip, j]
        # axial neighbour below: the end row (known) or a node (twice on a centre row: its mirror above)
        a_dn = 2.0 * an[i] if (centre and j == mh) else an[i]
        q = idx[i, j - 1]
        if j == 1:
            br += a_dn * p[i, 0]
        elif 0 <= q < r:
            env[sr + q] -= s * a_dn
        # axial neighbour above: a node, the far end row, or nothing (the mirror, folded or centre)
        if not symmetric and j == m:
            br += an[i] * p[i, nz - 1]
        else:
            q = idx[i, j + 1]
            if 0 <= q < r:
                env[sr + q] -= s * an[i]
        y[r] = s * br
    envelope_cholesky(first, start, env, inv_diag, r0, nu)
    envelope_solve(first, start, env, inv_diag, r0, nu, y, x)
    # write the field back (active nodes at 0), mirrored onto the upper half
    for i in range(n):
        if fixed[i]:
            continue
        for j in range(1, mh + 1):
            q = idx[i, j]
            val = x[q] if q >= 0 else 0.0
            p[i, j] = val
            if symmetric:
                p[i, m + 1 - j] = val
    work.order[0] = nu_old
    work.order[1] = c0
    return env


@njit(cache=True, error_model="numpy")
def active_set_field(params, state, p, fixed, opts, warm=None, warm_in=False):
    """The discrete Reynolds equation solved directly, as a linear complementarity problem if ``project``.

    Same discrete problem as ``sor_sweeps`` (the node columns ``fixed`` held at their values in ``p``, the
    end rows of ``p`` prescribed) and, with ``project``, the same complementarity problem as
    ``psor_swift_stieber``: p >= 0, G(p) = A p - rhs <= 0 where p = 0, G(p) = 0 where p > 0.  A
    primal-dual active-set iteration (Hintermueller, Ito & Kunisch 2003): with the active (cavitated)
    nodes held at p = 0, the Reynolds equation of the other nodes is solved directly; then free nodes with
    p < 0 become active and active nodes with G > 0 (the film would push pressure into them) are released,
    until the set no longer changes, which is then the exact solution of the discrete problem.  -A is a
    symmetric M-matrix, for which the iteration terminates in finitely many steps from any start.  The
    first free set is where the interior of ``p`` is > 0 on entry (the clipped Gumbel field: the
    Swift-Stieber film contains the full-Sommerfeld film), widened in theta by ``AS_WIDEN`` of the
    circumference.  Without ``project``: one linear solve.

    Each solve is a sparse Cholesky factorisation of the free nodes' equations in envelope storage,
    ordered column by column (theta outer, z inner) starting after a column with the fewest free nodes
    (a held groove column if any), kept from one iteration to the next while it stays the fewest, so the
    periodic wrap rarely costs anything and the factor rows before the first changed node are reused (the
    film edge nearer the end of the ordering moving alone refactors only the columns after it).  With
    ``p_supply == 0`` the field is symmetric about mid-length and only the lower half of the axial nodes is
    solved (the mirror folded into the top row; with an odd number of interior rows the centre row is
    halved to keep the matrix symmetric).

    With ``transform`` a solve goes instead by the axial sine transform where that is cheaper
    (``capacitance_field``: wholly cavitated or held node columns cut the ring into runs, each one symmetric
    tridiagonal system per axial mode, the active nodes inside a run held at zero by a small capacitance
    system): same free set, same discrete equations, the same solution to round-off.  ``warm``: a bool
    array (n_theta, rows solved + 2) that receives the final free set; with ``warm_in`` its content is the
    first free set (an earlier nearby state's) instead of the widened film of ``p``.

    ``state``: the journal's (x1, x2, v1, v2); ``opts``: an ``ActiveSetOptions`` (``project``, ``max_iter``,
    ``transform``).  ``p``: full (n_theta, n_z) field, updated in place.  Returns the number of linear solves,
    or -1 if ``max_iter`` solves did not settle the active set.  The first free set is
    ``_first_free_set``'s, each update of the set ``_update_active_set``'s.
    """
    x1, x2, v1, v2 = state
    project, max_iter, transform = opts.project, opts.max_iter, opts.transform
    n = params.n_theta
    nz = p.shape[1]
    m = nz - 2
    eqs = node_equations(params, x1, x2, v1, v2)
    aw, ae, an, ap, rhs = eqs
    symmetric = params.p_supply == 0.0
    mh = (m + 1) // 2 if symmetric else m  # rows solved: j = 1..mh
    centre = symmetric and m % 2 == 1  # row mh is the mid-plane row (halved)
    folded = symmetric and m % 2 == 0  # row mh's upper neighbour is its own mirror
    free = _first_free_set(params, eqs, p, fixed, project, warm, warm_in, mh, symmetric)
    # the envelope factorisation's work arrays, allocated on its first use (the transform path needs none)
    work = _envelope_work(0, 0)
    env = np.empty(0)
    dims = (n, m, mh, nz, symmetric, centre, folded)
    for it in range(max_iter):
        if transform and capacitance_field(params, aw, ae, an, rhs, free, fixed, p, m, mh, symmetric):
            work.order[0] = 0  # the envelope factor no longer matches: a later envelope solve starts afresh
        else:
            if work.idx.shape[0] == 0:
                work = _envelope_work(n, mh)
            env = _envelope_solve(eqs, p, free, fixed, dims, work, env)
        pmax = _field_max(p, fixed, mh)
        if not project:
            return it + 1
        # update the active set; unchanged means solved
        if not _update_active_set(eqs, p, free, fixed, mh, AS_TOL * pmax):
            if warm is not None:
                warm[:, :] = free
            # round-off negatives (above -thr) are the zeros of cavitated nodes
            for i in range(n):
                for j in range(1, nz - 1):
                    if p[i, j] < 0.0:
                        p[i, j] = 0.0
            return it + 1
    return -1


@njit(cache=True)
def integrate_field(params, p):
    """Simpson integral of a full (n_theta, n_z) field: F = -R sum w_theta w_z p (sin, cos)."""
    a_sin = params.a_sin
    a_cos = params.a_cos
    w_z = params.w_z
    n = p.shape[0]
    f1 = 0.0
    f2 = 0.0
    for i in range(n):
        col = 0.0
        for j in range(p.shape[1]):
            col += w_z[j] * p[i, j]
        f1 -= a_sin[i] * col
        f2 -= a_cos[i] * col
    return f1, f2


@njit(cache=True)
def swift_stieber_field(params, x1, x2, v1, v2, p):
    """Swift-Stieber field in place from the clipped linear field in ``p`` (boundary rows set), by the solver
    of ``params.ss_method``; raises if it did not converge."""
    if params.ss_method == SS_PSOR:
        it = psor_swift_stieber(params, x1, x2, v1, v2, p, params.sor_omega, params.sor_tol, params.sor_max_iter)
        if it < 0:
            raise RuntimeError("projected SOR (Swift-Stieber cavitation) did not converge; raise sor_max_iter")
    else:
        n = params.n_theta
        it = active_set_field(params, (x1, x2, v1, v2), p, np.zeros(n, dtype=np.bool_),
                              ActiveSetOptions(True, n * p.shape[1], True))
        if it < 0:
            raise RuntimeError("the active-set iteration (Swift-Stieber cavitation) did not settle")
    return it


@njit(cache=True)
def film_force_ss(params, x1, x2, v1, v2):
    """One force evaluation with Swift-Stieber cavitation (same signature as ``film_force``)."""
    n = params.n_theta
    full_basis = params.full_basis
    nz = full_basis.shape[0] + 2
    p = np.empty((n, nz))
    if params.p_supply == 0.0 and params.ss_method != SS_PSOR:
        # the active-set iteration's first guess of a symmetric field is ``mode_one_film``'s: only the end
        # rows of p are read
        p[:, :] = 0.0
    else:
        # the solvers start from the clipped linear field
        linear_field(params, x1, x2, v1, v2, full_basis, params.p_supply, p)
        for i in range(n):
            for j in range(nz):
                if p[i, j] < 0.0:
                    p[i, j] = 0.0
    swift_stieber_field(params, x1, x2, v1, v2, p)
    return integrate_field(params, p)


@njit(cache=True)
def general_linear_field(gp, x1, x2, v1, v2, out):
    """Pressure before cavitation for a film h(theta, z) on a surface of revolution R(z).

    The equation (``conical`` derives it), with H = h_r / c_ref the radial
    gap in units of a reference clearance:

        d/dtheta(H^3 dp/dtheta) + cos^2(alpha) R d/dz(R H^3 dp/dz)
            = R^2 [K_omega dH/dtheta + K_v (-V1 sin(theta) - V2 cos(theta))],

    conservative central differences (H^3 at theta-faces and z-half nodes),
    periodic in theta, p = p_supply at z = 0, 0 at z = L.  The unknowns of
    each angle form one axial line, so the matrix is block tridiagonal with
    cyclic corner blocks: tridiagonal diagonal blocks, diagonal off-diagonal
    blocks.  Solved directly: block Thomas over angles 1..n-1 with the first
    angle's line as a border unknown (P_i = x_i + Y_i P_0), then the first
    angle's equation for P_0.  O(n_theta n_z^3); used when h depends on z.

    ``gp``: a ``params.GeneralParams`` (``conical.build_general_params``).
    """
    n = gp.n_theta
    sin_n, cos_n, sin_f, cos_f = gp.sin_node, gp.cos_node, gp.sin_face, gp.cos_face
    c_node, c_half, r_node, r_half = gp.c_node, gp.c_half, gp.r_node, gp.r_half
    inv_cr, inv_dth2, inv_dth, cz = gp.inv_c_ref, gp.inv_dtheta2, gp.inv_dtheta, gp.axial_coef
    k_omega, k_v, p_s = gp.k_omega, gp.k_v, gp.p_supply
    nz = c_node.shape[0]
    m = nz - 2
    # block coefficients
    D = np.zeros((n, m, m))
    Lw = np.empty((n, m))
    Ue = np.empty((n, m))
    B = np.empty((n, m))
    for i in range(n):
        im = i - 1 if i > 0 else n - 1
        vterm = k_v * (-v1 * sin_n[i] - v2 * cos_n[i])
        for jj in range(m):
            j = jj + 1
            hf = (c_node[j] - x1 * sin_f[i] - x2 * cos_f[i]) * inv_cr
            hfm = (c_node[j] - x1 * sin_f[im] - x2 * cos_f[im]) * inv_cr
            hn = (c_half[j] - x1 * sin_n[i] - x2 * cos_n[i]) * inv_cr  # at z_{j+1/2}
            hs = (c_half[j - 1] - x1 * sin_n[i] - x2 * cos_n[i]) * inv_cr  # at z_{j-1/2}
            ue = hf * hf * hf * inv_dth2
            lw = hfm * hfm * hfm * inv_dth2
            an = cz * r_node[j] * r_half[j] * hn * hn * hn
            as_ = cz * r_node[j] * r_half[j - 1] * hs * hs * hs
            Ue[i, jj] = ue
            Lw[i, jj] = lw
            D[i, jj, jj] = -(ue + lw + an + as_)
            rhs = r_node[j] * r_node[j] * (k_omega * (hf - hfm) * inv_dth + vterm)
            if jj > 0:
                D[i, jj, jj - 1] = as_
            else:
                rhs -= as_ * p_s
            if jj < m - 1:
                D[i, jj, jj + 1] = an
            B[i, jj] = rhs
    # block Thomas over i = 1..n-1; column 0 of F carries x, columns 1..m carry Y
    E = np.zeros((n, m, m))
    F = np.zeros((n, m, m + 1))
    rhs_blk = np.zeros((m, 2 * m + 1))
    for i in range(1, n):
        G = D[i].copy()
        rhs_blk[:, :] = 0.0
        for a in range(m):
            rhs_blk[a, m] = B[i, a]
        if i == 1:
            for a in range(m):
                rhs_blk[a, m + 1 + a] -= Lw[1, a]
        if i == n - 1:
            for a in range(m):
                rhs_blk[a, m + 1 + a] -= Ue[n - 1, a]
        else:
            for a in range(m):
                rhs_blk[a, a] = Ue[i, a]
        if i > 1:
            for a in range(m):
                la = Lw[i, a]
                for b in range(m):
                    G[a, b] -= la * E[i - 1, a, b]
                for b in range(m + 1):
                    rhs_blk[a, m + b] -= la * F[i - 1, a, b]
        sol = np.linalg.solve(G, rhs_blk)
        if i < n - 1:
            E[i] = sol[:, :m]
        F[i] = sol[:, m:]
    # back substitution: S_i = F_i - E_i S_{i+1}
    for i in range(n - 2, 0, -1):
        F[i] -= E[i] @ F[i + 1]
    # the first angle's equation for its own line P_0
    A0 = D[0].copy()
    b0 = B[0].copy()
    for a in range(m):
        la = Lw[0, a]
        ua = Ue[0, a]
        for b in range(m):
            A0[a, b] += la * F[n - 1, a, 1 + b] + ua * F[1, a, 1 + b]
        b0[a] -= la * F[n - 1, a, 0] + ua * F[1, a, 0]
    p0 = np.linalg.solve(A0, b0)
    for i in range(n):
        out[i, 0] = p_s
        out[i, nz - 1] = 0.0
        for a in range(m):
            if i == 0:
                out[i, a + 1] = p0[a]
            else:
                acc = F[i, a, 0]
                for b in range(m):
                    acc += F[i, a, 1 + b] * p0[b]
                out[i, a + 1] = acc


@njit(cache=True)
def general_force(gp, x1, x2, v1, v2):
    """Force (F1, F2) of the general path; Gumbel clipping or none (``gp.cavitation``)."""
    p = np.empty((gp.n_theta, gp.c_node.shape[0]))
    general_linear_field(gp, x1, x2, v1, v2, p)
    f1, f2, _ = film_integrals(gp.a_sin, gp.a_cos, gp.w_theta, gp.w_zr, p, gp.cavitation == CAV_GUMBEL)
    return f1, f2


@njit(cache=True)
def film_integrals(a_sin, a_cos, w_theta, w_z, p, clip):
    """Simpson sums of a field p (n_theta, n_z), negative values dropped if ``clip`` (Gumbel):
    (-sum a_sin w_z p, -sum a_cos w_z p, sum w_theta w_z p)."""
    f1 = 0.0
    f2 = 0.0
    total = 0.0
    for i in range(p.shape[0]):
        col = 0.0
        for j in range(p.shape[1]):
            pij = p[i, j]
            if clip and pij < 0.0:
                pij = 0.0
            col += w_z[j] * pij
        f1 -= a_sin[i] * col
        f2 -= a_cos[i] * col
        total += w_theta[i] * col
    return f1, f2, total
