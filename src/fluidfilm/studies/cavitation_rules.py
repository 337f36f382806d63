"""How wrong are Guembel and Swift-Stieber orbits? The cavitation rules against the mass-conserving film
(``experiments/cavitation_rules.py``, docs/mass_conserving.md).

Like for like: the three rules run on one grid, one feed (an axial groove at the top, theta = pi, opposite a
load along gravity, at the bearing's supply pressure) and one solver (``reynolds.elrod_adams.ElrodAdamsSolver``
with ``cavitation="jfo" | "swift-stieber" | "gumbel"``; its Guembel and Swift-Stieber films equal the grooved
direct solver's, tests/reynolds/test_elrod_adams.py), so a difference is the rule's and nothing else.  The film
must be fed somewhere under mass conservation (docs); the groove is the feed of the comparison.

Parts:

1. the paper's seven cases (Fig. 4 a-g): orbit RMS distance and Hausdorff distance of each non-conserving
   rule's settled orbit from the JFO orbit in % of c, spans, equilibria; the grid checked by rerunning the
   largest orbit on a finer grid;
2. the whirl threshold (Lund's, from K and C with the film content at its steady value) and a run-up through
   it: Pfeil's example (d = L = 0.1 m, c = 150 um, mu = 0.02 Pa s, 200 kg, 0.005 kg m, 60 -> 140 Hz in 1 s),
   onset speed (order tracking, ``studies.runup``) and the limit cycle's amplitude;
3. a squeeze-film damper: the journal driven round a centred circular orbit, no rotation, the film fed at the
   groove and at z = 0: radial and tangential film force over a whirl period;
4. side flow and friction power along the orbits of part 1;
5. the JFO model's own numbers: the flow balance of committed steps, the published case (Ausas et al. 2009's
   squeeze film), the cost of a time step on 30 x 30.
"""
from __future__ import annotations

import dataclasses
import math
import os
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd

from fluidfilm.core.bearing import JournalBearing
from fluidfilm.studies.figure_style import square_window
from fluidfilm.characteristics.static import load_along_gravity
from fluidfilm.characteristics.stability import threshold_speed
from fluidfilm.reynolds import elrod_adams as ea
from fluidfilm.reynolds.elrod_adams import ElrodAdamsSolver
from fluidfilm.reynolds.jfo_cases import ausas_errors, ausas_squeeze
from fluidfilm.rotor.cases import rotor_for_case
from fluidfilm.rotor.integrate import simulate
from fluidfilm.rotor.metrics import compare_orbits, orbit_stats
from fluidfilm.rotor.model import Rotor, SpeedSchedule

INPUTS = ()
OUTPUTS = {"report_dir": ["cavitation_rules.json", "cavitation_rules"],
           "figure_dir": ["cavitation_rules_orbits.png", "cavitation_rules_runup.png"]}

RULES = ("gumbel", "swift-stieber", "jfo")
LABEL = {"gumbel": "Gümbel", "swift-stieber": "Swift-Stieber", "jfo": "JFO (mass-conserving)"}
COLOUR = {"gumbel": "tab:orange", "swift-stieber": "tab:blue", "jfo": "black"}


def tracking_run(cfg):
    return "cavitation_rules", None


def film(bearing: JournalBearing, grid, rule: str, s) -> ElrodAdamsSolver:
    """The study's film of one rule (``s``: the study's settings)."""
    return ElrodAdamsSolver(bearing, int(grid[0]), int(grid[1]), groove_angle=math.radians(float(s["groove_angle_deg"])),
                            tol=float(s["tol"]), tol_commit=float(s["tol_commit"]), cavitation=rule)


# ------------------------------------------------------------------------------------------ 1. and 4.: cases
def _case_job(job: dict) -> dict:
    """One (rule, case) run in a worker: the settled orbit and its film flows."""
    bearing = JournalBearing.from_dict(job["bearing"])
    model = film(bearing, job["grid"], job["rule"], job["s"])
    rotor = rotor_for_case(job["rotor"], job["case"])
    t0 = time.perf_counter()
    traj = simulate(model, rotor, t_end=job["t_end"], dt=job["dt"], record_every=job["record_every"],
                    x0=job.get("x0"))
    wall = time.perf_counter() - t0
    return {"rule": job["rule"], "case": job["name"], "grid": list(job["grid"]), "t": traj.t, "x": traj.x,
            "v": traj.v, "status": traj.status, "wall_s": wall, "steps": len(traj.t) * job["record_every"],
            "side_flow": traj.meta["side_flow_m3s"], "power": traj.meta["friction_power_W"],
            "sweeps_stage": traj.meta["sweeps_per_stage"], "sweeps_commit": traj.meta["sweeps_per_commit"]}


def _trajectory(res: dict):
    from fluidfilm.rotor.integrate import Trajectory

    return Trajectory(t=res["t"], x=res["x"], v=res["v"], status=res["status"])


def case_table(results: list[dict], clearance: float, t_settle: float, threshold_pct: float) -> pd.DataFrame:
    """One row per (case, rule): orbit statistics and, for the non-conserving rules, distances from JFO's orbit
    in % of c; mean side flow and friction power over the settled orbit and their differences from JFO's."""
    by = {(r["case"], r["rule"]): r for r in results}
    rows = []
    for (case, rule), res in sorted(by.items()):
        tr = _trajectory(res)
        row = {"case": case, "rule": rule, "status": res["status"], "wall_s": res["wall_s"],
               "sweeps_per_stage": res["sweeps_stage"], "sweeps_per_commit": res["sweeps_commit"]}
        row.update(orbit_stats(tr, clearance, t_settle))
        settled = res["t"] >= t_settle
        row["side_flow_m3s"] = float(np.mean(res["side_flow"][settled])) if tr.ok else math.nan
        row["friction_power_W"] = float(np.mean(res["power"][settled])) if tr.ok else math.nan
        ref = by.get((case, "jfo"))
        if rule != "jfo" and ref is not None and tr.ok and ref["status"] == "ok":
            d = compare_orbits(tr, _trajectory(ref), clearance, t_settle)
            row.update({k: d[k] for k in ("rms_pct", "hausdorff_pct", "span_err_pct", "mean_offset_pct")})
            row["over_threshold"] = bool(d["rms_pct"] > threshold_pct or d["hausdorff_pct"] > threshold_pct)
            q_ref = float(np.mean(ref["side_flow"][ref["t"] >= t_settle]))
            p_ref = float(np.mean(ref["power"][ref["t"] >= t_settle]))
            row["side_flow_rel_diff_pct"] = 100.0 * (row["side_flow_m3s"] / q_ref - 1.0)
            row["friction_power_rel_diff_pct"] = 100.0 * (row["friction_power_W"] / p_ref - 1.0)
        rows.append(row)
    return pd.DataFrame(rows)


# ------------------------------------------------------------------------------------ 2.: threshold, run-up
def run_up_job(job: dict) -> dict:
    """Pfeil's run-up for one rule in a worker: the orbit, and the onset from ``studies.runup``'s order tracking."""
    from fluidfilm.studies.runup import analyse, order_cascade, subsync_table

    r = job["r"]
    bearing = JournalBearing(length=r["length"], diameter=r["diameter"], clearance=r["clearance"],
                             speed_rpm=60.0 * r["f_start_hz"], viscosity=r["viscosity"],
                             supply_pressure=r["supply_pressure"])
    model = film(bearing, r["grid"], job["rule"], job["s"])
    rotor = Rotor(mass=r["mass"], imbalance=r["imbalance"])
    schedule = SpeedSchedule.table([0.0, r["duration_s"]], [60.0 * r["f_start_hz"], 60.0 * r["f_end_hz"]])
    from fluidfilm.characteristics.static import equilibrium

    x0 = equilibrium(model, load_along_gravity(rotor.mass * rotor.gravity))["X"]
    t0 = time.perf_counter()
    traj = simulate(model, rotor, t_end=r["duration_s"], dt=r["dt"], record_every=r["record_every"], x0=x0,
                    speed=schedule)
    wall = time.perf_counter() - t0
    out = {"rule": job["rule"], "status": traj.status, "wall_s": wall, "t": traj.t, "x": traj.x}
    if traj.ok:
        cas = order_cascade(traj, schedule, model.clearance, r["samples_per_rev"], r["window_revs"], r["hop_revs"])
        res = analyse(cas, tuple(r["band"]), r["whirl_level"], r["onset_fit_nepers"])
        out["analysis"] = {k: float(v) for k, v in res.items() if isinstance(v, (int, float))}
        out["subsync"] = subsync_table(cas, tuple(r["band"]))
        last = traj.t >= r["duration_s"] - r["limit_cycle_window_s"]
        xs = traj.x[last] - traj.x[last].mean(axis=0)
        out["limit_cycle_amplitude_c"] = float(np.hypot(xs[:, 0], xs[:, 1]).max() / model.clearance)
    return out


def thresholds(bearing: JournalBearing, grid, s, mass: float, bracket) -> dict:
    """Lund's threshold speed [rpm] of each rule (K and C with the content at its steady value)."""
    out = {}
    for rule in RULES:
        model = film(bearing, grid, rule, s)
        res = threshold_speed(model, mass=mass, load=load_along_gravity(mass * 9.81), speed_bracket=tuple(bracket))
        out[rule] = {"speed_rpm": float(res["speed_rpm"]), "whirl_ratio": float(res.get("whirl_ratio", math.nan)),
                     "eps": float(res.get("eps", math.nan))}
    return out


# ------------------------------------------------------------------------------------------- 3.: the damper
def damper(bearing: JournalBearing, grid, s, eps: float, whirl_hz: float, revolutions: int, steps_per_rev: int) -> dict:
    """The film force of each rule with the journal driven round a centred circular orbit of radius eps c at
    ``whirl_hz`` (forward), no shaft rotation: (radial, tangential) force over the last revolution and its means.

    JFO: the committed film steps along the prescribed path (the content carried); the others: their
    film at each state (nothing to carry)."""
    c = bearing.clearance
    om = 2.0 * math.pi * whirl_hz
    dt = 1.0 / (whirl_hz * steps_per_rev)
    n_steps = revolutions * steps_per_rev
    out = {}
    for rule in RULES:
        model = film(bearing, grid, rule, s)
        ep = model.params
        n, nz = model.n_theta, model.n_z
        p = np.zeros((n, nz))
        th = np.ones((n, nz))
        ea.reset_fields(ep, p, th)
        th_n = th.copy()
        content = np.empty_like(p)
        fr, ft, phases = [], [], []
        for k in range(n_steps):
            t0, t1 = k * dt, (k + 1) * dt
            xo = (eps * c * math.sin(om * t0), eps * c * math.cos(om * t0))
            xn = (eps * c * math.sin(om * t1), eps * c * math.cos(om * t1))
            vn = (eps * c * om * math.cos(om * t1), -eps * c * om * math.sin(om * t1))
            if rule == "jfo":
                _, status = ea.commit_film(ep, ep.k_omega, *xo, *xn, dt, th_n, content, p, th)
                th_n[:] = th
                f1, f2 = ea.ea_force(ep, p)
            else:
                f1, f2, _, status = ea.stage_film(ep, ep.k_omega, *xn, *vn, dt, ep.tol_commit, th_n, content, p, th)
            if status != ea.EA_CONVERGED:
                raise RuntimeError(f"the damper's film ({rule}) did not converge at step {k}")
            if k >= n_steps - steps_per_rev:
                # radial: along the journal's displacement (outward), tangential: along its velocity
                er = np.array(xn) / (eps * c)
                et = np.array(vn) / (eps * c * om)
                fr.append(f1 * er[0] + f2 * er[1])
                ft.append(f1 * et[0] + f2 * et[1])
                phases.append((om * t1) % (2.0 * math.pi))
        fr_a, ft_a = np.array(fr), np.array(ft)
        out[rule] = {"radial_mean_N": float(fr_a.mean()), "tangential_mean_N": float(ft_a.mean()),
                     "damping_N_s_m": float(-ft_a.mean() / (eps * c * om)),
                     "stiffness_N_m": float(-fr_a.mean() / (eps * c)),
                     "phase": np.array(phases), "radial": fr_a, "tangential": ft_a}
    return out


# --------------------------------------------------------------------------------------- 5.: JFO's own numbers
def mass_balance(bearing: JournalBearing, grid, s, eps: float, whirl_rad_s: float, n_steps: int, dt: float,
                 tol_commit: float | None = None) -> float:
    """The largest relative flow-balance error of committed steps along a whirl through a cavity
    (``elrod_adams.flow_balance``)."""
    settings = dict(s)
    if tol_commit is not None:
        settings["tol_commit"] = tol_commit
    model = film(bearing, grid, "jfo", settings)
    ep = model.params
    c = bearing.clearance

    def x(t):
        return eps * c * math.sin(whirl_rad_s * t) + 0.1 * c, eps * c * math.cos(whirl_rad_s * t) + 0.2 * c

    p, th = model.steady_field(x(0.0))
    th_n = th.copy()
    content = np.empty_like(p)
    h = np.empty(ep.n_theta)
    hf = np.empty(ep.n_theta)
    worst = 0.0
    for k in range(n_steps):
        xo, xn = x(k * dt), x((k + 1) * dt)
        ea.commit_film(ep, ep.k_omega, xo[0], xo[1], xn[0], xn[1], dt, th_n, content, p, th)
        ea.journal_gap(ep, xn[0] / c, xn[1] / c, h, hf)
        change, inflow, scale = ea.flow_balance(ep, ep.k_omega, h, hf, 1.0 / dt, content, p, th)
        worst = max(worst, abs(change - inflow) / scale)
        th_n[:] = th
    return worst


def step_cost(bearing: JournalBearing, s, rotor: Rotor, steps: int, repeats: int) -> dict:
    """Median wall time per rotor time step [us] of the JFO film on 30 x 30 (after a warm-up run)."""
    model = film(bearing, (30, 30), "jfo", s)
    simulate(model, rotor, t_end=20 * 1e-5, dt=1e-5)
    times = []
    for _ in range(repeats):
        tr = simulate(model, rotor, t_end=steps * 1e-5, dt=1e-5, record_every=100)
        times.append(tr.wall_time_s / steps)
    return {"us_per_step": 1e6 * float(np.median(times)), "steps": steps, "repeats": repeats,
            "sweeps_per_stage": tr.meta["sweeps_per_stage"], "sweeps_per_commit": tr.meta["sweeps_per_commit"]}


# ---------------------------------------------------------------------------------------------- figures
def plot_orbits(results: list[dict], clearance: float, t_settle: float, cases: list[str], labels: dict):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    n = len(cases)
    cols = min(n, 4)
    rows = int(math.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(3.3 * cols, 3.3 * rows), squeeze=False)
    by = {(r["case"], r["rule"]): r for r in results}
    marker = {"gumbel": "x", "swift-stieber": "+", "jfo": "o"}
    for ax, case in zip(axes.flat, cases):
        points = []
        for rule in RULES:
            res = by.get((case, rule))
            if res is None or not res["status"].startswith("ok"):
                continue
            m = res["t"] >= t_settle
            # gravity down the page: X1 across, X2 downwards
            x1, x2 = res["x"][m, 0] / clearance, -res["x"][m, 1] / clearance
            points.append(np.column_stack([x1, x2]))
            style = dict(color=COLOUR[rule], label=LABEL[rule])
            if max(np.ptp(x1), np.ptp(x2)) < 1e-3:
                # a settled equilibrium: a line of zero length would not show, so a marker at the point
                ax.plot([x1.mean()], [x2.mean()], ls="none", marker=marker[rule], ms=7, mfc="none", **style)
            else:
                ax.plot(x1, x2, lw=1.2 if rule == "jfo" else 0.9, ls="-" if rule == "jfo" else "--", **style)
        if points:
            # one square window round every rule's orbit (at least 0.05 c across), so that none is cut
            square_window(ax, np.vstack(points), 0.025)
        ax.set_title(f"{case}: {labels.get(case, '')}", fontsize=8)
        ax.set_aspect("equal")
        ax.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(4))
        ax.yaxis.set_major_locator(matplotlib.ticker.MaxNLocator(4))
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=7, loc="best")
    fig.suptitle("Settled orbits (X1/c across, X2/c down: gravity down the page) under the three cavitation rules",
                 fontsize=9)
    fig.tight_layout()
    return fig


def plot_runup_and_damper(runups: dict, damp: dict, thresholds_rpm: dict):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3.8))
    for rule, res in runups.items():
        if "subsync" not in res:
            continue
        tab = res["subsync"]
        a.semilogy(tab["speed_rpm"] / 60.0, tab["subsync_amplitude_c"], color=COLOUR[rule], label=LABEL[rule])
        on = res["analysis"].get("onset_rpm", math.nan)
        if math.isfinite(on):
            a.axvline(on / 60.0, color=COLOUR[rule], lw=0.7, ls=":")
    a.set_xlabel("shaft speed [Hz]")
    a.set_ylabel("sub-synchronous amplitude [c]")
    a.set_title("Pfeil's run-up 60 → 140 Hz in 1 s (dotted: onset)", fontsize=9)
    a.legend(fontsize=7)
    a.grid(alpha=0.3, which="both")
    for rule, res in damp.items():
        o = np.argsort(res["phase"])
        b.plot(np.degrees(res["phase"][o]), res["radial"][o], color=COLOUR[rule], label=f"{LABEL[rule]} radial")
        b.plot(np.degrees(res["phase"][o]), res["tangential"][o], color=COLOUR[rule], ls="--",
               label=f"{LABEL[rule]} tangential")
    b.set_xlabel("whirl angle [deg]")
    b.set_ylabel("film force [N]")
    b.set_title("Squeeze-film damper: circular orbit, no rotation", fontsize=9)
    b.legend(fontsize=6)
    b.grid(alpha=0.3)
    fig.tight_layout()
    return fig


# ------------------------------------------------------------------------------------------------- run
def run(cfg):
    """All parts (module doc): reports under ``report_dir`` (cavitation_rules.json, cavitation_rules/*.csv),
    figures under ``figure_dir``."""
    from fluidfilm import io
    from fluidfilm.workflow.config import bearing_from_cfg
    from fluidfilm.workflow.tracking import Logged

    s = dict(cfg.cavitation_rules)
    bearing = bearing_from_cfg(cfg.bearing)
    c = bearing.clearance
    report, figs = Path(cfg.report_dir), Path(cfg.figure_dir)
    workers = max(1, min(int(s["workers"]), os.cpu_count() or 1))
    t_start = time.perf_counter()
    cases = list(s["cases"])
    labels = {k: str(cfg.cases[k].label) for k in cases}
    base = {"bearing": bearing.to_dict(), "rotor": dict(cfg.rotor), "s": s, "t_end": float(s["t_end"]),
            "dt": float(s["dt"]), "record_every": int(s["record_every"])}
    jobs = [dict(base, rule=rule, name=k, case=dict(cfg.cases[k]), grid=list(s["grid"])) for k in cases for rule in RULES]
    check_case = str(s["check_case"])
    check_jobs = [dict(base, rule=rule, name=check_case, case=dict(cfg.cases[check_case]), grid=list(s["check_grid"]))
                  for rule in RULES] if check_case in cases else []
    r = dict(s["runup"])
    run_jobs = [{"rule": rule, "r": r, "s": s} for rule in RULES]
    with ProcessPoolExecutor(max_workers=workers) as pool:
        futs = [pool.submit(_case_job, j) for j in jobs]
        check_futs = [pool.submit(_case_job, j) for j in check_jobs]
        run_futs = [pool.submit(run_up_job, j) for j in run_jobs]
        # meanwhile, in this process: thresholds, the damper, the published case, the flow balance
        lund = thresholds(bearing, s["grid"], s, float(s["threshold_mass"]), s["speed_bracket"])
        pfeil = JournalBearing(length=r["length"], diameter=r["diameter"], clearance=r["clearance"],
                               speed_rpm=60.0 * r["f_start_hz"], viscosity=r["viscosity"],
                               supply_pressure=r["supply_pressure"])
        lund_pfeil = thresholds(pfeil, r["grid"], s, float(r["mass"]), [0.5, 10.0])
        d = dict(s["damper"])
        damper_bearing = dataclasses.replace(bearing, speed_rpm=0.0, supply_pressure=float(d["supply_pressure"]))
        damp = damper(damper_bearing, s["grid"], s, float(d["eps"]), float(d["whirl_hz"]), int(d["revolutions"]),
                      int(d["steps_per_rev"]))
        ausas = ausas_squeeze(nx=int(s["ausas_nodes"]), dt=float(s["ausas_dt"]))
        ausas_err = ausas_errors(ausas)
        balance = mass_balance(bearing, s["grid"], s, 0.4, bearing.omega * 0.5, int(s["balance_steps"]), 1e-5)
        balance_tight = mass_balance(bearing, s["grid"], s, 0.4, bearing.omega * 0.5, int(s["balance_steps"]), 1e-5,
                                     tol_commit=1e-13)
        results = [f.result() for f in futs]
        checks = [f.result() for f in check_futs]
        runups = {res["rule"]: res for res in (f.result() for f in run_futs)}
    # the cost of a step, alone on the machine (after the pool has finished)
    cost = step_cost(bearing, s, rotor_for_case(cfg.rotor, cfg.cases[check_case if check_case in cases else cases[0]]),
                     int(s["cost_steps"]), int(s["cost_repeats"]))
    table = case_table(results, c, float(s["t_settle"]), float(s["threshold_pct"]))
    check_table = case_table(checks, c, float(s["t_settle"]), float(s["threshold_pct"])) if checks else pd.DataFrame()
    # the grid check: the same case on the finer grid, each rule's orbit against its own coarser one
    grid_check = {}
    for res in checks:
        base_res = next(x for x in results if x["case"] == res["case"] and x["rule"] == res["rule"])
        if res["status"] == "ok" and base_res["status"] == "ok":
            grid_check[res["rule"]] = compare_orbits(_trajectory(base_res), _trajectory(res), c, float(s["t_settle"]))["rms_pct"]
    io.write_csv(report / "cavitation_rules" / "cases.csv", table)
    if not check_table.empty:
        io.write_csv(report / "cavitation_rules" / "grid_check.csv", check_table)
    for rule, res in runups.items():
        if "subsync" in res:
            io.write_csv(report / "cavitation_rules" / f"runup_subsync_{rule}.csv", res["subsync"])
    pd.DataFrame([{"rule": k, **{kk: vv for kk, vv in v.items() if np.ndim(vv) == 0}} for k, v in damp.items()]).pipe(
        lambda f: io.write_csv(report / "cavitation_rules" / "damper.csv", f))

    def worst(rule, key="rms_pct"):
        sel = table[(table["rule"] == rule)]
        return float(sel[key].max()) if key in sel and len(sel) else math.nan

    def rel(a, b):
        return abs(a / b - 1.0) if (math.isfinite(a) and math.isfinite(b) and b != 0) else math.nan

    onset = {k: v.get("analysis", {}).get("onset_rpm", math.nan) for k, v in runups.items()}
    metrics = {
        "jfo_mass_balance_rel_err_max": balance,
        "jfo_mass_balance_rel_err_max_tight": balance_tight,
        "jfo_published_case_max_err_pct": max(ausas_err.values()),
        "jfo_step_us_30x30": cost["us_per_step"],
        "jfo_orbit_rms_pct_c_gumbel_max": worst("gumbel"),
        "jfo_orbit_rms_pct_c_swift_max": worst("swift-stieber"),
        "jfo_orbit_hausdorff_pct_c_gumbel_max": worst("gumbel", "hausdorff_pct"),
        "jfo_orbit_hausdorff_pct_c_swift_max": worst("swift-stieber", "hausdorff_pct"),
        "jfo_whirl_threshold_rel_diff_gumbel": rel(lund["gumbel"]["speed_rpm"], lund["jfo"]["speed_rpm"]),
        "jfo_whirl_threshold_rel_diff_swift": rel(lund["swift-stieber"]["speed_rpm"], lund["jfo"]["speed_rpm"]),
        "jfo_runup_onset_rel_diff_gumbel": rel(onset.get("gumbel", math.nan), onset.get("jfo", math.nan)),
        "jfo_runup_onset_rel_diff_swift": rel(onset.get("swift-stieber", math.nan), onset.get("jfo", math.nan)),
        "jfo_damper_damping_rel_diff_gumbel": rel(damp["gumbel"]["damping_N_s_m"], damp["jfo"]["damping_N_s_m"]),
        "jfo_damper_damping_rel_diff_swift": rel(damp["swift-stieber"]["damping_N_s_m"], damp["jfo"]["damping_N_s_m"]),
        "jfo_friction_power_rel_diff_gumbel_max": float(table.get("friction_power_rel_diff_pct", pd.Series(
            dtype=float))[table["rule"] == "gumbel"].abs().max()) / 100.0,
        "jfo_side_flow_rel_diff_swift_max": float(table.get("side_flow_rel_diff_pct", pd.Series(
            dtype=float))[table["rule"] == "swift-stieber"].abs().max()) / 100.0,
    }
    over = table[table.get("over_threshold", pd.Series(False, index=table.index)).fillna(False).astype(bool)]
    summary = {
        "metrics": metrics,
        "settings": {"grid": list(s["grid"]), "check_grid": list(s["check_grid"]), "check_case": check_case,
                     "groove_angle_deg": float(
            s["groove_angle_deg"]), "tol": float(s["tol"]), "tol_commit": float(s["tol_commit"]),
            "dt": float(s["dt"]), "t_end": float(s["t_end"]), "t_settle": float(s["t_settle"]),
            "threshold_pct": float(s["threshold_pct"]), "supply_pressure_Pa": bearing.supply_pressure},
        "cases_over_threshold": [f"{row.case} ({row.rule}): RMS {row.rms_pct:.2f} %c, Hausdorff {row.hausdorff_pct:.2f} %c"
                                 for row in over.itertuples()],
        "grid_check_rms_pct_c": grid_check,
        "thresholds_paper_bearing": {"mass_kg": float(s["threshold_mass"]), **lund},
        "thresholds_pfeil": lund_pfeil,
        "runup_pfeil": {rule: {"status": v["status"], "wall_s": v["wall_s"], **v.get("analysis", {}),
                               "limit_cycle_amplitude_c": v.get("limit_cycle_amplitude_c", math.nan)}
                        for rule, v in runups.items()},
        "damper": {rule: {k: v for k, v in res.items() if np.ndim(v) == 0} for rule, res in damp.items()},
        "ausas_squeeze": {"nodes": int(s["ausas_nodes"]), "dt": float(s["ausas_dt"]), **ausas_err},
        "step_cost": cost,
        "wall_s": time.perf_counter() - t_start,
    }
    io.write_json(report / "cavitation_rules.json", summary)
    io.save_figure(plot_orbits(results, c, float(s["t_settle"]), cases, labels), figs / "cavitation_rules_orbits.png",
                   dpi=120)
    io.save_figure(plot_runup_and_damper(runups, damp, {k: v["speed_rpm"] for k, v in lund_pfeil.items()}),
                   figs / "cavitation_rules_runup.png", dpi=120)
    for row in table.itertuples():
        extra = f", RMS {row.rms_pct:.2f} %c from JFO" if getattr(row, "rms_pct", None) == getattr(row, "rms_pct", 0) \
            and row.rule != "jfo" else ""
        print(f"case {row.case} {row.rule}: {row.status}, span {row.span:.3f} c{extra}, {row.wall_s:.0f} s")
    print(f"Lund's threshold (paper bearing, {s['threshold_mass']} kg): " +
          ", ".join(f"{k} {v['speed_rpm']:,.0f} rpm" for k, v in lund.items()))
    print("Pfeil's run-up onset: " + ", ".join(f"{k} {v:,.0f} rpm" for k, v in onset.items()))
    print(f"JFO: flow balance {balance:.1e} (tol_commit 1e-13: {balance_tight:.1e}), Ausas' squeeze film "
          f"{max(ausas_err.values()):.3f} %, {cost['us_per_step']:.0f} us per step on 30x30")
    return Logged({k: float(v) for k, v in metrics.items() if v is not None and math.isfinite(v)},
                  [report / "cavitation_rules.json", figs / "cavitation_rules_orbits.png",
                   figs / "cavitation_rules_runup.png"])
