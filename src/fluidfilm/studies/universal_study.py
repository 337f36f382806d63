"""The universal plain-bearing surrogate: its dataset, its training, and its accuracy on bearings it never
saw (``experiments/universal.py``; ``part`` = dataset | train | evaluate).

- ``dataset``: the dimensionless dataset (``data.universal``) on Dask, resumable, checksummed.
- ``train``: one network per cavitation rule (``surrogate.training.universal_fit``, Lightning, logged to MLflow),
  written to ``models_dir`` as ``<rule>.npz`` + ``SHA256SUMS``, and ``reports/universal_train.json``: whether they
  are the shipped weights bit for bit.  The package ships a copy of these under
  ``src/fluidfilm/surrogate/universal_weights`` (``make universal-weights`` copies them there): the
  evaluation below always measures the shipped weights, what a user gets.  ``dataset`` and ``train`` run as
  ``make universal-train`` (about 15 min on two cores), outside ``make reproduce`` and its 60-minute budget;
  their output, the weights, is committed.
- ``evaluate``: the shipped model against the grid-converged reference on held-out L/D values with random
  sizes, clearances, speeds and viscosities (force errors, an error map over (L/D, eps)); K and C along
  the equilibrium locus; the whirl threshold; Raimondi & Boyd's S and attitude; the seven Fig. 4 cases
  on the paper's bearing; the cost per force beside the best model's shape.  Writes
  ``reports/universal.json`` and figures.
"""
from __future__ import annotations

from typing import Any

import math
import os
import shutil
import time
from pathlib import Path

import numpy as np
import pandas as pd

from fluidfilm import io
from fluidfilm.core.bearing import JournalBearing
from fluidfilm.data.spec import config_hash
from fluidfilm.workflow.config import bearing_from_cfg
from fluidfilm.workflow.config_check import ConfigError
from fluidfilm.workflow.entry import plain
from fluidfilm.workflow.tracking import Logged

PARTS = ("dataset", "train", "evaluate")
#: what ``part=train`` (``make universal-train``, outside the pipeline) writes beside the weights and commits: the
#: comparison of its weights with the shipped ones (``compare_weights``), the machine, the date and the wall time
TRAIN_REPORT = "universal_train.json"


def check(cfg) -> None:
    from fluidfilm.surrogate.activations import HIDDEN_ACTIVATIONS

    if cfg.part not in PARTS:
        raise ConfigError(f"part={cfg.part!r}; choose one of {PARTS}")
    if cfg.train.activation not in HIDDEN_ACTIVATIONS:
        raise ConfigError(f"train.activation={cfg.train.activation!r}; choose one of {HIDDEN_ACTIVATIONS}")


def outputs(cfg) -> dict:
    if cfg.part == "dataset":
        return {"dataset_dir": [""]}
    if cfg.part == "train":
        return {"models_dir": [""], "report_dir": [TRAIN_REPORT]}
    return {"report_dir": ["universal.json", "universal_errors.csv"],
            "figure_dir": ["universal_error_map.png", "universal_kc.png"]}


def tracking_run(cfg):
    return (f"universal_{cfg.part}", None) if cfg.part != "dataset" else (None, None)


# ------------------------------------------------------------------------------------------------ dataset
def _dataset(cfg) -> Logged:
    from fluidfilm.data.universal import UniversalSpec, generate_universal

    spec = UniversalSpec.from_cfg(dict(cfg.layout))
    meta = generate_universal(spec, cfg.dataset_dir, scheduler=cfg.dask.scheduler, n_workers=cfg.dask.n_workers)
    print(f"universal dataset: {meta['n_samples']} rows in {cfg.dataset_dir} "
          f"({meta['generation_seconds_total']:.0f} s of generation)")
    return Logged({"n_samples": meta["n_samples"], "generation_seconds": meta["generation_seconds_total"]})


# ------------------------------------------------------------------------------------------------ training
def for_rule(value, rule: str, key: str):
    """A ``train`` setting for one cavitation rule: one value for both rules, or a mapping rule -> value.

    Examples
    --------
    >>> for_rule(2.0, "gumbel", "derivative_weight"), for_rule({"gumbel": [3, 4], "swift-stieber": 5}, "gumbel", "steps")
    (2.0, [3, 4])
    """
    from collections.abc import Mapping

    if not isinstance(value, Mapping):  # a config node is a Mapping too
        return value
    if rule not in value:
        raise ConfigError(f"train.{key}={value!r}: give one value for both rules or one per rule ({rule!r} is missing)")
    return value[rule]


def derivative_weight_for(value, rule: str) -> float:
    """``train.derivative_weight`` for one rule: one number for both, or a mapping rule -> number.

    Examples
    --------
    >>> derivative_weight_for(2.0, "gumbel"), derivative_weight_for({"gumbel": 2, "swift-stieber": 0.5}, "swift-stieber")
    (2.0, 0.5)
    """
    weight = for_rule(value, rule, "derivative_weight")
    if isinstance(weight, bool) or not isinstance(weight, (int, float)):
        raise ConfigError(f"train.derivative_weight={value!r}: give one number or one per rule, not {weight!r}")
    return float(weight)


def _train(cfg) -> Logged:
    from fluidfilm.data.universal import load_universal
    from fluidfilm.surrogate.training.universal_fit import train_universals, write_weights
    from fluidfilm.workflow import tracking

    t0 = time.perf_counter()
    out = Path(cfg.models_dir)
    metrics: dict[str, Any] = {}
    parent = tracking.active_run()
    tr = cfg.train
    fits, metas, factories = {}, {}, {}
    for rule in tr.rules:
        frame, meta = load_universal(cfg.dataset_dir, rule)
        metas[rule] = (frame, meta)
        if parent is not None:
            factories[rule] = tracking.child_logger_factory(parent, cfg.tracking, f"universal_{rule}")
        settings = {k: for_rule(plain(tr)[k], rule, k) for k in ("steps", "max_minutes", "refine_steps", "refine_minutes")}
        # finished regions and the running fit's checkpoint: a rerun continues them.  Keyed by the data and
        # the first phase's settings (the second phase keys its own files: train_universal)
        first = {k: plain(tr)[k] for k in ("boundaries", "blend_width", "overlap", "power", "width", "floor_share",
                                           "seed")} | {k: settings[k] for k in ("steps", "max_minutes")}
        if tr.activation != "tanh":   # (tanh fits keep the folders they had before there was a choice)
            first["activation"] = str(tr.activation)
        work = Path(cfg.cache_dir) / f"{rule}-{meta['config_hash'][:12]}-{config_hash(first)[:8]}"
        fits[rule] = dict(frame=frame, boundaries=list(tr.boundaries), blend_width=tr.blend_width,
                          overlap=tr.overlap, power=tr.power, width=tr.width, floor_share=tr.floor_share,
                          seed=tr.seed, work_dir=work, what=f"{rule} ",
                          derivative_weight=derivative_weight_for(tr.derivative_weight, rule),
                          logger_for=factories[rule].logger_for if rule in factories else None,
                          derivative_rows=str(tr.derivative_rows), activation=str(tr.activation), **settings)
    try:
        # both rules' regions in one pool of workers, the largest first (weights as fitted one rule at a time)
        results = train_universals(fits, workers=tr.workers)
    except BaseException as exc:
        # a stopped worker could not end the MLflow run of the phase it was training
        for factory in factories.values():
            factory.end_open_runs("KILLED" if isinstance(exc, KeyboardInterrupt) else "FAILED")
        raise
    for rule, fit in results.items():
        frame, meta = metas[rule]
        weight = fits[rule]["derivative_weight"]
        info = {"dataset_hash": meta["config_hash"], "n_rows": int(len(frame)),
                **{k: v for k, v in fit.items() if k.startswith("val_") or k in ("train_seconds", "train_wall_s", "workers")},
                "threads_per_fit": 1,
                "width": int(tr.width), "depth": 1, "activation": str(tr.activation), "optimizer": "levenberg-marquardt",
                "derivative_weight": weight, "derivative_rows": str(tr.derivative_rows),
                "regions": [{k: v for k, v in reg.items() if isinstance(v, (int, float))} for reg in fit["regions"]]}
        write_weights(fit, rule, meta["spec"]["eps_max"], (meta["spec"]["ld_min"], meta["spec"]["ld_max"]), info,
                      directory=out)
        key = rule.replace("-", "_")
        metrics |= {f"{key}_val_rel_median": fit["val_rel_median"], f"{key}_val_rel_p99": fit["val_rel_p99"],
                    f"{key}_train_seconds": fit["train_seconds"]}
        print(f"{rule}: validation relative error of G (worst region) median {100 * fit['val_rel_median']:.3f} %, "
              f"p99 {100 * fit['val_rel_p99']:.2f} %, {fit['train_seconds']:.0f} s of one core each; "
              f"both rules' regions {fit['train_wall_s']:.0f} s on {fit['workers']} workers")
    # the training's one claim: the same data and settings give the weights the package ships, bit for bit
    from fluidfilm.perf.benchmarking import machine

    reproduced = compare_weights(out)
    report = Path(cfg.report_dir) / TRAIN_REPORT
    io.write_json(report, {"weights_reproduced": reproduced, "machine": machine(), "date": time.strftime("%Y-%m-%d"),
                           "wall_s": time.perf_counter() - t0, "models_dir": str(out),
                           "train_seconds": {rule: fit["train_seconds"] for rule, fit in results.items()}})
    print(f"universal: {report}: " + "; ".join(f"{rule} {'identical' if r.get('identical') else r}"
                                                for rule, r in reproduced.items()))
    return Logged(metrics, [out, report])


# ------------------------------------------------------------------------------------------------ evaluation
def reference_grid(ld: float, cavitation: str, eps: float, tol: float) -> tuple[int, int]:
    """The grid-converged reference for a held-out L/D: one step finer than the grid the convergence check
    accepts at ``tol`` (``data.universal.converged_grid``)."""
    from fluidfilm.data.universal import N_THETA_LADDER, _n_z, converged_grid

    nt, _, _ = converged_grid(ld, cavitation, eps, tol)
    finer = N_THETA_LADDER[min(N_THETA_LADDER.index(nt) + 1, len(N_THETA_LADDER) - 1)]
    return finer, _n_z(finer, ld)


def random_bearing(ld: float, rng, ranges) -> JournalBearing:
    """A bearing of slenderness ``ld`` with diameter, clearance, speed and viscosity drawn (log-uniform) from
    ``ranges`` (diameter_m, clearance_m, speed_rpm, viscosity_pa_s: [low, high] each)."""
    def draw(key):
        lo, hi = ranges[key]
        return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))

    d = draw("diameter_m")
    return JournalBearing(length=ld * d, diameter=d, clearance=draw("clearance_m"), speed_rpm=draw("speed_rpm"),
                          viscosity=draw("viscosity_pa_s"))


def held_out_force_errors(cfg, rng) -> pd.DataFrame:
    """Relative force errors of the shipped model against the converged reference at random states of random
    bearings at each held-out L/D (rows: rule, L/D, bearing, eps, |V| / (c omega), rel_err), and at the same
    states those of the reference itself on each coarser grid of the ladder (``rel_err_grid_<n_theta>``, with
    ``_n_z``'s axial count): the model's and the coarse grids' errors on one yardstick, which
    ``matched_grid`` reads."""
    from fluidfilm import ReynoldsSolver
    from fluidfilm.data.universal import N_THETA_LADDER, _n_z
    from fluidfilm.surrogate.universal import universal_bearing

    ev = cfg.evaluate
    rows = []
    for rule in ev.rules:
        for ld in ev.held_out_ld:
            grid = reference_grid(float(ld), rule, float(ev.eps_max), float(ev.reference_tol))
            for k in range(int(ev.n_bearings)):
                b = random_bearing(float(ld), rng, ev.ranges)
                model = universal_bearing(b, rule)
                ref = ReynoldsSolver(b, grid[0], grid[1], cavitation=rule)
                n = int(ev.n_states)
                eps = float(ev.eps_max) * np.sqrt(rng.random(n))   # uniform over the disc eps <= eps_max
                ang = 2 * np.pi * rng.random(n)
                X = b.clearance * np.stack([eps * np.sin(ang), eps * np.cos(ang)], axis=1)
                vmag = float(ev.v_max) * np.sqrt(rng.random(n))    # |V| <= v_max c omega, uniform over the disc
                vang = 2 * np.pi * rng.random(n)
                V = b.clearance * b.omega * np.stack([vmag * np.cos(vang), vmag * np.sin(vang)], axis=1)
                F = model.forces(X, V)
                F_ref = ref.forces(X, V)
                fn, bp = model.batch_force_kernel("float32", private=True)
                F32 = np.empty_like(F)
                fn(bp, np.ascontiguousarray(X), np.ascontiguousarray(V), F32)
                rel = np.hypot(*(F - F_ref).T) / np.hypot(*F_ref.T)
                rel32 = np.hypot(*(F32 - F_ref).T) / np.hypot(*F_ref.T)
                coarse = {f"rel_err_grid_{nt}": np.hypot(*(ReynoldsSolver(b, nt, _n_z(nt, float(ld)), cavitation=rule)
                                                           .forces(X, V) - F_ref).T) / np.hypot(*F_ref.T)
                          for nt in N_THETA_LADDER if nt < grid[0]}
                rows.append(pd.DataFrame({"cavitation": rule, "ld": float(ld), "bearing": k, "eps": eps,
                                          "v_rel": vmag, "rel_err": rel, "rel_err_float32": rel32,
                                          "n_theta": grid[0], "n_z": grid[1],
                                          "speed_rpm": b.speed_rpm, "viscosity": b.viscosity,
                                          "clearance": b.clearance, **coarse}))
            print(f"  {rule} L/D={ld}: reference grid {grid[0]} x {grid[1]}, median "
                  f"{100 * rows[-1].rel_err.median():.3f} % (last bearing)", flush=True)
    return pd.concat(rows, ignore_index=True)


def kc_along_locus(cfg) -> pd.DataFrame:
    """K and C of the shipped model and of the converged reference at the reference's equilibria with eps
    ``kc_eps``, for each held-out L/D (Gumbel and Swift-Stieber); ``coefficient_errors`` rows."""
    from fluidfilm import ReynoldsSolver
    from fluidfilm.studies.characteristics_study import coefficient_errors, coefficient_table, loads_for_eccentricities
    from fluidfilm.surrogate.universal import universal_bearing

    ev = cfg.evaluate
    out = []
    for rule in ev.kc_rules:
        for ld in ev.held_out_ld:
            b = JournalBearing(length=0.05 * float(ld), diameter=0.05, clearance=75e-6, speed_rpm=5000.0,
                               viscosity=0.02)
            nt, nz = reference_grid(float(ld), rule, float(max(ev.kc_eps)), float(ev.reference_tol))
            ref = ReynoldsSolver(b, nt, nz, cavitation=rule)
            loads = loads_for_eccentricities(ref, list(ev.kc_eps))
            table = coefficient_table({"reference": ref, "universal": universal_bearing(b, rule)}, loads,
                                      {"default": 1e-4})
            errors = coefficient_errors(table, "reference")
            out.append(errors.assign(cavitation=rule, ld=float(ld)))
    return pd.concat(out, ignore_index=True)


def whirl_thresholds(cfg) -> pd.DataFrame:
    """Onset speed of oil whirl, shipped model vs converged reference, per held-out L/D (Gumbel)."""
    from fluidfilm import ReynoldsSolver
    from fluidfilm.characteristics import threshold_speed
    from fluidfilm.characteristics.static import load_along_gravity
    from fluidfilm.surrogate.universal import universal_bearing

    ev = cfg.evaluate
    rows = []
    for ld in ev.held_out_ld:
        b = JournalBearing(length=0.05 * float(ld), diameter=0.05, clearance=75e-6, speed_rpm=3000.0,
                           viscosity=0.01)
        nt, nz = reference_grid(float(ld), "gumbel", 0.8, float(ev.reference_tol))
        mass = float(ev.whirl_mass_kg)
        W = load_along_gravity(mass * 9.81)
        # the bracket starts where the universal model still has an equilibrium inside its data (eps <= 0.95)
        t_ref = threshold_speed(ReynoldsSolver(b, nt, nz), mass=mass, load=W, speed_bracket=(0.5, 20.0))
        t_uni = threshold_speed(universal_bearing(b), mass=mass, load=W, speed_bracket=(0.5, 20.0))
        rows.append({"ld": float(ld), "reference_rpm": t_ref["speed_rpm"], "universal_rpm": t_uni["speed_rpm"],
                     "eps_reference": t_ref.get("eps", float("nan")), "rel_err":
                     abs(t_uni["speed_rpm"] / t_ref["speed_rpm"] - 1.0)})
    return pd.DataFrame(rows)


def raimondi_boyd(cfg) -> pd.DataFrame:
    """S and attitude of the shipped Swift-Stieber model at Raimondi & Boyd's eccentricities, beside the
    published values and our plain-bearing reference (no feed groove; R&B feed at the maximum film)."""
    from fluidfilm import ReynoldsSolver
    from fluidfilm.characteristics.published import RAIMONDI_BOYD
    from fluidfilm.surrogate.universal import universal_bearing

    rows = []
    for ld, table in RAIMONDI_BOYD.items():
        b = JournalBearing(length=0.04 * ld, diameter=0.04, clearance=60e-6, speed_rpm=3000.0, viscosity=0.01)
        model = universal_bearing(b, "swift-stieber")
        nt, nz = reference_grid(float(ld), "swift-stieber", 0.9, float(cfg.evaluate.reference_tol))
        ref = ReynoldsSolver(b, nt, nz, cavitation="swift-stieber")
        for eps, S_pub, phi_pub, *_ in table:
            if eps > model.eps_max:
                continue
            x = np.array([0.0, eps * b.clearance])
            vals = {}
            for name, m in (("universal", model), ("reference", ref)):
                F = m.forces(x, np.zeros(2))
                # the attitude angle between the load (-F) and the line of centres (+X2), positive as tabulated
                vals[name] = (b.sommerfeld(float(np.hypot(*F))), abs(math.degrees(math.atan2(-F[0], -F[1]))))
            rows.append({"ld": ld, "eps": eps, "S_pub": S_pub, "phi_pub": phi_pub,
                         "S": vals["universal"][0], "phi": vals["universal"][1],
                         "S_ref": vals["reference"][0], "phi_ref": vals["reference"][1],
                         "S_err_pct": 100 * (vals["universal"][0] / S_pub - 1),
                         "phi_err_pct": 100 * (vals["universal"][1] / phi_pub - 1),
                         "S_err_vs_ref_pct": 100 * (vals["universal"][0] / vals["reference"][0] - 1),
                         "phi_err_vs_ref_pct": 100 * (vals["universal"][1] / vals["reference"][1] - 1)})
    return pd.DataFrame(rows)


def fig4_cases(cfg) -> pd.DataFrame:
    """The seven Fig. 4 cases with the shipped Gumbel model on the paper's bearing, against the reference
    trajectories of the pipeline (``reference_trajectories_dir``), by the 2 %-of-c rule."""
    from fluidfilm.rotor import Trajectory
    from fluidfilm.rotor.cases import case_summary, run_case
    from fluidfilm.surrogate.universal import universal_bearing

    bearing = bearing_from_cfg(cfg.bearing)
    model = universal_bearing(bearing, "gumbel")
    rows = []
    for name in cfg.run_cases:
        case = cfg.cases[name]
        ref = Trajectory.from_npz(Path(cfg.reference_trajectories_dir) / f"{name}.npz")
        traj = run_case(model, cfg.rotor, case, cfg.integrator)
        s = case_summary(traj, bearing.clearance, cfg.integrator.t_settle, ref, cfg.threshold_pct)
        rows.append({"case": name, **{k: v for k, v in s.items() if np.isscalar(v)}})
        print(f"  case {name}: {traj.status}, rms {s.get('rms_pct', float('nan')):.2f} % of c, satisfactory "
              f"{s.get('satisfactory')}", flush=True)
    return pd.DataFrame(rows)


def round_ratios(numerator, denominator) -> tuple[float, float, float]:
    """Median, least and largest of the per-round ratios of two arms timed back to back in each round."""
    r = np.asarray(numerator, dtype=float) / np.asarray(denominator, dtype=float)
    return float(np.median(r)), float(r.min()), float(r.max())


def force_cost(cfg) -> dict:
    """Seconds per force of the shipped model and of the best model's shape (five regions, 3-64-2;
    ``perf.speed.best_shaped_surrogate``), side by side, medians of ``evaluate.timing_rounds`` interleaved
    rounds (cost ratios: the median of the rounds' own ratios), with the load: the
    one-state kernel in the integrator's loop (``simulate``), its networks in float64 (its default) and
    float32 (``simulate(precision="float32")``), and the batched kernel on ``evaluate.n_batch`` states per call
    in one thread (``simulate_batch``'s per RK4 stage), its networks in float32 (its default) and float64."""
    from fluidfilm.perf.benchmarking import machine
    from fluidfilm.perf.speed import (best_shaped_surrogate, sample_states, time_per_force_eval,
                                      time_per_force_eval_batched)
    from fluidfilm.surrogate.universal import universal_bearing

    bearing = bearing_from_cfg(cfg.bearing)
    x, v = sample_states(bearing.clearance, n=int(cfg.evaluate.n_timing), eps_max=0.9, v_max=0.05)
    xb, vb = sample_states(bearing.clearance, n=int(cfg.evaluate.n_batch), eps_max=0.9, v_max=0.05, seed=1)
    models = {"universal": universal_bearing(bearing, "gumbel"), "best_shape": best_shaped_surrogate(bearing)}
    arms = {"": lambda m: time_per_force_eval(m, x, v),
            "_float32": lambda m: time_per_force_eval(m, x, v, precision="float32"),
            "_batched_float32": lambda m: time_per_force_eval_batched(m, xb, vb, "float32"),
            "_batched_float64": lambda m: time_per_force_eval_batched(m, xb, vb, "float64")}
    load0 = os.getloadavg()[0]
    t: dict[str, list] = {f"{name}{arm}": [] for arm in arms for name in models}
    rounds = int(cfg.evaluate.get("timing_rounds", 7))
    for _ in range(rounds):  # interleaved: both see the same machine load
        for arm, timed in arms.items():
            for name, model in models.items():
                t[f"{name}{arm}"].append(timed(model))
    us = {k: 1e6 * float(np.median(v)) for k, v in t.items()}

    def ratio(arm: str) -> float:
        return round_ratios(t[f"universal{arm}"], t[f"best_shape{arm}"])[0]

    return {**{f"force_eval_us_{k}": val for k, val in us.items()},
            "universal_vs_best_cost_ratio": ratio(""), "universal_vs_best_cost_ratio_float32": ratio("_float32"),
            "universal_vs_best_cost_ratio_batched_float32": ratio("_batched_float32"), "rounds": rounds,
            "n_batch": int(cfg.evaluate.n_batch), "loadavg_1min": [load0, os.getloadavg()[0]], "machine": machine()}


def matched_grid(errors: pd.DataFrame, slenderness: float, median_tol: float, p99_tol: float) -> dict:
    """The coarsest grid of the ladder whose own relative force errors at the held-out states of one rule and
    L/D (``held_out_force_errors``' ``rel_err_grid_<n_theta>``, against the grid-converged reference the
    model is judged by) have a median and a 99th percentile no larger than ``median_tol`` and ``p99_tol``
    (the model's): the reference at the model's accuracy on the model's own yardstick.  When no coarser grid
    qualifies, the converged reference's own grid (error 0 by definition).  ``floor`` is True when the
    ladder's coarsest grid qualifies: a coarser grid than the ladder offers might too, so a speed-up against it
    is an upper bound.

    Examples
    --------
    >>> import pandas as pd
    >>> e = pd.DataFrame({"n_theta": 192, "n_z": 47, "rel_err_grid_48": [0.004, 0.006],
    ...                   "rel_err_grid_72": [0.001, 0.002], "rel_err_grid_96": [0.0005, 0.001]})
    >>> g = matched_grid(e, 0.75, median_tol=0.002, p99_tol=0.01)
    >>> g["n_theta"], g["n_z"], g["floor"]
    (72, 19, False)
    """
    from fluidfilm.data.universal import N_THETA_LADDER, _n_z

    for nt in N_THETA_LADDER:
        col = f"rel_err_grid_{nt}"
        if col not in errors:
            continue
        med, p99 = float(errors[col].median()), float(errors[col].quantile(0.99))
        if med <= median_tol and p99 <= p99_tol:
            return {"n_theta": nt, "n_z": _n_z(nt, slenderness), "median": med, "p99": p99,
                    "floor": nt == N_THETA_LADDER[0]}
    return {"n_theta": int(errors.n_theta.iloc[0]), "n_z": int(errors.n_z.iloc[0]), "median": 0.0, "p99": 0.0,
            "floor": False}


def reference_cost_at_equal_accuracy(cfg, errors: pd.DataFrame, rounds: int | None = None) -> pd.DataFrame:
    """Per rule and held-out L/D: the reference on a grid as accurate as the shipped model there, by two
    yardsticks, and its time per force beside the model's, timed side by side.

    - The convergence check (``data.universal.converged_grid``, the dataset's rule): the coarsest grid whose
      forces at eps 0.8, the check's eccentricity, change by less than ``tol`` in every direction on the next
      finer grid, ``tol`` the model's median relative error for that rule and L/D (the larger of its float64
      and float32 readings, so that every reading below is at equal accuracy).  Columns without a suffix.
    - The model's own yardstick (``matched_grid``, suffix ``_matched``): the coarsest grid whose errors at the
      held-out states, against the same converged reference, have a median and a 99th percentile no larger
      than the model's (each the larger of float64 and float32).  Needs ``held_out_force_errors``'
      ``rel_err_grid_<n_theta>`` columns; without them the matched reading is left out.

    ``rounds`` (default ``evaluate.timing_rounds``) interleaved rounds of each arm; times are medians over
    the rounds, speed-ups the median of the rounds' own ratios, with their least and largest (``_lo``,
    ``_hi``).  Three readings, each model run the same way: the one-state kernel in the integrator's loop (the
    model's networks in float64, and in float32 as ``simulate(precision="float32")`` runs them, against the
    same reference time), and the batched kernel as ``simulate_batch`` calls it, in one thread
    (``evaluate.n_batch`` states per call, the model's float32 networks; the reference's batched kernel is its
    one-state solve per row, in float64).  Rows: rule, ld, tol, n_theta, n_z, reference_us, universal_us,
    universal_float32_us, reference_batched_us, universal_batched_us, rounds, and speedup, speedup_float32,
    speedup_batched, each with its least and largest round (_lo, _hi); with the matched reading also tol_p99,
    n_theta_matched, n_z_matched, grid_median_matched, grid_p99_matched, grid_at_ladder_floor,
    reference_us_matched, reference_batched_us_matched and the three speed-ups with the suffix."""
    from fluidfilm import ReynoldsSolver
    from fluidfilm.data.universal import _n_z, converged_grid
    from fluidfilm.perf.speed import sample_states, time_per_force_eval, time_per_force_eval_batched
    from fluidfilm.surrogate.universal import universal_bearing

    rounds = int(cfg.evaluate.get("timing_rounds", 7)) if rounds is None else int(rounds)
    if rounds < 1:
        raise ValueError(f"reference_cost_at_equal_accuracy needs at least one round, got rounds={rounds}")
    rows = []
    for (rule, ld), g in errors.groupby(["cavitation", "ld"]):
        model_err = g[[c for c in ("rel_err", "rel_err_float32") if c in g]]  # the larger reading of each
        tol = float(model_err.median().max())
        tol99 = float(model_err.quantile(0.99).max())
        nt, _, _ = converged_grid(float(ld), rule, 0.8, tol)
        nz = _n_z(nt, float(ld))
        matched = matched_grid(g, float(ld), tol, tol99) if any(c.startswith("rel_err_grid_") for c in g) else None
        b = JournalBearing(length=0.05 * float(ld), diameter=0.05, clearance=75e-6, speed_rpm=5000.0, viscosity=0.02)
        ref = ReynoldsSolver(b, nt, nz, cavitation=rule)
        model = universal_bearing(b, rule)
        # the reference on a few hundred states (its solve is 10 us - 13 ms here), the model on evaluate.n_timing
        x, v = sample_states(b.clearance, n=200, eps_max=0.9, v_max=0.05)
        xm, vm = sample_states(b.clearance, n=int(cfg.evaluate.n_timing), eps_max=0.9, v_max=0.05)
        xb, vb = sample_states(b.clearance, n=int(cfg.evaluate.n_batch), eps_max=0.9, v_max=0.05, seed=1)
        arms = {"reference_us": lambda: time_per_force_eval(ref, x, v, repeats=3),
                "universal_us": lambda: time_per_force_eval(model, xm, vm, repeats=3),
                "universal_float32_us": lambda: time_per_force_eval(model, xm, vm, repeats=3, precision="float32"),
                "reference_batched_us": lambda: time_per_force_eval_batched(ref, x, v, "float64", repeats=3),
                "universal_batched_us": lambda: time_per_force_eval_batched(model, xb, vb, "float32", repeats=3)}
        same_grid = matched is not None and (matched["n_theta"], matched["n_z"]) == (nt, nz)
        if matched is not None and not same_grid:
            ref_m = ReynoldsSolver(b, matched["n_theta"], matched["n_z"], cavitation=rule)
            arms |= {"reference_us_matched": lambda: time_per_force_eval(ref_m, x, v, repeats=3),
                     "reference_batched_us_matched": lambda: time_per_force_eval_batched(ref_m, x, v, "float64",
                                                                                         repeats=3)}
        t: dict[str, list] = {k: [] for k in arms}
        for _ in range(rounds):
            for k, timed in arms.items():
                t[k].append(timed())
        if same_grid:  # one grid, one set of rounds: both readings are the same measurement
            t["reference_us_matched"], t["reference_batched_us_matched"] = t["reference_us"], t["reference_batched_us"]
        us = {k: 1e6 * float(np.median(val)) for k, val in t.items()}
        row = {"cavitation": rule, "ld": float(ld), "tol": tol, "n_theta": nt, "n_z": nz, **us,
               "rounds": rounds}
        # the ratio of each round (its arms run back to back), then the median and range over the rounds: this
        # host's speed drifts by tens of per cent over seconds, and the reference (a sparse direct solve) and
        # the model (vector arithmetic) are not slowed alike, so a ratio of separate medians drifted with it
        readings = (("speedup", "reference_us", "universal_us"),
                    ("speedup_float32", "reference_us", "universal_float32_us"),
                    ("speedup_batched", "reference_batched_us", "universal_batched_us"))
        for suffix in ("", "_matched") if matched is not None else ("",):
            for name, ref_arm, model_arm in readings:
                mid, lo, hi = round_ratios(t[ref_arm + suffix], t[model_arm])
                row.update({name + suffix: mid, f"{name}{suffix}_lo": lo, f"{name}{suffix}_hi": hi})
        if matched is not None:
            row.update({"tol_p99": tol99, "n_theta_matched": matched["n_theta"], "n_z_matched": matched["n_z"],
                        "grid_median_matched": matched["median"], "grid_p99_matched": matched["p99"],
                        "grid_at_ladder_floor": matched["floor"]})
        rows.append(row)
        print(f"  {rule} L/D={ld:g}: the reference as accurate ({100 * tol:.3f} %) by the convergence check needs "
              f"{nt} x {row['n_z']}: {us['reference_us']:.1f} us per force, {row['speedup']:.0f}x the universal "
              f"model ({row['speedup_float32']:.0f}x with float32 networks, {row['speedup_batched']:.0f}x batched)",
              flush=True)
        if matched is not None:
            print(f"    on the model's yardstick (median {100 * tol:.3f} %, p99 {100 * tol99:.2f} %): "
                  f"{matched['n_theta']} x {matched['n_z']}{' (the ladder floor)' if matched['floor'] else ''}, "
                  f"{us['reference_us_matched']:.1f} us per force, {row['speedup_matched']:.0f}x "
                  f"({row['speedup_float32_matched']:.0f}x float32, {row['speedup_batched_matched']:.0f}x batched)",
                  flush=True)
    return pd.DataFrame(rows)


def error_map(errors: pd.DataFrame, eps_edges) -> pd.DataFrame:
    """Median and 99th-percentile relative error per (rule, L/D, eps bin)."""
    e = errors.assign(eps_bin=pd.cut(errors.eps, list(eps_edges), include_lowest=True))
    g = e.groupby(["cavitation", "ld", "eps_bin"], observed=True).rel_err
    return pd.DataFrame({"median": g.median(), "p99": g.quantile(0.99), "n": g.size()}).reset_index()


def plot_universal_map(table: pd.DataFrame, eps_edges):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rules = list(dict.fromkeys(table.cavitation))
    fig, axes = plt.subplots(1, len(rules), figsize=(5.2 * len(rules), 3.6), constrained_layout=True)
    axes = np.atleast_1d(axes)
    im = None
    for ax, rule in zip(axes, rules):
        t = table[table.cavitation == rule]
        lds = sorted(set(t.ld))
        grid = np.full((len(lds), len(eps_edges) - 1), np.nan)
        for i, ld in enumerate(lds):
            for j, (_, r) in enumerate(t[t.ld == ld].iterrows()):
                grid[i, j] = 100 * r.p99
        im = ax.imshow(grid, aspect="auto", origin="lower", cmap="viridis",
                       extent=(0, len(eps_edges) - 1, 0, len(lds)))
        ax.set_xticks(np.arange(len(eps_edges)), [f"{e:g}" for e in eps_edges], fontsize=7)
        ax.set_yticks(np.arange(len(lds)) + 0.5, [f"{ld:g}" for ld in lds])
        ax.set_xlabel("eccentricity ratio")
        ax.set_ylabel("L/D (held out)")
        ax.set_title(f"{rule}: 99th-percentile relative force error [%]", fontsize=9)
        for i in range(grid.shape[0]):
            for j in range(grid.shape[1]):
                if np.isfinite(grid[i, j]):
                    ax.text(j + 0.5, i + 0.5, f"{grid[i, j]:.2g}", ha="center", va="center", fontsize=7, color="w")
    if im is not None:
        fig.colorbar(im, ax=list(axes), shrink=0.8)
    return fig


def plot_kc(errors: pd.DataFrame):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.6), constrained_layout=True)
    for (rule, kind), g in errors.groupby(["cavitation", "kind"]):
        worst = g.groupby("eps_ref").rel_err.max()
        ax.semilogy(worst.index, 100 * worst.values, "o-" if kind == "direct" else "s--", label=f"{rule}, {kind}")
    ax.axhline(2.0, color="k", lw=0.6)
    ax.axhline(5.0, color="k", lw=0.6, ls="--")
    ax.set_xlabel("eccentricity ratio at equilibrium (reference)")
    ax.set_ylabel("largest relative error of K, C [%]")
    ax.set_title("Universal model: K and C along the equilibrium locus, held-out L/D", fontsize=9)
    ax.legend(fontsize=7)
    return fig


def _evaluate(cfg) -> Logged:
    from fluidfilm.surrogate.universal import load_weights

    ev = cfg.evaluate
    rng = np.random.default_rng(int(ev.seed))
    report, figs = Path(cfg.report_dir), Path(cfg.figure_dir)
    print("held-out force errors", flush=True)
    errors = held_out_force_errors(cfg, rng)
    io.write_csv(report / "universal_errors.csv", errors)
    emap = error_map(errors, ev.eps_edges)
    io.save_figure(plot_universal_map(emap, list(ev.eps_edges)), figs / "universal_error_map.png", dpi=120)
    print("K and C along the locus", flush=True)
    kc = kc_along_locus(cfg)
    io.save_figure(plot_kc(kc), figs / "universal_kc.png", dpi=120)
    print("whirl thresholds", flush=True)
    whirl = whirl_thresholds(cfg)
    print("Raimondi & Boyd", flush=True)
    rb = raimondi_boyd(cfg)
    print("Fig. 4 cases", flush=True)
    cases = fig4_cases(cfg)
    cost = force_cost(cfg)
    print("the reference at equal accuracy", flush=True)
    same = reference_cost_at_equal_accuracy(cfg, errors)
    out = {
        "universal_rel_err_median": float(errors.rel_err.median()),
        "universal_rel_err_p99": float(errors.rel_err.quantile(0.99)),
        # the batched kernel's float32 networks (simulate_batch's default) at the same states
        "universal_rel_err_median_float32": float(errors.rel_err_float32.median()),
        "universal_rel_err_p99_float32": float(errors.rel_err_float32.quantile(0.99)),
        "universal_kc_max_rel_err_direct": float(kc[kc.kind == "direct"].rel_err.max()),
        "universal_kc_max_rel_err_cross": float(kc[kc.kind == "cross"].rel_err.max()),
        "universal_whirl_threshold_rel_err": float(whirl.rel_err.max()),
        "satisfactory_cases_universal": int(cases.satisfactory.sum()),
        "n_cases": int(len(cases)),
        "force_eval_us_universal": cost["force_eval_us_universal"],
        "force_eval_us_universal_float32": cost["force_eval_us_universal_float32"],
        "cost": cost,
        "universal_speedup_vs_reference_equal_accuracy_min": float(same.speedup.min()),
        "universal_speedup_vs_reference_equal_accuracy_float32_min": float(same.speedup_float32.min()),
        "universal_speedup_vs_reference_equal_accuracy_batched_min": float(same.speedup_batched.min()),
        # the reference's grid chosen on the model's own yardstick (matched_grid; coarser or finer than the
        # convergence check's)
        **({f"universal_speedup_vs_reference_matched{k}_min": float(same[f"speedup{k}_matched"].min())
            for k in ("", "_float32", "_batched")} if "speedup_matched" in same else {}),
        "reference_equal_accuracy": same.to_dict(orient="records"),
        "by_rule": {rule: {"median": float(g.rel_err.median()), "p99": float(g.rel_err.quantile(0.99)),
                           "max": float(g.rel_err.max()), "n": int(len(g))}
                    for rule, g in errors.groupby("cavitation")},
        "by_ld": {f"{rule}:{ld:g}": {"median": float(g.rel_err.median()), "p99": float(g.rel_err.quantile(0.99))}
                  for (rule, ld), g in errors.groupby(["cavitation", "ld"])},
        "kc_by_rule": {f"{rule}:{kind}": float(g.rel_err.max()) for (rule, kind), g in kc.groupby(["cavitation", "kind"])},
        # the worst over the held-out L/D at each equilibrium of the locus (the reference's eps, 1 d.p.)
        "held_out_ld": [float(x) for x in cfg.evaluate.held_out_ld],
        "kc_by_eps": {f"{rule}:{kind}:{eps:.1f}": float(g.rel_err.max())
                      for (rule, kind, eps), g in kc.assign(eps=kc.eps_ref.round(1)).groupby(["cavitation", "kind", "eps"])},
        "whirl": whirl.to_dict(orient="records"),
        "raimondi_boyd": {"max_S_err_pct": float(rb.S_err_pct.abs().max()),
                          "max_phi_err_pct": float(rb.phi_err_pct.abs().max()),
                          "max_S_err_vs_reference_pct": float(rb.S_err_vs_ref_pct.abs().max()),
                          "max_phi_err_vs_reference_pct": float(rb.phi_err_vs_ref_pct.abs().max()),
                          "rows": rb.to_dict(orient="records")},
        "cases": cases.to_dict(orient="records"),
        "error_map": [{**r, "eps_bin": str(r["eps_bin"])} for r in emap.to_dict(orient="records")],
        "weights": {rule: load_weights(rule)["info"] for rule in ("gumbel", "swift-stieber")},
        "goals": {"rel_err_median": 0.005, "rel_err_p99": 0.05, "kc_direct": 0.02, "kc_cross": 0.05,
                  "whirl_threshold": 0.01, "raimondi_boyd_pct": 2.0, "cases": 7, "speedup_equal_accuracy": 100.0},
    }
    io.write_json(report / "universal.json", out)
    print(f"universal: median {100 * out['universal_rel_err_median']:.3f} %, p99 {100 * out['universal_rel_err_p99']:.2f} %, "
          f"K/C direct {100 * out['universal_kc_max_rel_err_direct']:.2f} %, cross "
          f"{100 * out['universal_kc_max_rel_err_cross']:.2f} %, whirl {100 * out['universal_whirl_threshold_rel_err']:.2f} %, "
          f"cases {out['satisfactory_cases_universal']}/{len(cases)}, {out['force_eval_us_universal']:.3f} us/force")
    metrics = {k: v for k, v in out.items() if k.startswith(("universal_", "satisfactory_", "force_eval_"))}
    return Logged(metrics, [report / "universal.json", figs / "universal_error_map.png", figs / "universal_kc.png"])


def run(cfg) -> Logged:
    check(cfg)
    if cfg.part == "dataset":
        return _dataset(cfg)
    if cfg.part == "train":
        return _train(cfg)
    return _evaluate(cfg)


def compare_weights(models_dir, shipped=None) -> dict:
    """For each rule, the weights trained in ``models_dir`` against the package's (``shipped``; None: the
    package's own folder): ``identical`` (every array equal, bit for bit), ``max_rel_diff`` (each array's
    largest difference over its largest entry, the largest over the arrays; None where the shapes differ,
    e.g. the small profile's networks), or ``missing``.

    Examples
    --------
    >>> compare_weights("no/such/folder")["gumbel"]
    {'missing': True}
    """
    from fluidfilm.surrogate.universal import WEIGHTS_DIR

    shipped = Path(shipped) if shipped is not None else WEIGHTS_DIR
    out: dict[str, Any] = {}
    for rule in ("gumbel", "swift-stieber"):
        trained, ours = Path(models_dir) / f"{rule}.npz", shipped / f"{rule}.npz"
        if not (trained.exists() and ours.exists()):
            out[rule] = {"missing": True}
            continue
        with np.load(trained, allow_pickle=False) as a, np.load(ours, allow_pickle=False) as b:
            keys = sorted(k for k in a.files if k != "info")
            same_layout = keys == sorted(k for k in b.files if k != "info") and all(
                a[k].shape == b[k].shape and a[k].dtype == b[k].dtype for k in keys)
            if not same_layout:
                out[rule] = {"identical": False, "max_rel_diff": None}
                continue
            # each array's largest difference relative to its largest entry (the arrays' scales differ)
            diffs = [float(np.max(np.abs(a[k].astype(float) - b[k].astype(float)), initial=0.0)
                           / max(float(np.max(np.abs(b[k].astype(float)), initial=0.0)), 1e-300))
                     for k in keys if a[k].dtype.kind in "fi"]
            equal = all(np.array_equal(a[k], b[k]) for k in keys)
        out[rule] = {"identical": bool(equal), "max_rel_diff": max(diffs, default=0.0)}
    return out


def install_weights(models_dir, target) -> None:
    """Copy trained weights (``<rule>.npz`` and ``SHA256SUMS``) into the package's folder (``target``)."""
    target = Path(target)
    target.mkdir(parents=True, exist_ok=True)
    for f in sorted(Path(models_dir).iterdir()):
        if f.suffix == ".npz" or f.name == "SHA256SUMS":
            shutil.copy2(f, target / f.name)
