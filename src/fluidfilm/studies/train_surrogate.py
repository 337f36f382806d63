"""Train a surrogate (single or split by eccentricity) and save it under models/<name>/
(``experiments/train_surrogate.py``, config conf/train_surrogate.yaml).

Two trainers: Lightning (``fluidfilm.surrogate.training.fit``) or, with ``protocol`` set, the paper's protocol
(``fluidfilm.surrogate.training.protocol``).  The model is written beside the old one and swapped in whole, with
its report and model card; the job's MLflow run gets the metrics, one child run per network and the model.
"""
from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

from fluidfilm import GradedReynoldsModel, io
from fluidfilm.perf.speed import sample_states, time_per_force_eval
from fluidfilm.surrogate.training.fit import fit_surrogate, held_out_errors, training_digest
from fluidfilm.surrogate.training.lightning import read_dataset
from fluidfilm.workflow import sweeps, tracking
from fluidfilm.workflow.entry import current_job, plain

INPUTS = ("dataset_dir", "testset_dir")


def model_name(cfg) -> str:
    """``name``, or <model>-<split>-<scaling>-s<seed> from the chosen configs; in a sweep every job gets its
    own name (hence its own model folder and MLflow run name)."""
    job = current_job()
    choices = job.choices
    keys = os.environ.get(sweeps.SWEEP_KEYS_ENV)  # set by the sweep callback in the launching process
    return sweeps.job_name(cfg.name or f"{choices['model']}-{choices['split']}-{choices['scaling']}-s{cfg.seed}",
                           job.task_overrides, choices, job.multirun, None if keys is None else keys.split(","))


def outputs(cfg) -> dict:
    return {"out_dir": [model_name(cfg)]}


def tracking_run(cfg):
    name = model_name(cfg)
    return name, {"model_name": name}


def _fmt(value, spec=".1f"):
    return "-" if value is None else format(value, spec)


def model_card(name: str, report: dict, metrics: dict, cfg: dict) -> str:
    nets = "\n".join(f"| {k} | {n['eps_low']:g}-{n['eps_high']:g} | {n['n_train']:,} | {n['epochs']} | "
                     f"{_fmt(n['val_rel_rmse'], '.4f')} | {n['train_time_s']:.1f} | {_fmt(n['time_to_target_s'])} |"
                     for k, n in enumerate(report["networks"]))
    return f"""# Model card: {name}

- model: `{json.dumps(cfg['model'])}`
- split: `{json.dumps(cfg['split'])}`, scaling: `{json.dumps(cfg['scaling'])}`, seed {cfg['seed']}
- data: {report['n_samples']:,} samples, dataset hash `{report['dataset_hash']}`
- training time: {report['train_time_s']:.1f} s in all; to the target validation error
  {report['target_val_rel_rmse']}: {_fmt(report['time_to_target_s'])} s
- held-out test set: median relative force error {metrics['test_rel_err_median']:.4f},
  99th percentile {metrics['test_rel_err_p99']:.4f}
- speed: {metrics['time_per_eval_us']:.3f} us per force evaluation, {metrics['speedup_force_eval_vs_reference']:.1f}x
  the reference (graded 30x30/55x55) in the same compiled loop

| network | eps range | training rows | epochs | val rel. RMSE | train s | s to target |
|---|---|---|---|---|---|---|
{nets}
"""


def train_by_protocol(cfg, c: dict, name: str, parent):
    """The paper's protocol (or Adam under its rules; fluidfilm.surrogate.training.protocol): one hidden tanh layer per
    network, each network's final numbers and curves as a child run of ``parent`` (None: not logged)."""
    import pandas as pd

    from fluidfilm.surrogate.training.protocol import band_test_errors, train_protocol_model

    m = c["model"]
    if m["depth"] != 1 or m["activation"] != "tanh":
        raise ValueError(f"the training protocols train one hidden tanh layer (the paper's network), got model "
                         f"depth={m['depth']}, activation={m['activation']!r}")
    frame, meta = read_dataset(cfg.dataset_dir)

    def log_network(r, res):
        final = {k: res[k] for k in ("epochs", "best_epoch", "train_time_s", "train_mse", "val_mse", "test_mse",
                                     "train_rel_rmse", "val_rel_rmse", "test_rel_rmse", "n_train", "n_val", "n_test")}
        tracking.log_child_run(parent, f"{name}/network{r}", final, {k: res["history"][k] for k in
                                                                     ("val_mse", "train_mse", "wall_s")},
                               {"stop_reason": res["stop_reason"], "eps_low": res["eps_low"],
                                "eps_high": res["eps_high"]}, uri=cfg.tracking.uri)
        print(f"  network {r} (eps {res['eps_low']:g}-{res['eps_high']:g}): {res['epochs']} epochs, "
              f"stopped by {res['stop_reason']}, val rel. RMSE {res['val_rel_rmse']:.4f}, "
              f"{res['train_time_s']:.1f} s", flush=True)

    model, report = train_protocol_model(frame, meta, c["protocol"], c["split"]["boundaries"], seed=cfg.seed,
                                         n_samples=cfg.protocol_samples, name=name, n_hidden=int(m["width"]),
                                         log_network=log_network)
    c["scaling"] = {"kind": "minmax", "power": 0.0}  # what the protocol used, for the saved config
    report.pop("_sub")
    report.pop("_division")
    report["dataset_hash"] = meta.get("config_hash")
    band = band_test_errors(model, pd.read_parquet(cfg.testset_dir), floor_N=cfg.error_floor_N)
    return model, report, band



def swap_in(model, out: Path, files: dict) -> None:
    """Write the model and ``files`` ({name: text}) next to the old model folder, then swap, so a crash never
    leaves half a model (the old one stays whole until the new one is in place)."""
    tmp = out.with_name(out.name + ".tmp")
    shutil.rmtree(tmp, ignore_errors=True)
    model.save(tmp)
    for fname, text in files.items():
        io.write_text(tmp / fname, text)
    old = out.with_name(out.name + ".old")
    shutil.rmtree(old, ignore_errors=True)
    if out.exists():
        out.rename(old)
    tmp.rename(out)
    shutil.rmtree(old, ignore_errors=True)


def run(cfg) -> tracking.Logged:
    name = model_name(cfg)
    c = plain(cfg)
    digest = training_digest(c["model"], c["split"], c["scaling"], c["trainer"], c["seed"], c["dataset_dir"])
    ckpt_root = Path(cfg.checkpoint_dir) / name / digest
    parent = tracking.active_run()
    logger_for = None if parent is None else tracking.child_logger_factory(parent, cfg.tracking, name)
    if c.get("protocol"):
        model, report, band = train_by_protocol(cfg, c, name, parent)
    else:
        band = {}
        model, report = fit_surrogate(cfg.dataset_dir, c["model"], c["split"], c["scaling"], c["trainer"],
                                      cfg.trainer.target_val_rel_rmse, seed=cfg.seed, name=name,
                                      ckpt_root=ckpt_root, logger_for=logger_for,
                                      val_fraction=cfg.trainer.val_fraction, batch_size=cfg.trainer.batch_size,
                                      workers=cfg.trainer.workers)
    metrics = held_out_errors(model, cfg.testset_dir, cfg.error_floor_N) | band
    x, v = sample_states(model.bearing.clearance)
    reference = GradedReynoldsModel(model.bearing)
    t_model = time_per_force_eval(model, x, v)
    t_ref = time_per_force_eval(reference, x, v)
    metrics.update(time_per_eval_us=1e6 * t_model, reference_time_per_eval_us=1e6 * t_ref,
                   speedup_force_eval_vs_reference=t_ref / t_model, train_time_s=report["train_time_s"],
                   n_parameters=model.n_parameters)
    if report["time_to_target_s"] is not None:
        metrics["time_to_target_s"] = report["time_to_target_s"]
    out = Path(cfg.out_dir) / name
    swap_in(model, out, {"report.json": json.dumps({"report": report, "metrics": metrics, "config": c}, indent=2,
                                                   sort_keys=True) + "\n",
                         "card.md": model_card(name, report, metrics, c)})
    logged = {k: float(v) for k, v in metrics.items()}
    for k, n in enumerate(report["networks"]):
        logged[f"train_time_s_network{k}"] = n["train_time_s"]
        if n["time_to_target_s"] is not None:
            logged[f"time_to_target_s_network{k}"] = n["time_to_target_s"]
    print(f"{name}: test median rel. error {metrics['test_rel_err_median']:.4f}, p99 {metrics['test_rel_err_p99']:.3f}, "
          f"train {report['train_time_s']:.1f} s, to target {report['time_to_target_s']}, "
          f"{metrics['speedup_force_eval_vs_reference']:.1f}x faster than the reference per force")
    return tracking.Logged(logged, [(out, "model")], value=metrics)
