"""The reference model's studies behind the paper's Fig. 2 and Fig. 3, and the grid study.

Each study returns a pandas DataFrame (what goes to CSV) and has a plotting
function (what goes to PNG); entry points in ``experiments/`` only compose
them.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd

from fluidfilm.perf.benchmarking import median_seconds
from fluidfilm.studies.figure_style import readable_log_ticks
from fluidfilm.reynolds import ReynoldsSolver


def _direction(angle_deg: float) -> np.ndarray:
    """Unit vector at ``angle_deg`` from +X2 towards +X1 (theta's convention)."""
    a = math.radians(angle_deg)
    return np.array([math.sin(a), math.cos(a)])


def grid_comparison(solvers: dict[str, ReynoldsSolver], eccentricities, angle_deg: float = 0.0,
                    reference: str | None = None) -> pd.DataFrame:
    """Fig. 2: static reaction (journal at rest) against eccentricity for several grids.

    Columns: eps, then for each solver ``F1_<name>, F2_<name>, F_<name>`` [N] and,
    when ``reference`` names one of them, ``err_<name>_pct`` (relative error of |F|).
    """
    eps = np.asarray(eccentricities, dtype=float)
    c = next(iter(solvers.values())).bearing.clearance
    X = eps[:, None] * c * _direction(angle_deg)[None, :]
    frame = pd.DataFrame({"eps": eps})
    for name, solver in solvers.items():
        F = solver.forces(X, np.zeros_like(X))
        frame[f"F1_{name}"] = F[:, 0]
        frame[f"F2_{name}"] = F[:, 1]
        frame[f"F_{name}"] = np.hypot(F[:, 0], F[:, 1])
    if reference is not None:
        ref = frame[f"F_{reference}"].to_numpy()
        for name in solvers:
            if name != reference:
                with np.errstate(invalid="ignore", divide="ignore"):
                    err = np.where(ref > 0, 100.0 * (frame[f"F_{name}"] - ref) / ref, 0.0)
                frame[f"err_{name}_pct"] = err
    return frame


def velocity_response(model, eccentricities, v_max: float, n_v: int, angle_deg: float = 0.0) -> pd.DataFrame:
    """Fig. 3: reaction against the journal's velocity at several eccentricities.

    The velocity is swept along the line of centres (radial, squeeze) and
    across it (tangential), the other component zero.  Long format: eps,
    direction ('radial' | 'tangential'), V1, V2, v (signed speed), F1, F2.
    """
    c = model.bearing.clearance
    e_r = _direction(angle_deg)
    e_t = _direction(angle_deg + 90.0)
    speeds = np.linspace(-v_max, v_max, n_v)
    rows = []
    for eps in eccentricities:
        x = eps * c * e_r
        for name, unit in (("radial", e_r), ("tangential", e_t)):
            V = speeds[:, None] * unit[None, :]
            F = model.forces(np.broadcast_to(x, V.shape), V)
            rows.append(pd.DataFrame({"eps": eps, "direction": name, "V1": V[:, 0], "V2": V[:, 1],
                                      "v": speeds, "F1": F[:, 0], "F2": F[:, 1]}))
    return pd.concat(rows, ignore_index=True)


def velocity_response_wide(frame: pd.DataFrame, direction: str) -> pd.DataFrame:
    """One direction of ``velocity_response`` as a wide table: v, then F1/F2 per eccentricity (``F2_eps0.5``).

    What ``dvc plots`` draws: one line per eccentricity instead of every curve joined into one.
    """
    sub = frame[frame["direction"] == direction]
    if sub.empty:
        raise ValueError(f"no rows with direction {direction!r}; have {sorted(frame['direction'].unique())}")
    wide = sub.pivot(index="v", columns="eps", values=["F1", "F2"])
    wide.columns = [f"{comp}_eps{eps:g}" for comp, eps in wide.columns]
    return wide.reset_index()


def time_per_evaluation(model, x, v, repeats: int = 7, calls: int = 200) -> float:
    """Median wall time [s] of one ``forces(x, v)`` call (Python call included)."""
    return median_seconds(lambda: model.forces(x, v), repeats, calls)  # the warm-up call compiles


def grid_error_study(solver: ReynoldsSolver, converged: ReynoldsSolver, eccentricities,
                     angle_deg: float = 0.0, repeats: int = 7, calls: int = 200) -> dict:
    """Force error of ``solver`` against ``converged`` and its time per evaluation."""
    c = solver.bearing.clearance
    d = _direction(angle_deg)
    out = {}
    errs = []
    for eps in eccentricities:
        x = eps * c * d
        f = np.hypot(*solver.forces(x, [0.0, 0.0]))
        f_ref = np.hypot(*converged.forces(x, [0.0, 0.0]))
        err = 100.0 * abs(f - f_ref) / f_ref
        errs.append(err)
        out[f"force_error_pct_eps_{eps:g}"] = err
    out["force_error_pct_max"] = float(max(errs))
    out["time_per_eval_us"] = 1e6 * time_per_evaluation(solver, 0.5 * c * d, [0.01, -0.01], repeats, calls)
    return out


# --------------------------------------------------------------------------- plots
def plot_grid_comparison(frame: pd.DataFrame, names: list[str], labels: dict[str, str], reference: str):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, ax_err) = plt.subplots(2, 1, figsize=(6.4, 7.0), sharex=True,
                                     gridspec_kw={"height_ratios": [2, 1]})
    for name in names:
        ax.semilogy(frame["eps"], frame[f"F_{name}"], label=labels.get(name, name))
    ax.semilogy(frame["eps"], frame[f"F_{reference}"], "k--", lw=0.8, label=labels.get(reference, reference))
    ax.set_ylabel(r"$|F|$ [N]")
    ax.set_title("Fig. 2 - film reaction against eccentricity (journal at rest)")
    ax.axvspan(0.9, frame["eps"].max(), color="0.9", label=r"$\varepsilon > 0.9$: the paper's dense-grid region")
    ax.legend()
    ax.grid(True, which="both", alpha=0.3)
    readable_log_ticks(ax, "y")
    for name in names:
        ax_err.plot(frame["eps"], frame[f"err_{name}_pct"], label=labels.get(name, name))
    ax_err.axhline(0.0, color="k", lw=0.6)
    ax_err.axvspan(0.9, frame["eps"].max(), color="0.9")
    ax_err.set_xlabel(r"eccentricity ratio $\varepsilon$")
    ax_err.set_ylabel(f"error vs {labels.get(reference, reference)} [%]")
    ax_err.grid(True, alpha=0.3)
    fig.text(0.01, 0.005, "Journal displaced at rest, Gumbel cavitation. Grey band: $\\varepsilon$ > 0.9, where the paper "
             "switches to the dense grid\n(the coarse grid's error grows fast there). Dashed: grid-converged "
             "(Richardson) reference.", fontsize=7, va="bottom")
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    return fig


def plot_velocity_response(frame: pd.DataFrame):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(9.0, 7.0), sharex=True)
    for col, direction in enumerate(("radial", "tangential")):
        sub = frame[frame["direction"] == direction]
        for eps, g in sub.groupby("eps"):
            for row, comp in enumerate(("F1", "F2")):
                axes[row, col].plot(g["v"], g[comp], label=rf"$\varepsilon$ = {eps:g}")
        axes[1, col].set_xlabel(f"{direction} velocity [m/s]")
    for row, comp in enumerate(("F1", "F2")):
        for col in range(2):
            axes[row, col].set_yscale("symlog", linthresh=10.0)
            axes[row, col].grid(True, alpha=0.3)
        axes[row, 0].set_ylabel(f"${comp[0]}_{comp[1]}$ [N]")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle("Fig. 3 - film reaction against journal velocity")
    fig.tight_layout()
    return fig


def plot_orbits(panels: dict, clearance: float, t_settle: float, title: str):
    """Fig. 4: one panel per case; each panel overlays the trajectories of several models.

    ``panels``: {case_name: (label, {model_name: Trajectory})}.  The transient
    is drawn thin, the settled orbit thick; axes in units of the clearance
    with the clearance circle.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(panels)
    cols = min(4, n)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(3.3 * cols, 3.4 * rows), squeeze=False)
    # the reference is drawn wide and light underneath, the models narrower on top, so that a model
    # lying on the reference shows as a coloured line inside a grey band instead of hiding it
    styles = {"reference": dict(color="0.55"), "single": dict(color="tab:red", ls="--"),
              "split": dict(color="tab:blue", ls="-"), "best": dict(color="tab:green", ls="-")}
    settled_width = {"reference": 4.0}
    phi = np.linspace(0, 2 * np.pi, 200)
    for ax, (case, (label, trajs)) in zip(axes.flat, panels.items()):
        ax.plot(np.cos(phi), np.sin(phi), color="0.7", lw=0.8)
        for k, (name, tr) in enumerate(trajs.items()):
            st = styles.get(name, dict(color=f"C{k}"))
            x = tr.x / clearance
            done = tr.t >= t_settle
            ax.plot(x[:, 0], x[:, 1], lw=0.4, alpha=0.5, **st)
            ax.plot(x[-1:, 0], x[-1:, 1], marker="o", ms=3, **st)  # a settled point shows too
            ax.plot(x[done, 0], x[done, 1], lw=settled_width.get(name, 1.3),
                    label=name if tr.ok else f"{name} ({tr.status.split(':')[0]})", zorder=1 if name == "reference" else 2,
                    **st)
        ax.set_title(f"{case}) {label}", fontsize=9)
        ax.set_aspect("equal")
        ax.set_xlim(-1.05, 1.05)
        ax.set_ylim(1.05, -1.05)  # X2 (gravity) points down the page
        ax.set_xlabel("$X_1/c$", fontsize=8)
        ax.set_ylabel("$X_2/c$  (gravity: down)", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.legend(fontsize=6, loc="upper left")
    for ax in list(axes.flat)[n:]:
        ax.set_visible(False)
    fig.suptitle(title)
    fig.text(0.01, 0.005, "Journal-centre orbits in units of the radial clearance c; the grey circle is the clearance "
             "circle ($\\varepsilon$ = 1). X2 points along gravity, drawn downwards (the X2 axis is inverted).\nThin: the "
             "transient; thick: the settled orbit (t >= %g s); dot: the final position. Reference: wide grey band "
             "underneath the models." % t_settle, fontsize=7, va="bottom")
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    return fig


def plot_ensemble(table: pd.DataFrame, threshold_pct: float):
    """The ensemble study: orbit error per case and model (left), share answered by the reference (right).

    ``table``: ``comparison.ensemble_study``'s rows (case, model, rms_pct, hausdorff_pct, flagged_share).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = table[table.model != "reference"]
    models = list(dict.fromkeys(rows.model))
    cases = sorted(set(rows.case))
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 5.0), gridspec_kw={"width_ratios": [3, 2]})
    width = 0.8 / len(models)
    x = np.arange(len(cases))
    floor = 1e-3  # a hybrid that answered by the reference throughout lies on it (distance ~0): drawn at the floor
    for k, name in enumerate(models):
        r = rows[rows.model == name].set_index("case").reindex(cases)
        worst = np.maximum(r.rms_pct.to_numpy(float), r.hausdorff_pct.to_numpy(float))
        ax.bar(x + (k - (len(models) - 1) / 2) * width, np.clip(worst, floor, None), width, label=name)
    ax.axhline(threshold_pct, color="k", lw=1, ls="--", label=f"satisfactory below {threshold_pct:g} % of c")
    ax.set_yscale("log")
    ax.set_ylim(floor, None)
    readable_log_ticks(ax, "y")
    ax.set_xticks(x, cases)
    ax.set_xlabel("case (Fig. 4)")
    ax.set_ylabel("orbit distance from the reference [% of c]")
    ax.set_title("max(RMS, Hausdorff) over the settled orbit; bars at the bottom: below 0.001 %", fontsize=9)
    ax.legend(fontsize=7, ncol=4, loc="upper center", bbox_to_anchor=(0.5, -0.13))
    counted = [m for m in models if m.startswith("hybrid") or m == "ensemble"]
    width = 0.8 / max(len(counted), 1)
    for k, name in enumerate(counted):
        r = rows[rows.model == name].set_index("case").reindex(cases)
        bx.bar(x + (k - (len(counted) - 1) / 2) * width, 100 * r.flagged_share.to_numpy(float), width, label=name)
    bx.set_xticks(x, cases)
    bx.set_xlabel("case (Fig. 4)")
    bx.set_ylabel("force evaluations flagged [%]")
    top = float(np.nanmax(100 * rows.flagged_share.to_numpy(float), initial=0.0)) if counted else 0.0
    bx.set_ylim(0.0, max(1.0, 1.1 * top))  # a share: from 0, not around it
    if top == 0.0:
        bx.text(0.5, 0.5, "no force evaluation flagged in any case", transform=bx.transAxes, ha="center",
                fontsize=9, color="0.35")
    bx.set_title("ensemble: members disagree; hybrid: answered by the reference", fontsize=9)
    bx.legend(fontsize=7, ncol=3, loc="upper center", bbox_to_anchor=(0.5, -0.13))
    fig.suptitle("Seeds of the best surrogate, their ensemble and the hybrid with the reference")
    fig.tight_layout()
    return fig


def plot_equilibrium_locus(locus: pd.DataFrame, clearance: float):
    """The journal-centre locus of static equilibria for growing load (X2 down the page: gravity)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(9.0, 4.2))
    phi = np.linspace(0, 2 * np.pi, 200)
    ax.plot(np.cos(phi), np.sin(phi), color="0.7", lw=0.8)
    ax.plot(locus["X1"] / clearance, locus["X2"] / clearance, "o-", ms=3)
    ax.set_aspect("equal")
    ax.set_xlim(-1.05, 1.05)
    ax.set_ylim(1.05, -1.05)
    ax.set_xlabel("$X_1/c$")
    ax.set_ylabel("$X_2/c$ (gravity: down)")
    ax.set_title("equilibrium locus (load along $+X_2$)")
    ax2.semilogx(locus["sommerfeld"], locus["eps"], label="eccentricity ratio")
    ax2b = ax2.twinx()
    ax2b.semilogx(locus["sommerfeld"], locus["attitude_deg"].abs(), "C1--", label="attitude angle")
    ax2.set_xlabel("Sommerfeld number $S$")
    ax2.set_ylabel(r"eccentricity ratio $\varepsilon$")
    ax2.set_ylim(0, 1)
    ax2b.set_ylabel("attitude angle [deg]")
    ax2.grid(True, which="both", alpha=0.3)
    readable_log_ticks(ax2, "x")
    fig.tight_layout()
    return fig


def fig5_panels(runs: dict, clearance: float, out_dir, ramp: tuple[float, float]) -> list:
    """Fig. 5: rotor orbits under a growing imbalance, coloured by time, one file per controller
    (``fig5_a_dqn.png``: DQN control, ``fig5_b_none.png``: no control, ``fig5_c_mpc.png``: MPC), and
    ``fig5_amplitude.png``: orbit amplitude and sleeve position against time for all of them.

    ``runs``: {name: ``control.run_episode`` result}.  Axes in um; the grey circles are the
    clearances of the sleeve positions used (nominal dashed).
    """
    from pathlib import Path

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    from fluidfilm import io

    out = Path(out_dir)
    letters = {"dqn": "a", "none": "b", "mpc": "c"}
    titles = {"dqn": "DQN-agent control", "none": "no control", "mpc": "model predictive control"}
    written = []
    phi = np.linspace(0, 2 * np.pi, 200)
    lim = 1e6 * max(max(h["clearance"] for h in r["history"]) for r in runs.values()) * 1.05
    for name, r in runs.items():
        fig, ax = plt.subplots(figsize=(4.6, 4.2))
        for c_r in sorted({h["clearance"] for h in r["history"]}):
            ax.plot(1e6 * c_r * np.cos(phi), 1e6 * c_r * np.sin(phi), color="0.75", lw=0.8)
        ax.plot(1e6 * clearance * np.cos(phi), 1e6 * clearance * np.sin(phi), color="0.5", lw=0.8, ls="--")
        x = 1e6 * r["x"]
        seg = np.stack([x[:-1], x[1:]], axis=1)
        lc = LineCollection(seg, cmap="viridis", linewidths=0.6)  # type: ignore[arg-type]
        lc.set_array(r["t"][:-1])
        ax.add_collection(lc)
        cb = fig.colorbar(lc, ax=ax)
        cb.set_label("$t$ [s]")
        ax.set_aspect("equal")
        ax.set_xlim(-lim, lim)
        ax.set_ylim(lim, -lim)  # X2 (gravity) down the page
        ax.set_xlabel(r"$X_1$ [µm]")
        ax.set_ylabel(r"$X_2$ [µm]")
        ax.set_title(f"{letters.get(name, '')}) {titles.get(name, name)}: max amplitude "
                     f"{1e6 * r['max_amplitude_m']:.0f} µm", fontsize=9)
        fig.text(0.01, 0.005, "Grey circles: the radial clearance $c_r$ of each sleeve position used (dashed: the "
                 "nominal $c$).\n$X_2$ along gravity, drawn downwards. Colour: time along the imbalance ramp.",
                 fontsize=6.5, va="bottom")
        fig.tight_layout(rect=(0, 0.06, 1, 1))
        path = out / f"fig5_{letters.get(name, 'x')}_{name}.png"
        io.save_figure(fig, path, dpi=130)
        plt.close(fig)
        written.append(path)
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(6.4, 5.0), sharex=True)
    for name, r in runs.items():
        t = np.array([h["t"] for h in r["history"]])
        a1.plot(t, [1e6 * h["amplitude"] for h in r["history"]], label=titles.get(name, name), lw=1)
        a2.step(t, [1e3 * h["sleeve"] for h in r["history"]], where="pre", label=titles.get(name, name), lw=1)
    a1.set_ylabel("orbit amplitude [µm]")
    a1.set_title(f"imbalance ramp {ramp[0]:g} → {ramp[1]:g} kg m", fontsize=9)
    a1.legend(fontsize=8)
    a2.set_ylabel("sleeve position [mm]")
    a2.set_xlabel("$t$ [s]")
    fig.tight_layout()
    path = out / "fig5_amplitude.png"
    io.save_figure(fig, path, dpi=130)
    plt.close(fig)
    written.append(path)
    return written


def plot_grading_study(table: pd.DataFrame, title: str):
    """The grading study: held-out and orbit force error against dataset size (left) and against the time
    the reference model took to make the dataset (right), one point per job, labelled by the job.

    ``table``: ``grading.summarise``'s rows (job, n_samples, generation_s, held_out_rel_err_*,
    orbit_states_rel_err_*, n_satisfactory).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    series = (("held_out_rel_err_median", "held-out random states, median", "o"),
              ("held_out_rel_err_p99", "held-out random states, 99th percentile", "s"),
              ("orbit_states_rel_err_median", "states along the reference orbits, median", "^"),
              ("orbit_states_rel_err_p99", "states along the reference orbits, 99th percentile", "D"))
    if table["n_samples"].nunique() == 1:
        # one dataset for every job (the ablation): a size axis would stack every label on one point, so
        # one row per job, the errors along x
        return _plot_jobs_by_row(plt, table, series, title)
    fig, axes = plt.subplots(1, 2, figsize=(12, 5.0), sharey=True)
    for ax, xkey, xlabel in ((axes[0], "n_samples", "dataset size [samples]"),
                             (axes[1], "generation_s", "dataset generation time [s] (reference model, 2 cores)")):
        for key, label, marker in series:
            ax.scatter(table[xkey], 100 * table[key], marker=marker, label=label)
        for _, r in table.iterrows():
            cases = f" ({int(r['n_satisfactory'])}/7)" if "n_satisfactory" in r and not pd.isna(r["n_satisfactory"]) else ""
            label = str(r["job"]).replace("grading.", "")  # the swept keys are the grading's: say them once, in the title
            ax.annotate(f"{label}{cases}", (r[xkey], 100 * r["orbit_states_rel_err_p99"]), fontsize=6,
                        xytext=(3, 3), textcoords="offset points")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(xlabel)
        ax.grid(True, which="both", alpha=0.3)
        readable_log_ticks(ax, "x")
        readable_log_ticks(ax, "y")
    axes[0].set_ylabel("relative force error [%]")
    axes[0].legend(fontsize=7)
    fig.suptitle(f"{title}: labels are the jobs' swept values (grading.* shortened), (n/7) the Fig. 4 cases "
                 "within 2 % of c", fontsize=10)
    fig.tight_layout()
    return fig


def _plot_jobs_by_row(plt, table: pd.DataFrame, series, title: str):
    """The grading/ablation figure when every job has the same dataset: one row per job (its swept values and
    the Fig. 4 cases it passes), each error series a marker along a log x axis."""
    rows = table.reset_index(drop=True)
    labels = []
    for _, r in rows.iterrows():
        cases = f" ({int(r['n_satisfactory'])}/7)" if "n_satisfactory" in r and not pd.isna(r["n_satisfactory"]) else ""
        labels.append(str(r["job"]).replace("grading.", "") + cases)
    fig, ax = plt.subplots(figsize=(9, 1.2 + 0.38 * len(rows)))
    y = np.arange(len(rows))
    for key, label, marker in series:
        ax.scatter(100 * rows[key], y, marker=marker, label=label)
    ax.set_yticks(y, labels, fontsize=7)
    ax.invert_yaxis()
    ax.set_xscale("log")
    readable_log_ticks(ax, "x")
    ax.set_xlabel("relative force error [%]")
    ax.grid(True, which="both", axis="x", alpha=0.3)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.6 / (1.2 + 0.38 * len(rows)) - 0.1), ncol=2)
    n = int(rows["n_samples"].iloc[0])
    ax.set_title(f"{title}: every job on one dataset ({n:,} samples)\nrows: the swept values (grading.* "
                 "shortened), (n/7) the Fig. 4 cases within 2 % of c", fontsize=9)
    fig.tight_layout()
    return fig


def plot_error_map(maps: dict, title: str):
    """Where a surrogate's force errors sit: the 99th-percentile relative error per (eccentricity, |V|) bin,
    one heat map per state set (``maps``: name -> ``grading.binned_errors`` table), the number of states in
    each bin written in it."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    fig, axes = plt.subplots(1, len(maps), figsize=(6.2 * len(maps), 4.8), squeeze=False)
    vmax = max(float(t["p99"].max()) for t in maps.values()) * 100
    for ax, (name, t) in zip(axes[0], maps.items()):
        e_edges = np.unique(np.concatenate([t.eps_low, t.eps_high]))
        s_edges = np.unique(np.concatenate([t.speed_low, t.speed_high]))
        grid = np.full((len(s_edges) - 1, len(e_edges) - 1), np.nan)
        for _, r in t.iterrows():
            i = int(np.searchsorted(e_edges, r.eps_low))
            j = int(np.searchsorted(s_edges, r.speed_low))
            grid[j, i] = 100 * r.p99
            ax.text(i + 0.5, j + 0.5, f"{100 * r.p99:.3g}\n(n={int(r.n_states)})", ha="center", va="center", fontsize=6)
        mesh = ax.pcolormesh(np.arange(len(e_edges)), np.arange(len(s_edges)), grid, cmap="viridis",
                             norm=LogNorm(vmin=max(np.nanmin(grid), 1e-3), vmax=max(vmax, 1e-2)))
        ax.set_xticks(np.arange(len(e_edges)), [f"{e:g}" for e in e_edges], fontsize=7)
        ax.set_yticks(np.arange(len(s_edges)), [f"{1000 * s:g}" for s in s_edges], fontsize=7)
        ax.set_xlabel(r"eccentricity ratio $\varepsilon$")
        ax.set_ylabel(r"journal speed $|V|$ [mm/s]")
        ax.set_title(name, fontsize=9)
        fig.colorbar(mesh, ax=ax, label="99th percentile relative force error [%]")
    fig.suptitle(title)
    fig.tight_layout()
    return fig
