"""``simulate``: the rotor's equation of motion, one compiled loop for every force model.

Equation (paper eq. 4, CONVENTIONS.md):

    m dV/dt = F_bearing(X, V) + m_u d w^2 (cos wt, s sin wt) + m (0, g) + F_ext,   dX/dt = V

Scheme: classical fixed-step RK4.  A fixed step means every force model is
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
settled orbits converge (tests/test_rotor.py).

The loop is compiled with numba and calls the model's compiled force kernel
``fn(params, x1, x2, v1, v2) -> (F1, F2)`` directly, so the integrator's own
overhead is a few tens of nanoseconds per step.

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
        ``"ok"`` (reached the end time, possibly followed by "; <note>"), ``"contact: ..."`` or
        ``"diverged: ..."``.
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
        """The run reached t_end (a note after "ok;" may say it left a surrogate's training domain)."""
        return self.status == "ok" or self.status.startswith("ok;")

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
def _rk4_step(kernel, params, consts, x1, x2, v1, v2, t, t0, step, dt, eps_substep, max_substeps, stop2, retry):
    """Step ``step`` of RK4 from the state (x1, x2, v1, v2) at time t (= t0 + step dt), in substeps.

    The one RK4 step of ``simulate`` and ``simulate_batch``. Returns (x1, x2, v1, v2, t, n_evals, status):
    the state after the step, or the last valid state where it stopped (status ``CONTACT``,
    ``CONTACT_STAGE``, ``NONFINITE``). ``retry``: a stage outside the clearance says the step is too long,
    not that the journal touched: the step is redone with twice the substeps (up to ``max_substeps``)
    before contact is reported. Inlined, so each loop compiles it as if written in place.
    """
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
    return x1, x2, v1, v2, t, n_evals, status


@njit(cache=True)
def _rk4_run(kernel, params, consts, x0, v0, t0, dt, n_steps, record_every, eps_stop, eps_substep,
             max_substeps, out_t, out_x, out_v):
    """Integrate; returns (n_recorded, status, t_stop, n_force_evals)."""
    stop2 = eps_stop * eps_stop * consts[6]
    x1, x2 = x0[0], x0[1]
    v1, v2 = v0[0], v0[1]
    t = t0
    n_evals = 0
    n_rec = _record(out_t, out_x, out_v, 0, t, x1, x2, v1, v2)
    status = OK
    for step in range(n_steps):
        x1, x2, v1, v2, t, n, status = _rk4_step(kernel, params, consts, x1, x2, v1, v2, t0 + step * dt, t0, step,
                                                 dt, eps_substep, max_substeps, stop2, True)
        n_evals += n
        if status != OK:
            break
        if (step + 1) % record_every == 0:
            n_rec = _record(out_t, out_x, out_v, n_rec, t, x1, x2, v1, v2)
    if status != OK:
        # last valid state, so the trajectory ends where it stopped
        n_rec = _record(out_t, out_x, out_v, n_rec, t, x1, x2, v1, v2)
    return n_rec, status, t, n_evals


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


def simulate(model: ForceModel, rotor: Rotor, t_end: float, dt: float = 1e-5, x0=None, v0=None, *,
             eps_stop: float = 0.98, record_every: int = 1, eps_substep: float = 0.8,
             max_substeps: int = 256, t0: float = 0.0, speed: SpeedSchedule | None = None,
             precision: str = "float64", film_content=None) -> Trajectory:
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
    dt : float, default 1e-5
        RK4 step [s], at most the run's length.
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
    film_content : array_like or None, default None
        A film with memory only (``core.force_model.TransientFilmModel``, mass-conserving cavitation): the
        film content (n_theta, n_z) at t0, e.g. ``meta["film_content"]`` of a previous run to continue it;
        None: the steady film at x0.  Such a model runs in ``rotor.film_memory``'s loop, which carries the
        content between RK4 steps.

    Returns
    -------
    Trajectory
        The recorded states, ``status`` ("ok", "contact: ...", "diverged: ..."), force evaluations
        and wall time.

    Raises
    ------
    ValueError
        Naming the argument: a rotor that is not a ``Rotor``, a model that is not a force model,
        times or settings that are not finite positive numbers of the right kind, an initial state
        of the wrong shape, non-finite, or not below ``eps_stop``; a ``speed`` schedule that is not a
        ``SpeedSchedule``, or that leaves the bearing's speed for a model without speed-scaled forces
        (naming the model and the speeds); a ``precision`` other than "float64"/"float32", or "float32"
        networks with a speed schedule.

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
        return simulate_film(model, rotor, t_end, dt, x0, v0, eps_stop=eps_stop, record_every=record_every,
                             eps_substep=eps_substep, max_substeps=max_substeps, t0=t0, speed=speed,
                             film_content=film_content)
    # precision: what the networks actually run in (a model without float32 networks computes in float64)
    kernel, params, precision = one_state_kernel(model, precision)
    if precision == "float32" and speed is not None:
        raise ValueError("precision='float32' runs at constant speed only; a speed schedule takes float64")
    bearing = model.bearing
    # an active bearing reports the clearance of its current control setting
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
    record_every = int(record_every)
    n_out = n_steps // record_every + 2
    out_t = np.empty(n_out)
    out_x = np.empty((n_out, 2))
    out_v = np.empty((n_out, 2))
    omega = bearing.omega
    u_final = rotor.imbalance if rotor.imbalance_final is None else rotor.imbalance_final
    consts = (1.0 / rotor.mass, rotor.imbalance * omega**2, omega, float(rotor.imbalance_direction),
              rotor.external_force[0], rotor.external_force[1] + rotor.mass * rotor.gravity, c * c,
              u_final * omega**2, rotor.ramp_time if rotor.imbalance_final is not None else 0.0)
    meta: dict = {"dt": dt, "t0": t0, "t_end": t_end, "record_every": record_every, "precision": precision}
    speed_kernel = _speed_kernel(model, speed)
    model.reset_domain_counter()
    t_start = time.perf_counter()
    args = (x0, v0, float(t0), float(dt), n_steps, record_every, float(eps_stop), float(eps_substep),
            int(max_substeps), out_t, out_x, out_v)
    if speed_kernel is None:
        n_rec, status, t_stop, n_evals = run_loop(_rk4_run, _rk4_run_uncached, kernel, params, consts, *args)
    else:
        assert speed is not None
        consts_speed = consts + _schedule_arrays(speed, omega)
        n_rec, status, t_stop, n_evals = _rk4_run_speed(*speed_kernel, consts_speed, *args)
        meta["speed"] = {"times": speed.times.tolist(), "omega": speed.omega.tolist()}
    wall = time.perf_counter() - t_start
    if status == OK:
        text, t_stop = "ok", None
    elif status in (CONTACT, CONTACT_STAGE):
        text = f"contact: eccentricity reached eps_stop={eps_stop} at t={t_stop:.6g} s"
    else:
        text = f"diverged: non-finite state after t={t_stop:.6g} s"
    note = model.domain_report()
    n_outside = int(model.n_outside_domain)
    if note:
        text = f"{text}; {note}"
        warnings.warn(f"{model.name}: {note} during the simulation",
                      RuntimeWarning, stacklevel=2)
    return Trajectory(t=out_t[:n_rec].copy(), x=out_x[:n_rec].copy(), v=out_v[:n_rec].copy(), status=text,
                      t_stop=t_stop, n_force_evals=int(n_evals), wall_time_s=wall,
                      meta=meta, n_outside_domain=n_outside)
