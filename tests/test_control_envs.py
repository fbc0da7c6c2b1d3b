"""`pmd.envs`: Gymnasium's own checker on a scene env, and a seeded threaded vector env
reproducible run to run (same seeds: the same observations bit for bit)."""

from __future__ import annotations

import numpy as np
import pointmass_dyn as pmd
import pytest

gym = pytest.importorskip("gymnasium")
from gymnasium.utils.env_checker import check_env  # noqa: E402
from pointmass_dyn.envs import SceneEnv, VectorSceneEnv  # noqa: E402


def chain_env():
    scene = pmd.load_scene("chain7")
    return SceneEnv(scene, action_limit=5.0, control_period=0.01, method="RK4", dt=0.0025,
                    max_episode_steps=20, imu={"tip": pmd.IMU(6)},
                    observe=("q", "v", "tip.accel"),
                    reward=lambda env, r, a: -float(np.sum(r["v"] ** 2)),
                    terminated=lambda env, r: bool(np.abs(r["q"]).max() > 3.0))


def test_check_env_passes():
    env = chain_env()
    check_env(env, skip_render_check=True)
    assert env.observation_space.shape == (7 + 7 + 3,)
    assert env.action_space.shape == (7,)


def test_actions_are_clipped_to_the_limits():
    env = chain_env()
    env.reset(seed=0)
    env.step(np.full(7, 100.0))
    np.testing.assert_array_equal(env.sim.sensors()["tau"], np.full(7, 5.0))


def rollout(seed):
    venv = VectorSceneEnv(chain_env, 3, threads=3)
    obs, _ = venv.reset(seed=seed)
    rng = np.random.default_rng(seed)
    out = [obs]
    for _ in range(25):  # past the 20-step episodes: autoreset included
        obs, r, term, trunc, info = venv.step(rng.uniform(-5, 5, (3, 7)))
        out.append(obs)
    venv.close()
    return np.array(out)


def test_seeded_vector_env_is_reproducible():
    a, b, c = rollout(11), rollout(11), rollout(12)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)
    assert not np.array_equal(a[:, 0], a[:, 1])  # copies differ (seeded s + k)
