"""Bit-for-bit evidence for refactors of the batched integrator (``rotor.batch``, issue #50).

``simulate_batch`` over every kind of model its two loops take and the paths inside them: the linear
bearing, the plain and the graded reference, surrogates (a plain tanh network, a split network with a
banded validity domain, the damping structure, the best model's shapes through the generated batched
kernels, a velocity outside the training domain), a sleeve-input surrogate with per-trajectory settings,
an ensemble and a hybrid (the uncached twins), and a user's model (a compiled kernel from outside the
library: the uncached twins again, with and without a batched kernel); the stage-batched loop (float64 and
float32 networks, 1 to 3 threads) and the lockstep one, the default choice on both sides of
``STAGE_BATCHED_MIN_N``; rotors with imbalance, a ramped imbalance, the negative direction, static loads
and gravity; a start time t0; chunked (13 steps) and unchunked runs; and every end a trajectory can have:
ok, contact (after a step and inside a stage), diverged (a non-finite state), unresolved (the along-the-run
step check), outside-domain (each trajectory's count, and ``strict``'s error).

    python benchmarks/batch_bitwise.py save  OUT.npz   # before a change
    python benchmarks/batch_bitwise.py check OUT.npz   # after it: every array equal (np.array_equal)

Per run it keeps every array of the ``BatchTrajectory`` (x, v, t, n_recorded, t_stop, n_force_evals,
n_outside_domain, eps_reached), its statuses (as bytes) and the model's counters afterwards.
"""
from __future__ import annotations

import contextlib
import dataclasses
import sys
import warnings
from pathlib import Path

import numpy as np
from numba import njit

from fluidfilm.perf.benchmarking import save_or_check

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))


# --- a user's model: compiled kernels defined outside the library (the loops' uncached twins) -----------
@njit
def _user_force(params, x1, x2, v1, v2):
    k, c, k3, x_jump, f_jump = params
    if x_jump < x1 < x_jump + 1e-9:  # a jump: finite forces whose RK4 update overflows ("diverged")
        return f_jump, 0.0
    r2 = x1 * x1 + x2 * x2
    return -k * (1.0 + k3 * r2) * x1 - c * v1, -k * (1.0 + k3 * r2) * x2 - c * v2


@njit
def _user_forces(params, x, v, out):
    for i in range(x.shape[0]):
        out[i, 0], out[i, 1] = _user_force(params, x[i, 0], x[i, 1], v[i, 0], v[i, 1])


def _user_model(batched: bool, jump: tuple = (np.inf, 0.0)):
    from fluidfilm.rotor import LinearBearing

    class UserModel(LinearBearing):
        """A cubic spring-damper whose kernels are this script's (module ``__main__``)."""

        @property
        def force_kernel(self):
            return _user_force, (float(self.stiffness), float(self.damping), 3e7) + jump

        def batch_force_kernel(self, precision: str = "float64", private: bool = False):
            return (_user_forces, self.force_kernel[1]) if batched else None

    from fluidfilm import paper_bearing

    return UserModel(paper_bearing(), 1e6, 900.0)


@contextlib.contextmanager
def _chunks(min_steps: int | None):
    """Steps per chunk: ``min_steps`` (13: many chunks), None: the library's own rule; 0: one chunk."""
    from fluidfilm.rotor import integrate

    saved = integrate.CHUNK_MIN_STEPS, integrate.MAX_CHUNKS
    if min_steps == 0:
        integrate.CHUNK_MIN_STEPS, integrate.MAX_CHUNKS = 10**9, 1
    elif min_steps is not None:
        integrate.CHUNK_MIN_STEPS, integrate.MAX_CHUNKS = min_steps, 10**6
    try:
        yield
    finally:
        integrate.CHUNK_MIN_STEPS, integrate.MAX_CHUNKS = saved


def _text(strings) -> np.ndarray:
    return np.frombuffer("\n".join(strings).encode(), dtype=np.uint8).copy()


def _keep(res: dict, name: str, model, run) -> None:
    """``run()``'s BatchTrajectory (or its error's text) and the model's counters, under ``name/``."""
    try:
        bt = run()
    except Exception as err:  # noqa: BLE001 - the error is part of the evidence (strict=True)
        res[f"{name}/error"] = _text([f"{type(err).__name__}: {err}"])
    else:
        for key in ("x", "v", "t", "n_recorded", "t_stop", "n_force_evals", "n_outside_domain", "eps_reached"):
            res[f"{name}/{key}"] = np.asarray(getattr(bt, key))
        res[f"{name}/status"] = _text(bt.status)
    counters = [getattr(model, k) for k in ("n_outside_domain", "n_evaluations", "n_flagged", "n_fallbacks")
                if hasattr(model, k)]
    res[f"{name}/counters"] = np.array(counters, dtype=np.int64)


def evaluate() -> dict[str, np.ndarray]:
    from faults import models as fault_models
    from golden_models import _net, _scaling
    from golden_models import models as golden

    from fluidfilm import GradedReynoldsModel, ReynoldsSolver, Rotor, paper_bearing
    from fluidfilm.perf.speed import best_shaped_surrogate
    from fluidfilm.rotor import LinearBearing
    from fluidfilm.rotor.batch import STAGE_BATCHED_MIN_N, simulate_batch
    from fluidfilm.surrogate import SurrogateForceModel
    from fluidfilm.surrogate.ensemble import EnsembleForceModel, HybridForceModel

    warnings.simplefilter("ignore")
    res: dict[str, np.ndarray] = {}
    b = paper_bearing()
    c = b.clearance

    def run(name, model, rotors, t_end, dt=1e-5, chunk=None, **kw):
        def go():
            with _chunks(chunk):
                return simulate_batch(model, rotors, t_end, dt, **kw)
        _keep(res, name, model, go)

    # --- the linear bearing: a normal, a contact and a substepping trajectory ------------------------------
    lin = LinearBearing(b, stiffness=1e6, damping=1500.0)
    rotors = [Rotor(mass=2.5, imbalance=2e-4), Rotor(mass=2.5, external_force=(0.0, 400.0)), Rotor(mass=2.5)]
    x0 = np.array([[0.1 * c, 0.0], [0.0, 0.0], [0.0, -0.92 * c]])
    for threads in (1, 2, 3):
        run(f"linear_mixed_staged_t{threads}", lin, rotors, 0.01, x0=x0, record_every=3, threads=threads,
            stage_batched=True)
    run("linear_mixed_lockstep", lin, rotors, 0.01, x0=x0, record_every=3, stage_batched=False)
    for loop in ("staged", "lockstep"):
        for chunk in (13, 0):
            t0 = 0.1 if chunk else 0.0
            run(f"linear_mixed_{loop}_chunk{chunk}", lin, rotors, t0 + 0.01, chunk=chunk, x0=x0, record_every=7,
                threads=2, stage_batched=loop == "staged", t0=t0)
    # ramped imbalance, the negative direction, loads, gravity off and on, a start velocity, t0
    ramp = [Rotor(mass=2.5, imbalance=1e-4, imbalance_final=6e-4, ramp_time=3e-3),
            Rotor(mass=1.5, imbalance=3e-4, imbalance_direction=-1, external_force=(-40.0, 15.0), gravity=0.0),
            Rotor(mass=4.0, imbalance=2e-4, imbalance_final=1e-5, ramp_time=1e-2, imbalance_direction=-1),
            Rotor(mass=2.0, external_force=(25.0, -60.0))]
    x0r = np.array([[0.0, 0.2 * c], [-0.3 * c, 0.1 * c], [0.0, 0.0], [0.4 * c, -0.4 * c]])
    v0r = np.array([[0.01, 0.0], [0.0, -0.02], [0.0, 0.0], [0.005, 0.005]])
    for loop in ("staged", "lockstep"):
        for t0 in (0.0, 0.0137):
            run(f"linear_ramp_{loop}_t0{t0}", lin, ramp, t0 + 0.006, x0=x0r, v0=v0r, record_every=2, threads=2,
                stage_batched=loop == "staged", t0=t0)
        # a stage outside the clearance (contact inside a stage: no step check, a long step near the sleeve)
        run(f"linear_stage_contact_{loop}", LinearBearing(b, 1e5, 10.0), [Rotor(mass=0.05)] * 2, 2e-3, dt=5e-5,
            x0=np.array([[0.0, 0.9 * c], [0.0, 0.1 * c]]), v0=np.array([[0.0, 2.0], [0.0, 0.0]]),
            stage_batched=loop == "staged", check_step=False, threads=1)
        # diverged: a user's force that jumps to 1e308 N just past x1 = -1e-5 m: stages 1 and 2 of the first step
        # sit at the start, stages 3 and 4 just past it, and the update overflows (no step check)
        for batched in (True, False):
            run(f"user_diverged_{'batched' if batched else 'plain'}_{loop}", _user_model(batched, (-1e-5, 1e308)),
                [Rotor(mass=1.0, gravity=0.0), Rotor(mass=1.0)], 1e-4, x0=np.array([[-1e-5, 0.0], [0.0, 0.1 * c]]),
                stage_batched=loop == "staged", check_step=False, threads=1)
    # --- the references ---------------------------------------------------------------------------------------
    ref = ReynoldsSolver(b, 16, 8)
    rrot = [Rotor(mass=2.0, imbalance=5e-5), Rotor(mass=2.0, external_force=(0.0, 2000.0)),
            Rotor(mass=3.0, imbalance=2e-5)]
    rx0 = np.array([[0.0, 0.0], [0.0, 0.5 * c], [0.2 * c, 0.85 * c]])
    for loop in ("staged", "lockstep"):
        for chunk in (13, 0):
            run(f"reference_{loop}_chunk{chunk}", ref, rrot, 0.004, chunk=chunk, x0=rx0, record_every=7,
                threads=2, stage_batched=loop == "staged")
    graded = GradedReynoldsModel(b, coarse=(16, 8), dense=(24, 12))
    gx0 = np.array([[0.0, 0.0], [0.3 * c, 0.2 * c], [0.0, 0.93 * c]])
    for loop in ("staged", "lockstep"):
        run(f"graded_{loop}", graded, Rotor(mass=2.5, imbalance=5e-4), 0.002, x0=gx0, threads=2,
            stage_batched=loop == "staged")
    # unresolved along the run: a pushed rotor that the step stops resolving, beside one that stays resolved
    loose = ReynoldsSolver(b, 30, 30)
    for loop in ("staged", "lockstep"):
        run(f"unresolved_{loop}", loose, [Rotor(mass=0.5, external_force=(0.0, 150.0)), Rotor(mass=0.5)], 0.2,
            dt=4e-5, eps_substep=0.95, record_every=10, stage_batched=loop == "staged", threads=2)
    # --- surrogates -----------------------------------------------------------------------------------------
    gold = golden()
    sx0 = np.array([[0.0, 0.3 * c], [0.2 * c, 0.1 * c], [-0.1 * c, 0.4 * c], [0.0, 0.86 * c]])
    srot = [Rotor(mass=2.5, imbalance=1e-4), Rotor(mass=2.5, imbalance=3e-4, imbalance_final=5e-4, ramp_time=1e-3),
            Rotor(mass=2.5, external_force=(0.0, 30000.0)), Rotor(mass=2.5, imbalance=1e-4)]
    surrogates = {name: gold[name][0] for name in ("surrogate_std", "surrogate_split", "surrogate_damping")}
    surrogates["best_shaped"] = best_shaped_surrogate(b)
    surrogates["best_shaped_full"] = best_shaped_surrogate(b, seed=3, restoring=False)
    surrogates["faults_best"] = fault_models.best()
    for name, model in surrogates.items():
        for prec in ("float64", "float32"):
            for threads in (1, 2):
                run(f"{name}_staged_{prec}_t{threads}", model, srot, 1e-3, x0=sx0, precision=prec,
                    threads=threads, stage_batched=True, record_every=3)
        run(f"{name}_lockstep", model, srot, 1e-3, x0=sx0, stage_batched=False, record_every=3)
    for prec in ("float64", "float32"):
        run(f"best_shaped_staged_{prec}_chunk13", surrogates["best_shaped"], srot, 1e-3, chunk=13, x0=sx0,
            precision=prec, threads=2, stage_batched=True)
    # the default loop on both sides of STAGE_BATCHED_MIN_N (the default precision, float32)
    n = STAGE_BATCHED_MIN_N
    nx0 = np.zeros((n, 2))
    nx0[:, 1] = np.linspace(0.0, 0.4, n) * c
    for m in (n - 1, n):
        run(f"best_shaped_default_{m}", surrogates["best_shaped"], Rotor(mass=2.5, imbalance=5e-4), 3e-4,
            x0=nx0[:m], threads=1)
    # each trajectory's own domain count: a velocity outside the data; strict's error
    single = fault_models.single()
    dx0 = np.array([[0.0, 0.3 * c], [0.0, 0.3 * c]])
    dv0 = np.array([[0.0, 0.0], [0.0, 0.6]])
    for loop in ("staged", "lockstep"):
        for prec in ("float64", "float32"):
            run(f"domain_{loop}_{prec}", single, Rotor(mass=2.5), 3e-5, x0=dx0, v0=dv0,
                stage_batched=loop == "staged", precision=prec)
        run(f"domain_strict_{loop}", single, Rotor(mass=2.5), 3e-5, x0=dx0, v0=dv0, strict=True,
            stage_batched=loop == "staged")
        run(f"domain_split_{loop}", surrogates["surrogate_split"], Rotor(mass=2.5, imbalance=2e-4), 2e-3,
            x0=np.array([[0.0, 0.45 * c], [0.55 * c, 0.0], [0.0, 0.7 * c]]),
            v0=np.array([[0.0, 0.0], [0.0, 0.06], [0.2, 0.0]]), stage_batched=loop == "staged", threads=2,
            precision="float64")
    # per-trajectory sleeve settings (the lockstep loop)
    active, sleeve = gold["surrogate_sleeve"]
    active.set_sleeve(sleeve)
    ac = active.clearance
    run("sleeve_settings", active, Rotor(mass=2.5, imbalance=5e-4), 2e-3, x0=np.array([0.1 * ac, 0.2 * ac]),
        settings=[active.setting_for(s) for s in (-0.6e-3, 0.0, 0.4e-3)])
    run("sleeve_own_setting", active, Rotor(mass=2.5, imbalance=5e-4), 2e-3,
        x0=np.array([[0.1 * ac, 0.2 * ac], [0.0, 0.5 * ac]]), threads=2, stage_batched=True)
    # --- ensembles and hybrids (parameters holding compiled functions: the uncached twins) -------------------
    members = []
    for seed in range(3):
        rng = np.random.default_rng(seed)
        members.append(SurrogateForceModel(b, [_net(rng, 4, 8, 2)], [_scaling(np.random.default_rng(99), "standard",
                                                                            c, b.omega, "cartesian")], "tanh",
                                           name=f"s{seed}"))
    ens = EnsembleForceModel(members, rel_tol=0.3, floor_N=0.5)
    hyb = HybridForceModel([LinearBearing(b, 2.0e5, 300.0), LinearBearing(b, 3.0e5, 500.0)],
                           LinearBearing(b, 4.0e5, 250.0), rel_tol=0.3, floor_N=1e-3)
    hrot = [Rotor(mass=0.5, imbalance=u) for u in (2e-6, 5e-6, 1e-5)]
    hx0 = np.array([[1e-6, 0.0], [0.0, 0.2 * c], [0.3 * c, 0.0]])
    for loop in ("staged", "lockstep"):
        run(f"ensemble_{loop}", ens, srot[:2], 1e-3, x0=sx0[:2], stage_batched=loop == "staged", threads=2)
        run(f"hybrid_{loop}", hyb, hrot, 0.01, dt=1e-4, x0=hx0, stage_batched=loop == "staged", threads=2)
    # --- a user's model -------------------------------------------------------------------------------------
    for batched in (True, False):
        user = _user_model(batched)
        for loop in ("staged", "lockstep"):
            run(f"user_{'batched' if batched else 'plain'}_{loop}", user, rotors, 0.005, x0=x0, threads=2,
                stage_batched=loop == "staged", record_every=4)
    # --- without the step check; a different eps_stop, max_substeps -------------------------------------------
    for loop in ("staged", "lockstep"):
        run(f"linear_options_{loop}", lin, [dataclasses.replace(r, mass=r.mass * 1.1) for r in rotors], 0.005,
            x0=x0, eps_stop=0.95, eps_substep=0.5, max_substeps=3, check_step=False, threads=3,
            stage_batched=loop == "staged")
    return res


def main(argv: list[str]) -> int:
    return save_or_check(argv, __doc__, evaluate)


if __name__ == "__main__":
    sys.exit(main(sys.argv))
