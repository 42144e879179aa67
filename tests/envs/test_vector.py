"""The batched joint-level environment (mujoco.rollout) against the single environment it batches."""

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium", reason="the Gymnasium environments need gymnasium (the rl extra)")

import hexabot_sim.envs  # noqa: E402, F401 (registers the ids)
from hexabot_sim.envs.joints import LeggedJointsEnv  # noqa: E402
from hexabot_sim.envs.vector import LeggedJointsVectorEnv  # noqa: E402


def test_reset_and_step_agree_with_the_single_environment():
    """Resets bit for bit; one action to the solver's tolerance (rollout starts it without the warm start). The
    vector env reads the reward from sensors and its states, the single one from MjData's frames and velocities:
    two computations of the same terms."""
    vec = LeggedJointsVectorEnv(num_envs=3, threads=2, terrain="rough", randomize_servo_gain=(0.8, 1.2))
    obs, _ = vec.reset(seed=[4, 5, 6])
    actions = np.random.default_rng(0).uniform(-1.0, 1.0, (3, 18))
    vobs, vreward, vterm, vtrunc, vinfo = vec.step(actions)
    for i, seed in enumerate((4, 5, 6)):
        single = LeggedJointsEnv(terrain="rough", randomize_servo_gain=(0.8, 1.2))
        sobs, _ = single.reset(seed=seed)
        assert np.array_equal(obs[i], sobs)
        sobs, sreward, sterm, _, sinfo = single.step(actions[i])
        assert np.allclose(vobs[i], sobs, rtol=0, atol=1e-6)
        assert vreward[i] == pytest.approx(sreward, abs=1e-6)
        assert vinfo["foot_slip"][i] == pytest.approx(sinfo["foot_slip"], abs=1e-6)
        assert vinfo["power"][i] == pytest.approx(sinfo["power"], rel=1e-6)
        assert vterm[i] == sterm and not vtrunc[i]


def test_threads_do_not_change_the_episodes():
    def run(threads):
        vec = LeggedJointsVectorEnv(num_envs=4, threads=threads)
        vec.reset(seed=0)
        rng = np.random.default_rng(1)
        for _ in range(5):
            obs, *_ = vec.step(rng.uniform(-1.0, 1.0, (4, 18)))
        return obs

    assert np.array_equal(run(1), run(2))


def test_episodes_restart_on_the_step_after_they_end():
    vec = gymnasium.make_vec("hexabot_sim/HexabotJoints-v0", num_envs=2, max_episode_steps=2)
    assert isinstance(vec, LeggedJointsVectorEnv)  # make_vec's default for this id
    vec.reset(seed=0)
    zeros = np.zeros((2, 18))
    truncated = [vec.step(zeros)[3] for _ in range(5)]
    assert [t.tolist() for t in truncated] == [[False, False], [True, True], [False, False], [False, False],
                                               [True, True]]  # fmt: skip
    obs, reward, *_ = vec.step(zeros)
    assert (reward == 0.0).all() and vec.observation_space.contains(obs.astype(np.float64))


def test_bad_actions_and_arguments_say_what_is_allowed():
    vec = LeggedJointsVectorEnv(num_envs=2)
    with pytest.raises(RuntimeError, match=r"call reset\(\) before step\(\)"):  # it stepped from an all-zero state
        vec.step(np.zeros((2, 18)))
    vec.reset(seed=0)
    with pytest.raises(ValueError, match=r"real numbers in \[-1, 1\], shape \(2, 18\)"):  # imaginary part was dropped
        vec.step(np.zeros((2, 18)) + 1j)
    with pytest.raises(ValueError, match="max_episode_steps must be an integer >= 1; got 0"):
        LeggedJointsVectorEnv(num_envs=1, max_episode_steps=0)
    with pytest.raises(ValueError, match=r"shape \(2, 18\)"):
        vec.step(np.zeros(18))
    with pytest.raises(ValueError, match="finite"):
        vec.step(np.full((2, 18), np.nan))
    with pytest.raises(ValueError, match="num_envs must be an integer >= 1"):
        LeggedJointsVectorEnv(num_envs=0)


@pytest.mark.parametrize("threads", [-1, 0.5, "2", True])
def test_bad_threads_say_what_is_allowed(threads):
    """Found by fuzzing: threads=-1 was MuJoCo's 'The list of data instances is empty', 0.5 and "2" TypeErrors."""
    with pytest.raises(ValueError, match=r"threads must be an integer >= 1 or None \(one per core\); got "):
        LeggedJointsVectorEnv(num_envs=1, threads=threads)


def test_a_numpy_integer_is_a_number_of_environments():
    """num_envs=np.int64(2) was refused as 'not an integer' (max_episode_steps takes numpy integers)."""
    assert LeggedJointsVectorEnv(num_envs=np.int64(2)).num_envs == 2


def test_a_long_episode_is_not_taken_for_a_divergence():
    # The expected time was frame_skip x timestep added at once: it drifted from MuJoCo's (one timestep a step) by
    # 1e-9 s after 355 s, and a standing robot's episode ended at step 17752 as "diverged". Here from 10^6 s on.
    vec = LeggedJointsVectorEnv(num_envs=2, threads=1, max_episode_steps=100)
    vec.reset(seed=0)
    first = vec.envs[0]
    home = first.model.key_ctrl[first.scene.key, first.scene.pos_act]
    stand = np.tile((home - first._low) / first._half - 1.0, (2, 1))
    vec._state[:, 0] = vec._time[:] = 1e6  # the time a long episode reaches, without the hours of stepping
    for _ in range(10):
        _, _, terminated, _, info = vec.step(stand)
        assert not info["diverged"].any() and not terminated.any()


@pytest.mark.parametrize("seed", ["a", 1.5, True])
def test_a_seed_that_is_not_an_integer_says_so(seed):
    """reset(seed="a") was a TypeError from "a" + 0."""
    vec = LeggedJointsVectorEnv(num_envs=2, threads=1)
    with pytest.raises(ValueError, match=r"seed must be an integer, a list of one per environment, or None; got "):
        vec.reset(seed=seed)
    obs, _ = vec.reset(seed=np.int64(3))
    assert np.array_equal(obs[1], LeggedJointsEnv().reset(seed=4)[0])
