"""The joint-level environments against Gymnasium's checker, MuJoCo's own frames and the bounds of their spaces."""

import math
import re
import warnings

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium", reason="the Gymnasium environments need gymnasium (the rl extra)")

from gymnasium.utils.env_checker import check_env, env_render_passive_checker  # noqa: E402

import hexabot_sim.envs  # noqa: E402, F401 (registers the ids)
from hexabot_sim.envs.joints import LeggedJointsEnv  # noqa: E402


@pytest.mark.parametrize("robot", ["hexabot", "quadbot"])
def test_check_env_passes_with_frames(robot, gl_backend):
    name = f"hexabot_sim/{robot.capitalize()}Joints-v0"
    env = gymnasium.make(name, render_mode="rgb_array", width=64, height=48).unwrapped  # with its spec
    # Spaces, reset/step API, seeding determinism, close. Its render check makes the env in every declared mode, the
    # window of "human" too: it runs under Xvfb in test_render_human.py (Gymnasium's Ant-v5 aborts here without a
    # display); rgb_array's frames are checked here as it checks them.
    check_env(env, skip_render_check=True)
    env_render_passive_checker(env)
    env.reset(seed=3)
    frame = env.render()
    assert frame.shape == (48, 64, 3) and frame.dtype == np.uint8 and frame.std() > 0
    env.close()


@pytest.mark.parametrize("terrain", ["slope", "rough", "stairs"])
def test_check_env_passes_on_every_terrain(terrain):
    check_env(gymnasium.make("hexabot_sim/HexabotJoints-v0", terrain=terrain).unwrapped, skip_render_check=True)


def test_spaces_have_the_documented_sizes():
    for robot, legs in (("hexabot", 6), ("quadbot", 4)):
        env = LeggedJointsEnv(robot=robot)
        assert env.action_space.shape == (3 * legs,)
        assert env.observation_space.shape == (12 + 7 * legs,)
        assert env.obs_slices["command"].stop == 12 + 7 * legs
        assert env.metadata["render_fps"] == 50  # 10 steps of 2 ms


def test_same_seed_same_episode_bit_for_bit():
    def episode(seed):
        env = LeggedJointsEnv(terrain="rough", randomize_friction=(0.7, 1.3), randomize_servo_gain=(0.8, 1.2))
        env.action_space.seed(seed)
        obs, _ = env.reset(seed=seed)
        rows, rewards = [obs], []
        for _ in range(20):
            obs, reward, *_ = env.step(env.action_space.sample())
            rows.append(obs)
            rewards.append(reward)
        return np.array(rows), np.array(rewards)

    a, b, c = episode(7), episode(7), episode(8)
    assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])
    assert not np.array_equal(a[0], c[0])


def test_gravity_and_joints_are_mujocos_own():
    """The observation against MuJoCo's body frame (xmat) and state, on a slope where the body starts tilted.

    The sensors are read as MuJoCo computed them in the last physics step, before its integration, as the body's
    frame (xmat); the joint angles and speeds are the state after it.
    """
    env = LeggedJointsEnv(terrain="slope", slope_deg=10.0)
    obs, _ = env.reset(seed=0)
    obs, *_ = env.step(env.action_space.sample())
    d = env.data
    rot = d.xmat[env.model.body("torso").id].reshape(3, 3)
    s = env.obs_slices
    assert np.allclose(obs[s["gravity"]], rot.T @ [0.0, 0.0, -1.0], rtol=0, atol=1e-12)
    assert math.degrees(math.acos(-obs[2])) == pytest.approx(10.0, abs=2.0)  # parallel to the 10 deg slope
    assert np.array_equal(obs[s["joint_angles"]], d.qpos[7:])
    assert np.array_equal(obs[s["joint_speeds"]], d.qvel[6:])
    assert np.array_equal(obs[s["command"]], env.command)


def test_standing_reads_the_weight_on_the_feet():
    """At rest the touch sensors carry the robot's weight and the accelerometer reads +g up (specific force)."""
    env = LeggedJointsEnv()
    obs, _ = env.reset(seed=0)
    m = env.model
    weight = float(m.body_subtreemass[m.body("torso").id]) * 9.81
    assert obs[env.obs_slices["foot_touch"]].sum() == pytest.approx(weight, rel=0.02)
    assert obs[8] == pytest.approx(9.81, rel=0.01)


@pytest.mark.parametrize("ground", [{"terrain": "rough", "roughness": 0.03}, {"terrain": "slope", "slope_deg": 30.0}])
def test_action_bounds_and_the_worst_ground_stay_finite(ground):
    """Bang-bang actions at the bounds (and beyond them: clipped) on the roughest ground and the steepest slope:
    no NaN, ever."""
    env = LeggedJointsEnv(**ground)
    for seed in range(2):
        obs, _ = env.reset(seed=seed)
        for k in range(60):
            action = np.full(18, 1.0 if (k // 5) % 2 else -1.0) * (3.0 if k % 7 == 0 else 1.0)
            obs, reward, terminated, _, info = env.step(action)
            assert np.isfinite(obs).all() and math.isfinite(reward)
            if terminated:
                assert info["fell"] or info["diverged"]
                break


def test_target_mapping_reaches_the_servo_ranges():
    env = LeggedJointsEnv()
    env.reset(seed=0)
    lo, hi = env.model.actuator_ctrlrange[:18].T
    env.step(np.full(18, -1.0))
    assert np.array_equal(env.data.ctrl[:18], lo)
    env.step(np.full(18, 1.0))
    assert np.allclose(env.data.ctrl[:18], hi, rtol=0, atol=1e-12)
    assert not env.data.ctrl[18:].any()  # the velocity servos: pure damping


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        ({"terrain": "lava"}, "unknown terrain 'lava'; known: flat, slope, rough, stairs"),
        ({"frame_skip": -1}, "frame_skip must be an integer >= 1"),
        ({"frame_skip": 0}, "frame_skip must be an integer >= 1"),
        ({"robot": "octobot"}, "unknown robot 'octobot'; known: hexabot, quadbot"),
        ({"terrain": "rough", "roughness": 0.5}, "roughness must be > 0 and <= 0.03 m"),
        ({"randomize_mass": (1.2, 0.8)}, "randomize_mass must be (low, high)"),
        ({"command_range": ((0, 1),)}, "command_range must be three (low, high) pairs"),
        ({"reward": {"velocity_sigma": 0.0}}, "reward velocity_sigma must be a number from 1e-06 to 1e+06"),
        # Each of these was a TypeError, a KeyError at the first render(), a ZeroDivisionError at the first step or
        # an infinite reward, not a ValueError naming what is allowed:
        ({"terrain": "slope", "slope_deg": "10"}, "slope_deg must be > 0 and <= 30 deg (a number); got '10'"),
        ({"terrain": "slope", "slope_deg": True}, "slope_deg must be > 0 and <= 30 deg (a number); got True"),
        ({"terrain": "rough", "roughness": [0.01]}, "roughness must be > 0 and <= 0.03 m (a number); got [0.01]"),
        ({"reward": {"slipp": 1.0}}, "unknown reward field 'slipp'; known: velocity, yaw, velocity_sigma"),
        ({"reward": "slip"}, "reward must be a Reward, a dict of its fields or None; got str"),
        ({"reward": {"slip": "1"}}, "reward slip must be a number from 0 to 1e+06; got '1'"),
        ({"reward": {"velocity_sigma": 1e-300}}, "reward velocity_sigma must be a number from 1e-06 to 1e+06"),
        ({"reward": {"energy": 1e308}}, "reward energy must be a number from 0 to 1e+06; got 1e+308"),
        ({"camera": "nocam"}, "unknown camera 'nocam'; known: track, top"),
        ({"camera": 3}, "unknown camera 3; known: track, top"),
        ({"render_mode": "ansi"}, "unknown render_mode 'ansi'; known: None, human, rgb_array"),
        ({"width": 0}, "width must be an integer from 1 to 8192 pixels"),
        # Found by fuzzing: a TypeError (from Python, or from mj_step at the first step), or a string taken as a pair.
        ({"terain": "flat"}, "unknown keyword 'terain' of LeggedJointsEnv; known: robot, frame_skip, terrain,"),
        ({"frame_skip": 2**70}, "frame_skip must be an integer >= 1 and <= 10000 (a control period of at most 20 s)"),
        ({"randomize_friction": "12"}, "randomize_friction must be a pair (low, high) or None; got '12'"),
        ({"reset_noise_scale": False}, "reset_noise_scale must be a number from 0 to 0.5 rad; got False"),
        ({"robot": ["hexabot"]}, "unknown robot ['hexabot']; known: hexabot, quadbot"),  # was: unhashable type
        # Found by fuzzing: read as the numbers 0.5 and 1.0 (a vy command of 1 m/s).
        ({"randomize_friction": ("0.5", 1.0)}, "randomize_friction must be a pair (low, high) or None; got ('0.5'"),
        ({"command_range": ((0, 0.1), (True, True), (0, 0))}, "command_range"),
    ],
)
def test_bad_arguments_say_what_is_allowed(kwargs, words):
    with pytest.raises(ValueError, match=re.escape(words)):
        LeggedJointsEnv(**kwargs)


@pytest.mark.parametrize(
    ("action", "words"),
    [
        (np.zeros(17), r"shape \(18,\)"),
        (np.full(18, np.nan), "finite"),
        (np.zeros(18) + 0.5j, "the action must be 18 real numbers in \\[-1, 1\\]; got array"),  # was: imaginary dropped
        ([object()] * 18, "the action must be 18 real numbers"),  # was: a TypeError
        ({"a": 1}, "the action must be 18 real numbers"),
    ],
)
def test_bad_actions_say_what_is_allowed(action, words):
    env = LeggedJointsEnv()
    env.reset(seed=0)
    with pytest.raises(ValueError, match=words) as info:
        env.step(action)
    assert "\n" not in str(info.value)


def test_numpy_numbers_are_numbers():
    """reset_noise_scale=np.float32(0.02) was refused as not a number (the other keywords took numpy's numbers)."""
    env = LeggedJointsEnv(reset_noise_scale=np.float32(0.02), randomize_friction=(np.float32(0.5), np.int64(1)))
    assert env.reset_noise_scale == pytest.approx(0.02)
    assert env.scene.randomization.friction == (0.5, 1.0)


def test_a_reset_by_mujoco_is_a_divergence():
    """A bad position or velocity makes MuJoCo reset the data to qpos0 and time 0 and step on: the episode went on,
    the robot teleported, diverged False (only the bad-acceleration warning was counted)."""
    env = LeggedJointsEnv()
    env.reset(seed=0)
    env.data.qvel[:6] = 1e30
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _, _, terminated, _, info = env.step(np.zeros(18))
    assert terminated and info["diverged"]
    env.reset(seed=0)
    _, _, terminated, _, info = env.step(np.zeros(18))
    assert not terminated and not info["diverged"]


def test_a_negative_zero_reset_noise_resets():
    """reset_noise_scale=-0.0 was accepted, then every reset raised numpy's 'high - low < 0'."""
    obs, _ = LeggedJointsEnv(reset_noise_scale=-0.0).reset(seed=0)
    assert np.isfinite(obs).all()


def test_step_before_reset_says_so():
    """It raised AttributeError ('_command'); the command environment already said this."""
    with pytest.raises(RuntimeError, match=r"call reset\(\) before step\(\)"):
        LeggedJointsEnv().step(np.zeros(18))


def test_a_step_is_frame_skip_physics_steps_and_nothing_else():
    """The step's physics replayed with bare mj_step from the same start, on a fresh MjData: the same state bit for
    bit (the environment reads, it does not push)."""
    import mujoco

    env = LeggedJointsEnv(terrain="rough")
    env.reset(seed=2)
    m = env.model
    spec = mujoco.mjtState.mjSTATE_INTEGRATION
    start = np.empty(mujoco.mj_stateSize(m, spec))
    mujoco.mj_getState(m, env.data, start, spec)
    bare = mujoco.MjData(m)
    mujoco.mj_setState(m, bare, start, spec)
    env.action_space.seed(2)
    for _ in range(10):
        env.step(env.action_space.sample())
        bare.ctrl[:] = env.data.ctrl
        for _ in range(env.frame_skip):
            mujoco.mj_step(m, bare)
    assert np.array_equal(bare.qpos, env.data.qpos) and np.array_equal(bare.qvel, env.data.qvel)


@pytest.mark.parametrize("how", ["deepcopy", "pickle"])
def test_a_copy_steps_its_own_physics_as_the_original_does(how):
    # A deepcopy's observations were views of the original's MjData (stale: 41 apart after one step); pickle failed on
    # MuJoCo's warning counter.
    import copy
    import pickle

    env = LeggedJointsEnv(terrain="rough")
    env.reset(seed=1)
    env.step(np.full(18, 0.3))
    twin = copy.deepcopy(env) if how == "deepcopy" else pickle.loads(pickle.dumps(env))
    for a in np.random.default_rng(0).uniform(-1, 1, (5, 18)):
        obs, reward, *_ = env.step(a)
        obs_twin, reward_twin, *_ = twin.step(a)
        assert np.array_equal(obs, obs_twin) and reward == reward_twin
    assert np.array_equal(obs_twin[twin.obs_slices["joint_angles"]], twin.data.qpos[7:])
    assert np.array_equal(env.reset(seed=4)[0], twin.reset(seed=4)[0])


@pytest.mark.parametrize("options", [{"terrain": "rough"}, "x", [1]])
def test_reset_options_are_refused_not_ignored(options):
    # They were ignored without a word: options={"terrain": "rough"} reset on the flat.
    env = LeggedJointsEnv()
    assert np.array_equal(env.reset(seed=0, options={})[0], env.reset(seed=0, options=None)[0])  # check_env's {}
    with pytest.raises(ValueError, match=r"reset\(\) takes no options \(terrain, ranges and the rest are make\(\)'s"):
        env.reset(seed=0, options=options)
    vec = gymnasium.make_vec("hexabot_sim/HexabotJoints-v0", num_envs=1)
    with pytest.raises(ValueError, match=r"reset\(\) takes no options"):
        vec.reset(seed=0, options=options)


@pytest.mark.parametrize(("frame_skip", "fps"), [(10, 50), (30, 1 / 0.06), (2000, 0.25), (10000, 0.05)])
def test_render_fps_is_the_control_rate(frame_skip, fps, gl_backend):
    # round(1 / dt) was 0 from a 2 s control period on: Gymnasium's render check (run by make) then asserted.
    name = "hexabot_sim/HexabotJoints-v0"
    env = gymnasium.make(name, frame_skip=frame_skip, render_mode="rgb_array", width=8, height=6)
    assert env.metadata["render_fps"] == pytest.approx(fps, rel=1e-12)
    assert type(env.metadata["render_fps"]) is (int if frame_skip == 10 else float)
    env.reset(seed=0)
    assert env.render().shape == (6, 8, 3)


def test_a_robot_file_is_an_environments_robot(tmp_path):
    """robot= a legged-robot file (.toml): walked as the robot whose walk takes its number of legs (six: the
    hexabot's, four: the quadbot's), in its generated model. A renamed copy of quadbot.toml gives the quadbot's
    episode bit for bit; a copy of the environment reads the file's robot too; three legs are refused."""
    import copy
    from pathlib import Path

    from hexabot_sim.robots import quadbot

    example = Path(__file__).resolve().parents[2] / "examples" / "my_hexapod.toml"
    env = LeggedJointsEnv(robot=str(example))
    assert env.action_space.shape == (18,) and env.model.site("lf_hip").pos.tolist() == [0.16, 0.09, 0.0]
    check_env(env, skip_render_check=True)
    copy_file = tmp_path / "myquad.toml"
    copy_file.write_text(Path(quadbot.__file__).with_name("quadbot.toml").read_text().replace('"quadbot"', '"myquad"'))

    def episode(robot):
        env = LeggedJointsEnv(robot=robot, terrain="rough")
        rows = [env.reset(seed=3)[0]]
        rows += [env.step(a)[0] for a in np.random.default_rng(0).uniform(-1, 1, (10, 12))]
        return env, np.array(rows)

    mine, rows = episode(str(copy_file))
    assert np.array_equal(rows, episode("quadbot")[1])
    assert np.array_equal(episode(copy_file)[1], rows)  # a pathlib.Path, as hs.run takes: it was an "unknown robot"
    # Any file, and names in any case, as the CLI's robot=: 'q.txt' and 'QuadBot' were unknown robots.
    txt = tmp_path / "q.txt"
    txt.write_text(copy_file.read_text())
    assert np.array_equal(episode(str(txt))[1], rows) and np.array_equal(episode("QuadBot")[1], rows)
    with pytest.raises(ValueError, match=r"^unknown robot 'quadbott'; known: hexabot, quadbot, or the path of"):
        LeggedJointsEnv(robot="quadbott")
    twin = copy.deepcopy(mine)
    a = np.full(12, 0.2)
    assert np.array_equal(mine.step(a)[0], twin.step(a)[0])
    three = tmp_path / "three.toml"
    three.write_text(example.read_text().replace('rows = ["f", "m", "r"]', 'names = ["a", "b", "c"]').replace(
        "hips = [[0.16, 0.09], [0.0, 0.10], [-0.16, 0.09]]", "hips = [[0.16, 0.0], [-0.1, 0.09], [-0.1, -0.09]]"
    ).replace("yaws = [45.0, 90.0, 135.0]", "yaws = [0.0, 120.0, -120.0]"))  # fmt: skip
    with pytest.raises(ValueError, match=r"^robot: robot file .*three.toml: 3 legs; the environments walk robot files "
                       r"with 4 or 6 legs$"):  # fmt: skip
        LeggedJointsEnv(robot=str(three))
    low = tmp_path / "low.toml"  # refused by the walk with "set stand_height", not a keyword of the environments
    text = copy_file.read_text()
    low.write_text(text.replace("height = 0.07", "height = 0.015").replace("0.16, 0.03]", "0.16, 0.01]"))
    refusal = r"^robot: robot file .*low.toml: \[stance\] height 0.015 m is lower than the walk's lowest stance, "
    with pytest.raises(ValueError, match=refusal + r"0.02 m \(an environment .*: give the file a taller stance$"):
        LeggedJointsEnv(robot=str(low))
    with pytest.raises(ValueError, match=r"^robot: robot file .*none.toml: cannot be read"):
        LeggedJointsEnv(robot=str(tmp_path / "none.toml"))


def test_an_environment_keeps_the_robot_file_it_was_made_with(tmp_path):
    """The model is compiled at make: a reset takes the robot from the parameters made then, not from the file again
    (a file edited to another robot had the old model reset in the new one's stance, or refused: six legs, or the
    file removed, or a pickled environment's file absent where it is loaded)."""
    import pickle
    from pathlib import Path

    from hexabot_sim.robots import quadbot

    text = Path(quadbot.__file__).with_name("quadbot.toml").read_text().replace('"quadbot"', '"myquad"')
    path = tmp_path / "myquad.toml"
    path.write_text(text)
    env = LeggedJointsEnv(robot=str(path))
    first = env.reset(seed=1)[0]
    frozen = pickle.dumps(env)
    path.write_text(text.replace("l3 = 0.1 ", "l3 = 0.14 ").replace("height = 0.07", "height = 0.1"))
    assert np.array_equal(env.reset(seed=1)[0], first)
    path.unlink()
    assert np.array_equal(env.reset(seed=1)[0], first)
    assert np.array_equal(pickle.loads(frozen).reset(seed=1)[0], first)
