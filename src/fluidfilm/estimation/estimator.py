"""``estimate``: the on-line estimator over a probe record, and its offline (smoothed) review.

Runs the compiled EKF (``estimation.ekf``) over the record: removes the supplied slow-roll runout, integrates
the speed signal for the shaft angle, starts from the centreline baseline (position, load at the description's
viscosity, no imbalance) with wide uncertainty, and returns the estimates with their 2-sigma bands and the two
flags:

- **model mismatch** (innovation test): the normalised innovation squared (NIS) averaged over a sliding window
  of ``nis_window_s``; for a consistent filter its window mean times 2n is chi-square with 2n degrees of
  freedom (n samples); the flag fires where it exceeds ``nis_threshold`` (a multiple of the expected 1.0 that
  leaves room for a consistent filter's correlated windows) after ``flag_after_s`` of convergence;
- **out of domain**: the estimated state outside the force model's ``validity`` (the universal model:
  eccentricity above 0.95), or the speed outside the range the description allows.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from fluidfilm.estimation import ekf
from fluidfilm.estimation.baseline import centreline_load
from fluidfilm.estimation.plant import runout_signal


@dataclass(frozen=True)
class EstimatorSettings:
    """The filter's tuning (SI units; the process noises are random-walk densities per second).

    ``noise``: the probes' noise standard deviation [m]; ``lsb``: the digitiser's step [m] (adds lsb^2/12);
    ``nsub``: RK4 substeps per sample; ``q_v``: the velocity's process noise as a fraction of the static load's
    acceleration (model error of the film force); ``q_load``, ``q_imbalance``, ``q_viscosity``: how fast the
    load (fraction of the initial load), the imbalance (fraction of ``imbalance_scale``) and the viscosity
    ratio may drift, per sqrt(s); ``p0_*``: the starting uncertainty (same units).
    """

    noise: float = 1.0e-6
    lsb: float = 0.1e-6
    nsub: int = 2
    q_v: float = 2.0e-3
    q_load: float = 0.02
    q_imbalance: float = 0.02
    q_viscosity: float = 0.1
    p0_load: float = 0.5
    p0_imbalance: float = 1.0
    p0_viscosity: float = 0.3
    imbalance_scale: float | None = None
    nis_window_s: float = 0.05
    nis_threshold: float = 1.3
    persist_s: float = 0.08
    flag_after_s: float = 0.1
    inflate_threshold: float = 2.5
    inflate_tau_s: float = 0.005
    inflate_cooldown_s: float = 0.02
    inflate_fraction: float = 0.3
    smooth: bool = True


@dataclass
class Estimates:
    """The estimator's output over a record: ``t`` (N,) [s]; ``z`` (N, 9) the filtered state and ``sd`` (N, 9)
    its standard deviation (``ekf.STATE_NAMES``); ``zs``, ``sds`` the smoothed ones (None unless asked);
    ``nis`` (N,) and its window mean ``nis_mean``; ``mismatch`` and ``out_of_domain`` (N,) flags; the
    centreline baseline's load ``baseline_W`` (N, 2); ``mu0`` [Pa s]; ``us_per_sample`` the filter's compiled
    loop per sample [us] (one core)."""

    t: np.ndarray
    z: np.ndarray
    sd: np.ndarray
    nis: np.ndarray
    nis_mean: np.ndarray
    mismatch: np.ndarray
    out_of_domain: np.ndarray
    baseline_W: np.ndarray
    mu0: float
    us_per_sample: float
    zs: np.ndarray | None = None
    sds: np.ndarray | None = None
    info: dict = field(default_factory=dict)

    def frame(self, smoothed: bool = False) -> pd.DataFrame:
        """The estimates as a table: load [N], imbalance [kg m] and phase [rad], viscosity [Pa s], each with its
        2-sigma band (``*_lo``, ``*_hi``), the position [m], the flags and the baseline's load."""
        z, sd = (self.zs, self.sds) if smoothed else (self.z, self.sd)
        if z is None or sd is None:
            raise ValueError("no smoothed estimates: run estimate(..., settings with smooth=True)")
        out = {"time": self.t, "x1": z[:, 0], "x2": z[:, 1]}
        for name, val, err in (("load", *_magnitude(z[:, 4], z[:, 5], sd[:, 4], sd[:, 5])),
                               ("imbalance", *_magnitude(z[:, 6], z[:, 7], sd[:, 6], sd[:, 7]))):
            out[name] = val
            out[f"{name}_lo"] = val - 2.0 * err
            out[f"{name}_hi"] = val + 2.0 * err
        out["load_W1"], out["load_W2"] = z[:, 4], z[:, 5]
        out["imbalance_phase"] = np.arctan2(z[:, 7], z[:, 6])
        out["viscosity"] = z[:, 8] * self.mu0
        out["viscosity_lo"] = (z[:, 8] - 2.0 * sd[:, 8]) * self.mu0
        out["viscosity_hi"] = (z[:, 8] + 2.0 * sd[:, 8]) * self.mu0
        out["nis_mean"] = self.nis_mean
        out["flag_mismatch"] = self.mismatch
        out["flag_out_of_domain"] = self.out_of_domain
        out["baseline_load"] = np.hypot(self.baseline_W[:, 0], self.baseline_W[:, 1])
        return pd.DataFrame(out)


def _magnitude(a, b, sa, sb):
    m = np.hypot(a, b)
    with np.errstate(invalid="ignore", divide="ignore"):
        err = np.where(m > 0, np.sqrt((a * sa) ** 2 + (b * sb) ** 2) / np.where(m > 0, m, 1.0), np.hypot(sa, sb))
    return m, err


def shaft_angle(t, speed_rpm) -> np.ndarray:
    """The shaft's angle [rad] at each sample: the trapezoidal integral of the speed signal from the first sample
    (the speed signal's phase reference; a keyphasor would fix it to a mark on the shaft)."""
    w = np.asarray(speed_rpm, dtype=float) * 2.0 * math.pi / 60.0
    t = np.asarray(t, dtype=float)
    return np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(t))])


def estimate(frame: pd.DataFrame, model, mass: float, runout=None, settings: EstimatorSettings = EstimatorSettings(),
             sgn: int = 1, speed_range: tuple[float, float] | None = None) -> Estimates:
    """Estimate position, static load, imbalance and viscosity over a probe record.

    ``frame``: columns ``time`` [s], ``x``, ``y`` [m] (the probes, in the conventions' X1, X2 frame, relative to
    the bearing's centre), ``speed`` [rpm] (``probes.read_probe_file`` checks a file into this form); ``model``: the
    force model at the description's viscosity mu0 (any model with a speed kernel; the universal surrogate by
    default in ``assess``); ``mass`` [kg] the rotor mass per bearing; ``runout``: the slow-roll runout vector,
    ((c1, s1), (c2, s2), ...) [m] per axis (``plant.runout_signal``), subtracted before the filter;
    ``speed_range``: [rpm] where the out-of-domain flag should fire outside (None: no check).
    """
    st = settings
    t = frame["time"].to_numpy(dtype=float)
    speed = frame["speed"].to_numpy(dtype=float)
    y = frame[["x", "y"]].to_numpy(dtype=float)
    phase = shaft_angle(t, speed)
    if runout is not None:
        y = y - runout_signal(runout, phase)
    omega = speed * 2.0 * math.pi / 60.0
    # the speed's rate of change: the imbalance's tangential push in a run-up or coast-down (0 at a steady speed)
    alpha = np.gradient(omega, t) if t.size > 1 else np.zeros_like(omega)
    dt = float(np.median(np.diff(t)))
    c = model.clearance
    sk = model.speed_kernel()
    if sk is None:
        raise ValueError(f"{model.name}: the estimator needs a force model with a speed kernel")
    kernel, params = sk
    # a start from the centreline baseline over the first revolution
    rev = 60.0 / float(np.median(speed))
    first = t <= t[0] + rev
    base = centreline_load(model, t, y, speed, 1.0, revolutions=2.0)
    W0 = base["W"][int(first.sum()) - 1]
    load0 = max(float(np.hypot(*W0)), mass * 9.81)
    u_scale = st.imbalance_scale if st.imbalance_scale is not None else load0 / float(np.median(omega)) ** 2
    z0 = np.array([y[:first.sum()].mean(axis=0)[0], y[:first.sum()].mean(axis=0)[1], 0.0, 0.0,
                   W0[0], W0[1], 0.0, 0.0, 1.0])
    w = float(np.median(omega))
    p0 = np.array([(0.05 * c) ** 2, (0.05 * c) ** 2, (0.05 * c * w) ** 2, (0.05 * c * w) ** 2,
                   (st.p0_load * load0) ** 2, (st.p0_load * load0) ** 2,
                   (st.p0_imbalance * u_scale) ** 2, (st.p0_imbalance * u_scale) ** 2, st.p0_viscosity ** 2])
    P0 = np.diag(p0)
    acc = load0 / mass
    q = np.array([0.0, 0.0, (st.q_v * acc) ** 2 * dt, (st.q_v * acc) ** 2 * dt,
                  (st.q_load * load0) ** 2, (st.q_load * load0) ** 2,
                  (st.q_imbalance * u_scale) ** 2, (st.q_imbalance * u_scale) ** 2, st.q_viscosity ** 2])
    r_var = st.noise ** 2 + st.lsb ** 2 / 12.0
    N = t.size
    out_z = np.zeros((N, 9))
    out_P = np.zeros((N, 9, 9))
    nis = np.zeros(N)
    store = bool(st.smooth)
    shape = (N, 9, 9) if store else (1, 9, 9)
    Phi_all, Ppred_all, zpred_all = np.zeros(shape), np.zeros(shape), np.zeros((shape[0], 9))
    hx, hv = 1e-5 * c, 1e-5 * c * w
    p_infl = np.zeros(9)
    p_infl[4:6] = (st.inflate_fraction * load0) ** 2
    p_infl[6:8] = (st.inflate_fraction * u_scale) ** 2
    p_infl[8] = (st.inflate_fraction * st.p0_viscosity) ** 2
    p_infl[2:4] = p0[2:4] * 0.1
    inflated = np.zeros(N, dtype=np.bool_)
    tau = max(1.0, st.inflate_tau_s / dt)
    cool = max(1, int(round(st.inflate_cooldown_s / dt)))
    r_max = 0.99 * c
    args = (kernel, params, y, omega, alpha, phase, dt, float(mass), float(sgn), int(st.nsub), z0, P0, q, r_var, r_max, hx, hv,
            out_z, out_P, nis, store, Phi_all, Ppred_all, zpred_all, p_infl, float(st.inflate_threshold), tau, cool,
            inflated)
    ekf.run_filter(*args[:2], y[:2], omega[:2], alpha[:2], phase[:2], *args[6:17], out_z[:2], out_P[:2], nis[:2], store,
                   Phi_all[:2] if store else Phi_all, Ppred_all[:2] if store else Ppred_all,
                   zpred_all[:2] if store else zpred_all, p_infl, float(st.inflate_threshold), tau, cool,
                   inflated[:2])          # compile outside the timing
    tic = time.perf_counter()
    skipped = ekf.run_filter(*args)
    us = (time.perf_counter() - tic) / N * 1e6
    sd = np.sqrt(np.maximum(np.diagonal(out_P, axis1=1, axis2=2), 0.0))
    n_win = max(1, int(round(st.nis_window_s / dt)))
    cs = np.concatenate([[0.0], np.cumsum(np.nan_to_num(nis, nan=0.0))])
    idx = np.arange(1, N + 1)
    lo = np.maximum(idx - n_win, 0)
    nis_mean = (cs[idx] - cs[lo]) / (idx - lo) / 2.0    # per degree of freedom: 1.0 for a consistent filter
    armed = t >= t[0] + st.flag_after_s
    # the mismatch flag: the windowed NIS above the threshold without a break for persist_s (an abrupt change
    # the filter re-converges from makes a burst shorter than that; a model that cannot explain the orbit does not)
    over = armed & (nis_mean > st.nis_threshold)
    run = np.zeros(N, dtype=np.int64)
    for k in range(N):
        run[k] = (run[k - 1] + 1 if k else 1) if over[k] else 0
    n_persist = max(1, int(round(st.persist_s / dt)))
    mismatch = run >= n_persist
    eps = np.hypot(out_z[:, 0], out_z[:, 1]) / c
    ood = eps > model.validity.eps_max
    if speed_range is not None:
        ood |= (speed < speed_range[0]) | (speed > speed_range[1])
    zs = sds = None
    if store:
        zs = np.zeros_like(out_z)
        Ps = np.zeros_like(out_P)
        ekf.run_smoother(out_z, out_P, Phi_all, Ppred_all, zpred_all, zs, Ps)
        sds = np.sqrt(np.maximum(np.diagonal(Ps, axis1=1, axis2=2), 0.0))
    return Estimates(t=t, z=out_z, sd=sd, nis=nis, nis_mean=nis_mean, mismatch=mismatch, out_of_domain=ood,
                     baseline_W=base["W"], mu0=float(model.bearing.viscosity), us_per_sample=us, zs=zs, sds=sds,
                     info={"skipped": int(skipped), "inflations": int(inflated.sum()), "dt": dt, "imbalance_scale": u_scale, "load0": load0})
