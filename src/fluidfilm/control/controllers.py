"""Controllers of the active bearing and the loop that runs them on ``ActiveBearingEnv``.

Every controller is a callable ``controller(obs, env) -> action``: the DQN
agent reads only the observation; the model predictive controller reads the
measured state (position, velocity, time, current sleeve) from the
environment, as a real MPC reads its sensors.

- ``ConstantSleeve``: no control, the sleeve held (the passive bearing).
- ``DQNController``: a stable-baselines3 DQN policy, greedy.
- ``ModelPredictiveController``: at each decision, predicts the orbit over a
  horizon for every sleeve position held constant, with its own force model
  (the surrogate; the reference for a "perfect model"), and takes the
  position of least predicted cost, the environment's own cost.  The
  imbalance is held at its current value over the horizon: the controller
  knows the present imbalance (estimated from the measured orbit), not the
  future ramp.
"""
from __future__ import annotations

import time
from typing import Any, Protocol

import numpy as np

from fluidfilm.core.force_model import ForceModel, as_adjustable
from fluidfilm.rotor import simulate
from fluidfilm.control.env import ActiveBearingEnv


class Controller(Protocol):
    """What ``run_episode`` runs: a named callable ``controller(obs, env) -> action index``."""

    name: str

    def __call__(self, obs: Any, env: ActiveBearingEnv) -> int: ...


class ConstantSleeve:
    """No control: always the same sleeve position.

    Parameters
    ----------
    action : int
        The sleeve index held.
    name : str or None, default None
        Display name; None: ``"constant_<action>"``.

    Examples
    --------
    >>> from fluidfilm.control import ConstantSleeve
    >>> hold = ConstantSleeve(1)
    >>> hold.name, hold(None, None)
    ('constant_1', 1)
    """

    def __init__(self, action: int, name: str | None = None):
        self.action = int(action)
        self.name = name or f"constant_{self.action}"

    def __call__(self, obs, env) -> int:
        return self.action


class DQNController:
    """A trained stable-baselines3 DQN agent, acting greedily.

    Parameters
    ----------
    agent : stable_baselines3.DQN
        Anything with ``predict(obs, deterministic=True) -> (action, state)``.

    Examples
    --------
    >>> from fluidfilm.control import DQNController
    >>> class Always2:                                 # stands in for a trained agent
    ...     def predict(self, obs, deterministic=True):
    ...         return 2, None
    >>> DQNController(Always2())(obs=None, env=None)
    2
    """

    name = "dqn"

    def __init__(self, agent):
        self.agent = agent

    def __call__(self, obs, env) -> int:
        action, _ = self.agent.predict(obs, deterministic=True)
        return int(action)


class ModelPredictiveController:
    """Shooting MPC over constant sleeve holds, with its own force model.

    At each decision it integrates, from the measured state, every sleeve position held for
    ``horizon_intervals`` control intervals at the present imbalance, and takes the one of least
    predicted cost (the environment's own; contact costs ``contact_penalty``).

    Parameters
    ----------
    model : AdjustableForceModel
        The controller's own force model (a surrogate, or the reference for a perfect model).
    horizon_intervals : int, default 2
        Prediction horizon in control intervals (>= 1).

    Raises
    ------
    ValueError
        For a model without a sleeve input, or a horizon below 1.

    Examples
    --------
    The controller in an episode: see ``run_episode``.  It needs a model with a sleeve:

    >>> from fluidfilm import ReynoldsSolver, paper_bearing
    >>> from fluidfilm.control import ModelPredictiveController
    >>> ModelPredictiveController(ReynoldsSolver(paper_bearing(), 16, 8))
    Traceback (most recent call last):
    ...
    ValueError: ReynoldsSolver has no sleeve input: an active (adjustable) bearing model is needed
    """

    name = "mpc"

    def __init__(self, model: ForceModel, horizon_intervals: int = 2):
        model = as_adjustable(model)  # the MPC needs an active bearing model
        if int(horizon_intervals) < 1:
            raise ValueError(f"horizon_intervals must be >= 1, got {horizon_intervals!r}")
        self.model = model
        self.horizon = int(horizon_intervals)

    def predicted_costs(self, env: ActiveBearingEnv) -> np.ndarray:
        sc = env.scenario
        rotor = env.rotor_with(env.present_imbalance())
        costs = np.full(len(env.sleeve_positions), np.inf)
        for a, s in enumerate(env.sleeve_positions):
            self.model.set_sleeve(s)
            c_r = self.model.clearance
            if np.hypot(*env.x) >= sc.eps_stop * c_r:
                continue
            tr = simulate(self.model, rotor, env.t + self.horizon * sc.control_interval, sc.dt, x0=env.x, v0=env.v,
                          eps_stop=sc.eps_stop, record_every=sc.record_every, t0=env.t)
            if not tr.completed:
                costs[a] = env.weights.contact_penalty
                continue
            move = abs(s - env.sleeve_positions[env.action]) / env.travel
            costs[a] = env.interval_cost(tr.x, c_r, move)[0]
        return costs

    def __call__(self, obs, env) -> int:
        return int(np.argmin(self.predicted_costs(env)))


def run_episode(env: ActiveBearingEnv, controller: Controller, keep_trajectory: bool = True) -> dict:
    """One episode; returns the per-decision history, the whole trajectory and summary numbers.

    ``decision_ms``: wall time the controller took per decision (median), the
    figure that matters for running it on-line.

    Parameters
    ----------
    env : ActiveBearingEnv
        The environment (reset here).
    controller : Controller
        A named callable ``controller(obs, env) -> action index``.
    keep_trajectory : bool, default True
        Also return the whole trajectory (``t`` [s], ``x`` [m], ``v`` [m/s]).

    Returns
    -------
    dict
        ``controller``, ``return``, ``n_decisions``, ``contact``, ``max_amplitude_m``,
        ``final_amplitude_m``, ``mean_friction_power_W``, ``sleeve_travel_m``,
        ``decision_ms_median``, ``history`` (one record per decision) and, when kept, ``t``, ``x``, ``v``.

    Examples
    --------
    Two decisions of 0.02 s in a conical bearing, the sleeve held, then the model predictive
    controller on the same episode (the reference solver as its model):

    >>> from fluidfilm import ConicalBearing, ConicalReynoldsSolver, Rotor
    >>> from fluidfilm.control import (ActiveBearingEnv, ConstantSleeve, ModelPredictiveController, Scenario,
    ...                                run_episode)
    >>> solver = ConicalReynoldsSolver(ConicalBearing(0.05, 0.04, 0.05, 100e-6, 3000, 6.53e-4, sleeve_min=-0.5e-3,
    ...                                               sleeve_max=0.5e-3), 16, 8)
    >>> env = ActiveBearingEnv(solver, Rotor(mass=2.5), [-0.4e-3, 0.0, 0.4e-3],
    ...                        Scenario(t_end=0.04, ramp_time=0.04, control_interval=0.02, settle_time=0.0))
    >>> out = run_episode(env, ConstantSleeve(1))
    >>> out["controller"], out["n_decisions"], out["contact"], out["x"].shape[1]
    ('constant_1', 2, False, 2)
    >>> out = run_episode(env, ModelPredictiveController(solver, horizon_intervals=1), keep_trajectory=False)
    >>> out["controller"], [float(h["sleeve"]) for h in out["history"]]
    ('mpc', [-0.0004, -0.0004])
    """
    obs, _ = env.reset()
    t_parts: list[np.ndarray] = []
    x_parts: list[np.ndarray] = []
    v_parts: list[np.ndarray] = []
    decision_s = []
    total = 0.0
    while True:
        t0 = time.perf_counter()
        action = controller(obs, env)
        decision_s.append(time.perf_counter() - t0)
        obs, reward, terminated, truncated, info = env.step(action)
        total += reward
        tr = env.last_trajectory
        if keep_trajectory and tr is not None:
            t_parts.append(tr.t[1:] if t_parts else tr.t)
            x_parts.append(tr.x[1:] if x_parts else tr.x)
            v_parts.append(tr.v[1:] if v_parts else tr.v)
        if terminated or truncated:
            break
    hist = env.history
    amps = np.array([h["amplitude"] for h in hist])
    out = {
        "controller": controller.name,
        "return": float(total),
        "n_decisions": len(hist),
        "contact": bool(hist[-1]["terminated"]),
        "max_amplitude_m": float(amps.max()),
        "final_amplitude_m": float(amps[-max(1, len(amps) // 10):].mean()),
        "mean_friction_power_W": float(np.mean([h["friction_power"] for h in hist])),
        "sleeve_travel_m": float(sum(h["move"] for h in hist) * env.travel),
        "decision_ms_median": float(np.median(decision_s) * 1e3),
        "history": hist,
    }
    if keep_trajectory and t_parts:
        out["t"] = np.concatenate(t_parts)
        out["x"] = np.concatenate(x_parts)
        out["v"] = np.concatenate(v_parts)
    return out
