"""The twist-level environment: the gait controller follows the policy's twist, checked as Gymnasium checks."""

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium", reason="the Gymnasium environments need gymnasium (the rl extra)")

from gymnasium.utils.env_checker import check_env, env_render_passive_checker  # noqa: E402

import hexabot_sim.envs  # noqa: E402, F401 (registers the ids)
from hexabot_sim.envs.command import LeggedCommandEnv  # noqa: E402


def action_for(env, twist, step_height=0.03):
    """The normalised action that asks for `twist` (vx, vy, yaw rate) and `step_height`."""
    lo, hi = env.ranges[:, 0], env.ranges[:, 1]
    return 2.0 * (np.array([*twist, step_height]) - lo) / (hi - lo) - 1.0


@pytest.mark.slow
def test_check_env_passes_with_frames(gl_backend):
    env = gymnasium.make("hexabot_sim/HexabotCommand-v0", render_mode="rgb_array", width=64, height=48).unwrapped
    check_env(env, skip_render_check=True)  # every render mode: test_joints.py's test of the same name says why
    env_render_passive_checker(env)
    env.close()


def test_the_body_walks_at_the_twist_it_is_given():
    """Measured from MuJoCo's free joint (info's velocities): the verified gait delivers the twist asked for."""
    env = LeggedCommandEnv()
    env.reset(seed=0)
    twist = (0.08, -0.03, 0.15)
    speeds = []
    for k in range(40):
        _, _, terminated, _, info = env.step(action_for(env, twist))
        assert not terminated
        assert np.allclose(info["twist"], twist) and info["step_height"] == pytest.approx(0.03)
        if k >= 20:  # after the first 2 s
            speeds.append((info["vx"], info["vy"], info["yaw_rate"]))
    assert np.allclose(np.mean(speeds, axis=0), twist, rtol=0.15, atol=0.005)


def test_same_seed_same_episode_bit_for_bit_on_rough_ground():
    def episode(seed):
        env = LeggedCommandEnv(terrain="rough")
        env.action_space.seed(seed)
        rows = [env.reset(seed=seed)[0]]
        rows += [env.step(env.action_space.sample())[0] for _ in range(6)]
        return np.array(rows)

    assert np.array_equal(episode(3), episode(3))


def test_action_bounds_stay_finite_on_a_slope():
    env = LeggedCommandEnv(terrain="slope", slope_deg=15.0)
    env.reset(seed=0)
    for k in range(12):
        obs, reward, terminated, _, _ = env.step(np.full(4, 1.0 if k % 2 else -1.0))
        assert np.isfinite(obs).all() and np.isfinite(reward) and not terminated


def test_ranges_the_legs_cannot_deliver_are_refused():
    with pytest.raises(ValueError, match="twist_range and step_height_range must hold commands the legs can deliver"):
        LeggedCommandEnv(twist_range=((-0.9, 0.9), (-0.1, 0.1), (-0.4, 0.4)))
    with pytest.raises(ValueError, match=r"shape \(4,\)"):
        env = LeggedCommandEnv()
        env.reset(seed=0)
        env.step(np.zeros(3))


def test_a_step_height_the_legs_cannot_lift_names_the_environments_keyword(tmp_path):
    """A short-legged quadruped file cannot step in place at the default range's 4.5 cm: the refusal advised the walk's
    "lengthen 'period' or lower 'step_height' (or raise 'max_joint_speed')", none of them this environment's keywords;
    a lower step_height_range makes it."""
    from pathlib import Path

    from hexabot_sim.robots import quadbot

    text = Path(quadbot.__file__).with_name("quadbot.toml").read_text()
    for old, new in (("l2 = 0.1 ", "l2 = 0.05 "), ("l3 = 0.1 ", "l3 = 0.05 "), ("height = 0.07", "height = 0.05"),
                     ("reach = 0.13", "reach = 0.09")):  # fmt: skip
        text = text.replace(old, new)
    path = tmp_path / "short.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match=r"step height 0\.045: even stepping in place is infeasible with the crawl "
                       r"gait .* above 0\.9 x max_joint_speed; lower step_height_range$"):  # fmt: skip
        LeggedCommandEnv(robot=str(path))
    assert LeggedCommandEnv(robot=str(path), step_height_range=(0.015, 0.03)).ranges[3, 1] == 0.03


def test_an_unknown_keyword_is_a_value_error_naming_the_known_ones():
    """gymnasium.make(..., reset_noise_scale=0.1) (a joints environment's keyword) was a TypeError naming nothing."""
    with pytest.raises(ValueError, match="unknown keyword 'reset_noise_scale' of LeggedCommandEnv; known: robot, "):
        gymnasium.make("hexabot_sim/HexabotCommand-v0", reset_noise_scale=0.1)
    with pytest.raises(ValueError, match=r"frame_skip must be an integer >= 1 and <= 10000"):
        LeggedCommandEnv(frame_skip=10**30)


def test_a_slope_too_steep_for_a_level_body_says_the_steepest():
    """terrain="slope", slope_deg=30 (allowed: <= 30) was the start pose's IKError, 'foot target (0.13, ...) m is
    out of reach', naming no keyword."""
    with pytest.raises(ValueError, match=r"^slope_deg 30 is too steep for this controller: a level body on a 30 deg "
                       r"slope .* the steepest levelled slope is 21\.5 deg$"):  # fmt: skip
        LeggedCommandEnv(terrain="slope", slope_deg=30)


def test_a_slower_robot_gets_the_largest_part_of_the_default_ranges_its_legs_deliver():
    """The quadbot's crawl cannot deliver the hexabot's default twists (it was refused with the defaults): its default
    ranges are TWIST_RANGE scaled to the largest feasible part (to 1 %), and it walks at the twist it is given."""
    from hexabot_sim.envs.command import TWIST_RANGE

    env = LeggedCommandEnv(robot="quadbot")
    scale = env.ranges[0, 1] / TWIST_RANGE[0][1]
    assert 0.05 < scale < 1.0
    assert np.allclose(env.ranges[:3], np.array(TWIST_RANGE) * scale)
    wider = np.array(TWIST_RANGE) * (scale + 0.02)
    with pytest.raises(ValueError, match="must hold commands the legs can deliver"):
        LeggedCommandEnv(robot="quadbot", twist_range=wider)
    assert np.allclose(LeggedCommandEnv().ranges[:3], TWIST_RANGE)  # the hexabot delivers all of it
    env.reset(seed=0)
    twist = (0.05, 0.0, 0.0)
    speeds = []
    for k in range(60):
        _, _, terminated, _, info = env.step(action_for(env, twist, 0.03))
        assert not terminated
        if k >= 30:  # after the first 3 s
            speeds.append((info["vx"], info["vy"], info["yaw_rate"]))
    assert np.allclose(np.mean(speeds, axis=0), twist, rtol=0.15, atol=0.005)


def test_the_controller_writes_the_controls_and_mujoco_steps_them():
    """The controls seen at every physics step (MuJoCo's control callback), replayed with bare mj_step from the same
    start: the same state bit for bit."""
    import mujoco

    env = LeggedCommandEnv()
    env.reset(seed=1)
    m = env.model
    spec = mujoco.mjtState.mjSTATE_INTEGRATION
    start = np.empty(mujoco.mj_stateSize(m, spec))
    mujoco.mj_getState(m, env.data, start, spec)
    controls = []
    mujoco.set_mjcb_control(lambda model, data: controls.append(data.ctrl.copy()))
    try:
        for _ in range(3):
            env.step(action_for(env, (0.05, 0.02, 0.1)))
    finally:
        mujoco.set_mjcb_control(None)
    assert len(controls) == 3 * env.frame_skip
    bare = mujoco.MjData(m)
    mujoco.mj_setState(m, bare, start, spec)
    for ctrl in controls:
        bare.ctrl[:] = ctrl
        mujoco.mj_step(m, bare)
    assert np.array_equal(bare.qpos, env.data.qpos)


def test_a_new_step_height_lifts_a_swinging_foot_smoothly():
    """The step height of an action ramps in over its control period: no foot target jumps (setting the planner's
    step height moved a mid-swing foot's target by up to the range's 3 cm at once). Measured on the controller's
    published hip-frame targets, step by step, with the step height switching between its ends every action."""
    env = LeggedCommandEnv()
    env.reset(seed=0)
    published = []
    publish = env.controller._publish
    env.controller._publish = lambda rows, stance: (published.append(rows.copy()), publish(rows, stance))[1]
    for k in range(30):
        env.step(action_for(env, (0.05, 0.0, 0.0), 0.015 if k % 2 else 0.045))
    rows = np.concatenate([published[0][:1], *(chunk[1:] for chunk in published)])  # row 0 repeats the last
    assert len(rows) == 30 * env.frame_skip + 1
    fastest = np.abs(np.diff(rows, axis=0)).max()  # [m] per 2 ms step, any coordinate of any foot
    # A swing's own lift moves a foot at most pi h / T_swing (0.045 m over 0.5 s): 0.6 mm a step; the ramp of
    # 3 cm over 0.1 s adds at most 0.6 mm more.
    assert fastest < 0.002, fastest


@pytest.mark.slow
def test_the_gait_controller_climbs_the_stairs_with_its_reflex():
    """Walking forward at 0.05 m/s (mid step height), the body ends two steps (8 cm) up, never having fallen."""
    env = LeggedCommandEnv(terrain="stairs", command_range=((0.05, 0.05), (0.0, 0.0), (0.0, 0.0)))
    env.reset(seed=0)
    z0 = float(env.data.qpos[2])
    forward = np.array([1 / 3, 0.0, 0.0, 0.0])  # vx = 0.05 m/s on the default twist range
    for _ in range(220):  # 22 s: the body's centre 1.1 m ahead, past the second step's edge (0.75 m)
        _, reward, terminated, _, _ = env.step(forward)
        assert not terminated and np.isfinite(reward)
    assert env.data.qpos[0] > 1.0 and env.data.qpos[2] - z0 > 0.075


def test_a_stair_rise_is_checked_at_the_step_heights_the_environment_walks_with():
    """The rise is checked with step_height_range's low end (not the walk's default 3 cm), and a refusal names
    the environment's arguments, not the walk's parameters it does not take (stand_height, step_height)."""
    high = LeggedCommandEnv(terrain="stairs", stairs=(0.06, 0.25, 3), step_height_range=(0.045, 0.045))
    assert high.p_controller.stairs_rise == 0.06  # 2 x 4.5 cm less a foot radius climbs 6 cm
    for stairs, words in (((0.06, 0.25, 3), "above the largest climbable step"), ((0.1, 0.05, 3), "hit the plate")):
        with pytest.raises(ValueError, match=r"^stairs rise 0\.\d+ m at step height 0\.03 m") as e:  # default range
            LeggedCommandEnv(terrain="stairs", stairs=stairs)
        message = str(e.value)
        assert words in message and "step_height_range" in message and "'stand_height'" not in message
        assert "'step_height'" not in message and "\n" not in message


def test_a_copy_after_reset_is_refused_in_one_line():
    # Its controller's arrays are views of the live MjData; a deepcopy failed deep in copy ("cannot pickle 'module'").
    import copy

    env = LeggedCommandEnv()
    twin = copy.deepcopy(env)  # before reset: nothing live yet
    assert np.array_equal(env.reset(seed=2)[0], twin.reset(seed=2)[0])
    with pytest.raises(TypeError, match=r"cannot be copied or pickled after reset\(\)"):
        copy.deepcopy(env)


def test_reset_options_are_refused_not_ignored():
    with pytest.raises(ValueError, match=r"reset\(\) takes no options"):
        LeggedCommandEnv().reset(seed=0, options={"terrain": "stairs"})
