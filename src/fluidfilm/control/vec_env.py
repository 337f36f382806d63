"""``ActiveBearingVecEnv``: N active-bearing environments stepped together, one batched integration per step.

A stable-baselines3 ``VecEnv`` (DQN takes ``n_envs > 1``) over N ``ActiveBearingEnv`` on one force model.
Per step every environment takes its action (``ActiveBearingEnv.begin_step``), the intervals of all of
them are integrated by ONE ``simulate_batch`` call, and each environment finishes its step
(``finish_step``: state, cost, observation) - so a step costs one call into the compiled loop instead
of N, and the environments' transitions are the single environment's:

- a surrogate of the active bearing takes the sleeve per trajectory (``core.force_model.BatchSettable``):
  all N intervals are one batch, each at its own sleeve position; the reference solver rebuilds its
  kernel when the sleeve moves, so it runs one batch per sleeve position in use (at most one per action);
- environments at different times (one reset after a contact while the others went on) share one batch
  when the control interval is a whole number of shaft revolutions (the default, one decision per
  revolution): each is integrated from time 0 with its imbalance ramp shifted to start at its own time
  (``ActiveBearingEnv.interval_rotor``), which is the same imbalance force to round-off (the phase
  omega t differs by whole turns).  Otherwise one batch per distinct time;
- ``simulate_batch`` ends a trajectory whose RK4 stage leaves the clearance as a contact where
  ``simulate`` retries the step with more substeps: such a trajectory (its last state still inside
  ``eps_stop``) is run again by ``simulate``, so contacts are the single environment's too;
- autoreset as SB3's ``DummyVecEnv``: a finished environment's last observation goes to
  ``info["terminal_observation"]``, ``info["TimeLimit.truncated"]`` says a time limit ended it, and the
  observation returned is the reset one.

``tests/control/test_control.py`` checks the transitions against ``DummyVecEnv`` over single environments.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices, VecEnvObs, VecEnvStepReturn

from fluidfilm.control.env import ActiveBearingEnv, RewardWeights, Scenario
from fluidfilm.core.force_model import BatchSettable, ForceModel
from fluidfilm.rotor import Rotor, simulate
from fluidfilm.rotor.batch import simulate_batch


class ActiveBearingVecEnv(VecEnv):
    """N ``ActiveBearingEnv`` on one force model, their intervals integrated by one ``simulate_batch`` per step.

    Parameters
    ----------
    model : AdjustableForceModel
        Force model of a conical bearing with a sleeve input (a surrogate: one batch per step; the
        reference solver: one batch per sleeve position in use).
    rotor : Rotor
        What the bearing carries (as ``ActiveBearingEnv``).
    sleeve_positions, scenario, weights, load_share
        Each environment's, as ``ActiveBearingEnv`` takes them (the actions, the imbalance ramp and timing,
        the cost's weights, this bearing's share of the imbalance).
    n_envs : int, default 8
        Environments stepped together (>= 1).
    threads : int or None, default 1
        ``simulate_batch``'s threads (used where its stage-batched loop runs: batches of at least
        ``rotor.batch.STAGE_BATCHED_MIN_N`` without per-trajectory settings); None: all cores.

    Raises
    ------
    ValueError
        For ``n_envs`` below 1, and whatever ``ActiveBearingEnv`` rejects.

    Examples
    --------
    >>> import numpy as np
    >>> from fluidfilm import ConicalBearing, ConicalReynoldsSolver, Rotor
    >>> from fluidfilm.control import ActiveBearingVecEnv, Scenario
    >>> cone = ConicalBearing(length=0.05, diameter_small=0.04, diameter_large=0.05, clearance=100e-6,
    ...                       speed_rpm=3000, viscosity=6.53e-4, sleeve_min=-0.5e-3, sleeve_max=0.5e-3)
    >>> short = Scenario(t_end=0.04, ramp_time=0.04, control_interval=0.02, settle_time=0.0)
    >>> venv = ActiveBearingVecEnv(ConicalReynoldsSolver(cone, 16, 8), Rotor(mass=2.5), [-0.4e-3, 0.0, 0.4e-3],
    ...                            short, n_envs=3)
    >>> venv.reset().shape
    (3, 7)
    >>> obs, rewards, dones, infos = venv.step(np.array([0, 1, 2]))
    >>> obs.shape, [round(float(r), 3) for r in rewards], dones.tolist()
    ((3, 7), [-3.078, -4.645, -7.673], [False, False, False])
    """

    def __init__(self, model: ForceModel, rotor: Rotor, sleeve_positions, scenario: Scenario = Scenario(),
                 weights: RewardWeights = RewardWeights(), load_share: float = 1.0, n_envs: int = 8,
                 threads: int | None = 1):
        if isinstance(n_envs, bool) or not isinstance(n_envs, (int, np.integer)) or n_envs < 1:
            raise ValueError(f"n_envs must be a positive integer, got {n_envs!r}")
        self.envs = [ActiveBearingEnv(model, rotor, sleeve_positions, scenario, weights, load_share)
                     for _ in range(int(n_envs))]
        first = self.envs[0]
        for env in self.envs[1:]:
            env._settled = first._settled  # one settling run for all (same model, rotor and scenario)
        self.model = first.model
        self.scenario = scenario
        self.threads = threads
        self.per_trajectory = isinstance(self.model, BatchSettable)
        revolutions = scenario.control_interval * first.bearing.omega / (2.0 * math.pi)
        self.shifted = abs(revolutions - round(revolutions)) < 1e-9
        self.actions = np.zeros(len(self.envs), dtype=np.int64)
        self.n_batches = 0  # simulate_batch calls so far (one per step for a surrogate)
        super().__init__(len(self.envs), first.observation_space, first.action_space)

    # ------------------------------------------------------------------ SB3 VecEnv API
    def reset(self) -> VecEnvObs:
        obs = np.empty((self.num_envs, *self.observation_space.shape), dtype=np.float32)
        for i, env in enumerate(self.envs):
            maybe_options = {"options": self._options[i]} if self._options[i] else {}
            obs[i], self.reset_infos[i] = env.reset(seed=self._seeds[i], **maybe_options)
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self.actions = np.asarray(actions).reshape(self.num_envs)

    def step_wait(self) -> VecEnvStepReturn:
        begun = [env.begin_step(a) for env, a in zip(self.envs, self.actions)]
        running = [i for i, (_, _, closed) in enumerate(begun) if not closed]
        trajectories = self._integrate(running)
        obs = np.empty((self.num_envs, *self.observation_space.shape), dtype=np.float32)
        rewards = np.empty(self.num_envs, dtype=np.float32)
        dones = np.empty(self.num_envs, dtype=bool)
        infos: list[dict[str, Any]] = []
        for i, env in enumerate(self.envs):
            c_r, move, _ = begun[i]
            o, r, terminated, truncated, info = env.finish_step(trajectories.get(i), c_r, move)
            dones[i] = terminated or truncated
            info["TimeLimit.truncated"] = truncated and not terminated
            if dones[i]:
                info["terminal_observation"] = o
                o, self.reset_infos[i] = env.reset()
            obs[i], rewards[i] = o, r
            infos.append(info)
        return obs, rewards, dones, infos

    def close(self) -> None:
        for env in self.envs:
            env.close()

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        return [getattr(self.envs[i], attr_name) for i in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        for i in self._get_indices(indices):
            setattr(self.envs[i], attr_name, value)

    def env_method(self, method_name: str, *method_args, indices: VecEnvIndices = None, **method_kwargs) -> list[Any]:
        return [getattr(self.envs[i], method_name)(*method_args, **method_kwargs) for i in self._get_indices(indices)]

    def env_is_wrapped(self, wrapper_class: type, indices: VecEnvIndices = None) -> list[bool]:
        return [isinstance(self.envs[i], wrapper_class) for i in self._get_indices(indices)]

    # ------------------------------------------------------------------ the batched interval
    def _groups(self, running: Sequence[int]) -> dict[tuple, list[int]]:
        """Environments integrated together: one group (a surrogate, whole revolutions per interval), else
        split by time (intervals not whole revolutions) and sleeve (a model without per-trajectory settings)."""
        groups: dict[tuple, list[int]] = {}
        for i in running:
            env = self.envs[i]
            key = (0.0 if self.shifted else env.t, None if self.per_trajectory else env.action)
            groups.setdefault(key, []).append(i)
        return groups

    def _integrate(self, running: Sequence[int]) -> dict[int, Any]:
        """Each running environment's interval (a ``Trajectory``), by as few ``simulate_batch`` calls as the
        model allows (module doc)."""
        sc = self.scenario
        model: Any = self.model
        out: dict[int, Any] = {}
        for (t0, action), members in self._groups(running).items():
            envs = [self.envs[i] for i in members]
            rotors = [env.interval_rotor(shift=self.shifted) for env in envs]
            x0 = np.array([env.x for env in envs])
            v0 = np.array([env.v for env in envs])
            settings = None
            if self.per_trajectory:
                settings = np.array([model.setting_for(env.sleeve_positions[env.action]) for env in envs])
            else:
                model.set_sleeve(envs[0].sleeve_positions[action])
            batch = simulate_batch(model, rotors, t0 + sc.control_interval, sc.dt, x0, v0, settings=settings,
                                   eps_stop=sc.eps_stop, record_every=sc.record_every, t0=t0, threads=self.threads)
            self.n_batches += 1
            for j, (i, env) in enumerate(zip(members, envs)):
                tr = batch.trajectory(j)
                c_r = env.bearing.clearance_at(env.sleeve_positions[env.action])
                if not tr.completed and tr.status.startswith("contact") and np.hypot(*tr.x[-1]) < sc.eps_stop * c_r:
                    # a stage left the clearance: simulate retries such a step with more substeps
                    model.set_sleeve(env.sleeve_positions[env.action])
                    tr = simulate(model, rotors[j], t0 + sc.control_interval, sc.dt, x0=env.x, v0=env.v,
                                  eps_stop=sc.eps_stop, record_every=sc.record_every, t0=t0)
                if self.shifted:
                    tr.t = tr.t + env.t  # back on the environment's clock
                out[i] = tr
        return out
