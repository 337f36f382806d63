"""Evaluate no control, the DQN agent and MPC on the reference model of the active bearing (Fig. 5;
``experiments/evaluate_control.py``, reports/control.json and reports/figures/fig5_*.png)."""
from __future__ import annotations

import time

import numpy as np

from fluidfilm import io, load_surrogate
from fluidfilm.control import ConstantSleeve, DQNController, run_episode
from fluidfilm.control.build import env_from_cfg
from fluidfilm.control.dqn import load_agent
from fluidfilm.control.mpc import BatchedMPC
from fluidfilm.reynolds import ConicalReynoldsSolver
from fluidfilm.studies.plots import fig5_panels
from fluidfilm.workflow.config import bearing_from_cfg, reference_from_cfg
from fluidfilm.workflow.entry import plain
from fluidfilm.workflow.tracking import Logged

INPUTS = ("surrogate_dir", "agent_path")
OUTPUTS = {"out_json": [""], "figures_dir": ["fig5_a_dqn.png", "fig5_b_none.png", "fig5_c_mpc.png", "fig5_amplitude.png"]}


def tracking_run(cfg):
    return "control_evaluation", {"stage": "evaluate_control"}


def run(cfg):  # unannotated: models built from a config are typed as unions; the library calls are checked
    c = plain(cfg)
    reference = reference_from_cfg(bearing_from_cfg(cfg.bearing), cfg.reference)
    env = env_from_cfg(reference, c["rotor"], c["controller"])
    surrogate = load_surrogate(cfg.surrogate_dir)
    controllers = [ConstantSleeve(env.initial_action, name="none"), DQNController(load_agent(cfg.agent_path)),
                   BatchedMPC(surrogate, **c["controller"]["mpc"])]
    runs = {}
    for ctrl in controllers:
        t0 = time.perf_counter()
        res = run_episode(env, ctrl)
        res["wall_s"] = time.perf_counter() - t0
        runs[ctrl.name] = res
        print(f"{ctrl.name}: max amplitude {res['max_amplitude_m'] * 1e6:.1f} um, final {res['final_amplitude_m'] * 1e6:.1f} um, "
              f"friction {res['mean_friction_power_W']:.2f} W, sleeve travel {res['sleeve_travel_m'] * 1e3:.1f} mm, "
              f"{res['decision_ms_median']:.3f} ms per decision, return {res['return']:.1f}")
    none = runs["none"]["max_amplitude_m"]
    summary = {name: {k: v for k, v in r.items() if k not in ("history", "t", "x", "v")} for name, r in runs.items()}
    # the cone's axial film force over the last revolution (the planar rotor model does not carry it)
    cone = ConicalReynoldsSolver(reference.bearing, *cfg.reference.coarse)
    for name, r in runs.items():
        cone.set_sleeve(r["history"][-1]["sleeve"])
        n_rev = int(round(2 * np.pi / reference.bearing.omega / (r["t"][1] - r["t"][0])))
        idx = np.linspace(len(r["t"]) - n_rev, len(r["t"]) - 1, 24).astype(int)
        f3 = cone.forces_axial(r["x"][idx], r["v"][idx])[:, 2]
        summary[name]["axial_force_N_mean_last_rev"] = float(f3.mean())
        summary[name]["axial_force_N_max_last_rev"] = float(f3.max())
    for name, r in runs.items():
        summary[name]["amplitude_reduction_pct"] = 100.0 * (1.0 - r["max_amplitude_m"] / none)
        summary[name]["sleeve_schedule_m"] = [float(h["sleeve"]) for h in r["history"]]
    out = {"controllers": summary, "scenario": c["controller"]["scenario"], "reward": c["controller"]["reward"],
           "sleeve_positions_m": c["controller"]["sleeve_positions"],
           "controller_amplitude_reduction_pct": summary["dqn"]["amplitude_reduction_pct"],
           "mpc_amplitude_reduction_pct": summary["mpc"]["amplitude_reduction_pct"],
           "evaluated_on": repr(reference), "nominal_clearance_m": env.c0}
    io.write_json(cfg.out_json, out)
    fig5_panels(runs, env.c0, cfg.figures_dir, ramp=(env.scenario.imbalance_start, env.scenario.imbalance_end))
    metrics = {f"{name}_{k}": float(v) for name, s in summary.items() for k, v in s.items()
               if isinstance(v, (int, float)) and not isinstance(v, bool)}
    return Logged(metrics, value=out)
