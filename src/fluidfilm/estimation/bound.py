"""What a probe record can resolve at best: the Cramér-Rao bound of load, imbalance and viscosity.

``information_bound(model, scenario, x0, v0, ...)`` answers "is a goal missed by the estimator or by the
record?". It is a second method, independent of the filter: the Fisher information of the constant parameters

    theta = (x1, x2, v1, v2 at t = 0;  W1, W2, a, b, s;  the slow-roll vector's errors, 1x and 2x per axis)

from the probes' samples y_k = X(t_k; theta) + runout error(p_k) + noise, with the sensitivities dX/dtheta by
central differences of the rotor integrated in the estimator's own force model (``plant._plant_loop``, RK4),
the noise variance sigma^2 + lsb^2/12 per probe and a Gaussian prior on each slow-roll coefficient's error
(what the benchmark hands the estimator). Its inverse over the samples up to t bounds the covariance of any
unbiased estimator that uses the record up to t, even one that knows the parameters are constant and the force
model is exact: the filter, which lets them drift, can only do worse.

The confounding it measures (docs/online_assessment.md, "Observability"): with the rotor's mass m -> 0 the
equation of motion divided by s holds W/s and u/s alone, and the information on s vanishes; the known mass is
what resolves it.
"""
from __future__ import annotations

import math

import numpy as np

#: the parameters of the bound, in order (``runout`` errors: axis x/y, order 1/2, cos/sin)
PARAMETERS = ("x1", "x2", "v1", "v2", "W1", "W2", "a", "b", "s",
              "rx1c", "rx1s", "rx2c", "rx2s", "ry1c", "ry1s", "ry2c", "ry2s")


def _trajectory(kernel, params, table, mass, sgn, dt, n_steps, every, x0, v0, theta_p, clear2):
    from fluidfilm.estimation.plant import _plant_loop

    kv = np.vstack([theta_p, theta_p]).astype(float)
    out = np.zeros((n_steps // every + 1, 4))
    n = _plant_loop(kernel, params, *table, mass, float(sgn), 0.0, dt, n_steps, every, 0.0,
                    np.asarray(x0, float), np.asarray(v0, float), np.array([0.0, 1.0e9]), kv, clear2, out)
    if n < out.shape[0]:
        raise ValueError("the bound's rotor reached the sleeve: the scenario is outside the force model")
    return out[:, :2]


def sensitivities(kernel, params, clearance: float, speed_rpm, mass: float, theta, n_samples: int,
                  fs: float, sgn: int = 1, substeps: int = 5, runout: bool = True):
    """The probes' noise-free signal (n_samples, 2) at ``theta`` = (x1, x2, v1, v2, W1, W2, a, b, s[, runout
    errors]) and its derivatives (n_samples, 2, 9 or 17) by central differences of the rotor (RK4, ``substeps``
    per sample) in the speed kernel's force model; the runout errors' columns are cos and sin of the shaft angle's
    1x and 2x per axis (the signal includes their values). ``speed_rpm``: a steady speed or knots ((t, rpm), ...)
    (``plant.speed_table``)."""
    from fluidfilm.estimation.plant import shaft_speed, speed_table

    table = speed_table(speed_rpm)
    omega = float(np.max(table[1]))
    c = clearance
    th = np.asarray(theta, dtype=float)
    dt = 1.0 / fs / substeps
    n_steps = (n_samples - 1) * substeps
    W = max(math.hypot(th[4], th[5]), 1e-12)
    u = max(math.hypot(th[6], th[7]), 1e-12)
    # central-difference steps: a small fraction of each parameter's scale (the response is near linear in them)
    steps = np.array([1e-4 * c, 1e-4 * c, 1e-4 * c * omega, 1e-4 * c * omega, 1e-4 * W, 1e-4 * W, 1e-4 * u,
                      1e-4 * u, 1e-4])
    clear2 = (0.999 * c) ** 2

    def traj(t9):
        return _trajectory(kernel, params, table, mass, sgn, dt, n_steps, substeps, t9[:2], t9[2:4], t9[4:9], clear2)

    n_par = 17 if runout else 9
    S = np.zeros((n_samples, 2, n_par))
    y = traj(th[:9])
    for j in range(9):
        hi, lo = th[:9].copy(), th[:9].copy()
        hi[j] += steps[j]
        lo[j] -= steps[j]
        S[:, :, j] = (traj(hi) - traj(lo)) / (2.0 * steps[j])
    if runout:
        _, phase = shaft_speed(speed_rpm, np.arange(n_samples) / fs)
        for axis in range(2):
            for order in (1, 2):
                col = 9 + 4 * axis + 2 * (order - 1)
                S[:, axis, col] = np.cos(order * phase)
                S[:, axis, col + 1] = np.sin(order * phase)
        if th.size == 17:
            y = y + np.einsum("kai,i->ka", S[:, :, 9:], th[9:])
    return y, S


def information_bound(model, speed_rpm, mass: float, values, x0, v0, t_end: float, fs: float,
                      noise: float, lsb: float = 0.0, slow_roll_error: float = 0.0, sgn: int = 1,
                      substeps: int = 5, times=None) -> dict:
    """The Cramér-Rao bound of the relative load, imbalance and viscosity errors from ``t_end`` s of probes.

    Parameters
    ----------
    model : a force model with a speed kernel (the estimator's: the universal surrogate at mu0).
    speed_rpm, mass : the shaft speed [rpm], steady or knots ((t [s], rpm), ...) linear between
        (``plant.speed_table``), and the rotor mass per bearing [kg].
    values : (W1, W2, a, b, s), the true constant parameters ([N], [N], [kg m], [kg m], mu/mu0).
    x0, v0 : the journal's true position [m] and velocity [m/s] at the record's first sample.
    t_end, fs : the record's length [s] and the probes' sampling [Hz].
    noise, lsb : the probes' noise standard deviation and the digitiser's step [m].
    slow_roll_error : the standard deviation [m] of each coefficient of the slow-roll runout vector handed to
        the estimator (0: exact runout, those parameters left out).
    substeps : RK4 steps per sample of the sensitivities' integration.
    times : where to report the bound [s] (default: every sample).

    Returns
    -------
    dict with ``t`` (the report times), ``load_rel``, ``imbalance_rel``, ``viscosity_rel`` (one standard
    deviation of |W|/|W|, |u|/|u| and s/s at each time) and ``rms_over`` (a function of a window start giving the
    root mean square of each over the window to ``t_end``).

    Examples
    --------
    With exact runout the bound is proportional to the probes' noise (the information is 1/sigma^2):

    >>> from fluidfilm import JournalBearing, universal_bearing
    >>> from fluidfilm.characteristics.static import equilibrium
    >>> b = JournalBearing(length=0.03, diameter=0.06, clearance=80e-6, speed_rpm=6000.0, viscosity=0.02)
    >>> m = universal_bearing(b)
    >>> eq = equilibrium(m, (0.0, 490.5))
    >>> kw = dict(values=(0.0, 490.5, 1e-3, 0.0, 1.0), x0=(eq["X1"], eq["X2"]), v0=(0.0, 0.0), t_end=0.1, fs=5000.0)
    >>> one = information_bound(m, 6000.0, 50.0, noise=1e-6, **kw)["viscosity_rel"][-1]
    >>> two = information_bound(m, 6000.0, 50.0, noise=2e-6, **kw)["viscosity_rel"][-1]
    >>> round(float(two / one), 6)
    2.0
    """
    sk = model.speed_kernel()
    if sk is None:
        raise ValueError(f"{model.name}: the bound needs a force model with a speed kernel")
    kernel, params = sk
    checks = [("t_end", t_end), ("fs", fs), ("noise", noise), ("mass", mass)]
    if np.ndim(speed_rpm) == 0:
        checks.append(("speed_rpm", speed_rpm))
    for name, v in checks:
        if not (math.isfinite(v) and v > 0.0):
            raise ValueError(f"information_bound: {name} = {v!r}; a positive number is needed")
    if not (math.isfinite(slow_roll_error) and slow_roll_error >= 0.0):
        raise ValueError(f"information_bound: slow_roll_error = {slow_roll_error!r}; >= 0 is needed")
    p = np.asarray(values, dtype=float)
    if p.shape != (5,):
        raise ValueError(f"information_bound: values = {values!r}; (W1, W2, a, b, s) expected")
    W, u = math.hypot(p[0], p[1]), math.hypot(p[2], p[3])
    if W <= 0.0 or u <= 0.0 or p[4] <= 0.0:
        raise ValueError(f"information_bound: values = {values!r}; a load, an imbalance and s > 0 are needed")
    n_samples = int(round(t_end * fs)) + 1
    theta = np.concatenate([np.asarray(x0, float), np.asarray(v0, float), p])
    _, S = sensitivities(kernel, params, model.clearance, speed_rpm, mass, theta, n_samples, fs, sgn, substeps,
                         runout=slow_roll_error > 0.0)
    n_par = S.shape[2]
    r_var = noise ** 2 + lsb ** 2 / 12.0
    # the information up to each sample: the cumulative sum of S_k^T S_k / r_var, plus the runout prior
    info = np.cumsum(np.einsum("kai,kaj->kij", S, S), axis=0) / r_var
    prior = np.zeros(n_par)
    if slow_roll_error > 0.0:
        prior[9:] = 1.0 / slow_roll_error ** 2
    t = np.arange(n_samples) / fs
    keep = np.arange(n_samples) if times is None else np.searchsorted(t, np.asarray(times, float) - 0.5 / fs)
    keep = np.clip(keep, n_par, n_samples - 1)
    gW = np.zeros(n_par)
    gW[4:6] = p[:2] / W ** 2          # d(|W|/|W|)/d(W1, W2): the load's relative error
    gu = np.zeros(n_par)
    gu[6:8] = p[2:4] / u ** 2
    out: dict[str, list[float]] = {"load_rel": [], "imbalance_rel": [], "viscosity_rel": []}
    scale = np.sqrt(np.maximum(np.diagonal(info[-1]), 1e-300)) + np.sqrt(prior)   # conditioning of the inverse
    for k in keep:
        J = (info[k] + np.diag(prior)) / np.outer(scale, scale)
        C = np.linalg.pinv(J, rcond=1e-14, hermitian=True) / np.outer(scale, scale)
        out["load_rel"].append(math.sqrt(max(float(gW @ C @ gW), 0.0)))
        out["imbalance_rel"].append(math.sqrt(max(float(gu @ C @ gu), 0.0)))
        out["viscosity_rel"].append(math.sqrt(max(C[8, 8], 0.0)) / p[4])
    res: dict = {"t": t[keep]}
    res.update({k: np.asarray(v) for k, v in out.items()})

    def rms_over(t0: float) -> dict:
        win = res["t"] >= t0 - 0.5 / fs
        return {k: float(np.sqrt(np.mean(res[k][win] ** 2))) for k in out}

    res["rms_over"] = rms_over
    return res


def batch_fit(t, y, model, speed_rpm, mass: float, theta0, noise: float, lsb: float = 0.0,
              slow_roll_error: float = 0.0, sgn: int = 1, substeps: int = 3, iterations: int = 8) -> dict:
    """The offline batch counterpart that attains the bound: a maximum a posteriori fit of constant parameters.

    Gauss-Newton on the probes' residual over the whole record (``t`` (N,) [s] at a steady sampling, ``y`` (N, 2)
    [m] with the supplied slow-roll runout already removed), with the slow-roll vector's error as 8 parameters
    under a Gaussian prior of ``slow_roll_error`` [m] (left out where 0); ``theta0`` = (x1, x2, v1, v2, W1, W2, a,
    b, s) the start (the filter's estimate); ``speed_rpm`` steady or knots ((t, rpm), ...). Assumes what the bound
    assumes: the parameters constant over the record. Returns ``theta`` (the fit), ``cov`` (its covariance: the bound at the fit),
    ``iterations`` and the residual's RMS per probe [m].
    """
    sk = model.speed_kernel()
    if sk is None:
        raise ValueError(f"{model.name}: the batch fit needs a force model with a speed kernel")
    kernel, params = sk
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    if y.shape != (t.size, 2) or t.size < 20:
        raise ValueError(f"batch_fit: y of shape {y.shape} for {t.size} times; (N, 2) with N >= 20 expected")
    dts = np.diff(t)
    fs = 1.0 / float(np.median(dts))
    if np.ptp(dts) > 1e-6 / fs:
        raise ValueError("batch_fit: the samples are not evenly spaced")
    runout = slow_roll_error > 0.0
    n_par = 17 if runout else 9
    theta = np.zeros(n_par)
    theta[:9] = np.asarray(theta0, dtype=float)
    prior = np.zeros(n_par)
    if runout:
        prior[9:] = 1.0 / slow_roll_error ** 2
    r_var = noise ** 2 + lsb ** 2 / 12.0
    done = 0
    for it in range(iterations):
        yhat, S = sensitivities(kernel, params, model.clearance, speed_rpm, mass, theta, t.size, fs, sgn, substeps,
                                runout=runout)
        r = (y - yhat).reshape(-1)
        Sf = S.reshape(-1, n_par)
        J = Sf.T @ Sf / r_var + np.diag(prior)
        g = Sf.T @ r / r_var - prior * theta
        scale = np.sqrt(np.maximum(np.diagonal(J), 1e-300))
        step = np.linalg.solve(J / np.outer(scale, scale), g / scale) / scale
        theta = theta + step
        done = it + 1
        # converged: the step is a small fraction of the parameters' own uncertainty (1 / scale is about their
        # standard deviation where the information is not confounded)
        if np.all(np.abs(step) * scale < 1e-2):
            break
    yhat, S = sensitivities(kernel, params, model.clearance, speed_rpm, mass, theta, t.size, fs, sgn, substeps,
                            runout=runout)
    Sf = S.reshape(-1, n_par)
    J = Sf.T @ Sf / r_var + np.diag(prior)
    scale = np.sqrt(np.maximum(np.diagonal(J), 1e-300))
    cov = np.linalg.inv(J / np.outer(scale, scale)) / np.outer(scale, scale)
    res = y - yhat
    return {"theta": theta, "cov": cov, "iterations": done,
            "residual_rms": np.sqrt(np.mean(res ** 2, axis=0))}
