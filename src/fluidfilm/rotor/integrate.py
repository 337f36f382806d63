"""``simulate``: the rotor's equation of motion, one compiled loop for every force model.

Equation (paper eq. 4, CONVENTIONS.md):

    m dV/dt = F_bearing(X, V) + m_u d w^2 (cos wt, s sin wt) + m (0, g) + F_ext,   dX/dt = V

Scheme: classical fixed-step RK4 (or adaptive, ``dt=None``).  A fixed step means every force model is
evaluated at the same number of states, so comparing the wall time of two
models compares the models, and comparing their orbits compares their
forces, not step-size controllers.

Stiffness: squeeze damping grows like (1 - eps^2)^-1.5, so the film's
fastest eigenvalue ~ C/m grows the same way and RK4's stability bound
(|lambda dt| < 2.8) is lost near the sleeve.  Above ``eps_substep`` each step
is split into k = ceil(((1 - eps_substep^2)/(1 - eps^2))^1.5) equal substeps,
which keeps lambda*dt at the level it has at eps_substep.  With the paper's
bearing, m = 1-3 kg and dt = 1e-5 s (2000 steps per revolution), lambda*dt
stays below ~0.3 up to eps_substep = 0.8; the step-halving test shows the
settled orbits converge (tests/rotor/test_rotor.py).

The loop is compiled with numba and calls the model's compiled force kernel
``fn(params, x1, x2, v1, v2) -> (F1, F2)`` directly, so the integrator's own
overhead is a few tens of nanoseconds per step.

Step check (``check_step``): a fixed step must resolve the run.  The film
rotor system is linearised at the start state (``rk4_step_limit``: K and C by
central differences of the compiled kernel, the eigenvalues of the 4x4
system), and a ``dt`` beyond the largest safe step is refused naming both;
the loop runs in chunks of steps and the check is repeated at each chunk's
end, where a step that stops resolving the film ends the run "unresolved".
``dt=None`` instead integrates with an adaptive Dormand-Prince 5(4) pair in a
compiled loop of its own (``_dp45_run``: error control by ``rtol``/``atol``,
steps landed on the output times).  The chunks (also the progress bar's)
do not change a trajectory to the bit: step k's time is t0 + k dt in every
chunk, and the adaptive loop recomputes its first stage at each chunk start.

Domain: a run whose force evaluations left the model's validity domain ends
"outside-domain: ..." (not ``ok``; ``completed``), with one warning naming the
share of evaluations and the largest eccentricity, or ``OutsideDomainError``
with ``strict=True``.

Stopping: when the eccentricity reaches ``eps_stop`` (the journal touches the
sleeve, e.g. 0.98) or an RK stage would put the journal outside the
clearance, the run stops and ``status`` says so and when.  A non-finite
state stops it as well.  Never a NaN in the output, never a hang.
"""
from __future__ import annotations

import math
import time
import types
import warnings
from dataclasses import dataclass, field

import numpy as np
from numba import njit
from numba.core.registry import CPUDispatcher as Dispatcher

from fluidfilm.core.force_model import ForceModel, SpeedScalableModel, TransientFilmModel, one_state_kernel
from fluidfilm.rotor.model import RPM, Rotor, SpeedSchedule, ramped

_ramped = njit(inline="always")(ramped)

OK, CONTACT, CONTACT_STAGE, NONFINITE = 0, 1, 2, 3
#: status code of a run stopped by the along-the-run step check (set from Python, never by a loop)
UNRESOLVED = 4
#: the status prefix of a run that reached its end time with forces outside the model's domain
OUTSIDE_DOMAIN = "outside-domain"

#: RK4's stability bound on the negative real axis is |lambda dt| = 2.785 (2.83 on the imaginary axis);
#: a step is safe where every eigenvalue of the linearised film-rotor system has |lambda| h <= this (a
#: safety factor of 2), h the (sub)step
RK4_LAMBDA_DT = 1.4
#: resolution: at least this many steps per shaft revolution and per period of each oscillating mode
STEPS_PER_PERIOD = 20
#: the fixed-step loop runs in chunks of at least this many steps (progress bar, along-the-run check) and
#: in at most ``MAX_CHUNKS`` chunks
CHUNK_MIN_STEPS = 1000
MAX_CHUNKS = 100


class OutsideDomainError(RuntimeError):
    """A run with ``strict=True`` whose force evaluations left the model's validity domain."""


@dataclass
class Trajectory:
    """A rotor trajectory: t (n,), x (n, 2) m, v (n, 2) m/s, and how it ended.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Recorded times [s].
    x : ndarray, shape (n, 2)
        Journal positions (X1, X2) [m], +X2 along gravity.
    v : ndarray, shape (n, 2)
        Journal velocities [m/s].
    status : str
        ``"ok"`` (reached the end time, every force inside the model's domain), ``"outside-domain: ..."``
        (reached the end time, but some force evaluations left a surrogate's training domain: the share
        and the largest eccentricity are named), ``"contact: ..."``, ``"diverged: ..."`` or
        ``"unresolved: ..."`` (the step stopped resolving the film's time scales along the run).
    t_stop : float or None, default None
        Time [s] at which the run stopped; None when it reached the end.
    n_force_evals : int, default 0
        Force evaluations of the run.
    wall_time_s : float, default 0.0
        Wall time of the compiled loop [s].
    meta : dict, optional
        Run settings (``dt``, ``t_end``, ``record_every``).
    n_outside_domain : int, default 0
        Force evaluations outside the model's training domain (0 for a reference model).

    Examples
    --------
    >>> import numpy as np
    >>> from fluidfilm import Trajectory
    >>> tr = Trajectory(t=np.array([0.0, 1e-3]), x=np.array([[0.0, 0.0], [0.0, 3e-5]]),
    ...                 v=np.zeros((2, 2)), status="ok")
    >>> tr.ok, tr.eccentricity(clearance=1e-4).tolist()
    (True, [0.0, 0.3])
    """

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    status: str
    t_stop: float | None = None
    n_force_evals: int = 0
    wall_time_s: float = 0.0
    meta: dict = field(default_factory=dict)
    # force evaluations outside the model's training domain during this run (0 for a reference model)
    n_outside_domain: int = 0

    @property
    def ok(self) -> bool:
        """The run reached t_end with every force evaluation inside the model's domain: status "ok".

        A run whose forces left a surrogate's training domain has status "outside-domain: ..." and is not
        ok (``completed`` is still True); "contact: ...", "diverged: ..." and "unresolved: ..." are not ok.
        """
        return self.status == "ok" or self.status.startswith("ok;")

    @property
    def completed(self) -> bool:
        """The run reached t_end without contact, divergence or an unresolved step, inside the model's domain
        or not ("ok" or "outside-domain: ...")."""
        return self.ok or self.status.startswith(OUTSIDE_DOMAIN)

    @property
    def in_domain(self) -> bool:
        """No force evaluation of the run left the model's validity domain."""
        return self.n_outside_domain == 0 and not self.status.startswith(OUTSIDE_DOMAIN)

    def eccentricity(self, clearance: float) -> np.ndarray:
        """|X| / ``clearance`` at every recorded time."""
        return np.hypot(self.x[:, 0], self.x[:, 1]) / clearance

    def to_npz(self, path) -> None:
        """Write the trajectory to a compressed ``.npz`` file (atomically; ``from_npz`` reads it)."""
        from fluidfilm import io

        with io.atomic_path(path, suffix=".npz") as tmp:
            np.savez_compressed(tmp, t=self.t, x=self.x, v=self.v, status=np.array(self.status),
                                t_stop=np.array(np.nan if self.t_stop is None else self.t_stop),
                                n_force_evals=np.array(self.n_force_evals),
                                wall_time_s=np.array(self.wall_time_s),
                                n_outside_domain=np.array(self.n_outside_domain))

    @classmethod
    def from_npz(cls, path) -> "Trajectory":
        """A trajectory written by ``to_npz``."""
        d = np.load(path)
        t_stop = float(d["t_stop"])
        return cls(t=d["t"], x=d["x"], v=d["v"], status=str(d["status"]),
                   t_stop=None if math.isnan(t_stop) else t_stop,
                   n_force_evals=int(d["n_force_evals"]), wall_time_s=float(d["wall_time_s"]),
                   n_outside_domain=int(d["n_outside_domain"]) if "n_outside_domain" in d else 0)


@njit(cache=True)
def _acceleration(kernel, params, x1, x2, v1, v2, t, consts):
    """(a1, a2, inside): inside is False when the state lies outside the clearance."""
    inv_m, unb, omega, sgn, g1, g2, c2, unb_final, ramp_time = consts
    if x1 * x1 + x2 * x2 >= c2:
        return 0.0, 0.0, False
    f1, f2 = kernel(params, x1, x2, v1, v2)
    if ramp_time > 0.0:
        # imbalance growing uniformly over the ramp (Fig. 5's developing fault)
        unb = _ramped(unb, unb_final, t, ramp_time)
    ph = omega * t
    return (f1 + unb * math.cos(ph) + g1) * inv_m, (f2 + sgn * unb * math.sin(ph) + g2) * inv_m, True


@njit(cache=True, inline="always")
def _record(out_t, out_x, out_v, n, t, x1, x2, v1, v2):
    out_t[n] = t
    out_x[n, 0] = x1
    out_x[n, 1] = x2
    out_v[n, 0] = v1
    out_v[n, 1] = v2
    return n + 1


@njit(cache=True, inline="always")
def outside_domain(dom, inv_c2, x1, x2, v1, v2):
    """1 where a force evaluated at the state falls outside the validity domain ``dom``, else 0: the one-state
    surrogate kernels' rule (``surrogate.kernels``), eps = sqrt(|X|^2 inv_c2) above eps_max, or a velocity
    component above the v_max of the first band holding eps (the last band also above its top).

    ``dom`` (``domain_rule``): row 0 [eps_max, active (inf: no), 0], rows 1.. the bands (eps_low, eps_high,
    v_max)."""
    eps = math.sqrt((x1 * x1 + x2 * x2) * inv_c2)
    # as selects, without branches (the loops over a batch's states vectorise): the first band holding eps
    vmax = math.inf
    hit = False
    n = dom.shape[0]
    for s in range(1, n):
        now = (not hit) & (((dom[s, 0] <= eps) & (eps < dom[s, 1])) | ((s == n - 1) & (eps >= dom[s, 1])))
        vmax = dom[s, 2] if now else vmax
        hit = hit | now
    return 1 if (eps > dom[0, 0]) | (max(abs(v1), abs(v2)) > vmax) else 0


def domain_rule(model) -> np.ndarray:
    """``outside_domain``'s table of a model's validity domain: row 0 [eps_max, active, 0], then the bands;
    inactive (row 0 column 1 infinite: nothing counted) for a domain that is the whole film."""
    v = model.validity
    dom = np.zeros((1 + len(v.bands), 3))
    dom[0] = (v.eps_max, 0.0 if (v.eps_max < 1.0 or v.bands) else math.inf, 0.0)
    if v.bands:
        dom[1:] = np.asarray(v.bands, dtype=float)
    return dom


#: the domain table of a run that counts by the model's own counter (``simulate``): inactive
_NO_DOMAIN = np.array([[1.0, math.inf, math.inf]])


@njit(cache=True, inline="always")
def _rk4_step(kernel, params, consts, x1, x2, v1, v2, t, t0, step, dt, eps_substep, max_substeps, stop2, retry,
              dom, inv_c2):
    """Step ``step`` of RK4 from the state (x1, x2, v1, v2) at time t (= t0 + step dt), in substeps.

    The one RK4 step of ``simulate`` and ``simulate_batch``. Returns (x1, x2, v1, v2, t, n_evals, status,
    n_outside): the state after the step, or the last valid state where it stopped (status ``CONTACT``,
    ``CONTACT_STAGE``, ``NONFINITE``), and its force evaluations outside the domain table ``dom``
    (``outside_domain`` with 1/c^2 ``inv_c2``; none counted where ``dom`` is inactive). ``retry``: a stage
    outside the clearance says the step is too long,
    not that the journal touched: the step is redone with twice the substeps (up to ``max_substeps``)
    before contact is reported. Inlined, so each loop compiles it as if written in place.
    """
    counting = dom[0, 1] < math.inf
    n_out = 0
    c2 = consts[6]
    e2 = (x1 * x1 + x2 * x2) / c2
    k = 1
    if e2 > eps_substep * eps_substep:
        k = int(math.ceil(((1.0 - eps_substep * eps_substep) / (1.0 - e2)) ** 1.5))
        if k > max_substeps:
            k = max_substeps
    sx1, sx2, sv1, sv2, st = x1, x2, v1, v2, t
    n_evals = 0
    while True:
        x1, x2, v1, v2, t = sx1, sx2, sv1, sv2, st
        h = dt / k
        status = OK
        for sub in range(k):
            a1, a2, ok1 = _acceleration(kernel, params, x1, x2, v1, v2, t, consts)
            b1, b2, ok2 = _acceleration(kernel, params, x1 + 0.5 * h * v1, x2 + 0.5 * h * v2,
                                        v1 + 0.5 * h * a1, v2 + 0.5 * h * a2, t + 0.5 * h, consts)
            kx1 = v1 + 0.5 * h * a1
            kx2 = v2 + 0.5 * h * a2
            c1, c2_, ok3 = _acceleration(kernel, params, x1 + 0.5 * h * kx1, x2 + 0.5 * h * kx2,
                                         v1 + 0.5 * h * b1, v2 + 0.5 * h * b2, t + 0.5 * h, consts)
            lx1 = v1 + 0.5 * h * b1
            lx2 = v2 + 0.5 * h * b2
            d1, d2, ok4 = _acceleration(kernel, params, x1 + h * lx1, x2 + h * lx2,
                                        v1 + h * c1, v2 + h * c2_, t + h, consts)
            mx1 = v1 + h * c1
            mx2 = v2 + h * c2_
            n_evals += 4
            if counting:  # the stage states whose forces were evaluated (inside the clearance)
                n_out += (_outside_at(dom, inv_c2, x1, x2, v1, v2, ok1)
                          + _outside_at(dom, inv_c2, x1 + 0.5 * h * v1, x2 + 0.5 * h * v2, v1 + 0.5 * h * a1,
                                        v2 + 0.5 * h * a2, ok2)
                          + _outside_at(dom, inv_c2, x1 + 0.5 * h * kx1, x2 + 0.5 * h * kx2, v1 + 0.5 * h * b1,
                                        v2 + 0.5 * h * b2, ok3)
                          + _outside_at(dom, inv_c2, x1 + h * lx1, x2 + h * lx2, v1 + h * c1, v2 + h * c2_, ok4))
            if not (ok1 and ok2 and ok3 and ok4):
                status = CONTACT_STAGE
                break
            nx1 = x1 + h / 6.0 * (v1 + 2.0 * kx1 + 2.0 * lx1 + mx1)
            nx2 = x2 + h / 6.0 * (v2 + 2.0 * kx2 + 2.0 * lx2 + mx2)
            nv1 = v1 + h / 6.0 * (a1 + 2.0 * b1 + 2.0 * c1 + d1)
            nv2 = v2 + h / 6.0 * (a2 + 2.0 * b2 + 2.0 * c2_ + d2)
            if not (math.isfinite(nx1) and math.isfinite(nx2) and math.isfinite(nv1) and math.isfinite(nv2)):
                status = NONFINITE
                break
            x1, x2, v1, v2 = nx1, nx2, nv1, nv2
            t = t0 + (step + (sub + 1.0) / k) * dt
            # contact is checked after every substep, independent of how often the output is recorded
            if x1 * x1 + x2 * x2 >= stop2:
                status = CONTACT
                break
        if not (retry and status == CONTACT_STAGE and k < max_substeps):
            break
        k = min(2 * k, max_substeps)
    return x1, x2, v1, v2, t, n_evals, status, n_out


@njit(cache=True, inline="always")
def _outside_at(dom, inv_c2, x1, x2, v1, v2, evaluated):
    return outside_domain(dom, inv_c2, x1, x2, v1, v2) if evaluated else 0


@njit(cache=True)
def _rk4_run(kernel, params, consts, x0, v0, t0, dt, step0, step1, record_every, eps_stop, eps_substep,
             max_substeps, out_t, out_x, out_v, n_rec):
    """Steps ``step0`` to ``step1 - 1`` from the state x0, v0 at t0 + step0 dt, recording from row ``n_rec``
    (the caller records row 0, the start).  Step k's time is t0 + k dt whatever the chunk, so a run in
    chunks equals one call to the bit (``simulate``'s progress bar and along-the-run checks).

    Returns (n_recorded, status, t_stop, n_force_evals, x1, x2, v1, v2, e2max): the state after the last
    step and the largest |X|^2 reached after a step."""
    stop2 = eps_stop * eps_stop * consts[6]
    x1, x2 = x0[0], x0[1]
    v1, v2 = v0[0], v0[1]
    t = t0 + step0 * dt
    n_evals = 0
    e2max = 0.0
    status = OK
    for step in range(step0, step1):
        x1, x2, v1, v2, t, n, status, _ = _rk4_step(kernel, params, consts, x1, x2, v1, v2, t0 + step * dt, t0,
                                                    step, dt, eps_substep, max_substeps, stop2, True, _NO_DOMAIN, 0.0)
        n_evals += n
        e2 = x1 * x1 + x2 * x2
        if e2 > e2max:
            e2max = e2
        if status != OK:
            break
        if (step + 1) % record_every == 0:
            n_rec = _record(out_t, out_x, out_v, n_rec, t, x1, x2, v1, v2)
    if status != OK:
        # last valid state, so the trajectory ends where it stopped
        n_rec = _record(out_t, out_x, out_v, n_rec, t, x1, x2, v1, v2)
    return n_rec, status, t, n_evals, x1, x2, v1, v2, e2max


# Dormand-Prince 5(4): nodes, stage matrix, 5th-order weights and (5th - 4th)-order error weights
_DP_C = np.array([0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0])
_DP_A = np.array([
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [0.2, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0, 0.0],
    [9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0, 0.0],
    [35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0]])
_DP_E = np.array([71.0 / 57600.0, 0.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0, 22.0 / 525.0,
                  -1.0 / 40.0])


@njit(cache=True)
def _deriv(kernel, params, consts, y, t, out):
    """out = dy/dt of y = (x1, x2, v1, v2) at t; False where the state lies outside the clearance."""
    a1, a2, inside = _acceleration(kernel, params, y[0], y[1], y[2], y[3], t, consts)
    out[0] = y[2]
    out[1] = y[3]
    out[2] = a1
    out[3] = a2
    return inside


@njit(cache=True)
def _dp45_run(kernel, params, consts, x0, v0, t_start, h, j0, j1, out_times, rtol, atol_x, atol_v, eps_stop,
              h_min, out_t, out_x, out_v, n_rec):
    """Adaptive Dormand-Prince 5(4) from (x0, v0) at ``t_start`` through the output times ``out_times[j0:j1]``,
    recording the state at each (the step is shortened to land on it).  Error control per step: the RMS over
    the four components of err_i / (atol_i + rtol max(|y_i|, |y_new_i|)) at most 1 (atol_x for positions,
    atol_v for velocities); a rejected step or an RK stage outside the clearance or a non-finite state
    shortens the step, and a step below ``h_min`` stops the run (CONTACT_STAGE / NONFINITE).  The first
    stage is recomputed at entry (no first-same-as-last across calls), so a run in chunks equals one call.

    Returns (n_recorded, status, t, n_force_evals, x1, x2, v1, v2, h_next, e2max, n_accepted, n_rejected).
    """
    stop2 = eps_stop * eps_stop * consts[6]
    y = np.empty(4)
    y[0], y[1], y[2], y[3] = x0[0], x0[1], v0[0], v0[1]
    k = np.empty((7, 4))
    ys = np.empty(4)
    yn = np.empty(4)
    t = t_start
    n_evals = 1
    e2max = 0.0
    n_acc = 0
    n_rej = 0
    status = OK
    _deriv(kernel, params, consts, y, t, k[0])
    j = j0
    while j < j1:
        target = out_times[j]
        step = h
        hit = False
        if t + step >= target:
            step = target - t
            hit = True
        inside = True
        for s in range(1, 7):
            for i in range(4):
                acc = 0.0
                for q in range(s):
                    acc += _DP_A[s, q] * k[q, i]
                ys[i] = y[i] + step * acc
            n_evals += 1
            if not _deriv(kernel, params, consts, ys, t + _DP_C[s] * step, k[s]):
                inside = False
                break
        finite = True
        err = 0.0
        if inside:
            for i in range(4):
                yn[i] = ys[i]  # stage 7 is evaluated at the 5th-order solution (FSAL)
                e = 0.0
                for q in range(7):
                    e += _DP_E[q] * k[q, i]
                e *= step
                sc = (atol_x if i < 2 else atol_v) + rtol * max(abs(y[i]), abs(yn[i]))
                err += (e / sc) ** 2
                if not (math.isfinite(yn[i]) and math.isfinite(e)):
                    finite = False
            err = math.sqrt(err / 4.0)
        if not inside or not finite:
            n_rej += 1
            h = 0.25 * step
            if h < h_min:
                status = CONTACT_STAGE if not inside else NONFINITE
                break
            continue
        if err > 1.0:
            n_rej += 1
            h = step * max(0.2, 0.9 * err ** -0.2)
            if h < h_min:
                status = NONFINITE
                break
            continue
        n_acc += 1
        factor = 5.0 if err == 0.0 else min(5.0, max(0.2, 0.9 * err ** -0.2))
        if not hit:
            h = step * factor
        elif step * factor > h:
            h = step * factor
        t = target if hit else t + step
        for i in range(4):
            y[i] = yn[i]
            k[0, i] = k[6, i]
        e2 = y[0] * y[0] + y[1] * y[1]
        if e2 > e2max:
            e2max = e2
        if e2 >= stop2:
            status = CONTACT
            break
        if hit:
            n_rec = _record(out_t, out_x, out_v, n_rec, t, y[0], y[1], y[2], y[3])
            j += 1
    if status != OK:
        n_rec = _record(out_t, out_x, out_v, n_rec, t, y[0], y[1], y[2], y[3])
    return n_rec, status, t, n_evals, y[0], y[1], y[2], y[3], h, e2max, n_acc, n_rej


@njit
def schedule_at(times, omegas, cum, w_ref, t):
    """(omega, d omega/dt, integral from 0 to t of (omega - w_ref)) of the piecewise-linear speed table at t.

    ``cum[k]``: the integral up to ``times[k]`` (``_schedule_arrays``).  The rotation angle is
    w_ref t + the integral: for a schedule that stays at w_ref the integral is 0.0 exactly, so the angle
    is w_ref t to the bit, as in the constant-speed loop.
    """
    n = times.shape[0]
    if t <= times[0]:
        w = omegas[0]
        return w, 0.0, cum[0] + (w - w_ref) * (t - times[0])
    if t >= times[n - 1]:
        w = omegas[n - 1]
        return w, 0.0, cum[n - 1] + (w - w_ref) * (t - times[n - 1])
    k = np.searchsorted(times, t, side="right") - 1
    a = (omegas[k + 1] - omegas[k]) / (times[k + 1] - times[k])
    d = t - times[k]
    return omegas[k] + a * d, a, cum[k] + (omegas[k] - w_ref) * d + 0.5 * a * d * d


# not cached: the speed kernels' types (a surrogate's kernel inside its parameters) must not reach numba's cache
@njit
def _acceleration_speed(kernel, params, x1, x2, v1, v2, t, consts):
    """``_acceleration`` at the scheduled speed: ``kernel(params, omega, x1, x2, v1, v2)`` is the film force at
    shaft speed omega (``core.force_model.SpeedScalableModel``); the imbalance turns through phi(t) = integral
    of omega, with omega(t)^2 and the angular acceleration's tangential term (module doc)."""
    inv_m, unb, w_ref, sgn, g1, g2, c2, unb_final, ramp_time, times, omegas, cum = consts
    if x1 * x1 + x2 * x2 >= c2:
        return 0.0, 0.0, False
    w, alpha, corr = schedule_at(times, omegas, cum, w_ref, t)
    f1, f2 = kernel(params, w, x1, x2, v1, v2)
    if ramp_time > 0.0:
        unb = _ramped(unb, unb_final, t, ramp_time)
    # unb = m_u d w_ref^2: the imbalance force m_u d (omega^2 e_r + alpha e_t) in units of it
    s = w / w_ref
    s2 = s * s
    an = alpha / (w_ref * w_ref)
    ph = w_ref * t + corr
    cph = math.cos(ph)
    sph = math.sin(ph)
    return (f1 + unb * (s2 * cph + an * sph) + g1) * inv_m, (f2 + sgn * unb * (s2 * sph - an * cph) + g2) * inv_m, True


# Models from outside the library (a user's script, a notebook) get an uncached twin of the loop:
# numba's on-disk cache of ``_rk4_run`` records the argument types, and a kernel or parameter type
# defined in a module that a later process cannot import would make that cache unreadable.
def _uncached(dispatcher, **replace):
    """A non-caching copy of a compiled function (its other options kept), its global names in ``replace`` swapped."""
    fn = dispatcher.py_func
    glb = dict(fn.__globals__, **replace)
    options = {k: v for k, v in dispatcher.targetoptions.items() if k != "nopython"}  # njit sets it itself
    return njit(**options)(types.FunctionType(fn.__code__, glb, fn.__name__, fn.__defaults__,
                                                                fn.__closure__))


# the step inlined into a loop takes the globals of its own module: its twin calls the uncached acceleration
_rk4_step_uncached = _uncached(_rk4_step, _acceleration=_uncached(_acceleration))
_rk4_run_uncached = _uncached(_rk4_run, _rk4_step=_rk4_step_uncached)
# the same loop and step at a scheduled speed: only the acceleration differs (uncached, as above)
_rk4_run_speed = _uncached(_rk4_run, _rk4_step=_uncached(_rk4_step, _acceleration=_acceleration_speed))
# the adaptive loop's twins, the same way
_dp45_run_uncached = _uncached(_dp45_run, _deriv=_uncached(_deriv, _acceleration=_uncached(_acceleration)))
_dp45_run_speed = _uncached(_dp45_run, _deriv=_uncached(_deriv, _acceleration=_acceleration_speed))


def _holds_functions(params) -> bool:
    """True where the parameters carry compiled functions (an ensemble's members' kernels).

    Numba keys a cached specialisation by its argument types, and types of compiled functions refer to
    their dispatchers weakly; once, after an ensemble had run through the cached loop, a later process
    could not write that loop's cache index back ("ReferenceError: underlying object has vanished") and
    the simulation failed.  The sequence was not reproduced in isolation; such parameters take the
    uncached twins, as models from outside the library do."""
    if isinstance(params, Dispatcher):
        return True
    return isinstance(params, tuple) and any(_holds_functions(p) for p in params)


def run_loop(cached, uncached, kernel, params, *args):
    """Run the integrator's compiled loop: the cached one for the library's kernels (``_library_types``), the
    uncached twin otherwise, and the uncached twin as well where numba cannot write its cache index back.

    Numba keys a cached specialisation by its argument types, and a kernel argument's type refers to its
    dispatcher weakly: a later process that adds a specialisation to an index holding such keys re-pickles
    them, and a key whose dispatcher that process does not hold raises ``ReferenceError: underlying object
    has vanished`` (seen with a workspace's cache filled by many pipeline processes). The loop itself had
    compiled; only the cache write failed, so the same loop compiled without the cache gives the same
    trajectory."""
    if not _library_types(kernel, params):
        return uncached(kernel, params, *args)
    try:
        return cached(kernel, params, *args)
    except ReferenceError as err:
        warnings.warn(f"numba could not update its on-disk cache of the integrator loop ({err}); this process "
                      "compiles the loop without the cache (same arithmetic)", RuntimeWarning, stacklevel=3)
        return uncached(kernel, params, *args)


def _library_types(kernel, params) -> bool:
    """Whether the cached compiled loops may take this kernel: the library's own kernels and parameter
    types, without compiled functions inside the parameters."""
    fn = getattr(kernel, "py_func", kernel)
    return fn.__module__.split(".")[0] == "fluidfilm" and \
        type(params).__module__.split(".")[0] in ("fluidfilm", "builtins") and not _holds_functions(params)


def _is_real(value) -> bool:
    return not isinstance(value, (bool, np.bool_)) and isinstance(value, (int, float, np.integer, np.floating))


def check_run_args(t_end, dt, t0, eps_stop, eps_substep, record_every, max_substeps) -> int:
    """The checks of ``simulate`` and ``simulate_batch`` (one place): each argument by name, a bool or a
    string refused as not a number.  Returns the number of steps, round((t_end - t0) / dt)."""
    if not (_is_real(t0) and math.isfinite(t0)):
        raise ValueError(f"t0 must be a finite time in s, got {t0!r}")
    if not (_is_real(dt) and math.isfinite(dt) and dt > 0.0):
        raise ValueError(f"dt must be a positive finite time in s, got {dt!r}")
    if not (_is_real(t_end) and math.isfinite(t_end) and t_end > t0):
        raise ValueError(f"t_end must be a finite end time in s after t0={t0!r} (t_end is the time the run ends, "
                         f"not its duration), got {t_end!r}")
    if dt > t_end - t0:
        raise ValueError(f"dt={dt!r} s is longer than the run from t0={t0!r} s to t_end={t_end!r} s")
    for name, value in (("eps_stop", eps_stop), ("eps_substep", eps_substep)):
        if not _is_real(value):
            raise ValueError(f"{name} must be a number, got {value!r}")
    if not 0.0 < eps_stop < 1.0:
        raise ValueError(f"eps_stop must lie in (0, 1), got {eps_stop!r}")
    if not 0.0 < eps_substep < 1.0:
        raise ValueError(f"eps_substep must lie in (0, 1), got {eps_substep!r}")
    for name, value in (("record_every", record_every), ("max_substeps", max_substeps)):
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < 1:
            raise ValueError(f"{name} must be a positive integer, got {value!r}")
    return int(round((t_end - t0) / dt))


def _schedule_arrays(speed: SpeedSchedule, w_ref: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(times, omegas, cum) of ``schedule_at``: cum[k] = integral from 0 to times[k] of (omega - w_ref)."""
    times, w = speed.times.copy(), speed.omega.copy()
    cum = np.zeros_like(w)  # first from times[0], then shifted to start at t = 0
    for k in range(1, w.size):
        cum[k] = cum[k - 1] + 0.5 * ((w[k - 1] - w_ref) + (w[k] - w_ref)) * (times[k] - times[k - 1])
    at_zero = schedule_at(times, w, cum, w_ref, 0.0)[2]
    return times, w, cum - at_zero


def _speed_kernel(model: ForceModel, speed: SpeedSchedule | None):
    """``(fn, params)`` of the model's force at any speed for a schedule, None to run at the bearing's speed
    (no schedule, or a constant one at that speed for a model without speed-scaled forces); refuses a
    schedule that leaves the bearing's speed for a model that cannot follow it, naming the speeds."""
    if speed is None:
        return None
    if not isinstance(speed, SpeedSchedule):
        raise ValueError(f"speed must be a SpeedSchedule (SpeedSchedule.ramp, .table or .constant), got "
                         f"{type(speed).__name__}")
    kernel = model.speed_kernel() if isinstance(model, SpeedScalableModel) else None
    if kernel is not None:
        return kernel
    own = float(model.bearing.omega)
    if bool((speed.omega == own).all()):
        return None
    lo, hi = float(speed.omega.min()) / RPM, float(speed.omega.max()) / RPM
    asked = f"{lo:.6g} rpm" if lo == hi else f"{lo:.6g}-{hi:.6g} rpm"
    raise ValueError(f"{model.name} gives forces at its bearing's speed only, {own / RPM:.6g} rpm, and the speed "
                     f"schedule asks {asked}: its force does not scale exactly with speed. Speed schedules take "
                     "the Reynolds solver, LinearBearing and surrogates in the 'whirl' frame "
                     "(fluidfilm.core.SpeedScalableModel)")


@dataclass(frozen=True)
class StepLimit:
    """The largest RK4 step that resolves a run at one state (``rk4_step_limit``).

    Parameters
    ----------
    dt_max : float
        Largest safe step [s] (``inf`` where nothing limits it).
    rule : str
        The rule that sets it, in words (with the time scale it resolves).
    eigenvalues : ndarray, shape (4,)
        Eigenvalues [1/s] of the linearised film-rotor system at the state.
    substeps : int
        The substeps ``simulate`` splits a step into at this eccentricity (``eps_substep``).
    """

    dt_max: float
    rule: str
    eigenvalues: np.ndarray
    substeps: int


def film_eigenvalues(force, x, v, inv_mass: float, clearance: float, omega: float) -> np.ndarray:
    """Eigenvalues [1/s] of the film-rotor system linearised at the state (x, v).

    K = -dF/dX and C = -dF/dV by central differences of ``force(x1, x2, v1, v2) -> (F1, F2)`` (8 force
    evaluations, steps 1e-4 c and 1e-4 c max(omega, 1/s)); the system d(X, V)/dt = (V, -(K X + C V)/m).

    Parameters
    ----------
    force : callable
        ``force(x1, x2, v1, v2) -> (F1, F2)`` [N] (a model's compiled kernel with its parameters bound).
    x, v : array_like, shape (2,)
        Position [m] and velocity [m/s].
    inv_mass : float
        1 / rotor mass [1/kg].
    clearance : float
        Radial clearance [m].
    omega : float
        Shaft angular speed [rad/s] (scales the velocity step).

    Returns
    -------
    ndarray, shape (4,), complex
    """
    def forces(xs, vs):
        return np.array([force(xs[i, 0], xs[i, 1], vs[i, 0], vs[i, 1]) for i in range(xs.shape[0])], dtype=float)

    return film_eigenvalues_many(forces, np.array([[float(x[0]), float(x[1])]]), np.array([[float(v[0]), float(v[1])]]),
                                 np.array([inv_mass]), np.array([clearance]), omega)[0]


def film_eigenvalues_many(forces, X, V, inv_mass, clearance, omega: float) -> np.ndarray:
    """``film_eigenvalues`` of M states at once: ``forces(xs, vs) -> fs`` evaluates (8M, 2) states [m], [m/s]
    into forces (8M, 2) [N] (a batched kernel; the perturbed states of state i are rows 8i..8i+7);
    X, V (M, 2); ``inv_mass``, ``clearance`` (M,).  Returns (M, 4) complex, NaN where a force is not finite."""
    m = X.shape[0]
    hx = 1e-4 * np.asarray(clearance, dtype=float)
    hv = hx * max(omega, 1.0)
    xs = np.repeat(X, 8, axis=0).reshape(m, 8, 2)
    vs = np.repeat(V, 8, axis=0).reshape(m, 8, 2)
    for j in range(4):  # rows 2j, 2j+1: + and - the step in component j (x1, x2, v1, v2)
        arr, comp, h = (xs, j, hx) if j < 2 else (vs, j - 2, hv)
        arr[:, 2 * j, comp] = arr[:, 2 * j, comp] + h
        arr[:, 2 * j + 1, comp] = arr[:, 2 * j + 1, comp] - h
    fs = np.asarray(forces(xs.reshape(8 * m, 2), vs.reshape(8 * m, 2)), dtype=float).reshape(m, 8, 2)
    jac = np.zeros((m, 4, 4))
    jac[:, 0, 2] = jac[:, 1, 3] = 1.0
    for j in range(4):
        h = hx if j < 2 else hv
        jac[:, 2, j] = (fs[:, 2 * j, 0] - fs[:, 2 * j + 1, 0]) / (2.0 * h) * inv_mass
        jac[:, 3, j] = (fs[:, 2 * j, 1] - fs[:, 2 * j + 1, 1]) / (2.0 * h) * inv_mass
    lam = np.full((m, 4), np.nan + 0j)
    good = np.isfinite(jac).all(axis=(1, 2))
    if good.any():
        lam[good] = np.linalg.eigvals(jac[good])
    return lam


def rk4_step_limit(force, x, v, inv_mass: float, clearance: float, omega_max: float, eps_substep: float = 0.8,
                   max_substeps: int = 256) -> StepLimit:
    """The largest RK4 step of ``simulate`` that resolves the run at the state (x, v).

    Three rules, the smallest step wins: (1) RK4 stability with a safety factor of 2, |lambda| h <=
    ``RK4_LAMBDA_DT`` = 1.4 for every eigenvalue of the linearised film-rotor system (``film_eigenvalues``)
    with h = dt / k the substep at this eccentricity (``eps_substep``); (2) ``STEPS_PER_PERIOD`` = 20
    substeps per period 2 pi / |Im lambda| of each oscillating mode; (3) 20 steps per shaft revolution
    at the largest speed ``omega_max`` (the imbalance's period).

    Parameters
    ----------
    force : callable
        ``force(x1, x2, v1, v2) -> (F1, F2)`` [N].
    x, v : array_like, shape (2,)
        The state [m], [m/s].
    inv_mass : float
        1 / rotor mass [1/kg].
    clearance : float
        Radial clearance [m].
    omega_max : float
        Largest shaft angular speed of the run [rad/s] (0: a shaft at rest, no revolution rule).
    eps_substep, max_substeps
        As ``simulate``.

    Returns
    -------
    StepLimit
    """
    lam = film_eigenvalues(force, x, v, inv_mass, clearance, omega_max)
    e2 = (float(x[0]) ** 2 + float(x[1]) ** 2) / clearance**2
    k, steps = step_limits(lam[None, :], np.array([e2]), omega_max, eps_substep, max_substeps)
    rate = float(np.abs(lam).max()) if np.isfinite(lam).all() else 0.0
    osc = float(np.abs(lam.imag).max()) if np.isfinite(lam).all() else 0.0
    words = (f"RK4 stability |lambda dt| <= {RK4_LAMBDA_DT} (2.8 with a safety factor 2) for the film's fastest "
             f"rate |lambda| = {rate:.4g} 1/s" + (f" in {int(k[0])} substeps" if k[0] > 1 else ""),
             f"{STEPS_PER_PERIOD} steps per period of the film-rotor oscillation at {osc / (2 * math.pi):.4g} Hz",
             f"{STEPS_PER_PERIOD} steps per shaft revolution at {omega_max / RPM:.6g} rpm")
    rule = int(np.argmin(steps[0]))
    if not np.isfinite(steps[0, rule]):
        return StepLimit(math.inf, "nothing limits the step", lam, int(k[0]))
    return StepLimit(float(steps[0, rule]), words[rule], lam, int(k[0]))


def step_limits(lam: np.ndarray, e2: np.ndarray, omega_max: float, eps_substep: float,
                max_substeps: int) -> tuple[np.ndarray, np.ndarray]:
    """``rk4_step_limit``'s rules for M states at once: (substeps (M,), steps (M, 3)), the largest step of
    each rule (stability, oscillation, revolution; ``inf`` where it does not apply), from the eigenvalues
    ``lam`` (M, 4) and the squared eccentricities ``e2`` (M,).  The largest safe step is ``steps.min(1)``."""
    k = np.ones(e2.shape, dtype=np.int64)
    far = e2 > eps_substep**2
    k[far] = np.minimum(np.ceil(((1.0 - eps_substep**2) / (1.0 - e2[far])) ** 1.5), max_substeps).astype(np.int64)
    steps = np.full(e2.shape + (3,), math.inf)
    finite = np.isfinite(lam).all(axis=-1)
    with np.errstate(divide="ignore"):
        rate = np.where(finite, np.abs(lam).max(axis=-1, initial=0.0), 0.0)
        osc = np.where(finite, np.abs(lam.imag).max(axis=-1, initial=0.0), 0.0)
        steps[..., 0] = np.where(rate > 0.0, k * RK4_LAMBDA_DT / rate, math.inf)
        steps[..., 1] = np.where(osc > 0.0, k * 2.0 * math.pi / (STEPS_PER_PERIOD * osc), math.inf)
    if omega_max > 0.0:
        steps[..., 2] = 2.0 * math.pi / (STEPS_PER_PERIOD * omega_max)
    return k, steps


def _force_at(kernel, params, speed_kernel, consts_speed, omega_ref):
    """``force(t) -> force(x1, x2, v1, v2)``: the model's compiled kernel at the speed of time t."""
    if speed_kernel is None:
        def at_constant(t):
            return lambda x1, x2, v1, v2: kernel(params, x1, x2, v1, v2)
        return at_constant
    fn, sparams = speed_kernel
    times, omegas, cum = consts_speed[-3:]

    def at_speed(t):
        w = schedule_at(times, omegas, cum, omega_ref, t)[0]
        return lambda x1, x2, v1, v2: fn(sparams, w, x1, x2, v1, v2)
    return at_speed


def _integer_arrays(params, out: list) -> list:
    """Every integer ndarray inside ``params`` (tuples and named tuples, nested): a model's counters."""
    if isinstance(params, np.ndarray):
        if params.dtype.kind in "iu":
            out.append(params)
    elif isinstance(params, tuple):
        for p in params:
            _integer_arrays(p, out)
    return out


def _counted(model, fn, *param_sets):
    """Run ``fn()`` with the model's counters kept as they were, and return (its value, force evaluations it
    added to the model's domain counter, 0 where the counters live in ``param_sets``): the step checks'
    evaluations must count neither as the trajectory's domain evaluations nor as an ensemble's or a hybrid's
    evaluations, flags and fallbacks.  The counters are the integer arrays of the kernels' parameters
    (evaluating a kernel changes no other integer array, so restoring them all restores the counts)."""
    arrays = _integer_arrays(param_sets, [])
    saved = [a.copy() for a in arrays]
    before = int(model.n_outside_domain)
    try:
        value = fn()
    finally:
        for a, keep in zip(arrays, saved):
            a[...] = keep
    # what is still counted after the restore (a model whose counter lives outside its kernel's parameters)
    return value, int(model.n_outside_domain) - before


def _progress_bar(progress, total: int, what: str):
    """A tqdm bar on stderr, or None.  ``progress`` None: on where stderr is a terminal and ``CI`` is unset,
    shown only once the run has taken 2 s (tqdm's ``delay``); True: always (still after 2 s); False: off."""
    import os
    import sys

    if progress is None:
        progress = sys.stderr is not None and sys.stderr.isatty() and not os.environ.get("CI")
    elif not isinstance(progress, (bool, np.bool_)):
        raise ValueError(f"progress must be True, False or None, got {progress!r}")
    if not progress:
        return None
    from tqdm.auto import tqdm

    return tqdm(total=total, desc=what, unit="step", delay=2.0, file=sys.stderr, leave=False)


def _domain_note(model, n_outside: int, n_evals: int, e2max: float, c: float) -> str | None:
    """The status note of evaluations outside the model's domain: the count (the words of item 8 in
    docs/guarantees.md), the share of the run's evaluations and the largest eccentricity reached."""
    if n_outside <= 0:
        return model.domain_report()  # a model that reports without counting keeps its own note
    share = 100.0 * n_outside / max(n_evals, 1)
    return (f"outside the training domain in {n_outside} force evaluations ({share:.3g} % of {n_evals}), "
            f"largest eccentricity {math.sqrt(e2max) / c:.4g} (domain eps <= {model.validity.eps_max:g})")


def simulate(model: ForceModel, rotor: Rotor, t_end: float, dt: float | None = 1e-5, x0=None, v0=None, *,
             eps_stop: float = 0.98, record_every: int = 1, eps_substep: float = 0.8,
             max_substeps: int = 256, t0: float = 0.0, speed: SpeedSchedule | None = None,
             precision: str = "float64", check_step: bool = True, rtol: float = 1e-6, atol: float | None = None,
             record_dt: float | None = None, strict: bool = False, progress: bool | None = None,
             film_content=None) -> Trajectory:
    """Integrate the rotor in ``model`` (a ``fluidfilm.core.force_model.ForceModel``: its compiled ``force_kernel``).

    Fixed-step RK4 of m dV/dt = F_film(X, V) + imbalance + m g (along +X2) + F_ext (module doc);
    starts at the bearing centre at rest unless ``x0``/``v0`` are given.  The run stops early, with
    ``status`` saying why and when, at contact (eps reaching ``eps_stop``) or a non-finite state.

    Parameters
    ----------
    model : ForceModel
        The bearing's force model.
    rotor : Rotor
        What the bearing carries (mass, imbalance, external force, gravity).
    t_end : float
        The END TIME [s] of the run (absolute, not a duration): the run goes from ``t0`` to
        ``t_end`` in round((t_end - t0) / dt) steps.
    dt : float or None, default 1e-5
        RK4 step [s], at most the run's length; it must resolve the run (``check_step``).  None: the
        adaptive Dormand-Prince 5(4) integrator with error control (``rtol``, ``atol``) chooses its
        steps, recording every ``record_dt``.
    x0, v0 : array_like, shape (2,), optional
        Initial position [m] (eccentricity below ``eps_stop``) and velocity [m/s].
    eps_stop : float, default 0.98
        Eccentricity ratio in (0, 1) that ends the run as a contact.
    record_every : int, default 1
        Every ``record_every``-th step is recorded (a positive integer).
    eps_substep : float, default 0.8
        Eccentricity ratio above which steps are split into substeps (module doc).
    max_substeps : int, default 256
        Largest number of substeps per step.
    t0 : float, default 0.0
        Start time [s] (the imbalance phase and ramp run on absolute time).
    speed : SpeedSchedule or None, default None
        The shaft speed against time (a run-up or run-down, ``rotor.model.SpeedSchedule``); None: the
        bearing's own speed throughout.  The film force at each RK4 stage is the model's at the speed of
        that instant (``core.force_model.SpeedScalableModel``: the Reynolds solver through its own speed
        parameter, a surrogate in the 'whirl' frame by its exact speed scaling); a model that gives forces
        at its bearing's speed only is refused for any other speed.
    precision : {"float64", "float32"}, default "float64"
        The arithmetic of a surrogate's networks (``core.force_model.PrecisionKernelModel``): "float32"
        runs them in single precision (forces within 1e-5 of float64 relative to the larger of |F| and the states' RMS force; the integrator, frame and
        gains stay float64), at constant speed only.  A model without float32 networks (a reference
        solver, an ensemble) computes in float64 either way; the trajectory's ``meta["precision"]`` says
        which ran.
    check_step : bool, default True
        Refuse a fixed ``dt`` that cannot resolve the run, with a ValueError naming ``dt`` and the largest
        safe step (``rk4_step_limit``: RK4 stability for the fastest eigenvalue of the film-rotor system
        linearised at the start state, 20 steps per period of its oscillations and per shaft revolution),
        and re-check at the end of every chunk of steps along the run: where the step stops resolving the
        film, the run ends with status "unresolved: ..." (``traj.ok`` False).  False (for experts, e.g. to
        study the integrator itself): no check.
    rtol, atol : float
        The adaptive integrator's tolerances (``dt=None``): relative, and absolute in units of the
        clearance c for positions and c omega for velocities (None: ``rtol``); positive and finite.
    record_dt : float or None, default None
        The adaptive integrator's output interval [s] (``dt=None``); None: (t_end - t0) / 1000.  The step
        lands on every output time.
    strict : bool, default False
        Raise ``OutsideDomainError`` (naming the share of evaluations and the largest eccentricity) where
        the run's forces left the model's validity domain, instead of the warning and the
        "outside-domain: ..." status.
    progress : bool or None, default None
        A tqdm bar on stderr (shown once the run has taken 2 s); None: only where stderr is a terminal and
        the environment variable ``CI`` is unset.  The run goes in chunks of steps either way, and the
        trajectory does not depend on them to the bit.
    film_content : array_like or None, default None
        A film with memory only (``core.force_model.TransientFilmModel``, mass-conserving cavitation): the
        film content (n_theta, n_z) at t0, e.g. ``meta["film_content"]`` of a previous run to continue it;
        None: the steady film at x0.  Such a model runs in ``rotor.film_memory``'s loop, which carries the
        content between RK4 steps.

    Returns
    -------
    Trajectory
        The recorded states, ``status`` ("ok", "outside-domain: ...", "contact: ...", "diverged: ...",
        "unresolved: ..."), force evaluations and wall time.  A run whose forces left the model's domain
        is not ``ok`` (``completed`` is True) and warns once, naming the share and the largest eccentricity.

    Raises
    ------
    ValueError
        Naming the argument: a rotor that is not a ``Rotor``, a model that is not a force model,
        times or settings that are not finite positive numbers of the right kind, an initial state
        of the wrong shape, non-finite, or not below ``eps_stop``; a ``speed`` schedule that is not a
        ``SpeedSchedule``, or that leaves the bearing's speed for a model without speed-scaled forces
        (naming the model and the speeds); a ``precision`` other than "float64"/"float32", or "float32"
        networks with a speed schedule; a ``dt`` that cannot resolve the run (naming it and the largest
        safe step, with ``check_step``).
    OutsideDomainError
        With ``strict=True``, where force evaluations left the model's domain.

    Examples
    --------
    A spring-damper under the rotor's weight settles at m g / K = 2.4525e-5 m:

    >>> from fluidfilm import LinearBearing, Rotor, paper_bearing, simulate
    >>> spring = LinearBearing(paper_bearing(), stiffness=1e6, damping=1e3)
    >>> traj = simulate(spring, Rotor(mass=2.5), t_end=0.05, dt=1e-5, record_every=100)
    >>> traj.status, len(traj.t), f"{traj.x[-1, 1]:.4g}"
    ('ok', 51, '2.453e-05')
    >>> simulate(spring, Rotor(mass=2.5, external_force=(0.0, 1e3)), t_end=0.05).status
    'contact: eccentricity reached eps_stop=0.98 at t=0.0008075 s'
    """
    if not isinstance(rotor, Rotor):
        raise ValueError(f"rotor must be a Rotor, got {type(rotor).__name__}")
    if not isinstance(model, ForceModel):
        raise ValueError(f"{type(model).__name__} is not a force model (fluidfilm.core.force_model.ForceModel: forces, "
                         "force_kernel, bearing, clearance, validity, domain report); the integrator needs one")
    if film_content is not None and not isinstance(model, TransientFilmModel):
        raise ValueError(f"film_content is the state of a film with memory; {model.name} has none")
    if isinstance(model, TransientFilmModel):
        # a film with memory (mass-conserving cavitation): its content is state, integrated in its own loop
        from fluidfilm.rotor.film_memory import simulate_film

        if precision not in ("float64", "float32"):
            raise ValueError(f"precision must be 'float64' or 'float32', got {precision!r}")
        if dt is None:
            raise ValueError("dt=None (the adaptive integrator) does not carry a film's content; give a film with "
                             "memory a fixed dt")
        if not isinstance(check_step, (bool, np.bool_)):
            raise ValueError(f"check_step must be True or False, got {check_step!r}")
        if check_step:
            _check_film_step(model, rotor, dt, x0, v0, t0, speed, eps_substep, max_substeps)
        return simulate_film(model, rotor, t_end, dt, x0, v0, eps_stop=eps_stop, record_every=record_every,
                             eps_substep=eps_substep, max_substeps=max_substeps, t0=t0, speed=speed,
                             film_content=film_content, strict=strict)
    # precision: what the networks actually run in (a model without float32 networks computes in float64)
    kernel, params, precision = one_state_kernel(model, precision)
    if precision == "float32" and speed is not None:
        raise ValueError("precision='float32' runs at constant speed only; a speed schedule takes float64")
    bearing = model.bearing
    # an active bearing reports the clearance of its current control setting
    c = float(model.clearance)
    adaptive = dt is None
    if adaptive:
        record_dt = _check_adaptive_args(t_end, t0, rtol, atol, record_dt)
        n_steps = check_run_args(t_end, record_dt, t0, eps_stop, eps_substep, record_every, max_substeps)
    else:
        n_steps = check_run_args(t_end, dt, t0, eps_stop, eps_substep, record_every, max_substeps)
    if not isinstance(check_step, (bool, np.bool_)):
        raise ValueError(f"check_step must be True or False, got {check_step!r}")
    for name, value in (("x0", x0), ("v0", v0)):
        if value is not None and np.shape(value) != (2,):
            raise ValueError(f"{name} must be a pair ({name[0].upper()}1, {name[0].upper()}2), got shape {np.shape(value)}")
    x0 = np.zeros(2) if x0 is None else np.asarray(x0, dtype=float).reshape(2)
    v0 = np.zeros(2) if v0 is None else np.asarray(v0, dtype=float).reshape(2)
    if not (np.isfinite(x0).all() and np.isfinite(v0).all()):
        raise ValueError(f"initial state must be finite, got x0={tuple(x0)}, v0={tuple(v0)}")
    if np.hypot(*x0) >= eps_stop * c:
        raise ValueError(f"initial eccentricity {np.hypot(*x0) / c:.4g} is not below eps_stop={eps_stop}")
    record_every = int(record_every)
    omega = bearing.omega
    u_final = rotor.imbalance if rotor.imbalance_final is None else rotor.imbalance_final
    consts = (1.0 / rotor.mass, rotor.imbalance * omega**2, omega, float(rotor.imbalance_direction),
              rotor.external_force[0], rotor.external_force[1] + rotor.mass * rotor.gravity, c * c,
              u_final * omega**2, rotor.ramp_time if rotor.imbalance_final is not None else 0.0)
    meta: dict = {"dt": dt, "t0": t0, "t_end": t_end, "record_every": record_every, "precision": precision}
    speed_kernel = _speed_kernel(model, speed)
    run_consts: tuple = consts
    if speed_kernel is not None:
        assert speed is not None
        run_consts = consts + _schedule_arrays(speed, omega)
        meta["speed"] = {"times": speed.times.tolist(), "omega": speed.omega.tolist()}
    force_at = _force_at(kernel, params, speed_kernel, run_consts, omega)
    omega_max = float(omega) if speed is None else float(np.abs(speed.omega).max())

    def limit_at(x, v, t) -> StepLimit:
        return rk4_step_limit(force_at(t), x, v, consts[0], c, omega_max, eps_substep, max_substeps)

    start_limit = None
    if check_step or adaptive:
        start_limit = limit_at(x0, v0, float(t0))
        if check_step and dt is not None and dt > start_limit.dt_max * (1.0 + 1e-9):
            raise ValueError(
                f"dt={dt!r} s cannot resolve this run: the largest safe step is {start_limit.dt_max:.3g} s at the "
                f"start state (eccentricity {np.hypot(*x0) / c:.3g}; rule: {start_limit.rule}). Use dt <= "
                f"{start_limit.dt_max:.3g}, dt=None for the adaptive integrator, or check_step=False (experts)")
    model.reset_domain_counter()
    if adaptive:
        assert record_dt is not None and start_limit is not None
        run = _run_adaptive(model, kernel, params, speed_kernel, run_consts, x0, v0, float(t0), float(t_end),
                            float(record_dt), float(rtol), float(rtol if atol is None else atol), c,
                            max(omega_max, 1.0), float(eps_stop), start_limit, progress)
        meta.update({"method": "dormand-prince-5(4)", "rtol": rtol, "atol": rtol if atol is None else atol,
                     "record_dt": record_dt, "n_accepted": run["n_acc"], "n_rejected": run["n_rej"]})
    else:
        assert dt is not None
        run = _run_fixed(model, kernel, params, speed_kernel, run_consts, x0, v0, float(t0), float(dt), n_steps,
                         record_every, float(eps_stop), float(eps_substep), int(max_substeps),
                         limit_at if check_step else None, progress)
        meta["method"] = "rk4"
    status, t_stop, n_evals = run["status"], run["t_stop"], run["n_evals"]
    if status == OK:
        text, t_stop = "ok", None
    elif status in (CONTACT, CONTACT_STAGE):
        text = f"contact: eccentricity reached eps_stop={eps_stop} at t={t_stop:.6g} s"
    elif status == UNRESOLVED:
        text = unresolved_text(t_stop, np.hypot(*run['x_stop']) / c, dt, run["limit"], "dt=None (adaptive)")
    else:
        text = f"diverged: non-finite state after t={t_stop:.6g} s"
    n_outside = max(int(model.n_outside_domain) - run["check_outside"], 0)
    e2max = max(run["e2max"], float(x0 @ x0))
    if hasattr(model, "check_grid"):  # a reference solver warns once where its grid is too coarse for the run
        model.check_grid(math.sqrt(e2max) / c)
    note = _domain_note(model, n_outside, n_evals, e2max, c)
    if note:
        if strict:
            raise OutsideDomainError(f"{model.name}: {note} during the simulation (strict=True)")
        text = f"{OUTSIDE_DOMAIN}: reached the end time; {note}" if text == "ok" and n_outside > 0 else \
            f"{text}; {note}"
        warnings.warn(f"{model.name}: {note} during the simulation", RuntimeWarning, stacklevel=2)
    n_rec = run["n_rec"]
    out_t, out_x, out_v = run["out"]
    return Trajectory(t=out_t[:n_rec].copy(), x=out_x[:n_rec].copy(), v=out_v[:n_rec].copy(), status=text,
                      t_stop=t_stop, n_force_evals=int(n_evals), wall_time_s=run["wall"],
                      meta=meta, n_outside_domain=n_outside)


def _check_film_step(model, rotor: Rotor, dt, x0, v0, t0, speed, eps_substep, max_substeps) -> None:
    """A film with memory gets ``simulate``'s step check at the start state, on its force with the content
    held at its steady value (``force_kernel``): the fast rates of the film-rotor system are its damping's
    and stiffness', which the content's memory does not speed up.  Along the run the check is not repeated
    (the linearisation would need the content's own dynamics)."""
    try:
        xs = np.zeros(2) if x0 is None else np.asarray(x0, dtype=float).reshape(2)
        vs = np.zeros(2) if v0 is None else np.asarray(v0, dtype=float).reshape(2)
        dt_f = float(dt)
    except (TypeError, ValueError):
        return  # simulate_film names the bad argument
    c = float(model.clearance)
    if not (np.isfinite(xs).all() and np.isfinite(vs).all() and np.hypot(*xs) < c and math.isfinite(dt_f)
            and dt_f > 0.0):
        return
    kernel, params, _ = one_state_kernel(model, "float64")
    omega = float(model.bearing.omega)
    omega_max = omega if speed is None else float(np.abs(np.asarray(speed.omega)).max())
    counters = [a.copy() for a in _integer_arrays(params, [])]
    lim = rk4_step_limit(lambda x1, x2, v1, v2: kernel(params, x1, x2, v1, v2), xs, vs, 1.0 / rotor.mass, c,
                         omega_max, eps_substep, max_substeps)
    for a, kept in zip(_integer_arrays(params, []), counters):
        a[...] = kept   # the check's evaluations are not the run's (a surrogate's domain counter)
    if dt_f > lim.dt_max * (1.0 + 1e-9):
        raise ValueError(
            f"dt={dt!r} s cannot resolve this run: the largest safe step is {lim.dt_max:.3g} s at the start state "
            f"(eccentricity {np.hypot(*xs) / c:.3g}; rule: {lim.rule}). Use dt <= {lim.dt_max:.3g}, or "
            f"check_step=False (experts)")


def unresolved_text(t: float, eps: float, dt, lim: StepLimit, remedy: str) -> str:
    """The status of a run stopped by the along-the-run step check (``simulate``, ``simulate_batch``)."""
    return (f"unresolved: at t={t:.6g} s (eccentricity {eps:.3g}) dt={dt!r} s is longer than the largest safe "
            f"step {lim.dt_max:.3g} s ({lim.rule}); rerun with a shorter dt or {remedy}")


def _check_adaptive_args(t_end, t0, rtol, atol, record_dt) -> float:
    """The adaptive integrator's own arguments, by name; returns the output interval."""
    for name, value in (("rtol", rtol), ("atol", atol)):
        if value is None and name == "atol":
            continue
        if not (_is_real(value) and math.isfinite(value) and value > 0.0):
            raise ValueError(f"{name} must be a positive finite tolerance, got {value!r}")
    if record_dt is None:
        if not (_is_real(t_end) and _is_real(t0) and math.isfinite(t_end) and math.isfinite(t0) and t_end > t0):
            return 1.0  # check_run_args names the bad time
        return (float(t_end) - float(t0)) / 1000.0
    if not (_is_real(record_dt) and math.isfinite(record_dt) and record_dt > 0.0):
        raise ValueError(f"record_dt must be a positive finite time in s, got {record_dt!r}")
    return float(record_dt)


def _run_fixed(model, kernel, params, speed_kernel, consts, x0, v0, t0, dt, n_steps, record_every, eps_stop,
               eps_substep, max_substeps, limit_at, progress) -> dict:
    """The fixed-step RK4 loop in chunks of steps (bit for bit one call): a progress bar between chunks and,
    with ``limit_at``, the step check at each chunk's end state."""
    n_out = n_steps // record_every + 2
    out_t = np.empty(n_out)
    out_x = np.empty((n_out, 2))
    out_v = np.empty((n_out, 2))
    n_rec = _record(out_t, out_x, out_v, 0, t0, x0[0], x0[1], v0[0], v0[1])
    chunk = max(CHUNK_MIN_STEPS, -(-n_steps // MAX_CHUNKS))
    bar = _progress_bar(progress, n_steps, "simulate")
    x, v = x0.copy(), v0.copy()
    status, t, n_evals, e2max, check_outside, limit = OK, t0, 0, 0.0, 0, None
    t_start = time.perf_counter()
    try:
        for s0 in range(0, n_steps, chunk):
            s1 = min(s0 + chunk, n_steps)
            args = (x, v, t0, dt, s0, s1, record_every, eps_stop, eps_substep, max_substeps, out_t, out_x, out_v,
                    n_rec)
            if speed_kernel is None:
                res = run_loop(_rk4_run, _rk4_run_uncached, kernel, params, consts, *args)
            else:
                res = _rk4_run_speed(speed_kernel[0], speed_kernel[1], consts, *args)
            n_rec, status, t, n, x1, x2, v1, v2, e2 = res
            n_evals += n
            e2max = max(e2max, e2)
            x, v = np.array([x1, x2]), np.array([v1, v2])
            if bar is not None:
                bar.update(s1 - s0)
            if status != OK:
                break
            if limit_at is not None:
                limit, extra = _counted(model, lambda: limit_at(x, v, t), params,
                                        speed_kernel[1] if speed_kernel is not None else ())
                check_outside += extra
                if dt > limit.dt_max * (1.0 + 1e-9):
                    status = UNRESOLVED
                    if out_t[n_rec - 1] != t:
                        n_rec = _record(out_t, out_x, out_v, n_rec, t, x1, x2, v1, v2)
                    break
    finally:
        if bar is not None:
            bar.close()
    return {"status": status, "t_stop": t, "n_evals": n_evals, "e2max": e2max, "check_outside": check_outside,
            "limit": limit, "x_stop": x, "n_rec": n_rec, "out": (out_t, out_x, out_v),
            "wall": time.perf_counter() - t_start}


def _run_adaptive(model, kernel, params, speed_kernel, consts, x0, v0, t0, t_end, record_dt, rtol, atol, c, omega,
                  eps_stop, start_limit, progress) -> dict:
    """The adaptive Dormand-Prince loop, in chunks of output times; the first step is the start's safe RK4
    step (at most one output interval), error control takes over from there."""
    n_times = max(int(round((t_end - t0) / record_dt)), 1)
    out_times = t0 + np.arange(1, n_times + 1) * record_dt
    out_times[-1] = t_end
    n_out = n_times + 2
    out_t = np.empty(n_out)
    out_x = np.empty((n_out, 2))
    out_v = np.empty((n_out, 2))
    n_rec = _record(out_t, out_x, out_v, 0, t0, x0[0], x0[1], v0[0], v0[1])
    h = min(start_limit.dt_max, record_dt)
    h_min = 1e-12 * (t_end - t0)
    chunk = max(1, -(-n_times // MAX_CHUNKS))
    bar = _progress_bar(progress, n_times, "simulate (adaptive)")
    x, v, t = x0.copy(), v0.copy(), t0
    status, n_evals, e2max, n_acc, n_rej = OK, 0, 0.0, 0, 0
    t_start = time.perf_counter()
    try:
        for j0 in range(0, n_times, chunk):
            j1 = min(j0 + chunk, n_times)
            args = (x, v, t, h, j0, j1, out_times, rtol, atol * c, atol * c * omega, eps_stop, h_min, out_t, out_x,
                    out_v, n_rec)
            if speed_kernel is None:
                res = run_loop(_dp45_run, _dp45_run_uncached, kernel, params, consts, *args)
            else:
                res = _dp45_run_speed(speed_kernel[0], speed_kernel[1], consts, *args)
            n_rec, status, t, n, x1, x2, v1, v2, h, e2, a, r = res
            n_evals, e2max, n_acc, n_rej = n_evals + n, max(e2max, e2), n_acc + a, n_rej + r
            x, v = np.array([x1, x2]), np.array([v1, v2])
            if bar is not None:
                bar.update(j1 - j0)
            if status != OK:
                break
    finally:
        if bar is not None:
            bar.close()
    return {"status": status, "t_stop": t, "n_evals": n_evals, "e2max": e2max, "check_outside": 0, "limit": None,
            "x_stop": x, "n_rec": n_rec, "out": (out_t, out_x, out_v), "wall": time.perf_counter() - t_start,
            "n_acc": n_acc, "n_rej": n_rej}
