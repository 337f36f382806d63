"""The paper-comparison report: reports/metrics.json and reports/paper_comparison.md from the stages' outputs.

``load_inputs`` reads what the other stages wrote (comparison, training time, trajectory and speed
tables, the model reports, the datasets' metadata, the controller study, the characteristics);
``headline_metrics`` picks the headline numbers (reports/metrics.json); ``paper_comparison_markdown``
puts every number beside the paper's, from the pieces below (each one table's rows);
``write_report`` writes both files atomically. ``experiments/report.py`` composes the config and
calls these.
"""
from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from fluidfilm import io

#: the paper's verdicts on its Fig. 4 cases: which cases each network was satisfactory in, and its words
PAPER_SATISFACTORY = {"single": set("e"), "split": set("abcde")}
PAPER_WORDS = {"single": "satisfactory only in the largest-imbalance case (e)", "split": "satisfactory in a-e, not f, g"}
#: the eccentricity bands of the held-out error table (keys of a model report's metrics)
BAND_KEYS = ("test_rel_err_median_band_0_0.5", "test_rel_err_median_band_0.5_0.7", "test_rel_err_median_band_0.7_1",
             "test_rel_err_median_eps_below_0.7")
PAPER_NETWORKS = ("paper_single", "paper_split")
COMPARED = ("single", "split", "best")


@dataclass(frozen=True)
class ReportInputs:
    """Everything the report reads, as loaded from the stages' output files."""

    comparison: dict                  # reports/comparison.json
    train_time: dict                  # reports/train_time.json
    trajectories: pd.DataFrame        # reports/trajectory_metrics.csv
    speed: pd.DataFrame               # reports/speed.csv
    models: dict[str, dict]           # models/<name>/report.json, in the config's order
    dataset_meta: dict                # <dataset_dir>/_metadata.json
    control: dict                     # reports/control.json
    active_dataset_meta: dict
    active_model: dict                # models/<active_model>/report.json
    batch_speed: dict                 # reports/batch_speed.json
    controller_training_speed: dict   # reports/controller_training_speed.json
    characteristics: dict | None      # reports/characteristics.json, where that stage ran
    ensemble: dict | None = None      # reports/ensemble.json, where that stage ran
    grading_study: dict | None = None  # reports/grading_study/summary.json, where that stage ran
    ablation: dict | None = None      # reports/ablation/summary.json, where that stage ran
    error_map: dict | None = None     # reports/error_map.json, where that stage ran
    paper_scale: dict | None = None   # reports/paper_scale.json, where that stage ran
    # the other PAPER_SCALE_REPORTS (make paper-scale-curve / paper-full-scale, committed), those present
    paper_scale_beyond: tuple = ()
    runup: dict | None = None         # reports/runup.json, where that stage ran
    cavitation_rules: dict | None = None  # reports/cavitation_rules.json, where that stage ran
    universal: dict | None = None     # reports/universal.json, where that stage ran
    online_assessment: dict | None = None  # reports/online_assessment.json, where that stage ran
    jfo_surrogate: dict | None = None  # reports/jfo_surrogate.json, where that stage ran
    # reports/reproduce_timing.json: each stage's last wall time, written by `make reproduce` as stages finish
    # (not a DVC dependency: it is the pipeline's own record, and changes while the pipeline runs)
    reproduce_timing: dict | None = None
    dvc_stages: tuple = ()            # the stages of dvc.yaml beside report_dir, where it is found


#: the paper_scale study's reports, the pipeline's own first: the stage's (40 k and the ablation), then the
#: committed runs beyond it, the curve's larger sizes (make paper-scale-curve) and the full scale (make paper-full-scale)
PAPER_SCALE_REPORTS = ("paper_scale.json", "paper_scale_curve.json", "paper_full_scale.json", "paper_scale_ablation.json")


def _load(path: Path) -> Any:
    return json.loads(Path(path).read_text())


def _merge_ranking_check(out: dict, variant: dict, source: str) -> None:
    """``make train-time-ranking``'s ranking check, where the stage's own run has none."""
    if "ranking_check" not in out and "ranking_check" in variant:
        out["ranking_check"] = dict(variant["ranking_check"], **{"from": source})


def _merge_seeds(out: dict, variant: dict, source: str) -> None:
    """``make jfo-surrogate-seeds``'s other training seeds, and the least count of satisfactory cases over all."""
    seeds = dict(out.get("seeds", {}))
    for k, rec in variant.get("seeds", {}).items():
        seeds.setdefault(k, dict(rec, **{"from": source}))
    out["seeds"] = seeds
    out.setdefault("metrics", {})["satisfactory_cases_jfo_surrogate_min_over_seeds"] = min(
        len(s["satisfactory_cases"]) for s in seeds.values())


#: the long variants outside the pipeline's 60-minute budget: a stage's report -> the committed report of the
#: Makefile target that runs its variant (with the machine and date it ran on), and how its part is merged in
VARIANT_REPORTS: dict[str, tuple[str, Callable[[dict, dict, str], None]]] = {
    "train_time.json": ("train_time_ranking.json", _merge_ranking_check),
    "jfo_surrogate.json": ("jfo_surrogate_seeds.json", _merge_seeds)}


def with_variants(report_dir: Path | str, name: str) -> dict:
    """A stage's report ``name`` with its committed variant's part merged in, where the stage's own run has none:
    ``train_time.json`` gains ``ranking_check`` from ``make train-time-ranking``'s report; ``jfo_surrogate.json``
    gains the other training seeds from ``make jfo-surrogate-seeds``'s (and its ``..._min_over_seeds`` key is
    taken over all of them).  The part taken is marked ``from`` (file, machine, date).

    Examples
    --------
    >>> import json, tempfile
    >>> d = Path(tempfile.mkdtemp())
    >>> _ = (d / "jfo_surrogate.json").write_text(json.dumps({"seed": 0, "seeds": {"0": {"satisfactory_cases": "abcdefg"}},
    ...     "metrics": {"satisfactory_cases_jfo_surrogate_min_over_seeds": 7}}))
    >>> _ = (d / "jfo_surrogate_seeds.json").write_text(json.dumps({"machine": "m", "date": "d",
    ...     "seeds": {"0": {"satisfactory_cases": "abcdefg"}, "1": {"satisfactory_cases": "abcfg"}}}))
    >>> js = with_variants(d, "jfo_surrogate.json")
    >>> sorted(js["seeds"]), js["metrics"]["satisfactory_cases_jfo_surrogate_min_over_seeds"]
    (['0', '1'], 5)
    >>> js["seeds"]["1"]["from"]
    'reports/jfo_surrogate_seeds.json (m, d)'
    """
    rd = Path(report_dir)
    out = _load(rd / name)
    if name not in VARIANT_REPORTS:
        return out
    extra, merge = VARIANT_REPORTS[name]
    if not (rd / extra).exists():
        return out
    v = _load(rd / extra)
    merge(out, v, f"reports/{extra} ({v['machine']}, {v['date']})")
    return out


def load_inputs(report_dir: Path | str, models_dir: Path | str, dataset_dir: Path | str, models: Sequence[str],
                active_model: str, active_dataset_dir: Path | str) -> ReportInputs:
    """Read the report's inputs; a missing file raises ``FileNotFoundError`` naming it."""
    rd, md = Path(report_dir), Path(models_dir)
    charac = rd / "characteristics.json"
    ens = rd / "ensemble.json"

    def optional(path: Path) -> Any:
        return _load(path) if path.exists() else None

    return ReportInputs(
        comparison=_load(rd / "comparison.json"), train_time=with_variants(rd, "train_time.json"),
        trajectories=pd.read_csv(rd / "trajectory_metrics.csv"), speed=pd.read_csv(rd / "speed.csv"),
        models={m: _load(md / m / "report.json") for m in models},
        dataset_meta=_load(Path(dataset_dir) / "_metadata.json"), control=_load(rd / "control.json"),
        active_dataset_meta=_load(Path(active_dataset_dir) / "_metadata.json"),
        active_model=_load(md / active_model / "report.json"), batch_speed=_load(rd / "batch_speed.json"),
        controller_training_speed=_load(rd / "controller_training_speed.json"),
        characteristics=optional(charac), ensemble=optional(ens),
        grading_study=optional(rd / "grading_study" / "summary.json"), ablation=optional(rd / "ablation" / "summary.json"),
        error_map=optional(rd / "error_map.json"), paper_scale=optional(rd / "paper_scale.json"),
        paper_scale_beyond=tuple(_load(rd / name) for name in PAPER_SCALE_REPORTS[1:] if (rd / name).exists()),
        runup=optional(rd / "runup.json"), cavitation_rules=optional(rd / "cavitation_rules.json"),
        universal=optional(rd / "universal.json"),
        online_assessment=optional(rd / "online_assessment.json"), jfo_surrogate=(
            with_variants(rd, "jfo_surrogate.json") if (rd / "jfo_surrogate.json").exists() else None),
        reproduce_timing=optional(rd / "reproduce_timing.json"), dvc_stages=pipeline_stages(rd))


def pipeline_stages(report_dir: Path | str) -> tuple[str, ...]:
    """The stages of the ``dvc.yaml`` beside ``report_dir`` (empty where there is none)."""
    import yaml

    dvc_file = Path(report_dir).resolve().parent / "dvc.yaml"
    if not dvc_file.exists():
        return ()
    return tuple(yaml.safe_load(dvc_file.read_text()).get("stages") or {})


def untimed_stages(stages: Sequence[str], timed: Mapping) -> list[str]:
    """The ``stages`` with no time among ``timed`` (reproduce_timing.json's, where a foreach stage is
    ``name@key``): the stages a total of ``timed`` leaves out."""
    names = {k.split("@")[0] for k in timed}
    return [s for s in stages if s not in names]


def reproduce_time_metrics(timing: Mapping | None, stages: Sequence[str]) -> dict:
    """``reproduce_total_min``: the full profile's stages' last wall times summed (each stage's run may be
    from another sitting: a full run is longer than one); ``reproduce_total_min_partial``: whether stages of
    ``stages`` have no time yet (the total is then a lower bound), ``reproduce_stages_untimed`` which."""
    full = (timing or {}).get("full") or {}
    times = full.get("stages") or {}
    if not times:
        return {}
    missing = untimed_stages(stages, times)
    return {"reproduce_total_min": sum(times.values()) / 60.0, "reproduce_total_min_partial": bool(missing),
            "reproduce_stages_untimed": missing}


def _f(x, spec=".1f"):
    return "n/a" if x is None else format(x, spec)


def markdown_table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    """A Markdown table (one line per row, ending in a newline): every table of the report and the pages."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines) + "\n"


def generation_seconds(meta: Mapping) -> float:
    """A dataset's generation time: the total over resumed runs where recorded, else the last run's."""
    return meta.get("generation_seconds_total", meta["generation_seconds_last_run"])


def _seeds_needed(tt: dict) -> str:
    """', a +-10-point interval would need about N seeds' when the study could not afford them."""
    need, target = tt.get("train_time_seeds_needed_for_target"), tt.get("train_time_reduction_ci95_target")
    if not need or target is None or tt["train_time_reduction_ci95"] <= target:
        return ""
    return f"; a +-{target:.0f}-point interval would need about {need} seeds"


def headline_metrics(inp: ReportInputs) -> dict:
    """reports/metrics.json: the headline numbers of every stage, flat (what MLflow logs too)."""
    tt, comp, traj = inp.train_time, inp.comparison, inp.trajectories
    metrics = {
        "train_time_single_s": tt["train_time_single_s"],
        "train_time_split_s": tt["train_time_split_s"],
        "train_time_reduction_pct": tt["train_time_reduction_pct"],
        "train_time_reduction_pct_per_seed_min": tt["train_time_reduction_pct_per_seed_min"],
        "train_time_reduction_pct_per_seed_max": tt["train_time_reduction_pct_per_seed_max"],
        "train_time_all_reached_target": tt["all_reached_target"],
        "train_time_reduction_ci95": tt["train_time_reduction_ci95"],
        "train_time_reduction_pct_mean_of_seeds": tt.get("train_time_reduction_pct_mean_of_seeds"),
        "train_time_seeds_needed_for_target": tt.get("train_time_seeds_needed_for_target"),
        "train_time_seeds": tt["train_time_seeds"],
        "train_time_converged": tt["train_time_converged"],
        "train_time_protocol": tt["train_time_protocol"],
        "train_time_samples_per_seed": tt["train_time_samples_per_seed"],
        "train_time_split_parallel_s": tt["train_time_split_parallel_s"],
        "train_time_reduction_at_equal_accuracy_pct": tt["reduction_at_equal_accuracy_pct_mean"],
        "train_time_ranking_same_at_2x": tt.get("ranking_check", {}).get("same_ranking"),
        "train_time_2x_consistent": tt.get("ranking_check", {}).get("consistent"),
        "speedup_trajectory_single": comp["speedup_trajectory_single"],
        "speedup_trajectory_split": comp["speedup_trajectory_split"],
        "speedup_trajectory_best": comp["speedup_trajectory_best"],
        "speedup_force_eval": comp["speedup_force_eval_split"],
        "speedup_force_eval_single": comp["speedup_force_eval_single"],
        "speedup_force_eval_split": comp["speedup_force_eval_split"],
        "speedup_force_eval_best": comp["speedup_force_eval_best"],
        "dataset_samples": inp.dataset_meta["n_samples"],
        "dataset_generation_s": generation_seconds(inp.dataset_meta),
    }
    for m in COMPARED:
        rows = traj[traj.model == m]
        for _, r in rows.iterrows():
            metrics[f"orbit_rms_pct_{m}_{r.case}"] = float(r.rms_pct)
        metrics[f"satisfactory_cases_{m}"] = int(rows.satisfactory.astype(bool).sum())
        if "satisfactory_paper_reading" in rows:  # the paper's reading (span and shape, not position)
            metrics[f"satisfactory_cases_{m}_paper_reading"] = int(rows.satisfactory_paper_reading.astype(bool).sum())
    for name, rep in inp.models.items():
        metrics[f"test_rel_err_median_{name}"] = rep["metrics"]["test_rel_err_median"]
        metrics[f"test_rel_err_p99_{name}"] = rep["metrics"]["test_rel_err_p99"]
        for k, v in rep["metrics"].items():  # per eccentricity band (the paper's networks)
            if k.startswith("test_rel_err_median_band_") or k == "test_rel_err_median_eps_below_0.7":
                metrics[k.replace("test_rel_err_median_", f"test_rel_err_median_{name}_")] = v
    for k in [k for k in comp if k.startswith(("speedup_force_", "speedup_trajectory_")) and "sparse" in k]:
        metrics[k] = comp[k]
    for k in ("sparse_time_per_force_us", "sparse_trajectory_time_estimated_s"):
        if k in comp:
            metrics[k] = comp[k]
    control = inp.control
    ctl = control["controllers"]
    metrics.update({
        "controller_amplitude_reduction_pct": control["controller_amplitude_reduction_pct"],
        "mpc_amplitude_reduction_pct": control["mpc_amplitude_reduction_pct"],
        "controller_decision_ms_dqn": ctl["dqn"]["decision_ms_median"],
        "controller_decision_ms_mpc": ctl["mpc"]["decision_ms_median"],
        "active_dataset_samples": inp.active_dataset_meta["n_samples"],
        "active_dataset_generation_s": generation_seconds(inp.active_dataset_meta),
        "test_rel_err_median_active": inp.active_model["metrics"]["test_rel_err_median"],
    })
    if inp.characteristics is not None:  # the characteristics stage: K/C and whirl-threshold errors of the surrogates
        metrics.update(inp.characteristics["metrics"])
    if inp.ensemble is not None:  # the ensemble stage: every seed of the best model, the ensemble, the hybrids
        extra = ensemble_metrics(inp.ensemble)
        clash = sorted(set(extra) & set(metrics))
        if clash:  # a key of another stage would be silently replaced by the ensemble stage's value
            raise ValueError(f"the ensemble stage's metrics would overwrite {clash}")
        metrics.update(extra)
    if inp.error_map is not None:  # the error map: the seeds' force errors held out and along the reference orbits
        metrics.update(error_map_metrics(inp.error_map))
    # the paper's networks at larger sizes, the recipe's ingredients, the full scale
    metrics.update(paper_scale_all_metrics(inp.paper_scale, inp.paper_scale_beyond))
    if inp.runup is not None:  # the run-up: onset of whirl from the transient against Lund's threshold
        metrics.update(inp.runup["metrics"])
    if inp.cavitation_rules is not None:  # Guembel and Swift-Stieber against the mass-conserving film
        metrics.update(inp.cavitation_rules["metrics"])
    if inp.universal is not None:  # the universal plain-bearing surrogate on bearings it never saw
        metrics.update(universal_metrics(inp.universal))
    if inp.online_assessment is not None:  # the on-line estimator against the reference plant and the baseline
        metrics.update(inp.online_assessment["metrics"])
    if inp.jfo_surrogate is not None:  # the mass-conserving film's surrogate with memory against its reference
        metrics.update(inp.jfo_surrogate["metrics"])
    for study in ("grading_study", "ablation"):
        summary = getattr(inp, study)
        if summary is not None:
            metrics[f"{study}_jobs"] = summary["n_jobs"]
            metrics[f"{study}_lowest_orbit_p99"] = summary["lowest_orbit_p99"]
            metrics[f"{study}_lowest_orbit_p99_job"] = summary["lowest_orbit_p99_job"]
    # fast surrogates (docs/fast_surrogates.md): per-force cost, batched trajectories, controller training
    per_eval = dict(zip(inp.speed.model, inp.speed.time_per_eval_us))
    metrics["force_eval_us_best"] = float(per_eval["best"])
    metrics["trajectories_per_s_batch_speedup"] = inp.batch_speed["trajectories_per_s_batch_speedup"]
    metrics["trajectories_per_s_single_speedup"] = inp.batch_speed["trajectories_per_s_single_speedup"]
    for key in ("trajectories_per_s_batch_speedup_threads", "batch_thread_scaling"):  # since the threads arm
        if key in inp.batch_speed:
            metrics[key] = inp.batch_speed[key]
    # the speed issue's name for one trajectory against the graded reference, measured side by side (batch_speed)
    metrics["speedup_trajectory_best_vs_reference"] = metrics["trajectories_per_s_single_speedup"]
    metrics["controller_training_speedup"] = inp.controller_training_speed["controller_training_speedup"]
    metrics.update(reproduce_time_metrics(inp.reproduce_timing, inp.dvc_stages))
    metrics["surrogate_goals_met"] = sum(g["met"] is True for g in surrogate_goals(metrics))
    metrics["surrogate_goals"] = len(SURROGATE_GOALS)
    return metrics


def paper_scale_metrics(ps: Mapping) -> dict:
    """The paper_scale study's flat keys (``studies.paper_scale.summary_keys``: per size and structure, per
    ablation variant, at full scale) as they are in its report."""
    prefixes = ("satisfactory_cases_", "equilibrium_offset_pct_c_", "orbit_rms_pct_max_", "train_time_s_",
                "static_force_error_share_max_", "train_time_reduction_pct_full_scale_lm",
                "train_time_converged_full_scale_lm", "converged_")
    return {k: v for k, v in ps.items() if k.startswith(prefixes)}
def paper_scale_all_metrics(own: Mapping | None, beyond: Sequence[Mapping] = ()) -> dict:
    """``paper_scale_metrics`` of the pipeline's report (``own``, may be None) and of the committed reports of
    the runs beyond it (``beyond``: the curve's larger sizes, the full scale); a key of the pipeline's own run
    wins over the same key in a report that included its records."""
    out = dict(paper_scale_metrics(own)) if own is not None else {}
    for rep in beyond:
        out.update({k: v for k, v in paper_scale_metrics(rep).items() if k not in out})
    return out


#: the universal surrogate's keys in reports/universal.json, copied into the metrics as they are
UNIVERSAL_KEYS = ("universal_rel_err_median", "universal_rel_err_p99", "universal_kc_max_rel_err_direct",
                  "universal_kc_max_rel_err_cross", "universal_whirl_threshold_rel_err", "satisfactory_cases_universal",
                  "force_eval_us_universal")


def universal_metrics(u: Mapping) -> dict:
    """The universal surrogate's headline numbers (fractions, not per cent; microseconds per force)."""
    return {k: u[k] for k in UNIVERSAL_KEYS}


def error_map_metrics(em: Mapping) -> dict:
    """Held-out and orbit-state force errors of every model of the error map (fractions, not per cent)."""
    out = {}
    for name, m in em["models"].items():
        for q in ("median", "p99"):
            out[f"orbit_state_rel_err_{q}_{name}"] = m["orbit_states"][q]
    seeds = [k for k in em["models"] if k == "best" or k.startswith("best_s")]
    if seeds:
        out["test_rel_err_p99_best_max_over_seeds"] = max(em["models"][k]["held_out"]["p99"] for k in seeds)
        out["orbit_state_rel_err_p99_best_max_over_seeds"] = max(em["models"][k]["orbit_states"]["p99"] for k in seeds)
    return out


#: the goals of the fast-and-accurate-surrogate work for the best model: (metrics key, what, target,
#: direction, scale to the unit shown, unit, what was tried); a key missing from the metrics is "not measured"
SURROGATE_GOALS = (
    ("satisfactory_cases_best_min_over_seeds", "Fig. 4 cases satisfactory, worst of the 3 training seeds", 7, ">=",
     1, "/7", "three seeds, their ensemble and hybrids with the reference (the ensemble table); the grading "
              "study and the ablation (which grading and which ingredients buy accuracy)"),
    ("test_rel_err_median_best", "median force error, held-out random states", 0.5, "<=", 100, " %",
     "orbit-graded data, the whirl frame (journal's frame, the film's homogeneity in its drive), physics "
     "scaling, five blended regions, tanh units, longer training"),
    ("orbit_state_rel_err_median_best", "median force error, states along the reference orbits", 0.5, "<=", 100, " %",
     "as above; the error map shows where the errors sit"),
    ("test_rel_err_p99_best", "99th-percentile force error, held-out random states", 10, "<=", 100, " %",
     "as above; where the worst errors sit (eccentricity, speed): the error map"),
    ("orbit_state_rel_err_p99_best", "99th-percentile force error, along the reference orbits", 10, "<=", 100, " %",
     "as above"),
    ("force_eval_us_best", "time per force evaluation", 0.2, "<=", 1, " us",
     "a one-state kernel generated per model shape (docs/fast_surrogates.md): most of the rest is the "
     "network's own arithmetic"),
    ("speedup_trajectory_best_vs_reference", "one trajectory, surrogate vs graded reference", 20, ">=", 1, "x",
     "the compiled integrator with the surrogate kernel"),
    ("trajectories_per_s_batch_speedup", "batched trajectories, surrogate vs graded reference, one thread", 100,
     ">=", 1, "x", "the batched force kernel once per RK4 stage for the whole batch (states along the vector "
     "lanes), float32 networks"),
    ("trajectories_per_s_batch_speedup_threads", "batched trajectories, surrogate vs graded reference, all cores",
     100, ">=", 1, "x", "as above, the batch split across the cores; bounded by the scaling below"),
    ("batch_thread_scaling", "batched surrogate throughput, all cores vs one", 1.7, ">=", 1, "x",
     "chunks per core, pinning (worse), probes of the cores: the two vCPUs' vector throughput varies from run to "
     "run (docs/fast_surrogates.md)"),
    ("controller_decision_ms_mpc", "MPC time per decision (control period 20 ms) at the amplitude reduction below",
     2, "<=", 1, " ms", "candidates as one batch, 4e-4 s prediction step, one-revolution horizon; the active "
     "surrogate's SiLU units through the rational tanh (docs/fast_surrogates.md)"),
    ("mpc_amplitude_reduction_pct", "MPC amplitude reduction on the reference model", 57, ">=", 1, " %",
     "as above"),
    ("controller_training_speedup", "DQN training, surrogate vs reference, same steps", 10, ">=", 1, "x",
     "measured per environment step; the environment's own cost bounds the ratio"),
    ("reproduce_total_min", "make reproduce, every stage (the sum of each stage's last run)", 60, "<=", 1, " min",
     "stages that integrate use the fast kernels, and numba's cache keeps the stage-batched loop between "
     "processes; Lightning steps 1.6x faster with a vectorised tanh and fused Adam; the Levenberg-Marquardt fits "
     "form J^T J by symmetric rank-k updates on the Jacobian's structure, on both cores (SciPy's dsyrk held the "
     "GIL), the universal fit's step 3.7x faster (docs/universal.md) and both rules' fits in one pool; training "
     "to a stated rule is most of the time (the stage table in docs/results.md)"),
    # the engineer's checks (bearing characteristics): K/C along the equilibrium locus, eps 0.1-0.9
    ("kc_max_rel_err_direct_best", "stiffness/damping against the grid-converged reference, largest error of "
     "the direct terms, eps 0.1-0.9", 2, "<=", 100, " %",
     "the whirl frame and tanh units (ReLU / polar frame: 1400 %); what is left sits at eps 0.9 "
     "(docs/characteristics.md); against the 30x30 grid: kc_max_rel_err_*_vs_paper_grid"),
    ("kc_max_rel_err_cross_best", "stiffness/damping against the grid-converged reference, largest error of "
     "the cross terms, eps 0.1-0.9", 5, "<=", 100, " %", "as above"),
    ("whirl_threshold_rel_err_best", "whirl threshold speed against the grid-converged reference", 2, "<=", 100,
     " %", "as above (ReLU / polar frame: no threshold found)"),
)


def surrogate_goals(metrics: Mapping) -> list[dict]:
    """Each goal of ``SURROGATE_GOALS`` against its measured value: met (True/False) or not measured (None)."""
    rows = []
    for key, what, target, direction, scale, unit, tried in SURROGATE_GOALS:
        value = metrics.get(key)
        measured = None if value is None else float(value) * scale
        met = None if measured is None else (measured >= target if direction == ">=" else measured <= target)
        # a lower bound (a total with parts not measured) misses a limit it already exceeds, else is unknown
        partial = bool(metrics.get(f"{key}_partial"))
        if partial and measured is not None and not (direction == "<=" and measured > target):
            met = None
        gap = ""  # how far a missed goal is: a limit overshot by a factor, a target reached to a share
        if met is False and measured is not None:
            gap = (f"{measured / target:.3g}x the limit" if direction == "<=" else f"{100 * measured / target:.3g} % of it")
        rows.append({"key": key, "what": what, "target": f"{direction.replace('>=', '≥').replace('<=', '≤')} {target:g}{unit}",
                     "measured": None if measured is None else ("≥ " if partial else "") + f"{measured:.3g}{unit}"
                     + (" (stages not timed)" if partial else ""), "met": met, "gap": gap,
                     "tried": tried})
    return rows


STUDY_HEADER = ["job", "samples", "generation s", "training s (sum of networks; split: 1 thread each)", "held-out median %", "held-out p99 %",
                "orbit-state median %", "orbit-state p99 %", "Fig. 4 cases", "K/C error direct / cross %", "us per force"]


def _kc_cell(job: Mapping) -> str:
    """Largest K/C errors of a job in per cent, or why there are none ("no equilibrium", "not differentiable",
    "-" where not measured)."""
    status = job.get("kc_status", "not measured")
    if status == "not measured":
        return "-"
    if status != "ok":
        return str(status)
    return f"{100 * job['kc_max_rel_err_direct']:.0f} / {100 * job['kc_max_rel_err_cross']:.0f}"


def study_rows(summary: Mapping) -> list[list[str]]:
    """One row per job of a grading study or ablation (``grading.summarise``), in the table's order."""
    rows = []
    for j in summary["jobs"]:
        cases = "-" if j.get("n_satisfactory") is None or j["n_satisfactory"] != j["n_satisfactory"] else \
            f"{int(j['n_satisfactory'])}/7 ({j.get('satisfactory_cases') or '-'})"
        rows.append([f"`{j['job']}`", f"{int(j['n_samples']):,}", f"{j['generation_s']:.0f}", f"{j['train_time_s']:.0f}",
                     f"{100 * j['held_out_rel_err_median']:.2f}", f"{100 * j['held_out_rel_err_p99']:.0f}",
                     f"{100 * j['orbit_states_rel_err_median']:.2f}", f"{100 * j['orbit_states_rel_err_p99']:.0f}",
                     cases, _kc_cell(j), f"{j['time_per_eval_us']:.2f}"])
    return rows


def study_table(summary: Mapping) -> str:
    """A grading study's or ablation's jobs, one row each (the report and the results page)."""
    return markdown_table(STUDY_HEADER, study_rows(summary))


def study_section(summary: Mapping, title: str, figure: str) -> str:
    """Markdown: a grading study's or ablation's jobs as a table, and its figure."""
    return f"""
## {title}

{study_table(summary)}
![{title}]({figure})
"""


def goals_table(metrics: Mapping) -> str:
    """The surrogate goals, what was measured, met or missed (the report and the results page)."""
    return markdown_table(["goal", "target", "measured", "", "what was done"],
                          [[g["what"], g["target"], g["measured"] or "not measured", goal_verdict(g), g["tried"]]
                           for g in surrogate_goals(metrics)])


def goals_section(metrics: Mapping) -> str:
    """Markdown: the surrogate goals, what was measured, met or missed."""
    return f"""
## The best surrogate against its goals

{goals_table(metrics)}"""


def goal_verdict(goal: Mapping) -> str:
    """"met", "not measured", or "**missed** (by how much)"."""
    if goal["met"] is None:
        return "not measured"
    return "met" if goal["met"] else f"**missed** ({goal['gap']})"


# --- the tables' rows ---------------------------------------------------------------------------------
def _one(traj: pd.DataFrame, case: str, model: str):
    return traj[(traj.case == case) & (traj.model == model)].iloc[0]


def case_rows(traj: pd.DataFrame) -> list[str]:
    """Fig. 4 accuracy per case: reference span, then RMS / Hausdorff % of c (satisfactory) per model."""
    out = []
    for case in sorted(traj.case.unique()):
        ref = _one(traj, case, "reference")
        cells = []
        for m in COMPARED:
            r = _one(traj, case, m)
            ok = "yes" if bool(r.satisfactory) else "no"
            cells.append(f"{_f(r.rms_pct, '.2f')} / {_f(r.hausdorff_pct, '.2f')} ({ok})")
        out.append(f"| {case} | {ref.span:.3f} | " + " | ".join(cells) + " |")
    return out


def verdict_rows(traj: pd.DataFrame) -> list[str]:
    """Per case: the paper's verdict and ours, for the single and the split network."""
    out = []
    for case in sorted(traj.case.unique()):
        cells = []
        for m in ("single", "split"):
            ours = "yes" if bool(_one(traj, case, m).satisfactory) else "no"
            cells.append(f"{'yes' if case in PAPER_SATISFACTORY[m] else 'no'} | {ours}")
        out.append(f"| {case} | " + " | ".join(cells) + " |")
    return out


def band_rows(models: Mapping[str, dict]) -> list[str]:
    """Held-out median error per eccentricity band of the paper's networks, % ("n/a" where not measured)."""
    out = []
    for n in PAPER_NETWORKS:
        mt = models[n]["metrics"] if n in models else {}
        out.append(f"| {n} | " + " | ".join(_f(100 * mt[k], ".1f") if k in mt else "n/a" for k in BAND_KEYS) + " |")
    return out


def network_rows(models: Mapping[str, dict]) -> list[str]:
    """One row per network of the paper's models: band, rows, epochs, stop reason, errors, time."""
    out = []
    for n in PAPER_NETWORKS:
        if n in models:
            for k, net in enumerate(models[n]["report"]["networks"]):
                out.append(f"| {n} | {k} | {net['eps_low']:g}-{net['eps_high']:g} | {net['n_train']:,} | "
                           f"{net['epochs']} | {net.get('stop_reason', 'n/a')} | {_f(net.get('val_rel_rmse'), '.4f')} | "
                           f"{_f(net.get('test_rel_rmse'), '.4f')} | {net['train_time_s']:.1f} |")
    return out


def seed_rows(tt: Mapping) -> str:
    """The training-time study per seed."""
    return "\n".join(
        f"| {r['seed']} | {r['single']['train_time_s']:.1f} | {r['split']['train_time_s']:.1f} | "
        f"{r['reduction_pct']:.1f} | {_f(r['time_to_equal_accuracy_split_s'])} | "
        f"{', '.join(str(n['epochs']) for n in r['single']['networks'])} / "
        f"{', '.join(str(n['epochs']) for n in r['split']['networks'])} | "
        f"{', '.join(r['single']['stop_reasons'] + r['split']['stop_reasons'])} | "
        f"{r['single']['val_rel_rmse']:.4f} / {r['split']['val_rel_rmse']:.4f} |" for r in tt["runs"])


def ranking_line(tt: Mapping) -> str:
    """The ranking check at twice the study's size, led by its interval, or "not run."."""
    rc = tt.get("ranking_check")
    if not rc:
        return "not run."
    head = (f"{rc['train_time_samples_per_seed']:,} samples per seed ({rc['train_time_seeds']} seeds): reduction "
            f"{rc['train_time_reduction_pct']:.1f} %, 95 % interval {rc['train_time_reduction_ci95_low']:.0f} to "
            f"{rc['train_time_reduction_ci95_high']:.0f} %"
            + (f" (`make train-time-ranking`: {rc['from']})" if "from" in rc else ""))
    ranking = f"faster {rc['ranking']['faster']}, more accurate {rc['ranking']['more_accurate']}"
    if "consistent" not in rc:
        return f"{head}; {ranking}: the ranking is {'the same' if rc['same_ranking'] else '**not** the same'}."
    if rc["consistent"]:
        # overlapping intervals: a flip of the point estimates' ranking is inside the noise
        return (f"{head}. It overlaps the study's interval: the two sizes do not measurably differ. By the point "
                f"estimates alone, {ranking}"
                + (": the study's ranking." if rc["same_ranking"] else ": not the study's ranking, but inside the noise."))
    return (f"{head}. It does **not** overlap the study's interval: the subsample size changes the answer "
            f"({ranking}).")


def sparse_line(comp: Mapping) -> str:
    """The paper-like sparse reference's cost and the surrogates' speed-ups over it, or "not measured"."""
    return ("not measured" if "sparse_time_per_force_us" not in comp else
            f"{comp['sparse_time_per_force_us']:.0f} us per force (55x55: {comp['sparse_time_per_force_dense_us']:.0f} us); "
            f"split {comp['speedup_force_split_vs_sparse_reference']:.0f}x per force, "
            f"{comp['speedup_trajectory_split_vs_sparse_reference']:.0f}x per trajectory; single "
            f"{comp['speedup_force_single_vs_sparse_reference']:.0f}x / "
            f"{comp['speedup_trajectory_single_vs_sparse_reference']:.0f}x")


def model_rows(models: Mapping[str, dict]) -> str:
    """Each compared model's network, split, scaling, test errors and training time."""
    return "\n".join(
        f"| {n} | {json.dumps(r['config']['model'])} | {r['config']['split']['boundaries']} | "
        f"{r['config']['scaling']['kind']} | {r['metrics']['test_rel_err_median']:.4f} | "
        f"{r['metrics']['test_rel_err_p99']:.3f} | {r['report']['train_time_s']:.0f} |" for n, r in models.items())


def speed_rows(speed: pd.DataFrame) -> str:
    return "\n".join(f"| {r.model} | {r.kind} | {r.time_per_eval_us:.2f} |" for r in speed.itertuples())


CONTROLLER_NAMES = {"none": "none (sleeve held at 0)", "dqn": "DQN (SB3)", "mpc": "MPC (surrogate)"}


def controller_table(ctl: Mapping[str, dict]) -> str:
    """Fig. 5 study, evaluated on the reference model: amplitude, friction, sleeve travel, decision time and
    axial force per controller (the report and the results page)."""
    rows = [[CONTROLLER_NAMES.get(n, n), f"{1e6 * r['max_amplitude_m']:.1f} µm", f"{r['amplitude_reduction_pct']:.1f} %",
             f"{1e6 * r['final_amplitude_m']:.1f} µm", f"{r['mean_friction_power_W']:.2f} W",
             f"{1e3 * r['sleeve_travel_m']:.1f} mm", f"{r['decision_ms_median']:.2f} ms",
             _f(r.get("axial_force_N_mean_last_rev"), ".1f") + " N"] for n, r in ctl.items()]
    return markdown_table(["controller", "largest orbit amplitude", "reduction vs none", "amplitude at the end",
                           "mean friction power", "sleeve travel", "time per decision",
                           "axial force (last revolution)"], rows)


def grid_label(ch: dict, model: str) -> str:
    """'30x30': the characteristics study's grid of ``model`` (reference / reference_converged)."""
    grid = ch["grids"][model]
    return f"{grid[0]}x{grid[1]}"


def characteristics_section(ch: dict) -> str:
    """Markdown summary of reports/characteristics.json."""
    def pct(x):  # None: not finite (e.g. a surrogate stable over the whole speed bracket)
        return None if x is None else 100.0 * x

    coarse, fine = (grid_label(ch, k) for k in ("reference", "reference_converged"))
    paper_grid = ch.get("kc_max_rel_err_paper_grid", {})
    thr_paper = ch.get("whirl_threshold_rel_err_paper_grid", {})

    def vs_paper(n, key):
        return _f(pct(paper_grid[n][key]), '.2f') if n in paper_grid else "-"

    rows = "\n".join(f"| {n} | {_f(pct(e['direct']), '.2f')} | {_f(pct(e['cross']), '.2f')} | "
                     f"{_f(pct(ch['whirl_threshold_rel_err'].get(n)), '.2f')} | {vs_paper(n, 'direct')} | "
                     f"{vs_paper(n, 'cross')} | {_f(pct(thr_paper.get(n)), '.2f') if n in thr_paper else '-'} |"
                     for n, e in ch["kc_max_rel_err"].items())
    checks = "\n".join(f"| {c['factor']:.2f} | {c['speed_rpm']:.0f} | {c['ratio']:.3g} | {c['status']} |"
                        for c in ch["nonlinear_checks"])
    return f"""
## Bearing characteristics (stiffness, damping, whirl threshold)

Onset of oil whirl of the paper's rotor ({ch['rotor_mass_per_bearing_kg']:.2f} kg per bearing), reference model:
{ch['threshold']['reference']['speed_rpm']:.0f} rpm (whirl ratio {ch['threshold']['reference']['whirl_ratio']:.3f}).

Errors along the equilibrium locus (eps 0.1-0.9), first against the grid-converged reference ({fine},
{ch['threshold']['reference_converged']['speed_rpm']:.0f} rpm), then against the paper's {coarse} grid (the row
"reference" is that grid against the converged one; docs/characteristics.md, "Which reference").

| model | K/C direct % | K/C cross % | threshold % | vs {coarse}: K/C direct % | K/C cross % | threshold % |
|---|---|---|---|---|---|---|
{rows}

| nonlinear check, x threshold | speed rpm | amplitude last/first | status |
|---|---|---|---|
{checks}

![stability map](figures/characteristics_stability_map.png)

![coefficients](figures/characteristics_coefficients.png)
"""


def ensemble_metrics(ens: Mapping) -> dict:
    """The ensemble stage's headline numbers: verdicts per seed, of the ensemble and of each hybrid."""
    out: dict = {"best_seeds_all_seven": int(ens["n_seeds_all_cases"]), "best_seeds": len(ens["members"]),
                 "satisfactory_cases_best_min_over_seeds": min(int(ens["models"][m]["n_satisfactory"])
                                                               for m in ens["members"])}
    for name, m in ens["models"].items():
        # (``satisfactory_cases_<model>`` is the compare stage's count; these are the ensemble stage's run)
        out[f"seed_study_satisfactory_{name}"] = int(m["n_satisfactory"])
        out[f"seed_study_cases_{name}"] = m["satisfactory_cases"]
        if "flagged_share_mean" in m:
            out[f"flagged_share_mean_{name}"] = m["flagged_share_mean"]
            out[f"speedup_trajectory_{name}"] = m["speedup_trajectory"]
    cal = ens.get("flag_calibration")
    if cal is not None:  # the flag on the held-out set: does it mark the states where the ensemble is wrong?
        out.update({f"ensemble_flag_{k}_held_out": cal[k] for k in ("flagged_share", "wrong_share", "recall",
                                                                    "precision")})
    return out


def ensemble_block(ens: Mapping) -> str:
    """reports/ensemble.json: the seeds' verdicts, the flag, the table per model and the flag's calibration on
    the held-out set (the report and the results page)."""
    n = ens["n_cases"]
    rows = []
    for name, m in ens["models"].items():
        share = m.get("flagged_share_mean")
        rows.append([name, f"{m['n_satisfactory']} of {n} ({m['satisfactory_cases'] or '-'})",
                     f"{m['orbit_rms_pct_max']:.2f} %", f"{m['orbit_hausdorff_pct_max']:.2f} %",
                     "-" if share is None else f"{100 * share:.2f} %", f"{m['speedup_trajectory']:.1f}x"])
    cal = ens.get("flag_calibration") or {}

    def pct(key: str, spec: str) -> str:  # a share of the calibration in per cent ("n/a" where undefined)
        return "n/a" if cal[key] is None else f"{100 * cal[key]:{spec}} %"

    calibration = "" if not cal else (
        f"\nThe flag on the held-out orbit test set ({cal['n_states']:,} states, reference forces): "
        f"{pct('flagged_share', '.1f')} of the states flagged, {pct('wrong_share', '.1f')} with the ensemble's "
        f"force error above the tolerance; of those, {pct('recall', '.0f')} flagged (recall), and "
        f"{pct('precision', '.0f')} of the flagged states are such (precision); median error flagged / "
        f"unflagged {pct('median_err_flagged', '.2f')} / {pct('median_err_unflagged', '.2f')}; "
        f"rank correlation of spread and error {_f(cal['spearman_spread_error'], '.2f')}.\n")
    return (f"Seeds satisfactory in all {n} cases: **{ens['n_seeds_all_cases']} of {len(ens['members'])}** "
            f"({', '.join(ens['members'])}). Ensemble flag: spread of the members' forces above "
            f"{100 * ens['rel_tol']:g} % of the mean force (floor {ens['floor_N']:g} N); hybrid_<tol>: the "
            "reference model answers wherever the spread exceeds <tol>.\n\n"
            + markdown_table(["model", "satisfactory", "worst orbit RMS (% of c)", "worst Hausdorff (% of c)",
                              "flagged / answered by the reference", "trajectory speed-up vs reference"], rows)
            + calibration)


def ensemble_section(ens: Mapping) -> str:
    """Markdown: the ensemble stage's block under its heading, and its figure."""
    return f"""
## Every seed of the best model, their ensemble, and the hybrid with the reference

{ensemble_block(ens)}
![ensemble](figures/ensemble.png)
"""


def paper_comparison_markdown(inp: ReportInputs, paper: Mapping, threshold_pct: float, active_model: str) -> str:
    """reports/paper_comparison.md: every number beside the paper's (``paper``: the config's paper values)."""
    md = _body(inp, paper, threshold_pct, active_model)
    if inp.characteristics is not None:
        md += characteristics_section(inp.characteristics)
    if inp.ensemble is not None:
        md += ensemble_section(inp.ensemble)
    if inp.grading_study is not None:
        md += study_section(inp.grading_study, "Grading study: what each dataset grading buys", "grading_study/figure.png")
    if inp.ablation is not None:
        md += study_section(inp.ablation, "Ablation of the best surrogate's ingredients", "ablation/figure.png")
    if inp.error_map is not None:
        md += "\n## Where the best surrogate's force errors sit\n\n![error map](figures/error_map.png)\n"
    md += goals_section(headline_metrics(inp))
    return md


def _body(inp: ReportInputs, paper: Mapping, thr: float, active_model: str) -> str:
    comp, tt, data_meta, control = inp.comparison, inp.train_time, inp.dataset_meta, inp.control
    active_meta, active = inp.active_dataset_meta, inp.active_model
    ctl = control["controllers"]
    paper_words = PAPER_WORDS
    case_rows_, verdict_rows_ = case_rows(inp.trajectories), verdict_rows(inp.trajectories)
    band_rows_, net_rows = band_rows(inp.models), network_rows(inp.models)
    seeds, model_rows_, speed_rows_ = seed_rows(tt), model_rows(inp.models), speed_rows(inp.speed)
    ranking, sparse = ranking_line(tt), sparse_line(comp)
    return f"""# The paper's comparisons, reproduced

Machine: **{comp['machine']}** (no GPU). Paper: {paper['machine']}.
All numbers below are regenerated by `dvc repro`; headline values are in `reports/metrics.json`.

## Headline numbers

| quantity | paper | ours |
|---|---|---|
| dataset samples | {paper['samples']:,} | {data_meta['n_samples']:,} |
| dataset generation | hours (not given) | {data_meta.get('generation_seconds_total', data_meta['generation_seconds_last_run']):.0f} s |
| training time, single network | {paper['train_time_single_s'] / 3600:.2f} h | {tt['train_time_single_s']:.0f} s (median of {tt['n_seeds']} seeds, {tt['train_time_single_s_min']:.0f}-{tt['train_time_single_s_max']:.0f} s) |
| training time, split (3 networks) | {paper['train_time_split_s'] / 3600:.2f} h | {tt['train_time_split_s']:.0f} s ({tt['train_time_split_s_min']:.0f}-{tt['train_time_split_s_max']:.0f} s) |
| training time reduction, split vs single | {paper['train_time_reduction_pct']} % | {tt['train_time_reduction_pct']:.0f} % (per seed {tt['train_time_reduction_pct_per_seed_min']:.0f} to {tt['train_time_reduction_pct_per_seed_max']:.0f} %) |
| speed-up per force evaluation, split vs reference | {paper['speedup_force_model']}x | {comp['speedup_force_eval_split']:.1f}x (vs 30x30: {comp['speedup_force_eval_split_vs_30x30']:.1f}x, vs 55x55: {comp['speedup_force_eval_split_vs_55x55']:.1f}x) |
| speed-up per trajectory, single / split / best | {paper['speedup_force_model']}x | {comp['speedup_trajectory_single']:.1f}x / {comp['speedup_trajectory_split']:.1f}x / {comp['speedup_trajectory_best']:.1f}x |
| cases satisfactory, single | e only | {comp['satisfactory_cases_single'] or 'none'} |
| cases satisfactory, split | a-e | {comp['satisfactory_cases_split'] or 'none'} |
| cases satisfactory, best (ours) | - | {comp['satisfactory_cases_best'] or 'none'} |

Training-time rule: protocol `{tt['train_time_protocol']}` (min-max map, random 70/15/15 division, stop after
{tt['protocol']['max_fail']} epochs without a better validation error, at most {tt['max_epochs']} epochs), on
{tt['train_time_samples_per_seed']:,} random samples of the {tt['dataset_samples']:,} per seed, the same rows for both
structures. Reduction of the mean training time over {tt['train_time_seeds']} seeds: {tt['train_time_reduction_pct']:.1f} %,
paired bootstrap 95 % CI +-{tt['train_time_reduction_ci95']:.1f} points ({_f(tt['train_time_reduction_ci95_low'])} to
{_f(tt['train_time_reduction_ci95_high'])} %){_seeds_needed(tt)}. Every run stopped by the validation rule: {tt['train_time_converged']}.
The paper's own times (5 h 42 min, 4.5 h) give a 21 % reduction; its 26 % is the single network's extra time over the split's.
Time for the split networks to reach the single network's final validation error (same rows): mean reduction
{_f(tt['reduction_at_equal_accuracy_pct_mean'])} % ({tt['equal_accuracy_reached_seeds']} of {tt['train_time_seeds']} seeds got
there). The three split networks in parallel: {tt['train_time_split_parallel_s']:.1f} s (median, longest network).
Ranking check at twice the size, {ranking}

Paper-like reference (the same finite-difference system assembled as a sparse matrix and solved by SuperLU on
every call, 30x30 / 55x55, Gumbel): {sparse}.

## Fig. 4 verdicts with the converged paper networks (satisfactory: RMS and Hausdorff distance both within {thr} % of c)

| case | single: paper | single: ours | split: paper | split: ours |
|---|---|---|---|---|
{chr(10).join(verdict_rows_)}

Paper's words: single {paper_words['single']}; split {paper_words['split']}.

## Held-out median relative force error per eccentricity band, % (random test states)

| model | eps 0-0.5 | eps 0.5-0.7 | eps > 0.7 | eps < 0.7 |
|---|---|---|---|---|
{chr(10).join(band_rows_)}

## The paper networks, per network

| model | network | eps | training rows | epochs | stopped by | val rel. RMSE | test rel. RMSE | train s |
|---|---|---|---|---|---|---|---|---|
{chr(10).join(net_rows)}

## Fig. 4: trajectory accuracy per case

RMS distance / Hausdorff distance from the reference orbit over the settled cycles, in % of the clearance;
"satisfactory" means both are within {thr} %.

| case | reference span / c | single | split | best |
|---|---|---|---|---|
{chr(10).join(case_rows_)}

![Fig. 4](figures/fig4_comparison.png)

## Models

| model | network | split | scaling | test median rel. error | test p99 | train s |
|---|---|---|---|---|---|---|
{model_rows_}

## Speed per force evaluation (same compiled loop, same states)

| model | kind | us per evaluation |
|---|---|---|
{speed_rows_}

## Training time per seed

| seed | single s | split s | reduction % | split s to single's accuracy | epochs single / split | stopped by | val rel. RMSE single / split |
|---|---|---|---|---|---|---|---|
{seeds}

## Active conical bearing (Section 3.2, Fig. 5), evaluated on the reference model

Imbalance ramp {control['scenario']['imbalance_start']:g} -> {control['scenario']['imbalance_end']:g} kg m over
{control['scenario']['ramp_time']:g} s; sleeve positions {[round(1e3 * v, 2) for v in control['sleeve_positions_m']]} mm;
the DQN was trained on the surrogate `models/{active_model}` (dataset: {active_meta['n_samples']:,} samples with the
sleeve as an input, {active_meta.get('generation_seconds_total', active_meta['generation_seconds_last_run']):.0f} s; held-out median error
{active['metrics']['test_rel_err_median']:.4f}). Paper (qualitative): the DQN agent "tends to restrain the growth" of
the orbit, the passive bearing's orbit grows.

{controller_table(ctl)}
![Fig. 5 a](figures/fig5_a_dqn.png) ![Fig. 5 b](figures/fig5_b_none.png) ![MPC](figures/fig5_c_mpc.png)

![Fig. 5 amplitude](figures/fig5_amplitude.png)

## Reference model

![Fig. 2](figures/fig2_grid.png)

![Fig. 3](figures/fig3_velocity.png)
"""


def write_report(inp: ReportInputs, report_dir: Path | str, paper: Mapping, threshold_pct: float,
                 active_model: str) -> dict:
    """Write reports/metrics.json and reports/paper_comparison.md (atomically); returns the metrics."""
    rd = Path(report_dir)
    metrics = headline_metrics(inp)
    io.write_json(rd / "metrics.json", metrics)
    io.write_text(rd / "paper_comparison.md", paper_comparison_markdown(inp, paper, threshold_pct, active_model))
    return metrics
