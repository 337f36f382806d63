"""Run-ups through the whirl threshold (``experiments/runup.py``): the onset of oil whirl from the transient,
against Lund's linear threshold and between force models, the hysteresis on the run-down, and the
pictures rotordynamics engineers read (a cascade of the orbit's full spectrum against speed, the
sub-synchronous amplitude and the whirl frequency ratio against speed).

The analysis is order tracking: the journal's orbit z = X2 + i X1 (forward whirl, with the journal's
rotation from +X2 towards +X1, at positive frequencies) is resampled at equal steps of the rotation angle
phi(t) = integral of omega, so that 1x (the imbalance response) sits on one order bin whatever the speed
does, and cut into windows of a whole number of revolutions (a short-time FFT in the angle domain; 4-term
Blackman-Harris window, sidelobes below -92 dB). The sub-synchronous amplitude of a window is its largest
line in a band of orders (0.3-0.7 by default), the whirl frequency ratio that line's order.

Onset from the transient: below the threshold a disturbance of the whirl mode decays at the rate sigma(omega)
< 0, above it grows; on a slow ramp ln A(t) = ln A0 + integral sigma dt, so the sub-synchronous amplitude is
smallest where sigma = 0: the onset speed is where that amplitude stops falling and starts to grow (the
minimum of ln A over the run-up, refined by a parabola through the points within ``onset_fit_nepers`` of it).
The practical rule "amplitude above a level" (``whirl_level``) comes later, by the time the growth needs to
reach that level from the smallest amplitude (the delay of a ramp): it is reported as the speed where whirl
is established on the run-up, and the speed where it dies away on the run-down gives the hysteresis.
"""
from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path

import numpy as np
import pandas as pd

from fluidfilm.characteristics.static import equilibrium, load_along_gravity
from fluidfilm.characteristics.stability import threshold_speed
from fluidfilm.core.force_model import ForceModel
from fluidfilm.rotor.integrate import Trajectory, simulate
from fluidfilm.rotor.model import RPM, Rotor, SpeedSchedule

INPUTS = ()
OUTPUTS = {"report_dir": ["runup.json", "runup"], "figure_dir": ["runup_cascade.png", "runup_amplitude.png"]}


def tracking_run(cfg):
    return "runup", None


# ----------------------------------------------------------------------------- the run
def runup_schedule(threshold_rpm: float, start: float, top: float, end: float, rate_rpm_s: float,
                   hold_s: float) -> SpeedSchedule:
    """Run-up from ``start`` x the threshold to ``top`` x at ``rate_rpm_s``, a hold of ``hold_s`` there, and a
    run-down at the same rate to ``end`` x (factors of ``threshold_rpm``)."""
    if not 0.0 < start < 1.0 < top or not 0.0 < end < 1.0:
        raise ValueError(f"the schedule must start and end below the threshold and rise above it: start={start!r}, "
                         f"top={top!r}, end={end!r} (multiples of the threshold)")
    if not (math.isfinite(rate_rpm_s) and rate_rpm_s > 0.0):
        raise ValueError(f"rate_rpm_s must be a positive ramp rate in rpm/s, got {rate_rpm_s!r}")
    if not (math.isfinite(hold_s) and hold_s >= 0.0):
        raise ValueError(f"hold_s must be a time >= 0 s, got {hold_s!r}")
    n = float(threshold_rpm)
    t_up = (top - start) * n / rate_rpm_s
    t_down = (top - end) * n / rate_rpm_s
    times = [0.0, t_up] + ([t_up + hold_s] if hold_s > 0.0 else []) + [t_up + hold_s + t_down]
    speeds = [start * n, top * n] + ([top * n] if hold_s > 0.0 else []) + [end * n]
    return SpeedSchedule.table(times, speeds)


def start_state(model: ForceModel, mass: float, gravity: float, speed_rpm: float, perturbation: float) -> np.ndarray:
    """The static equilibrium at ``speed_rpm`` (the model's force at its own speed under the load scaled by
    omega_ref/omega: the film's exact speed scaling), displaced by ``perturbation`` * c along +X1: the
    disturbance whose decay and growth the run-up follows."""
    b = model.bearing
    load = np.asarray(load_along_gravity(mass * gravity)) * (b.speed_rpm / speed_rpm)
    eq = equilibrium(model, load)
    return np.array([eq["X1"], eq["X2"]]) + perturbation * model.clearance * np.array([1.0, 0.0])


def run_up(model: ForceModel, rotor: Rotor, schedule: SpeedSchedule, x0, dt: float, record_every: int) -> Trajectory:
    """The run-up and run-down: ``simulate`` from ``x0`` at rest over the whole schedule."""
    return simulate(model, rotor, t_end=float(schedule.times[-1]), dt=dt, x0=x0, v0=[0.0, 0.0],
                    record_every=record_every, speed=schedule)


# ----------------------------------------------------------------------------- order tracking
@dataclasses.dataclass
class Cascade:
    """Full spectra of the orbit in windows of whole revolutions: ``amplitude[k, j]`` [units of c] of order
    ``orders[j]`` (forward whirl positive) in window k, centred at time ``t[k]`` [s] and speed ``speed_rpm[k]``,
    with the speed rising, held or falling there (``direction[k]``: "up", "hold", "down")."""

    t: np.ndarray
    speed_rpm: np.ndarray
    direction: np.ndarray
    orders: np.ndarray
    amplitude: np.ndarray

    @property
    def rising(self) -> np.ndarray:
        return self.direction == "up"

    def band(self, lo: float, hi: float) -> tuple[np.ndarray, np.ndarray]:
        """(largest amplitude, its order refined by a parabola through the neighbouring bins) in lo < order < hi."""
        sel = np.flatnonzero((self.orders > lo) & (self.orders < hi))
        a = self.amplitude[:, sel]
        k = np.argmax(a, axis=1)
        peak = a[np.arange(len(k)), k]
        order = self.orders[sel][k].astype(float)
        inner = (k > 0) & (k < len(sel) - 1)
        rows = np.flatnonzero(inner)
        left, mid, right = (np.log(np.maximum(a[rows, k[rows] + d], 1e-300)) for d in (-1, 0, 1))
        den = left - 2.0 * mid + right
        shift = np.where(den < 0.0, 0.5 * (left - right) / np.where(den < 0.0, den, 1.0), 0.0)
        order[rows] += shift * (self.orders[1] - self.orders[0])
        return peak, order


def order_cascade(traj: Trajectory, schedule: SpeedSchedule, clearance: float, samples_per_rev: int = 32,
                  window_revs: int = 16, hop_revs: int = 2) -> Cascade:
    """The orbit's full spectrum against speed by order tracking (module doc); positions in units of c, each
    window's linear trend removed (the equilibrium moves with speed)."""
    from scipy.interpolate import CubicSpline
    from scipy.signal import get_window

    if window_revs < 2 or hop_revs < 1 or samples_per_rev < 8:
        raise ValueError(f"need window_revs >= 2, hop_revs >= 1 and samples_per_rev >= 8, got {window_revs}, "
                         f"{hop_revs}, {samples_per_rev}")
    phi = schedule.angle(traj.t)
    z = (traj.x[:, 1] + 1j * traj.x[:, 0]) / clearance
    n_rev = int((phi[-1] - phi[0]) // (2.0 * math.pi))
    if n_rev < window_revs:
        raise ValueError(f"the run covers {n_rev} revolutions, fewer than one window of {window_revs}")
    ph = phi[0] + np.arange(n_rev * samples_per_rev) * (2.0 * math.pi / samples_per_rev)
    zr = CubicSpline(phi, z.real)(ph) + 1j * CubicSpline(phi, z.imag)(ph)
    tt = np.interp(ph, phi, traj.t)
    n = window_revs * samples_per_rev
    win = get_window("blackmanharris", n)
    gain = 1.0 / win.sum()  # a circular orbit component a e^(i n phi) reads a (the full spectrum of a complex orbit)
    orders = np.fft.fftshift(np.fft.fftfreq(n, d=1.0 / samples_per_rev))
    k = np.arange(n)
    starts = range(0, (n_rev - window_revs) * samples_per_rev + 1, hop_revs * samples_per_rev)
    amp = np.empty((len(starts), n))
    tc = np.empty(len(starts))
    for i, s in enumerate(starts):
        seg = zr[s:s + n]
        seg = seg - np.polyval(np.polyfit(k, seg, 1), k)
        amp[i] = np.abs(np.fft.fftshift(np.fft.fft(seg * win))) * gain
        tc[i] = tt[s + n // 2]
    speed = schedule.speed_rpm(tc)
    acc = schedule.acceleration(tc)
    direction = np.where(acc > 0.0, "up", np.where(acc < 0.0, "down", "hold"))
    return Cascade(tc, speed, direction, orders, amp)


# ----------------------------------------------------------------------------- onset and hysteresis
def onset_speed(speed_rpm, amplitude, fit_nepers: float = 1.0) -> dict:
    """Where the sub-synchronous amplitude stops decaying and starts to grow, on a run-up (speeds increasing).

    The minimum of ln A over the run-up, refined by a least-squares
    parabola in speed through the points within ``fit_nepers`` of the minimum.  Returns ``onset_rpm`` (NaN when
    the amplitude never grows, or its minimum lies at the first or last point), ``min_amplitude`` and
    ``growth_nepers`` (ln of the largest amplitude after the minimum over the minimum: how clearly it grew).
    """
    s = np.asarray(speed_rpm, dtype=float)
    a = np.asarray(amplitude, dtype=float)
    if s.size < 5 or np.any(np.diff(s) <= 0.0):
        raise ValueError(f"a run-up needs at least 5 windows at increasing speeds, got {s.size}")
    la = np.log(np.maximum(a, 1e-300))
    i = int(np.argmin(la))
    growth = float(la[i:].max() - la[i])
    out = {"onset_rpm": math.nan, "min_amplitude": float(a[i]), "min_index": i, "growth_nepers": growth}
    if i == 0 or i == s.size - 1 or growth < 2.0 * fit_nepers:
        return out
    lo = i
    while lo > 0 and la[lo - 1] - la[i] <= fit_nepers:
        lo -= 1
    hi = i
    while hi < s.size - 1 and la[hi + 1] - la[i] <= fit_nepers:
        hi += 1
    if hi - lo < 2:
        lo, hi = i - 1, i + 1
    x = s[lo:hi + 1] - s[i]
    c2, c1, _ = np.polyfit(x, la[lo:hi + 1], 2)
    out["onset_rpm"] = float(s[i] - c1 / (2.0 * c2)) if c2 > 0.0 else float(s[i])
    out["fit_points"] = int(hi - lo + 1)
    return out


def level_speed(speed_rpm, amplitude, level: float, rising: bool, after: int = 0) -> float:
    """On a run-up (``rising``): the first speed from window ``after`` on where the amplitude exceeds ``level``;
    on a run-down (windows in time order): the speed where it has fallen below ``level`` for good (linear
    interpolation in log amplitude).  NaN where it never crosses."""
    s = np.asarray(speed_rpm, dtype=float)
    la = np.log(np.maximum(np.asarray(amplitude, dtype=float), 1e-300))
    ll = math.log(level)
    above = la > ll
    if rising:
        idx = np.flatnonzero(above[after:]) + after
        if idx.size == 0 or idx[0] == 0 or above[idx[0] - 1]:
            return math.nan
        j = idx[0]
    else:
        if not above.any() or above[-1]:
            return math.nan
        j = int(np.flatnonzero(above)[-1]) + 1
    f = (ll - la[j - 1]) / (la[j] - la[j - 1])
    return float(s[j - 1] + f * (s[j] - s[j - 1]))


def analyse(cascade: Cascade, band: tuple[float, float], whirl_level: float, fit_nepers: float) -> dict:
    """Onset, whirl established (run-up) and gone (run-down), the whirl ratio at onset and the hysteresis."""
    amp, order = cascade.band(*band)
    up = cascade.rising
    # the run-up is the windows of rising speed; the run-down those after the top
    down = (cascade.direction == "down") & (cascade.t > cascade.t[up].max())
    on = onset_speed(cascade.speed_rpm[up], amp[up], fit_nepers)
    res = {"onset_rpm": on["onset_rpm"], "min_subsync_amplitude_c": on["min_amplitude"],
           "growth_nepers": on["growth_nepers"],
           "whirl_ratio_at_onset": float(np.interp(on["onset_rpm"], cascade.speed_rpm[up], order[up]))
           if math.isfinite(on["onset_rpm"]) else math.nan,
           "established_rpm": level_speed(cascade.speed_rpm[up], amp[up], whirl_level, rising=True,
                                          after=on["min_index"]),
           "max_subsync_amplitude_c": float(amp.max())}
    res["gone_rpm"] = (level_speed(cascade.speed_rpm[down], amp[down], whirl_level, rising=False)
                       if down.sum() >= 2 else math.nan)
    # the speeds where the rotor whirls or not depending on where it came from: from where the whirl dies on
    # the run-down up to where it starts to grow on the run-up
    res["hysteresis_rpm"] = res["onset_rpm"] - res["gone_rpm"]
    return res


def subsync_table(cascade: Cascade, band: tuple[float, float]) -> pd.DataFrame:
    """Per window: time, speed, direction, the sub-synchronous amplitude and its order, and the 1x amplitude."""
    amp, order = cascade.band(*band)
    sync = cascade.amplitude[:, np.isclose(np.abs(cascade.orders), 1.0)].max(axis=1)  # +-1x
    return pd.DataFrame({"t": cascade.t, "speed_rpm": cascade.speed_rpm,
                         "direction": cascade.direction, "subsync_amplitude_c": amp,
                         "whirl_ratio": order, "sync_amplitude_c": sync})


def cascade_table(cascade: Cascade, max_order: float) -> pd.DataFrame:
    """The cascade as a table: one row per window, one column per order within +-``max_order``."""
    sel = np.abs(cascade.orders) <= max_order + 1e-12
    cols = {f"{o:+.4f}": cascade.amplitude[:, j] for o, j in zip(cascade.orders[sel], np.flatnonzero(sel))}
    return pd.DataFrame({"t": cascade.t, "speed_rpm": cascade.speed_rpm, "direction": cascade.direction, **cols})


# ----------------------------------------------------------------------------- figures
def plot_cascade(cascade: Cascade, threshold_rpm: float, max_order: float = 1.5, title: str = "",
                 floor: float = 3e-4):
    """The waterfall engineers read: each window's full spectrum drawn at the height of its speed, run-up
    (left) and run-down (right); forward whirl at positive orders, the imbalance response at -1x (eq. 4's
    imbalance turns against the journal).  Line height: log amplitude above ``floor`` [c] (as analysers show
    it in dB), so that a growing whirl shows long before it dominates."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 6.2), sharey=True)
    sel = np.abs(cascade.orders) <= max_order + 1e-12
    o = cascade.orders[sel]
    level = np.log10(np.maximum(cascade.amplitude[:, sel], floor) / floor)
    top = max(float(level.max()), 1.0)
    for ax, direction, label in ((axes[0], "up", "run-up"), (axes[1], "down", "run-down")):
        rows = np.flatnonzero(cascade.direction == direction)
        if rows.size == 0:
            continue
        step = max(1, rows.size // 40)
        rows = rows[::step]
        span = np.ptp(cascade.speed_rpm[rows]) or 1.0
        height = 5.0 * span / max(len(rows), 1)  # the largest line rises five rows
        order = rows if direction == "up" else rows[::-1]
        for r in order[::-1]:  # far lines first, near ones drawn over them
            base = cascade.speed_rpm[r]
            y = base + height * level[r] / top
            ax.fill_between(o, base, y, color="white", zorder=2)
            ax.plot(o, y, color="C0", lw=0.7, zorder=3)
        ax.axhline(threshold_rpm, color="C3", ls="--", lw=1, zorder=4, label="Lund's linear threshold")
        for x, txt in ((-1.0, "-1x (imbalance)"), (0.5, "0.5x")):
            ax.axvline(x, color="grey", lw=0.6, ls=":", zorder=1)
            ax.text(x, 1.0, txt, transform=ax.get_xaxis_transform(), ha="center", va="bottom", fontsize=8)
        ax.set_xlabel("order (frequency / shaft speed); forward whirl > 0")
        ax.set_title(label, pad=14)
        ax.legend(loc="lower left", fontsize=8)
    axes[0].set_ylabel(f"shaft speed [rpm] (line height: log amplitude above {floor:g} c)")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def plot_amplitude(tables: dict[str, pd.DataFrame], threshold_rpm: float, onsets: dict[str, dict],
                   whirl_ratio_linear: float | None = None):
    """Sub-synchronous amplitude (log) and whirl frequency ratio against speed, run-up and run-down, per model;
    the onset from each transient and Lund's linear threshold marked."""
    import matplotlib.pyplot as plt

    from fluidfilm.studies.figure_style import readable_log_ticks
    fig, ax = plt.subplots(2, 1, figsize=(9, 7.5), sharex=True)
    for k, (name, tab) in enumerate(tables.items()):
        color = f"C{k}"
        for direction, ls in (("up", "-"), ("down", "--")):
            g = tab[tab.direction == direction]
            ax[0].semilogy(g.speed_rpm, g.subsync_amplitude_c, ls, color=color, lw=1.2,
                           label=f"{name}, run-{direction}")
            strong = g.subsync_amplitude_c > 3.0 * g.subsync_amplitude_c.min()
            ax[1].plot(g.speed_rpm[strong], g.whirl_ratio[strong], ls, color=color, lw=1.0)
        on = onsets.get(name, {}).get("onset_rpm", math.nan)
        if math.isfinite(on):
            ax[0].axvline(on, color=color, lw=0.8, ls=":")
            ax[0].text(on, 0.02 + 0.07 * k, f" onset {name} {on:,.0f} rpm", color=color, fontsize=8,
                       transform=ax[0].get_xaxis_transform())
    for a in ax:
        a.axvline(threshold_rpm, color="k", lw=1, ls="--")
    ax[0].text(threshold_rpm, 0.97, f" Lund {threshold_rpm:,.0f} rpm", fontsize=8, va="top",
               transform=ax[0].get_xaxis_transform())
    if whirl_ratio_linear is not None:
        ax[1].plot([threshold_rpm], [whirl_ratio_linear], "k*", ms=10, label="Lund's whirl ratio at the threshold")
        ax[1].legend(loc="upper right", fontsize=8)
    ax[0].set_ylabel("sub-synchronous amplitude / c")
    readable_log_ticks(ax[0], "y")
    ax[0].legend(loc="lower right", fontsize=8)
    ax[1].set_ylabel("whirl frequency ratio")
    ax[1].set_ylim(0.3, 0.7)
    ax[1].set_xlabel("shaft speed [rpm]")
    fig.tight_layout()
    return fig


# ----------------------------------------------------------------------------- the study
def _models(cfg, bearing, reference) -> dict:
    """name -> force model or the reason it is not run: the reference, the saved surrogates of ``cfg.models``,
    and the universal model where the library has it."""
    from fluidfilm import load_surrogate

    models: dict = {"reference": reference}
    for name, path in (cfg.models or {}).items():
        models[name] = load_surrogate(path) if Path(path).exists() else f"not run: {path} does not exist"
    if cfg.universal.enabled:
        import fluidfilm

        make = getattr(fluidfilm, "universal_bearing", None)
        models["universal"] = (make(bearing, cavitation=cfg.universal.cavitation) if make is not None
                               else "not run: this version of the library has no universal_bearing")
    return models


def run(cfg):
    """Lund's threshold of the reference model, then a run-up and run-down of each model through it: reports
    under ``report_dir`` (runup.json, runup/*.csv), figures under ``figure_dir``."""
    import os

    from fluidfilm import io
    from fluidfilm.reynolds import ReynoldsSolver
    from fluidfilm.workflow.config import bearing_from_cfg
    from fluidfilm.workflow.tracking import Logged

    r = cfg.runup
    bearing = bearing_from_cfg(cfg.bearing)
    reference = ReynoldsSolver(bearing, *r.grid, cavitation=r.cavitation)
    rotor = Rotor(mass=float(r.mass), imbalance=float(r.imbalance), gravity=float(r.gravity))
    lin = threshold_speed(reference, mass=rotor.mass, load=load_along_gravity(rotor.mass * rotor.gravity),
                          speed_bracket=tuple(r.speed_bracket))
    n_th = float(lin["speed_rpm"])
    print(f"Lund's threshold of the reference ({r.grid[0]}x{r.grid[1]}, {r.cavitation}): {n_th:,.0f} rpm, whirl "
          f"ratio {lin['whirl_ratio']:.3f}, eps {lin['eps']:.3f}")
    schedule = runup_schedule(n_th, r.start, r.top, r.end, r.rate_rpm_s, r.hold_s)
    band = (float(r.band[0]), float(r.band[1]))
    report, figs = Path(cfg.report_dir), Path(cfg.figure_dir)
    results: dict = {}
    tables: dict[str, pd.DataFrame] = {}
    cascades: dict[str, Cascade] = {}
    load = os.getloadavg()

    def one(name, model, rotor, schedule) -> Cascade | None:
        t0 = time.perf_counter()
        try:
            x0 = start_state(model, rotor.mass, rotor.gravity, r.start * n_th, r.perturbation)
            traj = run_up(model, rotor, schedule, x0, r.dt, r.record_every)
        except ValueError as err:  # a model that cannot follow the speed says why
            results[name] = {"status": f"not run: {err}"}
            print(f"{name}: {err}")
            return None
        wall = time.perf_counter() - t0
        if not traj.completed:  # an outside-domain run is analysed; its status says so
            results[name] = {"status": traj.status, "wall_s": wall}
            print(f"{name}: {traj.status}")
            return None
        cas = order_cascade(traj, schedule, model.clearance, r.samples_per_rev, r.window_revs, r.hop_revs)
        res = analyse(cas, band, r.whirl_level, r.onset_fit_nepers)
        res.update(status=traj.status, wall_s=wall, n_force_evals=traj.n_force_evals,
                   us_per_force=1e6 * traj.wall_time_s / max(traj.n_force_evals, 1),
                   imbalance_kg_m=rotor.imbalance, rate_rpm_s=float(np.max(np.abs(np.diff(schedule.omega) / np.diff(
                       schedule.times)))) / RPM)
        results[name] = res
        print(f"{name}: onset {res['onset_rpm']:,.0f} rpm ({100 * (res['onset_rpm'] / n_th - 1):+.2f} % of Lund's), "
              f"whirl above {r.whirl_level:g} c from {res['established_rpm']:,.0f} rpm up, gone below it at "
              f"{res['gone_rpm']:,.0f} rpm down; {wall:.0f} s")
        return cas

    for name, model in _models(cfg, bearing, reference).items():
        if isinstance(model, str):
            results[name] = {"status": model}
            print(f"{name}: {model}")
            continue
        cas = one(name, model, rotor, schedule)
        if cas is not None:
            cascades[name] = cas
            tables[name] = subsync_table(cas, band)
            io.write_csv(report / "runup" / f"subsync_{name}.csv", tables[name])
            io.write_csv(report / "runup" / f"cascade_{name}.csv", cascade_table(cas, r.max_order))
    # the reference again: at a slower ramp (is the onset quasi-static?) and with a larger imbalance
    checks = {}
    if r.rate_check_factor is not None:
        slow = runup_schedule(n_th, r.start, r.top, r.end, r.rate_rpm_s * r.rate_check_factor, r.hold_s)
        checks[f"reference_rate_x{r.rate_check_factor:g}"] = (rotor, slow)
    if r.imbalance_check is not None:
        checks[f"reference_imbalance_{r.imbalance_check:g}"] = (dataclasses.replace(rotor, imbalance=float(
            r.imbalance_check)), schedule)
    for name, (rot, sch) in checks.items():
        one(name, reference, rot, sch)
    ref = results.get("reference", {})
    metrics: dict = {}
    if math.isfinite(ref.get("onset_rpm", math.nan)):
        metrics["runup_onset_rel_err_reference"] = abs(ref["onset_rpm"] / n_th - 1.0)
        for name, res in results.items():
            if name != "reference" and name not in checks and math.isfinite(res.get("onset_rpm", math.nan)):
                metrics[f"runup_onset_rel_err_{name}"] = abs(res["onset_rpm"] / ref["onset_rpm"] - 1.0)
        metrics["runup_hysteresis_rpm_reference"] = ref["hysteresis_rpm"]
    rate_s = r.rate_rpm_s * RPM
    summary = {
        "metrics": metrics,
        "linear": {"threshold_rpm": n_th, "whirl_ratio": lin["whirl_ratio"], "eps": lin["eps"],
                   "grid": list(r.grid), "cavitation": r.cavitation},
        "rotor": {"mass_kg": rotor.mass, "imbalance_kg_m": rotor.imbalance, "gravity": rotor.gravity},
        "schedule": {"times_s": schedule.times.tolist(), "speeds_rpm": (schedule.omega / RPM).tolist(),
                     "rate_rpm_s": float(r.rate_rpm_s), "rate_rad_s2": rate_s, "dt_s": float(r.dt)},
        "analysis": {"band": list(band), "window_revs": int(r.window_revs), "hop_revs": int(r.hop_revs),
                     "samples_per_rev": int(r.samples_per_rev), "whirl_level_c": float(r.whirl_level),
                     "onset_fit_nepers": float(r.onset_fit_nepers)},
        "models": results, "loadavg": list(load) + list(os.getloadavg()),
    }
    io.write_json(report / "runup.json", summary)
    first = "reference" if "reference" in cascades else next(iter(cascades), None)
    if first is not None:
        io.save_figure(plot_cascade(cascades[first], n_th, r.max_order,
                                    f"{first}: full spectrum of the orbit against speed"),
                       figs / "runup_cascade.png", dpi=110)
    io.save_figure(plot_amplitude(tables, n_th, results, lin["whirl_ratio"]), figs / "runup_amplitude.png", dpi=110)
    return Logged({k: float(v) for k, v in metrics.items()}, [report / "runup.json", figs / "runup_cascade.png",
                                                             figs / "runup_amplitude.png"])
