"""The rotor in a film with memory: RK4 with the film content carried between steps (mass-conserving cavitation).

A transient film model (``core.force_model.TransientFilmModel``; ``reynolds.elrod_adams.ElrodAdamsSolver``)
gives two compiled kernels: ``stage(params, K_omega, x1, x2, v1, v2, dt, tol, th_n, content, p, th)`` -> the
force of one RK4 stage, a backward-Euler film step of length dt from the committed content ``th_n``; and
``commit(params, K_omega, x1_old, x2_old, x1, x2, dt, th_n, content, p, th)``, the committed film step from
the accepted (sub)step's start to its end.  How the state advances:

- each RK4 stage solves its own film step from the content committed at the step's start, so a full film
  gives exactly the Reynolds solver's force with the stage's squeeze velocity;
- after each accepted (sub)step one more solve commits the content phi^{n+1}: backward Euler from
  phi^n H(X_n) to X_{n+1}, whose flow balance closes to the solver's tolerance (``flow_balance``).

The rotor's states therefore see a film that lags by at most one step: the scheme is first order in dt for
what the film remembers (RK4's order for a full film), and the tests measure it.  The (sub)step is the
same as ``integrate._rk4_step``'s: split above ``eps_substep``; contact and non-finite states stop the run.
"""
from __future__ import annotations

import math
import time
import warnings

import numpy as np
from numba import njit

from fluidfilm.rotor.integrate import (CONTACT, CONTACT_STAGE, NONFINITE, OK, OUTSIDE_DOMAIN, OutsideDomainError,
                                       Trajectory, _domain_note,
                                       _ramped, _schedule_arrays, check_run_args, schedule_at)
from fluidfilm.rotor.model import RPM, Rotor, SpeedSchedule

#: a film solve did not converge (status of the loop)
FILM_FAILED = 4
#: how far above 1 a carried film content may be: a full node's committed content is 1 up to the commit
#: solve's residual (``reynolds.elrod_adams.close_content`` keeps each node's flow balance exact)
CONTENT_SLACK = 1e-6


@njit
def _film_acceleration(stage, ep, k_ref, x1, x2, v1, v2, t, h, tol, th_n, content, p, th, consts):
    """(a1, a2, inside, sweeps, converged) at one RK4 stage: the film step of length ``h`` from ``th_n``."""
    inv_m, unb, w_ref, sgn, g1, g2, c2, unb_final, ramp_time, times, omegas, cum = consts
    if x1 * x1 + x2 * x2 >= c2:
        return 0.0, 0.0, False, 0, True
    w, alpha, corr = schedule_at(times, omegas, cum, w_ref, t)
    f1, f2, sweeps, status = stage(ep, k_ref * (w / w_ref), x1, x2, v1, v2, h, tol, th_n, content, p, th)
    if ramp_time > 0.0:
        unb = _ramped(unb, unb_final, t, ramp_time)
    s = w / w_ref
    s2 = s * s
    an = alpha / (w_ref * w_ref)
    ph = w_ref * t + corr
    cph = math.cos(ph)
    sph = math.sin(ph)
    return ((f1 + unb * (s2 * cph + an * sph) + g1) * inv_m, (f2 + sgn * unb * (s2 * sph - an * cph) + g2) * inv_m,
            True, sweeps, status == 0)


@njit(inline="always")
def _record_film(out_film, n, values):
    q, power, f1, f2 = values
    out_film[n, 0] = q
    out_film[n, 1] = power
    out_film[n, 2] = f1
    out_film[n, 3] = f2


@njit
def _film_run(stage, commit, flows, ep, k_ref, tol, consts, x0, v0, t0, dt, n_steps, record_every, eps_stop,
              eps_substep, max_substeps, th_n, p, th, out_t, out_x, out_v, out_film, stats):
    """Integrate; returns (n_recorded, status, t_stop, n_force_evals).  ``th_n``, ``p``, ``th``: the committed
    content and the working fields (warm starts), updated in place.  ``out_film``: (side flow [m^3/s], friction
    power [W], film force F1, F2 [N]) of the committed film at each record (``flows``).  ``stats``: [stage sweeps, commit sweeps, stage solves, commit solves]."""
    c2 = consts[6]
    w_ref = consts[2]
    times, omegas, cum = consts[9], consts[10], consts[11]
    stop2 = eps_stop * eps_stop * c2
    x1, x2 = x0[0], x0[1]
    v1, v2 = v0[0], v0[1]
    t = t0
    n_evals = 0
    content = np.empty_like(th_n)
    out_t[0] = t
    out_x[0, 0] = x1
    out_x[0, 1] = x2
    out_v[0, 0] = v1
    out_v[0, 1] = v2
    w = schedule_at(times, omegas, cum, w_ref, t)[0]
    inv_c = 1.0 / math.sqrt(c2)
    _record_film(out_film, 0, flows(ep, w, x1 * inv_c, x2 * inv_c, p, th))
    n_rec = 1
    status = OK
    for step in range(n_steps):
        e2 = (x1 * x1 + x2 * x2) / c2
        k = 1
        if e2 > eps_substep * eps_substep:
            k = int(math.ceil(((1.0 - eps_substep * eps_substep) / (1.0 - e2)) ** 1.5))
            if k > max_substeps:
                k = max_substeps
        h = dt / k
        for sub in range(k):
            a1, a2, ok1, s1, c1_ = _film_acceleration(stage, ep, k_ref, x1, x2, v1, v2, t, h, tol, th_n, content,
                                                      p, th, consts)
            b1, b2, ok2, s2, c2_ = _film_acceleration(stage, ep, k_ref, x1 + 0.5 * h * v1, x2 + 0.5 * h * v2,
                                                      v1 + 0.5 * h * a1, v2 + 0.5 * h * a2, t + 0.5 * h, h, tol,
                                                      th_n, content, p, th, consts)
            kx1 = v1 + 0.5 * h * a1
            kx2 = v2 + 0.5 * h * a2
            d1_, d2_, ok3, s3, c3_ = _film_acceleration(stage, ep, k_ref, x1 + 0.5 * h * kx1, x2 + 0.5 * h * kx2,
                                                        v1 + 0.5 * h * b1, v2 + 0.5 * h * b2, t + 0.5 * h, h, tol,
                                                        th_n, content, p, th, consts)
            lx1 = v1 + 0.5 * h * b1
            lx2 = v2 + 0.5 * h * b2
            e1_, e2_, ok4, s4, c4_ = _film_acceleration(stage, ep, k_ref, x1 + h * lx1, x2 + h * lx2,
                                                        v1 + h * d1_, v2 + h * d2_, t + h, h, tol, th_n, content,
                                                        p, th, consts)
            mx1 = v1 + h * d1_
            mx2 = v2 + h * d2_
            n_evals += 4
            stats[0] += s1 + s2 + s3 + s4
            stats[2] += 4
            if not (ok1 and ok2 and ok3 and ok4):
                status = CONTACT_STAGE
                break
            if not (c1_ and c2_ and c3_ and c4_):
                status = FILM_FAILED
                break
            nx1 = x1 + h / 6.0 * (v1 + 2.0 * kx1 + 2.0 * lx1 + mx1)
            nx2 = x2 + h / 6.0 * (v2 + 2.0 * kx2 + 2.0 * lx2 + mx2)
            nv1 = v1 + h / 6.0 * (a1 + 2.0 * b1 + 2.0 * d1_ + e1_)
            nv2 = v2 + h / 6.0 * (a2 + 2.0 * b2 + 2.0 * d2_ + e2_)
            if not (math.isfinite(nx1) and math.isfinite(nx2) and math.isfinite(nv1) and math.isfinite(nv2)):
                status = NONFINITE
                break
            if nx1 * nx1 + nx2 * nx2 >= c2:
                status = CONTACT_STAGE
                break
            # commit the film content over the accepted (sub)step
            tn = t0 + (step + (sub + 1.0) / k) * dt
            w, alpha, corr = schedule_at(times, omegas, cum, w_ref, tn)
            sweeps, cst = commit(ep, k_ref * (w / w_ref), x1, x2, nx1, nx2, h, th_n, content, p, th)
            stats[1] += sweeps
            stats[3] += 1
            if cst != 0:
                status = FILM_FAILED
                break
            th_n[:, :] = th
            x1, x2, v1, v2 = nx1, nx2, nv1, nv2
            t = tn
            if x1 * x1 + x2 * x2 >= stop2:
                status = CONTACT
                break
        if status != OK:
            break
        if (step + 1) % record_every == 0:
            out_t[n_rec] = t
            out_x[n_rec, 0] = x1
            out_x[n_rec, 1] = x2
            out_v[n_rec, 0] = v1
            out_v[n_rec, 1] = v2
            _record_film(out_film, n_rec, flows(ep, w, x1 * inv_c, x2 * inv_c, p, th))
            n_rec += 1
    if status != OK:
        out_t[n_rec] = t
        out_x[n_rec, 0] = x1
        out_x[n_rec, 1] = x2
        out_v[n_rec, 0] = v1
        out_v[n_rec, 1] = v2
        out_film[n_rec, :] = np.nan
        n_rec += 1
    return n_rec, status, t, n_evals


def simulate_film(model, rotor: Rotor, t_end: float, dt: float = 1e-5, x0=None, v0=None, *, eps_stop: float = 0.98,
                  record_every: int = 1, eps_substep: float = 0.8, max_substeps: int = 256, t0: float = 0.0,
                  speed: SpeedSchedule | None = None, film_content=None, strict: bool = False) -> Trajectory:
    """Integrate the rotor in a transient film with memory (``simulate`` calls it for such a model).

    As ``rotor.integrate.simulate`` (the same arguments, checks and status texts), with the film content
    carried from step to step (module doc).  ``film_content``: the content phi (n_theta, n_z) at t0; None:
    the steady film at x0.  The returned trajectory's ``meta`` holds ``film_content`` at the end (to continue
    the run), ``side_flow_m3s``, ``friction_power_W`` and ``film_force_N`` (the committed film's force, (n, 2))
    at every record, the sweeps per stage and per commit,
    and the speed schedule if any.
    """
    if not isinstance(rotor, Rotor):
        raise ValueError(f"rotor must be a Rotor, got {type(rotor).__name__}")
    stage, commit, flows, ep = model.transient_kernels()
    c = float(model.clearance)
    n_steps = check_run_args(t_end, dt, t0, eps_stop, eps_substep, record_every, max_substeps)
    for name, value in (("x0", x0), ("v0", v0)):
        if value is not None and np.shape(value) != (2,):
            raise ValueError(f"{name} must be a pair ({name[0].upper()}1, {name[0].upper()}2), got shape {np.shape(value)}")
    x0 = np.zeros(2) if x0 is None else np.asarray(x0, dtype=float).reshape(2)
    v0 = np.zeros(2) if v0 is None else np.asarray(v0, dtype=float).reshape(2)
    if not (np.isfinite(x0).all() and np.isfinite(v0).all()):
        raise ValueError(f"initial state must be finite, got x0={tuple(x0)}, v0={tuple(v0)}")
    if np.hypot(*x0) >= eps_stop * c:
        raise ValueError(f"initial eccentricity {np.hypot(*x0) / c:.4g} is not below eps_stop={eps_stop}")
    bearing = model.bearing
    omega = bearing.omega
    if speed is None:
        speed = SpeedSchedule.constant(omega / RPM)
    elif not isinstance(speed, SpeedSchedule):
        raise ValueError(f"speed must be a SpeedSchedule (SpeedSchedule.ramp, .table or .constant), got "
                         f"{type(speed).__name__}")
    if getattr(model, "fixed_speed", False) and not bool((speed.omega == omega).all()):
        raise ValueError(f"{model.name} holds one shaft speed ({bearing.speed_rpm:g} rpm, its training data's): "
                         f"a speed schedule cannot run in it")
    w0 = float(schedule_at(*_schedule_arrays(speed, omega), omega, t0)[0])
    if film_content is None:
        p, th = model.steady_field(x0, omega=w0)
    elif hasattr(model, "check_film_state"):  # a model whose carried state is not a content field
        p, th = model.steady_field(x0, omega=w0)
        th = model.check_film_state(film_content)
    else:
        th = np.array(film_content, dtype=float)
        # a committed full node holds 1 up to the commit's residual (``elrod_adams.close_content``)
        if (th.shape != (model.n_theta, model.n_z) or not np.isfinite(th).all() or th.min() < 0.0
                or th.max() > 1.0 + CONTENT_SLACK):
            raise ValueError(f"film_content must be an array of shape {(model.n_theta, model.n_z)} with values in "
                             f"[0, 1], got shape {th.shape}"
                             + (f" and values in [{th.min():.6g}, {th.max():.6g}]" if th.size and np.isfinite(th).all()
                                else ""))
        p = np.zeros_like(th)
    th_n = np.ascontiguousarray(th.copy())
    p = np.ascontiguousarray(p)
    th = np.ascontiguousarray(th)
    record_every = int(record_every)
    n_out = n_steps // record_every + 2
    out_t = np.empty(n_out)
    out_x = np.empty((n_out, 2))
    out_v = np.empty((n_out, 2))
    out_film = np.empty((n_out, 4))
    stats = np.zeros(4, dtype=np.int64)
    u_final = rotor.imbalance if rotor.imbalance_final is None else rotor.imbalance_final
    consts = (1.0 / rotor.mass, rotor.imbalance * omega**2, omega, float(rotor.imbalance_direction),
              rotor.external_force[0], rotor.external_force[1] + rotor.mass * rotor.gravity, c * c,
              u_final * omega**2, rotor.ramp_time if rotor.imbalance_final is not None else 0.0) \
        + _schedule_arrays(speed, omega)
    model.reset_domain_counter()
    t_start = time.perf_counter()
    n_rec, status, t_stop, n_evals = _film_run(stage, commit, flows, ep, float(ep.k_omega), float(ep.tol), consts, x0, v0,
                                               float(t0), float(dt), n_steps, record_every, float(eps_stop),
                                               float(eps_substep), int(max_substeps), th_n, p, th, out_t, out_x,
                                               out_v, out_film, stats)
    wall = time.perf_counter() - t_start
    if status == OK:
        text, t_stop = "ok", None
    elif status in (CONTACT, CONTACT_STAGE):
        text = f"contact: eccentricity reached eps_stop={eps_stop} at t={t_stop:.6g} s"
    elif status == FILM_FAILED:
        text = (f"diverged: the film solve did not converge within max_sweeps={ep.max_sweeps} after t={t_stop:.6g} s")
    else:
        text = f"diverged: non-finite state after t={t_stop:.6g} s"
    # a surrogate counts its stages outside its training domain: "ok" is not promised there (rotor.integrate)
    n_outside = int(model.n_outside_domain)
    e_max = float(np.max(np.hypot(out_x[:n_rec, 0], out_x[:n_rec, 1])))
    note = _domain_note(model, n_outside, int(n_evals), e_max * e_max, c) if n_outside else None
    if note:
        if strict:
            raise OutsideDomainError(f"{model.name}: {note} during the simulation (strict=True)")
        text = f"{OUTSIDE_DOMAIN}: reached the end time; {note}" if text == "ok" else f"{text}; {note}"
        warnings.warn(f"{model.name}: {note} during the simulation", RuntimeWarning, stacklevel=3)
    meta = {"dt": dt, "t0": t0, "t_end": t_end, "record_every": record_every, "precision": "float64",
            "film_content": th_n.copy(), "side_flow_m3s": out_film[:n_rec, 0].copy(),
            "friction_power_W": out_film[:n_rec, 1].copy(), "film_force_N": out_film[:n_rec, 2:].copy(),
            "sweeps_per_stage": float(stats[0]) / max(int(stats[2]), 1),
            "sweeps_per_commit": float(stats[1]) / max(int(stats[3]), 1),
            "film_solves": int(stats[2] + stats[3])}
    if not bool((speed.omega == omega).all()):
        meta["speed"] = {"times": speed.times.tolist(), "omega": speed.omega.tolist()}
    return Trajectory(t=out_t[:n_rec].copy(), x=out_x[:n_rec].copy(), v=out_v[:n_rec].copy(), status=text,
                      t_stop=t_stop, n_force_evals=int(n_evals), wall_time_s=wall, meta=meta, n_outside_domain=n_outside)
