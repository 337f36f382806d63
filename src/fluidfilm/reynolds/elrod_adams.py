"""Mass-conserving cavitation: the Elrod-Adams p-theta film with the Jakobsson-Floberg-Olsson conditions.

Why: Guembel and Swift-Stieber cavitation do not conserve mass in the cavitated zone, so the film they
give forgets where oil was and was not.  Under dynamic load that is exactly what matters (Yu & Sawicki
2002; Zhao et al. 1998).  This model carries the film content theta (the fraction of the gap filled with
liquid, 1 in the full film) as a state from one time step to the next.

The equation (CONVENTIONS.md frame; H = h/c = 1 - e1 sin(theta) - e2 cos(theta), zeta = z/R), in the scaling
of ``kernels`` (K_omega = 6 mu omega R^2/c^2, K_v c = 12 mu R^2/c^2)::

    d/dtheta(H^3 dp/dtheta) + d/dzeta(H^3 dp/dzeta) = K_omega d(phi H)/dtheta + K_v c d(phi H)/dt

    p > 0  =>  phi = 1        (full film: the Reynolds equation)
    p = 0  =>  0 <= phi <= 1  (cavity: the liquid is carried by the journal, no pressure flow inside)

(phi is the film content; the code calls it ``th``.)  Discretisation: finite volumes on the grid of
``mesh.FilmMesh`` (node angles turned so that node 0 sits on the first groove), the diffusive fluxes exactly
those of ``kernels.node_equations``, the Couette flux K_omega phi H_face upwinded (the journal drags the
liquid towards +theta), the time derivative by backward Euler (Ausas, Jai & Buscaglia, J. Tribol. 131
031702, 2009).  Where phi = 1 on every node this is ``kernels``' discrete Reynolds equation to the bit's
arithmetic, so the steady field equals the Swift-Stieber complementarity field wherever the liquid reaching
the pressure zone arrives full (``tests/reynolds/test_elrod_adams.py``).

Why this scheme (and not an LCP solver per step, Giacopini et al. 2010): Ausas' node-wise switch is the
complementarity condition itself (p_trial <= 0 if and only if phi <= 1, see ``ea_sweep``), it needs no
matrix, its sweep in +theta carries the film content downstream within one sweep, and warm-started from the
previous time step it needs few sweeps: the fields move little per rotor step (Courant number ~ 0.02).

Feed: the film must be fed, or it drains through its ends (with the ends at the cavity pressure, no liquid
enters a cavity).  A groove: axial line(s) of nodes held at the supply pressure and full (phi = 1); and/or
the supply end z = 0 at ``bearing.supply_pressure``.  Both ends are flooded (phi = 1 there).

Time stepping inside RK4 (``rotor.film_memory``): the committed content phi^n lives between steps.  Each RK4
stage at (X, V) solves one backward-Euler step of length dt from the content phi^n H(X - dt V) (the gap one
step earlier along the stage's own velocity, so a full film gives the squeeze term -V.(sin, cos) exactly,
as the Reynolds solver does), and after each accepted (sub)step one more solve from phi^n H(X_n) to X_{n+1}
commits phi^{n+1}: that solve is the one whose flow balance closes to round-off.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from fluidfilm.core.bearing import JournalBearing
from fluidfilm.core.force_model import ReferenceModel
from fluidfilm.core.states import as_state_pairs
from fluidfilm.reynolds.mesh import FilmMesh

# Let LLVM reassociate the sweep's sums so that its inner loop vectorises; no finite-math assumptions (the
# divergence check needs NaN and inf)
_FAST = {"reassoc", "contract", "arcp"}

# the sweep's results: converged, or the sweep limit reached
EA_CONVERGED, EA_NOT_CONVERGED, EA_DIVERGED = 0, 1, 2
# the cavitation rules one solver runs on the same grid and feed: mass-conserving (the film content carried),
# Swift-Stieber (p >= 0 by complementarity, the content held full) and Guembel (the linear film, negative
# pressures dropped from the force)
RULE_JFO, RULE_SWIFT_STIEBER, RULE_GUMBEL = 0, 1, 2
RULES = {"jfo": RULE_JFO, "swift-stieber": RULE_SWIFT_STIEBER, "gumbel": RULE_GUMBEL}

# sweeps after which a solve drops its over-relaxation (``ea_sweeps``)
SLOW_SWEEPS = 500


class EAParams(NamedTuple):
    """The compiled kernels' parameters (numba compiles a NamedTuple to a struct)."""

    n_theta: int
    n_z: int
    sin_node: np.ndarray     # (n_theta,) sin/cos of the node angles (node 0 on the first groove)
    cos_node: np.ndarray
    sin_face: np.ndarray     # (n_theta,) the same at the faces theta_{i+1/2}
    cos_face: np.ndarray
    inv_c: float             # 1 / clearance [1/m]
    inv_dtheta: float
    inv_dtheta2: float
    inv_dzeta2: float        # (R / dz)^2
    k_omega: float           # 6 mu omega_ref R^2 / c^2 [Pa] at the bearing's speed
    kvc: float               # K_v c = 12 mu R^2 / c^2 [Pa s]
    a_sin: np.ndarray        # (n_theta,) R w_theta sin(theta): the force's theta weights
    a_cos: np.ndarray
    w_z: np.ndarray          # (n_z,) axial Simpson weights
    w_cell: float            # the area of one cell in (theta, zeta) units, dtheta * dzeta
    p_supply: float          # [Pa] at z = 0 and in the grooves
    p_end: float             # [Pa] at z = L (0 for a bearing: ambient)
    fixed: np.ndarray        # (n_theta,) bool: groove columns (held at p_supply, full)
    sor_omega: float         # over-relaxation of the pressure
    tol: float               # stage solve: max change of p relative to max p, and of phi
    tol_commit: float        # commit solve (its flow balance closes to round-off at any tolerance: close_content)
    tol_steady: float        # steady solves and the quasi-static force (K, C by perturbation need its digits)
    max_sweeps: int
    coarse_every: int        # a coarse correction (``coarse_correction``) every that many sweeps; 0: none
    mode_shape: np.ndarray   # (n_z,) the coarse correction's axial shape, sin(pi z / L)
    rule: int                # RULE_JFO, or a non-conserving rule on the same grid and feed (content held at 1)
    mu: float                # viscosity [Pa s], radius and clearance [m], axial node spacing [m]: the film's flow
    radius: float            # and friction (``film_flows``)
    clearance: float
    dz: float


@njit(cache=True)
def journal_gap(ep, e1, e2, h, hf):
    """The dimensionless gap H = h/c = 1 - e1 sin(theta) - e2 cos(theta) at the nodes (``h``) and faces (``hf``)."""
    for i in range(ep.n_theta):
        h[i] = 1.0 - e1 * ep.sin_node[i] - e2 * ep.cos_node[i]
        hf[i] = 1.0 - e1 * ep.sin_face[i] - e2 * ep.cos_face[i]


@njit(cache=True, inline="always")
def _coefficients(ep, h, hf, k_omega):
    """Per angle (aw, ae, an, ap, cout, cin): the diffusive coefficients (as ``kernels.node_equations``) and the
    Couette coefficients K_omega H_face / dtheta of the node's outflow and of its west neighbour's inflow."""
    n = ep.n_theta
    aw = np.empty(n)
    ae = np.empty(n)
    an = np.empty(n)
    ap = np.empty(n)
    cout = np.empty(n)
    cin = np.empty(n)
    for i in range(n):
        im = i - 1 if i > 0 else n - 1
        h3w = hf[im] * hf[im] * hf[im]
        h3e = hf[i] * hf[i] * hf[i]
        aw[i] = h3w * ep.inv_dtheta2
        ae[i] = h3e * ep.inv_dtheta2
        an[i] = h[i] * h[i] * h[i] * ep.inv_dzeta2
        ap[i] = aw[i] + ae[i] + 2.0 * an[i]
        cout[i] = k_omega * hf[i] * ep.inv_dtheta
        cin[i] = k_omega * hf[im] * ep.inv_dtheta
    return aw, ae, an, ap, cout, cin


@njit(cache=True, error_model="numpy")
def cyclic_tridiagonal(lo, d, up, b, x):
    """Solve lo[i] x[i-1] + d[i] x[i] + up[i] x[i+1] = b[i], i periodic (Sherman-Morrison on Thomas; n >= 3)."""
    n = d.shape[0]
    gamma = -d[0]
    bb = d.copy()
    bb[0] = d[0] - gamma
    bb[n - 1] = d[n - 1] - lo[0] * up[n - 1] / gamma
    u = np.zeros(n)
    u[0] = gamma
    u[n - 1] = up[n - 1]
    cp = np.empty(n)
    y = np.empty(n)
    z = np.empty(n)
    # forward sweep of both right-hand sides
    beta = bb[0]
    y[0] = b[0] / beta
    z[0] = u[0] / beta
    for i in range(1, n):
        cp[i] = up[i - 1] / beta
        beta = bb[i] - lo[i] * cp[i]
        y[i] = (b[i] - lo[i] * y[i - 1]) / beta
        z[i] = (u[i] - lo[i] * z[i - 1]) / beta
    for i in range(n - 2, -1, -1):
        y[i] -= cp[i + 1] * y[i + 1]
        z[i] -= cp[i + 1] * z[i + 1]
    fact = (y[0] + lo[0] * y[n - 1] / gamma) / (1.0 + z[0] + lo[0] * z[n - 1] / gamma)
    for i in range(n):
        x[i] = y[i] - fact * z[i]


@njit(cache=True, error_model="numpy")
def coarse_correction(ep, aw, ae, an, ap, cin, cout, tk, h, content, p, th):
    """A Galerkin correction of the pressure on the full-film nodes in the space of one axial shape per node
    column (``ep.mode_shape``, sin(pi z/L)): the error modes smooth along the bearing, which Gauss-Seidel
    damps slowest, are removed by one periodic tridiagonal solve in theta.  Only nodes with p > 0 take part;
    a corrected pressure below zero is set to zero (the next sweep re-decides the node)."""
    n = ep.n_theta
    nz = ep.n_z
    s = ep.mode_shape
    every = ep.rule == RULE_GUMBEL   # the linear film: every node is an unknown, whatever its sign
    d = np.zeros(n)
    lo = np.zeros(n)
    up = np.zeros(n)
    b = np.zeros(n)
    for i in range(n):
        if ep.fixed[i]:
            d[i] = 1.0
            continue
        im = i - 1 if i > 0 else n - 1
        ip = i + 1 if i < n - 1 else 0
        pw = p[im]
        pe = p[ip]
        pc = p[i]
        tw = th[im]
        full = cout[i] + tk * h[i]
        dd = 0.0
        ll = 0.0
        uu = 0.0
        bb = 0.0
        for j in range(1, nz - 1):
            if pc[j] <= 0.0 and not every:
                continue
            sj = s[j]
            # residual of the node's full-film equation: ap (p_trial - p)
            src = aw[i] * pw[j] + ae[i] * pe[j] + an[i] * (pc[j - 1] + pc[j + 1]) + cin[i] * tw[j]
            if tk != 0.0:
                src += tk * content[i, j]
            bb += sj * (src - full - ap[i] * pc[j])
            a_s = ap[i] * sj
            if pc[j - 1] > 0.0 or (every and j > 1):
                a_s -= an[i] * s[j - 1]
            if pc[j + 1] > 0.0 or (every and j < nz - 2):
                a_s -= an[i] * s[j + 1]
            dd += sj * a_s
            if (pw[j] > 0.0 or every) and not ep.fixed[im]:
                ll -= sj * aw[i] * sj
            if (pe[j] > 0.0 or every) and not ep.fixed[ip]:
                uu -= sj * ae[i] * sj
        if dd == 0.0:
            d[i] = 1.0
        else:
            d[i] = dd
            lo[i] = ll
            up[i] = uu
            b[i] = bb
    a = np.empty(n)
    cyclic_tridiagonal(lo, d, up, b, a)
    for i in range(n):
        if ep.fixed[i] or a[i] == 0.0:
            continue
        pc = p[i]
        for j in range(1, nz - 1):
            if every:
                pc[j] += a[i] * s[j]
            elif pc[j] > 0.0:
                v = pc[j] + a[i] * s[j]
                pc[j] = v if v > 0.0 else 0.0


# --- the colour layout of the sweeps ---------------------------------------------------------------------------
# Red-black Gauss-Seidel: node (i, j) has colour (i + j) % 2 and depends on the other colour only.  Each colour's
# nodes are held in a plane P_c[k + 1, i + 1] with j = 2k + (c + i) % 2 (one row per pair of axial nodes, one
# column per angle, a ghost column at each end for the periodic neighbours and a ghost row at each end).  Then
# a node's west/east neighbours sit in the other plane at the same row, its axial neighbours at the same column
# in rows k and k -+ 1 (which one, by the column's parity), and the sweep's inner loop runs over the angles with
# unit stride, long enough to vectorise (the j-split layout before gave loops of n_z / 2 ~ 15, mostly scalar
# remainders).


@njit(cache=True)
def _pack(ep, a, colour, out):
    """out[k + 1, i + 1] = a[i, 2k + (colour + i) % 2] (0 where that j is past the end), ghosts filled."""
    n = ep.n_theta
    nz = ep.n_z
    out[:, :] = 0.0
    for i in range(n):
        q = (colour + i) % 2
        for k in range(out.shape[0] - 2):
            j = 2 * k + q
            if j < nz:
                out[k + 1, i + 1] = a[i, j]
    _ghosts(out, n)


@njit(cache=True, inline="always")
def _ghosts(plane, n):
    for r in range(plane.shape[0]):
        plane[r, 0] = plane[r, n]
        plane[r, n + 1] = plane[r, 1]


@njit(cache=True)
def _unpack(ep, plane, colour, a):
    n = ep.n_theta
    nz = ep.n_z
    for i in range(n):
        q = (colour + i) % 2
        for k in range(plane.shape[0] - 2):
            j = 2 * k + q
            if j < nz:
                a[i, j] = plane[k + 1, i + 1]


@njit(cache=True)
def _unknown_mask(ep, colour, out):
    """1.0 where the plane holds an unknown node (1 <= j <= n_z - 2, not a groove column), else 0.0."""
    n = ep.n_theta
    nz = ep.n_z
    out[:, :] = 0.0
    for i in range(n):
        if ep.fixed[i]:
            continue
        q = (colour + i) % 2
        for k in range(out.shape[0] - 2):
            j = 2 * k + q
            if 1 <= j <= nz - 2:
                out[k + 1, i + 1] = 1.0


@njit(cache=True, error_model="numpy", fastmath=_FAST)
def _colour_sweep(rule, colour, rows, n, w, tk, aw, ae, an, inv_ap, cin, full_rhs, cav_den, odd, mask, pc, tc, cc,
                  po, to):
    """Update colour ``colour``'s plane (``pc``, ``tc``; content ``cc``) from the other colour's (``po``, ``to``).
    Per-angle coefficients are padded like the planes; ``odd[ii]`` is 1.0 where the column's nodes of this
    colour sit at odd j (their axial neighbours at rows k and k + 1), else 0.0 (rows k - 1 and k).  Returns the
    sums of the squared changes of p and phi and of p^2 over the unknowns."""
    dp2 = 0.0
    dth2 = 0.0
    p2 = 0.0
    lo = 0.0 if rule == RULE_SWIFT_STIEBER else -np.inf
    for r in range(1, rows + 1):
        prow = pc[r]
        trow = tc[r]
        crow = cc[r]
        mrow = mask[r]
        o_mid = po[r]
        o_up = po[r + 1]
        o_dn = po[r - 1]
        t_mid = to[r]
        if rule == RULE_JFO:
            for ii in range(1, n + 1):
                axial = o_mid[ii] + odd[ii] * o_up[ii] + (1.0 - odd[ii]) * o_dn[ii]
                src = (aw[ii] * o_mid[ii - 1] + ae[ii] * o_mid[ii + 1] + an[ii] * axial + cin[ii] * t_mid[ii - 1]
                       + tk * crow[ii])
                p_old = prow[ii]
                th_old = trow[ii]
                p_new = p_old + w * ((src - full_rhs[ii]) * inv_ap[ii] - p_old)
                t = src * cav_den[ii]
                t = t if t < 1.0 else 1.0
                full = p_new > 0.0
                pn = p_new if full else 0.0
                tn = 1.0 if full else t
                m = mrow[ii]
                dpn = m * (pn - p_old)
                dtn = m * (tn - th_old)
                prow[ii] = p_old + dpn
                trow[ii] = th_old + dtn
                dp2 += dpn * dpn
                dth2 += dtn * dtn
                p2 += m * pn * pn
        else:
            for ii in range(1, n + 1):
                axial = o_mid[ii] + odd[ii] * o_up[ii] + (1.0 - odd[ii]) * o_dn[ii]
                src = aw[ii] * o_mid[ii - 1] + ae[ii] * o_mid[ii + 1] + an[ii] * axial + cin[ii] + tk * crow[ii]
                p_old = prow[ii]
                p_new = p_old + w * ((src - full_rhs[ii]) * inv_ap[ii] - p_old)
                pn = p_new if p_new > lo else lo
                dpn = mrow[ii] * (pn - p_old)
                prow[ii] = p_old + dpn
                dp2 += dpn * dpn
                p2 += mrow[ii] * pn * pn
        prow[0] = prow[n]
        prow[n + 1] = prow[1]
        trow[0] = trow[n]
        trow[n + 1] = trow[1]
    return dp2, dth2, p2


@njit(cache=True, error_model="numpy")
def ea_sweeps(ep, k_omega, h, hf, inv_dt, content, p, th, tol, max_sweeps):
    """Red-black Gauss-Seidel sweeps of the Elrod-Adams system for the gap H (``h`` at the nodes, ``hf`` at
    the faces theta_{i+1/2}; any function of theta) until converged; in place.

    ``content``: (n_theta, n_z) phi^n H^n of the step's start (not read when ``inv_dt`` = 0: the steady
    film).  ``p`` [Pa], ``th`` (phi): the fields, warm start in, solution out; their boundary rows and groove
    columns must hold their fixed values (``reset_fields``).  Each node (Ausas et al. 2009): the pressure it
    would have full, p_trial, over-relaxed; if positive the node is full (phi = 1), else p = 0 and phi from the
    same node balance.  p_trial <= 0 exactly when that phi <= 1, so the switch is the complementarity
    condition.  Every ``ep.coarse_every`` sweeps a coarse correction (``coarse_correction``) removes the
    error smooth along the bearing.  The sweeps run on the colour layout (``_colour_sweep``).  Returns
    (sweeps, status): ``EA_CONVERGED`` when in a sweep the RMS change of p was at most ``tol`` of the RMS p and
    the RMS change of phi at most ``tol``; ``EA_DIVERGED`` on a non-finite change (over-relaxation too strong),
    ``EA_NOT_CONVERGED`` after ``max_sweeps``.
    """
    n = ep.n_theta
    nz = ep.n_z
    aw, ae, an, ap, cout, cin = _coefficients(ep, h, hf, k_omega)
    w = ep.sor_omega
    tk = ep.kvc * inv_dt
    if inv_dt == 0.0:
        content = np.zeros((n, nz))  # steady: the time term vanishes (tk = 0); an array keeps one loop
    # per-angle coefficients, padded like the planes (ghost columns 0 and n + 1)
    awp = np.zeros(n + 2)
    aep = np.zeros(n + 2)
    anp = np.zeros(n + 2)
    iap = np.zeros(n + 2)
    cinp = np.zeros(n + 2)
    frp = np.zeros(n + 2)
    cdp = np.zeros(n + 2)
    for i in range(n):
        awp[i + 1] = aw[i]
        aep[i + 1] = ae[i]
        anp[i + 1] = an[i]
        iap[i + 1] = 1.0 / ap[i]
        cinp[i + 1] = cin[i]
        frp[i + 1] = cout[i] + tk * h[i]     # the node's outflow and content when full
        cdp[i + 1] = 1.0 / frp[i + 1]
    rows = (nz + 1) // 2
    shape = (rows + 2, n + 2)
    planes_p = (np.empty(shape), np.empty(shape))
    planes_t = (np.empty(shape), np.empty(shape))
    planes_c = (np.empty(shape), np.empty(shape))
    masks = (np.empty(shape), np.empty(shape))
    odds = (np.zeros(n + 2), np.zeros(n + 2))
    for c in range(2):
        _pack(ep, p, c, planes_p[c])
        _pack(ep, th, c, planes_t[c])
        _pack(ep, content, c, planes_c[c])
        _unknown_mask(ep, c, masks[c])
        for i in range(n):
            odds[c][i + 1] = float((c + i) % 2)
    ce = ep.coarse_every
    tol2 = tol * tol
    n_nodes = float(n * (nz - 2))
    status = EA_NOT_CONVERGED
    sweeps = max_sweeps
    for it in range(max_sweeps):
        if it == SLOW_SWEEPS:
            # a node on the cavity's edge can flip between full and cavitated under over-relaxation and stall
            # the convergence: plain Gauss-Seidel from here on (slower, but it settles)
            w = 1.0
        if ce > 0 and it % ce == ce - 1:
            for c in range(2):
                _unpack(ep, planes_p[c], c, p)
                _unpack(ep, planes_t[c], c, th)
            coarse_correction(ep, aw, ae, an, ap, cin, cout, tk, h, content, p, th)
            for c in range(2):
                _pack(ep, p, c, planes_p[c])
        a1, b1, c1 = _colour_sweep(ep.rule, 0, rows, n, w, tk, awp, aep, anp, iap, cinp, frp, cdp, odds[0], masks[0],
                                   planes_p[0], planes_t[0], planes_c[0], planes_p[1], planes_t[1])
        a2, b2, c2 = _colour_sweep(ep.rule, 1, rows, n, w, tk, awp, aep, anp, iap, cinp, frp, cdp, odds[1], masks[1],
                                   planes_p[1], planes_t[1], planes_c[1], planes_p[0], planes_t[0])
        dp2 = a1 + a2
        dth2 = (b1 + b2) / n_nodes
        p2 = c1 + c2
        if dp2 <= tol2 * p2 and dth2 <= tol2:
            status, sweeps = EA_CONVERGED, it + 1
            break
        if not (dp2 + dth2 + p2 < np.inf):  # a NaN or an overflow: over-relaxation diverged
            status, sweeps = EA_DIVERGED, it + 1
            break
    for c in range(2):
        _unpack(ep, planes_p[c], c, p)
        _unpack(ep, planes_t[c], c, th)
    return sweeps, status


@njit(cache=True)
def ea_force(ep, p):
    """Simpson integral of the field: F = -R sum w_theta w_z p (sin, cos) [N] (``kernels.integrate_field``), the
    negative pressures dropped under Guembel's rule."""
    f1 = 0.0
    f2 = 0.0
    clip = ep.rule == RULE_GUMBEL
    for i in range(ep.n_theta):
        col = 0.0
        for j in range(ep.n_z):
            col += ep.w_z[j] * (max(p[i, j], 0.0) if clip else p[i, j])
        f1 -= ep.a_sin[i] * col
        f2 -= ep.a_cos[i] * col
    return f1, f2


@njit(cache=True)
def fill_content(ep, th, h, out):
    """out = phi H at every node (the film content: the gap's liquid fraction times the dimensionless gap)."""
    for i in range(ep.n_theta):
        hi = h[i]
        for j in range(ep.n_z):
            out[i, j] = th[i, j] * hi


@njit(cache=True)
def reset_fields(ep, p, th):
    """The boundary rows and groove columns: p_supply at z = 0 and in the grooves, p_end at z = L; full
    everywhere there.  The interior is left as it is."""
    nz = ep.n_z
    for i in range(ep.n_theta):
        p[i, 0] = ep.p_supply
        p[i, nz - 1] = ep.p_end
        th[i, 0] = 1.0
        th[i, nz - 1] = 1.0
        if ep.fixed[i]:
            for j in range(nz):
                p[i, j] = ep.p_supply
                th[i, j] = 1.0


@njit(cache=True)
def steady_film(ep, k_omega, x1, x2, p, th):
    """The steady film at X (the journal at rest): fields in place from their warm start; returns the status."""
    content = np.empty((1, 1))  # not read: inv_dt = 0
    h = np.empty(ep.n_theta)
    hf = np.empty(ep.n_theta)
    journal_gap(ep, x1 * ep.inv_c, x2 * ep.inv_c, h, hf)
    sweeps, status = ea_sweeps(ep, k_omega, h, hf, 0.0, content, p, th, ep.tol_steady, ep.max_sweeps)
    return status


@njit(cache=True)
def stage_film(ep, k_omega, x1, x2, v1, v2, dt, tol, th_n, content, p, th):
    """One RK4 stage's film: a backward-Euler step of length dt from the content phi^n H(X - dt V) to X.

    ``tol``: the solve's tolerance (``ea_sweeps``); ``th_n``: the committed content phi^n; ``content``:
    scratch; ``p``, ``th``: warm start in, the stage's fields out.  Returns (F1, F2, sweeps, status)."""
    inv_c = ep.inv_c
    h = np.empty(ep.n_theta)
    hf = np.empty(ep.n_theta)
    journal_gap(ep, (x1 - dt * v1) * inv_c, (x2 - dt * v2) * inv_c, h, hf)
    fill_content(ep, th_n, h, content)
    journal_gap(ep, x1 * inv_c, x2 * inv_c, h, hf)
    sweeps, status = ea_sweeps(ep, k_omega, h, hf, 1.0 / dt, content, p, th, tol, ep.max_sweeps)
    f1, f2 = ea_force(ep, p)
    return f1, f2, sweeps, status


@njit(cache=True)
def commit_film(ep, k_omega, x1_old, x2_old, x1, x2, dt, th_n, content, p, th):
    """The committed step: backward Euler from phi^n H(X_n) to X_{n+1}; ``th`` is phi^{n+1} on return and
    ``content`` holds phi^n H(X_n) (the flow balance's start).  Returns (sweeps, status); nothing to commit (0
    sweeps) under a non-conserving rule, whose content stays full."""
    if ep.rule != RULE_JFO:
        return 0, EA_CONVERGED
    inv_c = ep.inv_c
    h = np.empty(ep.n_theta)
    hf = np.empty(ep.n_theta)
    journal_gap(ep, x1_old * inv_c, x2_old * inv_c, h, hf)
    fill_content(ep, th_n, h, content)
    journal_gap(ep, x1 * inv_c, x2 * inv_c, h, hf)
    sweeps, status = ea_sweeps(ep, k_omega, h, hf, 1.0 / dt, content, p, th, ep.tol_commit, ep.max_sweeps)
    if status == EA_CONVERGED:
        close_content(ep, k_omega, h, hf, 1.0 / dt, content, p, th)
    return sweeps, status


@njit(cache=True, error_model="numpy")
def close_content(ep, k_omega, h, hf, inv_dt, content, p, th):
    """Make every unknown node's flow balance exact for the pressure field ``p``: the content phi^{n+1} of each
    node from its own equation, (cout + K_v c H / dt) phi_i = (pressure flows in) + cin phi_{i-1} + K_v c
    content_i / dt, a recursion along the journal's motion (+theta) from the node after a groove (cyclic where
    the film has none).

    Why: a solve stopped at its tolerance leaves each node a residual of that order, and summed over the film
    they are the step's mass error.  Re-deriving phi from the balance puts the residual into the content
    instead (phi of a full node becomes 1 +- the residual's share, a cavity node's phi is the sweep's own
    formula with the final neighbours), so the film's flow balance closes to round-off whatever the solve's
    tolerance: what the last sweeps of a tight solve bought, at the cost of one pass."""
    n = ep.n_theta
    nz = ep.n_z
    aw, ae, an, ap, cout, cin = _coefficients(ep, h, hf, k_omega)
    tk = ep.kvc * inv_dt
    start = 0
    for i in range(n):
        if ep.fixed[i]:
            start = i
            break
    grooved = ep.fixed[start]
    for j in range(1, nz - 1):
        if grooved:
            for k in range(1, n):
                i = (start + k) % n
                if ep.fixed[i]:
                    continue
                im = i - 1 if i > 0 else n - 1
                ip = i + 1 if i < n - 1 else 0
                src = (aw[i] * p[im, j] + ae[i] * p[ip, j] + an[i] * (p[i, j - 1] + p[i, j + 1]) - ap[i] * p[i, j]
                       + cin[i] * th[im, j] + tk * content[i, j])
                th[i, j] = src / (cout[i] + tk * h[i])
        else:
            # phi_i = a_i + b_i phi_{i-1} around the ring: phi_0 from the product of the b's (each < 1)
            a0 = 0.0
            b0 = 0.0
            prod_a = 0.0
            prod_b = 1.0
            for i in range(n):
                im = i - 1 if i > 0 else n - 1
                ip = i + 1 if i < n - 1 else 0
                den = cout[i] + tk * h[i]
                a = (aw[i] * p[im, j] + ae[i] * p[ip, j] + an[i] * (p[i, j - 1] + p[i, j + 1]) - ap[i] * p[i, j]
                     + tk * content[i, j]) / den
                b = cin[i] / den
                if i == 0:
                    a0 = a
                    b0 = b
                prod_a = a + b * prod_a
                prod_b = b * prod_b
            # phi_{n-1} = prod_a + prod_b phi_{n-1}  (the ring closes on itself)
            last = prod_a / (1.0 - prod_b)
            th[0, j] = a0 + b0 * last
            for i in range(1, n):
                im = i - 1
                ip = i + 1 if i < n - 1 else 0
                src = (aw[i] * p[im, j] + ae[i] * p[ip, j] + an[i] * (p[i, j - 1] + p[i, j + 1]) - ap[i] * p[i, j]
                       + cin[i] * th[im, j] + tk * content[i, j])
                th[i, j] = src / (cout[i] + tk * h[i])


@njit(cache=True)
def film_flows(ep, omega, e1, e2, p, th):
    """(side flow [m^3/s], friction power [W], F1, F2 [N]) of a film at position e = X/c and shaft speed omega.

    Side flow: the pressure flow out through both ends, h^3/(12 mu) dp/dz on the end faces (the scheme's own
    face fluxes).  Friction: the shear on the journal, tau = phi mu omega R / h + (h / 2R) dp/dtheta (the liquid
    fraction phi carries the Couette shear in a cavity: striated film; phi = 1 under the non-conserving rules,
    which assume the film full), times the surface speed omega R over the journal's surface."""
    n = ep.n_theta
    nz = ep.n_z
    c = ep.clearance
    r = ep.radius
    mu = ep.mu
    dth = 1.0 / ep.inv_dtheta
    q = 0.0
    power = 0.0
    for i in range(n):
        h = c * (1.0 - e1 * ep.sin_node[i] - e2 * ep.cos_node[i])
        g = h * h * h / (12.0 * mu) * r * dth / ep.dz
        q += g * ((p[i, 1] - p[i, 0]) + (p[i, nz - 2] - p[i, nz - 1]))
        im = i - 1 if i > 0 else n - 1
        ip = i + 1 if i < n - 1 else 0
        for j in range(nz):
            phi = th[i, j] if ep.rule == RULE_JFO else 1.0
            pj = max(p[i, j], 0.0) if ep.rule == RULE_GUMBEL else p[i, j]
            pe = max(p[ip, j], 0.0) if ep.rule == RULE_GUMBEL else p[ip, j]
            pw = max(p[im, j], 0.0) if ep.rule == RULE_GUMBEL else p[im, j]
            tau = phi * mu * omega * r / h + h / (2.0 * r) * (pe - pw) * 0.5 * ep.inv_dtheta
            power += tau * omega * r * r * dth * ep.w_z[j]
            if pj < -1e300:  # keeps pj used under every rule (numba types it alike)
                power = np.nan
    f1, f2 = ea_force(ep, p)
    return q, power, f1, f2


@njit(cache=True)
def flow_balance(ep, k_omega, h, hf, inv_dt, content, p, th):
    """(change, net inflow, scale) of one committed step, all per unit time in the scaled equation's units:
    change = sum over unknown nodes of K_v c (phi H - content) / dt, net inflow = the pressure and Couette flows
    entering them through the ends and the grooves; scale = the largest flow term seen (the balance's yardstick).
    Summing every node's equation telescopes the inner fluxes away, so change = net inflow up to the nodes'
    residuals: a mass-conserving solution closes it to round-off."""
    n = ep.n_theta
    nz = ep.n_z
    aw, ae, an, ap, cout, cin = _coefficients(ep, h, hf, k_omega)
    tk = ep.kvc * inv_dt
    change = 0.0
    inflow = 0.0
    scale = 0.0
    for i in range(n):
        if ep.fixed[i]:
            continue
        im = i - 1 if i > 0 else n - 1
        ip = i + 1 if i < n - 1 else 0
        for j in range(1, nz - 1):
            d = tk * (th[i, j] * h[i] - content[i, j])
            change += d
            scale = max(scale, abs(d), abs(cout[i] * th[i, j]))
            # flows across the node's faces that come from a boundary row or a groove column
            if j == 1:
                q = an[i] * (p[i, 0] - p[i, 1])
                inflow += q
                scale = max(scale, abs(q))
            if j == nz - 2:
                q = an[i] * (p[i, nz - 1] - p[i, nz - 2])
                inflow += q
                scale = max(scale, abs(q))
            if ep.fixed[im]:
                q = aw[i] * (p[im, j] - p[i, j]) + cin[i] * th[im, j]
                inflow += q
            if ep.fixed[ip]:
                q = ae[i] * (p[ip, j] - p[i, j]) - cout[i] * th[i, j]
                inflow += q
    return change, inflow, scale


# --- the force model ------------------------------------------------------------------------------------------

#: the instantaneous force's film step, in shaft revolutions: small enough that no cavitated node can fill
#: within it (the force of a moving journal with the content frozen at its steady value), large enough that
#: K_v c (H - H(X - dt V)) / dt keeps ~9 digits
QUASI_STATIC_STEP_REV = 1e-4


@njit(cache=True)
def quasi_static_force(sp, x1, x2, v1, v2):
    """The film force at (X, V) with the film content at its steady value at X [N].

    ``sp``: (``EAParams``, K_omega, dt_inst).  The steady film at X (``steady_film``, cold start), then one
    stage of length dt_inst with the velocity V: for V = 0 the steady force itself (the steady film is the
    step's fixed point); otherwise the squeeze response with the cavity held where the steady film has it.
    This is ``forces(X, V)`` and the ``force_kernel`` of ``ElrodAdamsSolver``: equilibria, K and C by
    perturbation with the state at its steady value.  NaN forces if a solve did not converge (the Python
    wrapper raises)."""
    ep, k_omega, dt_inst = sp
    n = ep.n_theta
    nz = ep.n_z
    p = np.zeros((n, nz))
    th = np.ones((n, nz))
    reset_fields(ep, p, th)
    if steady_film(ep, k_omega, x1, x2, p, th) != EA_CONVERGED:
        return np.nan, np.nan
    if v1 == 0.0 and v2 == 0.0:
        return ea_force(ep, p)
    th_n = th.copy()
    content = np.empty((n, nz))
    # converged to the steady tolerance: the squeeze force is a small difference here
    f1, f2, sweeps, status = stage_film(ep, k_omega, x1, x2, v1, v2, dt_inst, ep.tol_steady, th_n, content, p, th)
    if status != EA_CONVERGED:
        return np.nan, np.nan
    return f1, f2


@njit(cache=True)
def quasi_static_force_at_speed(sp, omega, x1, x2, v1, v2):
    """``quasi_static_force`` at shaft speed omega [rad/s] (``sp`` = (EAParams, K_omega_ref, dt_inst, omega_ref))."""
    ep, k_ref, dt_inst, w_ref = sp
    return quasi_static_force((ep, k_ref * (omega / w_ref), dt_inst), x1, x2, v1, v2)


class ElrodAdamsSolver(ReferenceModel):
    """Mass-conserving (JFO) cavitation: the Elrod-Adams p-theta film of a fed journal bearing.

    The same grid, scaling and force integration as ``ReynoldsSolver`` (module doc for the scheme).  As a
    force model of the one interface (``forces``, ``force_kernel``) it gives the film's force with the film
    content at its steady value at X (``quasi_static_force``): equilibria, stiffness and damping by
    perturbation.  ``simulate`` integrates a rotor in the transient film itself, carrying the content from
    step to step (``rotor.film_memory``).

    Parameters
    ----------
    bearing : JournalBearing
        Geometry, lubricant, speed; ``supply_pressure`` [Pa] holds at z = 0 and in the grooves.
    n_theta, n_z : int, default 60, 31
        Circumferential nodes (periodic) and axial nodes (both ends included).
    groove_angle : float or None, default pi
        Angle [rad] of the (first) axial feed groove, measured like theta (from +X2 towards +X1): pi is the
        top of the bearing, opposite a load along gravity.  None: no groove (the film is then fed only
        through z = 0, which needs ``bearing.supply_pressure`` > 0).
    n_grooves : int, default 1
        Grooves equally spaced from ``groove_angle``; ``n_theta`` must be a multiple.
    sor_omega : float, default 1.5
        Over-relaxation of the pressure in (0, 2).  Stronger relaxation makes nodes on the cavity's edge flip
        (a solve that stalls drops to 1 after ``SLOW_SWEEPS`` sweeps).
    tol, tol_commit, tol_steady : float, default 1e-5, 1e-5, 1e-8
        Convergence of a rotor stage's solve, of the committed step's and of the steady solves (equilibria, K
        and C by perturbation, the quasi-static force): the RMS change of p in a sweep relative to the RMS p,
        and the RMS change of the film content.  Whatever ``tol_commit``, the committed step's flow balance
        closes to round-off (``close_content``).  The orbits of the paper's case d move by about 1e-5 c
        between these and (1e-9, 1e-11) (docs/mass_conserving.md).
    max_sweeps : int, default 100000
        Sweeps before a solve is reported as not converged.
    coarse_every : int, default 3
        Sweeps between coarse corrections (``coarse_correction``); 0: none.
    cavitation : {"jfo", "swift-stieber", "gumbel"}, default "jfo"
        The mass-conserving film, or a non-conserving rule on the same grid, feed and solver (the content held
        full; Swift-Stieber by complementarity, Guembel by dropping negative pressures from the force): the
        like-for-like comparison of the rules (``studies.cavitation_rules``).

    Raises
    ------
    ValueError
        A bearing that is not a ``JournalBearing``; a film with no feed (no groove and no supply pressure:
        with the ends at the cavity pressure no liquid enters a cavity, so the film drains); grids or
        settings out of range (each named).

    Examples
    --------
    >>> from fluidfilm import paper_bearing
    >>> from fluidfilm.reynolds.elrod_adams import ElrodAdamsSolver
    >>> film = ElrodAdamsSolver(paper_bearing(), 40, 21)
    >>> film.forces([0.0, 60e-6], [0.0, 0.0]).round(1).tolist()   # eps = 0.5 along +X2, groove on top [N]
    [18.3, -11.6]
    """

    def __init__(self, bearing: JournalBearing, n_theta: int = 60, n_z: int = 31, groove_angle: float | None = math.pi,
                 n_grooves: int = 1, sor_omega: float = 1.5, tol: float = 1e-5, tol_commit: float = 1e-5,
                 tol_steady: float = 1e-8, max_sweeps: int = 100_000, coarse_every: int = 3,
                 cavitation: str = "jfo"):
        if not isinstance(bearing, JournalBearing):
            raise ValueError(f"bearing must be a JournalBearing, got {type(bearing).__name__}")
        if cavitation not in RULES:
            raise ValueError(f"unknown cavitation rule {cavitation!r}; choose one of {tuple(RULES)}")
        self.cavitation = cavitation
        self._bearing = bearing
        self._c = bearing.clearance
        self.mesh = FilmMesh(n_theta, n_z, bearing.length)
        n = self.mesh.n_theta
        if groove_angle is None:
            if bearing.supply_pressure <= 0.0:
                raise ValueError("a mass-conserving film needs a feed: give a groove_angle or a bearing with "
                                 "supply_pressure > 0 (with both ends at the cavity pressure no liquid enters a "
                                 "cavity, and the film drains through its ends)")
            g = 0.0
            fixed = np.zeros(n, dtype=np.bool_)
            self.n_grooves = 0
        else:
            g = float(groove_angle)
            if not math.isfinite(g):
                raise ValueError(f"groove_angle must be a finite angle in rad or None, got {groove_angle!r}")
            ng = n_grooves
            if isinstance(ng, bool) or int(ng) != ng or ng < 1 or n % int(ng):
                raise ValueError(f"n_grooves must be a positive integer dividing n_theta={n}, got {n_grooves!r}")
            ng = int(ng)
            fixed = np.zeros(n, dtype=np.bool_)
            fixed[::n // ng] = True
            self.n_grooves = ng
        self.groove_angle = None if groove_angle is None else g
        if isinstance(coarse_every, bool) or not isinstance(coarse_every, int) or coarse_every < 0:
            raise ValueError(f"coarse_every must be an integer >= 0, got {coarse_every!r}")
        for name, value, lo, hi in (("sor_omega", sor_omega, 0.0, 2.0), ("tol", tol, 0.0, 1.0),
                                    ("tol_commit", tol_commit, 0.0, 1.0), ("tol_steady", tol_steady, 0.0, 1.0)):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not lo < value < hi:
                raise ValueError(f"{name} must be a number in ({lo}, {hi}), got {value!r}")
        if isinstance(max_sweeps, bool) or not isinstance(max_sweeps, int) or max_sweeps < 1:
            raise ValueError(f"max_sweeps must be a positive integer, got {max_sweeps!r}")
        r = bearing.radius
        c = bearing.clearance
        mu = bearing.viscosity
        theta = g + self.mesh.theta           # node 0 on the first groove
        theta_f = theta + 0.5 * self.mesh.dtheta
        dzeta = self.mesh.dz / r
        self.theta_nodes = theta
        self.params = EAParams(
            n_theta=n, n_z=self.mesh.n_z,
            sin_node=np.sin(theta), cos_node=np.cos(theta), sin_face=np.sin(theta_f), cos_face=np.cos(theta_f),
            inv_c=1.0 / c, inv_dtheta=1.0 / self.mesh.dtheta, inv_dtheta2=1.0 / self.mesh.dtheta**2,
            inv_dzeta2=1.0 / dzeta**2,
            k_omega=6.0 * mu * bearing.omega * r**2 / c**2, kvc=12.0 * mu * r**2 / c**2,
            a_sin=r * self.mesh.w_theta * np.sin(theta), a_cos=r * self.mesh.w_theta * np.cos(theta),
            w_z=self.mesh.w_z.copy(), w_cell=self.mesh.dtheta * dzeta,
            p_supply=float(bearing.supply_pressure), p_end=0.0, fixed=fixed,
            sor_omega=float(sor_omega), tol=float(tol), tol_commit=float(tol_commit), tol_steady=float(tol_steady),
            max_sweeps=int(max_sweeps),
            coarse_every=int(coarse_every), mode_shape=np.sin(np.pi * self.mesh.z / bearing.length),
            rule=RULES[cavitation], mu=float(mu), radius=float(r), clearance=float(c), dz=float(self.mesh.dz))
        # a squeeze film (no rotation) takes the step of a 3000 rpm shaft
        self.dt_inst = QUASI_STATIC_STEP_REV * 2.0 * math.pi / (bearing.omega if bearing.omega > 0.0 else 100.0 * math.pi)

    # --- the one interface ---------------------------------------------------------------------------------
    @property
    def name(self) -> str:
        return "ElrodAdamsSolver" if self.cavitation == "jfo" else f"ElrodAdamsSolver[{self.cavitation}]"

    # bearing, clearance, validity (the whole film) and the empty domain report: ``ReferenceModel``

    @property
    def n_theta(self) -> int:
        return self.mesh.n_theta

    @property
    def n_z(self) -> int:
        return self.mesh.n_z

    @property
    def force_kernel(self):
        """``(quasi_static_force, (params, K_omega, dt_inst))``: the force with the content at its steady value."""
        return quasi_static_force, (self.params, self.params.k_omega, self.dt_inst)

    def speed_kernel(self):
        """``(fn, params)`` of the quasi-static force at any shaft speed (``SpeedScalableModel``)."""
        return quasi_static_force_at_speed, (self.params, self.params.k_omega, self.dt_inst,
                                             float(self._bearing.omega))

    def transient_kernels(self):
        """What ``rotor.film_memory`` integrates: ``(stage_film, commit_film, film_flows, params)``."""
        return stage_film, commit_film, film_flows, self.params

    def __repr__(self) -> str:
        g = "no groove" if self.groove_angle is None else f"{self.n_grooves} groove(s) at {self.groove_angle:.4g} rad"
        return f"ElrodAdamsSolver({self.n_theta}x{self.n_z}, {g}, cavitation={self.cavitation!r})"

    def forces(self, X, V) -> np.ndarray:
        """Film force [N] at positions X [m] and velocities V [m/s], (..., 2), the content at its steady value."""
        x, v, shape = as_state_pairs(X, V, self._c)
        out = np.empty_like(x)
        fn, sp = self.force_kernel
        for k in range(x.shape[0]):
            f = fn(sp, x[k, 0], x[k, 1], v[k, 0], v[k, 1])
            if not (math.isfinite(f[0]) and math.isfinite(f[1])):
                raise RuntimeError(f"the Elrod-Adams solve did not converge at X={tuple(x[k])} m, V={tuple(v[k])} "
                                   f"m/s within max_sweeps={self.params.max_sweeps}")
            out[k] = f
        return out.reshape(shape + (2,))

    # --- fields ---------------------------------------------------------------------------------------------
    def steady_field(self, x, omega: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(p [Pa], film content phi) of the steady film at position x [m], each (n_theta, n_z) on
        ``theta_nodes`` x ``mesh.z``; at shaft speed ``omega`` [rad/s] (None: the bearing's)."""
        xa, va, _ = as_state_pairs(x, (0.0, 0.0), self._c)
        k_omega = self.params.k_omega if omega is None else self.params.k_omega * float(omega) / self._bearing.omega
        p = np.zeros((self.n_theta, self.n_z))
        th = np.ones((self.n_theta, self.n_z))
        reset_fields(self.params, p, th)
        if steady_film(self.params, k_omega, xa[0, 0], xa[0, 1], p, th) != EA_CONVERGED:
            raise RuntimeError(f"the steady Elrod-Adams solve did not converge at x={tuple(xa[0])} m")
        return p, th

    def flows(self, x, p, th, omega: float | None = None) -> tuple[float, float]:
        """(side flow [m^3/s], friction power [W]) of a field (p, th) at position x [m] (``film_flows``)."""
        w = self._bearing.omega if omega is None else float(omega)
        q, power, _, _ = film_flows(self.params, w, x[0] / self._c, x[1] / self._c, np.ascontiguousarray(p),
                                    np.ascontiguousarray(th))
        return q, power

    def integrate(self, p) -> np.ndarray:
        """Force [N] of a pressure field on this grid by Simpson integration."""
        return np.array(ea_force(self.params, np.ascontiguousarray(p, dtype=np.float64)))
