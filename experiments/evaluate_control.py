"""Evaluate no control, the DQN agent and MPC on the reference model of the active bearing (Fig. 5).

    python experiments/evaluate_control.py
Writes reports/control.json (amplitudes, friction, sleeve travel, time per decision, the
amplitude reduction) and reports/figures/fig5_*.png; logs to MLflow.
"""
import time

import hydra
import numpy as np
from omegaconf import DictConfig, OmegaConf

from fluidfilm import io, load_surrogate
from fluidfilm.workflow import tracking
from fluidfilm.workflow.config import bearing_from_cfg, reference_from_cfg
from fluidfilm.control import ConstantSleeve, DQNController, run_episode
from fluidfilm.control.mpc import BatchedMPC
from fluidfilm.control.build import env_from_cfg
from fluidfilm.control.dqn import load_agent
from fluidfilm.studies.plots import fig5_panels
from fluidfilm.reynolds import ConicalReynoldsSolver
from fluidfilm.workflow.config_check import check_config


@hydra.main(config_path="../conf", config_name="control", version_base="1.3")
def main(cfg: DictConfig) -> dict:
    check_config(cfg)  # a mistyped value or an unknown key is refused here, before any work
    c = OmegaConf.to_container(cfg, resolve=True)
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
    with tracking.run(cfg.tracking, "control_evaluation", c, tags={"stage": "evaluate_control"}) as run:
        if run is not None:
            for name, s in summary.items():
                tracking.log_metrics({f"{name}_{k}": float(v) for k, v in s.items()
                                    if isinstance(v, (int, float)) and not isinstance(v, bool)})
    return out


if __name__ == "__main__":
    io.run_interruptible(main, "the controller evaluation", "run the same command again")
