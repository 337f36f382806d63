"""The paper's networks at larger scale, and what in their recipe decides the verdicts.

Two parts, one record per trained model (``experiments/paper_scale.py``, conf/paper_scale.yaml):

- **the curve**: the paper's recipe (protocol ``paper``: 1 x 50 tanh, min-max map, random 70/15/15
  division, Levenberg-Marquardt to the validation rule) at growing subsample sizes, single and
  split, one seed each;
- **the mechanism**: at one size, the paper's split model with one ingredient of its recipe changed
  at a time: the output map (min-max over the whole velocity range, or after dividing the force by
  1 + |V|/(c omega), i.e. per velocity magnitude), the frame (the journal's own, or the whirl
  frame, whose drive |u| also scales the force per velocity), the region boundaries, and the
  grading near V = 0 (the dataset's velocities have no V = 0: the static states at its positions
  added, forces from the reference).

For every model: epochs, stop reasons and training time per network; the held-out median and
99th-percentile relative force error per eccentricity band; the static force error along the
reference's equilibrium locus (loads a multiple of the rotor's, in N and as a share of that load);
the equilibrium offset (the model's equilibrium under each case's static load against the
reference's, in % of c); and cases a-g against the reference orbits, judged by the workspace's rule
(RMS and Hausdorff distance within 2 % of c) and by the paper's reading (span and shape after
removing the mean offset within 2 % of c; ``rotor.metrics.is_satisfactory_paper_reading``).

Every finished model's record is kept under ``cache_dir`` (keyed by what it depends on), and its
Levenberg-Marquardt networks checkpoint there after every epoch, so the same command resumes an
interrupted run, mid-network included.
"""
from __future__ import annotations

import hashlib
import json
import math
import os
import time
from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from fluidfilm import io

#: the paper's verdicts per structure (Fig. 4): satisfactory cases
PAPER_VERDICTS = {"single": "e", "split": "abcde"}
CASES = "abcdefg"


# --------------------------------------------------------------------------- evaluation pieces
def static_rows(frame: pd.DataFrame, reference) -> pd.DataFrame:
    """The dataset's positions at rest (V = 0), forces from ``reference``: rows with ``frame``'s columns."""
    pos = frame[["X1", "X2"]].drop_duplicates().reset_index(drop=True)
    X = pos.to_numpy()
    F = np.asarray(reference.forces(X, np.zeros_like(X)))
    rows = pd.DataFrame({c: np.zeros(len(X)) for c in frame.columns})
    for c in frame.columns:
        rows[c] = rows[c].astype(frame[c].dtype, copy=False)
    rows["X1"], rows["X2"] = X[:, 0], X[:, 1]
    rows["V1"], rows["V2"] = 0.0, 0.0
    rows["F1"], rows["F2"] = F[:, 0], F[:, 1]
    c = reference.bearing.clearance
    rows["eps"] = np.hypot(X[:, 0], X[:, 1]) / c
    return rows


def locus_errors(model, reference, loads: np.ndarray, direction: np.ndarray) -> dict:
    """The static force error of ``model`` along the reference's equilibrium locus.

    ``loads`` [N] along the unit vector ``direction``: at each, the reference's equilibrium X*
    (F_ref(X*, 0) = -W) and |F_model(X*, 0) - F_ref(X*, 0)| in N and as a share of the load.
    """
    from fluidfilm.characteristics.static import equilibrium

    rows = []
    guess = None
    c = reference.bearing.clearance
    for w in sorted(float(x) for x in loads):
        eq = equilibrium(reference, tuple(w * direction), guess=guess)
        guess = (eq["eps"], math.atan2(eq["X1"] / c, eq["X2"] / c))
        X = np.array([[eq["X1"], eq["X2"]]])
        fm = np.asarray(model.forces(X, np.zeros_like(X)))[0]
        fr = np.asarray(reference.forces(X, np.zeros_like(X)))[0]
        err = fm - fr
        rows.append({"load_N": w, "eps": float(eq["eps"]), "error_N": [float(err[0]), float(err[1])],
                     "error_abs_N": float(np.hypot(*err)), "error_share_of_load": float(np.hypot(*err) / w)})
    shares = [float(r["error_share_of_load"]) for r in rows]  # type: ignore[arg-type]
    return {"points": rows, "error_share_of_load_max": max(shares), "error_share_of_load_median": float(np.median(shares))}


def equilibrium_offset(model, reference, load) -> dict:
    """Distance [% of c] between the model's and the reference's equilibrium under ``load`` (W1, W2);
    None (and the reason) when the model has none there."""
    from fluidfilm.characteristics.static import equilibrium

    c = reference.bearing.clearance
    ref = equilibrium(reference, tuple(load))
    out: dict = {"eps_reference": float(ref["eps"]), "load_N": float(np.hypot(*load))}
    X = np.array([[ref["X1"], ref["X2"]]])
    err = np.asarray(model.forces(X, np.zeros_like(X)))[0] - np.asarray(reference.forces(X, np.zeros_like(X)))[0]
    out["static_force_error_N"] = [float(err[0]), float(err[1])]
    try:
        m = equilibrium(model, tuple(load), guess=(ref["eps"], math.atan2(ref["X1"] / c, ref["X2"] / c)))
    except (ValueError, RuntimeError) as exc:  # no equilibrium of the model near the load
        return out | {"offset_pct_c": None, "eps_model": None, "failed": str(exc)[:200]}
    return out | {"offset_pct_c": float(100 * math.hypot(m["X1"] - ref["X1"], m["X2"] - ref["X2"]) / c),
                  "eps_model": float(m["eps"])}


def resolution(model, reference, load, networks: list[dict]) -> dict:
    """What one mapped unit of the network that holds the reference's equilibrium is worth there, in N.

    The network's outputs are forces mapped to [-1, 1] over its rows (``Scaling.forces``): at the
    equilibrium state (V = 0) one unit is gain x half-range newtons per component.  Times the
    network's validation RMS error in mapped units it is the static force error to expect there,
    beside the load the equilibrium has to balance.
    """
    from fluidfilm.characteristics.static import equilibrium

    ref = equilibrium(reference, tuple(load))
    r = int(np.searchsorted(np.asarray(model.boundaries), ref["eps"], side="right"))
    sc = model.scalings[r]
    X = np.array([ref["X1"], ref["X2"]])
    unit = np.abs(np.asarray(sc.gain(X[None, :], np.zeros((1, 2))))[0] * np.asarray(sc.out_std))
    rms = math.sqrt(networks[r]["val_mse"])
    return {"network": r, "newton_per_mapped_unit": [float(u) for u in unit], "val_rms_mapped": rms,
            "expected_static_error_N": float(rms * np.hypot(*unit)), "load_N": float(np.hypot(*load))}


def verdicts(rows: list[dict], structure: str) -> dict:
    """Satisfactory cases by both readings, and how many of the paper's seven verdicts each reproduces."""
    paper = PAPER_VERDICTS.get(structure)
    out: dict = {}
    for key, reading in (("satisfactory", "position"), ("satisfactory_paper_reading", "paper_reading")):
        good = "".join(r["case"] for r in rows if r[key])
        out[f"satisfactory_cases_{reading}"] = good
        if paper is not None:
            out[f"paper_verdicts_reproduced_{reading}"] = sum((k in good) == (k in paper) for k in CASES)
    return out


# --------------------------------------------------------------------------- one model
def point_key(point: Mapping, protocol: Mapping, meta: Mapping, seed: int) -> str:
    """What one model's record depends on (the data's content, the point, the protocol, the code: the
    training recipe's version, ``surrogate.training.protocol.RECIPE_VERSION``)."""
    from fluidfilm.surrogate.training.protocol import RECIPE_VERSION
    # the threads and the progress lines do not change the weights; the device changes them by round-off
    # only, and a run continues on another device from the same checkpoint (the record says which device)
    proto = {k: v for k, v in protocol.items() if k not in ("workers", "progress_every_s", "threads", "device")}
    # the label names the record, the key what it is: the same model under two labels is trained once
    pt = {k: v for k, v in point.items() if k != "label"}
    what = {"parts": meta.get("parts"), "config_hash": meta.get("config_hash"), "point": pt,
            "protocol": proto, "seed": int(seed), "code": RECIPE_VERSION}
    return hashlib.sha256(json.dumps(what, sort_keys=True, default=str).encode()).hexdigest()[:16]


def evaluate(model, reference, references: dict, testset: pd.DataFrame, cfg: Mapping, structure: str,
             loads: Mapping[str, np.ndarray], locus_factors) -> dict:
    """Band errors, locus errors, equilibrium offsets and cases a-g of one trained model."""
    from fluidfilm.rotor.cases import case_summary, run_case
    from fluidfilm.surrogate.training.protocol import band_test_errors

    out: dict = {"bands": band_test_errors(model, testset, floor_N=float(cfg["error_floor_N"]))}
    w_a = np.asarray(loads["a"])
    out["locus"] = locus_errors(model, reference, np.asarray(locus_factors) * float(np.hypot(*w_a)),
                                w_a / np.hypot(*w_a))
    eq = {k: equilibrium_offset(model, reference, w) for k, w in loads.items()}
    out["equilibrium"] = eq
    # the headline: under the rotor's weight alone (the static load of cases a-e)
    out["equilibrium_offset_pct_c"] = eq["a"]["offset_pct_c"]
    rows = []
    c = reference.bearing.clearance
    thr = float(cfg["metrics"]["threshold_pct"])
    for name, case in cfg["cases"].items():
        traj = run_case(model, cfg["rotor"], case, cfg["integrator"])
        s = case_summary(traj, c, cfg["integrator"]["t_settle"], references[name], thr)
        rows.append({"case": name, **{k: (float(v) if isinstance(v, (int, float, np.floating)) and
                                          not isinstance(v, bool) else v) for k, v in s.items()}})
    out["cases"] = rows
    out.update(verdicts(rows, structure))
    finite = [r["rms_pct"] for r in rows if math.isfinite(r["rms_pct"])]
    out["orbit_rms_pct_max"] = max(r["rms_pct"] for r in rows)
    out["orbit_rms_pct_median"] = float(np.median([r["rms_pct"] for r in rows])) if finite else math.inf
    out["orbit_shape_pct_max"] = max(r["shape_pct"] for r in rows)
    out["orbit_mean_offset_pct_median"] = float(np.median([r["mean_offset_pct"] for r in rows]))
    return out


def size_label(n_samples: int | None) -> str:
    """A point's sample count in words: "40,000", or "all" for the full scale (n_samples None)."""
    return "all" if n_samples is None else f"{int(n_samples):,}"


def train_point(frame, meta, point: Mapping, protocol: Mapping, seed: int, ckpt_dir: Path, reference):
    """Train one model of the study (``point``: n_samples, structure, boundaries, scaling, static_rows,
    network_protocol); returns the force model and the training report."""
    from fluidfilm.surrogate.training.protocol import train_protocol_model

    bounds = [] if point["structure"] == "single" else list(point["boundaries"])
    extra = static_rows(frame, reference) if point.get("static_rows") else None
    name = f"{point['structure']}_{'full' if point['n_samples'] is None else point['n_samples']}"
    return train_protocol_model(frame, meta, protocol, bounds, seed=seed, n_samples=point["n_samples"], name=name,
                                scaling=point.get("scaling"), extra_rows=extra, checkpoint_dir=ckpt_dir,
                                network_protocol=point.get("network_protocol"))


def _net_summary(n: Mapping) -> dict:
    keys = ("eps_low", "eps_high", "n_train", "epochs", "best_epoch", "stop_reason", "train_time_s", "val_mse",
            "test_mse", "val_rel_rmse", "test_rel_rmse", "device")
    out = {k: n.get(k) for k in keys}
    if out["eps_high"] is not None and math.isinf(out["eps_high"]):
        out["eps_high"] = None
    return out


def run_point(frame, meta, testset, point: Mapping, protocol: Mapping, cfg: Mapping, reference, references, loads,
              cache: Path) -> dict:
    """One model of the study, from the cache when it finished before."""
    key = point_key(point, protocol, meta, int(cfg["seed"]))
    path = cache / f"{key}.json"
    if path.exists():
        rec = json.loads(path.read_text()) | {"resumed": True}
        if "resolution" not in rec and (cache / "models" / key).exists():  # a record of before this measure
            from fluidfilm import load_surrogate

            rec["resolution"] = resolution(load_surrogate(cache / "models" / key), reference, loads["a"],
                                           rec["networks"])
        return rec
    t0 = time.perf_counter()
    print(f"paper_scale: {point['label']}: {point['structure']}, {size_label(point['n_samples'])} samples "
          f"(record {path})", flush=True)
    # the checkpoints: shared by points that differ only in one network's protocol (the full-scale split's
    # Adam arm resumes the LM networks the LM arm finished; each file checks it belongs to its network)
    ckpt = cache / "checkpoints" / point_key(dict(point) | {"network_protocol": None}, protocol, meta,
                                             int(cfg["seed"]))
    model, rep = train_point(frame, meta, point, protocol, int(cfg["seed"]), ckpt, reference)
    nets = [_net_summary(n) for n in rep["networks"]]
    rec = {"label": point["label"], "point": dict(point), "key": key, "n_samples": rep["n_samples"],
           "structure": point["structure"], "networks": nets, "train_time_s": rep["train_time_s"],
           "converged": rep["converged"], "stop_reasons": rep["stop_reasons"],
           "val_rel_rmse": rep["val_rel_rmse"], "test_rel_rmse": rep["test_rel_rmse"]}
    print(f"  trained in {rep['train_time_s']:.0f} s: epochs {[n['epochs'] for n in nets]}, stopped by "
          f"{rep['stop_reasons']}", flush=True)
    rec.update(evaluate(model, reference, references, testset, cfg, point["structure"], loads,
                        cfg["locus_load_factors"]))
    rec["resolution"] = resolution(model, reference, loads["a"], nets)
    rec["wall_s"] = time.perf_counter() - t0
    model.save(cache / "models" / key)
    io.write_json(path, rec)
    print(f"  equilibrium offset {rec['equilibrium_offset_pct_c']} % of c; satisfactory {rec['satisfactory_cases_position'] or '-'}"
          f" (position), {rec['satisfactory_cases_paper_reading'] or '-'} (paper's reading)", flush=True)
    return rec


def points(cfg: Mapping) -> list[dict]:
    """The study's models: the curve (every size x structure) and the ablation's variants."""
    out = []
    base = {"boundaries": list(cfg["boundaries"]), "scaling": None, "static_rows": False, "network_protocol": None}
    budgets = {int(k): v for k, v in (cfg.get("size_budget_s") or {}).items()}
    for n in cfg["sizes"]:
        for structure in cfg["structures"]:
            p = base | {"label": f"curve {structure} {int(n)}", "n_samples": int(n), "structure": structure}
            if budgets.get(int(n)) is not None:
                # every network of the model stops by this LM time budget if the validation rule has not
                # stopped it first (recorded, and not counted as converged); the checkpoints are the
                # unbudgeted run's, so a larger budget later continues from where this one stopped
                n_nets = 1 if structure == "single" else len(cfg["boundaries"]) + 1
                p["network_protocol"] = {r: {"max_time_s": float(budgets[int(n)])} for r in range(n_nets)}
            out.append(p)
    ab = cfg.get("ablation") or {}
    if ab.get("enabled"):
        for name, change in ab["variants"].items():
            p = base | {"label": f"ablation {name}", "n_samples": int(ab["n_samples"]), "structure": "split"}
            p.update({k: (list(v) if k == "boundaries" else v) for k, v in (change or {}).items()})
            out.append(p)
    for name, fs in (cfg.get("full_scale") or {}).items():
        if fs is not None and fs.get("enabled"):
            out.append(base | {"label": f"full scale {name}", "n_samples": None, "structure": fs["structure"],
                               "network_protocol": fs.get("network_protocol")})
    return out


# --------------------------------------------------------------------------- summary and figure
def summary_keys(records: list[dict]) -> dict:
    """Flat headline keys: per size of the curve, per ablation variant, at full scale."""
    out: dict = {}
    for r in records:
        lab = r["label"]
        if lab.startswith("curve "):
            sfx = f"{r['structure']}_{r['point']['n_samples']}"
        elif lab.startswith("ablation "):
            sfx = f"ablation_{lab.split(' ', 1)[1]}"
        else:
            sfx = f"{lab.split(' ', 2)[2]}_full_scale"
        out[f"satisfactory_cases_{sfx}"] = len(r["satisfactory_cases_position"])
        out[f"satisfactory_cases_{sfx}_paper_reading"] = len(r["satisfactory_cases_paper_reading"])
        out[f"equilibrium_offset_pct_c_{sfx}"] = r["equilibrium_offset_pct_c"]
        out[f"orbit_rms_pct_max_{sfx}"] = r["orbit_rms_pct_max"]
        out[f"train_time_s_{sfx}"] = r["train_time_s"]
        out[f"static_force_error_share_max_{sfx}"] = r["locus"]["error_share_of_load_max"]
        # 1: every network stopped by the validation rule; 0: one stopped by a time or epoch budget
        out[f"converged_{sfx}"] = 1.0 if r["converged"] else 0.0
    full = {r["label"]: r for r in records if r["label"].startswith("full scale ")}
    if "full scale single" in full and "full scale split" in full:
        # the paper's 26 % from one LM run per structure (one seed), only where every network stopped by the
        # validation rule: times capped by budgets compare the budgets, not the structures
        converged = bool(full["full scale single"]["converged"] and full["full scale split"]["converged"])
        out["train_time_converged_full_scale_lm"] = converged
        if converged:
            t1, t3 = full["full scale single"]["train_time_s"], full["full scale split"]["train_time_s"]
            out["train_time_reduction_pct_full_scale_lm"] = 100.0 * (1.0 - t3 / t1)
    return out


def included_records(paths) -> list[dict]:
    """The curve's and the full scale's records of other runs of this study (their reports), for the figure
    and the keys: e.g. the pipeline's 40 k beside `make paper-scale-curve`'s larger sizes."""
    out = []
    for p in paths or []:
        if Path(p).exists():
            out += [r | {"from_report": str(p)} for r in json.loads(Path(p).read_text())["records"]
                    if not r["label"].startswith("ablation ") and "from_report" not in r]
    return out


def plot_curve(records: list[dict], path) -> None:
    """Equilibrium offset and the orbits' largest RMS error against the training samples."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for structure, marker in (("single", "s"), ("split", "o")):
        # the curve and the full scale's LM runs (the Adam arm is a second arm of the full scale, not a size)
        rs = sorted((r for r in records if r["structure"] == structure and not r["label"].startswith("ablation")
                     and not r["label"].endswith("_adam")), key=lambda r: r["n_samples"])
        if not rs:
            continue
        n = np.array([r["n_samples"] for r in rs])
        off = np.array([np.nan if r["equilibrium_offset_pct_c"] is None else r["equilibrium_offset_pct_c"] for r in rs])
        rms = np.array([min(r["orbit_rms_pct_median"], 1e3) for r in rs])
        capped = np.array([not r.get("converged", True) for r in rs])
        for ax, y in ((axes[0], off), (axes[1], rms)):
            line, = ax.plot(n, y, marker=marker, label=f"{structure}, trained to the validation rule")
            if capped.any():  # hollow: a network stopped by its time budget (not converged)
                ax.plot(n[capped], y[capped], ls="none", marker=marker, ms=9, mfc="white", color=line.get_color(),
                        label=f"{structure}, stopped by its LM time budget")
    axes[0].set_ylabel("equilibrium offset under the rotor's weight [% of c]")
    axes[1].set_ylabel("median over cases a-g of the orbit RMS error [% of c]")
    for ax in axes:
        ax.set_xscale("log")
        ax.set_xlabel("samples drawn from the paper dataset (70 % train)")
        ax.axhline(2.0, color="k", lw=0.8, ls="--")
        ax.legend(fontsize=7)
    fig.suptitle("The paper's networks (1x50 tanh, min-max, LM) against data size (rightmost: all 4,512,900)")
    fig.tight_layout(rect=(0.0, 0.0, 1.0, 0.94))
    io.save_figure(fig, path, dpi=120)


# --------------------------------------------------------------------------- the study (experiments/paper_scale.py)
INPUTS = ("dataset_dir", "testset_dir")
OUTPUTS = {"out": [""], "figure": [""]}


def tracking_run(cfg):
    return "paper_scale", None


def run(cfg):
    """Train and evaluate every model of ``points(cfg)``; write the report and the figure."""
    from fluidfilm.perf.benchmarking import machine
    from fluidfilm.rotor.cases import rotor_for_case, run_case
    from fluidfilm.surrogate.training.lightning import read_dataset
    from fluidfilm.workflow import tracking
    from fluidfilm.workflow.config import bearing_from_cfg, reference_from_cfg
    from fluidfilm.workflow.entry import plain

    c = plain(cfg)
    frame, meta = read_dataset(cfg.dataset_dir)
    testset = pd.read_parquet(cfg.testset_dir)
    bearing = bearing_from_cfg(c["bearing"])
    reference = reference_from_cfg(bearing, c["reference"])
    c["cases"] = {k: c["cases"][k] for k in sorted(c["cases"])}
    loads = {k: np.asarray(rotor_for_case(c["rotor"], case).static_load(), dtype=float)
             for k, case in c["cases"].items()}
    t0 = time.perf_counter()
    references = {k: run_case(reference, c["rotor"], case, c["integrator"]) for k, case in c["cases"].items()}
    print(f"paper_scale: reference orbits a-g in {time.perf_counter() - t0:.0f} s", flush=True)
    cache = Path(cfg.cache_dir)
    records = [run_point(frame, meta, testset, p, c["protocol"], c, reference, references, loads, cache)
               for p in points(c)]
    load = float(np.hypot(*loads["a"]))
    labels = {r["label"] for r in records}
    others = [r for r in included_records(c.get("include_reports")) if r["label"] not in labels]
    out = {"machine": machine(), "date": time.strftime("%Y-%m-%d"), "seed": int(cfg.seed), "protocol": c["protocol"],
           "dataset_samples": len(frame), "threshold_pct": float(c["metrics"]["threshold_pct"]),
           "static_load_N": load, "paper_verdicts": PAPER_VERDICTS, "load_average": list(os.getloadavg()),
           "records": records + others} | summary_keys(records + others)
    io.write_json(cfg.out, out)
    plot_curve(records + others, cfg.figure)
    metrics = {k: float(v) for k, v in out.items() if isinstance(v, (int, float)) and not isinstance(v, bool)
               and math.isfinite(v)}
    return tracking.Logged(metrics, [str(cfg.out), str(cfg.figure)])
