"""A scene as a ``gymnasium.Env`` over :class:`pointmass_dyn.Simulator`, and copies of it
stepped on threads (the core releases the interpreter during a step)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import VectorEnv

from .. import Simulator
from ..errors import InvalidInputError, SimulationError

__all__ = ["SceneEnv", "VectorSceneEnv"]

_SPEEDS = {"Revolute": 1, "Prismatic": 1, "Spherical": 3, "SphericalZYZ": 3, "FreeFlyer": 6}


def _one_dof_speeds(model: Any) -> tuple[list[int], list[str]]:
    """The speed index and joint name of every revolute or prismatic joint (the actuated
    ones by default; a free base or a ball joint is not)."""
    kinds = {}
    for i in range(model.nbodies):
        _, kind, _, link = model.body_info(i)
        if link >= 0 and kind != "Fixed":
            kinds.setdefault(link, kind)
    speeds, names, at = [], [], 0
    for link, name in enumerate(model.joint_names):
        n = _SPEEDS.get(kinds.get(link, "Revolute"), 1)
        if n == 1:
            speeds.append(at)
            names.append(name)
        at += n
    return speeds, names


class SceneEnv(gym.Env):
    """A scene as a Gymnasium environment.

    Action: ``control="torque"``: torques on the ``actuated`` speeds (default: every revolute
    and prismatic joint's), within ``±action_limit`` (default: the joints' efforts from the
    robot file; required where it gives none); ``control="pd"``: targets of the scene's PD
    torques within ``±action_limit`` (default π). Actions outside are clipped. Observation:
    the readings named in ``observe`` (default ``("q", "v")``; IMU readings
    ``"<name>.accel"``/``"<name>.gyro"`` with ``imu=``), concatenated. Each step holds the
    action for ``control_period`` seconds. ``reward(env, readings, action) -> float`` and
    ``terminated(env, readings) -> bool`` are the task's hooks (default: 0 and never);
    a failed integration terminates the episode (``info["error"]``). ``max_episode_steps``
    truncates. Resets start at the scene's state plus uniform noise of ``±reset_noise`` on
    ``q`` and ``v``, from the generator seeded by ``reset(seed=...)``.
    """

    metadata = {"render_modes": []}

    def __init__(
        self,
        scene: Any,
        *,
        control: str = "torque",
        actuated: Sequence[int] | None = None,
        action_limit: Any = None,
        control_period: float = 0.01,
        observe: Sequence[str] = ("q", "v"),
        reward: Callable | None = None,
        terminated: Callable | None = None,
        max_episode_steps: int = 1000,
        reset_noise: float = 0.01,
        **simulator: Any,
    ):
        self.scene = scene
        self.control_period = float(control_period)
        self.control = control
        self.observe = tuple(observe)
        self.reward_fn, self.terminated_fn = reward, terminated
        self.max_episode_steps = int(max_episode_steps)
        self.reset_noise = float(reset_noise)
        self._simulator = dict(simulator, control=control, record=False)
        model = scene.model
        self._nv = model.nv
        sim = self._make()
        if control == "torque":
            speeds, names = _one_dof_speeds(model)
            self.actuated = list(speeds if actuated is None else actuated)
            efforts = None
            if action_limit is None:
                limits = model.joint_limits()
                efforts = [limits[n][2] for n in names] if actuated is None else None
            limit = efforts if efforts is not None else action_limit
        else:
            self.actuated = None
            limit = np.pi if action_limit is None else action_limit
        n = sim._core.control_len if control == "pd" else len(self.actuated)
        high = np.broadcast_to(np.asarray(1.0 if limit is None else limit, float), (n,)).copy()
        if limit is None or not np.all(np.isfinite(high) & (high > 0)):
            raise InvalidInputError(
                f"action_limit: expected positive finite limits for the {n} actions (the model "
                f"gives none for some joints), got {action_limit!r}"
            )
        self.action_space = gym.spaces.Box(-high, high, dtype=np.float64)
        size = sum(np.size(v) for k, v in sim.sensors().items() if k in self.observe)
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, (size,), dtype=np.float64)
        self.sim = sim
        self._steps = 0

    def _make(self) -> Simulator:
        return Simulator(self.scene, control_period=self.control_period, **self._simulator)

    def _observe(self) -> tuple[np.ndarray, dict]:
        readings = self.sim.sensors()
        missing = [k for k in self.observe if k not in readings]
        if missing:
            raise InvalidInputError(
                f"observe: expected names of readings ({sorted(readings)}), got {missing[0]!r}"
            )
        obs = np.concatenate([np.ravel(readings[k]) for k in self.observe]).astype(np.float64)
        return obs, readings

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        self.sim = self._make()
        q0, v0 = self.sim.state
        r = self.reset_noise
        q = q0 + self.np_random.uniform(-r, r, q0.shape)
        v = v0 + self.np_random.uniform(-r, r, v0.shape)
        self.sim.state = (q, v)
        self._steps = 0
        obs, _ = self._observe()
        return obs, {}

    def _control(self, action: Any) -> np.ndarray:
        a = np.clip(np.asarray(action, dtype=float), self.action_space.low, self.action_space.high)
        if self.actuated is None:
            return a
        u = np.zeros(self._nv)
        u[self.actuated] = a
        return u

    def step(self, action: Any):
        info: dict = {}
        failed = False
        try:
            self.sim.step(control=self._control(action))
        except SimulationError as error:
            failed, info["error"] = True, str(error)
        self._steps += 1
        obs, readings = self._observe()
        reward = 0.0 if self.reward_fn is None else float(self.reward_fn(self, readings, action))
        done = failed or (self.terminated_fn is not None and bool(self.terminated_fn(self, readings)))
        truncated = self._steps >= self.max_episode_steps
        return obs, reward, done, truncated, info


class VectorSceneEnv(VectorEnv):
    """``num_envs`` copies of ``make_env()`` stepped on a thread pool (each step releases the
    interpreter while it integrates). A finished copy is reset within the same step (its
    last observation in ``infos["final_obs"]``). ``reset(seed=s)`` seeds copy ``k`` with
    ``s + k``, so a seeded run is reproducible whatever the threads' order."""

    def __init__(self, make_env: Callable[[], SceneEnv], num_envs: int, threads: int | None = None):
        self.envs = [make_env() for _ in range(num_envs)]
        self.num_envs = num_envs
        self.single_observation_space = self.envs[0].observation_space
        self.single_action_space = self.envs[0].action_space
        self.observation_space = gym.vector.utils.batch_space(self.single_observation_space, num_envs)
        self.action_space = gym.vector.utils.batch_space(self.single_action_space, num_envs)
        self.metadata = {"autoreset_mode": gym.vector.AutoresetMode.SAME_STEP}
        self._pool = ThreadPoolExecutor(threads or num_envs)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        seeds = [None if seed is None else seed + k for k in range(self.num_envs)]
        out = list(self._pool.map(lambda ks: ks[0].reset(seed=ks[1]), zip(self.envs, seeds)))
        return np.stack([o for o, _ in out]), {}

    def step(self, actions: Any):
        def one(k: int):
            env = self.envs[k]
            obs, r, term, trunc, info = env.step(actions[k])
            final = None
            if term or trunc:
                final, (obs, _) = obs, env.reset()
            return obs, r, term, trunc, final

        out = list(self._pool.map(one, range(self.num_envs)))
        obs = np.stack([o[0] for o in out])
        infos = {"final_obs": np.array([o[4] for o in out], dtype=object)}
        return (obs, np.array([o[1] for o in out]), np.array([o[2] for o in out]),
                np.array([o[3] for o in out]), infos)

    def close_extras(self, **kwargs: Any) -> None:
        self._pool.shutdown()
