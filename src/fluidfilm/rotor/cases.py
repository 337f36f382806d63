"""The paper's seven trajectory cases (Fig. 4 a-g) as plain data, and running them on any force model."""
from __future__ import annotations

from collections.abc import Mapping

from fluidfilm.rotor.integrate import Trajectory, simulate
from fluidfilm.rotor.metrics import compare_orbits, is_satisfactory, is_satisfactory_paper_reading, orbit_stats
from fluidfilm.rotor.model import Rotor


def rotor_for_case(rotor_cfg: Mapping, case_cfg: Mapping) -> Rotor:
    """What one bearing carries in a case: the rotor's share of mass, imbalance and external force."""
    return Rotor.shared(total_mass=rotor_cfg["mass"], total_imbalance=case_cfg["imbalance"],
                        total_external_force=tuple(case_cfg["external_force"]),
                        load_share=rotor_cfg.get("load_share", 1.0), gravity=rotor_cfg.get("gravity", 9.81),
                        imbalance_direction=int(rotor_cfg.get("imbalance_direction", 1)))


def run_case(model, rotor_cfg: Mapping, case_cfg: Mapping, integrator_cfg: Mapping) -> Trajectory:
    """Integrate one case with the configured integrator settings."""
    return simulate(model, rotor_for_case(rotor_cfg, case_cfg), t_end=integrator_cfg["t_end"],
                    dt=integrator_cfg["dt"], eps_stop=integrator_cfg["eps_stop"],
                    eps_substep=integrator_cfg["eps_substep"], record_every=integrator_cfg["record_every"])


def run_cases(model, runs, integrator_cfg: Mapping, threads: int | None = None) -> list[Trajectory]:
    """Integrate several (rotor config, case config) pairs at once, as ``run_case`` each would.

    One ``simulate_batch`` over all of them, stage-batched whatever their number (the force kernel called
    once per RK4 stage for every running trajectory, ``threads`` across the batch; None: every core), so a
    study of many reference orbits uses both cores.  The reference solvers' batched path equals ``simulate``
    to the last bit (tests/rotor/test_batch.py); a surrogate's runs in float64 here, as ``simulate``'s.
    """
    from fluidfilm.rotor.batch import _thread_count, simulate_batch

    if not runs:
        return []
    # threads take contiguous chunks of the batch: dealt out round-robin, each chunk gets a share of every
    # kind of run (a sweep's heavy, eccentric runs take substeps and cost several times the others)
    n = len(runs)
    k = _thread_count(threads, n)
    order = [i for t in range(k) for i in range(t, n, k)]
    rotors = [rotor_for_case(*runs[i]) for i in order]
    batch = simulate_batch(model, rotors, t_end=integrator_cfg["t_end"], dt=integrator_cfg["dt"],
                           eps_stop=integrator_cfg["eps_stop"], eps_substep=integrator_cfg["eps_substep"],
                           record_every=integrator_cfg["record_every"], threads=threads, precision="float64",
                           stage_batched=True)
    out: list[Trajectory] = [None] * n  # type: ignore[list-item]
    for p, i in enumerate(order):
        out[i] = batch.trajectory(p)
    return out


def case_summary(traj: Trajectory, clearance: float, t_settle: float, ref: Trajectory | None = None,
                 threshold_pct: float | None = None) -> dict:
    """Orbit statistics of a case, and its distances from a reference orbit when one is given."""
    out = {"status": traj.status, "wall_time_s": traj.wall_time_s, "n_force_evals": traj.n_force_evals,
           "n_outside_domain": traj.n_outside_domain}
    out.update(orbit_stats(traj, clearance, t_settle))
    if ref is not None:
        d = compare_orbits(traj, ref, clearance, t_settle)
        out.update(d)
        if threshold_pct is not None:
            out["satisfactory"] = is_satisfactory(d, threshold_pct)
            out["satisfactory_paper_reading"] = is_satisfactory_paper_reading(d, threshold_pct)
    return out
