"""The grading study: what a dataset's layout, and a surrogate's ingredients, buy in accuracy and cost.

One job is one grading (velocity range, core width and share, counts per section, where the
eccentricity sections meet) and one surrogate configuration:

1. its dataset, made with the reference model, or found in the cache (``cached_dataset``: keyed by the
   dataset's identity and by the source of the code that computes the forces, so a repeated grading
   is never regenerated and a changed solver never reuses old forces);
2. a surrogate trained on it (``fluidfilm.surrogate.training.fit``);
3. the surrogate judged on what does not depend on the grading: the held-out random test set, the
   states along the seven reference orbits (``OrbitBenchmark.force_errors``), the seven cases
   themselves by the Fig. 4 rule (``OrbitBenchmark.verdicts``) and the stiffness and damping
   coefficients at the reference's equilibria (``StiffnessBenchmark``).

``summarise`` turns the jobs of a sweep into one table; ``SweepSummaryCallback`` (a Hydra callback by
duck typing: this module imports no Hydra) writes it when a multirun ends.
"""
from __future__ import annotations

import copy
import hashlib
import json
import math
import os
import uuid
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from fluidfilm import io
from fluidfilm.data.schema import relative_force_errors
from fluidfilm.data.spec import DatasetConfigError, DatasetSpec, config_hash

#: grading keys (``grading.<key>=...``) and where each acts; None keeps the dataset config's value
VELOCITY_KEYS = ("v_max", "core", "core_fraction", "n_per_side")
POSITION_KEYS = ("n_angle", "eps_density", "eps_split")
GRADING_KEYS = VELOCITY_KEYS + POSITION_KEYS

#: environment variable naming the sweep a job belongs to (set when the multirun starts)
SWEEP_ID_ENV = "FLUIDFILM_GRADING_SWEEP_ID"


def apply_grading(dataset_cfg: Mapping, grading: Mapping) -> dict:
    """The dataset config with the grading's values in every section (``None`` keeps a value).

    - ``v_max``, ``core``, ``core_fraction``, ``n_per_side``: every velocity section;
    - ``n_angle``: every position section;
    - ``eps_density``: each position section's ``n_eps`` times this (rounded, at least 2);
    - ``eps_split``: where the two position sections meet (the fine section above it).
    The result is checked by ``DatasetSpec.from_cfg``; a bad value is named by its key here or there.
    """
    cfg = copy.deepcopy(_plain(dataset_cfg))
    for key, value in grading.items():
        if key not in GRADING_KEYS:
            raise DatasetConfigError(f"grading.{key} is not a grading key; use one of {', '.join(GRADING_KEYS)}")
        if value is None:
            continue
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise DatasetConfigError(f"grading.{key}={value!r} must be a finite number")
        if key in VELOCITY_KEYS:
            for s in cfg["velocity_sections"]:
                s[key] = value
        elif key == "n_angle":
            for s in cfg["position_sections"]:
                s["n_angle"] = value
        elif key == "eps_density":
            if value <= 0:
                raise DatasetConfigError(f"grading.eps_density={value!r} must be > 0")
            for s in cfg["position_sections"]:
                s["n_eps"] = max(2, int(round(s["n_eps"] * value)))
        else:  # eps_split
            sections = cfg["position_sections"]
            if len(sections) != 2:
                raise DatasetConfigError(f"grading.eps_split={value!r} needs a layout of two position sections, "
                                         f"this one has {len(sections)}")
            if not sections[0]["eps_start"] < value < sections[1]["eps_stop"]:
                raise DatasetConfigError(f"grading.eps_split={value!r} must lie between "
                                         f"{sections[0]['eps_start']} and {sections[1]['eps_stop']}")
            sections[0]["eps_stop"] = value
            sections[1]["eps_start"] = value
    DatasetSpec.from_cfg(cfg)  # names any value the grading made invalid, before any work
    return cfg


def _plain(node) -> dict:
    return json.loads(json.dumps(node, default=lambda o: dict(o) if isinstance(o, Mapping) else list(o)))


def source_digest() -> str:
    """SHA-256 (16 hex) of the source that computes and writes a dataset's forces: the bearing, the states,
    the force-model protocol, the Reynolds solver package and the dataset generator, layout and schema."""
    root = Path(__file__).resolve().parents[1]  # the package: this module lives in studies/
    files = [root / "core" / "bearing.py", root / "core" / "states.py", root / "core" / "force_model.py",
             root / "data" / "generate.py", root / "data" / "spec.py", root / "data" / "schema.py",
             *sorted((root / "reynolds").rglob("*.py"))]
    h = hashlib.sha256()
    for f in files:
        h.update(f.relative_to(root).as_posix().encode())
        h.update(f.read_bytes())
    return h.hexdigest()[:16]


def cached_dataset(bearing, reference: Mapping, spec: DatasetSpec, cache_dir, *, scheduler: str = "local",
                   n_workers: int | None = None, progress: bool = True) -> tuple[Path, dict, bool]:
    """The dataset of this grading: ``cache_dir/<key>``, generated unless a complete, undamaged copy is
    there.  Returns (path, metadata, reused).  The metadata's ``generation_seconds_total`` is the time it
    took when it was made (reused or not)."""
    from fluidfilm.data import generate
    from fluidfilm.data.schema import DatasetIntegrityError, verify_dataset

    import fcntl

    key = config_hash(generate.dataset_digest(bearing, dict(reference), spec), source_digest())
    path = Path(cache_dir) / key
    path.parent.mkdir(parents=True, exist_ok=True)
    # jobs of a parallel sweep (hydra/launcher=joblib) may want the same grading: one makes it, the others
    # wait for it and then find it complete
    with open(path.parent / f".{key}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if (path / "_metadata.json").exists():
            try:
                return path, verify_dataset(path), True
            except DatasetIntegrityError as err:  # the generator below recomputes what is damaged
                print(f"cached dataset {path} is damaged ({err}); repairing it", flush=True)
        meta = generate.generate_dataset(bearing, dict(reference), spec, path, scheduler=scheduler,
                                         n_workers=n_workers, progress=progress,
                                         config={"spec": spec.to_dict(), "source": source_digest()})
        return path, meta, False


relative_errors = relative_force_errors  # |F_model - F| / max(|F|, floor) per state


def error_quantiles(rel: np.ndarray, what: str = "the model") -> dict:
    """Median, 99th percentile and largest relative error; a non-finite error (a diverged network's NaN
    forces) is refused with the number of such states, never averaged into a table."""
    bad = int(np.count_nonzero(~np.isfinite(rel)))
    if bad:
        raise ValueError(f"{what} gives non-finite forces at {bad} of {len(rel)} states")
    return {"median": float(np.median(rel)), "p99": float(np.quantile(rel, 0.99)), "max": float(rel.max())}


@dataclass
class OrbitBenchmark:
    """The seven reference orbits, and the reference forces along them: what every job is judged on.

    ``x``, ``v``: every recorded state of every case (m, m/s); ``forces``: the reference's forces
    there; ``trajectories``: the reference runs themselves (``Trajectory``), by case.
    """

    trajectories: dict
    x: np.ndarray
    v: np.ndarray
    forces: np.ndarray
    clearance: float

    @classmethod
    def from_dir(cls, reference, trajectory_dir, cases: Sequence[str]) -> "OrbitBenchmark":
        from fluidfilm.rotor.integrate import Trajectory

        trajs = {}
        for case in cases:
            f = Path(trajectory_dir) / f"{case}.npz"
            if not f.exists():
                raise FileNotFoundError(f"reference trajectory {f} is missing: run experiments/trajectories.py "
                                        "(the DVC stage reference_trajectories) first")
            trajs[case] = Trajectory.from_npz(f)
            if not trajs[case].ok:
                raise ValueError(f"reference trajectory {f} did not finish ({trajs[case].status})")
        x = np.concatenate([t.x for t in trajs.values()])
        v = np.concatenate([t.v for t in trajs.values()])
        return cls(trajs, x, v, np.asarray(reference.forces(x, v)), reference.bearing.clearance)

    def force_errors(self, model, floor_N: float) -> dict:
        """Relative force error of ``model`` at the states along the reference orbits."""
        return error_quantiles(relative_errors(np.asarray(model.forces(self.x, self.v)), self.forces, floor_N),
                               f"{getattr(model, 'name', 'the model')} (along the reference orbits)")

    def verdicts(self, model, rotor_cfg: Mapping, cases: Mapping[str, Mapping], integrator_cfg: Mapping,
                 threshold_pct: float) -> dict:
        """The seven cases run with ``model`` and judged against the reference orbits by the Fig. 4 rule."""
        from fluidfilm.rotor.cases import case_summary, run_case

        rows = {}
        for name, case in cases.items():
            ref = self.trajectories[name]
            traj = run_case(model, rotor_cfg, case, integrator_cfg)
            if traj.completed and (len(traj.t) != len(ref.t) or not np.allclose(traj.t, ref.t)):
                raise ValueError(f"case {name}: the reference trajectory was recorded with other integrator settings "
                                 f"({len(ref.t)} samples to t = {ref.t[-1]:g} s, this run {len(traj.t)} to "
                                 f"{traj.t[-1]:g} s); use the integrator settings of the reference run")
            rows[name] = case_summary(traj, self.clearance, integrator_cfg["t_settle"], ref, threshold_pct)
        good = "".join(k for k, r in rows.items() if r["satisfactory"])
        return {"satisfactory_cases": good, "n_satisfactory": len(good), "n_cases": len(rows),
                "orbit_rms_pct_max": float(max(r["rms_pct"] for r in rows.values())),
                "orbit_hausdorff_pct_max": float(max(r["hausdorff_pct"] for r in rows.values())),
                "orbit_rms_pct": {k: float(r["rms_pct"]) for k, r in rows.items()}}


@dataclass
class StiffnessBenchmark:
    """The reference's eight stiffness and damping coefficients at its equilibria along eccentricity: what a
    job's K and C are checked on (``fluidfilm.characteristics``: the same loads for both, the surrogate at
    its own equilibrium under each load, its exact Jacobian)."""

    loads: list
    table: pd.DataFrame

    @classmethod
    def from_reference(cls, reference, eps_values: Sequence[float], h_rel: float = 1e-4) -> "StiffnessBenchmark":
        from fluidfilm.studies import characteristics_study as study

        loads = study.loads_for_eccentricities(reference, list(eps_values))
        return cls(loads, study.coefficient_table({"reference": reference}, loads, {"default": h_rel}))

    def errors(self, model) -> dict:
        """Largest error of the direct (Kxx, Kyy, Cxx, Cyy) and cross terms over the loads, each relative to
        the reference coefficient (floored at a tenth of its matrix's largest; ``study.coefficient_errors``).
        None where the model finds no equilibrium under one of the loads."""
        from fluidfilm.studies import characteristics_study as study

        try:
            table = study.coefficient_table({"model": model}, self.loads, {})
        except (ValueError, RuntimeError, FloatingPointError) as err:
            return {"direct_max": None, "cross_max": None, "status": "no equilibrium", "note": str(err)}
        eps = table.eps.to_numpy(float)
        if not (np.isfinite(eps).all() and (eps < 1.0).all()):  # a poor surrogate "balances" the load outside the film
            return {"direct_max": None, "cross_max": None, "status": "no equilibrium",
                    "note": f"no equilibrium inside the clearance (eps {', '.join(f'{e:.3g}' for e in eps)})"}
        e = study.coefficient_errors(pd.concat([self.table, table], ignore_index=True), "reference")
        if not np.isfinite(e.rel_err.to_numpy(float)).all():
            # the force has no derivative there: e.g. a scaling by (1 + |V|/(c omega)) has a kink at V = 0 (no
            # damping coefficient at rest), or an equilibrium at the centre, where the polar frame is singular
            return {"direct_max": None, "cross_max": None, "status": "not differentiable",
                    "note": f"coefficients not finite at the equilibria (eps {', '.join(f'{v:.3g}' for v in eps)})"}
        return {"direct_max": float(e[e.kind == "direct"].rel_err.max()),
                "cross_max": float(e[e.kind == "cross"].rel_err.max()), "status": "ok"}


@dataclass
class Judges:
    """What every job's surrogate is judged on, fixed for a sweep: the held-out random states (X1, X2, V1, V2,
    F1, F2), the reference orbits (``OrbitBenchmark``), the reference's K and C (``StiffnessBenchmark``, or
    None), and the settings of the Fig. 4 cases (rotor, cases, integrator, threshold in % of c)."""

    held_out: pd.DataFrame
    orbits: OrbitBenchmark
    stiffness: StiffnessBenchmark | None
    rotor: Mapping
    cases: Mapping
    integrator: Mapping
    threshold_pct: float
    floor_N: float
    evaluate_cases: bool = True

    def judge(self, model) -> dict:
        """The surrogate's held-out and orbit-state force errors, its verdicts in the cases, its K/C errors and
        its time per force evaluation (the compiled loop of ``fluidfilm.perf.speed``)."""
        from fluidfilm.perf.speed import sample_states, time_per_force_eval

        h = self.held_out
        predicted = np.asarray(model.forces(h[["X1", "X2"]].to_numpy(), h[["V1", "V2"]].to_numpy()))
        x, v = sample_states(model.bearing.clearance)
        return {
            "held_out": error_quantiles(relative_errors(predicted, h[["F1", "F2"]].to_numpy(), self.floor_N),
                                        f"{getattr(model, 'name', 'the model')} (held-out states)"),
            "orbit_states": self.orbits.force_errors(model, self.floor_N),
            "cases": (self.orbits.verdicts(model, self.rotor, self.cases, self.integrator, self.threshold_pct)
                      if self.evaluate_cases else None),
            "stiffness": self.stiffness.errors(model) if self.stiffness is not None else None,
            "time_per_eval_us": 1e6 * time_per_force_eval(model, x, v),
        }


def flat_metrics(result: Mapping) -> dict:
    """A job's numbers as one flat row (the summary table and MLflow)."""
    d, t = result["dataset"], result["training"]
    row = {"n_samples": d["n_samples"], "generation_s": d["generation_s"], "train_time_s": t["train_time_s"],
           "time_per_eval_us": result["time_per_eval_us"]}
    for where in ("held_out", "orbit_states"):
        for q, v in result[where].items():
            row[f"{where}_rel_err_{q}"] = v
    cases = result.get("cases")
    if cases:
        row.update(n_satisfactory=cases["n_satisfactory"], orbit_rms_pct_max=cases["orbit_rms_pct_max"])
    kc = result.get("stiffness")
    if kc:
        row.update(kc_max_rel_err_direct=kc["direct_max"], kc_max_rel_err_cross=kc["cross_max"])
    return row


def summarise(results: Sequence[Mapping]) -> tuple[pd.DataFrame, dict]:
    """One row per job (its swept values and numbers), ordered by dataset size, and a summary."""
    if not results:
        raise ValueError("no finished jobs to summarise")
    rows = [{"job": r["job"], **{k: v for k, v in r["swept"].items()}, **flat_metrics(r),
             "satisfactory_cases": (r.get("cases") or {}).get("satisfactory_cases", ""),
             "kc_status": (r.get("stiffness") or {}).get("status", "not measured")} for r in results]
    table = pd.DataFrame(rows).sort_values(["n_samples", "job"]).reset_index(drop=True)
    swept = sorted({k for r in results for k in r["swept"]})
    best = table.loc[table["orbit_states_rel_err_p99"].idxmin()]
    summary = {"n_jobs": len(table), "swept": swept, "jobs": table.to_dict(orient="records"),
               "lowest_orbit_p99_job": str(best["job"]), "lowest_orbit_p99": float(best["orbit_states_rel_err_p99"])}
    return table, summary


def read_results(sweep_dir, sweep_id: str | None = None) -> list[dict]:
    """Every job result (``result.json``) under a sweep's folder; with ``sweep_id`` only that sweep's."""
    out = []
    for f in sorted(Path(sweep_dir).rglob("result.json")):
        r = json.loads(f.read_text())
        if sweep_id is None or r.get("sweep_id") == sweep_id:
            out.append(r)
    return out


def write_summary(results: Sequence[Mapping], out_dir, title: str) -> dict:
    """``summary.json``, ``table.csv`` and ``figure.png`` of a sweep in ``out_dir`` (each atomic)."""
    from fluidfilm.studies.plots import plot_grading_study

    table, summary = summarise(results)
    out = Path(out_dir)
    io.write_csv(out / "table.csv", table)
    io.save_figure(plot_grading_study(table, title), out / "figure.png", dpi=120)
    io.write_json(out / "summary.json", summary)
    return summary


class SweepSummaryCallback:
    """Hydra callback (duck-typed): tags the sweep's jobs with one id, and when the multirun ends writes
    the summary of exactly those jobs to ``summary_dir`` (or the sweep's own folder)."""

    def __init__(self, **_):
        pass

    def on_multirun_start(self, config, **kwargs):
        os.environ[SWEEP_ID_ENV] = uuid.uuid4().hex

    def on_multirun_end(self, config, **kwargs):
        sweep_dir = Path(str(config.hydra.sweep.dir))
        results = read_results(sweep_dir, os.environ.get(SWEEP_ID_ENV))
        out = Path(str(config.get("summary_dir") or sweep_dir))
        summary = write_summary(results, out, str(config.get("title", "grading study")))
        print(f"{summary['n_jobs']} jobs summarised in {out} (summary.json, table.csv, figure.png); lowest "
              f"p99 force error along the orbits: {summary['lowest_orbit_p99_job']} "
              f"({100 * summary['lowest_orbit_p99']:.1f} %)", flush=True)

    # the other hooks Hydra calls
    def on_run_start(self, config, **kwargs): ...
    def on_run_end(self, config, **kwargs): ...
    def on_job_start(self, config, **kwargs): ...
    def on_job_end(self, config, job_return, **kwargs): ...
    def on_compose_config(self, config, **kwargs): ...


def binned_errors(rel: np.ndarray, eps: np.ndarray, speed: np.ndarray, eps_edges: Sequence[float],
                  speed_edges: Sequence[float]) -> pd.DataFrame:
    """Where the errors sit: per (eccentricity, |V|) bin the number of states and the median, 99th
    percentile and largest relative error (bins without states are left out)."""
    rows = []
    e_idx = np.digitize(eps, eps_edges) - 1
    s_idx = np.digitize(speed, speed_edges) - 1
    for i in range(len(eps_edges) - 1):
        for j in range(len(speed_edges) - 1):
            m = (e_idx == i) & (s_idx == j)
            if m.any():
                r = rel[m]
                rows.append({"eps_low": float(eps_edges[i]), "eps_high": float(eps_edges[i + 1]),
                             "speed_low": float(speed_edges[j]), "speed_high": float(speed_edges[j + 1]),
                             "n_states": int(m.sum()), "median": float(np.median(r)),
                             "p99": float(np.quantile(r, 0.99)), "max": float(r.max())})
    return pd.DataFrame(rows)


# --- the study run by experiments/grading_study.py (conf/grading_study.yaml), one job of a sweep ---

INPUTS = ("testset_dir", "reference_trajectories_dir")


def _job_name() -> tuple[str, dict]:
    """(the job's name, its swept values): ``key=value,...`` of the keys the sweep varies, or "single"."""
    from fluidfilm.workflow import sweeps
    from fluidfilm.workflow.entry import current_job

    keys = os.environ.get(sweeps.SWEEP_KEYS_ENV)  # set by the sweep callback in the launching process
    swept = sweeps.swept_values(current_job().task_overrides, keys.split(",") if keys else [])
    return ",".join(f"{k}={v}" for k, v in swept.items()) or "single", swept


def tracking_run(cfg):
    return f"grading {_job_name()[0]}", {"study": cfg.title}


def run(cfg):
    """Generate (or reuse) the dataset of one grading, train a surrogate on it, judge it; ``result.json`` in the
    job's output folder, the flat metrics to the job's MLflow run."""
    import shutil

    from fluidfilm.data import load_test_set
    from fluidfilm.data.spec import check_reference
    from fluidfilm.reynolds import ReynoldsSolver
    from fluidfilm.surrogate.training.fit import fit_surrogate, training_digest
    from fluidfilm.workflow.config import bearing_from_cfg, reference_from_cfg
    from fluidfilm.workflow.entry import current_job, plain
    from fluidfilm.workflow.tracking import Logged

    name, swept = _job_name()
    c = plain(cfg)
    # everything is checked, and what the surrogate is judged on is read or computed, before the long work
    bearing = bearing_from_cfg(cfg.bearing)
    reference_policy = check_reference(c["reference"])
    spec = DatasetSpec.from_cfg(apply_grading(c["dataset"], c["grading"]))
    cases = {k: cfg.cases[k] for k in sorted(cfg.cases)}
    judges = Judges(held_out=load_test_set(cfg.testset_dir),
                    orbits=OrbitBenchmark.from_dir(reference_from_cfg(bearing, cfg.reference),
                                                   cfg.reference_trajectories_dir, cases),
                    stiffness=(StiffnessBenchmark.from_reference(ReynoldsSolver(bearing, *cfg.kc_reference_grid),
                                                                 cfg.kc_eps) if cfg.kc_eps else None),
                    rotor=cfg.rotor, cases=cases, integrator=cfg.integrator, threshold_pct=cfg.metrics.threshold_pct,
                    floor_N=cfg.error_floor_N, evaluate_cases=cfg.evaluate_cases)
    print(f"job {name}: {spec.n_samples(bearing.clearance):,} samples planned", flush=True)
    path, meta, reused = cached_dataset(bearing, reference_policy, spec, cfg.cache_dir, scheduler=cfg.dask.scheduler,
                                        n_workers=cfg.dask.n_workers, progress=cfg.progress)
    digest = training_digest(c["model"], c["split"], c["scaling"], c["trainer"], c["seed"], path.name)
    model, report = fit_surrogate(path, c["model"], c["split"], c["scaling"], c["trainer"], None, seed=cfg.seed,
                                  name=name, ckpt_root=Path(cfg.checkpoint_dir) / digest,
                                  val_fraction=cfg.trainer.val_fraction, batch_size=cfg.trainer.batch_size,
                                  workers=cfg.trainer.workers)
    result = {
        "job": name, "swept": swept, "sweep_id": os.environ.get(SWEEP_ID_ENV), "grading": c["grading"],
        "dataset": {"n_samples": int(meta["n_samples"]), "generation_s": float(meta["generation_seconds_total"]),
                    "reused": reused, "path": str(path), "spec": spec.to_dict()},
        "training": {"train_time_s": report["train_time_s"], "epochs": c["trainer"]["max_epochs"],
                     "networks": report["networks"]},
        **judges.judge(model),
        "config": {k: c[k] for k in ("model", "split", "scaling", "trainer", "seed")},
    }
    io.write_json(current_job().output_dir / "result.json", result)
    # the checkpoint is there to resume an interrupted job, not to skip the training of a later one
    shutil.rmtree(Path(cfg.checkpoint_dir) / digest, ignore_errors=True)
    row = flat_metrics(result)
    print(f"job {name}: {row['n_samples']:,} samples ({'cached' if reused else 'made'} in {row['generation_s']:.1f} s), "
          f"trained {row['train_time_s']:.0f} s; held-out median {100 * row['held_out_rel_err_median']:.2f} %, "
          f"p99 {100 * row['held_out_rel_err_p99']:.1f} %; along the orbits median "
          f"{100 * row['orbit_states_rel_err_median']:.2f} %, p99 {100 * row['orbit_states_rel_err_p99']:.1f} %"
          + (f", {row['n_satisfactory']}/7 cases" if "n_satisfactory" in row else ""), flush=True)
    return Logged({k: float(v) for k, v in row.items() if v is not None}, value=row)
