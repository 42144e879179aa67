"""Changing commands (control/commands.py) and the path follower (control/follower.py), against closed forms and
an independent integration of the body's pose."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hexabot_sim.control.commands import STAIR_TIME, Schedule, Setpoint
from hexabot_sim.control.follower import ACCELERATION, PathFollower
from hexabot_sim.control.gait import GAITS, Command, GaitPlanner
from hexabot_sim.robots.hexabot.model import DEFAULT_LAYOUT


def _schedule() -> Schedule:
    rows = [
        Setpoint(0.0, Command(0.1, 0.0, 0.0), "tripod", 0.03, 0.09),
        Setpoint(2.0, Command(0.0, 0.0, 0.3), "tripod", 0.04, 0.10),
        Setpoint(2.4, Command(0.0, 0.08, 0.0), "tripod", 0.04, 0.10),  # cuts the previous ramp short
    ]
    return Schedule(rows, start=0.5, ramp_time=1.0, step_height=0.03, stand_height=0.09)


def test_schedule_ramps_linearly_from_where_the_last_ramp_got():
    s = _schedule()
    # Standing until the gait clock starts, then 0 -> 0.1 m/s over a second (closed form: linear).
    assert s.value(0.3)[:3] == pytest.approx([0, 0, 0])
    assert s.value(1.0)[0] == pytest.approx(0.05)
    assert s.value(1.9)[:3] == pytest.approx([0.1, 0, 0])
    # Row 2 ramps in from 2.0 s; at 2.4 s it is 40 % there, and row 3 ramps from that value over the next second.
    at_cut = np.array([0.1 * 0.6, 0.0, 0.3 * 0.4, 0.03 + 0.01 * 0.4, 0.09 + 0.01 * 0.4])
    assert s.value(2.4) == pytest.approx(at_cut)
    target = np.array([0.0, 0.08, 0.0, 0.04, 0.10])
    assert s.value(2.9) == pytest.approx(at_cut + 0.5 * (target - at_cut))
    assert s.value(10.0) == pytest.approx(target)


def test_schedule_segments_hold_until_the_next_knot_or_are_stairs_of_a_ramp():
    s = _schedule()
    constant = s.segment(1.6)
    assert constant.until == pytest.approx(2.0) and constant.command.vx == pytest.approx(0.1)
    stair = s.segment(2.1)
    assert stair.until == pytest.approx(2.1 + STAIR_TIME)
    mid = s.value(2.1 + STAIR_TIME / 2)
    assert (stair.command.vx, stair.command.yaw_rate) == pytest.approx((mid[0], mid[2]), abs=1e-6)
    assert math.isinf(s.segment(20.0).until)


def test_schedule_refuses_times_that_do_not_increase():
    with pytest.raises(ValueError, match="increase"):
        Schedule([Setpoint(1.0, Command(), "tripod", 0.03, 0.09)] * 2, 0.5, 1.0, 0.03, 0.09)


def _se2(pose: np.ndarray, cmd: Command, tau: float) -> np.ndarray:
    """The body's planar pose after tau [s] of a constant body twist (closed form of the SE(2) exponential)."""
    x, y, th = pose
    w = cmd.yaw_rate
    if abs(w) < 1e-12:
        dx, dy = cmd.vx * tau, cmd.vy * tau
    else:
        dx = (math.sin(w * tau) * cmd.vx - (1 - math.cos(w * tau)) * cmd.vy) / w
        dy = ((1 - math.cos(w * tau)) * cmd.vx + math.sin(w * tau) * cmd.vy) / w
    c, s = math.cos(th), math.sin(th)
    return np.array([x + c * dx - s * dy, y + s * dx + c * dy, th + w * tau])


def test_stance_feet_stay_ground_fixed_through_a_schedules_ramps():
    """Plan a walk chunk by chunk with the schedule's segments, integrate the body's pose independently (the
    SE(2) exponential of each chunk's twist) and map every stance target to the world: it must not move."""
    dt = 0.002
    layout = DEFAULT_LAYOUT
    planner = GaitPlanner(GAITS["tripod"], 1.0, 0.03, layout.neutral_feet_body(), dt, start_time=0.5)
    s = _schedule()
    pose = np.zeros(3)
    t = 0.0
    worst = 0.0
    anchors: dict[int, np.ndarray] = {}
    while t < 4.5:
        seg = s.segment(t)
        n = min(planner.max_chunk, max(1, round((seg.until - t) / dt))) if math.isfinite(seg.until) else 100
        rows = planner.plan(seg.command, n)  # (n + 1, legs, 3)
        times = t + dt * np.arange(n + 1)
        stance = planner.in_stance(times)
        for k in range(n + 1):
            p_k = _se2(pose, seg.command, k * dt)
            c, sn = math.cos(p_k[2]), math.sin(p_k[2])
            world = p_k[:2] + rows[k, :, :2] @ np.array([[c, sn], [-sn, c]])
            for leg in range(layout.n_legs):
                if not stance[k, leg]:
                    anchors.pop(leg, None)
                elif leg in anchors:
                    worst = max(worst, float(np.hypot(*(world[leg] - anchors[leg]))))
                else:
                    anchors[leg] = world[leg]
        pose = _se2(pose, seg.command, n * dt)
        t = planner.time
    assert worst < 1e-9


def test_cross_track_distance_is_the_distance_to_the_nearest_segment():
    f = PathFollower([(1.0, 0.0, None), (1.0, 1.0, None)], 0.1, 0.5, 0.5, "tripod", 0.03, 0.09)
    points = np.array([[0.5, 0.2], [1.3, 0.5], [1.2, 1.4], [-0.3, -0.4]])
    expected = [0.2, 0.3, math.hypot(0.2, 0.4), 0.5]  # to the x axis, x = 1, the corner (1, 1), the start
    assert f.cross_track(points) == pytest.approx(expected)
    assert f.total == pytest.approx(2.0)


def test_follower_walks_a_point_robot_through_its_waypoints():
    """A holonomic point that moves exactly as commanded (integrated here) follows an L-shaped course, turns to
    face along it, and arrives within the follower's radius."""
    f = PathFollower([(0.5, 0.0, None), (0.5, 0.5, None)], 0.1, 0.5, 0.5, "tripod", 0.03, 0.09)
    pose, t, errors = np.zeros(3), 0.0, []
    while t < 20.0 and f.arrived_at is None:
        seg = f.segment(t, tuple(pose))
        pose = _se2(pose, seg.command, seg.until - t)
        errors.append(float(f.cross_track(pose[None, :2])[0]))
        t = seg.until
    assert f.arrived_at is not None and np.hypot(pose[0] - 0.5, pose[1] - 0.5) < 0.01
    # At the corner the velocity turns by 90 deg: a change of 0.1 sqrt(2) m/s at ACCELERATION takes 0.71 s, while
    # the point runs on at no more than 0.1 m/s on average half of it: at most 3.5 cm past the corner.
    turn_time = 0.1 * math.sqrt(2) / ACCELERATION
    assert max(errors) < 0.1 * turn_time / 2
    assert math.remainder(pose[2] - math.pi / 2, 2 * math.pi) == pytest.approx(0.0, abs=0.05)


def test_a_waypoints_heading_is_held_along_the_segment_that_ends_there():
    """A crab course: straight along +x to a waypoint whose heading is pi/2; the body turns to face +y while its
    velocity stays along the path (the holonomic twist), and the path is kept as on a straight course."""
    f = PathFollower([(0.6, 0.0, math.pi / 2)], 0.1, 0.5, 0.5, "tripod", 0.03, 0.09)
    pose, t, worst = np.zeros(3), 0.0, 0.0
    while t < 20.0 and f.arrived_at is None:
        seg = f.segment(t, tuple(pose))
        pose = _se2(pose, seg.command, seg.until - t)
        worst = max(worst, abs(pose[1]))
        t = seg.until
    assert f.arrived_at is not None and abs(pose[0] - 0.6) < 0.01
    assert pose[2] == pytest.approx(math.pi / 2, abs=0.02)
    assert worst < 0.005  # turning while walking sideways does not pull it off the line


def test_with_sensed_touchdown_a_rows_stand_height_ramps_over_the_period_not_ahead_of_it():
    """The ground controller's stance plane took the chunk's last stand height (a chunk is up to 1 s): a row raising
    it 0.09 -> 0.12 m over its 1 s ramp lifted the body 12 mm in the first 0.1 s, 14 mm ahead of the ramp (found by
    fuzzing). Row by row, the plane follows the ramp (its height gain's lag: a few mm behind)."""
    import hexabot_sim as hs

    rows = [[0, 0.05, 0, 0, None, 0.03, 0.09], [1.5, 0.05, 0, 0, None, 0.03, 0.12]]
    r = hs.run("hexabot-walk", touchdown="sensed", schedule=rows, duration=3.5)
    t, z = r.columns["t"], r.columns["z"]
    ahead = (z - (0.098 + 0.03 * np.clip(t - 1.5, 0.0, 1.0)))[t > 1.0]  # above the planned body height
    assert ahead.max() < 0.002 and ahead.min() > -0.008


def test_the_last_waypoints_heading_is_reached_before_arriving_and_its_turn_timed():
    """A short last segment with a heading: the follower arrived on the point facing wherever it got (0.31 rad of
    3.1 in a walk), and the duration check counted no turn (found by fuzzing). It turns on the spot to the heading
    before it arrives, and the walk's duration must leave time for the turn."""
    from hexabot_sim import params
    from hexabot_sim.errors import UsageError
    from hexabot_sim.robots.hexabot.walk import HexabotParams

    f = PathFollower([(0.05, 0.0, 3.1)], 0.1, 0.5, 0.5, "tripod", 0.03, 0.09)
    pose, t = np.zeros(3), 0.0
    while t < 30.0 and f.arrived_at is None:
        seg = f.segment(t, tuple(pose))
        pose = _se2(pose, seg.command, seg.until - t)
        t = seg.until
    assert f.arrived_at is not None and np.hypot(pose[0] - 0.05, pose[1]) < 0.01
    assert math.remainder(pose[2] - 3.1, 2 * math.pi) == pytest.approx(0.0, abs=0.02)
    with pytest.raises(UsageError, match=r"\(turning at path_yaw_rate 0\.5 rad/s\) the walk needs about"):
        params.resolve(HexabotParams, {}, {"waypoints": [[0.05, 0, 3.1]], "duration": 3.2})
