"""A path follower for a legged robot: walk through waypoints with a twist that tracks the path.

The path is the polyline from the start pose (0, 0) through the waypoints (world frame, metres). Every
`UPDATE_TIME` the follower reads the body's planar pose and commands a body twist:

- progress s: the arc length of the point of the path closest to the body, searched forward from the last s
  (over the next `SEARCH_AHEAD` metres: a figure-eight's crossing does not make it jump);
- velocity: along the path's tangent at s, plus `CROSS_GAIN` times the vector from the body to that closest
  point (the cross-track error), the sum no faster than `speed` (a pursuit of the path point, on the
  holonomic body twist: the legs walk in any direction, so the velocity, not the heading, closes the error);
  within `SLOW_RADIUS` of the last waypoint the speed tapers to stop on it;
- yaw rate: `YAW_GAIN` times the heading error, no more than `max_yaw_rate` nor than it can stop from in time
  (sqrt(2 ACCELERATION |error|)); the heading wanted is the
  waypoint's heading where one is given for the segment's end point, else the segment's direction;
- the twist changes by at most `ACCELERATION` per second (the legs' stances stay ground-fixed: the controller
  plans each update's constant twist).
It has arrived when it is within `ARRIVE_RADIUS` of the last waypoint with its progress within twice that of the
path's end, and within `ARRIVE_HEADING` of the last waypoint's heading where one is given (it turns on the spot to
it); from then on it stands.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from hexabot_sim.control.commands import Segment
from hexabot_sim.control.gait import Command

UPDATE_TIME: float = 0.1  # [s] the follower's period: each update's twist is held over it
CROSS_GAIN: float = 2.0  # [1/s] velocity toward the closest path point per metre of cross-track error
YAW_GAIN: float = 2.0  # [1/s] yaw rate per radian of heading error
ACCELERATION: float = 0.2  # [m/s^2] (and rad/s^2) largest change of the commanded twist
SLOW_RADIUS: float = 0.1  # [m] the speed tapers linearly to zero over this distance before the last waypoint
ARRIVE_RADIUS: float = 0.01  # [m] arrived: this close to the last waypoint, the whole path behind
SEARCH_AHEAD: float = 0.3  # [m] the closest point is searched this far ahead of the last progress
ARRIVE_HEADING: float = 0.02  # [rad] arrived: this close to the last waypoint's heading, where one is given


class PathFollower:
    """Walks a polyline of waypoints (CommandSource of control/commands.py).

    Attributes:
        arrived_at: Run time [s] when it arrived (None: not yet).
    """

    def __init__(
        self,
        waypoints: Sequence[tuple[float, float, float | None]],
        speed: float,
        max_yaw_rate: float,
        start: float,
        gait: str,
        step_height: float,
        stand_height: float,
    ) -> None:
        points = np.array([[0.0, 0.0], *[(x, y) for x, y, _ in waypoints]], dtype=float)  # (n + 1, 2)
        seg = np.diff(points, axis=0)  # (n, 2)
        self.lengths = np.hypot(seg[:, 0], seg[:, 1])
        if not (self.lengths > 0).all():
            raise ValueError("consecutive waypoints must differ (and the first from the start)")
        self.points, self.tangents = points, seg / self.lengths[:, None]
        self.cum = np.concatenate([[0.0], np.cumsum(self.lengths)])  # arc length at each point
        self.total = float(self.cum[-1])
        directions = np.arctan2(seg[:, 1], seg[:, 0])
        self.headings = np.array([d if h is None else h for d, (_, _, h) in zip(directions, waypoints, strict=True)])
        self.final_heading = waypoints[-1][2]  # given (or None): reached before it arrives
        self.speed, self.max_yaw_rate, self.start = speed, max_yaw_rate, start
        self.gait, self._heights = gait, (step_height, stand_height)
        self.s = 0.0
        self.now = np.zeros(3)  # the commanded twist (vx, vy, yaw rate), body frame
        self._t = start
        self.arrived_at: float | None = None

    def closest(self, xy: np.ndarray, s_from: float, ahead: float) -> tuple[float, np.ndarray, int]:
        """Arc length, point (2,) and segment of the path point closest to xy among s in [s_from, s_from + ahead]."""
        best = (math.inf, s_from, self.point(s_from), 0)
        first = int(np.searchsorted(self.cum, s_from, side="right")) - 1
        for i in range(max(first, 0), len(self.lengths)):
            if self.cum[i] > s_from + ahead:
                break
            u = float(np.clip((xy - self.points[i]) @ self.tangents[i], 0.0, self.lengths[i]))
            s = min(max(self.cum[i] + u, s_from), s_from + ahead)
            p = self.point(s)
            d = float(np.hypot(*(xy - p)))
            if d < best[0]:
                best = (d, s, p, i)
        return best[1], best[2], best[3]

    def point(self, s: float) -> np.ndarray:
        """The path point (2,) at arc length s."""
        i = min(max(int(np.searchsorted(self.cum, s, side="right")) - 1, 0), len(self.lengths) - 1)
        return self.points[i] + self.tangents[i] * (s - self.cum[i])

    def cross_track(self, xy: np.ndarray) -> np.ndarray:
        """Distance [m] (n,) of points xy (n, 2) from the path (its nearest segment)."""
        rel = xy[:, None, :] - self.points[None, :-1]  # (n, segs, 2)
        u = np.clip(np.einsum("nsk,sk->ns", rel, self.tangents), 0.0, self.lengths)
        near = self.points[None, :-1] + u[..., None] * self.tangents[None]
        return np.hypot(*(xy[:, None, :] - near).transpose(2, 0, 1)).min(axis=1)

    def segment(self, t: float, pose: tuple[float, float, float]) -> Segment:
        """The twist for the next UPDATE_TIME from the body's pose (x, y, yaw)."""
        x, y, yaw = pose
        xy = np.array([x, y])
        want = np.zeros(3)
        if t >= self.start and self.arrived_at is None:
            self.s, near, i = self.closest(xy, self.s, SEARCH_AHEAD)
            end = self.points[-1]
            left = self.total - self.s + float(np.hypot(*(xy - near)))
            # The last heading where given: it stopped on the point facing wherever it got (0.31 rad of 3.1).
            turned = self.final_heading is None or abs(math.remainder(self.final_heading - yaw, 2 * math.pi)) < (
                ARRIVE_HEADING
            )
            if self.total - self.s < 2 * ARRIVE_RADIUS and float(np.hypot(*(xy - end))) < ARRIVE_RADIUS and turned:
                self.arrived_at = t
            else:
                speed = self.speed * min(1.0, left / SLOW_RADIUS)
                toward = CROSS_GAIN * (near - xy)
                pull = float(np.hypot(*toward))
                if pull > speed:
                    toward *= speed / pull
                    pull = speed
                along = math.sqrt(max(speed * speed - pull * pull, 0.0))
                v_world = along * self.tangents[i] + toward
                c, s_ = math.cos(yaw), math.sin(yaw)
                error = math.remainder(float(self.headings[i]) - yaw, 2 * math.pi)
                # No faster than it can stop on the heading at ACCELERATION (else the rate limit makes it overshoot).
                rate = min(self.max_yaw_rate, YAW_GAIN * abs(error), math.sqrt(2 * ACCELERATION * abs(error)))
                yaw_rate = math.copysign(rate, error)
                want = np.array([c * v_world[0] + s_ * v_world[1], -s_ * v_world[0] + c * v_world[1], yaw_rate])
        step = ACCELERATION * max(t - self._t, UPDATE_TIME)
        self._t = t
        self.now += np.clip(want - self.now, -step, step)
        if self.arrived_at is not None:
            self.now[:] = 0.0
        return Segment(Command(*(float(v) for v in self.now)), t + UPDATE_TIME, self.gait)

    def heights(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        times = np.asarray(times, dtype=float)
        return np.full(times.shape, self._heights[0]), np.full(times.shape, self._heights[1])


__all__ = ["PathFollower"]
