"""Swings that land on a terrain map (terrain_map=on, issue 19) and a soft foot's first contact near its swing's end
(the pad's early band): the map against MuJoCo's own ray casting, the compiled reading and frames against closed
forms, and the walks."""

import math

import mujoco
import numpy as np
import pytest
from helpers import compiled_scene, metric, walk_params

import hexabot_sim as hs
from hexabot_sim.control import kernels as K
from hexabot_sim.control import map_kernels
from hexabot_sim.terrain.heightmap import HeightMap
from hexabot_sim.walking import ground as walking_ground

FORCE_PAD = {"load_sharing": "force", "feet": "pad", "swing": "quintic"}


def _rough_map(**overrides):
    p = walk_params(roughness=0.01, seed=3, touchdown="sensed", terrain_map="on", **overrides)
    return p, walking_ground.terrain_map(p)


def test_the_map_is_the_ground_mujoco_collides():
    """The map's heights, read between its grid points, are the heightfield's as MuJoCo's ray casting finds it, to
    0.2 mm (the 2 cm heightfield's triangles read bilinearly on the map's 1 cm grid: 0.18 mm at worst of 400 points,
    0.03 mm RMS, measured; the bumps are 10 mm)."""
    p, hmap = _rough_map()
    model, data = compiled_scene(p)
    x0, x1, y0, y1 = walking_ground.terrain(p).rough.extent
    rng = np.random.default_rng(5)
    terrain_only = np.array([1, 0, 0, 0, 0, 0], dtype=np.uint8)
    geom = np.zeros(1, dtype=np.int32)
    errors = []
    for x, y in rng.uniform([x0, y0], [x1, y1], size=(400, 2)):
        distance = mujoco.mj_ray(model, data, np.array([x, y, 1.0]), np.array([0.0, 0.0, -1.0]), terrain_only, 1, -1,
                                 geom)  # fmt: skip
        errors.append(abs(1.0 - distance - float(hmap.height(x, y))))
    assert hmap.cell == 0.01
    assert max(errors) < 2e-4
    assert math.sqrt(np.mean(np.square(errors))) < 5e-5
    assert float(np.ptp(hmap.heights)) > 0.015  # a rough patch, not a level map


def test_the_maps_error_is_seeded_noise_of_the_asked_size():
    _, exact = _rough_map()
    _, noisy = _rough_map(map_error=0.002)
    _, again = _rough_map(map_error=0.002)
    diff = noisy.heights - exact.heights
    assert np.array_equal(noisy.heights, again.heights)
    assert float(diff.std()) == pytest.approx(0.002, rel=0.02)
    assert abs(float(diff.mean())) < 1e-4


def test_the_compiled_map_reads_as_the_numpy_one_and_knows_nothing_beyond_its_edges():
    _, hmap = _rough_map()
    ny, nx = hmap.heights.shape
    rng = np.random.default_rng(2)
    span_x, span_y = hmap.cell * (nx - 1), hmap.cell * (ny - 1)
    points = rng.uniform([hmap.x0 - 0.5, hmap.y0 - 0.5], [hmap.x0 + span_x + 0.5, hmap.y0 + span_y + 0.5], (500, 2))
    compiled = [map_kernels.map_height(hmap.params(), hmap.heights, x, y) for x, y in points]
    assert np.allclose(compiled, hmap.height(points[:, 0], points[:, 1]), atol=1e-12, rtol=0, equal_nan=True)
    assert 0 < np.isnan(compiled).sum() < len(points)  # both inside and outside were drawn
    # A grid point reads its own height (the far corner too); beyond the grid, nothing.
    assert map_kernels.map_height(hmap.params(), hmap.heights, hmap.x0 + 3 * hmap.cell, hmap.y0) == pytest.approx(
        hmap.heights[0, 3], abs=1e-15
    )
    far = (hmap.x0 + span_x, hmap.y0 + span_y)
    assert map_kernels.map_height(hmap.params(), hmap.heights, *far) == pytest.approx(hmap.heights[-1, -1], abs=1e-15)
    assert math.isnan(map_kernels.map_height(hmap.params(), hmap.heights, hmap.x0 - 1e-6, hmap.y0))


def test_a_swings_landing_height_is_the_maps_ground_under_where_the_body_will_be():
    """One swinging leg, the body turned 30 deg and rolled 4 deg, the command moving it on for 0.2 s: the landing
    point is carried to the world as the body will stand at the touchdown, the map (a tilted plane, which bilinear
    reads exactly) read there; MAP_Z is that ground, a foot radius up, in today's body frame (its z along the world's
    vertical through the point); NaN for the legs not swinging."""
    slope = (0.01, 0.05, -0.02)  # z = a + b x + c y [m]
    xs, ys = np.arange(-2, 3) * 1.0, np.arange(-2, 4) * 1.0
    heights = slope[0] + slope[1] * xs[None, :] + slope[2] * ys[:, None]
    hmap = HeightMap(-2.0, -2.0, 1.0, np.ascontiguousarray(heights))
    radius = 0.008
    yaw, roll = math.radians(30), math.radians(4)
    quat = np.zeros(4)
    mujoco.mju_euler2Quat(quat, np.array([roll, 0.0, yaw]), "XYZ")
    qpos = np.zeros(7 + 18)
    qpos[:3], qpos[3:7] = (1.0, 0.5, 0.12), quat
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, quat)
    rot = rot.reshape(3, 3)
    par = np.zeros(K.NPAR)
    par[K.DT], par[K.SWING_TIME], par[K.SETTLE_TIME] = 0.002, 0.5, 0.0
    t = 3.0
    plane = np.array([-0.1, 0.02, -0.01])
    cmd = np.array([0.1, -0.04, 0.3])

    def landing(filter_time, before=math.nan):
        legs, flags = np.zeros((6, K.NLEG)), np.zeros((6, 3), dtype=np.int64)
        flags[:, K.MODE] = K.STANCE
        flags[2, K.MODE] = K.SWING
        legs[2, K.T_LIFT] = t - 0.3  # 0.2 s to the touchdown
        legs[2, K.LANDING : K.LANDING + 2] = (0.15, 0.12)
        legs[2, K.MAP_Z] = before
        mpar = np.array([*hmap.params(), radius, filter_time, map_kernels.EDGE])
        map_kernels.landing_heights(par, mpar, hmap.heights, legs, flags, plane, qpos, cmd, t)
        assert np.all(np.isnan(legs[[0, 1, 3, 4, 5], K.MAP_Z]))
        return legs[2, K.MAP_Z]

    # By hand: the body at the touchdown is 0.2 s on, turned by 0.06 rad and moved by (0.02, -0.008) in today's frame.
    turn = 0.3 * 0.2
    lx, ly = 0.15, 0.12
    bx = math.cos(turn) * lx - math.sin(turn) * ly + 0.1 * 0.2
    by = math.sin(turn) * lx + math.cos(turn) * ly - 0.04 * 0.2
    bz = plane[0] + plane[1] * lx + plane[2] * ly
    world = qpos[:3] + rot @ np.array([bx, by, bz])
    gap = slope[0] + slope[1] * world[0] + slope[2] * world[1] + radius - world[2]  # along the world's vertical
    expected = (rot.T @ (world + np.array([0.0, 0.0, gap]) - qpos[:3]))[2]
    assert landing(0.0) == pytest.approx(expected, abs=1e-12)
    assert landing(0.02) == pytest.approx(expected, abs=1e-12)  # a swing's first reading is taken as it is
    assert landing(0.02, before=-0.1) == pytest.approx(-0.1 + (expected + 0.1) * 0.002 / 0.02, abs=1e-12)
    qpos[0] = 50.0  # the landing point off the map: NaN, the swing ends on the stance plane
    assert math.isnan(landing(0.02, before=-0.1))


def test_the_maps_parameters_are_refused_without_what_they_apply_to():
    with pytest.raises(ValueError, match="'terrain_map' = on needs touchdown=sensed"):
        walk_params(terrain_map="on")
    with pytest.raises(ValueError, match="'map_error' is the terrain map's error: it needs terrain_map=on"):
        walk_params(roughness=0.01, touchdown="sensed", map_error=0.001)
    with pytest.raises(ValueError, match="map_error"):
        walk_params(roughness=0.01, touchdown="sensed", terrain_map="on", map_error=-0.001)
    # At most 1 cm (the bumps' own size: the quadbot's rough trot fell at 2 cm).
    with pytest.raises(ValueError, match=r"0 <= map_error <= 0.01 m"):
        walk_params(roughness=0.01, touchdown="sensed", terrain_map="on", map_error=0.011)
    # An area the 1 cm map cannot hold is refused (the map used to coarsen silently, to 5 cm on a slow turn).
    with pytest.raises(ValueError, match=r"the terrain map of this walk's area \(100 m x 100 m\) needs 100,420,441 "):
        walk_params(touchdown="sensed", terrain_map="on", vx=0.3, yaw_rate=0.001, duration=165)
    assert (
        walking_ground.terrain_map(walk_params(touchdown="sensed", terrain_map="on", vx=0.3, duration=165)).cell == 0.01
    )


def test_a_gait_with_two_feet_down_takes_the_map_only_with_a_level_body():
    """With two feet down no stance plane corrects the body's tilt, which the map's landings keep: the flat trot rolled
    7.4 deg with the map, 0.4 without, 0.7 with level_body=on (measured, 8 s)."""
    from hexabot_sim import params
    from hexabot_sim.robots.quadbot.walk import QuadbotParams

    def trot(**overrides):
        return params.resolve(QuadbotParams, {"gait": "trot", "vx": 0.1, "period": 0.3}, overrides)

    with pytest.raises(
        ValueError, match="'terrain_map' = on in a gait with 2 feet down \\(the trot gait\\) needs level_body=on"
    ):
        trot(touchdown="sensed", terrain_map="on")
    assert trot(touchdown="sensed", terrain_map="on", level_body="on").terrain_map == "on"
    assert trot(touchdown="sensed", terrain_map="on", gait="crawl", vx=0.05, period=2.0).terrain_map == "on"


@pytest.mark.slow
def test_a_pads_first_contact_near_its_swings_end_is_not_an_early_touchdown():
    """With sensed touchdown the pad meets the ground ~20 ms before the planned touchdown, 0.8 mm above the swing's
    end: taken as an early touchdown, the target stopped there and the landing foot rebounded off the pad at every
    hand-over (4 bounces in the tripod's 4 s, 2 in the wave's, measured with the band at 0); within the band the
    swing goes on to its end, as with planned touchdown."""
    for gait, vx in (("tripod", 0.1), ("wave", 0.05)):
        r = hs.run("hexabot-walk", gait=gait, vx=vx, duration=4, touchdown="sensed", **FORCE_PAD)
        assert metric(r, "foot_bounces") == 0, gait
        assert metric(r, "stance_loaded_fraction_min") == 1.0, gait


@pytest.mark.slow
def test_with_the_map_the_feet_land_on_time_and_stay_loaded_on_rough_ground():
    """1 cm rough ground, the tripod at 0.1 m/s, 4 s: without the map the feet meet the bumps up to 68 ms before or
    after the planned touchdown and one foot is loaded 0.96 of its stance; with it, the pads touch within 22 ms (the
    pad's first contact, ~20 ms early, as on the flat) and every foot is loaded all through its stance."""
    common = dict(gait="tripod", vx=0.1, duration=4, seed=0, **FORCE_PAD)
    without = hs.run("hexabot-rough", **common)
    mapped = hs.run("hexabot-rough", terrain_map="on", **common)
    assert metric(without, "touchdown_error_max") > 0.05
    assert metric(without, "stance_loaded_fraction_min") < 0.97
    assert metric(mapped, "touchdown_error_max") < 0.025
    assert metric(mapped, "late_touchdowns") == 0
    assert metric(mapped, "foot_bounces") == 0
    assert metric(mapped, "stance_loaded_fraction_min") == 1.0
    assert not metric(mapped, "fell")


def _step_map(edge=0.5, rise=0.04):
    """A 1 cm map of a riser across x at `edge` [m] (as terrain.Ground's stairs: the upper step from the edge on)."""
    xs, ys = np.arange(0.0, 1.01, 0.01), np.arange(-0.5, 0.51, 0.01)
    heights = np.where(xs[None, :] + 1e-9 >= edge, rise, 0.0) + 0.0 * ys[:, None]
    return HeightMap(0.0, -0.5, 0.01, np.ascontiguousarray(heights))


def _swing_on(hmap, landing_x, s, shift=(0.0, 0.0)):
    """One leg swinging at the fraction s of its 0.5 s swing, the level body at the origin walking at 0.1 m/s, its
    landing point `landing_x` [m] ahead in the world at the touchdown; returns its legs row after landing_heights."""
    par = np.zeros(K.NPAR)
    par[K.DT], par[K.SWING_TIME], par[K.SETTLE_TIME] = 0.002, 0.5, 0.0
    t, tau = 3.0, 0.5 * (1 - s)
    legs, flags = np.zeros((6, K.NLEG)), np.zeros((6, 3), dtype=np.int64)
    flags[:, K.MODE] = K.STANCE
    flags[2, K.MODE] = K.SWING
    legs[2, K.T_LIFT] = t - 0.5 * s
    legs[2, K.LANDING : K.LANDING + 2] = (landing_x - 0.1 * tau, 0.0)
    legs[2, K.MAP_Z] = math.nan
    legs[2, K.SHIFT : K.SHIFT + 2] = shift
    qpos = np.zeros(7 + 18)
    qpos[2], qpos[3] = 0.1, 1.0
    mpar = np.array([*hmap.params(), 0.008, 0.0, map_kernels.EDGE])
    map_kernels.landing_heights(par, mpar, hmap.heights, legs, flags, np.array([-0.09, 0.0, 0.0]), qpos,
                                np.array([0.1, 0.0, 0.0]), t)  # fmt: skip
    assert np.all(legs[[0, 1, 3, 4, 5], K.SHIFT : K.SHIFT + 2] == 0.0)
    return legs[2]


def test_a_landing_point_at_a_risers_foot_is_moved_off_the_edge():
    """hexabot-stairs with waypoints turning onto the landing (22 s): two rear feet landed 8 mm before a riser (the
    map's bilinear height there is between the steps), stopped against its face, slid into the corner and at their
    next lift-off drove into the face, pitching the body 10.8 deg. A landing point whose foot would touch a riser, or
    stand within AHEAD before one, is moved along the body's x to the nearest level spot, in the swing's first half
    (then held); the landing height is the map's there. Level ground and 1 cm rough ground are never moved."""
    hmap = _step_map()
    mpar = np.array([*hmap.params(), 0.008, 0.0, map_kernels.EDGE])
    for x in (0.47, 0.485, 0.492, 0.495, 0.5, 0.505):
        row = _swing_on(hmap, x, s=0.2)
        sx, sy = row[K.SHIFT : K.SHIFT + 2]
        assert sy == 0.0 and 0.0 < abs(sx) <= map_kernels.MAX_SHIFT, x
        spot = x + sx
        # The foot and the way ahead clear of the riser's face, or the foot on the step above.
        assert spot + 0.008 + map_kernels.AHEAD < 0.5 or spot - 0.008 > 0.5, (x, sx)
        assert map_kernels.level_spot(mpar, hmap.heights, spot, 0.0, 1.0, 0.0)
        ground = 0.04 if spot >= 0.5 else 0.0
        assert row[K.MAP_Z] == pytest.approx(ground + 0.008 - 0.1, abs=1e-12), x
    # Level spots keep the planned landing point: well before the riser, and on the step above.
    for x in (0.40, 0.56, 0.8):
        row = _swing_on(hmap, x, s=0.2)
        assert tuple(row[K.SHIFT : K.SHIFT + 2]) == (0.0, 0.0), x
    # A shift kept while its spot stays level; none chosen in the swing's second half (the foot is on its way).
    row = _swing_on(hmap, 0.492, s=0.2, shift=(0.03, 0.0))
    assert row[K.SHIFT] == 0.03
    row = _swing_on(hmap, 0.492, s=0.6)
    assert tuple(row[K.SHIFT : K.SHIFT + 2]) == (0.0, 0.0)
    assert row[K.MAP_Z] == pytest.approx(hmap.height(0.492, 0.0) + 0.008 - 0.1, abs=1e-12)
    # On a map with an error its noise is no edge (6 errors more): with 1 cm of noise a 4 cm riser is not told from it.
    assert _rough_map(map_error=0.002)[1].error == 0.002
    mpar[map_kernels.EDGE_RANGE] = map_kernels.edge_range(0.01)
    assert not map_kernels.level_spot(np.array([*hmap.params(), 0.008, 0.0, map_kernels.EDGE]), hmap.heights, 0.492,
                                      0.0, 1.0, 0.0)  # fmt: skip
    assert map_kernels.level_spot(mpar, hmap.heights, 0.492, 0.0, 1.0, 0.0)
    # 1 cm rough ground is never an edge.
    _, rough = _rough_map()
    rng = np.random.default_rng(4)
    for x, y in rng.uniform([0.3, -0.2], [1.0, 0.2], size=(200, 2)):
        assert map_kernels.level_spot(
            np.array([*rough.params(), 0.008, 0.0, map_kernels.EDGE]), rough.heights, x, y, 1.0, 0.0
        )


@pytest.mark.slow
def test_the_map_climbs_the_stairs_turning_onto_the_landing_without_catching_a_riser():
    """hexabot-stairs, waypoints turning onto the landing, 22 s: roll / pitch peak to peak 12.6 / 15.4 deg with the map
    before its landing points were moved off the risers (8.4 / 6.5 without it); measured after: 0.5 / 0.9."""
    r = hs.run("hexabot-stairs", waypoints=[[1, 0], [1.5, 0.3]], duration=22, terrain_map="on")
    assert metric(r, "roll_ptp") < 3.0
    assert metric(r, "pitch_ptp") < 3.0
    assert not metric(r, "fell")
