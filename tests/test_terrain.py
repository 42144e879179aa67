"""The hexabot on real ground: the terrain itself, feet that find the ground, a levelled body, refusals."""

import math

import mujoco
import numpy as np
import pytest

from hexabot_sim import params
from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics import hexabot as hx
from hexabot_sim.kinematics.hexabot_terrain import Terrain
from hexabot_sim.scenarios import hexabot as scenario

SLOPE = {"slope_deg": 10.0, "touchdown": "sensed", "level_body": "on", "duration": 10.0}


def resolve(**overrides):
    return params.resolve(scenario.HexabotParams, {}, overrides)


def walk(**overrides):
    return scenario.run("hexabot-walk", resolve(**overrides))


def value(result, name):
    return result.metrics[name].value


def compiled(p):
    model = mujoco.MjModel.from_xml_string(scenario.build_xml(p))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data


# --- the terrain itself ------------------------------------------------------------------------------


def test_heightfield_is_seeded_and_has_the_asked_amplitude():
    base = Terrain(roughness=0.01, seed=4, extent=(-0.5, 1.5, -0.6, 0.6))
    again = Terrain(roughness=0.01, seed=4, extent=(-0.5, 1.5, -0.6, 0.6))
    other = Terrain(roughness=0.01, seed=5, extent=(-0.5, 1.5, -0.6, 0.6))
    h = base.heights()
    assert np.array_equal(h, again.heights())
    assert np.abs(h - other.heights()).max() > 0.005
    assert np.abs(h).max() == pytest.approx(0.01)
    # The compiled model holds the same field (float32, normalised by MuJoCo), row 0 at the -y edge.
    p = resolve(roughness=0.01, seed=4)
    model, _ = compiled(p)
    norm, _, size = scenario.terrain(p).hfield_levels()
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
    ground = scenario.terrain(p)
    assert ground.height(0.1, 0.0) - ground.height(0.0, 0.0) == pytest.approx(0.1 * math.tan(a) * uphill[0])
    assert ground.height(0.0, 0.1) - ground.height(0.0, 0.0) == pytest.approx(0.1 * math.tan(a) * uphill[1])


@pytest.mark.parametrize(
    "overrides",
    [{"roughness": 0.01, "seed": 3}, {"slope_deg": 10.0, "slope_heading": "across"}, {"kerb_height": 0.02}],
    ids=["rough", "slope", "kerb"],
)
def test_ground_height_agrees_with_mujoco_ray_casting(overrides):
    p = resolve(**overrides)
    model, data = compiled(p)
    ground = scenario.terrain(p)
    x0, x1, y0, y1 = ground.extent
    rng = np.random.default_rng(11)
    terrain_only = np.array([1, 0, 0, 0, 0, 0], dtype=np.uint8)  # group 0: floor, heightfield, kerb
    geom = np.zeros(1, dtype=np.int32)
    worst = 0.0
    for x, y in rng.uniform([x0, y0], [x1, y1], size=(400, 2)):
        distance = mujoco.mj_ray(
            model, data, np.array([x, y, 1.0]), np.array([0.0, 0.0, -1.0]), terrain_only, 1, -1, geom
        )
        worst = max(worst, abs((1.0 - distance) - float(ground.height(x, y))))
    assert worst < 1e-6  # the heightfield is stored in float32


def test_only_feet_and_plate_touch_the_terrain():
    for overrides in ({"roughness": 0.01}, {"kerb_height": 0.02}):
        model, _ = compiled(resolve(**overrides))
        name = "terrain" if "roughness" in overrides else "kerb"
        g = model.geom(name).id
        touching = {
            model.geom(h).name
            for h in range(model.ngeom)
            if model.geom_contype[h] & model.geom_conaffinity[g] or model.geom_contype[g] & model.geom_conaffinity[h]
        }
        assert touching == {"torso", *(f"{leg}_foot" for leg in hx.LEGS)}


# --- refusals ------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("overrides", "fragment"),
    [
        ({"slope_deg": 30.0, "friction": 0.5}, "friction coefficient of at least tan(slope) = 0.577"),
        ({"slope_deg": 30.0, "level_body": "on"}, "steepest levelled slope is"),
        ({"roughness": 0.01, "slope_deg": 5.0}, "one terrain feature at a time"),
    ],
)
def test_impossible_ground_is_refused_in_one_line(overrides, fragment):
    with pytest.raises(UsageError) as refused:
        resolve(**overrides)
    assert fragment in str(refused.value) and "\n" not in str(refused.value)


def test_largest_climbable_kerb_is_predicted_and_ten_percent_more_refused():
    p = resolve(kerb_height=0.03, step_height=0.04)
    largest = scenario.largest_climbable_kerb(p)
    # The swing clears step_height less a foot radius; the legs can reach much higher (95 mm) at this stance.
    assert largest == pytest.approx(0.04 - hx.DEFAULT_LAYOUT.foot_radius)
    assert scenario.depth_range(p)[0] < p.stand_height - largest
    with pytest.raises(UsageError, match=f"largest climbable, {largest * 1000:.1f} mm"):
        resolve(kerb_height=1.1 * largest, step_height=0.04)


# --- walking on it --------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def slope_runs():
    runs = {h: walk(**SLOPE, slope_heading=h) for h in ("uphill", "downhill", "across")}
    runs["off"] = walk(**{**SLOPE, "level_body": "off"})
    return runs


@pytest.mark.parametrize("heading", ["uphill", "downhill", "across"])
def test_levelled_body_on_a_10_degree_slope(slope_runs, heading):
    r = slope_runs[heading]
    for angle in ("roll", "pitch"):
        assert value(r, f"{angle}_peak") <= 1.0, (angle, value(r, f"{angle}_peak"))
        assert value(r, f"{angle}_rms") <= 0.5, (angle, value(r, f"{angle}_rms"))
    assert abs(value(r, "speed_made_good_error")) <= 0.05
    assert not value(r, "fell")
    assert value(r, "level_clipped_fraction") == 0.0
    # At the set height above the ground under the body (stand height + foot radius, within 5 mm).
    assert value(r, "height_above_ground_mean") == pytest.approx(0.098, abs=0.005)


def test_without_levelling_the_body_tilts_with_the_slope(slope_runs):
    off, on = slope_runs["off"], slope_runs["uphill"]
    # Uphill along +x: the nose up by the slope (negative pitch in z-y-x angles), by the expected 10 deg.
    assert value(off, "pitch_rms") == pytest.approx(10.0, abs=0.5)
    assert value(on, "pitch_rms") < 0.5
    assert not value(off, "fell") and abs(value(off, "speed_made_good_error")) <= 0.05


def test_standing_still_on_the_slope_does_not_slide():
    r = walk(**{**SLOPE, "vx": 0.0, "duration": 8.0})
    assert abs(value(r, "distance_made_good")) < 0.002  # over 5.5 s of stepping in place
    assert value(r, "pitch_peak") <= 1.0 and not value(r, "fell")


@pytest.fixture(scope="module")
def rough_runs():
    # A subset of the 5 seeds x 3 gaits that keeps the test time reasonable: each gait on its own seed.
    cases = {
        ("tripod", 0.1, 0): None,
        ("ripple", 0.1, 1): None,
        ("wave", 0.05, 2): None,
    }
    return {
        case: walk(roughness=0.01, seed=case[2], gait=case[0], vx=case[1], touchdown="sensed", duration=20.0)
        for case in cases
    }


def test_rough_ground_no_fall_speed_and_attitude(rough_runs):
    for case, r in rough_runs.items():
        assert not value(r, "fell"), case
        assert abs(value(r, "speed_made_good_error")) <= 0.10, (case, value(r, "speed_made_good_error"))
        assert value(r, "roll_peak") <= 3.0 and value(r, "pitch_peak") <= 3.0, case
        assert value(r, "feet_without_ground") == 0, case
        assert value(r, "early_touchdowns") + value(r, "late_touchdowns") > 0, case  # the ground is felt


def test_touchdown_happens_at_the_ground_height_under_the_foot(rough_runs):
    r = rough_runs[("tripod", 0.1, 0)]
    ground: Terrain = r.extras["terrain"]
    points = r.extras["contacts"].point  # (n, 6, 3)
    loaded = np.stack([r.columns[f"contact_{leg}"] for leg in hx.LEGS], axis=1) > 0.5
    rows, legs = np.nonzero(np.diff(loaded.astype(int), axis=0) == 1)
    pts = points[rows + 1, legs]
    gap = pts[:, 2] - ground.height(pts[:, 0], pts[:, 1])
    assert len(gap) > 50
    assert np.abs(gap).max() < 1e-3  # the contact point lies on the ground (penetration well below 1 mm)


def test_sensed_touchdown_on_flat_ground_keeps_the_walk():
    r = walk(touchdown="sensed", duration=8.0)
    assert abs(value(r, "vx_error")) <= 0.02
    assert value(r, "touchdown_error_max") <= 0.02
    assert value(r, "early_touchdowns") == value(r, "late_touchdowns") == value(r, "feet_without_ground") == 0


def test_a_3_cm_kerb_is_climbed():
    r = walk(kerb_height=0.03, step_height=0.04, touchdown="sensed", level_body="on", duration=14.0)
    c = r.columns
    assert not value(r, "fell")
    assert c["x"][-1] > 0.5 + 0.4  # the whole robot is past the kerb's edge
    above = c["z"][-1] - r.extras["terrain"].height(c["x"][-1], c["y"][-1])
    assert above == pytest.approx(0.098, abs=0.003)  # back at its height, now above the pavement
    assert value(r, "largest_climbable_kerb") == pytest.approx(0.032)
