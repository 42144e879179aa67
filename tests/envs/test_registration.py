"""The environments as a Gymnasium user meets them: by id, in a fresh interpreter, vectorised in subprocesses."""

import subprocess
import sys

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium", reason="the Gymnasium environments need gymnasium (the rl extra)")

import hexabot_sim.envs  # noqa: E402

IDS = [f"{hexabot_sim.envs.NAMESPACE}/{name}" for name in hexabot_sim.envs.ENVS]


@pytest.mark.slow
def test_make_by_module_prefix_without_importing_the_package_first():
    code = (
        "import sys, gymnasium\n"
        "env = gymnasium.make('hexabot_sim.envs:hexabot_sim/HexabotJoints-v0')\n"
        "obs, _ = env.reset(seed=0)\n"
        "print(obs.shape, env.spec.max_episode_steps, 'hexabot_sim' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=True)
    assert out.stdout.split() == ["(54,)", "1000", "True"]


@pytest.mark.parametrize("env_id", IDS)
def test_every_id_makes_its_environment_with_a_time_limit(env_id):
    env = gymnasium.make(env_id)
    obs, _ = env.reset(seed=0)
    assert env.observation_space.contains(obs)
    assert env.spec.max_episode_steps * env.unwrapped.dt == pytest.approx(20.0)
    env.close()


@pytest.mark.slow
def test_async_vector_env_steps_in_subprocesses():
    envs = gymnasium.make_vec("hexabot_sim/HexabotJoints-v0", num_envs=2, vectorization_mode="async")
    obs, _ = envs.reset(seed=[1, 2])
    assert obs.shape == (2, 54) and not np.array_equal(obs[0], obs[1])
    for _ in range(3):
        obs, reward, *_ = envs.step(envs.action_space.sample())
    assert obs.shape == (2, 54) and np.isfinite(reward).all()
    envs.close()
