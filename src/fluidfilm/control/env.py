"""``ActiveBearingEnv``: the rotor in the active conical bearing as a gymnasium environment.

Scenario (paper Fig. 5): a fault develops - the rotor's imbalance grows
uniformly from ``imbalance_start`` to ``imbalance_end`` over ``ramp_time``
(5 s) - while a controller picks the axial sleeve position every
``control_interval`` seconds (one shaft revolution by default).  Between
decisions the sleeve is held and the rotor integrated with the same compiled
RK4 loop as every other trajectory in the workspace (``rotor.simulate``), so
the force model is swappable: a surrogate for training, the reference
solver for evaluation.

Observation (7, float32), all things a rig measures or the controller knows:
journal position X/c and velocity V/(c omega) (proximity probes, c the
nominal clearance), the orbit amplitude over the last interval /c (how big
the vibration has become: the imbalance itself is not measured), the
largest eccentricity ratio over the last interval relative to the current
clearance (how close to contact), and the sleeve position scaled to [-1, 1].

Actions: ``Discrete(len(sleeve_positions))``, the index of a sleeve position.

Reward per interval (negative cost; weights in config, documented in
``conf/control``):

    r = -( A / a_ref  +  w_friction P / P_ref  +  w_move |s_new - s_old| / travel )

A the orbit amplitude over the interval (largest distance of the journal
from the interval's mean position), P the film's viscous friction power
(Petroff with the eccentricity factor, 2 pi mu omega^2 R^3 L / (c_r
sqrt(1 - eps^2)), eps of the mean position), P_ref its value at the nominal
clearance and eps = 0.  Without the friction term closing the sleeve would
always win (a thinner film is stiffer), and the controller would be a
constant; with it, the sleeve must follow the growing imbalance - the
vibration-versus-friction trade-off the paper names as the aim of active
bearings.  Contact (eps reaching ``eps_stop`` of the current clearance)
ends the episode with ``contact_penalty``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import gymnasium as gym
import numpy as np

from fluidfilm.core.bearing import ConicalBearing
from fluidfilm.core.force_model import ForceModel, as_adjustable
from fluidfilm.rotor import Rotor, simulate
from fluidfilm.rotor.model import ramped


@dataclass(frozen=True)
class Scenario:
    """The Fig. 5 scenario and the controller's timing; SI units.

    Parameters
    ----------
    imbalance_start : float, default 2e-4
        Total rotor imbalance at t = 0 [kg m].
    imbalance_end : float, default 2e-3
        Total rotor imbalance at t = ``ramp_time`` [kg m].
    ramp_time : float, default 5.0
        Duration of the imbalance ramp [s].
    t_end : float, default 5.0
        Episode length [s], a whole number of control intervals.
    control_interval : float, default 0.02
        Time between decisions [s], a whole number of ``record_every`` steps.
    settle_time : float, default 0.2
        Run before t = 0 at the initial sleeve and imbalance [s].
    dt : float, default 1e-5
        RK4 step [s].
    record_every : int, default 10
        Steps between recorded states.
    eps_stop : float, default 0.95
        Eccentricity ratio (of the current clearance) that ends the episode as a contact.
    initial_action : int or None, default None
        Sleeve index at t = 0; None: the position closest to s = 0.

    Raises
    ------
    ValueError
        Naming the field: non-positive times, negative imbalances, or intervals that are not whole
        numbers of steps.

    Examples
    --------
    >>> from fluidfilm.control import Scenario
    >>> Scenario().n_decisions
    250
    >>> Scenario(control_interval=0.015)
    Traceback (most recent call last):
    ...
    ValueError: scenario.t_end=5.0 must be a whole number of control intervals (0.015 s)
    """

    imbalance_start: float = 2.0e-4      # kg m, total rotor imbalance at t = 0
    imbalance_end: float = 2.0e-3        # kg m, at t = ramp_time
    ramp_time: float = 5.0               # s
    t_end: float = 5.0                   # s, episode length
    control_interval: float = 0.02       # s between decisions
    settle_time: float = 0.2             # s run before t = 0 at the initial sleeve and imbalance
    dt: float = 1.0e-5                   # s, RK4 step
    record_every: int = 10
    eps_stop: float = 0.95
    initial_action: int | None = None    # None: the position closest to s = 0

    def __post_init__(self) -> None:
        for name in ("ramp_time", "t_end", "control_interval", "dt"):
            v = float(getattr(self, name))
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"scenario.{name} must be a positive time in s, got {v!r}")
        for name in ("imbalance_start", "imbalance_end", "settle_time"):
            v = float(getattr(self, name))
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(f"scenario.{name} must be finite and >= 0, got {v!r}")
        n = self.control_interval / self.dt
        if abs(n - round(n)) > 1e-6 or round(n) % self.record_every:
            raise ValueError(f"scenario.control_interval={self.control_interval} must be a whole number of "
                             f"record_every={self.record_every} steps of dt={self.dt}")
        k = self.t_end / self.control_interval
        if abs(k - round(k)) > 1e-6:
            raise ValueError(f"scenario.t_end={self.t_end} must be a whole number of control intervals "
                             f"({self.control_interval} s)")

    @property
    def n_decisions(self) -> int:
        return int(round(self.t_end / self.control_interval))


@dataclass(frozen=True)
class RewardWeights:
    """Weights of the environment's cost per interval (module doc); the reward is its negative.

    Parameters
    ----------
    amplitude_ref : float, default 0.2
        a_ref, the orbit amplitude of unit cost, as a fraction of the nominal clearance.
    friction : float, default 1.0
        w_friction, weight of the friction power relative to its nominal value.
    move : float, default 0.5
        w_move, weight of a sleeve move relative to the whole travel.
    contact_penalty : float, default 100.0
        Cost added when the episode ends in contact.

    Examples
    --------
    >>> from fluidfilm.control import RewardWeights
    >>> RewardWeights(friction=0.0)
    RewardWeights(amplitude_ref=0.2, friction=0.0, move=0.5, contact_penalty=100.0)
    """

    amplitude_ref: float = 0.2       # a_ref as a fraction of the nominal clearance
    friction: float = 1.0            # w_friction
    move: float = 0.5                # w_move
    contact_penalty: float = 100.0


def friction_power(bearing, clearance: float, eps: float) -> float:
    """Viscous power loss of the film [W]: Petroff's 2 pi mu omega^2 R^3 L / c with 1/sqrt(1 - eps^2).

    Parameters
    ----------
    bearing : JournalBearing or ConicalBearing
        Gives mu, omega, R (the mean radius of a cone) and L.
    clearance : float
        Radial clearance [m] (of the current sleeve position).
    eps : float
        Eccentricity ratio (1 - eps^2 is floored at 1e-6).

    Returns
    -------
    float

    Examples
    --------
    >>> from fluidfilm import paper_bearing
    >>> from fluidfilm.control import friction_power
    >>> round(friction_power(paper_bearing(), 120e-6, 0.0), 3), round(friction_power(paper_bearing(), 120e-6, 0.6), 3)
    (1.728, 2.16)
    """
    r = bearing.radius
    return 2 * math.pi * bearing.viscosity * bearing.omega**2 * r**3 * bearing.length / (
        clearance * math.sqrt(max(1.0 - eps * eps, 1e-6)))


def orbit_amplitude(x: np.ndarray) -> float:
    """Largest distance of the journal from the mean position of a stretch of orbit [m].

    Parameters
    ----------
    x : ndarray, shape (n, 2)
        Journal positions [m].

    Returns
    -------
    float

    Examples
    --------
    >>> import numpy as np
    >>> from fluidfilm.control import orbit_amplitude
    >>> orbit_amplitude(np.array([[1e-5, 0.0], [-1e-5, 0.0], [0.0, 1e-5], [0.0, -1e-5]]))
    1e-05
    """
    return float(np.max(np.linalg.norm(x - x.mean(axis=0), axis=1)))


class ActiveBearingEnv(gym.Env):
    """Rotor in an active bearing under a growing imbalance; a discrete sleeve controller acts on it.

    A gymnasium environment (module doc): 7 observations, ``Discrete(len(sleeve_positions))``
    actions, one decision per ``scenario.control_interval``.

    Parameters
    ----------
    model : AdjustableForceModel
        Force model of a conical bearing with a sleeve input (reference solver or surrogate).
    rotor : Rotor
        What the bearing carries (mass share, gravity along +X2, external force); its own imbalance
        is ignored.
    sleeve_positions : sequence of float
        At least two increasing sleeve positions [m] inside the bearing's travel.
    scenario : Scenario, default Scenario()
        The imbalance ramp and the timing.
    weights : RewardWeights, default RewardWeights()
        The cost's weights.
    load_share : float, default 1.0
        Fraction in (0, 1] of the scenario's total imbalance this bearing carries.

    Raises
    ------
    ValueError
        For a model without a sleeve input or of a non-conical bearing, sleeve positions that are
        not increasing or outside the travel, a ``load_share`` outside (0, 1] or a bad
        ``initial_action`` (each named).

    Examples
    --------
    >>> from fluidfilm import ConicalBearing, ConicalReynoldsSolver, Rotor
    >>> from fluidfilm.control import ActiveBearingEnv, Scenario
    >>> cone = ConicalBearing(length=0.05, diameter_small=0.04, diameter_large=0.05, clearance=100e-6,
    ...                       speed_rpm=3000, viscosity=6.53e-4, sleeve_min=-0.5e-3, sleeve_max=0.5e-3)
    >>> model = ConicalReynoldsSolver(cone, 16, 8)
    >>> short = Scenario(t_end=0.04, ramp_time=0.04, control_interval=0.02, settle_time=0.0)   # two decisions
    >>> env = ActiveBearingEnv(model, Rotor(mass=2.5), [-0.4e-3, 0.0, 0.4e-3], short)
    >>> obs, info = env.reset()
    >>> obs.shape, env.action_space
    ((7,), Discrete(3))
    >>> obs, reward, terminated, truncated, info = env.step(1)     # hold the sleeve at s = 0
    >>> round(reward, 3), terminated, truncated
    (-4.645, False, False)
    """

    metadata: dict = {"render_modes": []}

    def __init__(self, model: ForceModel, rotor: Rotor, sleeve_positions, scenario: Scenario = Scenario(),
                 weights: RewardWeights = RewardWeights(), load_share: float = 1.0):
        """``rotor``: what the bearing carries (mass share, gravity, external force; its own
        imbalance is ignored); the scenario's total imbalances are multiplied by ``load_share``."""
        model = as_adjustable(model)  # the environment needs an active bearing model
        if not isinstance(model.bearing, ConicalBearing):
            raise ValueError(f"the environment needs a conical bearing, got {type(model.bearing).__name__}")
        positions = np.asarray(sleeve_positions, dtype=float)
        if positions.ndim != 1 or positions.size < 2 or np.any(np.diff(positions) <= 0):
            raise ValueError(f"sleeve_positions must be >= 2 increasing values (m), got {list(positions)}")
        for s in positions:
            model.bearing.clearance_at(s)  # inside the travel, or a clear error
        self.model = model
        self.bearing = model.bearing
        self.sleeve_positions = positions
        self.scenario = scenario
        self.weights = weights
        # the rotor as one bearing sees it, with the ramp; the base rotor gives mass, gravity, load share
        self.rotor = rotor
        if not 0.0 < float(load_share) <= 1.0:
            raise ValueError(f"load_share must lie in (0, 1], got {load_share!r}")
        self.load_share = float(load_share)
        self.c0 = self.bearing.clearance
        self.travel = float(positions[-1] - positions[0])
        self.p_ref = friction_power(self.bearing, self.c0, 0.0)
        self.action_space = gym.spaces.Discrete(len(positions))
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, shape=(7,), dtype=np.float32)
        self.initial_action = (int(np.argmin(np.abs(positions))) if scenario.initial_action is None
                               else int(scenario.initial_action))
        if not 0 <= self.initial_action < len(positions):
            raise ValueError(f"scenario.initial_action={scenario.initial_action} is not an action index")
        self._settled: dict = {}
        self.history: list[dict] = []

    # ------------------------------------------------------------------ helpers
    def ramp_rotor(self) -> Rotor:
        """The rotor with the scenario's imbalance ramp (what the bearing carries)."""
        return self.rotor_with(self.scenario.imbalance_start, self.scenario.imbalance_end, self.scenario.ramp_time)

    def rotor_with(self, u_start: float, u_end: float | None = None, ramp_time: float = 0.0) -> Rotor:
        r = self.rotor
        share = self.load_share
        return Rotor(mass=r.mass, imbalance=u_start * share, external_force=r.external_force, gravity=r.gravity,
                     imbalance_direction=r.imbalance_direction,
                     imbalance_final=None if u_end is None else u_end * share, ramp_time=ramp_time)

    def initial_state(self) -> tuple[np.ndarray, np.ndarray]:
        """State at t = 0: settled for ``settle_time`` at the initial sleeve and the initial imbalance."""
        a = self.initial_action
        if a not in self._settled:
            sc = self.scenario
            self.model.set_sleeve(self.sleeve_positions[a])
            if sc.settle_time > 0:
                # a whole number of revolutions ending at t = 0, so the imbalance phase is continuous
                tr = simulate(self.model, self.rotor_with(sc.imbalance_start), 0.0, sc.dt,
                              eps_stop=sc.eps_stop, record_every=sc.record_every, t0=-sc.settle_time)
                if not tr.completed:
                    raise RuntimeError(f"settling run failed: {tr.status}")
                self._settled[a] = (tr.x[-1].copy(), tr.v[-1].copy())
            else:
                self._settled[a] = (np.zeros(2), np.zeros(2))
        x, v = self._settled[a]
        return x.copy(), v.copy()

    def interval_cost(self, xs: np.ndarray, clearance: float, move: float) -> tuple[float, float, float]:
        """(cost, orbit amplitude, friction power) of a stretch of orbit ``xs`` at radial clearance
        ``clearance`` after a sleeve move of ``move`` (fraction of the travel); the reward is -cost."""
        w = self.weights
        amp = orbit_amplitude(xs)
        eps_mean = float(np.hypot(*xs.mean(axis=0)) / clearance)
        power = friction_power(self.bearing, clearance, min(eps_mean, 0.99))
        cost = amp / (w.amplitude_ref * self.c0) + w.friction * power / self.p_ref + w.move * move
        return cost, amp, power

    def present_imbalance(self) -> float:
        """Total rotor imbalance [kg m] at the present time of the scenario."""
        sc = self.scenario
        return ramped(sc.imbalance_start, sc.imbalance_end, self.t, sc.ramp_time)

    def _observe(self, amp: float, eps_max: float) -> np.ndarray:
        cw = self.c0 * self.bearing.omega
        s_norm = 2.0 * (self.sleeve_positions[self.action] - self.sleeve_positions[0]) / self.travel - 1.0
        return np.array([self.x[0] / self.c0, self.x[1] / self.c0, self.v[0] / cw, self.v[1] / cw,
                         amp / self.c0, eps_max, s_norm], dtype=np.float32)

    # ------------------------------------------------------------------ gymnasium API
    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.action = self.initial_action
        self.model.set_sleeve(self.sleeve_positions[self.action])
        self.x, self.v = self.initial_state()
        self.t = 0.0
        self.k = 0
        self.history = []
        self._ramp = self.ramp_rotor()
        eps = float(np.hypot(*self.x) / self.model.clearance)
        return self._observe(0.0, eps), {"t": 0.0}

    def step(self, action):
        c_r, move, closed = self.begin_step(action)
        tr = None
        if not closed:
            sc = self.scenario
            tr = simulate(self.model, self._ramp, self.t + sc.control_interval, sc.dt, x0=self.x, v0=self.v,
                          eps_stop=sc.eps_stop, record_every=sc.record_every, t0=self.t)
        return self.finish_step(tr, c_r, move)

    # ------------------------------------------------------------------ the two halves of a step
    def begin_step(self, action) -> tuple[float, float, bool]:
        """Check and take ``action`` (the model's sleeve moves there): returns (clearance c_r [m], sleeve move
        as a fraction of the travel, True if the sleeve closed onto the journal, so nothing is integrated).
        ``step`` is ``begin_step``, the integration over one interval (``interval_rotor``) and ``finish_step``;
        ``ActiveBearingVecEnv`` integrates many environments' intervals in one batch between the two."""
        if not self.action_space.contains(int(action)):
            raise ValueError(f"action {action!r} is not in {self.action_space}")
        a_old = self.action
        self.action = int(action)
        s_new = self.sleeve_positions[self.action]
        self.model.set_sleeve(s_new)
        c_r = self.model.clearance
        move = abs(s_new - self.sleeve_positions[a_old]) / self.travel
        closed = bool(np.hypot(*self.x) >= self.scenario.eps_stop * c_r)
        return c_r, move, closed

    def interval_rotor(self, shift: bool = False) -> Rotor:
        """The rotor over the coming interval: the ramp (``shift=False``), or (``shift=True``) the same ramp
        on a clock that reads 0 now, ``u(t + tau)`` as a function of ``tau`` (for a batch of environments at
        different times integrated from one start time; exact where the interval is whole revolutions, so
        that the imbalance phase omega t is the same)."""
        if not shift:
            return self._ramp
        sc = self.scenario
        u_now = self.present_imbalance()
        left = sc.ramp_time - self.t
        if left <= 0.0 or u_now == sc.imbalance_end:
            return self.rotor_with(sc.imbalance_end)
        return self.rotor_with(u_now, sc.imbalance_end, left)

    def finish_step(self, tr, c_r: float, move: float):
        """The rest of ``step`` after the interval's trajectory ``tr`` (anything with ``x``, ``v`` of its
        recorded states and ``ok``; None where the sleeve closed onto the journal): the new state, cost,
        observation and the gymnasium step tuple."""
        sc, w = self.scenario, self.weights
        if tr is not None:
            terminated = not tr.completed  # contact or divergence
            xs = tr.x
            self.x, self.v = tr.x[-1].copy(), tr.v[-1].copy()
        else:
            terminated = True  # the sleeve closed onto the journal
            xs = self.x[None, :]
        cost, amp, power = self.interval_cost(xs, c_r, move)
        eps_all = np.hypot(xs[:, 0], xs[:, 1]) / c_r
        if terminated:
            cost += w.contact_penalty
        self.k += 1
        self.t = self.k * sc.control_interval
        truncated = (not terminated) and self.k >= sc.n_decisions
        s_new = self.sleeve_positions[self.action]
        rec = {"t": self.t, "sleeve": s_new, "clearance": c_r, "amplitude": amp, "eps_max": float(eps_all.max()),
               "friction_power": power, "move": move, "cost": cost, "terminated": terminated}
        self.history.append(rec)
        # the interval's trajectory stays on the environment (infos must compare by value)
        self.last_trajectory = tr
        return self._observe(amp, float(eps_all.max())), -float(cost), terminated, truncated, dict(rec)
