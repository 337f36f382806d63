"""``simulate_batch``: N rotor trajectories integrated together, the force model called on the whole batch per step.

What the batch is for: a sweep over imbalance, load or initial state, a
Monte Carlo over rotor parameters, or the candidate control settings of a
model predictive controller - many trajectories that share a force model and
a time grid.  One compiled loop advances every trajectory of the batch by one
step before the next (lockstep), so per step the force model is evaluated at
the states of the whole batch; the per-trajectory Python overhead of
``simulate`` (argument checks, array allocation, a call into numba) is paid
once per batch instead of once per trajectory.

Two loops, one arithmetic per trajectory (fixed-step RK4, the same
eccentricity-dependent substeps, the same stopping rules as ``simulate``;
unlike ``simulate``, a step whose RK stage leaves the clearance is not retried
with more substeps: it ends the trajectory as a contact):

- stage-batched (``_rk4_stages``), for models with a batched kernel
  (``core.force_model.BatchForceModel``: the reference solvers, the
  surrogates, their ensembles and hybrids, the linear bearing) and, by
  default, batches of at least ``STAGE_BATCHED_MIN_N``: the state is held per component, the
  running trajectories in a compacted index list, and every RK4 stage calls
  the batched kernel ONCE on the stage states of all trajectories stepping
  (cos/sin(omega t) once per stage time).  A trajectory above
  ``eps_substep`` takes its k substeps inside the same loop: it joins the
  stage calls of the first k substeps of the step, at its own times.  A
  stopped one (contact, divergence) leaves the list.  With the reference
  models each force is exactly the one-state kernel's, so a batch equals
  ``simulate``'s runs to the last bit; a surrogate's batched kernel equals
  its one-state kernel to round-off (float64) or within 1e-5 relative
  (float32 networks); tests/rotor/test_batch.py bounds the trajectories'
  difference.  ``threads``: contiguous chunks of the batch, one thread each
  (the loop releases the GIL), each with its own kernel parameters and
  domain counter; trajectories do not depend on the chunking.
- lockstep (``_rk4_batch``), for the other models and for per-trajectory
  ``settings``: each trajectory's step calls the one-state kernel
  (``integrate._rk4_step``), serially (the surrogates' one-state kernels
  keep scratch rows in their parameters, which threads would share).

Chunks, as ``simulate``'s: both loops run steps ``steps[0]`` to ``steps[1] - 1`` per call, the running
state carried between calls in a ``BatchRun`` (a packed (N, 5) state: position, velocity, largest |X|^2;
status, time, counters and the recorded rows, one row per trajectory in each) under a ``StepRule`` (the run's
scalars), so a run in chunks equals one call to the bit.  Between chunks ``simulate_batch`` moves the
progress bar and re-checks the step of every running trajectory (``_StepCheck``).  Each loop counts every
trajectory's force evaluations outside the model's validity domain in column 1 of ``evals`` (column 0: all
its evaluations), by the one-state kernels' rule (``integrate.outside_domain``).

Per-trajectory control settings (``settings``): a surrogate of the active
bearing reads its sleeve position from a small mutable array in its kernel
parameters; with ``settings`` (N, k) the lockstep loop writes trajectory p's
row into that array before evaluating p's forces, so candidates with
different sleeve positions run in one batch.  The reference solver rebuilds
its parameters when the sleeve moves, so it takes one setting per batch.
"""
from __future__ import annotations

import contextlib
import math
import os
import time
import warnings
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from numba import njit, typeof
from numba.core import types as nb_types

from fluidfilm.core.force_model import BatchForceModel, BatchSettable, ForceModel, TransientFilmModel, check_precision
from fluidfilm.rotor import integrate
from fluidfilm.rotor.integrate import (CONTACT, CONTACT_STAGE, NONFINITE, OK, OUTSIDE_DOMAIN, UNRESOLVED,
                                       OutsideDomainError, Trajectory, _counted, _domain_note, _holds_functions, _progress_bar, _ramped, _rk4_step,
                                       _rk4_step_uncached, _uncached, check_run_args, domain_rule,
                                       film_eigenvalues_many, outside_domain, rk4_step_limit, run_loop, step_limits,
                                       unresolved_text)
from fluidfilm.rotor.model import Rotor


@contextlib.contextmanager
def _lockstep_chunks(kernel, params, setting, settings_arr, consts, dom, rule, run):
    """``_rk4_batch`` as ``advance(steps)`` (``_stage_chunks``' contract, one thread)."""
    def advance(steps: tuple) -> None:
        run_loop(_rk4_batch, _rk4_batch_uncached, kernel, params, setting, settings_arr, consts, dom, rule, steps,
                 run)
    yield advance


@dataclass
class BatchTrajectory:
    """N trajectories on a shared time grid: t (n,), x and v (N, n, 2); ``n_recorded[p]`` rows of p are valid
    (a stopped trajectory's last valid row is its stopping state, the rest is NaN)."""

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    n_recorded: np.ndarray
    status: list
    t_stop: np.ndarray
    n_force_evals: np.ndarray
    wall_time_s: float = 0.0
    meta: dict = field(default_factory=dict)
    #: per trajectory: force evaluations outside the model's validity domain, and the largest eccentricity
    #: ratio reached after a step (the start included)
    n_outside_domain: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    eps_reached: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def __len__(self) -> int:
        return self.x.shape[0]

    @property
    def ok(self) -> np.ndarray:
        """Per trajectory: reached t_end with every force inside the model's domain (``Trajectory.ok``)."""
        return np.array([s == "ok" or s.startswith("ok;") for s in self.status], dtype=bool)

    @property
    def completed(self) -> np.ndarray:
        """Per trajectory: reached t_end, inside the model's domain or not (``Trajectory.completed``)."""
        return np.array([s == "ok" or s.startswith("ok;") or s.startswith(OUTSIDE_DOMAIN) for s in self.status],
                        dtype=bool)

    def trajectory(self, p: int) -> Trajectory:
        """Trajectory p as ``simulate`` would have returned it (its stopping time on its own time axis)."""
        n = int(self.n_recorded[p])
        t = self.t[:n].copy()
        if not self.completed[p]:
            t[-1] = self.t_stop[p]
        ts = None if math.isnan(self.t_stop[p]) else float(self.t_stop[p])
        return Trajectory(t=t, x=self.x[p, :n].copy(), v=self.v[p, :n].copy(), status=self.status[p], t_stop=ts,
                          n_force_evals=int(self.n_force_evals[p]), wall_time_s=self.wall_time_s / len(self),
                          meta=dict(self.meta),
                          n_outside_domain=int(self.n_outside_domain[p]) if self.n_outside_domain.size else 0)


class BatchRun(NamedTuple):
    """What both batch loops carry from chunk to chunk and record: one row per trajectory in every field, so
    a thread's part of the batch is a slice of each (``_run_rows``)."""

    state: np.ndarray    #: (N, 5): x1, x2, v1, v2 and the largest |X|^2 reached (the running state)
    out_x: np.ndarray    #: (N, n_out, 2): recorded positions, NaN past ``n_rec`` (``_fill_unrecorded``)
    out_v: np.ndarray    #: (N, n_out, 2): recorded velocities
    n_rec: np.ndarray    #: (N,) int64: rows recorded
    status: np.ndarray   #: (N,) int64: ``OK`` while running, then how the trajectory stopped
    t_stop: np.ndarray   #: (N,): the current time (the stopping time once stopped)
    evals: np.ndarray    #: (N, 2) int64: force evaluations, and those outside the model's domain


class StepRule(NamedTuple):
    """The run's integration rule, ``simulate``'s arguments of the same names (floats and ints)."""

    t0: float
    dt: float
    record_every: int
    eps_stop: float
    eps_substep: float
    max_substeps: int


def _run_rows(run: BatchRun, lo: int, hi: int) -> BatchRun:
    """Trajectories lo..hi-1 of the batch (views)."""
    return BatchRun(*(a[lo:hi] for a in run))


@njit(cache=True, inline="always")
def _start_row(p, run, t0):
    """Trajectory p's first recorded row and counters (both batch loops, at step 0)."""
    state = run.state
    run.out_x[p, 0, 0], run.out_x[p, 0, 1] = state[p, 0], state[p, 1]
    run.out_v[p, 0, 0], run.out_v[p, 0, 1] = state[p, 2], state[p, 3]
    run.n_rec[p] = 1
    run.status[p] = 0
    run.t_stop[p] = t0
    run.evals[p, 0] = 0
    run.evals[p, 1] = 0


@njit(cache=True, inline="always")
def _record_row(p, out_x, out_v, n_rec, x1, x2, v1, v2):
    """Trajectory p's next recorded row (the arrays of a ``BatchRun``, read once outside the loops)."""
    r = n_rec[p]
    out_x[p, r, 0], out_x[p, r, 1] = x1, x2
    out_v[p, r, 0], out_v[p, r, 1] = v1, v2
    n_rec[p] = r + 1


@njit(cache=True, nogil=True)
def _fill_unrecorded(run):
    """NaN in every row past trajectory p's ``n_rec[p]`` recorded ones.  The outputs are allocated empty and
    filled here, by the thread that ran the chunk, rather than by ``np.full`` before the run: a serial fill
    of the 16 MB of a 1024 x 500 step batch (first touch of every page) took ~6 ms, 4 % of the two-thread
    run, on the project machine."""
    out_x, out_v, n_rec = run.out_x, run.out_v, run.n_rec
    nan = np.nan
    for p in range(out_x.shape[0]):
        for r in range(n_rec[p], out_x.shape[1]):
            out_x[p, r, 0], out_x[p, r, 1] = nan, nan
            out_v[p, r, 0], out_v[p, r, 1] = nan, nan


@njit(cache=True)
def _rk4_batch(kernel, params, setting, settings, consts, dom, rule, steps, run):
    """Lockstep RK4 of N trajectories, steps ``steps[0]`` to ``steps[1] - 1`` of ``steps[2]`` (a chunk of the
    run: the running trajectories carried in ``run``; module doc of ``simulate_batch``); each one's arithmetic
    is ``integrate._rk4_run``'s."""
    step0, step1, n_steps = steps
    state, out_x, out_v, n_rec, status, t_stop, evals = run
    n_traj = state.shape[0]
    n_set = settings.shape[1]
    n_running = 0
    for p in range(n_traj):
        if step0 == 0:
            _start_row(p, run, rule.t0)
        n_running += 1 if status[p] == 0 else 0
    for step in range(step0, step1):
        if n_running == 0:
            break
        for p in range(n_traj):
            if status[p] != 0:
                continue
            for j in range(n_set):
                setting[j] = settings[p, j]
            cp = (consts[p, 0], consts[p, 1], consts[p, 2], consts[p, 3], consts[p, 4], consts[p, 5],
                  consts[p, 6], consts[p, 7], consts[p, 8])
            x1, x2, v1, v2 = state[p, 0], state[p, 1], state[p, 2], state[p, 3]
            # no retry of a step whose stage left the clearance (simulate's retry=True): it ends the trajectory
            x1, x2, v1, v2, t, n, st, n_out = _rk4_step(kernel, params, cp, x1, x2, v1, v2, t_stop[p], rule.t0, step,
                                                        rule.dt, rule.eps_substep, rule.max_substeps,
                                                        rule.eps_stop * rule.eps_stop * consts[p, 6], False, dom,
                                                        consts[p, 9])
            evals[p, 0] += n
            evals[p, 1] += n_out
            state[p, 0], state[p, 1], state[p, 2], state[p, 3] = x1, x2, v1, v2
            state[p, 4] = max(state[p, 4], x1 * x1 + x2 * x2)
            t_stop[p] = t  # the trajectory's current time (its stopping time once it stops)
            if st != 0:
                status[p] = st
                n_running -= 1
            if st != 0 or (step + 1) % rule.record_every == 0:
                _record_row(p, out_x, out_v, n_rec, x1, x2, v1, v2)
    if step1 == n_steps:
        _fill_unrecorded(run)


# kernels the on-disk cache cannot take (a user's model, an ensemble's members): an uncached twin
_rk4_batch_uncached = _uncached(_rk4_batch, _rk4_step=_rk4_step_uncached)


# --- the stage-batched loop -------------------------------------------------------------------------------
# Its state is held per component and per ENTRY of the running list (``Entries``), its scratch per substep
# (``StageWork``); both are allocated once per chunk and handed to the loop's functions whole.  The helpers
# that run over the entries in every stage (``_stage_states``, ``_film_accelerations``, ``_late_stage``,
# ``_rk4_update``) are inlined: one substep of 1024 linear-bearing entries took 4.1-4.3 ns per force so,
# 4.6-4.9 as separate functions and 4.6-5.2 before the packing (loaded 2-core machine); the per-step and
# per-chunk ones are separate functions, compiled once whatever the kernel.

class Entries(NamedTuple):
    """The stage-batched loop's running trajectories: entry j is trajectory ``run[j]`` (the arrays compacted,
    in order, when one stops); n entries each, the first ``n_run`` in use."""

    run: np.ndarray   #: (n,) int64: the trajectory of each entry
    X1: np.ndarray    #: (n,): the state, per component: positions, velocities and time
    X2: np.ndarray
    V1: np.ndarray
    V2: np.ndarray
    T: np.ndarray
    C: np.ndarray     #: (11, n): ``consts`` per column, the stopping radius^2 (eps_stop^2 c^2) and 1/c^2
    K: np.ndarray     #: (n,) int64: substeps of this step
    ST: np.ndarray    #: (n,) int64: status of this step
    NE: np.ndarray    #: (2, n) int64: force evaluations of this step, and those outside the domain


class StageWork(NamedTuple):
    """The scratch of one substep (``_substep``), n entries each."""

    act: np.ndarray   #: (n,) int64: the entries stepping in this substep (where not all: ``ident`` False)
    tq: np.ndarray    #: (n,): the stage times
    acc: tuple        #: per RK4 stage, (ax, ay, ok): accelerations and whether the state was inside the clearance
    scratch: tuple    #: (sx1, sx2, sv1, sv2): stage states copied out where one lies outside the clearance
    buf: tuple        #: (xs, vs, fs), (2 n,) each: the kernel's column-major states and forces (``_accelerations``)
    rows: np.ndarray  #: (n,) int64: each entry's row in the kernel's call, -1 outside the clearance


@njit(cache=True, nogil=True, error_model="numpy")
def _load_entries(consts, eps_stop, t0, step0, run):
    """The entries of the trajectories still running at the chunk's start (``run.status`` OK, in order), their
    first rows recorded at step 0; returns (entries, n_run)."""
    n = run.state.shape[0]
    E = Entries(np.empty(n, dtype=np.int64), np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n),
                np.empty((11, n)), np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64),
                np.zeros((2, n), dtype=np.int64))
    state, status, t_stop = run.state, run.status, run.t_stop
    ent, X1, X2, V1, V2, T, C = E.run, E.X1, E.X2, E.V1, E.V2, E.T, E.C
    n_run = 0
    for p in range(n):
        if step0 == 0:
            _start_row(p, run, t0)
        if status[p] != OK:
            continue
        j = n_run
        X1[j], X2[j], V1[j], V2[j], T[j] = state[p, 0], state[p, 1], state[p, 2], state[p, 3], t_stop[p]
        ent[j] = p
        for k in range(9):
            C[k, j] = consts[p, k]
        C[9, j] = eps_stop * eps_stop * consts[p, 6]
        C[10, j] = consts[p, 9]
        n_run += 1
    return E, n_run


@njit(cache=True, nogil=True)
def _stage_work(n):
    """A ``StageWork`` for n entries (allocated once per chunk)."""
    acc = ((np.empty(n), np.empty(n), np.empty(n, dtype=np.bool_)),
           (np.empty(n), np.empty(n), np.empty(n, dtype=np.bool_)),
           (np.empty(n), np.empty(n), np.empty(n, dtype=np.bool_)),
           (np.empty(n), np.empty(n), np.empty(n, dtype=np.bool_)))
    return StageWork(np.empty(n, dtype=np.int64), np.empty(n), acc,
                     (np.empty(n), np.empty(n), np.empty(n), np.empty(n)),
                     (np.empty(2 * n), np.empty(2 * n), np.empty(2 * n)), np.empty(n, dtype=np.int64))


@njit(cache=True, nogil=True, error_model="numpy")
def _substep_counts(E, n_run, es2, max_substeps):
    """Each entry's substeps of this step (``integrate._rk4_step``'s rule), its status and counts reset;
    returns the largest."""
    X1, X2, C, K, ST, NE = E.X1, E.X2, E.C, E.K, E.ST, E.NE
    far = 0
    for j in range(n_run):
        far += 1 if (X1[j] * X1[j] + X2[j] * X2[j]) / C[6, j] > es2 else 0
        K[j] = 1
        ST[j] = OK
        NE[0, j] = 0
        NE[1, j] = 0
    kmax = 1
    if far > 0:
        for j in range(n_run):
            e2 = (X1[j] * X1[j] + X2[j] * X2[j]) / C[6, j]
            if e2 > es2:
                k = int(math.ceil(((1.0 - es2) / (1.0 - e2)) ** 1.5))
                if k > max_substeps:
                    k = max_substeps
                K[j] = k
                if k > kmax:
                    kmax = k
    return kmax


@njit(cache=True, nogil=True, error_model="numpy")
def _stepping(E, act, n_run, sub):
    """The entries that take part in substep ``sub`` (substeps left, not stopped) into ``act``; returns how many."""
    K, ST = E.K, E.ST
    m = 0
    for j in range(n_run):
        if K[j] > sub and ST[j] == OK:
            act[m] = j
            m += 1
    return m


@njit(cache=True, nogil=True, error_model="numpy")
def _end_step(E, n_run, step, record_every, run):
    """After a step: each entry's counts, time and largest |X|^2 into ``run``, its row recorded where it
    stopped or the step is a recorded one, and the running entries compacted (in order); returns their
    number."""
    ent, X1, X2, V1, V2, T, C, ST, NE = E.run, E.X1, E.X2, E.V1, E.V2, E.T, E.C, E.ST, E.NE
    state, out_x, out_v, n_rec, status, t_stop, evals = run
    keep = 0
    for j in range(n_run):
        p = ent[j]
        evals[p, 0] += NE[0, j]
        evals[p, 1] += NE[1, j]
        t_stop[p] = T[j]  # the trajectory's current time (its stopping time once it stops)
        state[p, 4] = max(state[p, 4], X1[j] * X1[j] + X2[j] * X2[j])
        st = ST[j]
        if st != 0:
            status[p] = st
        if st != 0 or (step + 1) % record_every == 0:
            _record_row(p, out_x, out_v, n_rec, X1[j], X2[j], V1[j], V2[j])
        if st == 0:
            if keep != j:
                ent[keep] = p
                X1[keep], X2[keep], V1[keep], V2[keep], T[keep] = X1[j], X2[j], V1[j], V2[j], T[j]
                for k in range(11):
                    C[k, keep] = C[k, j]
            keep += 1
    return keep


@njit(cache=True, inline="always", error_model="numpy")
def _stage_states(E, W, m, ident, q):
    """How many of the stage states q (qx1, qx2, qv1, qv2) lie inside the clearance, all of them copied out to
    the scratch rows ``W.scratch`` where some do not (``_accelerations`` gathers those inside back); returns
    (xs, vs, fs, inside): the kernel's (inside, 2) column-major views of the buffers ``W.buf``, and that
    count."""
    qx1, qx2, qv1, qv2 = q
    sx1, sx2, sv1, sv2 = W.scratch
    xsb, vsb, fsb = W.buf
    C, act = E.C, W.act
    inside = 0
    for i in range(m):
        j = i if ident else act[i]
        inside += 1 if qx1[i] * qx1[i] + qx2[i] * qx2[i] < C[6, j] else 0
    if inside < m:
        for i in range(m):
            sx1[i], sx2[i], sv1[i], sv2[i] = qx1[i], qx2[i], qv1[i], qv2[i]
    # the kernel's (inside, 2) states and forces as column-major views of flat buffers (component k of entry
    # r at k * inside + r): its per-state loops then read and write each component contiguously, which a
    # surrogate's frame pass needs to run as a vector loop (interleaved rows: 10 ns per state, against 2.5)
    xs = xsb[:2 * inside].reshape((2, inside)).T
    vs = vsb[:2 * inside].reshape((2, inside)).T
    fs = fsb[:2 * inside].reshape((2, inside)).T
    return xs, vs, fs, inside


@njit(cache=True, nogil=True, error_model="numpy")
def _accelerations(fn, bp, dom, E, W, m, ident, q, acc):
    """One RK4 stage of the m entries ``W.act[:m]`` (``ident``: entries 0..m-1) at the stage states q (qx1,
    qx2, qv1, qv2) and times ``W.tq``: the film forces in ONE call ``fn(bp, xs, vs, fs)`` of the states
    inside the clearance (column-major (r, 2) views of the flat buffers ``W.buf``), then
    ``_acceleration``'s arithmetic per entry into ``acc`` (ax, ay, ok; ``_film_accelerations``).
    ``E.C[k, j]``: entry j's constants (``simulate_batch``'s ``consts`` per column).

    The stage states are views of the kernel's buffers (``_substep``: qx1 = xs[:m], qx2 = xs[m:2m], qv1,
    qv2 likewise in vs), so when every state lies inside the clearance (the rule) the kernel reads them where
    the stage wrote them: no copy (copying them cost ~1.2 ns per force, a scalar loop). Otherwise they are
    copied out to the scratch rows ``W.scratch`` and the states inside gathered back, in order.

    With an active domain table ``dom`` (``integrate.domain_rule``), each entry's evaluations outside the
    model's domain are counted in ``E.NE[1, j]`` (``integrate.outside_domain``, the states inside the
    clearance: those whose forces are evaluated)."""
    qx1, qx2, qv1, qv2 = q
    C, NE, act, rows, ok = E.C, E.NE, W.act, W.rows, acc[2]
    if dom[0, 1] < math.inf:
        for i in range(m):
            j = i if ident else act[i]
            evaluated = 1 if qx1[i] * qx1[i] + qx2[i] * qx2[i] < C[6, j] else 0
            NE[1, j] += evaluated * outside_domain(dom, C[10, j], qx1[i], qx2[i], qv1[i], qv2[i])
    xs, vs, fs, inside = _stage_states(E, W, m, ident, q)
    r = 0
    if inside == m:
        # every state inside the clearance: already in place
        for i in range(m):
            ok[i] = True
            rows[i] = i
        r = m
    else:
        sx1, sx2, sv1, sv2 = W.scratch
        for i in range(m):
            j = i if ident else act[i]
            x1, x2 = sx1[i], sx2[i]
            if x1 * x1 + x2 * x2 >= C[6, j]:
                ok[i] = False  # outside the clearance: no force, acceleration 0, the step fails (as _acceleration)
                rows[i] = -1
                continue
            ok[i] = True
            xs[r, 0], xs[r, 1], vs[r, 0], vs[r, 1] = x1, x2, sv1[i], sv2[i]
            rows[i] = r
            r += 1
    if r > 0:
        fn(bp, xs, vs, fs)
    _film_accelerations(E.C, W, m, ident, inside == m, fs, acc)


@njit(cache=True, inline="always", error_model="numpy")
def _film_accelerations(C, W, m, ident, all_inside, fs, acc):
    """``_acceleration``'s arithmetic per entry (the same expressions, so the same bits for the same forces):
    the film forces ``fs[W.rows[i]]`` with the imbalance (ramped), the static load and gravity, times 1/m, into
    ``acc`` (ax, ay); 0 for an entry outside the clearance.  cos/sin(omega t) are computed once per distinct
    phase: every entry without substeps shares its time."""
    ax, ay = acc[0], acc[1]
    tq, rows, act = W.tq, W.rows, W.act
    if ident and all_inside:
        # the common stage: every entry inside, one phase for all, no ramp (checked): without branches
        t = tq[0]
        ph = C[2, 0] * t
        same = 0
        for i in range(m):
            same += 1 if (C[2, i] * tq[i] == ph) & (C[8, i] <= 0.0) else 0
        if same == m:
            cph = math.cos(ph)
            sph = math.sin(ph)
            for i in range(m):
                unb = C[1, i]
                ax[i] = (fs[i, 0] + unb * cph + C[4, i]) * C[0, i]
                ay[i] = (fs[i, 1] + C[3, i] * unb * sph + C[5, i]) * C[0, i]
            return
    last_ph = math.nan
    cph = 0.0
    sph = 0.0
    for i in range(m):
        if rows[i] < 0:
            ax[i] = 0.0
            ay[i] = 0.0
            continue
        j = i if ident else act[i]
        f1, f2 = fs[rows[i], 0], fs[rows[i], 1]
        inv_m, unb, omega, sgn, g1, g2 = C[0, j], C[1, j], C[2, j], C[3, j], C[4, j], C[5, j]
        t = tq[i]
        if C[8, j] > 0.0:
            unb = _ramped(unb, C[7, j], t, C[8, j])
        ph = omega * t
        if ph != last_ph:
            cph = math.cos(ph)
            sph = math.sin(ph)
            last_ph = ph
        ax[i] = (f1 + unb * cph + g1) * inv_m
        ay[i] = (f2 + sgn * unb * sph + g2) * inv_m


@njit(cache=True, inline="always", error_model="numpy")
def _late_stage(f, P, Q, E, W, m, ident, dt, q):
    """Stage states 3 (f = 0.5: P = a, Q = b) and 4 (f = 1: P = b, Q = c) of RK4 into q: position
    X + f h (V + h/2 P), velocity V + f h Q, time T + f h (``W.tq``); ``_rk4_step``'s expressions (f h = h
    exactly for f = 1).  P, Q: stages' (ax, ay, ok)."""
    p1, p2, q1, q2 = P[0], P[1], Q[0], Q[1]
    qx1, qx2, qv1, qv2 = q
    X1, X2, V1, V2, T, K, act, tq = E.X1, E.X2, E.V1, E.V2, E.T, E.K, W.act, W.tq
    for i in range(m):
        j = i if ident else act[i]
        h = dt / K[j]
        u1 = V1[j] + 0.5 * h * p1[i]
        u2 = V2[j] + 0.5 * h * p2[i]
        qx1[i], qx2[i] = X1[j] + f * h * u1, X2[j] + f * h * u2
        qv1[i], qv2[i], tq[i] = V1[j] + f * h * q1[i], V2[j] + f * h * q2[i], T[j] + f * h


@njit(cache=True, nogil=True, error_model="numpy")
def _substep(fn, bp, dom, E, W, m, ident, sub, step, rule):
    """Substep ``sub`` of the entries ``W.act[:m]`` (``ident``: every entry, none substepping): four stages and
    the update, ``_rk4_step``'s arithmetic per entry.  The stage states are written into the kernel's flat
    buffers ``W.buf`` (``_accelerations``)."""
    X1, X2, V1, V2, T, K, act, tq = E.X1, E.X2, E.V1, E.V2, E.T, E.K, W.act, W.tq
    dt = rule.dt
    xs, vs = W.buf[0], W.buf[1]
    q = (xs[:m], xs[m:2 * m], vs[:m], vs[m:2 * m])
    qx1, qx2, qv1, qv2 = q
    A, B, Cs, D = W.acc
    # stage 1: the state itself
    for i in range(m):
        j = i if ident else act[i]
        qx1[i], qx2[i], qv1[i], qv2[i], tq[i] = X1[j], X2[j], V1[j], V2[j], T[j]
    _accelerations(fn, bp, dom, E, W, m, ident, q, A)
    a1, a2 = A[0], A[1]
    for i in range(m):
        j = i if ident else act[i]
        h = dt / K[j]
        qx1[i], qx2[i] = X1[j] + 0.5 * h * V1[j], X2[j] + 0.5 * h * V2[j]
        qv1[i], qv2[i], tq[i] = V1[j] + 0.5 * h * a1[i], V2[j] + 0.5 * h * a2[i], T[j] + 0.5 * h
    _accelerations(fn, bp, dom, E, W, m, ident, q, B)
    _late_stage(0.5, A, B, E, W, m, ident, dt, q)
    _accelerations(fn, bp, dom, E, W, m, ident, q, Cs)
    _late_stage(1.0, B, Cs, E, W, m, ident, dt, q)
    _accelerations(fn, bp, dom, E, W, m, ident, q, D)
    _rk4_update(E, W, m, ident, sub, step, rule)


@njit(cache=True, inline="always", error_model="numpy")
def _rk4_update(E, W, m, ident, sub, step, rule):
    """The RK4 update of substep ``sub`` from the four stages' accelerations ``W.acc``, per entry: the new
    state, or the old one and the status where a stage left the clearance (contact) or the state is not
    finite (divergence); a contact at eps_stop (``E.C[9]``)."""
    X1, X2, V1, V2, T, K, ST, NE, C, act = E.X1, E.X2, E.V1, E.V2, E.T, E.K, E.ST, E.NE, E.C, W.act
    (a1, a2, ok1), (b1, b2, ok2), (c1, c2, ok3), (d1, d2, ok4) = W.acc
    t0, dt = rule.t0, rule.dt
    for i in range(m):
        j = i if ident else act[i]
        k = K[j]
        h = dt / k
        x1, x2, v1, v2 = X1[j], X2[j], V1[j], V2[j]
        NE[0, j] += 4
        kx1 = v1 + 0.5 * h * a1[i]
        kx2 = v2 + 0.5 * h * a2[i]
        lx1 = v1 + 0.5 * h * b1[i]
        lx2 = v2 + 0.5 * h * b2[i]
        mx1 = v1 + h * c1[i]
        mx2 = v2 + h * c2[i]
        nx1 = x1 + h / 6.0 * (v1 + 2.0 * kx1 + 2.0 * lx1 + mx1)
        nx2 = x2 + h / 6.0 * (v2 + 2.0 * kx2 + 2.0 * lx2 + mx2)
        nv1 = v1 + h / 6.0 * (a1[i] + 2.0 * b1[i] + 2.0 * c1[i] + d1[i])
        nv2 = v2 + h / 6.0 * (a2[i] + 2.0 * b2[i] + 2.0 * c2[i] + d2[i])
        # as selects (the loop vectorises): a failed stage ends the step as a contact, a non-finite state as a
        # divergence, both leaving the state as it was; else the new state, a contact at eps_stop
        good = ok1[i] & ok2[i] & ok3[i] & ok4[i]
        fin = (abs(nx1) < math.inf) & (abs(nx2) < math.inf) & (abs(nv1) < math.inf) & (abs(nv2) < math.inf)
        upd = good & fin
        ST[j] = CONTACT_STAGE if not good else (NONFINITE if not fin else
                                                (CONTACT if nx1 * nx1 + nx2 * nx2 >= C[9, j] else ST[j]))
        X1[j] = nx1 if upd else x1
        X2[j] = nx2 if upd else x2
        V1[j] = nv1 if upd else v1
        V2[j] = nv2 if upd else v2
        T[j] = t0 + (step + (sub + 1.0) / k) * dt if upd else T[j]


@njit(cache=True, nogil=True, error_model="numpy")
def _rk4_stages(fn, bp, consts, dom, rule, steps, run):
    """RK4 of N trajectories with the force model evaluated once per stage for all running ones: steps
    ``steps[0]`` to ``steps[1] - 1`` of ``steps[2]`` (a chunk, as ``_rk4_batch``).

    Per trajectory, the arithmetic of ``_rk4_batch`` (``integrate._rk4_step`` without the retry): the same
    substep counts, stage states, stopping rules and recorded rows.  The state is held per component
    (X1, X2, V1, V2, T) and per ENTRY of the running list (``Entries``: entry j is trajectory ``run[j]``;
    the arrays are compacted, in order, when a trajectory stops), the constants per column ``C[k, j]``.  A
    step in which no entry substeps runs every loop over the entries 0..m-1 (contiguous); otherwise per
    substep the entries still stepping (a trajectory with k substeps takes part in the first k; one that
    stopped in this step drops out) are a second list ``act``.  Every stage gathers its entries' states
    inside the clearance and calls ``fn`` once on them.  A chunk starts from the state carried in ``run``
    (``BatchRun``: rows x1, x2, v1, v2 and the largest |X|^2 so far, the current time ``t_stop`` and the
    running trajectories ``status``, in order: the list a single call would hold at that step), and leaves
    it there."""
    step0, step1, n_steps = steps
    E, n_run = _load_entries(consts, rule.eps_stop, rule.t0, step0, run)
    W = _stage_work(run.state.shape[0])
    es2 = rule.eps_substep * rule.eps_substep
    for step in range(step0, step1):
        if n_run == 0:
            break
        kmax = _substep_counts(E, n_run, es2, rule.max_substeps)
        if kmax == 1:
            _substep(fn, bp, dom, E, W, n_run, True, 0, step, rule)
        else:
            for sub in range(kmax):
                m = _stepping(E, W.act, n_run, sub)
                if m == 0:
                    break
                _substep(fn, bp, dom, E, W, m, False, sub, step, rule)
        n_run = _end_step(E, n_run, step, rule.record_every, run)
    state, ent, X1, X2, V1, V2 = run.state, E.run, E.X1, E.X2, E.V1, E.V2
    for j in range(n_run):  # the running trajectories' states, for the next chunk
        p = ent[j]
        state[p, 0], state[p, 1], state[p, 2], state[p, 3] = X1[j], X2[j], V1[j], V2[j]
    if step1 == n_steps:
        _fill_unrecorded(run)


_rk4_stages_uncached = _uncached(_rk4_stages, _substep=_uncached(_substep, _accelerations=_uncached(_accelerations)))


#: the smallest batch ``simulate_batch`` runs stage-batched by default: the best-shaped surrogate's batched
#: kernel took 1.8 us per call for 1 state, 0.45 us per state for 16, 0.21 for 64 and 0.15 for 1024 on the
#: loaded project machine, its one-state kernel inside the lockstep loop 0.17 us per force
STAGE_BATCHED_MIN_N = 128


def _thread_count(threads, n: int) -> int:
    """Threads for a batch of n: ``threads`` (a positive integer) or, for None, the cores this process may use;
    at most n."""
    if threads is None:
        threads = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    elif isinstance(threads, (bool, np.bool_)) or not isinstance(threads, (int, np.integer)) or threads < 1:
        raise ValueError(f"threads must be a positive integer or None (all cores), got {threads!r}")
    return max(1, min(int(threads), n))


#: the (inside, 2) state and force views ``_accelerations`` hands the batched kernel (column-major, float64)
_STAGE_VIEW = nb_types.Array(nb_types.float64, 2, "F")


def _first_class_kernel(fn, bp) -> bool:
    """Whether ``_stages_loop`` may type ``fn`` by its signature and cache the loop: a compiled function of
    the library (its module ``fluidfilm...`` or ``fluidfilm_generated``) with library-typed parameters."""
    from numba.core.registry import CPUDispatcher

    module = getattr(getattr(fn, "py_func", None), "__module__", "") or ""
    return isinstance(fn, CPUDispatcher) and module.split(".")[0] in ("fluidfilm", "fluidfilm_generated") and \
        type(bp).__module__.split(".")[0] in ("fluidfilm", "builtins") and not _holds_functions(bp)


@contextlib.contextmanager
def _first_class_compile():
    """Silence exactly numba's "First-class function type feature is experimental" warning while the
    stage-batched loop compiles: the loop takes the force kernel as a first-class function by design (see
    ``_stages_loop``), numba prints that warning at every such compilation, and it would land in a user's
    run as noise about our code, not theirs (``tests/rotor/test_batch.py`` holds the loop's trajectories equal to
    ``simulate``'s).  Any other warning still shows."""
    from numba.core.errors import NumbaExperimentalFeatureWarning

    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*First-class function type feature is experimental",
                                category=NumbaExperimentalFeatureWarning)
        yield


def _stages_loop(fn, bp, loop_args):
    """``_rk4_stages`` compiled for this kernel, as a callable ``loop(fn, bp, *loop_args)``.

    Why: numba types a compiled function passed as an argument by the function object itself (its type's
    equality is identity), so the on-disk cache never matched in a new process and every process compiled
    the loop afresh, ~20 s per kernel (the stage-batched reference, each surrogate precision).  Typed instead
    as a first-class function of its signature (``FunctionType``: equal across processes), the loop is
    compiled once per kernel signature and then loaded from the cache in ~0.3 s.  The kernel is called
    through a function pointer once per RK4 stage for the whole batch (side by side: 0.051 against 0.050 s
    per 1,024 best-shaped trajectories of 5 ms, one thread).
    The kernel may be any compiled function of the library, generated ones included (a surrogate's
    ``fluidfilm_generated`` kernel for its shape: every shape with the same parameter types shares the one
    compiled loop, since the kernel is now a value, not part of the loop's type); parameters must be the
    library's types without compiled functions inside (``integrate._holds_functions``: an ensemble's), else
    the uncached twin runs, as it does for kernels from outside the library."""
    def dispatcher_typed(kernel, params, *rest):  # the loop as ``run_loop`` runs it (cached or uncached twin)
        with _first_class_compile():
            return run_loop(_rk4_stages, _rk4_stages_uncached, kernel, params, *rest)

    if not _first_class_kernel(fn, bp):
        return dispatcher_typed
    kernel_args = (typeof(bp), _STAGE_VIEW, _STAGE_VIEW, _STAGE_VIEW)
    fn.compile(kernel_args)
    signature = fn.overloads[kernel_args].signature
    loop_types = (nb_types.FunctionType(signature.return_type(*kernel_args)), kernel_args[0]) + \
        tuple(typeof(a) for a in loop_args)
    try:
        with _first_class_compile():
            _rk4_stages.compile(loop_types)
    except ReferenceError as err:  # the cache index held a key it cannot rebuild (``run_loop``)
        if loop_types not in _rk4_stages.overloads:
            warnings.warn(f"numba could not use its on-disk cache of the stage-batched loop ({err}); this process "
                          "compiles the loop without the cache (same arithmetic)", RuntimeWarning, stacklevel=3)
            return dispatcher_typed
    entry = _rk4_stages.overloads[loop_types].entry_point
    kernel_type = kernel_args[0]

    def loop(kernel, params, *rest):
        # the compiled entry skips the dispatcher's type checks: every chunk must bring this kernel's types
        if kernel is not fn or typeof(params) != kernel_type:
            return dispatcher_typed(kernel, params, *rest)
        return entry(kernel, params, *rest)

    return loop


@contextlib.contextmanager
def _stage_chunks(model, precision, n_threads, consts, dom, rule, run):
    """``_rk4_stages`` over ``n_threads`` contiguous chunks of the batch, as ``advance(steps)`` (one chunk of
    steps, ``(step0, step1, n_steps)``): each chunk of trajectories in its own thread with its own private
    batched-kernel parameters (their own counters: nothing mutable is shared), the counts merged into the
    model's at the end.  Each chunk takes its rows of ``consts`` and ``run``; the domain table ``dom`` and the
    ``rule`` are the whole batch's."""
    n = consts.shape[0]
    edges = np.linspace(0, n, n_threads + 1).round().astype(int)
    kernels = []
    for _ in range(n_threads):
        kernel = model.batch_force_kernel(precision, private=True)
        assert kernel is not None  # checked by the caller
        kernels.append(kernel)

    def chunk_args(c: int, steps: tuple) -> tuple:
        lo, hi = int(edges[c]), int(edges[c + 1])
        return consts[lo:hi], dom, rule, steps, _run_rows(run, lo, hi)

    # compiled (or loaded from the cache) here, before any thread starts; every chunk has the same types
    loop = _stages_loop(kernels[0][0], kernels[0][1], chunk_args(0, (0, 0, 0)))
    # the compiled loop releases the GIL (nogil): the chunks run in parallel
    pool = ThreadPoolExecutor(max_workers=n_threads) if n_threads > 1 else None

    def advance(steps: tuple) -> None:
        def chunk(c: int) -> None:
            fn, bp = kernels[c]
            loop(fn, bp, *chunk_args(c, steps))
        if pool is None:
            chunk(0)
        else:
            list(pool.map(chunk, range(n_threads)))

    try:
        yield advance
    finally:
        if pool is not None:
            pool.shutdown()
        for _, bp in kernels:
            model.merge_counts(bp)


class _StepCheck:
    """``simulate``'s step check for a batch (``rk4_step_limit`` per trajectory), at the start and at the end of
    every chunk of steps.  The eigenvalues of all trajectories come from one call of the model's batched
    kernel (the run's ``precision``, already loaded; private parameters: nothing counted) or of its ``forces``, and only the trajectories whose
    step is within a factor 2 of the limit so found (and the one with the smallest) get the one-state check
    whose verdict and words are ``simulate``'s.  Per-trajectory settings: the one-state check for each."""

    def __init__(self, model, force: tuple, setting, settings_arr, consts, c, rule: StepRule, omega: float,
                 per_setting: bool, precision: str):
        """``force``: the model's one-state ``(kernel, params)``; ``rule``: the run's (its dt, eps_substep and
        max_substeps); ``omega``: the shaft speed of the limit's per-period rule."""
        self.model, (self.kernel, self.params), self.setting = model, force, setting
        self.settings_arr, self.consts, self.c, self.dt = settings_arr, consts, c, rule.dt
        self.rule = (omega, rule.eps_substep, rule.max_substeps)
        self.batched = None
        if not per_setting and isinstance(model, BatchForceModel):
            self.batched = model.batch_force_kernel(precision, private=True)
        self.per_setting = per_setting
        self.check_outside = 0  # evaluations of the checks the model's own counter took (subtracted)

    def _forces(self, xs, vs):
        if self.batched is not None:
            fn, bp = self.batched
            fs = np.empty((xs.shape[0], 2), order="F")  # the kernel's compiled layout (``_STAGE_VIEW``)
            fn(bp, np.asfortranarray(xs), np.asfortranarray(vs), fs)
            return fs
        return np.asarray(self.model.forces(xs, vs), dtype=float)

    def one(self, p: int, x, v):
        """The one-state limit of trajectory p at (x, v), the model's counters kept."""
        if self.setting.size:
            self.setting[:] = self.settings_arr[p]
        kernel, params = self.kernel, self.params

        def force(x1, x2, v1, v2):
            return kernel(params, x1, x2, v1, v2)
        omega, eps_substep, max_substeps = self.rule
        lim, extra = _counted(self.model, lambda: rk4_step_limit(force, x, v, self.consts[p, 0], float(self.c[p]),
                                                                  omega, eps_substep, max_substeps), params)
        self.check_outside += extra
        return lim

    def limits(self, idx: np.ndarray, X: np.ndarray, V: np.ndarray) -> dict:
        """{p: StepLimit} for the trajectories ``idx`` (states X, V) that may not be resolved, and the one with
        the smallest limit; the model's setting restored."""
        saved = self.setting.copy()
        try:
            if self.per_setting:
                cand = list(range(idx.size))
            else:
                omega, eps_substep, max_substeps = self.rule
                lam, extra = _counted(self.model, lambda: film_eigenvalues_many(
                    self._forces, X, V, self.consts[idx, 0], self.c[idx], omega), self.params)
                self.check_outside += extra
                e2 = (X[:, 0] ** 2 + X[:, 1] ** 2) / self.c[idx] ** 2
                dt_max = step_limits(lam, e2, omega, eps_substep, max_substeps)[1].min(axis=1)
                cand = sorted(set(np.flatnonzero(self.dt > 0.5 * dt_max).tolist()) | {int(np.argmin(dt_max))})
            return {int(idx[i]): self.one(int(idx[i]), X[i], V[i]) for i in cand}
        finally:
            self.setting[:] = saved

    def start(self, x0, v0) -> None:
        """A ValueError naming dt, the trajectory with the smallest limit and that limit, where dt exceeds it."""
        lims = self.limits(np.arange(x0.shape[0]), x0, v0)
        p = min(lims, key=lambda q: lims[q].dt_max)
        lim = lims[p]
        if self.dt > lim.dt_max * (1.0 + 1e-9):
            raise ValueError(f"dt={self.dt!r} s cannot resolve this batch: the largest safe step is {lim.dt_max:.3g} s "
                             f"(trajectory {p} at its start, eccentricity {np.hypot(*x0[p]) / self.c[p]:.3g}; rule: "
                             f"{lim.rule}). Use dt <= {lim.dt_max:.3g} or check_step=False (experts)")

    def along(self, run: BatchRun, s1: int, record_every: int) -> dict:
        """The check at the end of a chunk (step ``s1``): each running trajectory that the step no longer
        resolves ends "unresolved" (status ``UNRESOLVED``, its state recorded); returns {p: StepLimit} of those."""
        state, status = run.state, run.status
        idx = np.flatnonzero(status == OK)
        if idx.size == 0:
            return {}
        lims = self.limits(idx, state[idx, :2].copy(), state[idx, 2:4].copy())
        bad = {p: lim for p, lim in lims.items() if self.dt > lim.dt_max * (1.0 + 1e-9)}
        for p in bad:
            status[p] = UNRESOLVED
            if s1 % record_every:  # the state at the check is not a recorded row yet
                _record_row(p, run.out_x, run.out_v, run.n_rec, state[p, 0], state[p, 1], state[p, 2], state[p, 3])
        return bad


def _domain_texts(model, texts: list, evals, eps_reached, strict: bool) -> list:
    """The batch's statuses with each trajectory's evaluations outside the model's domain (``evals[:, 1]``):
    "outside-domain: ..." for a finished one, a note after the others', one warning naming the share, or
    ``OutsideDomainError`` with ``strict`` (``simulate_batch``'s Returns)."""
    if hasattr(model, "check_grid"):  # a reference solver warns once where its grid is too coarse for the run
        model.check_grid(float(eps_reached.max()))
    n_out = evals[:, 1]
    out = list(texts)
    if n_out.sum() > 0:
        hit = np.flatnonzero(n_out > 0)
        total, n_evals = int(n_out.sum()), int(evals[:, 0].sum())
        summary = (f"{hit.size} of {len(texts)} trajectories outside the training domain, in {total} force "
                   f"evaluations ({100.0 * total / max(n_evals, 1):.3g} % of {n_evals}); largest eccentricity "
                   f"{eps_reached[hit].max():.4g} (domain eps <= {model.validity.eps_max:g})")
        if strict:
            raise OutsideDomainError(f"{model.name}: {summary} during the batch (strict=True)")
        warnings.warn(f"{model.name}: {summary} during the batch", RuntimeWarning, stacklevel=3)
        for p in hit:
            note = _domain_note(model, int(n_out[p]), int(evals[p, 0]), float(eps_reached[p]) ** 2, 1.0)
            out[p] = f"{OUTSIDE_DOMAIN}: reached the end time; {note}" if out[p] == "ok" else f"{out[p]}; {note}"
        return out
    # a model whose count its validity domain does not describe, or that reports without counting: the note
    # is the whole batch's, and no finished trajectory can be vouched for where it counted
    note = model.domain_report()
    if not note:
        return out
    counted = int(model.n_outside_domain) > 0
    if strict and counted:
        raise OutsideDomainError(f"{model.name}: {note} during the batch (strict=True)")
    warnings.warn(f"{model.name}: {note} during the batch", RuntimeWarning, stacklevel=3)
    return [f"{OUTSIDE_DOMAIN}: reached the end time; {note} (whole batch)" if s == "ok" and counted else
            f"{s}; {note} (whole batch)" for s in out]


def _rotor_constants(rotors: list, omega: float, c: np.ndarray, inv_c2) -> np.ndarray:
    """``consts`` (N, 10) of the loops, a row per rotor: 1/m, the imbalance force m_u d omega^2, omega, the
    imbalance direction, the static load (gravity in column 5), c^2, the final imbalance force and the ramp
    time of a ramped imbalance (0: none), and 1/c^2 as the kernels hold it (``inv_c2``)."""
    # column by column (a row per trajectory: building rows of Python floats cost ~0.9 ms per 1024 rotors,
    # ~1 % of a surrogate batch's run); the same IEEE operations as one rotor's
    mass, imb, imb_final, direction, ext, gravity, ramp = (np.array(col, dtype=float) for col in zip(*[
        (r.mass, r.imbalance, np.nan if r.imbalance_final is None else r.imbalance_final, r.imbalance_direction,
         r.external_force, r.gravity, r.ramp_time) for r in rotors]))
    ramped = ~np.isnan(imb_final)
    consts = np.empty((len(rotors), 10))
    consts[:, 0] = 1.0 / mass
    consts[:, 1] = imb * omega**2
    consts[:, 2] = omega
    consts[:, 3] = direction
    consts[:, 4] = ext[:, 0]
    consts[:, 5] = ext[:, 1] + mass * gravity
    consts[:, 6] = c**2
    consts[:, 7] = np.where(ramped, imb_final, imb) * omega**2
    consts[:, 8] = np.where(ramped, ramp, 0.0)
    consts[:, 9] = inv_c2
    return consts


def _stop_texts(run: BatchRun, c: np.ndarray, eps_stop: float, dt: float, unresolved: dict) -> tuple[list, np.ndarray]:
    """Each trajectory's status text before the domain count ("ok", contact, unresolved, diverged: as
    ``simulate``'s) and its stopping time (NaN where it reached the end)."""
    status, t_stop, state = run.status, run.t_stop, run.state
    texts = ["ok"] * len(status)
    t_stop_out = np.full(len(status), np.nan)
    for p in np.flatnonzero(status != OK):
        t_stop_out[p] = t_stop[p]
        if status[p] in (CONTACT, CONTACT_STAGE):
            texts[p] = f"contact: eccentricity reached eps_stop={eps_stop} at t={t_stop[p]:.6g} s"
        elif status[p] == UNRESOLVED:
            texts[p] = unresolved_text(t_stop[p], np.hypot(*state[p, :2]) / c[p], dt, unresolved[p],
                                       "simulate(..., dt=None) (adaptive)")
        else:
            texts[p] = f"diverged: non-finite state after t={t_stop[p]:.6g} s"
    return texts, t_stop_out


def _rows(value, n: int, what: str) -> np.ndarray:
    a = np.zeros((n, 2)) if value is None else np.asarray(value, dtype=float)
    if a.ndim == 1:
        a = np.broadcast_to(a.reshape(1, 2), (n, 2))
    if a.shape != (n, 2):
        raise ValueError(f"{what} must be (2,) or ({n}, 2), got shape {a.shape}")
    if not np.isfinite(a).all():
        raise ValueError(f"{what} must be finite")
    return np.ascontiguousarray(a, dtype=float)


def simulate_batch(model, rotors, t_end: float, dt: float = 1e-5, x0=None, v0=None, *, settings=None,
                   eps_stop: float = 0.98, record_every: int = 1, eps_substep: float = 0.8,
                   max_substeps: int = 256, t0: float = 0.0, threads: int | None = None,
                   precision: str = "float32", stage_batched: bool | None = None, check_step: bool = True,
                   strict: bool = False, progress: bool | None = None) -> BatchTrajectory:
    """Integrate N rotors (a ``Rotor`` or a sequence of N) in ``model`` from x0, v0 ((2,) or (N, 2)).

    Parameters
    ----------
    model : ForceModel
        The force model.  Where it is a ``BatchForceModel`` (the reference solvers, the surrogates, the
        linear bearing) and ``settings`` is None, its batched kernel is called once per RK4 stage for all
        running trajectories (module doc); otherwise each trajectory's step calls the one-state kernel.
    rotors : Rotor or sequence of Rotor
        One rotor for all trajectories, or one per trajectory.
    t_end, dt, x0, v0, eps_stop, record_every, eps_substep, max_substeps, t0
        As ``simulate`` and checked by the same function: ``t_end`` is the END TIME [s] of the run
        (absolute), which goes from ``t0`` to ``t_end``; x0, v0 (2,) or (N, 2).
    settings : array_like, shape (N, k), optional
        Per-trajectory values of the model's control setting (for a surrogate of the active bearing,
        ``model.setting_for(sleeve)`` rows); the model's own setting is restored afterwards.  Runs the
        per-trajectory loop, in one thread.
    threads : int or None, default None
        Threads across the batch (stage-batched path): each runs a contiguous chunk of the trajectories
        with its own domain counter; None: every core this process may use.  The trajectories do not
        depend on it.
    precision : {"float32", "float64"}, default "float32"
        Arithmetic of a surrogate's networks in the stage-batched path (its batched kernel: float32 keeps
        the forces within 1e-5 relative of float64 and costs about half as much; tests/rotor/test_batch.py bounds
        the trajectories' difference); a reference model computes in float64 either way.
    stage_batched : bool or None, default None
        True: the stage-batched loop wherever the model has a batched kernel; False: the per-trajectory
        lockstep loop (one-state kernel); None: stage-batched for batches of at least
        ``STAGE_BATCHED_MIN_N`` trajectories (a surrogate's batched kernel costs ~2 us per call however
        few its states, so a small batch runs faster through the one-state kernel).
    check_step : bool, default True
        Refuse a ``dt`` that cannot resolve some trajectory at its start state (``integrate.rk4_step_limit``),
        with a ValueError naming ``dt``, the trajectory and the largest safe step; and, as ``simulate``, re-check
        every running trajectory at the end of each chunk of steps: one that the step no longer resolves ends
        with status "unresolved: ..." naming dt and its largest safe step (one warning for the batch); the
        others run on.  False (experts): no check.
    strict : bool, default False
        Raise ``OutsideDomainError`` where force evaluations of some trajectory left the model's domain.
    progress : bool or None, default None
        A tqdm bar on stderr (shown once the batch has taken 2 s), as ``simulate``'s: None shows it only where
        stderr is a terminal and ``CI`` is unset (so not in the pipeline's logs).  The loops run in chunks of
        steps either way (``integrate.CHUNK_MIN_STEPS``), and the trajectories do not depend on them to the bit.

    Returns
    -------
    BatchTrajectory
        ``status[p]`` as ``simulate``'s: each trajectory's own force evaluations outside the model's domain
        (``n_outside_domain[p]``, counted by ``integrate.outside_domain``, the one-state kernels' rule) make a
        finished trajectory "outside-domain: ..." (not ok, ``completed``) naming its count, share and largest
        eccentricity (``eps_reached[p]``); one warning names how many trajectories and the share of the
        batch's evaluations.
    """
    if not isinstance(model, ForceModel):
        raise ValueError(f"{type(model).__name__} is not a force model (fluidfilm.core.force_model.ForceModel); "
                         "the integrator needs one")
    if isinstance(model, TransientFilmModel):
        raise ValueError(f"{model.name} is a film with memory (mass-conserving cavitation): its content is state that "
                         "simulate_batch does not carry; integrate each rotor with simulate")
    kernel, params = model.force_kernel
    bearing = model.bearing
    rotor_list = [rotors] if isinstance(rotors, Rotor) else list(rotors)
    if not rotor_list or not all(isinstance(r, Rotor) for r in rotor_list):
        raise ValueError("rotors must be a Rotor or a non-empty sequence of Rotor")
    shapes = [np.shape(a)[0] for a in (x0, v0, settings) if a is not None and np.ndim(a) == 2]
    n = max([len(rotor_list)] + shapes)
    if len(rotor_list) == 1:
        rotor_list = rotor_list * n
    if len(rotor_list) != n:
        raise ValueError(f"{len(rotor_list)} rotors for a batch of {n} trajectories")
    n_steps = check_run_args(t_end, dt, t0, eps_stop, eps_substep, record_every, max_substeps)
    x0 = _rows(x0, n, "x0")
    v0 = _rows(v0, n, "v0")
    setting = model.setting_array if isinstance(model, BatchSettable) else None
    if settings is None:
        if setting is None:
            setting = np.zeros(0)
        settings_arr = np.tile(setting, (n, 1))
        c = np.full(n, float(model.clearance))
    else:
        if setting is None:
            raise ValueError(f"{type(model).__name__} takes no per-trajectory settings (not BatchSettable)")
        settings_arr = np.ascontiguousarray(np.asarray(settings, dtype=float).reshape(n, -1))
        if settings_arr.shape[1] != setting.shape[0]:
            raise ValueError(f"settings rows must have {setting.shape[0]} values, got {settings_arr.shape[1]}")
        c = 1.0 / np.sqrt(settings_arr[:, 0])  # row 0 of a surrogate's setting is 1/c^2 of its clearance
    eccentric = np.hypot(x0[:, 0], x0[:, 1]) >= eps_stop * c
    if eccentric.any():
        raise ValueError(f"initial eccentricity of trajectory {int(np.argmax(eccentric))} is not below "
                         f"eps_stop={eps_stop}")
    omega = bearing.omega
    # 1/c^2 as the kernels hold it (a surrogate's setting row 0), for the per-trajectory domain count
    consts = _rotor_constants(rotor_list, omega, c, settings_arr[:, 0] if settings is not None else 1.0 / c**2)
    record_every = int(record_every)
    n_out = n_steps // record_every + 2
    # empty: the compiled loops write every row, the recorded ones and NaN past them (_fill_unrecorded)
    out_x = np.empty((n, n_out, 2))
    out_v = np.empty((n, n_out, 2))
    n_rec = np.zeros(n, dtype=np.int64)
    status = np.zeros(n, dtype=np.int64)
    t_stop = np.zeros(n)
    evals = np.zeros((n, 2), dtype=np.int64)  # per trajectory: force evaluations, and those outside the domain
    # the running state carried between chunks: x1, x2, v1, v2 and the largest |X|^2 reached
    state = np.concatenate([x0, v0, (x0[:, 0] ** 2 + x0[:, 1] ** 2)[:, None]], axis=1)
    dom = domain_rule(model)
    check_precision(precision)
    n_threads = _thread_count(threads, n)
    if not isinstance(check_step, (bool, np.bool_)):
        raise ValueError(f"check_step must be True or False, got {check_step!r}")
    saved = setting.copy()
    # the loops' arguments after ``consts`` and ``dom``; each chunk brings its ``steps`` (step0, step1, n_steps)
    rule = StepRule(float(t0), float(dt), record_every, float(eps_stop), float(eps_substep), int(max_substeps))
    run = BatchRun(state, out_x, out_v, n_rec, status, t_stop, evals)
    check = _StepCheck(model, (kernel, params), setting, settings_arr, consts, c, rule, float(omega),
                       settings is not None, precision) if check_step else None
    if check is not None:
        check.start(x0, v0)
    if stage_batched is None:
        stage_batched = n >= STAGE_BATCHED_MIN_N
    staged = stage_batched and settings is None and isinstance(model, BatchForceModel) and \
        model.batch_force_kernel(precision) is not None
    chunk = max(integrate.CHUNK_MIN_STEPS, -(-n_steps // integrate.MAX_CHUNKS))  # as simulate's
    unresolved: dict = {}
    model.reset_domain_counter()
    t_start = time.perf_counter()
    bar = _progress_bar(progress, n_steps, "simulate_batch")
    try:
        with (_stage_chunks(model, precision, n_threads, consts, dom, rule, run) if staged else
              _lockstep_chunks(kernel, params, setting, settings_arr, consts, dom, rule, run)) as advance:
            for s0 in range(0, n_steps, chunk):
                s1 = min(s0 + chunk, n_steps)
                advance((s0, s1, n_steps))
                if bar is not None:
                    bar.update(s1 - s0)
                if check is not None:
                    unresolved.update(check.along(run, s1, record_every))
    finally:
        setting[:] = saved
        if bar is not None:
            bar.close()
    wall = time.perf_counter() - t_start
    # the recorded time grid, as simulate's: t0 + (j * record_every) dt, computed the way its loop does
    t_grid = np.empty(n_out)
    t_grid[0] = t0
    steps = np.arange(1, n_out) * record_every
    t_grid[1:] = t0 + (steps - 1 + 1.0) * dt
    texts, t_stop_out = _stop_texts(run, c, eps_stop, dt, unresolved)
    if unresolved:
        warnings.warn(f"{len(unresolved)} of {n} trajectories ended unresolved: dt={dt!r} s no longer resolves "
                      f"them along the run (their status names the largest safe step)", RuntimeWarning, stacklevel=2)
    eps_reached = np.sqrt(state[:, 4]) / c
    texts = _domain_texts(model, texts, evals, eps_reached, strict)
    return BatchTrajectory(t=t_grid, x=out_x, v=out_v, n_recorded=n_rec, status=texts, t_stop=t_stop_out,
                           n_force_evals=evals[:, 0].copy(), wall_time_s=wall,
                           meta={"dt": dt, "t0": t0, "t_end": t_end, "record_every": record_every},
                           n_outside_domain=evals[:, 1].copy(), eps_reached=eps_reached)
