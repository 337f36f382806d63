"""The batched integrator against the unbatched one (same trajectories, to the last bit).

- reference solver, linear bearing and a sleeve-input surrogate: every trajectory of a batch
  (different imbalance, load, initial state, sleeve) equals ``simulate``'s run of it alone;
- trajectories that stop (contact) stop at the same time with the same state, the others go on;
- the model's own control setting is restored after a batch; bad input raises a clear error;
- the stage-batched loop (one batched-kernel call per RK4 stage; the default for models with a batched
  kernel and batches of at least ``STAGE_BATCHED_MIN_N``): to the last bit for the reference models and the linear bearing (their batched kernels give
  the one-state kernel's forces exactly), whatever the threads and against the lockstep loop; for a
  surrogate (batched kernel equal to the one-state kernel to round-off) within 1e-9 c of ``simulate`` in
  float64 and 1e-4 c with float32 networks over case d of the paper, with equal counters; batches mixing a
  contact, a substepping and a normal trajectory.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import yaml

from fluidfilm import GradedReynoldsModel, ReynoldsSolver, Rotor, paper_bearing, simulate
from fluidfilm.core.bearing import bearing_from_dict
from fluidfilm.rotor import LinearBearing
from fluidfilm.perf.speed import best_shaped_surrogate
from fluidfilm.rotor.batch import simulate_batch
from fluidfilm.rotor.cases import rotor_for_case
from fluidfilm.surrogate.inference import SurrogateForceModel
from fluidfilm.surrogate.scaling import Scaling

from conftest import ROOT


def _assert_same(batch, p, single):
    tp = batch.trajectory(p)
    assert tp.status == single.status
    assert tp.n_force_evals == single.n_force_evals
    np.testing.assert_array_equal(tp.x, single.x)
    np.testing.assert_array_equal(tp.v, single.v)
    np.testing.assert_allclose(tp.t, single.t, rtol=0, atol=1e-15)


@pytest.mark.parametrize("stage_batched", [False, True])
def test_batch_of_reference_trajectories_equals_simulate(stage_batched):
    b = paper_bearing()
    solver = ReynoldsSolver(b, 30, 30)
    c = b.clearance
    rotors = [Rotor(mass=2.5, imbalance=u, external_force=f) for u, f in
              [(0.0, (0.0, 0.0)), (5e-4, (0.0, 0.0)), (1e-3, (20.0, 0.0)), (2e-4, (-30.0, 10.0))]]
    x0 = np.array([[0.0, 0.0], [0.3 * c, 0.0], [0.0, 0.5 * c], [-0.2 * c, 0.6 * c]])
    v0 = np.array([[0.0, 0.0], [0.0, 0.01], [0.005, 0.0], [0.0, 0.0]])
    batch = simulate_batch(solver, rotors, 0.005, 1e-5, x0, v0, record_every=7, stage_batched=stage_batched)
    assert len(batch) == 4 and batch.ok.all()
    for p in range(4):
        _assert_same(batch, p, simulate(solver, rotors[p], 0.005, 1e-5, x0[p], v0[p], record_every=7))


@pytest.mark.parametrize("stage_batched", [False, True])
def test_batch_with_contact_stops_only_that_trajectory(stage_batched):
    b = paper_bearing()
    lin = LinearBearing(b, stiffness=1e6, damping=50.0)
    # a soft spring and a heavy static load drive trajectory 1 into the sleeve; 0 stays inside
    rotors = [Rotor(mass=2.5), Rotor(mass=2.5, external_force=(0.0, 400.0))]
    batch = simulate_batch(lin, rotors, 0.12, 1e-5, record_every=5, t0=0.1,  # t_end: the end time
                           stage_batched=stage_batched)
    assert batch.ok.tolist() == [True, False]
    for p in range(2):
        _assert_same(batch, p, simulate(lin, rotors[p], 0.12, 1e-5, record_every=5, t0=0.1))
    # the outputs start empty: the loops write the recorded rows and NaN in every row past them
    n_rec = batch.n_recorded
    assert n_rec[1] < n_rec[0] < batch.x.shape[1]  # one spare row: a stop between two recorded steps
    for p in range(2):
        for out in (batch.x, batch.v):
            assert np.isfinite(out[p, :n_rec[p]]).all() and np.isnan(out[p, n_rec[p]:]).all()


def _random_active_surrogate(seed=0):
    """A sleeve-input surrogate with random weights: not a physical model, a kernel to compare paths on."""
    cone = bearing_from_dict(yaml.safe_load((ROOT / "conf" / "bearing" / "conical.yaml").read_text()))
    rng = np.random.default_rng(seed)
    n_in = 4
    sc = Scaling("physics", cone.clearance, cone.omega, 20.0, 1.5, np.zeros(n_in), np.ones(n_in),
                 np.array([-1.0, 0.3]), np.ones(2) * 0.2, "polar", ("S",),
                 (cone.clearance_at(1e-4) - cone.clearance) / 1e-4)
    layers = [(rng.normal(size=(16, n_in)), rng.normal(size=16)), (0.1 * rng.normal(size=(2, 16)), np.zeros(2))]
    return SurrogateForceModel(cone, [layers], [sc], "tanh", name="random_active")


def test_batch_with_per_trajectory_sleeve_equals_simulate_at_each_sleeve():
    model = _random_active_surrogate()
    sleeves = [-0.8e-3, 0.0, 0.4e-3]
    rotor = Rotor(mass=2.5, imbalance=5e-4)
    model.set_sleeve(0.0)
    c = model.clearance
    x0 = np.array([0.1 * c, 0.2 * c])
    batch = simulate_batch(model, rotor, 0.004, 1e-5, x0, settings=[model.setting_for(s) for s in sleeves])
    assert model.sleeve == 0.0 and model.clearance == c  # restored
    assert len({tuple(batch.x[p, batch.n_recorded[p] - 1]) for p in range(3)}) == 3  # the sleeve matters
    for p, s in enumerate(sleeves):
        model.set_sleeve(s)
        _assert_same(batch, p, simulate(model, rotor, 0.004, 1e-5, x0))


def test_the_default_loop_depends_on_the_batch_size():
    """Below ``STAGE_BATCHED_MIN_N`` trajectories the lockstep loop, from it on the stage-batched one: seen in
    the surrogate's float32 option, which only the stage-batched loop takes."""
    from fluidfilm.rotor.batch import STAGE_BATCHED_MIN_N

    b = paper_bearing()
    model = best_shaped_surrogate(b)
    n = STAGE_BATCHED_MIN_N
    x0 = np.zeros((n, 2))
    x0[:, 1] = np.linspace(0.0, 0.4, n) * b.clearance
    rotor = Rotor(mass=2.5, imbalance=5e-4)

    def run(m, **kw):
        return simulate_batch(model, rotor, 5e-4, 1e-5, x0[:m], threads=1, **kw).x

    np.testing.assert_array_equal(run(n - 1, precision="float32"), run(n - 1))  # lockstep: float64 kernel
    assert not np.array_equal(run(n, precision="float32"), run(n))
    np.testing.assert_array_equal(run(n), run(n, stage_batched=True))


def _assert_batches_equal(a, b):
    for name in ("x", "v", "n_recorded", "t_stop", "n_force_evals"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert a.status == b.status


def _mixed_linear_batch():
    """A normal, a contact (heavy static load) and a substepping trajectory (released at eps 0.92, it spends
    its first steps above eps_substep = 0.8) of a linear bearing, 20 ms."""
    b = paper_bearing()
    lin = LinearBearing(b, stiffness=1e6, damping=1500.0)  # about half the critical damping: little overshoot
    c = b.clearance
    rotors = [Rotor(mass=2.5, imbalance=2e-4), Rotor(mass=2.5, external_force=(0.0, 400.0)), Rotor(mass=2.5)]
    x0 = np.array([[0.1 * c, 0.0], [0.0, 0.0], [0.0, -0.92 * c]])
    return lin, rotors, x0


def test_stage_batched_mixed_batch_equals_simulate_and_the_lockstep_loop_to_the_last_bit():
    lin, rotors, x0 = _mixed_linear_batch()
    n_steps = 2000
    runs = {threads: simulate_batch(lin, rotors, 0.02, 1e-5, x0, record_every=3, threads=threads, stage_batched=True)
            for threads in (1, 2, 3)}
    lockstep = simulate_batch(lin, rotors, 0.02, 1e-5, x0, record_every=3, stage_batched=False)
    batch = runs[1]
    assert batch.ok.tolist() == [True, False, True]
    assert batch.n_force_evals[0] == 4 * n_steps and batch.n_force_evals[2] > 4 * n_steps  # 2 substepped
    for p in range(3):
        _assert_same(batch, p, simulate(lin, rotors[p], 0.02, 1e-5, x0[p], record_every=3))
    for other in (runs[2], runs[3], lockstep):
        _assert_batches_equal(batch, other)


def test_stage_batched_graded_reference_equals_simulate_to_the_last_bit():
    """The graded reference's batched kernel (each state on its grid, the dense one above eps 0.9)."""
    b = paper_bearing()
    model = GradedReynoldsModel(b, coarse=(16, 8), dense=(24, 12))
    c = b.clearance
    rotor = Rotor(mass=2.5, imbalance=5e-4)
    x0 = np.array([[0.0, 0.0], [0.3 * c, 0.2 * c], [0.0, 0.93 * c]])  # the last starts on the dense grid
    batch = simulate_batch(model, rotor, 0.003, 1e-5, x0, threads=2, stage_batched=True)
    assert batch.n_force_evals[2] > 4 * 300  # substeps near the sleeve
    for p in range(3):
        _assert_same(batch, p, simulate(model, rotor, 0.003, 1e-5, x0[p]))


def _case_d_rotor():
    rotor_cfg = yaml.safe_load((ROOT / "conf" / "rotor" / "paper.yaml").read_text())
    return rotor_for_case(rotor_cfg, yaml.safe_load((ROOT / "conf" / "case" / "d.yaml").read_text()))


#: the stage-batched surrogate against ``simulate`` (its one-state kernel), max |dX| (and 0.1 ms times |dV|) over
#: the run in units of c: float64 round-off, float32 networks.  The random-weight surrogate's case-d orbit is
#: irregular (eps 0.004-0.5) and amplifies a difference about 2x every 5 ms (measured: 1e-12 c after 40 ms,
#: 4e-9 c after 100 ms in float64), so the comparison runs 40 ms (two revolutions)
SURROGATE_F64_TOL = 1e-9
SURROGATE_F32_TOL = 1e-4


def _max_dx(batch, p, single, c):
    tp = batch.trajectory(p)
    # the same end, contact or divergence text (the domain counted per trajectory, as simulate's)
    assert tp.completed == single.completed
    if not tp.completed:
        assert tp.status.split(";")[0] == single.status.split(";")[0]
    assert tp.n_force_evals == single.n_force_evals and len(tp.x) == len(single.x)
    np.testing.assert_allclose(tp.t, single.t, rtol=0, atol=1e-15)
    return max(np.abs(tp.x - single.x).max(), np.abs(tp.v - single.v).max() * 1e-4) / c


@pytest.mark.filterwarnings("ignore:.*outside the training domain:RuntimeWarning")
def test_stage_batched_surrogate_follows_simulate_over_case_d_in_float64_and_float32():
    b = paper_bearing()
    model = best_shaped_surrogate(b)
    c = b.clearance
    rotor = _case_d_rotor()
    x0 = np.array([[0.0, 0.0], [0.3 * c, 0.1 * c], [-0.2 * c, -0.4 * c], [0.0, 0.5 * c]])
    t_end = 0.04
    singles = [simulate(model, rotor, t_end, 1e-5, x0[p], record_every=10) for p in range(4)]
    n_outside = sum(s.n_outside_domain for s in singles)
    for precision, tol in (("float64", SURROGATE_F64_TOL), ("float32", SURROGATE_F32_TOL)):
        batch = simulate_batch(model, rotor, t_end, 1e-5, x0, record_every=10, threads=1, precision=precision,
                               stage_batched=True)
        assert model.n_outside_domain == n_outside, precision
        if precision == "float64":  # each trajectory its own count (float32 networks move the states by 1e-4 c)
            assert batch.n_outside_domain.tolist() == [s.n_outside_domain for s in singles]
        worst = max(_max_dx(batch, p, singles[p], c) for p in range(4))
        assert worst < tol, (precision, worst)
        # the orbits are not trivial: they span a good part of the clearance
        assert np.hypot(*batch.x[0, :batch.n_recorded[0]].T).max() > 0.1 * c
        # threads split the batch into chunks; a trajectory does not depend on them
        _assert_batches_equal(batch, simulate_batch(model, rotor, t_end, 1e-5, x0, record_every=10, threads=3,
                                                    precision=precision, stage_batched=True))
        assert model.n_outside_domain == n_outside, precision


@pytest.mark.filterwarnings("ignore:.*outside the training domain:RuntimeWarning")
def test_stage_batched_surrogate_mixed_batch_of_contact_substeps_and_a_normal_orbit():
    """2 ms: the random-weight surrogate's orbit released near the sleeve is chaotic (its round-off doubles
    about every 40 steps), so the comparison with ``simulate`` is kept short."""
    b = paper_bearing()
    model = best_shaped_surrogate(b)
    c = b.clearance
    rotor = _case_d_rotor()
    rotors = [rotor, dataclasses.replace(rotor, external_force=(0.0, 30000.0)), rotor]
    x0 = np.array([[0.1 * c, 0.0], [0.0, 0.5 * c], [0.0, 0.88 * c]])
    n_steps = 200
    batch = simulate_batch(model, rotors, 0.002, 1e-5, x0, threads=2, stage_batched=True, precision="float64")
    n_outside = model.n_outside_domain  # the whole batch's (simulate resets the counter)
    singles = [simulate(model, rotors[p], 0.002, 1e-5, x0[p]) for p in range(3)]
    # each trajectory's own domain count and status, as simulate's
    assert batch.completed.tolist() == [True, False, True] and batch.ok.tolist() == [s.ok for s in singles]
    assert batch.n_outside_domain.tolist() == [s.n_outside_domain for s in singles]
    assert batch.n_force_evals[0] == 4 * n_steps and batch.n_force_evals[2] > 4 * n_steps
    assert max(_max_dx(batch, p, singles[p], c) for p in range(3)) < SURROGATE_F64_TOL
    assert n_outside == sum(s.n_outside_domain for s in singles) > 0


@pytest.mark.parametrize("kwargs, match", [
    ({"x0": np.zeros((3, 2))}, "3 rotors|rotors for a batch"),
    ({"x0": np.zeros((2, 3))}, "x0 must be"),
    ({"dt": -1.0}, "dt must be"),
    ({"settings": np.zeros((2, 2))}, "no per-trajectory settings"),
    ({"threads": 0}, "threads must be a positive integer or None"),
    ({"threads": 1.5}, "threads must be"),
    ({"precision": "float16"}, "precision must be 'float64' or 'float32', got 'float16'"),
])
def test_bad_batch_input_raises(kwargs, match):
    lin = LinearBearing(paper_bearing(), 1e7, 100.0)
    args = {"rotors": [Rotor(mass=1.0), Rotor(mass=2.0)], "t_end": 0.001, "dt": 1e-5} | kwargs
    with pytest.raises(ValueError, match=match):
        simulate_batch(lin, **args)


def test_run_cases_equals_run_case_one_by_one_to_the_last_bit():
    """``run_cases`` (one stage-batched, threaded batch, dealt round-robin to the threads) returns each run's
    trajectory, in the order given, exactly as ``run_case`` integrates it alone (the reference model)."""
    from fluidfilm.rotor.cases import run_case, run_cases

    model = GradedReynoldsModel(paper_bearing())
    integ = {"t_end": 0.004, "dt": 1e-5, "eps_stop": 0.98, "eps_substep": 0.8, "record_every": 1}
    runs = [({"mass": m, "load_share": s}, {"imbalance": u, "external_force": [0.0, 0.0]})
            for m, s, u in ((2.5, 1.0, 1e-4), (10.0, 1.0, 1e-3), (0.5, 0.5, 5e-5))]
    together = run_cases(model, runs, integ, threads=2)
    assert len(together) == len(runs)
    for traj, (rotor, case) in zip(together, runs):
        alone = run_case(model, rotor, case, integ)
        assert traj.status == alone.status and traj.n_force_evals == alone.n_force_evals
        np.testing.assert_array_equal(traj.x, alone.x)
        np.testing.assert_array_equal(traj.v, alone.v)
    assert run_cases(model, [], integ) == []


_CACHE_PROBE = """
import numpy as np
from fluidfilm import GradedReynoldsModel, Rotor, paper_bearing
from fluidfilm.perf.speed import best_shaped_surrogate
from fluidfilm.rotor.batch import _rk4_stages, simulate_batch
for model in (GradedReynoldsModel(paper_bearing()), best_shaped_surrogate(paper_bearing())):
    simulate_batch(model, [Rotor(mass=2.5)] * 2, t_end=2e-4, threads=1, stage_batched=True)
print(len(_rk4_stages.stats.cache_hits), len(_rk4_stages.stats.cache_misses))
"""


def test_the_stage_batched_loop_is_compiled_once_and_then_loaded_from_numbas_cache(tmp_path):
    """A new process finds the stage-batched loop in numba's on-disk cache (numba's own hit and miss
    counts), for the reference and for a surrogate's generated kernel: the kernel is typed by its signature,
    not by the function object, whose type numba compares by identity (so that every process compiled the
    loop again, ~20 s per kernel)."""
    import os
    import subprocess
    import sys

    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))  # an empty cache: the first run must compile

    def probe():
        out = subprocess.run([sys.executable, "-c", _CACHE_PROBE], env=env, capture_output=True, text=True,
                             cwd=ROOT, check=True).stdout.split()
        return int(out[-2]), int(out[-1])

    hits, misses = probe()
    assert (hits, misses) == (0, 2)  # one loop per kernel signature (the two models' parameters differ)
    hits, misses = probe()
    assert (hits, misses) == (2, 0)


@pytest.mark.filterwarnings("ignore:.*outside the training domain:RuntimeWarning")
def test_threads_do_not_change_the_domain_counts_of_a_batch_as_long_as_the_domain_table():
    """The threads' chunks slice the per-trajectory arrays, not the domain table: a batch of as many trajectories
    as the table has rows (1 + 2 bands) once counted trajectory 2 by a table that was its last band alone."""
    from golden_models import models

    model = models()["surrogate_split"][0]
    assert len(model.validity.bands) == 2
    c = model.clearance
    x0 = np.array([[0.0, 0.45 * c], [0.55 * c, 0.0], [0.0, 0.7 * c]])
    v0 = np.array([[0.0, 0.0], [0.0, 0.06], [0.2, 0.0]])
    runs = [simulate_batch(model, Rotor(mass=2.5, imbalance=2e-4), 2e-3, 1e-5, x0, v0, threads=threads,
                           stage_batched=True, precision="float64") for threads in (1, 2, 3)]
    lockstep = simulate_batch(model, Rotor(mass=2.5, imbalance=2e-4), 2e-3, 1e-5, x0, v0, stage_batched=False)
    assert lockstep.n_outside_domain.min() > 0
    for batch in runs:
        assert batch.n_outside_domain.tolist() == lockstep.n_outside_domain.tolist()
        assert batch.status == lockstep.status
