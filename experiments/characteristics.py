"""Static characteristics, K/C coefficients and the whirl threshold: reference vs surrogates.

    python experiments/characteristics.py                 # the DVC stage
    python experiments/characteristics.py characteristics=quick models.best=/path/to/best ...
"""
import math
from pathlib import Path

import hydra
import numpy as np
import pandas as pd
from omegaconf import DictConfig, OmegaConf

from fluidfilm import ReynoldsSolver, io, load_along_gravity, load_surrogate
from fluidfilm.workflow import tracking
from fluidfilm.characteristics import stability as stab
from fluidfilm.studies import characteristics as study
from fluidfilm.workflow.config import bearing_from_cfg
from fluidfilm.workflow.config_check import check_config


def _finite_or_none(obj):
    """Strict JSON: a threshold that does not exist (stable over the whole bracket) is written as null."""
    if isinstance(obj, dict):
        return {k: _finite_or_none(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_finite_or_none(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


@hydra.main(config_path="../conf", config_name="characteristics", version_base="1.3")
def main(cfg: DictConfig) -> None:
    check_config(cfg)  # a mistyped value or an unknown key is refused here, before any work
    ch = cfg.characteristics
    bearing = bearing_from_cfg(cfg.bearing)
    tables = Path(cfg.table_dir)
    figs = Path(cfg.figure_dir)
    out = {}

    # 1. static characteristics, both cavitation rules and feed assumptions
    static = pd.concat([study.static_table(bearing, cav, feed, ch.static.grid, ch.static.eps)
                        for cav in ch.static.cavitation for feed in ch.static.feeds], ignore_index=True)
    io.write_csv(tables / "static.csv", static)
    io.save_figure(study.plot_static(static), figs / "characteristics_static.png", dpi=120)

    # 2. validation: Raimondi & Boyd, short bearing
    rb = study.raimondi_boyd_table(ch.raimondi_boyd_grid)
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
    lt = study.lund_thomsen_table(ch.lund_thomsen_grid)
    io.write_csv(tables / "lund_thomsen.csv", lt)
    kc_cols = [c for c in lt.columns if c.endswith("_err_pct")]
    out["lund_thomsen"] = {"grid": lt.grid.iloc[0], "rows": len(lt),
                           "rows_two_typings": int(lt.two_typings.sum()),
                           "eps_max_err": float(lt.eps_err.abs().max()),
                           "phi_max_err_deg": float(lt.phi_err_deg.abs().max()),
                           "kc_max_err_pct": float(lt[kc_cols].max().max()),
                           "kc_max_err_pct_by_coefficient": {c[:-8]: float(lt[c].max()) for c in kc_cols},
                           "kc_max_err_pct_two_typings": float(lt[lt.two_typings][kc_cols].max().max())}
    sbt = study.short_bearing_table(ch.short_bearing.l_over_d, ch.short_bearing.grid, ch.short_bearing.eps)
    io.write_csv(tables / "short_bearing.csv", sbt)
    out["short_bearing"] = {
        "l_over_d": float(ch.short_bearing.l_over_d),
        "load_max_err_pct": float(sbt.load_err_pct.abs().max()),
        "attitude_max_err_deg": float(sbt.attitude_err_deg.abs().max()),
        "kc_max_err_scale_pct": float(max(sbt[f"{k}_err_scale_pct"].max() for k in study.DIRECT + study.CROSS)),
        "critical_mass_max_err_pct": float(np.nanmax(sbt.Mcrit_err_pct.abs())),
    }

    # 3. eight coefficients: reference (coarse and converged grids) and surrogates at the same loads
    ref = ReynoldsSolver(bearing, *ch.reference_grid, cavitation="gumbel")
    conv = ReynoldsSolver(bearing, *ch.converged_grid, cavitation="gumbel")
    surrogates = {name: load_surrogate(path) for name, path in cfg.models.items()}
    loads = study.loads_for_eccentricities(ref, ch.kc_eps)
    models = {"reference": ref, "reference_converged": conv, **surrogates}
    h = {"default": ch.h_rel_reference}  # surrogates: exact Jacobian (no step)
    kc = study.coefficient_table(models, loads, h, on_error="nan")  # a surrogate without an equilibrium: NaN
    io.write_csv(tables / "coefficients.csv", kc)
    # Errors against both references. The headline is the grid-converged one: the paper's 30 x 30 grid is
    # itself up to ~7 % (direct) / ~23 % (cross) off it above eps 0.7, and a surrogate, which learned that
    # grid's forces, need not share its derivative error (docs/characteristics.md, "Which reference").
    err = pd.concat([study.coefficient_errors(kc, "reference_converged").assign(against="reference_converged"),
                     study.coefficient_errors(kc, "reference").assign(against="reference")], ignore_index=True)
    io.write_csv(tables / "coefficient_errors.csv", err)
    io.save_figure(study.plot_coefficients(kc), figs / "characteristics_coefficients.png", dpi=120)
    out["kc_against"] = {"kc_max_rel_err": "reference_converged", "kc_max_rel_err_paper_grid": "reference"}
    out["grids"] = {"reference": list(ch.reference_grid), "reference_converged": list(ch.converged_grid)}
    for key, against, names in (("kc_max_rel_err", "reference_converged", ["reference", *surrogates]),
                                ("kc_max_rel_err_paper_grid", "reference", ["reference_converged", *surrogates])):
        out[key] = {}
        for name in names:
            out[key][name] = study.coefficient_error_summary(err[(err.against == against) & (err.model == name)])
    x0 = stab.operating_point(ref, load_along_gravity(study.loads_for_eccentricities(ref, [ch.step_study_eps])[0]))["X"]
    steps = study.step_table(ref, x0, ch.step_study_steps)
    steps_sur = {n: study.step_table(m, x0, ch.step_study_steps) for n, m in surrogates.items()}
    io.write_csv(tables / "step_study.csv", pd.concat([steps.assign(model="reference")] +
                                                     [s.assign(model=n) for n, s in steps_sur.items()]))
    timing = study.timing({"reference": ref, "reference_converged": conv, **surrogates}, x0, ch.timing_repeats, h)
    io.write_csv(tables / "timing.csv", timing)

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
    io.save_figure(study.plot_stability_map(kc, rotor_line, checks), figs / "characteristics_stability_map.png",
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
    out["timing_ms_per_coefficient_set"] = dict(zip(timing.model, timing.time_per_set_ms))
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
    out["metrics"] = metrics
    io.write_json(Path(cfg.out_json), _finite_or_none(out))
    with tracking.run(cfg.tracking, "characteristics", OmegaConf.to_container(cfg, resolve=True)):
        tracking.log_metrics({k: v for k, v in metrics.items() if math.isfinite(v)})
        for name in ("characteristics_static", "characteristics_coefficients", "characteristics_stability_map"):
            tracking.log_artifact(str(figs / f"{name}.png"))
        tracking.log_artifact(str(cfg.out_json))
    print(pd.Series(metrics).to_string())


if __name__ == "__main__":
    io.run_interruptible(main, "the bearing-characteristics study", "run the same command again")
