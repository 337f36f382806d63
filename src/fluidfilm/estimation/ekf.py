"""The compiled extended Kalman filter and its Rauch-Tung-Striebel smoother (numba).

The augmented state (``N_STATE`` = 9), SI units::

    z = (x1, x2, v1, v2, W1, W2, a, b, s)

journal position [m] and velocity [m/s] in the conventions' frame; the static load W [N] the film carries
(weight plus any constant external force, +X2 along gravity); the imbalance m_u d = sqrt(a^2 + b^2) [kg m]
with phase phi = atan2(b, a) relative to the speed signal's phase reference; the film's effective viscosity
as a ratio s = mu / mu0 to the description's mu0.

Process model (the rotor of ``fluidfilm.rotor.integrate``, paper eq. 4), with F0 the force model's film force
at the description's viscosity and the measured shaft speed omega::

    m dV/dt = s F0(X, V; omega) + W + Re/Im[(omega^2 + i alpha) (a + i b) e^{ip}] (Im times sgn),  dX/dt = V,
    p = the shaft's angle (the speed signal's integral), alpha = d omega/dt (0 at a steady speed: the imbalance's
    tangential push while the speed changes), W, a, b, s: random walks.

``s F0`` is exact for the universal model and the Reynolds solvers without supply pressure: the film
pressure is linear in mu for both cavitation rules (docs/universal.md). The imbalance term is linear in
(a, b), so the imbalance's magnitude and phase enter the filter without a nonlinearity.

Discretisation: between two samples, ``nsub`` RK4 substeps of the mean; the transition matrix of each
substep is the 4th-order Taylor series of expm(A h), A the Jacobian at the substep's start (the force's
derivatives by central differences of the compiled kernel: 8 more force evaluations, any force model).
Measurement: the two probes, runout already subtracted: y = (x1, x2) + noise.

Why compiled, not filterpy: a filterpy EKF step is ~20 numpy calls on 9x9 arrays (tens of microseconds of
Python overhead each sample before a single force) and calls back into Python for the model; the goal is
<= 50 us per sample on one core. Here one sample (2 substeps) is 24 force evaluations plus a few 9x9
products, all in one compiled loop over the record.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

N_STATE = 9
STATE_NAMES = ("x1", "x2", "v1", "v2", "W1", "W2", "a", "b", "s")


@njit(cache=True, inline="always")
def _force(kernel, params, omega, x1, x2, v1, v2, r_max):
    """The film force, with the position held inside ``r_max`` (the kernel's domain) if the estimate strays."""
    r = math.sqrt(x1 * x1 + x2 * x2)
    if r > r_max:
        x1 = x1 * r_max / r
        x2 = x2 * r_max / r
    return kernel(params, omega, x1, x2, v1, v2)


@njit(cache=True, inline="always")
def _deriv(kernel, params, z, omega, alpha, p, inv_m, sgn, r_max, out):
    """dz/dt into ``out`` (the process model of the module docstring) at shaft angle ``p``, speed ``omega`` and
    angular acceleration ``alpha`` (the imbalance's tangential push while the speed changes)."""
    f1, f2 = _force(kernel, params, omega, z[0], z[1], z[2], z[3], r_max)
    w2 = omega * omega
    cp = math.cos(p)
    sp = math.sin(p)
    out[0] = z[2]
    out[1] = z[3]
    out[2] = (z[8] * f1 + z[4] + z[6] * (w2 * cp - alpha * sp) - z[7] * (w2 * sp + alpha * cp)) * inv_m
    out[3] = (z[8] * f2 + z[5] + sgn * (z[6] * (w2 * sp + alpha * cp) + z[7] * (w2 * cp - alpha * sp))) * inv_m
    for i in range(4, N_STATE):
        out[i] = 0.0


@njit(cache=True, inline="always")
def _jacobian(kernel, params, z, omega, alpha, p, inv_m, sgn, r_max, hx, hv, A):
    """A = d(dz/dt)/dz at z (central differences of the force in X and V)."""
    for i in range(N_STATE):
        for j in range(N_STATE):
            A[i, j] = 0.0
    A[0, 2] = 1.0
    A[1, 3] = 1.0
    s = z[8]
    for k in range(4):
        h = hx if k < 2 else hv
        zp0, zp1, zp2, zp3 = z[0], z[1], z[2], z[3]
        zm0, zm1, zm2, zm3 = z[0], z[1], z[2], z[3]
        if k == 0:
            zp0 += h
            zm0 -= h
        elif k == 1:
            zp1 += h
            zm1 -= h
        elif k == 2:
            zp2 += h
            zm2 -= h
        else:
            zp3 += h
            zm3 -= h
        a1, a2 = _force(kernel, params, omega, zp0, zp1, zp2, zp3, r_max)
        b1, b2 = _force(kernel, params, omega, zm0, zm1, zm2, zm3, r_max)
        A[2, k] = s * (a1 - b1) / (2.0 * h) * inv_m
        A[3, k] = s * (a2 - b2) / (2.0 * h) * inv_m
    f1, f2 = _force(kernel, params, omega, z[0], z[1], z[2], z[3], r_max)
    w2 = omega * omega
    cp = math.cos(p)
    sp = math.sin(p)
    A[2, 4] = inv_m
    A[3, 5] = inv_m
    A[2, 6] = (w2 * cp - alpha * sp) * inv_m
    A[2, 7] = -(w2 * sp + alpha * cp) * inv_m
    A[3, 6] = sgn * (w2 * sp + alpha * cp) * inv_m
    A[3, 7] = sgn * (w2 * cp - alpha * sp) * inv_m
    A[2, 8] = f1 * inv_m
    A[3, 8] = f2 * inv_m


@njit(cache=True, inline="always")
def _matmul(A, B, out):
    n = A.shape[0]
    for i in range(n):
        for j in range(n):
            acc = 0.0
            for k in range(n):
                acc += A[i, k] * B[k, j]
            out[i, j] = acc


@njit(cache=True)
def _propagate(kernel, params, z, omega, alpha, p0, T, nsub, inv_m, sgn, r_max, hx, hv, Phi, A, M, T1, T2, k1, k2, k3,
               k4, zt):
    """Advance the mean ``z`` by T (nsub RK4 substeps) and return its transition matrix in ``Phi``."""
    n = N_STATE
    for i in range(n):
        for j in range(n):
            Phi[i, j] = 1.0 if i == j else 0.0
    # substeps: at least nsub, more where the film's fastest rate (the velocity block of A) makes the step stiff
    # (the squeeze damping grows like (1 - eps^2)^-1.5): |lambda| h <= 1 keeps RK4 and the Taylor series accurate
    _jacobian(kernel, params, z, omega, alpha, p0, inv_m, sgn, r_max, hx, hv, A)
    rate = abs(A[2, 2]) + abs(A[3, 3]) + abs(A[2, 3]) + abs(A[3, 2])
    rate = max(rate, math.sqrt(abs(A[2, 0]) + abs(A[3, 1]) + abs(A[2, 1]) + abs(A[3, 0])))
    n_sub = max(nsub, int(math.ceil(rate * T)))
    if n_sub > 64:
        n_sub = 64
    h = T / n_sub
    for sub in range(n_sub):
        p = p0 + omega * sub * h
        if sub > 0:
            _jacobian(kernel, params, z, omega, alpha, p, inv_m, sgn, r_max, hx, hv, A)
        # M = I + Ah + (Ah)^2/2 + (Ah)^3/6 + (Ah)^4/24 (Horner: I + Ah(I + Ah/2(I + Ah/3(I + Ah/4))))
        for i in range(n):
            for j in range(n):
                M[i, j] = (1.0 if i == j else 0.0) + A[i, j] * h / 4.0
        for order in (3.0, 2.0, 1.0):
            _matmul(A, M, T1)
            for i in range(n):
                for j in range(n):
                    M[i, j] = (1.0 if i == j else 0.0) + T1[i, j] * h / order
        _matmul(M, Phi, T2)
        for i in range(n):
            for j in range(n):
                Phi[i, j] = T2[i, j]
        # RK4 of the mean
        _deriv(kernel, params, z, omega, alpha, p, inv_m, sgn, r_max, k1)
        for i in range(n):
            zt[i] = z[i] + 0.5 * h * k1[i]
        _deriv(kernel, params, zt, omega, alpha, p + 0.5 * omega * h, inv_m, sgn, r_max, k2)
        for i in range(n):
            zt[i] = z[i] + 0.5 * h * k2[i]
        _deriv(kernel, params, zt, omega, alpha, p + 0.5 * omega * h, inv_m, sgn, r_max, k3)
        for i in range(n):
            zt[i] = z[i] + h * k3[i]
        _deriv(kernel, params, zt, omega, alpha, p + omega * h, inv_m, sgn, r_max, k4)
        for i in range(n):
            z[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])


@njit(cache=True)
def run_filter(kernel, params, y, omega, alpha, phase, dt, mass, sgn, nsub, z0, P0, q, r_var, r_max, hx, hv,
               out_z, out_P, out_nis, store, Phi_all, Ppred_all, zpred_all, p_inflate, inflate_thr, inflate_tau,
               inflate_cooldown, out_inflated):
    """The EKF over a record: y (N, 2) probe positions [m] (runout removed), omega (N,) [rad/s], alpha (N,)
    [rad/s^2] (the speed's rate of change), phase (N,) [rad] at each sample, sample interval dt [s]; q (9,) process noise densities (per second), r_var the
    probes' noise variance [m^2]. Writes the filtered mean (N, 9), covariance (N, 9, 9) and the normalised
    innovation squared (N,); where ``store``, the transitions, predicted covariances and means for the
    smoother (``run_smoother``).

    Abrupt changes (a load step, a blade loss) are not random walks: where the innovation's exponential
    average (time constant ``inflate_tau`` samples, NIS per degree of freedom) exceeds ``inflate_thr``, the
    parameters' variances grow by ``p_inflate`` (9,), at most once per ``inflate_cooldown`` samples (marked in
    ``out_inflated``), so the filter re-converges in a few revolutions instead of at the random walk's pace.
    Returns the number of samples whose update was skipped (non-finite)."""
    n = N_STATE
    N = y.shape[0]
    inv_m = 1.0 / mass
    z = z0.copy()
    P = P0.copy()
    Phi = np.zeros((n, n))
    A = np.zeros((n, n))
    M = np.zeros((n, n))
    T1 = np.zeros((n, n))
    T2 = np.zeros((n, n))
    k1 = np.zeros(n)
    k2 = np.zeros(n)
    k3 = np.zeros(n)
    k4 = np.zeros(n)
    zt = np.zeros(n)
    K = np.zeros((n, 2))
    skipped = 0
    ema = 1.0
    last = -inflate_cooldown
    for k in range(N):
        out_inflated[k] = False
        if k > 0:
            _propagate(kernel, params, z, omega[k - 1], alpha[k - 1], phase[k - 1], dt, nsub, inv_m, sgn, r_max, hx,
                       hv, Phi, A, M, T1, T2, k1, k2, k3, k4, zt)
            # P = Phi P Phi^T + Q dt
            _matmul(Phi, P, T1)
            for i in range(n):
                for j in range(n):
                    acc = 0.0
                    for col in range(n):
                        acc += T1[i, col] * Phi[j, col]
                    T2[i, j] = acc
            for i in range(n):
                for j in range(n):
                    P[i, j] = 0.5 * (T2[i, j] + T2[j, i])
                P[i, i] += q[i] * dt
        if store:
            for i in range(n):
                zpred_all[k, i] = z[i]
                for j in range(n):
                    Ppred_all[k, i, j] = P[i, j]
                    Phi_all[k, i, j] = Phi[i, j] if k > 0 else (1.0 if i == j else 0.0)
        # update with the two probes
        n1 = y[k, 0] - z[0]
        n2 = y[k, 1] - z[1]
        s11 = P[0, 0] + r_var
        s22 = P[1, 1] + r_var
        s12 = P[0, 1]
        det = s11 * s22 - s12 * s12
        if not (math.isfinite(n1) and math.isfinite(n2)) or det <= 0.0:
            skipped += 1
            out_nis[k] = np.nan
        else:
            i11 = s22 / det
            i22 = s11 / det
            i12 = -s12 / det
            out_nis[k] = n1 * (i11 * n1 + i12 * n2) + n2 * (i12 * n1 + i22 * n2)
            ema += (0.5 * out_nis[k] - ema) / inflate_tau
            if inflate_thr > 0.0 and ema > inflate_thr and k - last >= inflate_cooldown:
                for i in range(n):
                    P[i, i] += p_inflate[i]
                    if store:   # the smoother sees the inflation as this step's process noise
                        Ppred_all[k, i, i] += p_inflate[i]
                last = k
                out_inflated[k] = True
                # the update below uses the inflated covariance
                s11 = P[0, 0] + r_var
                s22 = P[1, 1] + r_var
                s12 = P[0, 1]
                det = s11 * s22 - s12 * s12
                i11 = s22 / det
                i22 = s11 / det
                i12 = -s12 / det
            for i in range(n):
                K[i, 0] = P[i, 0] * i11 + P[i, 1] * i12
                K[i, 1] = P[i, 0] * i12 + P[i, 1] * i22
            for i in range(n):
                z[i] += K[i, 0] * n1 + K[i, 1] * n2
            # P = P - K H P  (H P = the first two rows of P), kept symmetric
            for i in range(n):
                for j in range(n):
                    T1[i, j] = P[i, j] - (K[i, 0] * P[0, j] + K[i, 1] * P[1, j])
            for i in range(n):
                for j in range(n):
                    P[i, j] = 0.5 * (T1[i, j] + T1[j, i])
        for i in range(n):
            out_z[k, i] = z[i]
            for j in range(n):
                out_P[k, i, j] = P[i, j]
    return skipped


@njit(cache=True)
def run_smoother(out_z, out_P, Phi_all, Ppred_all, zpred_all, zs, Ps):
    """Rauch-Tung-Striebel: the smoothed means (N, 9) and covariances (N, 9, 9) of the whole window from the
    filter's stored pass (``run_filter(..., store=True)``)."""
    N = out_z.shape[0]
    zs[N - 1] = out_z[N - 1]
    Ps[N - 1] = out_P[N - 1]
    for k in range(N - 2, -1, -1):
        # G = P_k Phi_{k+1}^T Ppred_{k+1}^{-1}
        Pp = Ppred_all[k + 1]
        PPt = out_P[k] @ Phi_all[k + 1].T
        G = np.linalg.solve(Pp.T, PPt.T).T
        zs[k] = out_z[k] + G @ (zs[k + 1] - zpred_all[k + 1])
        D = Ps[k + 1] - Pp
        Pk = out_P[k] + G @ D @ G.T
        Ps[k] = 0.5 * (Pk + Pk.T)
