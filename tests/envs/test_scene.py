"""An environment's ground and randomisation: a fresh rough patch per reset as MuJoCo collides it, factors in range."""

import re

import mujoco
import numpy as np
import pytest

pytest.importorskip("gymnasium", reason="the Gymnasium environments need gymnasium (the rl extra)")

from hexabot_sim.envs.command import LeggedCommandEnv
from hexabot_sim.envs.joints import LeggedJointsEnv
from hexabot_sim.envs.scene import ROUGHNESS, SLOPE_DEG, STAIRS, terrain_keywords


def ray_heights(env, x, y):
    """Ground heights under (x, y) by MuJoCo's own ray casting (the robot's geoms excluded: group 0 only)."""
    geomgroup = np.array([1, 0, 0, 0, 0, 0], dtype=np.uint8)
    geomid = np.zeros(1, dtype=np.int32)
    out = []
    for xi, yi in zip(x, y, strict=True):
        dist = mujoco.mj_ray(env.model, env.data, np.array([xi, yi, 1.0]), np.array([0.0, 0.0, -1.0]), geomgroup, 1,
                             -1, geomid)  # fmt: skip
        out.append(1.0 - dist)
    return np.array(out)


def test_every_reset_draws_a_fresh_patch_that_mujoco_collides():
    env = LeggedJointsEnv(terrain="rough", roughness=0.02)
    rng = np.random.default_rng(0)
    x, y = rng.uniform(-1.0, 1.0, (2, 40))
    patches = []
    for seed in (0, 1):
        env.reset(seed=seed)
        truth = env.scene.ground.rough.surface(x, y)  # the patch's own heights (terrain/heightfield.py)
        assert np.allclose(ray_heights(env, x, y), truth, rtol=0, atol=1e-9)
        assert np.abs(truth).max() > 0.005
        patches.append(truth)
    assert not np.allclose(patches[0], patches[1])  # a new seed from the environment's RNG
    env.reset(seed=0)
    assert np.array_equal(env.scene.ground.rough.surface(x, y), patches[0])


def test_robot_starts_on_the_new_patch_without_falling():
    env = LeggedJointsEnv(terrain="rough", roughness=0.03)
    for seed in range(3):
        obs, _ = env.reset(seed=seed)
        assert -obs[2] > 0.95  # nearly level after landing
        assert obs[env.obs_slices["foot_touch"]].sum() > 5.0  # standing on its feet
        assert env.data.sensordata[env._plate] == 0.0  # the plate clear of the bumps


def test_randomised_factors_are_drawn_in_range_from_the_nominal_model():
    env = LeggedJointsEnv(randomize_friction=(0.5, 1.5), randomize_mass=(0.8, 1.2), randomize_servo_gain=(0.9, 1.1))
    nominal = LeggedJointsEnv()
    m0, sc = nominal.model, env.scene
    draws = []
    for seed in range(3):
        env.reset(seed=seed)
        m = env.model
        friction = m.geom_friction[sc.feet, 0] / m0.geom_friction[sc.feet, 0]
        mass = m.body_mass[sc.torso] / m0.body_mass[sc.torso]
        kp = m.actuator_gainprm[sc.pos_act, 0] / m0.actuator_gainprm[sc.pos_act, 0]
        kv = m.actuator_gainprm[sc.vel_act, 0] / m0.actuator_gainprm[sc.vel_act, 0]
        assert ((0.5 <= friction) & (friction <= 1.5)).all() and 0.8 <= mass <= 1.2
        assert ((0.9 <= kp) & (kp <= 1.1)).all() and np.allclose(kp, kv)
        assert np.allclose(m.actuator_biasprm[sc.pos_act, 1], -m.actuator_gainprm[sc.pos_act, 0])
        assert np.allclose(m.body_inertia[sc.torso] / m0.body_inertia[sc.torso], mass)
        # The subtree mass MuJoCo derives from the masses follows (mj_setConst).
        assert m.body_subtreemass[sc.torso] == pytest.approx(m0.body_subtreemass[sc.torso] + m.body_mass[sc.torso]
                                                             - m0.body_mass[sc.torso])  # fmt: skip
        draws.append(mass)
    assert len(set(draws)) == 3


def test_stairs_are_where_mujoco_collides_them():
    env = LeggedJointsEnv(terrain="stairs", stairs=(0.05, 0.3, 4))
    env.reset(seed=0)
    x = np.linspace(-0.3, 2.5, 57)
    y = np.full(x.size, 0.2)
    # Closed form: 0 before 0.5 m, then 5 cm more every 0.3 m, the fourth step's top the landing beyond.
    expected = 0.05 * np.clip(np.floor((x - 0.5) / 0.3) + 1, 0, 4)
    inside = np.abs((x - 0.5) / 0.3 - np.round((x - 0.5) / 0.3)) > 1e-6  # not on an edge
    assert np.allclose(ray_heights(env, x, y)[inside], expected[inside], rtol=0, atol=1e-9)
    assert np.allclose(env.scene.ground.surface(x, y)[inside], expected[inside], rtol=0, atol=1e-9)


@pytest.mark.parametrize(
    ("stairs", "words"),
    [((0.0, 0.25, 3), "stairs rise must be 0 < rise <= 0.1 m; got 0.0"), ((0.04, 0.25, 2.5), "an integer"),
     ((0.04, 0.01, 3), "stairs run must be 0.05 <= run <= 2 m"), ("steps", "stairs must be (rise [m], run [m], count)"),
     ((float("nan"), 0.25, 3), "got nan"), ((0.04, 0.25), "stairs must be"),
     ("abc", "stairs must be (rise [m], run [m], count); got 'abc'"),  # not "stairs rise ...; got 'a'"
     ({"rise": 0.04, "run": 0.25, "count": 3}, "stairs must be (rise [m], run [m], count); got {")],
)  # fmt: skip
def test_bad_stairs_are_refused_naming_what_is_allowed(stairs, words):
    with pytest.raises(ValueError, match=re.escape(words)):
        LeggedJointsEnv(terrain="stairs", stairs=stairs)


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [({"terrain": "flat", "stairs": "junk"}, "stairs is the stairs terrain's: it has no effect on terrain='flat'"),
     ({"terrain": "rough", "slope_deg": -5}, "slope_deg is the slope terrain's: it has no effect on terrain='rough'"),
     ({"terrain": "slope", "roughness": 0.02}, "roughness is the rough terrain's: it has no effect on terrain='slope'"),
     ({"terrain": "flat", "slope_deg": 10.0}, "choose terrain='slope' or leave slope_deg out"),  # even its default
     ({"terrain": "hills", "slope_deg": 10.0}, "unknown terrain 'hills'; known: flat, slope, rough, stairs")],
)  # fmt: skip
def test_a_terrain_keyword_given_with_another_terrain_is_refused(kwargs, words):
    """terrain="flat", slope_deg=20 used to walk on the flat without a word: each terrain's keyword is refused with
    another terrain (both environments), as a walk parameter the run makes no use of is."""
    for env in (LeggedJointsEnv, LeggedCommandEnv):
        with pytest.raises(ValueError, match=re.escape(words)) as e:
            env(**kwargs)
        assert "\n" not in str(e.value)


def test_a_terrain_keyword_not_given_takes_its_default():
    assert terrain_keywords("slope", None, None, None) == (SLOPE_DEG, ROUGHNESS, STAIRS)
    assert terrain_keywords("stairs", None, None, (0.05, 0.3, 4)) == (SLOPE_DEG, ROUGHNESS, (0.05, 0.3, 4))
    assert LeggedJointsEnv(terrain="slope").scene.slope.slope_deg == SLOPE_DEG


def test_rough_ground_for_fast_commands_is_refused_at_make_with_the_speed_that_fits(monkeypatch):
    """terrain='rough' lays a square patch holding any episode's walk: at 1 m/s 8.4e6 points (25 s and ~1 GB to build,
    several GB at the 3 m/s command_range allows, times num_envs in a vector environment). Above the heightfield limit
    the environment is refused at make, naming the largest speed; that speed builds (checked under a smaller limit,
    which the refusal follows: a patch near the real one takes seconds to draw)."""
    from hexabot_sim.envs import scene

    with pytest.raises(ValueError, match=r"terrain='rough' for commanded speeds up to 1 m/s lays a 57.8 m square") as e:
        LeggedJointsEnv(terrain="rough", command_range=((0, 1.0), (0, 0), (0, 0)))
    assert "\n" not in str(e.value) and "keep command_range's vx and vy within +-0.477 m/s" in str(e.value)
    monkeypatch.setattr(scene, "MAX_POINTS", 200_000)
    with pytest.raises(ValueError, match=r"\(at most 2e\+05\): keep command_range's vx and vy within \+-0.135 m/s"):
        LeggedJointsEnv(terrain="rough", command_range=((0, 0.2), (0, 0), (0, 0)))
    env = LeggedJointsEnv(terrain="rough", command_range=((-0.135, 0.135), (0, 0), (0, 0)))
    assert 150_000 < env.scene.ground.rough.points() <= 200_000
