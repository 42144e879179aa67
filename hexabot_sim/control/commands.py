"""Commands that change during a walk: a schedule of setpoints with smooth ramps, and live steering.

A command source tells the walking controller, each time it plans, which body twist holds from now and until
when (a `Segment`), and the step and stand heights at any time. The controller plans its targets with a
constant twist up to `until` (at most a chunk), so a stance foot stays exactly ground-fixed: the planner
moves it along the twist in force, chunk after chunk. A ramp between two twists is therefore a staircase of
`STAIR_TIME` stairs (the twist of each stair is the ramp's value at the stair's middle): the twist moves in
steps of a twentieth of the change over a one-second ramp, while the heights, which the controller adds to
the targets row by row, ramp linearly.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Sequence
from typing import Protocol

import numpy as np

from hexabot_sim.control.gait import Command

STAIR_TIME: float = 0.05  # [s] a ramp's twist is held constant over stairs of this length

TIME_TOLERANCE: float = 1e-6  # [s] a query this close before a knot or row counts as at it


@dataclasses.dataclass(frozen=True)
class Setpoint:
    """One row of a schedule: from time t on, this twist, gait and these heights (ramped in).

    Attributes:
        t: Run time [s] at which the row's ramp starts (the robot settles first: a row before the gait clock
            starts ramps in from it).
        command: Body twist (vx, vy [m/s], yaw rate [rad/s]).
        gait: The gait's name.
        step_height: Foot lift at mid-swing [m].
        stand_height: Foot depth below the hips [m].
    """

    t: float
    command: Command
    gait: str
    step_height: float
    stand_height: float


@dataclasses.dataclass(frozen=True)
class Segment:
    """What a command source asks for from the time it was queried.

    Attributes:
        command: Body twist to hold.
        until: Run time [s] up to which it holds (inf: until further notice, the controller plans whole chunks).
        gait: The gait in force.
    """

    command: Command
    until: float
    gait: str


class CommandSource(Protocol):
    """What the walking controller asks of a changing command (Schedule, Steering, control.follower.PathFollower)."""

    def segment(self, t: float, pose: tuple[float, float, float]) -> Segment:
        """The twist from run time t [s] on; pose: the body's (x [m], y [m], yaw [rad]) at t."""
        ...

    def heights(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Step height and stand height [m] (each like `times` [s])."""
        ...


class Schedule:
    """Setpoints in time order, each ramped in linearly over `ramp_time` from the value in force when it starts.

    The twist and heights are a piecewise-linear function of time through knots: before the first row's
    ramp, standing (zero twist) at the start heights; a row at t starts its ramp at max(t, start) from the
    value there, and a row that comes before the previous ramp has ended starts from where that ramp got.
    """

    def __init__(
        self, rows: Sequence[Setpoint], start: float, ramp_time: float, step_height: float, stand_height: float
    ) -> None:
        if not rows:
            raise ValueError("a schedule needs at least one row")
        times = [t.t for t in rows]
        if any(b <= a for a, b in itertools.pairwise(times)):
            raise ValueError("schedule times must increase")
        self.rows = tuple(rows)
        self.ramp_time = float(ramp_time)
        knots_t: list[float] = [0.0]
        knots_v: list[np.ndarray] = [np.array([0.0, 0.0, 0.0, step_height, stand_height])]
        self.starts: list[float] = []  # [s] when each row's ramp starts
        for row in rows:
            begin = max(row.t, start)
            value = self._interp(begin, knots_t, knots_v)
            while knots_t and knots_t[-1] >= begin:  # a ramp cut short: it ends where it got to
                knots_t.pop()
                knots_v.pop()
            c = row.command
            target = np.array([c.vx, c.vy, c.yaw_rate, row.step_height, row.stand_height])
            knots_t += [begin, begin + max(self.ramp_time, 1e-9)]
            knots_v += [value, target]
            self.starts.append(begin)
        self.knots_t = np.array(knots_t)  # (k,)
        self.knots_v = np.array(knots_v)  # (k, 5) vx, vy, yaw rate, step height, stand height

    @staticmethod
    def _interp(t: float, knots_t: list[float], knots_v: list[np.ndarray]) -> np.ndarray:
        values = np.array(knots_v)
        return np.array([np.interp(t, knots_t, values[:, j]) for j in range(values.shape[1])])

    def value(self, t: np.ndarray | float) -> np.ndarray:
        """(..., 5): vx, vy, yaw rate, step height, stand height at run time t."""
        t = np.asarray(t, dtype=float)
        return np.stack([np.interp(t, self.knots_t, self.knots_v[:, j]) for j in range(5)], axis=-1)

    def row_at(self, t: float) -> int:
        """Index of the row whose ramp has started last at t (-1: none yet)."""
        return int(np.searchsorted(np.array(self.starts), t, side="right")) - 1

    def segment(self, t: float, pose: tuple[float, float, float] | None = None) -> Segment:
        """The twist from t: constant up to the next knot, or a stair of a ramp (its value at the stair's middle)."""
        t += TIME_TOLERANCE  # the simulation's clock (a sum of steps) may come a hair before a row's time
        k = int(np.searchsorted(self.knots_t, t, side="right"))  # next knot after t
        nxt = float(self.knots_t[k]) if k < len(self.knots_t) else math.inf
        a, b = self.value(t)[:3], self.value(min(nxt, t + STAIR_TIME))[:3]
        if np.array_equal(a, b):  # constant up to the next knot (or for ever)
            until = nxt
        else:
            until = min(nxt, t + STAIR_TIME)
            a = self.value(0.5 * (t + until))[:3]
        i = self.row_at(t)
        gait = self.rows[max(i, 0)].gait
        return Segment(Command(*(float(v) for v in a)), until, gait)

    def heights(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        v = self.value(times)
        return v[..., 3], v[..., 4]


# [m/s^2, rad/s^2] The live steering's twist changes at most this fast at a gait period of 1 s or less, and by
# (1 s / period)^2 of it at longer periods (steering_acceleration).
STEERING_ACCELERATION: float = 0.2


def steering_acceleration(period: float) -> float:
    """The live steering's largest change of the twist [m/s^2, rad/s^2] for a gait of this period [s].

    A stance foot lands where the twist at its touchdown puts it; a speed change of a during the stance (duty x
    period long) then carries its lift-off a S^2 / 2 further (S the stance's length), so the rate is scaled by
    1 / period^2 to keep that as at 1 s. Measured (hexabot-force, 3 s period, the keys asking 0.1 m/s from standing,
    then -0.1, then 0.07 sideways, 30 s): at 0.2 m/s^2 a rear stance foot ran out of its workspace at the first
    hand-over after the start, its servo saturated and the body was thrown 34 mm up; it was off the ground for 90 ms
    in all and sank 31 mm (with position-controlled legs, load_sharing=off, it sank 27 mm); at 0.022 (this rule) the
    body stayed within 0.4 mm of its height and every step had a foot down. At 1 s the 0.2 walks as smoothly."""
    return STEERING_ACCELERATION * min(1.0, 1.0 / period**2)


@dataclasses.dataclass
class Steering:
    """A command set live (the viewer's keys): the twist and heights move toward what was asked at bounded rates.

    Attributes:
        target: The twist asked for.
        gait: The gait asked for.
        step_height, stand_height: The heights asked for [m].
        acceleration: Largest change of the twist [m/s^2, rad/s^2] (the same rate for the three; a walk's is
            steering_acceleration(period)).
        height_rate: Largest change of a height [m/s].
        start: When the gait clock starts [s]: standing still before.
    """

    target: Command
    gait: str
    step_height: float
    stand_height: float
    start: float = 0.5
    acceleration: float = STEERING_ACCELERATION
    height_rate: float = 0.02

    def __post_init__(self) -> None:
        self.now = np.zeros(3)  # the twist in force (vx, vy, yaw rate)
        self._h = np.array([self.step_height, self.stand_height])  # the heights reached at the last query
        self._h_from = self._h.copy()  # ... and at the one before: heights() ramps between them
        self._t = 0.0  # [s] the last query

    def segment(self, t: float, pose: tuple[float, float, float] | None = None) -> Segment:
        """One stair toward what is asked (the keys change it between stairs)."""
        dt = max(0.0, t - self._t)
        self._t = t
        want = np.array([self.target.vx, self.target.vy, self.target.yaw_rate]) if t >= self.start else np.zeros(3)
        self.now += np.clip(want - self.now, -self.acceleration * dt, self.acceleration * dt)
        step = self.height_rate * STAIR_TIME
        self._h_from = self._h.copy()
        self._h = self._h + np.clip(np.array([self.step_height, self.stand_height]) - self._h, -step, step)
        return Segment(Command(*(float(v) for v in self.now)), t + STAIR_TIME, self.gait)

    def heights(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Linear from the heights at the last query but one to those at the last, over the stair."""
        f = np.clip((np.asarray(times, dtype=float) - self._t) / STAIR_TIME, 0.0, 1.0)
        h = self._h_from[:, None] + (self._h - self._h_from)[:, None] * f.reshape(1, -1)
        return h[0].reshape(f.shape), h[1].reshape(f.shape)


def add_heights(targets, source, heights0, times, stance, swing_s, stand: bool = True) -> np.ndarray:
    """Adds a source's change of step height (from heights0's) to the swings' lift h sin^2(pi s) of the targets
    (n + 1, legs, 3) at `times` (n + 1,), and with `stand` its change of stand height to every foot (a higher stand:
    the feet deeper below the hips); returns its stand heights (n + 1,) [m]."""
    from hexabot_sim.control import plan_kernels  # numba: imported on first use (its kernels compiled by the walker)

    step, stand_heights = source.heights(times)
    lower = np.asarray(stand_heights - heights0[1], dtype=float) if stand else _NO_CHANGE
    plan_kernels.add_heights(targets, np.asarray(step - heights0[0], dtype=float), lower, stance, swing_s)
    return stand_heights


_NO_CHANGE = np.zeros(0)


class StanceLog:
    """The stance flags a controller planned, chunk by chunk (its gait may change between chunks)."""

    def __init__(self) -> None:
        self.chunks: list[tuple[np.ndarray, np.ndarray]] = []  # (times (n + 1,), flags (n + 1, legs))

    def __bool__(self) -> bool:
        return bool(self.chunks)

    def append(self, times: np.ndarray, stance: np.ndarray) -> None:
        self.chunks.append((times, stance))

    def at(self, t: np.ndarray) -> np.ndarray:
        """The flags (n, legs) in force at the times t (n,): the last planned row at or before each."""
        times = np.concatenate([rows for rows, _ in self.chunks])
        flags = np.concatenate([stance for _, stance in self.chunks])
        idx = np.searchsorted(times, np.asarray(t) + 1e-9, side="right") - 1
        return flags[np.clip(idx, 0, len(times) - 1)]


__all__ = ["STAIR_TIME", "CommandSource", "Schedule", "Segment", "Setpoint", "StanceLog", "Steering", "add_heights"]
