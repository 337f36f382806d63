"""Hard switch vs smoothstep blend at the split boundaries (``experiments/boundary_study.py``,
reports/boundary_study.json)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from fluidfilm import io
from fluidfilm.rotor.cases import case_summary, run_case
from fluidfilm.rotor.integrate import Trajectory
from fluidfilm.surrogate.training.fit import fit_surrogate, held_out_errors
from fluidfilm.workflow.entry import plain

INPUTS = ("dataset_dir", "testset_dir", "reference_dir")
OUTPUTS = {"out": [""]}


def boundary_jump(model, boundary: float, n: int = 400, delta: float = 1e-6, seed: int = 0) -> tuple[float, float]:
    """|F(eps_b + d) - F(eps_b - d)| over random angles and orbit-like velocities:
    (median relative to |F|, largest in N)."""
    rng = np.random.default_rng(seed)
    c = model.bearing.clearance
    ang = 2 * np.pi * rng.random(n)
    v = rng.uniform(-0.03, 0.03, (n, 2))
    unit = np.stack([np.sin(ang), np.cos(ang)], axis=1)
    lo = model.forces((boundary - delta) * c * unit, v)
    hi = model.forces((boundary + delta) * c * unit, v)
    jump = np.hypot(*(hi - lo).T)
    return float(np.median(jump / np.maximum(np.hypot(*hi.T), 1e-9))), float(jump.max())


def run(cfg) -> None:
    c = plain(cfg)
    out = {}
    for name, split in c["splits"].items():
        model, rep = fit_surrogate(cfg.dataset_dir, c["model"], split, c["scaling"], c["trainer"], None,
                                   seed=cfg.seed, name=name, workers=cfg.trainer.workers)
        jumps = [boundary_jump(model, b) for b in split["boundaries"]]
        res = {"median_relative_jump_at_boundary": max(j[0] for j in jumps),
               "max_jump_at_boundary_N": max(j[1] for j in jumps),
               "train_time_s": rep["train_time_s"], **held_out_errors(model, cfg.testset_dir)}
        for k, case in cfg.cases.items():
            ref = Trajectory.from_npz(Path(cfg.reference_dir) / f"{k}.npz")
            s = case_summary(run_case(model, cfg.rotor, case, cfg.integrator), model.bearing.clearance,
                             cfg.integrator.t_settle, ref, cfg.metrics.threshold_pct)
            res[f"orbit_rms_pct_{k}"] = s["rms_pct"]
            res[f"satisfactory_{k}"] = bool(s["satisfactory"])
        out[name] = res
        print(name, {k: v for k, v in res.items() if "jump" in k or k.startswith("orbit") or k == "test_rel_err_median"})
    io.write_json(cfg.out, out)
