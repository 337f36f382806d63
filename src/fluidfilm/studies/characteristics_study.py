"""The characteristics study behind ``experiments/characteristics.py``: tables (DataFrames) and figures.

Every function takes plain mappings and force models and returns pandas
DataFrames (what goes to CSV) or a matplotlib figure (what goes to PNG);
the entry point only composes them.
"""
from __future__ import annotations

import functools
import math
import warnings

import numpy as np
import pandas as pd

from fluidfilm.core.bearing import JournalBearing
from fluidfilm.perf.benchmarking import median_seconds
from fluidfilm.reynolds import ReynoldsSolver
from fluidfilm.characteristics import coefficients as coef
from fluidfilm.characteristics import shortbearing as sb
from fluidfilm.characteristics import stability as stab
from fluidfilm.characteristics import static
from fluidfilm.characteristics import published as pub
from fluidfilm.characteristics.published import RAIMONDI_BOYD, short_bearing_kc
from fluidfilm.characteristics.static import load_along_gravity

DIRECT = ("Kxx", "Kyy", "Cxx", "Cyy")
CROSS = ("Kxy", "Kyx", "Cxy", "Cyx")


def static_table(bearing, cavitation: str, feed, grid, eps_values) -> pd.DataFrame:
    """eps, attitude, load, S, friction (power loss) and flows of one cavitation rule and feed assumption."""
    s = static.film_solver(bearing, cavitation, feed, int(grid[0]), int(grid[1]))
    rows = static.sommerfeld_sweep(s, eps_values)
    frame = pd.DataFrame(rows)
    frame.insert(0, "feed", str(feed))
    frame.insert(0, "cavitation", cavitation)
    return frame


def raimondi_boyd_table(grid, d: float = 0.04, clearance: float = 120e-6) -> pd.DataFrame:
    """Our values beside Raimondi & Boyd's at their eccentricities, for both feed assumptions."""
    rows = []
    for l_over_d, table in RAIMONDI_BOYD.items():
        b = JournalBearing(length=l_over_d * d, diameter=d, clearance=clearance, speed_rpm=3000.0,
                           viscosity=6.53e-4)
        for feed in ("max-film", "none"):
            s = static.film_solver(b, "swift-stieber", feed, int(grid[0]), int(grid[1]))
            for eps, S, phi, fv, qv, qs in table:
                r = static.static_point(s, eps)
                eps_s = static.eccentricity_at_sommerfeld(s, S, 0.02, 0.99)
                rows.append({"l_over_d": l_over_d, "feed": feed, "eps": eps, "eps_at_S_pub": eps_s,
                             "eps_at_S_err": eps_s - eps,
                             "S_pub": S, "S": r["sommerfeld"], "S_err_pct": 100 * (r["sommerfeld"] / S - 1),
                             "phi_pub": phi, "phi": r["attitude_deg"], "phi_err_deg": r["attitude_deg"] - phi,
                             "fric_pub": fv, "fric": r["friction_variable"],
                             "fric_err_pct": 100 * (r["friction_variable"] / fv - 1),
                             "flow_pub": qv, "flow": r["flow_variable"],
                             "flow_err_pct": 100 * (r["flow_variable"] / qv - 1),
                             "qs_ratio_pub": qs, "qs_ratio": r["side_flow_ratio"],
                             "qs_ratio_err_pct": 100 * (r["side_flow_ratio"] / qs - 1)})
    return pd.DataFrame(rows)


def lund_thomsen_bearing(l_over_d: float, grid, d: float = 0.1, clearance: float = 100e-6,
                         cavitation: str = "swift-stieber"):
    """Lund & Thomsen's two-axial-groove bearing on our grooved solver: grooves of 20 deg centred at +-90 deg
    from the load line (+X2), at zero gauge pressure, Swift-Stieber (their condition; ``cavitation="gumbel"``
    for a like-for-like peer that clips at zero).  (The dimensionless results depend only on L/D; the size,
    speed and viscosity are arbitrary.)"""
    from fluidfilm.reynolds.feed import GroovedReynoldsSolver

    b = JournalBearing(length=l_over_d * d, diameter=d, clearance=clearance, speed_rpm=3000.0, viscosity=0.02)
    return GroovedReynoldsSolver(b, int(grid[0]), int(grid[1]), cavitation=cavitation, groove_angle=math.pi / 2,
                                 n_grooves=2, groove_width=math.radians(pub.LUND_THOMSEN_GROOVE_WIDTH_DEG))


def load_at_sommerfeld(bearing, sommerfeld: float) -> float:
    """The load W [N] that puts ``bearing`` at the Sommerfeld number S = mu N L D (R/c)^2 / W (N in rev/s)."""
    if not (math.isfinite(sommerfeld) and sommerfeld > 0.0):
        raise ValueError(f"Sommerfeld number must be finite and > 0, got {sommerfeld!r}")
    return bearing.sommerfeld(1.0) / float(sommerfeld)


def lund_thomsen_table(grid, l_over_d=None, only_two_typings: bool = False, h_rel: float = 1e-4) -> pd.DataFrame:
    """Our equilibrium and seven printed coefficients beside Lund & Thomsen's (1978) at their Sommerfeld
    numbers (``lund_thomsen_point``; they print Byx = Bxy once).
    Per coefficient: ``<name>_err_pct`` = the part of |ours - published| beyond half a unit of the
    printed last digit, relative to max(|published|, 0.1 x the largest published term of that matrix)
    (the floor of ``coefficient_errors``: a term through zero is judged on the matrix's scale).
    ``l_over_d``: the tables to use (default both); ``only_two_typings``: only the rows both public
    typings share (``published.LUND_THOMSEN_TWO_TYPINGS``).
    """
    rows = []
    for ld, table in pub.LUND_THOMSEN_1978.items():
        if l_over_d is not None and ld not in l_over_d:
            continue
        solver = lund_thomsen_bearing(ld, grid)
        for values in table:
            p = dict(zip(pub.LUND_THOMSEN_COLUMNS, values))
            if only_two_typings and (ld, p["S"]) not in pub.LUND_THOMSEN_TWO_TYPINGS:
                continue
            ours = lund_thomsen_point(solver, p["S"], h_rel)
            row = {"l_over_d": ld, "S": p["S"], "two_typings": (ld, p["S"]) in pub.LUND_THOMSEN_TWO_TYPINGS,
                   "grid": f"{solver.n_theta}x{solver.n_z}", "eps_pub": p["eps"], "eps": ours.pop("eps"),
                   "phi_pub": p["phi"], "phi": ours.pop("phi")}
            row.update(eps_err=row["eps"] - p["eps"], phi_err_deg=row["phi"] - p["phi"])
            for name, value in ours.items():
                row[f"{name}_pub"] = p[name]
                row[name] = value
                row[f"{name}_err_pct"] = lund_thomsen_err_pct(value, p, name)
            rows.append(row)
    return pd.DataFrame(rows)


def lund_thomsen_point(solver, sommerfeld: float, h_rel: float = 1e-4) -> dict:
    """Equilibrium (eps, attitude phi [deg]) and the seven printed coefficients of a bearing model at a
    Sommerfeld number, load along +X2, in Lund & Thomsen's frame, names and units
    (``pub.LUND_THOMSEN_FRAME``: x along the load = our X2, y horizontal = our X1, so their Kxy is our
    K[1, 0], ``pub.LUND_THOMSEN_INDEX``); K = k c / W, B = b c omega / W."""
    b = solver.bearing
    load = load_at_sommerfeld(b, sommerfeld)
    eq = static.equilibrium(solver, static.load_along_gravity(load))
    kc = coef.reference_coefficients(solver, eq["X"], h_rel)
    scaled = {"K": kc["K"] * b.clearance / load, "C": kc["C"] * b.clearance * b.omega / load}
    return {"eps": eq["eps"], "phi": eq["attitude_deg"],
            **{name: scaled[m][i, j] for name, (m, i, j) in pub.LUND_THOMSEN_INDEX.items()}}


def lund_thomsen_err_pct(value: float, published: dict, name: str) -> float:
    """Error [%] of one coefficient ``name`` (Kxx ... Byy) against a Lund & Thomsen row ``published`` (a dict
    of ``LUND_THOMSEN_COLUMNS``): |value - published| beyond half a printed unit, relative to
    max(|published|, 0.1 x the largest published term of the same matrix, K or B)."""
    scale = max(abs(published[n]) for n in pub.LUND_THOMSEN_COEFFICIENTS if n[0] == name[0])
    excess = max(abs(value - published[name]) - pub.LUND_THOMSEN_PRINT_HALF_UNIT, 0.0)
    return 100.0 * excess / max(abs(published[name]), 0.1 * scale)


def short_bearing_table(l_over_d: float, grid, eps_values, d: float = 0.04, clearance: float = 120e-6):
    """Reference solver (Gumbel) at small L/D against Ocvirk: load, attitude, eight coefficients, critical mass."""
    b = JournalBearing(length=l_over_d * d, diameter=d, clearance=clearance, speed_rpm=3000.0, viscosity=6.53e-4)
    solver = ReynoldsSolver(b, int(grid[0]), int(grid[1]), "gumbel")
    rows = []
    for eps in eps_values:
        st = static.static_point(solver, eps)
        w = sb.load_capacity(b, eps)
        op = stab.operating_point(solver, static.load_along_gravity(w))
        ref = short_bearing_kc(op["eps"])
        row = {"eps": eps, "load_err_pct": 100 * (st["load_N"] / w - 1),
               "attitude_err_deg": st["attitude_deg"] - sb.attitude_angle_deg(eps)}
        kscale = max(abs(ref[k]) for k in coef.NAMES[:4])
        cscale = max(abs(ref[k]) for k in coef.NAMES[4:])
        for k in coef.NAMES:
            row[f"{k}_closed"] = ref[k]
            row[k] = op[k]
            row[f"{k}_err_pct"] = 100 * (op[k] / ref[k] - 1)
            row[f"{k}_err_scale_pct"] = 100 * abs(op[k] - ref[k]) / (kscale if k[0] == "K" else cscale)
        mc = stab.lund(ref)["critical_mass_bar"]
        row["Mcrit_closed"] = mc
        row["Mcrit"] = op["critical_mass_bar"]
        row["Mcrit_err_pct"] = 100 * (op["critical_mass_bar"] / mc - 1) if math.isfinite(mc) else float("nan")
        rows.append(row)
    return pd.DataFrame(rows)


def coefficient_table(models: dict, loads, h_rel: dict, on_error: str = "raise") -> pd.DataFrame:
    """Equilibrium, eight coefficients and Lund's numbers of every model at the same loads (same S).

    ``on_error``: what a load without an equilibrium does (``operating_point`` raises): ``"raise"``, or
    ``"nan"``: a row of NaN for that model and load, with a RuntimeWarning naming both (a poor surrogate
    in a study of several models must not stop the others, nor give numbers of a point that is none).
    """
    if on_error not in ("raise", "nan"):
        raise ValueError(f"on_error must be 'raise' or 'nan', got {on_error!r}")
    rows = []
    for name, model in models.items():
        for w in loads:
            try:
                op = stab.operating_point(model, static.load_along_gravity(float(w)),
                                          h_rel.get(name, h_rel.get("default", 1e-4)))
            except ValueError as err:
                if on_error == "raise":
                    raise
                warnings.warn(f"{name}: {err}; its row at {float(w):.6g} N is NaN", RuntimeWarning, stacklevel=2)
                nan = float("nan")
                rows.append({"model": name, "load_N": float(w), "sommerfeld": model.bearing.sommerfeld(float(w)),
                             "eps": nan, "attitude_deg": nan,
                             **{k: nan for k in coef.NAMES}, "whirl_ratio": nan, "critical_mass_bar": nan})
                continue
            rows.append({"model": name, "load_N": float(w), "sommerfeld": op["sommerfeld"], "eps": op["eps"],
                         "attitude_deg": op["attitude_deg"], **{k: op[k] for k in coef.NAMES},
                         "whirl_ratio": op["whirl_ratio"], "critical_mass_bar": op["critical_mass_bar"]})
    return pd.DataFrame(rows)


def coefficient_errors(table: pd.DataFrame, reference: str) -> pd.DataFrame:
    """Per model, load and coefficient: error against the reference at the same load.

    ``rel_err``: |K - K_ref| / max(|K_ref|, 0.1 * scale), scale the largest
    reference coefficient of the same matrix (stiffness or damping) at that
    load; the floor keeps a cross term passing through zero from turning a
    tiny absolute error into an unbounded ratio (where |K_ref| > 0.1 scale it
    is the plain relative error).  ``plain_rel_err`` is the unfloored ratio;
    ``scale_rel_err`` = |K - K_ref| / scale, the error as a share of the
    matrix (what a rotor model feels: a 20 % error of a cross term that is a
    tenth of the direct ones is 2 % of the matrix).
    """
    ref = table[table.model == reference].set_index("load_N")
    rows = []
    for _, r in table[table.model != reference].iterrows():
        q = ref.loc[r.load_N]
        kscale = max(abs(q[k]) for k in coef.NAMES[:4])
        cscale = max(abs(q[k]) for k in coef.NAMES[4:])
        for k in coef.NAMES:
            scale = kscale if k[0] == "K" else cscale
            diff = abs(r[k] - q[k])
            rows.append({"model": r.model, "load_N": r.load_N, "eps_ref": q.eps, "coefficient": k,
                         "kind": "direct" if k in DIRECT else "cross", "value": r[k], "reference": q[k],
                         "rel_err": diff / max(abs(q[k]), 0.1 * scale),
                         "plain_rel_err": diff / abs(q[k]) if q[k] != 0 else float("inf"),
                         "scale_rel_err": diff / scale})
    return pd.DataFrame(rows)


def coefficient_error_summary(errors: pd.DataFrame) -> dict:
    """Largest errors of one model's rows of ``coefficient_errors``: direct and cross terms (``rel_err``),
    share of the matrix (``scale``), per coefficient and per equilibrium (keyed by the reference's eps, 2 d.p.)."""
    if errors.empty:
        raise ValueError("no coefficient errors to summarise (no rows for this model and reference)")

    def worst(e):
        return {"direct": float(e[e.kind == "direct"].rel_err.max()), "cross": float(e[e.kind == "cross"].rel_err.max())}

    return {**worst(errors), "scale": float(errors.scale_rel_err.max()),
            "by_coefficient": {k: float(g.rel_err.max()) for k, g in errors.groupby("coefficient")},
            "by_eps": {f"{eps:.2f}": worst(g) for eps, g in errors.groupby("eps_ref")}}


def loads_for_eccentricities(model, eps_values) -> list[float]:
    """Loads [N] along +X2 at which ``model`` (rotationally symmetric) sits at each eccentricity."""
    c = model.bearing.clearance
    return [float(np.hypot(*model.forces(np.array([0.0, e * c]), np.zeros(2)))) for e in eps_values]


def step_table(model, x0, steps) -> pd.DataFrame:
    """Coefficients at a ladder of relative steps.  For a surrogate: central differences at each step,
    then the exact Jacobian (h_rel = 0), to show the differences converge to it."""
    from fluidfilm.surrogate import SurrogateForceModel
    exact = isinstance(model, SurrogateForceModel)
    method = coef.coefficients if exact else coef.reference_coefficients
    rows = [{"h_rel": h, **coef.dimensionless(method(model, x0, h), model.bearing)} for h in steps]
    if exact:
        rows.append({"h_rel": 0.0, **coef.dimensionless(coef.reference_coefficients(model, x0), model.bearing)})
    return pd.DataFrame(rows)


def timing(models: dict, x0, repeats: int = 5, h_rel: dict | None = None) -> pd.DataFrame:
    """Median wall time of one coefficient set (eight coefficients at a given position) per model."""
    rows = []
    for name, model in models.items():
        h = (h_rel or {}).get(name, 1e-4)
        # the first (untimed) call compiles
        med = median_seconds(functools.partial(coef.reference_coefficients, model, x0, h), repeats)
        rows.append({"model": name, "time_per_set_ms": 1e3 * med})
    return pd.DataFrame(rows)


# --- figures ---------------------------------------------------------------------------------------
# Axes span the reference models' values (the truth; a surrogate far off it is a finding, written on the
# figure, not a reason to flatten every curve onto the axis): see figure_style.limit_with_outliers.
def _is_reference(name: str) -> bool:
    return name.startswith("reference")


def _style(name: str) -> dict:
    return dict(marker="o", lw=2, ms=5) if _is_reference(name) else dict(marker=".", lw=1)


def plot_static(tables: pd.DataFrame):
    """Static characteristics against the Sommerfeld number, one line per (cavitation, feed)."""
    import matplotlib.pyplot as plt

    from fluidfilm.studies.figure_style import readable_log_ticks
    fig, ax = plt.subplots(1, 4, figsize=(18, 4))
    for (cav, feed), g in tables.groupby(["cavitation", "feed"]):
        lab = f"{cav}, feed {feed}"
        ax[0].semilogx(g.sommerfeld, g.eps, marker=".", label=lab)
        ax[1].semilogx(g.sommerfeld, g.attitude_deg, marker=".", label=lab)
        ax[2].loglog(g.sommerfeld, g.power_W, marker=".", label=lab)
        ax[3].semilogx(g.sommerfeld, 1e6 * g.side_flow_m3s, marker=".", label=lab)
    ax[0].set_ylabel(r"eccentricity ratio $\varepsilon$")
    ax[1].set_ylabel(r"attitude angle $\phi$ [deg]")
    ax[2].set_ylabel("power loss [W]")
    ax[3].set_ylabel(r"side flow [cm$^3$/s]")
    ax[0].set_ylim(0, 1)
    for a in ax:
        a.set_xlabel("Sommerfeld number $S$")
        a.grid(True, which="both", alpha=0.3)
        readable_log_ticks(a, "x")
    readable_log_ticks(ax[2], "y")
    ax[0].legend(fontsize=7)
    fig.suptitle("Static characteristics of the paper's bearing")
    fig.tight_layout()
    return fig


def plot_coefficients(table: pd.DataFrame):
    """The eight dimensionless coefficients along the equilibrium locus, per model; each panel spans the
    reference models' values, a surrogate's values beyond it are marked at the edge."""
    import matplotlib.pyplot as plt

    from fluidfilm.studies.figure_style import limit_with_outliers, reference_range
    fig, axes = plt.subplots(2, 4, figsize=(15, 7.5), sharex=True)
    models = list(dict.fromkeys(table.model))
    colors = {name: f"C{k}" for k, name in enumerate(models)}
    refs = table[table.model.map(_is_reference)]
    for ax, k in zip(axes.ravel(), coef.NAMES):
        series = []
        for name, g in table.groupby("model", sort=False):
            ax.plot(g.eps, g[k], color=colors[name], label=name, **_style(name))
            series.append((g.eps, g[k], name, colors[name]))
        if not refs.empty:
            lo, hi = reference_range(refs[k], pad=0.35)
            limit_with_outliers(ax, lo, hi, [s for s in series if not _is_reference(s[2])])
        sym = "K" if k.startswith("K") else "C"
        ax.set_title(f"${sym}_{{{k[1:]}}}$" + (r"$\,c/W$" if sym == "K" else r"$\,c\,\omega/W$"))
        ax.grid(True, alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel(r"eccentricity ratio $\varepsilon$ (equilibrium)")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=8)
    fig.suptitle(r"Dimensionless stiffness $K\,c/W$ and damping $C\,c\,\omega/W$ along the equilibrium locus"
                 " (axes: the reference's range; triangles: values beyond it)")
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    return fig


def plot_stability_map(table: pd.DataFrame, rotor_line: dict | None = None, checks: list[dict] | None = None):
    """Critical mass and whirl frequency ratio against the Sommerfeld number, per model.

    The critical mass axis spans the reference models' values (and the nonlinear checks); the whirl ratio
    axis spans 0 to 1 (a whirl at onset is sub-synchronous).  A surrogate's values beyond either are
    marked at the edge with the value written, instead of rescaling the axis.
    """
    import matplotlib.pyplot as plt

    from fluidfilm.studies.figure_style import limit_with_outliers, readable_log_ticks, reference_range
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.8))
    models = list(dict.fromkeys(table.model))
    colors = {name: f"C{k}" for k, name in enumerate(models)}
    mass, whirl = [], []
    for name, g in table.groupby("model", sort=False):
        m = np.isfinite(g.critical_mass_bar) & (g.critical_mass_bar > 0)
        ax[0].loglog(g.sommerfeld[m], g.critical_mass_bar[m], color=colors[name], label=name, **_style(name))
        ax[1].semilogx(g.sommerfeld, g.whirl_ratio, color=colors[name], label=name, **_style(name))
        if not _is_reference(name):
            mass.append((g.sommerfeld[m], g.critical_mass_bar[m], name, colors[name]))
            whirl.append((g.sommerfeld, g.whirl_ratio, name, colors[name]))
    s_lo, s_hi = table.sommerfeld.min(), table.sommerfeld.max()
    if rotor_line:
        s = np.geomspace(s_lo, s_hi, 50)
        ax[0].loglog(s, rotor_line["k"] * s**2, "k--", lw=1, label="paper rotor as speed varies")
    for chk in checks or []:
        ax[0].plot(chk["sommerfeld"], chk["mass_bar"], "v" if chk["ratio"] < 1 else "^", ms=10,
                   color="green" if chk["ratio"] < 1 else "red", ls="none",
                   label=f"nonlinear {chk['factor']:.2f}x: {'decays' if chk['ratio'] < 1 else 'grows'}")
    refs = table[table.model.map(_is_reference)]
    if not refs.empty:
        lo, hi = reference_range(refs.critical_mass_bar, pad=0.6, log=True,
                                 include=[c["mass_bar"] for c in checks or []])
        limit_with_outliers(ax[0], lo, hi, mass)
    limit_with_outliers(ax[1], 0.0, 1.0, whirl)
    ax[0].set_xlabel("Sommerfeld number $S$")
    ax[0].set_ylabel(r"critical mass $\bar{m}\,c\,\omega^2/W$ (unstable above)")
    ax[1].set_xlabel("Sommerfeld number $S$")
    ax[1].set_ylabel(r"whirl frequency ratio $\omega_\mathrm{whirl}/\omega$ at onset")
    for a in ax:
        a.set_xlim(s_lo / 1.3, s_hi * 1.3)
        readable_log_ticks(a, "x")
        a.grid(True, which="both", alpha=0.3)
        a.legend(fontsize=7, loc="best")
    fig.suptitle("Stability map (Lund's criterion, rigid rotor)")
    fig.tight_layout()
    return fig


# --- the study run by experiments/characteristics.py (conf/characteristics.yaml) ---

INPUTS = ("models",)
OUTPUTS = {"out_json": [""], "table_dir": [""],
           "figure_dir": ["characteristics_static.png", "characteristics_coefficients.png",
                          "characteristics_stability_map.png"]}


def tracking_run(cfg):
    return "characteristics", None


def _finite_or_none(obj):
    """Strict JSON: a threshold that does not exist (stable over the whole bracket) is written as null."""
    if isinstance(obj, dict):
        return {k: _finite_or_none(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_finite_or_none(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def headline_metrics(out: dict, surrogates: list[str], thr: dict) -> dict:
    """The study's headline numbers (what MLflow and reports/characteristics.json's ``metrics`` show): per
    model the largest K/C errors and the whirl-threshold error against both references."""
    metrics = {}
    for name in ["reference", *surrogates]:  # "reference": the paper's grid against the converged one
        for key, tail in (("kc_max_rel_err", ""), ("kc_max_rel_err_paper_grid", "_vs_paper_grid")):
            if name in out[key]:
                metrics[f"kc_max_rel_err_direct_{name}{tail}"] = out[key][name]["direct"]
                metrics[f"kc_max_rel_err_cross_{name}{tail}"] = out[key][name]["cross"]
                metrics[f"kc_max_scale_err_{name}{tail}"] = out[key][name]["scale"]
        metrics[f"whirl_threshold_rel_err_{name}"] = float(out["whirl_threshold_rel_err"][name])
        if name != "reference":
            metrics[f"whirl_threshold_rel_err_{name}_vs_paper_grid"] = float(
                out["whirl_threshold_rel_err_paper_grid"][name])
    metrics["lund_thomsen_kc_max_err_pct"] = out["lund_thomsen"]["kc_max_err_pct"]
    metrics["lund_thomsen_phi_max_err_deg"] = out["lund_thomsen"]["phi_max_err_deg"]
    metrics["whirl_threshold_rpm_reference"] = float(thr["reference"]["speed_rpm"])
    metrics["whirl_threshold_rpm_reference_converged"] = float(thr["reference_converged"]["speed_rpm"])
    return metrics


def run(cfg):
    """Static characteristics, K/C coefficients and the whirl threshold, reference vs surrogates: tables under
    ``table_dir``, figures under ``figure_dir``, the summary in ``out_json`` (``experiments/characteristics.py``)."""
    from pathlib import Path

    from fluidfilm import io, load_surrogate
    from fluidfilm.workflow.config import bearing_from_cfg
    from fluidfilm.workflow.tracking import Logged

    ch = cfg.characteristics
    bearing = bearing_from_cfg(cfg.bearing)
    tables = Path(cfg.table_dir)
    figs = Path(cfg.figure_dir)
    out = {}

    # 1. static characteristics, both cavitation rules and feed assumptions
    static = pd.concat([static_table(bearing, cav, feed, ch.static.grid, ch.static.eps)
                        for cav in ch.static.cavitation for feed in ch.static.feeds], ignore_index=True)
    io.write_csv(tables / "static.csv", static)
    io.save_figure(plot_static(static), figs / "characteristics_static.png", dpi=120)

    # 2. validation: Raimondi & Boyd, short bearing
    rb = raimondi_boyd_table(ch.raimondi_boyd_grid)
    io.write_csv(tables / "raimondi_boyd.csv", rb)
    fed = rb[(rb.feed == "max-film") & (rb.eps <= 0.9)]
    out["raimondi_boyd"] = {"S_max_err_pct": float(fed.S_err_pct.abs().max()),
                            "eps_at_S_max_err": float(fed.eps_at_S_err.abs().max()),
                            "phi_max_err_deg": float(fed.phi_err_deg.abs().max()),
                            "friction_max_err_pct": float(fed.fric_err_pct.abs().max()),
                            "flow_max_err_pct": float(fed.flow_err_pct.abs().max()),
                            "side_flow_ratio_max_err_pct": float(fed.qs_ratio_err_pct.abs().max()),
                            "phi_max_err_deg_no_feed": float(rb[(rb.feed == "none") & (rb.eps <= 0.9)]
                                                             .phi_err_deg.abs().max())}
    lt = lund_thomsen_table(ch.lund_thomsen_grid)
    io.write_csv(tables / "lund_thomsen.csv", lt)
    kc_cols = [c for c in lt.columns if c.endswith("_err_pct")]
    out["lund_thomsen"] = {"grid": lt.grid.iloc[0], "rows": len(lt),
                           "rows_two_typings": int(lt.two_typings.sum()),
                           "eps_max_err": float(lt.eps_err.abs().max()),
                           "phi_max_err_deg": float(lt.phi_err_deg.abs().max()),
                           "kc_max_err_pct": float(lt[kc_cols].max().max()),
                           "kc_max_err_pct_by_coefficient": {c[:-8]: float(lt[c].max()) for c in kc_cols},
                           "kc_max_err_pct_two_typings": float(lt[lt.two_typings][kc_cols].max().max())}
    sbt = short_bearing_table(ch.short_bearing.l_over_d, ch.short_bearing.grid, ch.short_bearing.eps)
    io.write_csv(tables / "short_bearing.csv", sbt)
    out["short_bearing"] = {
        "l_over_d": float(ch.short_bearing.l_over_d),
        "load_max_err_pct": float(sbt.load_err_pct.abs().max()),
        "attitude_max_err_deg": float(sbt.attitude_err_deg.abs().max()),
        "kc_max_err_scale_pct": float(max(sbt[f"{k}_err_scale_pct"].max() for k in DIRECT + CROSS)),
        "critical_mass_max_err_pct": float(np.nanmax(sbt.Mcrit_err_pct.abs())),
    }

    # 3. eight coefficients: reference (coarse and converged grids) and surrogates at the same loads
    ref = ReynoldsSolver(bearing, *ch.reference_grid, cavitation="gumbel")
    conv = ReynoldsSolver(bearing, *ch.converged_grid, cavitation="gumbel")
    surrogates = {name: load_surrogate(path) for name, path in cfg.models.items()}
    loads = loads_for_eccentricities(ref, ch.kc_eps)
    models = {"reference": ref, "reference_converged": conv, **surrogates}
    h = {"default": ch.h_rel_reference}  # surrogates: exact Jacobian (no step)
    kc = coefficient_table(models, loads, h, on_error="nan")  # a surrogate without an equilibrium: NaN
    io.write_csv(tables / "coefficients.csv", kc)
    # Errors against both references. The headline is the grid-converged one: the paper's 30 x 30 grid is
    # itself up to ~7 % (direct) / ~23 % (cross) off it above eps 0.7, and a surrogate, which learned that
    # grid's forces, need not share its derivative error (docs/characteristics.md, "Which reference").
    err = pd.concat([coefficient_errors(kc, "reference_converged").assign(against="reference_converged"),
                     coefficient_errors(kc, "reference").assign(against="reference")], ignore_index=True)
    io.write_csv(tables / "coefficient_errors.csv", err)
    io.save_figure(plot_coefficients(kc), figs / "characteristics_coefficients.png", dpi=120)
    out["kc_against"] = {"kc_max_rel_err": "reference_converged", "kc_max_rel_err_paper_grid": "reference"}
    out["grids"] = {"reference": list(ch.reference_grid), "reference_converged": list(ch.converged_grid)}
    for key, against, names in (("kc_max_rel_err", "reference_converged", ["reference", *surrogates]),
                                ("kc_max_rel_err_paper_grid", "reference", ["reference_converged", *surrogates])):
        out[key] = {}
        for name in names:
            out[key][name] = coefficient_error_summary(err[(err.against == against) & (err.model == name)])
    x0 = stab.operating_point(ref, load_along_gravity(loads_for_eccentricities(ref, [ch.step_study_eps])[0]))["X"]
    steps = step_table(ref, x0, ch.step_study_steps)
    steps_sur = {n: step_table(m, x0, ch.step_study_steps) for n, m in surrogates.items()}
    io.write_csv(tables / "step_study.csv", pd.concat([steps.assign(model="reference")] +
                                                     [s.assign(model=n) for n, s in steps_sur.items()]))
    timings = timing({"reference": ref, "reference_converged": conv, **surrogates}, x0, ch.timing_repeats, h)
    io.write_csv(tables / "timing.csv", timings)

    # 4. stability: threshold speed of the paper's rotor, per model; nonlinear check with the reference
    mass = float(cfg.rotor.mass) * float(cfg.rotor.load_share)
    load = mass * float(cfg.rotor.gravity)
    thr = {}
    for name, m in models.items():
        try:
            thr[name] = stab.threshold_speed(m, mass, load_along_gravity(load), tuple(ch.threshold.speed_bracket),
                                             h.get(name, h["default"]))
        except ValueError as err:  # e.g. a poor surrogate unstable over the whole bracket: recorded, not fatal
            thr[name] = {"speed_rad_s": float("nan"), "speed_rpm": float("nan"), "note": str(err)}
    checks = []
    make = lambda b: ReynoldsSolver(b, *ch.nonlinear.grid, cavitation="gumbel")  # noqa: E731
    for f in ch.nonlinear.factors:
        rpm = f * thr["reference"]["speed_rpm"]
        r = stab.nonlinear_check(make, bearing, mass, rpm, ch.nonlinear.perturbation, ch.nonlinear.n_periods)
        om = rpm * 2 * math.pi / 60
        checks.append({"factor": f, "speed_rpm": rpm, "eps_eq": r["eps_eq"], "amp_first": r["amp_first"],
                       "amp_last": r["amp_last"], "ratio": r["ratio"], "contact": r["contact"], "status": r["status"],
                       "sommerfeld": bearing.sommerfeld(load) * om / bearing.omega,
                       "mass_bar": mass * bearing.clearance * om**2 / load})
    io.write_csv(tables / "nonlinear_checks.csv", pd.DataFrame(checks))
    s_per_rad = bearing.sommerfeld(load) / bearing.omega
    rotor_line = {"k": mass * bearing.clearance / load / s_per_rad**2}
    io.save_figure(plot_stability_map(kc, rotor_line, checks), figs / "characteristics_stability_map.png",
                   dpi=120)
    io.write_csv(tables / "thresholds.csv", pd.DataFrame([{"model": n, **t} for n, t in thr.items()]))
    out["threshold"] = {n: {k: (v if isinstance(v, str) else float(v)) for k, v in t.items()} for n, t in thr.items()}
    for key, against in (("whirl_threshold_rel_err", "reference_converged"),
                         ("whirl_threshold_rel_err_paper_grid", "reference")):
        th_ref = thr[against]["speed_rad_s"]
        out[key] = {n: abs(t["speed_rad_s"] / th_ref - 1) for n, t in thr.items() if n != against}
    out["nonlinear_checks"] = checks
    out["bracket_holds"] = bool(checks[0]["ratio"] < 1 < checks[-1]["ratio"] or checks[-1]["contact"])
    out["rotor_mass_per_bearing_kg"] = mass
    out["timing_ms_per_coefficient_set"] = dict(zip(timings.model, timings.time_per_set_ms))
    metrics = headline_metrics(out, list(surrogates), thr)
    out["metrics"] = metrics
    io.write_json(Path(cfg.out_json), _finite_or_none(out))
    print(pd.Series(metrics).to_string())
    figures = [figs / f"{name}.png" for name in ("characteristics_static", "characteristics_coefficients",
                                                  "characteristics_stability_map")]
    return Logged({k: v for k, v in metrics.items() if math.isfinite(v)}, [*figures, str(cfg.out_json)])
