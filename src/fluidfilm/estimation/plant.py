"""Synthetic plant data the estimator never sees the inside of: the rotor in the *reference* solver, probes.

``simulate_plant(model, scenario)`` integrates the rotor (paper eq. 4) in any force model with a speed kernel
(the pipeline passes ``ReynoldsSolver`` on a converged grid, not the surrogate), with the load, imbalance and
viscosity following the scenario's piecewise-linear schedules; the viscosity enters as F = (mu/mu0) F(mu0),
exact for a plain film without supply pressure. ``probe_signals`` turns the true orbit into what two proximity
probes and a speed pickup record: sampled at ``fs``, mechanical/electrical runout (a once-per-rev pattern with
a 2x harmonic), white noise, quantisation to the digitiser's step.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from numba import njit

#: schedule columns: static load W1, W2 [N], imbalance a, b [kg m] (m_u d (cos phi, sin phi)), viscosity ratio s
SCHEDULE_COLUMNS = ("W1", "W2", "a", "b", "s")


@dataclass(frozen=True)
class Scenario:
    """One synthetic plant record.

    ``times`` (K,) [s] and ``values`` (K, 5) [W1, W2, a, b, s]: the true parameters, linear between the knots
    and held outside; ``speed_rpm`` the shaft speed, or ``speed_knots`` ((t, rpm), ...) a profile linear between
    its knots and held outside (a run-up, a coast-down; the imbalance then also pushes tangentially with the
    shaft's angular acceleration); ``mass`` the rotor mass per bearing [kg];
    ``t_end`` [s] of record after ``t_warm`` [s] of settling (not recorded); probe settings: ``fs`` [Hz],
    ``noise`` [m] (standard deviation), ``lsb`` [m] (quantisation step), ``runout`` [m] per axis as
    ((c1, s1), (c2, s2)) harmonics of the shaft angle; ``runout_known_error``: the fraction of the runout the
    slow-roll vector handed to the estimator misses (the rest it subtracts); ``force_2x`` [N]: a twice-per-rev
    force (a misaligned coupling, a cracked shaft) in the plant alone: a model mismatch.
    """

    name: str
    times: tuple
    values: tuple
    speed_rpm: float
    mass: float
    t_end: float = 0.5
    t_warm: float = 0.05
    fs: float = 10000.0
    noise: float = 1.0e-6
    lsb: float = 0.1e-6
    runout: tuple = (((3.0e-6, 1.0e-6), (0.5e-6, 0.0)), ((1.0e-6, -2.0e-6), (0.0, 0.5e-6)))
    runout_known_error: float = 0.05
    sgn: int = 1
    force_2x: float = 0.0                         # N, a twice-per-rev force the estimator's model lacks
    speed_knots: tuple = ()                       # ((t [s], rpm), ...): a speed profile, linear between; () steady
    bearing: dict = field(default_factory=dict)   # overrides of the description's bearing (the plant's own)
    description: str = ""

    def truth(self, t) -> np.ndarray:
        """(len(t), 5): the true W1, W2, a, b, s at times t [s]."""
        tt = np.asarray(self.times, dtype=float)
        vv = np.asarray(self.values, dtype=float)
        return np.stack([np.interp(t, tt, vv[:, j]) for j in range(vv.shape[1])], axis=-1)


def speed_table(speed) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The shaft's speed as the compiled loops read it: knot times [s] (the first at 0), the angular speed at
    each [rad/s] and the shaft angle there [rad] (0 at t = 0). ``speed``: a steady speed [rpm], or knots
    ((t, rpm), ...) linear between and held outside.

    >>> st, sw, sp = speed_table(((0.0, 6000.0), (0.1, 3000.0)))
    >>> round(float(sp[-1]), 6) == round(0.1 * (6000.0 + 3000.0) / 2 * 2 * math.pi / 60.0, 6)
    True
    """
    if np.ndim(speed) == 0:
        w = float(speed) * 2.0 * math.pi / 60.0
        return np.array([0.0, 1.0]), np.array([w, w]), np.array([0.0, w])
    k = np.asarray(speed, dtype=float)
    if k.ndim != 2 or k.shape[1] != 2 or k.shape[0] < 1 or np.any(np.diff(k[:, 0]) <= 0) or k[0, 0] < 0.0:
        raise ValueError(f"speed knots {speed!r}: rows (t [s], rpm) at increasing times from t >= 0 expected")
    if np.any(k[:, 1] <= 0.0) or not np.all(np.isfinite(k)):
        raise ValueError(f"speed knots {speed!r}: positive, finite speeds [rpm] expected")
    if k[0, 0] > 0.0:
        k = np.vstack([[0.0, k[0, 1]], k])
    if k.shape[0] == 1:
        k = np.vstack([k, [k[0, 0] + 1.0, k[0, 1]]])
    st = k[:, 0].copy()
    sw = k[:, 1] * 2.0 * math.pi / 60.0
    sp = np.concatenate([[0.0], np.cumsum(0.5 * (sw[1:] + sw[:-1]) * np.diff(st))])
    return st, sw, sp


def shaft_speed(speed, t) -> tuple[np.ndarray, np.ndarray]:
    """The angular speed [rad/s] and the shaft angle [rad] at times ``t`` [s] (``speed`` as ``speed_table``)."""
    st, sw, sp = speed_table(speed)
    t = np.asarray(t, dtype=float)
    w = np.empty(t.size)
    p = np.empty(t.size)
    for i, ti in enumerate(t.ravel()):
        w[i], _, p[i] = _speed(ti, st, sw, sp)
    return w.reshape(t.shape), p.reshape(t.shape)


@njit(cache=True, inline="always")
def _speed(t, st, sw, sp):
    """(omega, d omega/dt, shaft angle) at t: omega linear between the knots (st, sw), held outside; sp the angle
    at each knot."""
    n = st.size
    if t <= st[0]:
        return sw[0], 0.0, sp[0] + sw[0] * (t - st[0])
    if t >= st[n - 1]:
        return sw[n - 1], 0.0, sp[n - 1] + sw[n - 1] * (t - st[n - 1])
    k = np.searchsorted(st, t) - 1
    alpha = (sw[k + 1] - sw[k]) / (st[k + 1] - st[k])
    d = t - st[k]
    return sw[k] + alpha * d, alpha, sp[k] + sw[k] * d + 0.5 * alpha * d * d


@njit(cache=True, inline="always")
def _acc(kernel, params, st, sw, sp, inv_m, sgn, f2x, kt, kv, t, x1, x2, v1, v2):
    W1 = np.interp(t, kt, kv[:, 0])
    W2 = np.interp(t, kt, kv[:, 1])
    ua = np.interp(t, kt, kv[:, 2])
    ub = np.interp(t, kt, kv[:, 3])
    s = np.interp(t, kt, kv[:, 4])
    omega, alpha, p = _speed(t, st, sw, sp)
    f1, f2 = kernel(params, omega, x1, x2, v1, v2)
    w2 = omega * omega
    cp = math.cos(p)
    sn = math.sin(p)
    c2p = math.cos(2.0 * p)
    s2p = math.sin(2.0 * p)
    # the imbalance (ua + i ub) e^{ip} pushes with (omega^2 + i alpha): centrifugal and, while the speed changes,
    # tangential
    return ((s * f1 + W1 + ua * (w2 * cp - alpha * sn) - ub * (w2 * sn + alpha * cp) + f2x * c2p) * inv_m,
            (s * f2 + W2 + sgn * (ua * (w2 * sn + alpha * cp) + ub * (w2 * cp - alpha * sn)) + f2x * s2p) * inv_m)


@njit(cache=True)
def _plant_loop(kernel, params, st, sw, sp, mass, sgn, f2x, dt, n_steps, record_every, t0, x0, v0, kt, kv, clear2, out):
    """RK4 at fixed dt from t0; ``out`` rows: x1, x2, v1, v2 at t0 and every ``record_every`` steps after.
    Returns the rows written (fewer where the journal reached the sleeve: the run stops there)."""
    x1, x2, v1, v2 = x0[0], x0[1], v0[0], v0[1]
    inv_m = 1.0 / mass
    out[0, 0], out[0, 1], out[0, 2], out[0, 3] = x1, x2, v1, v2
    n = 1
    for step in range(n_steps):
        t = t0 + step * dt
        h = dt
        a1, a2 = _acc(kernel, params, st, sw, sp, inv_m, sgn, f2x, kt, kv, t, x1, x2, v1, v2)
        b1, b2 = _acc(kernel, params, st, sw, sp, inv_m, sgn, f2x, kt, kv, t + 0.5 * h, x1 + 0.5 * h * v1, x2 + 0.5 * h * v2,
                      v1 + 0.5 * h * a1, v2 + 0.5 * h * a2)
        kx1 = v1 + 0.5 * h * a1
        kx2 = v2 + 0.5 * h * a2
        c1, c2 = _acc(kernel, params, st, sw, sp, inv_m, sgn, f2x, kt, kv, t + 0.5 * h, x1 + 0.5 * h * kx1, x2 + 0.5 * h * kx2,
                      v1 + 0.5 * h * b1, v2 + 0.5 * h * b2)
        lx1 = v1 + 0.5 * h * b1
        lx2 = v2 + 0.5 * h * b2
        d1, d2 = _acc(kernel, params, st, sw, sp, inv_m, sgn, f2x, kt, kv, t + h, x1 + h * lx1, x2 + h * lx2,
                      v1 + h * c1, v2 + h * c2)
        mx1 = v1 + h * c1
        mx2 = v2 + h * c2
        x1 += h / 6.0 * (v1 + 2.0 * kx1 + 2.0 * lx1 + mx1)
        x2 += h / 6.0 * (v2 + 2.0 * kx2 + 2.0 * lx2 + mx2)
        v1 += h / 6.0 * (a1 + 2.0 * b1 + 2.0 * c1 + d1)
        v2 += h / 6.0 * (a2 + 2.0 * b2 + 2.0 * c2 + d2)
        if not (math.isfinite(x1) and math.isfinite(x2)) or x1 * x1 + x2 * x2 >= clear2:
            break
        if (step + 1) % record_every == 0:
            out[n, 0], out[n, 1], out[n, 2], out[n, 3] = x1, x2, v1, v2
            n += 1
    return n


@dataclass
class PlantRecord:
    """A synthetic record: ``frame`` what the probes and the speed pickup recorded (the probe-file columns
    ``time, x, y, speed``: s, m, m, rpm), ``truth`` (N, 5) the true W1, W2, a, b, s at each sample, ``x_true``
    (N, 4) the journal's true state, ``runout_supplied``: the slow-roll runout vector handed to the estimator
    (the part of the true runout it knows), and the plant's wall time [s]."""

    scenario: Scenario
    frame: pd.DataFrame
    truth: np.ndarray
    x_true: np.ndarray
    runout_supplied: tuple
    wall_s: float
    stopped_early: bool


def runout_signal(runout, phase) -> np.ndarray:
    """(len(phase), 2) [m]: sum over orders k = 1, 2, ... of c_k cos(k p) + s_k sin(k p), per axis."""
    phase = np.asarray(phase, dtype=float)
    out = np.zeros((phase.size, 2))
    for axis in range(2):
        for k, (c, s) in enumerate(runout[axis], start=1):
            out[:, axis] += c * np.cos(k * phase) + s * np.sin(k * phase)
    return out


def simulate_plant(model, scenario: Scenario, dt: float = 5e-6, seed: int = 0) -> PlantRecord:
    """The scenario's rotor in ``model`` (a force model with a speed kernel; the pipeline's reference solver),
    recorded through the probes. Starts at the static equilibrium of the first knot's load and viscosity,
    settles for ``t_warm`` (not recorded), then records ``t_end`` s at ``fs``. ``seed`` draws the probes' noise
    alone: ``probe_record(plant_orbit(...), seed)`` with other seeds records the same orbit again."""
    return probe_record(plant_orbit(model, scenario, dt), seed)


@dataclass
class PlantOrbit:
    """The plant's true motion at the probes' samples: ``t`` (N,) [s], ``x_true`` (N, 4) the journal's state,
    the plant's wall time [s] and whether the journal reached the sleeve before ``t_end``."""

    scenario: Scenario
    t: np.ndarray
    x_true: np.ndarray
    wall_s: float
    stopped_early: bool


def plant_orbit(model, scenario: Scenario, dt: float = 5e-6) -> PlantOrbit:
    """The plant's physics (no noise): the rotor in ``model`` under the scenario's schedules, sampled at ``fs``."""
    import time

    from fluidfilm.characteristics.static import equilibrium

    sk = model.speed_kernel()
    if sk is None:
        raise ValueError(f"{model.name}: the plant needs a force model with a speed kernel")
    kernel, params = sk
    st, sw, sp = speed_table(scenario.speed_knots or scenario.speed_rpm)
    omega = float(sw[0])
    omega_ref = model.bearing.speed_rpm * 2.0 * math.pi / 60.0
    vals = np.asarray(scenario.values, dtype=float)
    w0 = vals[0, :2] / vals[0, 4] * (omega_ref / omega)   # the load the model at its own speed and mu0 sees
    eq = equilibrium(model, tuple(w0))
    x0 = np.array([eq["X1"], eq["X2"]])
    record_every = int(round(1.0 / (scenario.fs * dt)))
    if abs(record_every * dt * scenario.fs - 1.0) > 1e-9:
        raise ValueError(f"fs = {scenario.fs} Hz is not a whole number of plant steps of {dt} s")
    t0 = -scenario.t_warm
    n_steps = int(round((scenario.t_end + scenario.t_warm) / dt))
    kt = np.asarray(scenario.times, dtype=float)
    out = np.zeros((n_steps // record_every + 1, 4))
    tic = time.perf_counter()
    n = _plant_loop(kernel, params, st, sw, sp, scenario.mass, float(scenario.sgn), float(scenario.force_2x), dt, n_steps, record_every, t0, x0,
                    np.zeros(2), kt, vals, model.clearance ** 2, out)
    wall = time.perf_counter() - tic
    t_all = t0 + np.arange(n) * record_every * dt
    keep = t_all >= -1e-12
    t = t_all[keep]
    return PlantOrbit(scenario, t, out[:n][keep], wall,
                      stopped_early=bool(t[-1] < scenario.t_end - 2.0 / scenario.fs) if t.size else True)


def probe_record(orbit: PlantOrbit, seed: int = 0) -> PlantRecord:
    """What the probes and the speed pickup record of ``orbit``: runout, noise drawn from ``seed``, quantisation."""
    scenario, t, xs = orbit.scenario, orbit.t, orbit.x_true
    rng = np.random.default_rng(seed)
    w, phase = shaft_speed(scenario.speed_knots or scenario.speed_rpm, t)
    ro = runout_signal(scenario.runout, phase)
    meas = xs[:, :2] + ro + rng.normal(0.0, scenario.noise, size=(t.size, 2))
    if scenario.lsb > 0.0:
        meas = np.round(meas / scenario.lsb) * scenario.lsb
    frame = pd.DataFrame({"time": t, "x": meas[:, 0], "y": meas[:, 1],
                          "speed": w * 60.0 / (2.0 * math.pi)})
    known = tuple(tuple((c * (1.0 - scenario.runout_known_error), s * (1.0 - scenario.runout_known_error))
                        for c, s in axis) for axis in scenario.runout)
    return PlantRecord(scenario, frame, scenario.truth(t), xs, known, orbit.wall_s, orbit.stopped_early)
