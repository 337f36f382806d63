"""On-line assessment (``experiments/online_assessment.py``): the estimator against synthetic plant records.

Benchmark mode (the DVC stage, ``input: null``): each scenario of the config is simulated with the *reference*
solver (``ReynoldsSolver`` on ``plant.grid``, the universal model's cavitation rule), recorded through the
probes (noise, runout, quantisation, ``plant.fs``), and handed to the estimator (``fluidfilm.estimation``,
the universal surrogate of the description's bearing) and to the plants' centreline baseline. Reports
``reports/online_assessment.json`` (the issue's keys under ``metrics``, every scenario's errors, flags and
timings) and ``reports/figures/online_assessment.png`` (true against estimated load, imbalance and viscosity
with 2-sigma bands).

Assessment mode (``input=<probe file>``): a recorded probe file (CSV or Parquet, ``estimation.probes``) and the
bearing's ``description`` give the estimates, their bands and the flags in ``assess.out_dir``
(``estimation.assess``).

Error measures, per scenario, over its evaluation window (the samples at least ``eval_after_s`` after the
record's start and after the scenario's last abrupt change): the RMS of |W_est - W| / |W| (vector error),
of |u_est| / |u| - 1 (the imbalance's magnitude; the phase error is reported beside it) and of s_est / s - 1.
"""
from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

import numpy as np

INPUTS = ()


def outputs(cfg):
    if cfg.get("input"):
        return {}
    return {"report_dir": ["online_assessment.json"], "figure_dir": ["online_assessment.png"]}


def tracking_run(cfg):
    return ("online_assessment" if not cfg.get("input") else "online_assessment_file"), None


# ----------------------------------------------------------------------------- the scenarios
def scenario_from_cfg(name: str, sc, plant, description: dict):
    """A ``plant.Scenario`` from the config's mapping: ``knots`` rows (t, W1, W2, u, phi, s), optional
    ``speed_rpm`` or ``speed_knots`` (rows (t, rpm): a speed profile), ``t_end``, ``bearing`` (overrides of the description for plant and estimator alike) and
    ``plant_bearing`` (overrides for the plant only: a bearing unlike its description)."""
    from fluidfilm.estimation.plant import Scenario

    knots = np.asarray(sc["knots"], dtype=float)
    if knots.ndim != 2 or knots.shape[1] != 6:
        raise ValueError(f"scenarios.{name}.knots: rows (t, W1, W2, u, phi, s) expected")
    values = np.stack([knots[:, 1], knots[:, 2], knots[:, 3] * np.cos(knots[:, 4]),
                       knots[:, 3] * np.sin(knots[:, 4]), knots[:, 5]], axis=1)
    times = knots[:, 0]
    if times.size == 1:
        times = np.array([0.0, 1.0])
        values = np.vstack([values, values])
    runout = (tuple(tuple(r) for r in plant["runout_x"]), tuple(tuple(r) for r in plant["runout_y"]))
    return Scenario(name=name, times=tuple(times), values=tuple(map(tuple, values)),
                    speed_rpm=float(sc.get("speed_rpm") or description["speed_rpm"]),
                    mass=float(description["mass"]), t_end=float(sc.get("t_end") or plant["t_end"]),
                    t_warm=float(plant["t_warm"]), fs=float(plant["fs"]), noise=float(plant["noise"]),
                    lsb=float(plant["lsb"]), runout=runout, runout_known_error=0.0,
                    force_2x=float(sc.get("force_2x", 0.0)),
                    speed_knots=tuple(tuple(float(v) for v in row) for row in (sc.get("speed_knots") or ())),
                    description=str(sc.get("what", "")))


def _descr(cfg_description: dict, overrides) -> dict:
    d = dict(cfg_description)
    d.update(dict(overrides or {}))
    return d


def _told(descr: dict):
    """The ``BearingDescription`` of a description mapping (its bearing keys; the scenario's extras left out)."""
    from fluidfilm.estimation.probes import BearingDescription

    keys = ("length", "diameter", "clearance", "speed_rpm", "viscosity", "mass", "cavitation")
    return BearingDescription.from_mapping({k: v for k, v in descr.items() if k in keys})


def scenario_seeds(plant: dict, k: int) -> list[int]:
    """The noise seeds of the ``k``-th scenario: ``plant.seed + k + 100 j`` for j < ``plant.n_seeds`` (j = 0 the
    stage's single seed of before; each seed draws the probes' noise and the slow-roll vector's errors, never the
    plant's physics)."""
    return [int(plant["seed"]) + k + 100 * j for j in range(int(plant.get("n_seeds", 1)))]


def run_scenario(name: str, sc: dict, cfg: dict, seeds) -> dict:
    """Plant, estimator and baseline on one scenario, the plant's orbit once and its probe record once per noise
    seed: the errors, flags and timings per seed, their median and worst over the seeds, and the first seed's
    series for the figure."""
    from fluidfilm.estimation.plant import plant_orbit
    from fluidfilm.reynolds import ReynoldsSolver
    from fluidfilm.surrogate.universal import universal_bearing

    seeds = [int(x) for x in (seeds if isinstance(seeds, (list, tuple)) else [seeds])]
    plant = cfg["plant"]
    descr = _descr(cfg["description"], sc.get("bearing"))
    told = _told(descr)
    plant_descr = _told(_descr(descr, sc.get("plant_bearing")))
    scenario = scenario_from_cfg(name, sc, plant, descr)
    b_plant = plant_descr.journal_bearing()
    n_theta = int(plant["grid"][0])
    n_z = int(plant["grid"][1]) or max(n_theta // 6, int(round(n_theta * b_plant.length / (math.pi * b_plant.diameter))) + 1)
    reference = ReynoldsSolver(b_plant, n_theta, n_z, cavitation=told.cavitation)
    orbit = plant_orbit(reference, scenario, dt=float(sc.get("dt") or plant["dt"]))
    model = universal_bearing(told.journal_bearing(), cavitation=told.cavitation)
    x_true = orbit.x_true
    res = {"what": scenario.description, "dynamic": bool(sc.get("dynamic", True)), "trip": sc.get("trip"),
           "blind_spot": bool(sc.get("blind_spot", False)), "plant_s": orbit.wall_s,
           "plant_stopped_early": orbit.stopped_early,
           "eps_true_max": float(np.max(np.hypot(x_true[:, 0], x_true[:, 1])) / b_plant.clearance),
           "orbit_pk_pk_um": [float(np.ptp(x_true[:, 0]) * 1e6), float(np.ptp(x_true[:, 1]) * 1e6)],
           "seeds": seeds}
    res["bound"] = _bound(orbit, sc, cfg, model, told)
    per_seed, series = [], None
    for seed in seeds:
        one, ser = _score_seed(orbit, seed, sc, cfg, model, told, batch=res["bound"] is not None)
        per_seed.append(one)
        series = series or ser
    res.update({k: per_seed[0][k] for k in ("n_samples", "t_eval_s", "n_eval")})
    res.update(aggregate(per_seed))
    res["per_seed"] = per_seed
    return {"result": res, "series": series}


#: an efficient estimator's expected median |error| over noise draws, in the bound's standard deviations (the median
#: of |e| for e ~ N(0, sigma^2); a window's RMS of an error that wanders within it is somewhat larger)
EFFICIENT_MEDIAN = 0.6745


def _bound(orbit, sc: dict, cfg: dict, model, told) -> dict | None:
    """The record's information bound (``estimation.bound``) where the scenario's parameters are constant and its
    model is the estimator's (no change, no force the model lacks, not a blind spot): one standard deviation of the
    relative load, imbalance and viscosity errors at ``eval_after_s``, as the RMS over the evaluation window and at
    the record's end, and what ``bound_long_s`` of the same record would give (the bound's model continues the
    orbit); with the slow-roll vector exact and with the benchmark's error."""
    from fluidfilm.estimation.bound import information_bound

    scenario = orbit.scenario
    vals = np.asarray(scenario.values, dtype=float)
    if (np.ptp(vals, axis=0).max() > 0.0 or sc.get("trip") or sc.get("blind_spot") or sc.get("changes")
            or scenario.force_2x or orbit.stopped_early):
        return None
    plant = cfg["plant"]
    t_eval = float(cfg["eval_after_s"])
    t_end = float(orbit.t[-1])
    if t_end <= t_eval:
        return None
    t_long = max(float(cfg.get("bound_long_s", 4.0)), t_end)
    grid = np.arange(t_eval, t_end + 0.5 / scenario.fs, 0.005)
    out: dict = {"long_s": t_long}
    keys = ("load_rel", "imbalance_rel", "viscosity_rel")
    for label, err in (("exact_runout", 0.0), ("slow_roll_error", float(plant["slow_roll_error"]))):
        b = information_bound(model, scenario.speed_knots or scenario.speed_rpm, told.mass, vals[0], orbit.x_true[0, :2],
                              orbit.x_true[0, 2:], t_long, scenario.fs, scenario.noise, scenario.lsb, err,
                              sgn=scenario.sgn, times=np.append(grid, t_long))
        n = grid.size
        out[label] = {"at_eval": {k: float(b[k][0]) for k in keys}, "end": {k: float(b[k][n - 1]) for k in keys},
                      "window_rms": {k: float(np.sqrt(np.mean(b[k][:n] ** 2))) for k in keys},
                      "long": {k: float(b[k][-1]) for k in keys}}
    return out


def what_if(name: str, sc: dict, cfg: dict) -> dict:
    """The bound of scenario ``name`` on the records ``bound_what_if.variants`` describe (a better slow-roll vector,
    a longer record, quieter or faster probes, a speed change in the record): what would close a goal the
    benchmark's record cannot reach. Each variant overrides ``slow_roll_error``, ``t_end``, ``noise``, ``fs`` or
    gives ``speed_ratio_knots`` (rows (t, speed / the scenario's speed)); the bound's model runs the orbit from the plant's own start (the surrogate's orbit here: the
    bound needs the start state alone)."""
    from fluidfilm.estimation.bound import information_bound
    from fluidfilm.estimation.plant import plant_orbit
    from fluidfilm.surrogate.universal import universal_bearing

    plant = cfg["plant"]
    descr = _descr(cfg["description"], sc.get("bearing"))
    told = _told(descr)
    model = universal_bearing(told.journal_bearing(), cavitation=told.cavitation)
    scenario = scenario_from_cfg(name, sc, plant, descr)
    vals = np.asarray(scenario.values, dtype=float)
    t_eval = float(cfg["eval_after_s"])
    start = plant_orbit(model, scenario, dt=float(sc.get("dt") or plant["dt"]))
    out = {}
    for label, v in cfg["bound_what_if"]["variants"].items():
        v = dict(v or {})
        unknown = set(v) - {"slow_roll_error", "t_end", "noise", "fs", "speed_ratio_knots", "what"}
        if unknown:
            raise ValueError(f"bound_what_if.variants.{label}: unknown keys {sorted(unknown)}")
        t_end = float(v.get("t_end", float(start.t[-1])))
        speed = (tuple((float(t), float(r) * scenario.speed_rpm) for t, r in v["speed_ratio_knots"])
                 if v.get("speed_ratio_knots") else (scenario.speed_knots or scenario.speed_rpm))
        b = information_bound(model, speed, told.mass, vals[0], start.x_true[0, :2], start.x_true[0, 2:], t_end,
                              float(v.get("fs", scenario.fs)), float(v.get("noise", scenario.noise)), scenario.lsb,
                              float(v.get("slow_roll_error", plant["slow_roll_error"])), sgn=scenario.sgn,
                              times=[t_eval, t_end])
        out[label] = {"what": str(v.get("what", "")), "t_end": t_end,
                      "at_eval": {k: float(b[k][0]) for k in ("load_rel", "imbalance_rel", "viscosity_rel")},
                      "end": {k: float(b[k][-1]) for k in ("load_rel", "imbalance_rel", "viscosity_rel")}}
    return out


def _batch(rec, known, est, model, told, plant: dict) -> dict | None:
    """The batch maximum a posteriori fit (``estimation.bound.batch_fit``) of a constant-parameter record, started
    from the filter: its relative errors at the record's end (it uses the whole record, as the bound's ``end``)."""
    from fluidfilm.estimation.bound import batch_fit
    from fluidfilm.estimation.estimator import shaft_angle
    from fluidfilm.estimation.plant import runout_signal

    sc = rec.scenario
    f = rec.frame
    t = f["time"].to_numpy(dtype=float)
    y = f[["x", "y"]].to_numpy(dtype=float) - runout_signal(known, shaft_angle(t, f["speed"].to_numpy(dtype=float)))
    z0 = est.zs[0] if est.zs is not None else est.z[0]
    theta0 = np.concatenate([z0[:4], est.z[-1, 4:9]])
    tic = time.perf_counter()
    fit = batch_fit(t, y, model, sc.speed_knots or sc.speed_rpm, told.mass, theta0, sc.noise, sc.lsb, float(plant["slow_roll_error"]),
                    sgn=sc.sgn)
    return dict(_end_errors(fit["theta"], rec.truth[-1]), iterations=int(fit["iterations"]),
                fit_s=time.perf_counter() - tic)


def _end_errors(z, truth) -> dict:
    """Relative errors of one estimate ``z`` (state order of ``ekf.STATE_NAMES``) against the true (W1, W2, a, b, s)."""
    return {"load_rel_err": float(math.hypot(z[4] - truth[0], z[5] - truth[1]) / math.hypot(truth[0], truth[1])),
            "imbalance_rel_err": float(abs(math.hypot(z[6], z[7]) / math.hypot(truth[2], truth[3]) - 1.0)),
            "viscosity_rel_err": float(abs(z[8] / truth[4] - 1.0))}


ERROR_KEYS = ("load_rel_err", "imbalance_rel_err", "imbalance_phase_err_deg", "viscosity_rel_err")


def aggregate(per_seed: list[dict]) -> dict:
    """A scenario's figures over its noise seeds: ``filter``/``smoother`` the median of each error over the seeds
    and ``*_worst`` the largest; the baseline's likewise; the filter's own end 1-sigma (median); the flags' armed
    fractions (mean and largest over the seeds), how many seeds each flag fired on, and when (median of the first
    firings); the time per sample (median)."""
    out: dict = {}
    for label in ("filter", "smoother"):
        rows = [p[label] for p in per_seed if label in p]
        if rows:
            out[label] = {k: float(np.median([r[k] for r in rows])) for k in ERROR_KEYS}
            out[label + "_worst"] = {k: float(max(r[k] for r in rows)) for k in ERROR_KEYS}
    for label in ("filter_end", "batch"):
        rows = [p[label] for p in per_seed if p.get(label)]
        if rows:
            keys = ("load_rel_err", "imbalance_rel_err", "viscosity_rel_err")
            out[label] = {k: float(np.median([r[k] for r in rows])) for k in keys}
            out[label + "_rms"] = {k: float(np.sqrt(np.mean([r[k] ** 2 for r in rows]))) for k in keys}
    b = [p["baseline"]["load_rel_err"] for p in per_seed]
    out["baseline"] = {"load_rel_err": float(np.median(b)), "load_rel_err_worst": float(max(b)),
                       "viscosity_assumed": per_seed[0]["baseline"]["viscosity_assumed"]}
    out["sd_end"] = {k: float(np.median([p["sd_end"][k] for p in per_seed])) for k in per_seed[0]["sd_end"]}
    flags: dict = {}
    for f in ("mismatch", "out_of_domain"):
        frac = [p["flags"][f + "_fraction"] for p in per_seed]
        first = [p["flags"][f + "_first_s"] for p in per_seed if p["flags"][f + "_first_s"] is not None]
        flags[f + "_fraction"] = float(np.mean(frac))
        flags[f + "_fraction_max"] = float(max(frac))
        flags[f + "_seeds"] = len(first)
        flags[f + "_first_s"] = float(np.median(first)) if first else None
    flags["nis_mean_median"] = float(np.median([p["flags"]["nis_mean_median"] for p in per_seed]))
    out["flags"] = flags
    out["us_per_sample"] = float(np.median([p["us_per_sample"] for p in per_seed]))
    out["estimate_s"] = float(sum(p["estimate_s"] for p in per_seed))
    return out


def _score_seed(orbit, seed: int, sc: dict, cfg: dict, model, told, batch: bool = False) -> tuple[dict, dict]:
    """One noise seed of a scenario: the probe record, the estimator and the baseline on it, and the errors over
    the evaluation window; where ``batch`` (a constant-parameter record), also the filter's and the batch fit's
    errors at the record's end (what the bound's ``end`` compares with)."""
    from fluidfilm.estimation import EstimatorSettings, estimate
    from fluidfilm.estimation.plant import probe_record

    plant = cfg["plant"]
    rec = probe_record(orbit, seed)
    scenario = orbit.scenario
    # the slow-roll runout vector handed to the estimator: the true runout measured with an error per coefficient
    rng = np.random.default_rng(seed + 1000)
    err = float(plant["slow_roll_error"])
    known = tuple(tuple((c + rng.normal(0.0, err), s + rng.normal(0.0, err)) for c, s in axis)
                  for axis in scenario.runout)
    settings = EstimatorSettings(noise=float(plant["noise"]), lsb=float(plant["lsb"]), **dict(cfg["estimator"]))
    tic = time.perf_counter()
    est = estimate(rec.frame, model, told.mass, runout=known, settings=settings)
    est_s = time.perf_counter() - tic
    t = est.t
    truth = rec.truth
    changes = [float(c) for c in sc.get("changes", [])]
    t_eval = max([float(cfg["eval_after_s"])] + [c + float(cfg["eval_after_s"]) for c in changes])
    win = t >= t_eval
    if win.sum() < 10:   # a record too short for the window (the small profile): its last fifth
        t_eval = float(t[-1] - 0.2 * (t[-1] - t[0]))
        win = t >= t_eval
    res: dict[str, Any] = {"seed": int(seed), "n_samples": int(t.size), "t_eval_s": t_eval, "n_eval": int(win.sum()),
           "estimate_s": est_s, "us_per_sample": est.us_per_sample}
    for label, z in (("filter", est.z), ("smoother", est.zs)):
        if z is None or not win.any():
            continue
        W = truth[:, :2]
        u_true = np.hypot(truth[:, 2], truth[:, 3])
        load_err = np.hypot(z[:, 4] - W[:, 0], z[:, 5] - W[:, 1]) / np.hypot(W[:, 0], W[:, 1])
        u_est = np.hypot(z[:, 6], z[:, 7])
        imb_err = u_est / u_true - 1.0
        phase_err = np.degrees(np.angle(np.exp(1j * (np.arctan2(z[:, 7], z[:, 6]) - np.arctan2(truth[:, 3],
                                                                                              truth[:, 2])))))
        visc_err = z[:, 8] / truth[:, 4] - 1.0
        rms = lambda e: float(np.sqrt(np.mean(e[win] ** 2)))   # noqa: E731
        res[label] = {"load_rel_err": rms(load_err), "imbalance_rel_err": rms(imb_err),
                      "imbalance_phase_err_deg": rms(phase_err), "viscosity_rel_err": rms(visc_err)}
    if batch:
        res["filter_end"] = _end_errors(est.z[-1], truth[-1])
        res["batch"] = _batch(rec, known, est, model, told, plant)
    zl, sl = est.z[-1], est.sd[-1]
    res["sd_end"] = {   # the filter's own 1-sigma at the record's end, relative: what the data resolve (observability)
        "load_rel": float(math.hypot(zl[4] * sl[4], zl[5] * sl[5]) / max(math.hypot(zl[4], zl[5]) ** 2, 1e-30)),
        "imbalance_rel": float(math.hypot(zl[6] * sl[6], zl[7] * sl[7]) / max(math.hypot(zl[6], zl[7]) ** 2, 1e-30)),
        "viscosity_rel": float(sl[8] / max(abs(zl[8]), 1e-12))}
    bW = est.baseline_W
    b_err = np.hypot(bW[:, 0] - truth[:, 0], bW[:, 1] - truth[:, 1]) / np.hypot(truth[:, 0], truth[:, 1])
    res["baseline"] = {"load_rel_err": float(np.sqrt(np.mean(b_err[win] ** 2))),
                       "viscosity_assumed": float(told.viscosity)}
    armed = t >= t[0] + settings.flag_after_s
    if not armed.any():
        armed = np.ones(t.size, dtype=bool)
    res["flags"] = {"mismatch_fraction": float(est.mismatch[armed].mean()),
                    "out_of_domain_fraction": float(est.out_of_domain[armed].mean()),
                    "mismatch_first_s": float(t[np.argmax(est.mismatch)]) if est.mismatch.any() else None,
                    "out_of_domain_first_s": float(t[np.argmax(est.out_of_domain)]) if est.out_of_domain.any()
                    else None,
                    "nis_mean_median": float(np.median(est.nis_mean[armed]))}
    series = {"t": t, "truth": truth, "z": est.z, "sd": est.sd, "zs": est.zs, "sds": est.sds, "baseline_W": bW,
              "mu0": est.mu0, "nis_mean": est.nis_mean, "threshold": settings.nis_threshold,
              "mismatch": est.mismatch, "ood": est.out_of_domain}
    return res, series


def summarise(results: dict, cfg: dict) -> dict:
    """The issue's keys from the scenarios' results (definitions in docs/online_assessment.md): an accuracy key is
    the worst scenario's *median* over its noise seeds (``*_worst``: the worst scenario and seed); the ratio to the
    centreline baseline the least over the dynamic scenarios of the median over seeds of the per-seed ratio
    (``*_worst``: the least over scenarios and seeds); the false-flag rate the flagged fraction over every
    scenario and seed; a trip scenario counts as caught on a seed where its flag fires."""
    # the accuracy and false-flag figures: every scenario not made to trip a flag and not a documented blind spot
    normal = [n for n, r in results.items() if not r.get("trip") and not r.get("blind_spot")]
    dynamic = [n for n in normal if results[n]["dynamic"]]
    worst = lambda label, key: max(results[n][label][key] for n in normal)   # noqa: E731

    def seed_ratios(n):
        return [p["baseline"]["load_rel_err"] / max(p["filter"]["load_rel_err"], 1e-12)
                for p in results[n]["per_seed"]]

    ratios = {n: float(np.median(seed_ratios(n))) for n in dynamic}
    false_flags = [max(p["flags"]["mismatch_fraction"], p["flags"]["out_of_domain_fraction"])
                   for n in normal for p in results[n]["per_seed"]]
    trips = [n for n in results if results[n].get("trip")]
    fired = [float(p["flags"][results[n]["trip"] + "_first_s"] is not None)
             for n in trips for p in results[n]["per_seed"]]
    metrics = {}
    for key in ("load_rel_err", "imbalance_rel_err", "viscosity_rel_err"):
        metrics[f"estimator_{key}"] = worst("filter", key)
        metrics[f"estimator_{key}_worst"] = worst("filter_worst", key)
    metrics.update({
        "estimator_us_per_sample": float(np.median([p["us_per_sample"] for n in normal
                                                    for p in results[n]["per_seed"]])),
        "estimator_us_per_sample_worst": float(max(p["us_per_sample"] for r in results.values()
                                                   for p in r["per_seed"])),
        "estimator_vs_centreline_load_err_ratio": float(min(ratios.values())) if ratios else float("nan"),
        "estimator_vs_centreline_load_err_ratio_worst": (float(min(min(seed_ratios(n)) for n in dynamic))
                                                         if dynamic else float("nan")),
        "estimator_false_flag_rate": float(np.mean(false_flags)) if false_flags else float("nan"),
        "estimator_trip_flag_rate": float(np.mean(fired)) if fired else float("nan"),
        "estimator_noise_seeds": int(min(len(r["per_seed"]) for r in results.values())),
    })
    # what the records resolve at best (estimation.bound): the largest window-RMS bound over the scenarios it
    # covers (constant parameters), with the benchmark's slow-roll error, and whether the goal lies below what an
    # efficient estimator would reach at the median there
    bounded = [n for n in normal if results[n].get("bound")]
    below = {}
    for key, short in (("load_rel_err", "load_rel"), ("imbalance_rel_err", "imbalance_rel"),
                       ("viscosity_rel_err", "viscosity_rel")):
        if bounded:
            worst_b = max(bounded, key=lambda n: results[n]["bound"]["slow_roll_error"]["window_rms"][short])
            sig = results[worst_b]["bound"]["slow_roll_error"]["window_rms"][short]
            metrics[f"estimator_{key}_bound"] = sig
            below[key.removesuffix("_rel_err")] = {
                "scenario": worst_b, "bound_sd": sig, "efficient_median": EFFICIENT_MEDIAN * sig,
                "goal_out_of_reach": bool(EFFICIENT_MEDIAN * sig > cfg["goals"][key])}
    goals = cfg["goals"]
    met = {
        "load": metrics["estimator_load_rel_err"] <= goals["load_rel_err"],
        "imbalance": metrics["estimator_imbalance_rel_err"] <= goals["imbalance_rel_err"],
        "viscosity": metrics["estimator_viscosity_rel_err"] <= goals["viscosity_rel_err"],
        "speed": metrics["estimator_us_per_sample"] <= goals["us_per_sample"],
        "vs_centreline": metrics["estimator_vs_centreline_load_err_ratio"] >= goals["vs_centreline"],
        "flags": (metrics["estimator_false_flag_rate"] <= goals["false_flag_rate"]
                  and metrics["estimator_trip_flag_rate"] >= 1.0),
    }
    return {"metrics": metrics, "goals_met": met, "ratios": ratios, "information_bound": below, "worst_scenario": {
        key: max(normal, key=lambda n: results[n]["filter"][key])
        for key in ("load_rel_err", "imbalance_rel_err", "viscosity_rel_err")}}


# ----------------------------------------------------------------------------- the figure
def plot(series: dict, names: list[str]):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(4, len(names), figsize=(4.2 * len(names), 10.5), sharex="col", squeeze=False)
    for j, name in enumerate(names):
        s = series[name]
        t, tr, z, sd = s["t"], s["truth"], s["z"], s["sd"]
        load = np.hypot(z[:, 4], z[:, 5])
        load_sd = np.sqrt((z[:, 4] * sd[:, 4]) ** 2 + (z[:, 5] * sd[:, 5]) ** 2) / np.maximum(load, 1e-12)
        u = np.hypot(z[:, 6], z[:, 7])
        u_sd = np.sqrt((z[:, 6] * sd[:, 6]) ** 2 + (z[:, 7] * sd[:, 7]) ** 2) / np.maximum(u, 1e-30)
        rows = [(np.hypot(tr[:, 0], tr[:, 1]), load, load_sd, "static load [N]", 1.0),
                (np.hypot(tr[:, 2], tr[:, 3]) * 1e3, u * 1e3, u_sd * 1e3, "imbalance m_u d [g m]", 1.0),
                (tr[:, 4] * s["mu0"] * 1e3, z[:, 8] * s["mu0"] * 1e3, sd[:, 8] * s["mu0"] * 1e3,
                 "viscosity [mPa s]", 1.0)]
        for i, (true, val, err, label, _) in enumerate(rows):
            ax = axes[i, j]
            ax.fill_between(t, val - 2 * err, val + 2 * err, color="C0", alpha=0.25, lw=0, label="EKF ±2σ")
            ax.plot(t, val, color="C0", lw=1.0, label="EKF (on-line)")
            if s["zs"] is not None and i < 3:
                zs = s["zs"]
                sm = [np.hypot(zs[:, 4], zs[:, 5]), np.hypot(zs[:, 6], zs[:, 7]) * 1e3, zs[:, 8] * s["mu0"] * 1e3][i]
                ax.plot(t, sm, color="C2", lw=1.0, ls="--", label="RTS smoother (offline)")
            ax.plot(t, true, color="k", lw=1.2, label="true (reference plant)")
            if i == 0:
                ax.plot(t, np.hypot(s["baseline_W"][:, 0], s["baseline_W"][:, 1]), color="C3", lw=1.0,
                        label="centreline baseline")
                ax.set_title(name)
            lo, hi = np.nanpercentile(np.concatenate([true, val]), [1, 99])
            pad = 0.25 * max(hi - lo, 0.05 * abs(hi))
            if i == 0:
                lo = min(lo, np.nanpercentile(np.hypot(s["baseline_W"][:, 0], s["baseline_W"][:, 1]), 5))
            ax.set_ylim(lo - pad, hi + pad)
            if j == 0:
                ax.set_ylabel(label)
        ax = axes[3, j]
        ax.plot(t, s["nis_mean"], color="C4", lw=1.0, label="windowed NIS / dof")
        ax.axhline(s["threshold"], color="C3", ls=":", lw=1.0, label="mismatch threshold")
        if s["mismatch"].any():
            ax.fill_between(t, 0.0, 3.0, where=s["mismatch"], color="C3", alpha=0.15, lw=0, label="mismatch flag")
        if s["ood"].any():
            ax.fill_between(t, 0.0, 3.0, where=s["ood"], color="C1", alpha=0.2, lw=0, label="out of domain")
        ax.set_ylim(0.5, 2.5)
        ax.set_xlabel("time [s]")
        if j == 0:
            ax.set_ylabel("innovation test")
    axes[0, 0].legend(fontsize=7, loc="best")
    for j in range(len(names)):
        if axes[3, j].get_legend_handles_labels()[0]:
            axes[3, j].legend(fontsize=7, loc="upper right")
    fig.suptitle("On-line assessment from two probes: the estimator (universal surrogate in an EKF) against the "
                 "reference plant", fontsize=10)
    fig.tight_layout()
    return fig


# ----------------------------------------------------------------------------- entry
def run(cfg):
    from fluidfilm import io
    from fluidfilm.workflow.entry import plain
    from fluidfilm.workflow.tracking import Logged

    c = plain(cfg)
    if c.get("input"):
        return run_file(c)
    results, series = {}, {}
    tic = time.perf_counter()
    for k, (name, sc) in enumerate(c["scenarios"].items()):
        out = run_scenario(name, sc, c, seeds=scenario_seeds(c["plant"], k))
        results[name], series[name] = out["result"], out["series"]
        r = out["result"]
        f, fw = r.get("filter", {}), r.get("filter_worst", {})
        nan = float("nan")
        print(f"{name:16s} median/worst over {len(r['seeds'])} seeds: load {f.get('load_rel_err', nan):.2%}/"
              f"{fw.get('load_rel_err', nan):.2%}  imbalance {f.get('imbalance_rel_err', nan):.2%}/"
              f"{fw.get('imbalance_rel_err', nan):.2%}  viscosity {f.get('viscosity_rel_err', nan):.2%}/"
              f"{fw.get('viscosity_rel_err', nan):.2%}  baseline load {r['baseline']['load_rel_err']:.2%}  flags "
              f"mismatch {r['flags']['mismatch_seeds']} ood {r['flags']['out_of_domain_seeds']} seeds  "
              f"{r['us_per_sample']:.1f} us/sample  plant {r['plant_s']:.1f} s  estimator {r['estimate_s']:.1f} s",
              flush=True)
    what = {}
    for name in (c.get("bound_what_if") or {}).get("scenarios", []):
        tic_w = time.perf_counter()
        what[name] = what_if(name, c["scenarios"][name], c)
        print(f"{name:16s} information bound, viscosity at {c['eval_after_s']} s: " + ", ".join(
            f"{k} {v['at_eval']['viscosity_rel']:.2%}" for k, v in what[name].items())
            + f"  ({time.perf_counter() - tic_w:.1f} s)", flush=True)
    summary = summarise(results, c)
    report = {"metrics": summary["metrics"], "goals": c["goals"], "goals_met": summary["goals_met"],
              "ratios_vs_centreline": summary["ratios"], "worst_scenario": summary["worst_scenario"],
              "information_bound": summary["information_bound"], "bound_what_if": what,
              "scenarios": results, "description": c["description"], "plant": {k: v for k, v in c["plant"].items()},
              "estimator": c["estimator"], "eval_after_s": c["eval_after_s"], "wall_s": time.perf_counter() - tic,
              "machine": _machine()}
    rd, fd = Path(c["report_dir"]), Path(c["figure_dir"])
    io.write_json(rd / "online_assessment.json", report)
    names = [n for n in c["figure_scenarios"] if n in series]
    io.save_figure(plot(series, names), fd / "online_assessment.png", dpi=100)
    for k, v in summary["metrics"].items():
        print(f"{k}: {v:.4g}")
    return Logged(summary["metrics"], [rd / "online_assessment.json", fd / "online_assessment.png"])


def _machine() -> str:
    try:
        from fluidfilm.perf.benchmarking import machine

        return machine()
    except Exception:   # the report does not depend on it
        import platform

        return platform.platform()


def run_file(c: dict):
    """Assessment mode: a recorded probe file and the bearing's description -> estimates, bands and flags."""
    from fluidfilm.estimation.assess import assess
    from fluidfilm.estimation.probes import BearingDescription
    from fluidfilm.workflow.tracking import Logged

    descr = BearingDescription.from_mapping(c["assess"]["description"] or c["description"])
    out = assess(c["input"], descr, c["assess"]["out_dir"], bearing=c["assess"].get("bearing"),
                 settings_overrides=c["estimator"])
    metrics = {k: v for k, v in out["summary"].items() if isinstance(v, (int, float)) and not isinstance(v, bool)}
    return Logged(metrics, [Path(p) for p in out["files"]])
