"""The hexabot's ground: the terrain itself (heights against MuJoCo, rendering, contacts), the refusals (the walks on
it: test_terrain_walks.py)."""

import math

import mujoco
import numpy as np
import pytest
from helpers import compiled_scene, metric, walk_params

from hexabot_sim import registry
from hexabot_sim.errors import UsageError
from hexabot_sim.robots.hexabot import model as hx
from hexabot_sim.robots.hexabot import walk as scenario
from hexabot_sim.terrain import RoughPatch
from hexabot_sim.terrain.ground import SQUARE as TERRAIN_SQUARE
from hexabot_sim.walking import ground as walking_ground

resolve, value, compiled = walk_params, metric, compiled_scene


# --- the terrain itself ------------------------------------------------------------------------------


def test_heightfield_is_seeded_and_has_the_asked_amplitude():
    base = RoughPatch(0.01, seed=4, extent=(-0.5, 1.5, -0.6, 0.6))
    again = RoughPatch(0.01, seed=4, extent=(-0.5, 1.5, -0.6, 0.6))
    other = RoughPatch(0.01, seed=5, extent=(-0.5, 1.5, -0.6, 0.6))
    h = base.heights()
    assert np.array_equal(h, again.heights())
    assert np.abs(h - other.heights()).max() > 0.005
    assert np.abs(h).max() == pytest.approx(0.01)
    # The compiled model holds the same field (float32, normalised by MuJoCo), row 0 at the -y edge.
    p = resolve(roughness=0.01, seed=4)
    model, _ = compiled(p)
    norm, _, size = walking_ground.terrain(p).rough.hfield_levels()
    stored = model.hfield_data.reshape(model.hfield_nrow[0], model.hfield_ncol[0])
    assert np.abs(stored - norm).max() < 1e-6
    assert model.hfield_size[0][2] == pytest.approx(size)


@pytest.mark.parametrize(("heading", "uphill"), [("uphill", (1, 0)), ("downhill", (-1, 0)), ("across", (0, 1))])
def test_slope_normal_is_what_was_asked(heading, uphill):
    p = resolve(slope_deg=10.0, slope_heading=heading)
    model, data = compiled(p)
    normal = data.geom_xmat[model.geom("floor").id].reshape(3, 3)[:, 2]
    a = math.radians(10.0)
    expected = np.array([-math.sin(a) * uphill[0], -math.sin(a) * uphill[1], math.cos(a)])
    assert np.abs(normal - expected).max() < 1e-12
    # The robot walks along +x: uphill rises ahead, across rises to its left.
    ground = walking_ground.terrain(p)
    assert ground.height(0.1, 0.0) - ground.height(0.0, 0.0) == pytest.approx(0.1 * math.tan(a) * uphill[0])
    assert ground.height(0.0, 0.1) - ground.height(0.0, 0.0) == pytest.approx(0.1 * math.tan(a) * uphill[1])


@pytest.mark.slow
@pytest.mark.parametrize(
    "overrides",
    [
        {"roughness": 0.01, "seed": 3},
        {"slope_deg": 10.0, "slope_heading": "across"},
        {"kerb_height": 0.02},
        # The types compose: a rough slope, a kerb on rough ground, a kerb on a slope, all three.
        {"slope_deg": 8.0, "roughness": 0.01, "seed": 1},
        {"slope_deg": 8.0, "roughness": 0.01, "slope_heading": "across"},
        {"roughness": 0.01, "kerb_height": 0.02, "step_height": 0.04},
        {"slope_deg": 6.0, "kerb_height": 0.02},
        {"slope_deg": 6.0, "roughness": 0.005, "kerb_height": 0.02, "step_height": 0.04, "slope_heading": "downhill"},
        {"stairs_rise": 0.02, "stairs_run": 0.2, "stairs_distance": 0.4},
        {"stairs_rise": 0.02, "roughness": 0.005, "step_height": 0.04, "vy": 0.05, "seed": 2},
        {"stairs_rise": 0.03, "stairs_count": 4, "slope_deg": 6.0, "step_height": 0.05, "slope_heading": "across"},
    ],
    ids=[
        "rough",
        "slope",
        "kerb",
        "rough-slope",
        "rough-slope-across",
        "kerb-on-rough",
        "kerb-on-slope",
        "all",
        "stairs",
        "stairs-on-rough-diagonal",
        "stairs-on-slope",
    ],
)
def test_ground_height_agrees_with_mujoco_ray_casting(overrides):
    """The height function every metric and figure uses is the ground MuJoCo collides (its own ray casting)."""
    p = resolve(**overrides)
    model, data = compiled(p)
    ground = walking_ground.terrain(p)
    x0, x1, y0, y1 = ground.rough.extent if ground.rough is not None else (-1.0, 1.0, -1.0, 1.0)
    rng = np.random.default_rng(11)
    terrain_only = np.array([1, 0, 0, 0, 0, 0], dtype=np.uint8)  # group 0: floor, heightfield, kerb
    geom = np.zeros(1, dtype=np.int32)
    worst = 0.0
    # On the terrain, and up to 3 m beyond it (a robot that wanders off the rough patch still has ground).
    inside = rng.uniform([x0, y0], [x1, y1], size=(400, 2))
    around = rng.uniform([x0 - 3, y0 - 3], [x1 + 3, y1 + 3], size=(400, 2))
    for x, y in np.vstack([inside, around]):
        distance = mujoco.mj_ray(
            model, data, np.array([x, y, 1.0]), np.array([0.0, 0.0, -1.0]), terrain_only, 1, -1, geom
        )
        worst = max(worst, abs((1.0 - distance) - float(ground.height(x, y))))
    assert worst < 1e-6  # the heightfield is stored in float32


@pytest.mark.parametrize("roughness", [0.0, 0.01])
def test_ground_height_at_a_kerbs_edge_on_a_downhill_slope_is_the_one_mujoco_collides(roughness):
    """Downhill the kerb's face leans out over the slope below: a vertical line there meets the kerb, where the
    fixed-point iteration of the ground's height did not converge (42 mm off, found by fuzzing)."""
    p = resolve(
        slope_deg=20.0, slope_heading="downhill", kerb_height=0.04, step_height=0.06, friction=2.0, roughness=roughness
    )
    model, data = compiled(p)
    ground = walking_ground.terrain(p)
    terrain_only = np.array([1, 0, 0, 0, 0, 0], dtype=np.uint8)
    geom = np.zeros(1, dtype=np.int32)
    x = np.linspace(0.44, 0.5, 601) + 1.234e-6  # across the edge's band (kerb_height x tan(slope) wide)
    heights = ground.height(x, np.full(x.size, 0.05))
    worst = 0.0
    for xi, h in zip(x, heights, strict=True):
        start = np.array([xi, 0.05, 2.0])
        distance = mujoco.mj_ray(model, data, start, np.array([0.0, 0.0, -1.0]), terrain_only, 1, -1, geom)
        worst = max(worst, abs((2.0 - distance) - h))
    assert worst < 1e-6


def test_a_kerb_on_rough_ground_reaches_down_to_its_valleys():
    """The kerb's box started at the ground's level: where the bumps dipped below it, a gap (up to the
    roughness) opened under the kerb's edge for a foot to slip into."""
    p = resolve(roughness=0.01, kerb_height=0.01, step_height=0.05)
    model, _ = compiled(p)
    kerb, field = model.geom("kerb"), model.geom("terrain")
    assert kerb.pos[2] - kerb.size[2] < field.pos[2]  # the box's bottom below the heightfield's lowest valley
    assert kerb.pos[2] + kerb.size[2] == pytest.approx(0.01)  # its top where it was


def test_the_kerb_runs_on_beyond_a_long_walk_in_mujoco_and_in_the_heights():
    """A 0.2 m/s walk of 200 s goes 40 m: the kerb's 20 m pavement ended under it at 20.5 m (a step down), where
    the heights the metrics use still had the kerb. Now the pavement covers the walk, and the heights end with it."""
    terrain_only = np.array([1, 0, 0, 0, 0, 0], dtype=np.uint8)
    geom = np.zeros(1, dtype=np.int32)
    for overrides, x, top in (({"vx": 0.2, "duration": 200.0}, 40.0, 0.02), ({}, 21.0, 0.0)):
        p = resolve(kerb_height=0.02, **overrides)
        model, data = compiled(p)
        distance = mujoco.mj_ray(
            model, data, np.array([x, 0.0, 1.0]), np.array([0.0, 0.0, -1.0]), terrain_only, 1, -1, geom
        )
        on_kerb = distance >= 0 and mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, int(geom[0])) == "kerb"
        assert on_kerb == (top > 0) and (not on_kerb or 1.0 - distance == pytest.approx(top, abs=1e-9))
        assert float(walking_ground.terrain(p).height(x, 0.0)) == pytest.approx(top, abs=1e-9)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("overrides", "top"), [({"roughness": 0.01}, 0.0), ({"kerb_height": 0.03, "step_height": 0.04}, 0.03)]
)
def test_the_terrain_is_drawn_with_its_grid(gl_backend, overrides, top):
    """Looking straight down on the ground ahead of the robot, the checker repeats every 2 TERRAIN_SQUARE."""
    model, data = compiled(resolve(**overrides))
    camera = mujoco.MjvCamera()
    camera.lookat[:] = (1.3, 0.0, top)  # on the heightfield / the kerb's top, well ahead of the feet
    camera.distance, camera.elevation, camera.azimuth = 1.0, -90.0, 90.0
    with mujoco.Renderer(model, 200, 200) as renderer:
        renderer.update_scene(data, camera)
        image = renderer.render().astype(float).mean(axis=2)  # (200, 200) brightness
    width = 2 * camera.distance * math.tan(math.radians(model.vis.global_.fovy) / 2)  # [m] seen across
    # Strongest brightness period across the rows (the bumps' shading is broadband, the checker is not).
    spectrum = (np.abs(np.fft.rfft(image - image.mean(axis=1, keepdims=True), axis=1)) ** 2).mean(axis=0)
    period = width / (int(np.argmax(spectrum[1:])) + 1)
    assert period == pytest.approx(2 * TERRAIN_SQUARE, rel=0.15)  # 1 m squares (texuniform, texrepeat 1): 0.4-0.8 m


def test_the_slope_video_looks_across_the_slope():
    for heading, uphill in (("uphill", (1.0, 0.0)), ("across", (0.0, 1.0))):
        p = resolve(slope_deg=10.0, slope_heading=heading, duration=2.0)
        model, data = compiled(p)
        view = -data.cam_xmat[model.camera("slope").id].reshape(3, 3)[:, 2]  # the camera looks along -z
        assert abs(view[:2] @ np.array(uphill)) < 1e-9  # along the contour lines: the tilt shows in the frame
    assert scenario.run("hexabot-slope", resolve(slope_deg=10.0, duration=1.6)).camera == "slope"


def test_only_feet_and_plate_touch_the_terrain():
    for overrides in ({"roughness": 0.01}, {"kerb_height": 0.02}):
        model, _ = compiled(resolve(**overrides))
        names = (
            ["terrain", "floor_west", "floor_east", "floor_south", "floor_north"]
            if "roughness" in overrides
            else ["kerb"]
        )
        for name in names:
            g = model.geom(name).id
            touching = {
                model.geom(h).name
                for h in range(model.ngeom)
                if model.geom_contype[h] & model.geom_conaffinity[g]
                or model.geom_contype[g] & model.geom_conaffinity[h]
            }
            assert touching == {"torso", *(f"{leg}_foot" for leg in hx.LEGS)}, name


# --- refusals ------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("overrides", "fragment"),
    [
        ({"slope_deg": 30.0, "friction": 0.5}, "friction coefficient of at least tan(slope) = 0.578"),
        ({"slope_deg": 30.0, "level_body": "on"}, "steepest levelled slope is"),
        # Kinds compose, and so do their limits: a kerb on rough ground is climbed from the lowest valley.
        ({"roughness": 0.01, "kerb_height": 0.03, "step_height": 0.04}, "less 10 mm of rough ground"),
        ({"roughness": 0.01, "slope_deg": 30.0, "friction": 0.5}, "friction coefficient of at least"),
        # The plate 23 mm above the ground: a 20 mm kerb knocked it over (found by fuzzing).
        ({"kerb_height": 0.02, "stand_height": 0.03}, "kerb would hit the plate"),
    ],
)
def test_impossible_ground_is_refused_in_one_line(overrides, fragment):
    with pytest.raises(UsageError) as refused:
        resolve(**overrides)
    assert fragment in str(refused.value) and "\n" not in str(refused.value)


def test_largest_climbable_kerb_is_predicted_and_ten_percent_more_refused():
    p = resolve(kerb_height=0.03, step_height=0.04)
    largest = walking_ground.largest_climbable_kerb(p)
    # The swing clears step_height less a foot radius; the legs can reach much higher (95 mm) at this stance.
    assert largest == pytest.approx(0.04 - hx.DEFAULT_LAYOUT.foot_radius)
    assert walking_ground.depth_range(p)[0] < p.stand_height - largest
    with pytest.raises(UsageError, match=f"largest climbable, {largest * 1000:.3g} mm"):
        resolve(kerb_height=1.1 * largest, step_height=0.04)


def test_rough_ground_taking_all_the_climb_refuses_a_kerb_without_a_negative_limit():
    """1 cm kerb on 5 cm bumps with the feet lifted 3 cm: nothing is climbable; it said "the largest climbable,
    -28 mm ...; raise 'step_height'" (a negative limit, and lowering the roughness is the other way)."""
    with pytest.raises(UsageError) as refused:
        resolve(roughness=0.05, kerb_height=0.01)
    text = str(refused.value)
    assert "largest climbable, 0 mm" in text and "-" not in text.split("largest climbable")[1].split("(")[0]
    assert text.endswith("raise 'step_height' or lower 'roughness'") and "\n" not in text


def test_the_rough_grounds_size_is_checked_over_the_course_not_each_row_walked_for_the_whole_walk():
    """A schedule row was checked as a walk of its own for the whole duration: 0.35 m/s for 10 s, then standing, in a
    1990 s walk was refused as a 698 m heightfield ('shorten duration or lower the speed'). A waypoint course's field
    covers its waypoints, and the advice was the duration and the speed, which changed nothing (found by fuzzing)."""
    resolve(roughness=0.01, schedule=[[0, 0.35, 0, 0], [10, 0, 0, 0]], duration=1990)
    with pytest.raises(UsageError, match=r"51\.2 x 51\.2 m heightfield .*; bring the waypoints closer together$"):
        resolve(roughness=0.01, waypoints=[[50, 0], [50, 50]], path_speed=0.3, duration=1000)
    with pytest.raises(UsageError, match=r"^the rough ground under this walk .*; shorten 'duration'"):
        resolve(roughness=0.01, schedule=[[0, 0.39, 0, 0]], duration=1990)


@pytest.mark.parametrize("obstacle", ["kerb_height", "stairs_rise"])
def test_a_kerb_above_the_largest_lift_names_the_reflex_not_the_step_height(obstacle):
    """A 10 cm kerb (allowed) with the feet lifted step_height = 0.1 m, its largest, was told "raise 'step_height'"
    (found by fuzzing). The advice is the elevator reflex, and taken it is accepted."""
    walk = {obstacle: 0.1, "step_height": 0.1, "vx": 0.05, "stand_height": 0.17, "period": 2.0}
    for extra, advice in (({}, "touchdown=sensed"), ({"reflex": "off"}, "touchdown=sensed and reflex=on")):
        with pytest.raises(UsageError) as refused:
            resolve(**walk, **extra)
        assert str(refused.value).endswith(f"set {advice} (the elevator reflex lifts a blocked foot higher)")
    with pytest.raises(UsageError, match=r"; set reflex=on \("):
        resolve(**walk, touchdown="sensed", reflex="off")
    resolve(**walk, touchdown="sensed")


def test_a_kerb_beyond_the_legs_reach_names_the_stance_not_the_lift():
    """Feet lifted 8 cm on a sideways walk: the legs reach 46 mm above the stance, less than the lift, so a 5 cm kerb
    is limited by the reach; it said "raise 'step_height'", which cannot help (a deeper stance does)."""
    with pytest.raises(UsageError) as refused:
        resolve(kerb_height=0.05, step_height=0.08, vx=0.0, vy=0.1)
    text = str(refused.value)
    assert "the legs reach 46 mm above the stance" in text and text.endswith("raise 'stand_height'")
    resolve(kerb_height=0.05, step_height=0.08, vx=0.0, vy=0.1, stand_height=0.11)  # and so it does


@pytest.mark.parametrize(
    "overrides, fragment",
    [
        # 5 cm bumps and the lowest stance: the plate started 31 mm inside a bump and was thrown out (fell).
        ({"stand_height": 0.02, "roughness": 0.05, "seed": 6, "touchdown": "sensed"}, "rough ground (roughness 50 mm"),
        # A level body on 9 deg at a 3 cm stance: the plate's uphill edge started in the slope.
        ({"stand_height": 0.03, "slope_deg": 9.0, "level_body": "on"}, "the slope rises under the level body"),
    ],
)
def test_a_body_that_would_start_in_the_ground_is_refused(overrides, fragment):
    with pytest.raises(UsageError) as refused:
        resolve(**overrides)
    text = str(refused.value)
    assert text.startswith("the body would start in the ground: ") and fragment in text, text
    assert "raise 'stand_height'" in text and "\n" not in text


def test_a_level_start_the_legs_cannot_reach_names_what_to_change():
    """It said only "foot target (...) m is out of reach: ..." (from the scene, after the check)."""
    with pytest.raises(UsageError) as refused:
        resolve(stand_height=0.09, roughness=0.05, seed=3, level_body="on", slope_deg=20.0, friction=2.0)
    text = str(refused.value)
    assert text.startswith("the legs cannot stand level on this ground at the start (foot target")
    assert text.endswith("or set touchdown=planned and level_body=off") and "\n" not in text


def test_the_start_pose_is_above_the_ground_for_the_scenarios_and_their_smoke_runs():
    for name in ("hexabot-slope", "hexabot-rough", "hexabot-kerb"):
        entry = registry.get(name)
        for layer in ({}, entry.smoke):
            p = resolve(**{**entry.defaults, **layer})
            assert walking_ground.start_problem(p, walking_ground.terrain(p)) == ""


def test_a_slope_s_friction_check_takes_the_feet_that_stand_at_once_with_friction_spread():
    """friction_spread was not in the slope check: friction 0.18 +- 50 % on a 10 deg slope (tan 0.176) passed. The check
    now takes the least mean of the seeded frictions over the feet the gait stands on at once (the tripods here)."""
    from hexabot_sim.walking.perturb import perturbations

    p = walk_params(slope_deg=10, friction=0.2, friction_spread=0.5, duration=4)  # holds: checked below
    frictions = 0.18 * perturbations(p)[2]  # the same seed's draws at friction 0.18
    tripods = [(0, 2, 4), (1, 3, 5)]  # lf, lr, rm and lm, rf, rr (control/gait.py's tripod offsets)
    least = min(float(frictions[list(t)].mean()) for t in tripods)
    assert least < math.tan(math.radians(10)) < 0.18
    with pytest.raises(UsageError, match=rf"friction is {least:.3g} \(the mean over .*, which the tripod gait stands "):
        walk_params(slope_deg=10, friction=0.18, friction_spread=0.5, duration=4)
    assert walk_params(slope_deg=10, friction=0.18, duration=4).friction == 0.18  # no spread: friction alone
