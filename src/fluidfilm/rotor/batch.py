"""``simulate_batch``: N rotor trajectories integrated together, the force model called on the whole batch per step.

What the batch is for: a sweep over imbalance, load or initial state, a
Monte Carlo over rotor parameters, or the candidate control settings of a
model predictive controller - many trajectories that share a force model and
a time grid.  One compiled loop advances every trajectory of the batch by one
step before the next (lockstep), so per step the force model is evaluated at
the states of the whole batch; the per-trajectory Python overhead of
``simulate`` (argument checks, array allocation, a call into numba) is paid
once per batch instead of once per trajectory.

Each trajectory is integrated by exactly the arithmetic of ``simulate``
(fixed-step RK4, the same eccentricity-dependent substeps, the same stopping
rules), in the same order, so a batch reproduces the unbatched trajectories
to the last bit (tests/test_batch.py checks this); a trajectory that stops
(contact, divergence) drops out of the batch while the others go on.

Per-trajectory control settings (``settings``): a surrogate of the active
bearing reads its sleeve position from a small mutable array in its kernel
parameters; with ``settings`` (N, k) the loop writes trajectory p's row into
that array before evaluating p's forces, so candidates with different sleeve
positions run in one batch.  The reference solver rebuilds its parameters
when the sleeve moves, so it takes one setting per batch.

The loop is serial: the surrogate kernel uses preallocated scratch rows in
its parameters (no allocation per evaluation), which threads would share.
"""
from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from fluidfilm.core.force_model import BatchSettable, ForceModel
from fluidfilm.rotor.integrate import (CONTACT, CONTACT_STAGE, OK, Trajectory, _rk4_step, _rk4_step_uncached, _uncached,
                                       check_run_args, run_loop)
from fluidfilm.rotor.model import Rotor


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

    def __len__(self) -> int:
        return self.x.shape[0]

    @property
    def ok(self) -> np.ndarray:
        return np.array([s == "ok" or s.startswith("ok;") for s in self.status])

    def trajectory(self, p: int) -> Trajectory:
        """Trajectory p as ``simulate`` would have returned it (its stopping time on its own time axis)."""
        n = int(self.n_recorded[p])
        t = self.t[:n].copy()
        if not self.ok[p]:
            t[-1] = self.t_stop[p]
        ts = None if math.isnan(self.t_stop[p]) else float(self.t_stop[p])
        return Trajectory(t=t, x=self.x[p, :n].copy(), v=self.v[p, :n].copy(), status=self.status[p], t_stop=ts,
                          n_force_evals=int(self.n_force_evals[p]), wall_time_s=self.wall_time_s / len(self),
                          meta=dict(self.meta))


@njit(cache=True)
def _rk4_batch(kernel, params, setting, settings, consts, x0, v0, t0, dt, n_steps, record_every, eps_stop,
               eps_substep, max_substeps, out_x, out_v, n_rec, status, t_stop, n_evals):
    """Lockstep RK4 of N trajectories; each one's arithmetic is ``integrate._rk4_run``'s."""
    n_traj = x0.shape[0]
    n_set = settings.shape[1]
    state = np.empty((n_traj, 4))
    for p in range(n_traj):
        state[p, 0], state[p, 1], state[p, 2], state[p, 3] = x0[p, 0], x0[p, 1], v0[p, 0], v0[p, 1]
        out_x[p, 0, 0], out_x[p, 0, 1] = x0[p, 0], x0[p, 1]
        out_v[p, 0, 0], out_v[p, 0, 1] = v0[p, 0], v0[p, 1]
        n_rec[p] = 1
        status[p] = 0
        t_stop[p] = t0
        n_evals[p] = 0
    n_running = n_traj
    for step in range(n_steps):
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
            x1, x2, v1, v2, t, n, st = _rk4_step(kernel, params, cp, x1, x2, v1, v2, t_stop[p], t0, step, dt,
                                                 eps_substep, max_substeps, eps_stop * eps_stop * consts[p, 6], False)
            n_evals[p] += n
            state[p, 0], state[p, 1], state[p, 2], state[p, 3] = x1, x2, v1, v2
            t_stop[p] = t  # the trajectory's current time (its stopping time once it stops)
            if st != 0:
                status[p] = st
                n_running -= 1
            if st != 0 or (step + 1) % record_every == 0:
                r = n_rec[p]
                out_x[p, r, 0], out_x[p, r, 1] = x1, x2
                out_v[p, r, 0], out_v[p, r, 1] = v1, v2
                n_rec[p] = r + 1


# kernels the on-disk cache cannot take (a user's model, an ensemble's members): an uncached twin
_rk4_batch_uncached = _uncached(_rk4_batch, _rk4_step=_rk4_step_uncached)


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
                   max_substeps: int = 256, t0: float = 0.0) -> BatchTrajectory:
    """Integrate N rotors (a ``Rotor`` or a sequence of N) in ``model`` from x0, v0 ((2,) or (N, 2)).

    ``settings`` (N, k): per-trajectory values of the model's control setting
    (for a surrogate of the active bearing, ``model.setting_for(sleeve)``
    rows); the model's own setting is restored afterwards.  Arguments
    otherwise as ``simulate``, checked by the same function: ``t_end`` is the
    END TIME [s] of the run (absolute), which goes from ``t0`` to ``t_end``.
    """
    if not isinstance(model, ForceModel):
        raise ValueError(f"{type(model).__name__} is not a force model (fluidfilm.core.force_model.ForceModel); "
                         "the integrator needs one")
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
    consts = np.empty((n, 9))
    for p, rotor in enumerate(rotor_list):
        u_final = rotor.imbalance if rotor.imbalance_final is None else rotor.imbalance_final
        consts[p] = (1.0 / rotor.mass, rotor.imbalance * omega**2, omega, float(rotor.imbalance_direction),
                     rotor.external_force[0], rotor.external_force[1] + rotor.mass * rotor.gravity, c[p] ** 2,
                     u_final * omega**2, rotor.ramp_time if rotor.imbalance_final is not None else 0.0)
    record_every = int(record_every)
    n_out = n_steps // record_every + 2
    out_x = np.full((n, n_out, 2), np.nan)
    out_v = np.full((n, n_out, 2), np.nan)
    n_rec = np.zeros(n, dtype=np.int64)
    status = np.zeros(n, dtype=np.int64)
    t_stop = np.zeros(n)
    n_evals = np.zeros(n, dtype=np.int64)
    model.reset_domain_counter()
    saved = setting.copy()
    t_start = time.perf_counter()
    try:
        run_loop(_rk4_batch, _rk4_batch_uncached, kernel, params, setting, settings_arr, consts, x0, v0, float(t0),
                 float(dt), n_steps, record_every, float(eps_stop), float(eps_substep), int(max_substeps), out_x, out_v,
                 n_rec, status, t_stop, n_evals)
    finally:
        setting[:] = saved
    wall = time.perf_counter() - t_start
    # the recorded time grid, as simulate's: t0 + (j * record_every) dt, computed the way its loop does
    t_grid = np.empty(n_out)
    t_grid[0] = t0
    steps = np.arange(1, n_out) * record_every
    t_grid[1:] = t0 + (steps - 1 + 1.0) * dt
    texts = []
    t_stop_out = np.full(n, np.nan)
    for p in range(n):
        if status[p] == OK:
            texts.append("ok")
        elif status[p] in (CONTACT, CONTACT_STAGE):
            texts.append(f"contact: eccentricity reached eps_stop={eps_stop} at t={t_stop[p]:.6g} s")
            t_stop_out[p] = t_stop[p]
        else:
            texts.append(f"diverged: non-finite state after t={t_stop[p]:.6g} s")
            t_stop_out[p] = t_stop[p]
    note = model.domain_report()
    if note:
        texts = [f"{s}; {note} (whole batch)" for s in texts]
        warnings.warn(f"{model.name}: {note} during the batch",
                      RuntimeWarning, stacklevel=2)
    return BatchTrajectory(t=t_grid, x=out_x, v=out_v, n_recorded=n_rec, status=texts, t_stop=t_stop_out,
                           n_force_evals=n_evals, wall_time_s=wall,
                           meta={"dt": dt, "t0": t0, "t_end": t_end, "record_every": record_every})
