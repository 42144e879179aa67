"""Gait generator: per-leg phase clocks and the body-frame foot targets for a body-velocity command.

A foot in stance stays fixed on the ground, so in the body frame it moves as  dp/dt = -v - w x p  for
the body twist (v_x, v_y, w_z): a straight line opposite to the motion, or an arc about the
instantaneous centre of rotation when turning. A foot in swing follows the report's elliptic-like
arc: a cubic Hermite in the ground plane whose end velocities equal the stance velocity at lift-off
and touchdown (no stubbing, no scuffing), lifted by h sin^2(pi s) (zero vertical speed at both ends).
Or (profile "quintic") a quintic Hermite whose end accelerations are zero too: the foot stays on its stance
path to second order while it is within a millimetre of the ground, where a compliant foot is already loaded
(a cubic's foot moves over the ground there at a third of its mean swing speed); its peak speed is 1.875x the
mean, the cubic's 1.5x, so the joint-speed limit refuses ~20 % lower commands.

Targets are planned in chunks (numpy over all the legs and every step of the chunk); between chunks
the command may change (heading hold), and every leg continues from where its target is, so the
targets stay continuous in position and velocity.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

CHUNK_TIME: float = 1.0  # [s] targets planned at once


@dataclasses.dataclass(frozen=True)
class Gait:
    """Phase offsets of the legs (the layout's leg order, in cycles) and the stance fraction of a cycle.

    A leg's phase is (cycles + offset) mod 1, in stance while it is below `duty`: within a cycle the
    leg with the largest offset lifts first.
    """

    name: str
    offsets: tuple[float, ...]
    duty: float
    doc: str


# The gaits of each leg count. Offsets follow the legs' order in the layout: the left row front to rear,
# then the right row (kinematics/legged.Layout).
HEXAPOD_GAITS: tuple[Gait, ...] = (  # lf, lm, lr, rf, rm, rr
    Gait("tripod", (0.0, 0.5, 0.0, 0.5, 0.0, 0.5), 0.5, "two alternating tripods (lf, rm, lr) and (rf, lm, rr)"),
    Gait(
        "ripple",
        (2 / 3, 1 / 3, 0.0, 1 / 6, 5 / 6, 0.5),
        2 / 3,
        "a wave front to rear on each side, the sides half a cycle apart: four feet down",
    ),
    Gait(
        "wave",
        (2 / 6, 1 / 6, 0.0, 5 / 6, 4 / 6, 3 / 6),
        5 / 6,
        "one leg at a time, front to rear, right then left: five feet down",
    ),
)
QUADRUPED_GAITS: tuple[Gait, ...] = (  # lf, lr, rf, rr
    # Swings lr, lf, rr, rf (left hind, left fore, right hind, right fore: the lateral-sequence crawl), a
    # quarter cycle each. Of the six orders it keeps the body's centre best inside the triangle of the three
    # feet down: on its edge at worst at duty 3/4 while walking straight, inside with a larger duty
    # (tests/test_legged.py); the other orders put it outside.
    Gait(
        "crawl",
        (0.5, 0.75, 0.0, 0.25),
        0.75,
        "one leg at a time, hind then fore, left then right (lr, lf, rr, rf): three feet down",
    ),
    Gait("trot", (0.0, 0.5, 0.5, 0.0), 0.5, "two alternating diagonal pairs (lf, rr) and (rf, lr)"),
)
GAITS_BY_LEGS: dict[int, dict[str, Gait]] = {
    len(gaits[0].offsets): {g.name: g for g in gaits} for gaits in (HEXAPOD_GAITS, QUADRUPED_GAITS)
}
GAITS: dict[str, Gait] = GAITS_BY_LEGS[6]  # the six-legged gaits (the hexabot's); per robot: gaits_for(n_legs)


def gaits_for(n_legs: int) -> dict[str, Gait]:
    """The gaits of a robot with n_legs legs, by name.

    Raises:
        ValueError: if no gait is defined for that many legs.
    """
    if n_legs not in GAITS_BY_LEGS:
        counts = ", ".join(str(n) for n in sorted(GAITS_BY_LEGS))
        raise ValueError(f"no gaits for {n_legs} legs (gaits exist for {counts} legs)")
    return GAITS_BY_LEGS[n_legs]


@dataclasses.dataclass(frozen=True)
class Command:
    """Body twist in the body frame: forward and sideways speed [m/s], yaw rate [rad/s]."""

    vx: float = 0.0
    vy: float = 0.0
    yaw_rate: float = 0.0

    def scaled(self, factor: float) -> Command:
        return Command(self.vx * factor, self.vy * factor, self.yaw_rate * factor)


def stance_velocity(cmd: Command, p: np.ndarray) -> np.ndarray:
    """Body-frame velocity (..., 2) of ground-fixed points p (..., >=2): -v - w x p."""
    return np.stack([-cmd.vx + cmd.yaw_rate * p[..., 1], -cmd.vy - cmd.yaw_rate * p[..., 0]], axis=-1)


def stance_path(cmd: Command, start: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Body-frame positions (..., n, 2) of ground-fixed points that are at `start` (..., 2), tau [s] (n,) later.

    p(tau) = R(-w tau) p0 - [[S, C], [-C, S]] v with S = sin(w tau) / w and C = (1 - cos(w tau)) / w: the
    solution of dp/dtau = -v - w x p written without the centre of rotation (-vy / w, vx / w), which is
    ill-conditioned for the tiny yaw rates heading hold can ask for (w = 1e-19 put it 1e18 m away).
    S and C are evaluated as tau sinc(w tau) and (w tau^2 / 2) sinc^2(w tau / 2), with no division by w:
    where w tau underflows to 0 (w = 5e-324) they are the straight-line tau and 0, not 0 and 0.
    """
    start = np.asarray(start, dtype=float)[..., None, :]  # (..., 1, 2)
    vx, vy, w = cmd.vx, cmd.vy, cmd.yaw_rate
    if w == 0.0:
        return start - np.stack([vx * tau, vy * tau], axis=-1)
    angle = w * tau
    c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]  # (n, 1)
    big_s = (tau * np.sinc(angle / np.pi))[:, None]  # numpy's sinc(x) = sin(pi x) / (pi x)
    big_c = (0.5 * w * tau**2 * np.sinc(angle / (2 * np.pi)) ** 2)[:, None]
    x0, y0 = start[..., :1], start[..., 1:]
    x = c * x0 + s * y0 - (big_s * vx + big_c * vy)
    y = -s * x0 + c * y0 + (big_c * vx - big_s * vy)
    return np.concatenate([x, y], -1)


def touchdown_point(cmd: Command, neutral: np.ndarray, stance_time: float) -> np.ndarray:
    """Where a foot must land (..., 2) so that its stance is centred on `neutral` (..., 2)."""
    return stance_path(cmd, neutral, np.array([-stance_time / 2]))[..., 0, :]


def hermite(p0, v0, p1, v1, duration: float, s: np.ndarray) -> np.ndarray:
    """Cubic Hermite (n, 2) from (p0, v0) to (p1, v1) over `duration` [s] at fractions s (n,).

    h00 p0 + h10 T v0 + h01 p1 + h11 T v1 with h00 = 1 - h01, h01 = 3 s^2 - 2 s^3, h10 = s^3 - 2 s^2 + s,
    h11 = s^3 - s^2 (written with few array operations: this runs for every swing of every chunk).
    """
    p0, v0, p1, v1 = (np.asarray(v, dtype=float) for v in (p0, v0, p1, v1))
    s = s[:, None]
    s2 = s * s
    h11 = s2 * (s - 1.0)
    h01 = s2 - 2.0 * h11  # 3 s^2 - 2 s^3
    h10 = h11 - s2 + s  # s^3 - 2 s^2 + s
    return p0 + h01 * (p1 - p0) + (duration * h10) * v0 + (duration * h11) * v1


def quintic(u):
    """Quintic Hermite basis at fractions u (floats or arrays): the weights of (p1 - p0, T v0, T v1, T^2 a0) in
    the position, and their first and second derivatives in u; zero acceleration at u = 1."""
    u2 = u * u
    u3 = u2 * u
    h = (u3 * (10 - 15 * u + 6 * u2), u - u3 * (6 - 8 * u + 3 * u2), -u3 * (4 - 7 * u + 3 * u2))
    h = (*h, 0.5 * u2 - u3 * (1.5 - 1.5 * u + 0.5 * u2))
    d = (30 * u2 * (1 - u) ** 2, 1 - u2 * (18 - 32 * u + 15 * u2), -u2 * (12 - 28 * u + 15 * u2))
    d = (*d, u - u2 * (4.5 - 6 * u + 2.5 * u2))
    dd = (60 * u - u2 * (180 - 120 * u), -36 * u + u2 * (96 - 60 * u), -24 * u + u2 * (84 - 60 * u))
    dd = (*dd, 1 - 9 * u + u2 * (18 - 10 * u))
    return h, d, dd


def hermite5(p0, v0, a0, p1, v1, duration: float, s: np.ndarray) -> np.ndarray:
    """Quintic Hermite (n, 2) from (p0, v0, a0) to (p1, v1, zero acceleration) over `duration` [s] at fractions
    s (n,)."""
    p0, v0, a0, p1, v1 = (np.asarray(v, dtype=float) for v in (p0, v0, a0, p1, v1))
    (h01, h10, h11, h20), _, _ = quintic(s[:, None])
    return p0 + h01 * (p1 - p0) + (duration * h10) * v0 + (duration * h11) * v1 + (duration**2 * h20) * a0


PROFILES: tuple[str, ...] = ("cubic", "quintic")  # the swing's horizontal arc (GaitPlanner.profile)


Scale = Callable[[np.ndarray], np.ndarray]  # t [s] (array) -> fraction of the command in force


class _Warp:
    """Warped time tau(t) = integral of s dt over a chunk (trapezoids on its rows: exact for s linear between rows)."""

    def __init__(self, times: np.ndarray, scale: Scale | None) -> None:
        self.t0, self.dt = float(times[0]), float(times[1] - times[0]) if len(times) > 1 else 1.0
        self._scale = scale
        if scale is None:
            self.rows = times - times[0]
            self._s = None
        else:
            s = np.asarray(scale(times), dtype=float)
            self.rows = np.concatenate([[0.0], np.cumsum(0.5 * (s[1:] + s[:-1]) * self.dt)])
            self._s = s

    def factor(self, t: float) -> float:
        """s(t): the fraction of the command in force at t (any t, also beyond the chunk)."""
        return 1.0 if self._scale is None else float(self._scale(np.asarray(t, dtype=float)))

    def __call__(self, t: float) -> float:
        """tau(t) for t inside the chunk, relative to its first row."""
        if self._s is None:
            return t - self.t0
        k = min(max(int((t - self.t0) / self.dt), 0), len(self.rows) - 2)
        f = t - (self.t0 + k * self.dt)
        s_t = self._s[k] + (self._s[k + 1] - self._s[k]) * f / self.dt
        return float(self.rows[k] + 0.5 * f * (self._s[k] + s_t))


@dataclasses.dataclass
class GaitPlanner:
    """Plans body-frame foot targets, chunk by chunk, for a gait, period and step height.

    Attributes:
        gait: Which legs swing when.
        period: Gait cycle [s].
        step_height: Swing lift [m].
        neutral: Neutral foot centres (n_legs, 3) in the body frame [m]; z is the stance height. The leg count
            comes from here; the gait must have as many offsets.
        dt: Control period [s]; targets are produced for every multiple of dt.
        start_time: Gait clock starts here [s] (before it, every foot holds its neutral point).
        profile: The swing's horizontal arc, one of PROFILES.
    """

    gait: Gait
    period: float
    step_height: float
    neutral: np.ndarray
    dt: float
    start_time: float = 0.0
    profile: str = "cubic"

    def __post_init__(self) -> None:
        if self.profile not in PROFILES:
            raise ValueError(f"swing profile {self.profile!r}: one of {', '.join(PROFILES)}")
        self.neutral = np.asarray(self.neutral, dtype=float).copy()
        if self.neutral.ndim != 2 or self.neutral.shape[1] != 3:
            raise ValueError(f"neutral feet must be (n_legs, 3); got {self.neutral.shape}")
        self.n_legs = n = self.neutral.shape[0]
        if len(self.gait.offsets) != n:
            raise ValueError(f"the {self.gait.name} gait is for {len(self.gait.offsets)} legs; the robot has {n}")
        self.offsets = np.array(self.gait.offsets)
        self.stance_time = self.gait.duty * self.period
        self.swing_time = (1 - self.gait.duty) * self.period
        # State of every foot target at the planner's time: position (n, 3), planar velocity and acceleration
        # (n, 2) (a stance's acceleration, which turning gives, is taken as zero: the swing starts from it).
        self.time = 0.0
        self.pos = self.neutral.copy()
        self.vel = np.zeros((n, 2))
        self.acc = np.zeros((n, 2))
        self.swing_targets: list[np.ndarray | None] = [None] * n  # touchdown point of each swing under way
        # Steps planned at once: planning costs ~0.4 ms a chunk plus ~4 us a step (numpy over the legs and
        # the rows), and the command (heading hold) changes between chunks. With 1 s chunks the loop is ~1 us
        # a step cheaper than with 0.5 s, and heading hold keeps an imperfect robot as straight (measured).
        self.max_chunk = max(1, round(CHUNK_TIME / self.dt))
        self._warp = _Warp(np.zeros(1), None)
        # After a gait switch (switch()): the previous gait's swings under way, [lift-off, touchdown) [s], and the
        # time before which a leg does not lift under the new gait's clock; -inf: none.
        self._finish_lift = np.full(n, -np.inf)
        self._finish = np.full(n, -np.inf)
        self._no_lift_before = np.full(n, -np.inf)
        self._touchdown = np.full(n, self.start_time)  # [s] each leg's latest touchdown
        self.switches: list[tuple[float, str]] = []  # (time, gait) of each switch

    def phase(self, t: np.ndarray | float) -> np.ndarray:
        """Gait phase in [0, 1) of each leg (..., n_legs); stance while phase < duty. Before start_time: stance."""
        cycles = (np.asarray(t, dtype=float) - self.start_time) / self.period
        return np.mod(np.asarray(cycles)[..., None] + self.offsets, 1.0)

    def in_stance(self, t: np.ndarray | float) -> np.ndarray:
        """True where the plan has the foot on the ground (..., n_legs).

        Every foot is down before start_time, and a swing whose lift-off would have come before it is
        skipped (that foot stays down until its next lift-off): no foot is snatched up mid-swing.
        """
        t = np.asarray(t, dtype=float)
        frac = self.phase(t)
        lift_time = t[..., None] - (frac - self.gait.duty) * self.period
        swing = (frac >= self.gait.duty) & (lift_time >= self.start_time - 1e-9)
        if self.switches:  # the previous gait's swings finish; the new gait's that would lift before are skipped
            swing &= lift_time >= self._no_lift_before - 1e-9
            swing |= (t[..., None] >= self._finish_lift) & (t[..., None] < self._finish)
        return ~swing

    def swing_fraction(self, t: np.ndarray, stance: np.ndarray) -> np.ndarray:
        """How far each swing has come (..., n_legs) in [0, 1) at times t (...,); 0 in stance."""
        duty = self.gait.duty
        s = np.where(stance, 0.0, (self.phase(t) - duty) / (1.0 - duty))
        if self.switches:
            t = np.asarray(t, dtype=float)[..., None]
            old = (t >= self._finish_lift) & (t < self._finish)
            with np.errstate(invalid="ignore"):  # legs without such a swing: -inf - -inf (not used)
                s = np.where(old, (t - self._finish_lift) / np.where(old, self._finish - self._finish_lift, 1.0), s)
        return s

    def switch_swing(self, leg: int) -> tuple[float, float]:
        """(lift-off, touchdown) [s] of the leg's swing under way at the last switch (-inf, -inf: none)."""
        return float(self._finish_lift[leg]), float(self._finish[leg])

    def switch(self, gait: Gait, min_down: int = 3, candidates: int = 48) -> None:
        """Walks with another gait (same period) from the planner's time on (the next chunk).

        Every leg's swing and stance stay continuous: a swing under way finishes at its planned touchdown; no leg
        lifts under the new gait's clock before t and before every such swing has landed (a swing the new clock
        would have begun earlier is skipped: the foot stays down until its next lift-off; otherwise a tripod's
        swing under way and the new gait's first swings would leave too few feet down). The new clock's phase is chosen
        among `candidates` shifts of a period: the one whose longest stance across the switch (from a foot's
        last touchdown to its first lift-off under the new gait) is shortest (the foot travels least far), then
        whose shortest is longest, with at least `min_down` feet down at every time of the next two periods.
        """
        if len(gait.offsets) != self.n_legs:
            raise ValueError(f"the {gait.name} gait is for {len(gait.offsets)} legs; the robot has {self.n_legs}")
        # The planner's own clock (its phases and events agree on it), and no earlier than the gait clock's start.
        n, t = self.n_legs, max(self.time, self.start_time)
        stance = self.in_stance(np.array(t))
        finish, lift = self._finish.copy(), self._finish_lift.copy()
        for leg in np.flatnonzero(~stance).tolist():
            if not lift[leg] <= t < finish[leg]:  # a swing of the current gait
                finish[leg] = self._next_touchdown(leg, t)
                lift[leg] = finish[leg] - self.swing_time
        landed = np.where(stance, self._touchdown, finish)  # (n,) each foot's latest (or coming) touchdown
        no_lift = np.full(n, max(float(finish.max()), t))  # the new gait lifts no foot before the last has landed
        offsets = np.array(gait.offsets)
        samples = t + self.period * np.arange(0, 2 * 96) / 96  # the next two periods
        best = None
        for j in range(candidates):
            start = t + self.period * (j / candidates - 1.0)  # at or before t
            # First lift-off at or after no_lift: phase == duty, i.e. start + (k + duty - offset) period.
            k = np.ceil((no_lift - start) / self.period - (gait.duty - offsets) - 1e-9)
            first = start + (k + gait.duty - offsets) * self.period  # (n,)
            stances = first - landed  # (n,) [s] each stance across the switch
            longest, shortest = round(float(stances.max()), 9), float(stances.min())
            frac = np.mod((samples[:, None] - start) / self.period + offsets, 1.0)
            lift_t = samples[:, None] - (frac - gait.duty) * self.period
            swing = ((frac >= gait.duty) & (lift_t >= no_lift - 1e-9)) | (
                (samples[:, None] >= lift) & (samples[:, None] < finish)
            )
            down = n - swing.sum(axis=1).max()
            key = (down < min(min_down, n), longest, -shortest)  # shortest longest stance; then no stutter step
            if best is None or key < best[0]:
                best = (key, start)
        self.gait, self.offsets = gait, offsets
        self.stance_time, self.swing_time = gait.duty * self.period, (1 - gait.duty) * self.period
        self.start_time = best[1]  # type: ignore[index]
        self._finish, self._finish_lift, self._no_lift_before = finish, lift, no_lift
        self.switches.append((t, gait.name))
        self.clock_from = float(no_lift[0])  # [s] the old gait's swings have landed: the new gait's may begin

    def plan(self, cmd: Command, n_steps: int, scale: Scale | None = None) -> np.ndarray:
        """Targets (n_steps + 1, n_legs, 3) at time, time + dt, ..., time + n_steps dt; advances the planner n_steps dt.

        Row 0 equals the last row of the previous chunk (continuity); n_steps <= max_chunk.

        Args:
            cmd: Body twist of the chunk.
            n_steps: Steps to plan.
            scale: Fraction of `cmd` in force at time t (vectorised over t; default 1): a command that ramps
                inside the chunk. The body twist s(t) cmd moves ground-fixed points along the same paths as
                cmd does, in the warped time tau = integral of s dt, so stances are exact for any s(t).
        """
        if not 1 <= n_steps <= self.max_chunk:
            raise ValueError(f"a chunk must have 1 to {self.max_chunk} steps; got {n_steps}")
        before = round((self.start_time - self.time) / self.dt)
        if 0 < before < n_steps:  # the gait clock starts inside: stand still up to it, then walk
            standing = self.plan(Command(), before)
            return np.concatenate([standing, self.plan(cmd, n_steps - before, scale)[1:]])
        times = self.time + self.dt * np.arange(n_steps + 1)  # (n+1,)
        out = np.repeat(self.pos[None], n_steps + 1, axis=0)  # (n+1, n_legs, 3)
        if times[-1] <= self.start_time:  # standing still before the gait starts
            self.time = float(times[-1])
            return out
        self._warp = _Warp(times, scale)
        new_vel, new_acc = np.zeros((self.n_legs, 2)), np.zeros((self.n_legs, 2))
        stance_all = self.in_stance(times)  # (n+1, n_legs)
        for leg in range(self.n_legs):
            stance = stance_all[:, leg]
            p0, v0, a0 = self.pos[leg, :2], self.vel[leg], self.acc[leg]
            xy = np.empty((n_steps + 1, 2))
            z = np.full(n_steps + 1, self.neutral[leg, 2])
            z[0] = self.pos[leg, 2]
            # Row 0 is the current state; rows after a mode change restart from the state at the event.
            k = 1
            xy[0] = p0
            t_state, p_state, v_state, a_state = times[0], p0, v0, a0
            mode = bool(stance[0])
            # Segments of one mode: rows k .. end - 1, end being the next row whose mode differs (or n + 1).
            for end in [*(np.flatnonzero(stance[1:] != stance[:-1]) + 1).tolist(), n_steps + 1]:
                rows = slice(k, end)
                if mode:  # stance: ground-fixed point, from the state at t_state
                    xy[rows] = stance_path(cmd, p_state, self._warp.rows[rows] - self._warp(t_state))
                else:  # swing: Hermite from the current state to the touchdown point
                    touchdown_t = self._next_touchdown(leg, t_state)
                    target, target_v = self._swing_target(cmd, leg, touchdown_t, lifting=t_state > times[0])
                    duration = touchdown_t - t_state
                    s = (times[rows] - t_state) / duration
                    if self.profile == "cubic":
                        xy[rows] = hermite(p_state, v_state, target, target_v, duration, s)
                    else:
                        xy[rows] = hermite5(p_state, v_state, a_state, target, target_v, duration, s)
                    swing_time = self.swing_time
                    if touchdown_t == self._finish[leg]:  # a swing of the gait before a switch
                        swing_time = self._finish[leg] - self._finish_lift[leg]
                    swing_s = (times[rows] - (touchdown_t - swing_time)) / swing_time
                    z[rows] += self.step_height * np.sin(np.pi * np.clip(swing_s, 0.0, 1.0)) ** 2
                state = (p_state, v_state, a_state)
                if end <= n_steps:  # a phase event between end-1 and end: state at the event time
                    t_event = self._event_time(leg, times[end - 1], times[end])
                    p_state, v_state, a_state = self._state_at(cmd, leg, mode, t_state, state, t_event)
                    t_state, mode = t_event, not mode
                    if mode:
                        self._touchdown[leg] = t_event
                k = end
            # State at the chunk's last time, for the next chunk.
            state = (p_state, v_state, a_state)
            p_last, new_vel[leg], new_acc[leg] = self._state_at(cmd, leg, mode, t_state, state, times[-1])
            xy[-1] = p_last
            out[:, leg, :2] = xy
            out[:, leg, 2] = z
        self.pos = out[-1].copy()
        self.vel, self.acc = new_vel, new_acc
        self.time = float(times[-1])
        return out

    def _swing_target(self, cmd: Command, leg: int, touchdown_t: float, lifting: bool) -> tuple[np.ndarray, np.ndarray]:
        """Touchdown point of a swing and the stance velocity there.

        Chosen from the command at lift-off and kept for the whole swing (re-aiming a foot late in its
        swing, when the command changes, would take a jolt); the landing velocity follows the command.
        The point is where the stance that follows is centred on the neutral point: half a stance of
        warped time before it, s(t) being linear over the first half (s at its midpoint times T/2).
        """
        factor = self._warp.factor
        if lifting or self.swing_targets[leg] is None:
            half = factor(touchdown_t + 0.25 * self.stance_time) * self.stance_time
            self.swing_targets[leg] = touchdown_point(cmd, self.neutral[leg, :2], half)
        target = self.swing_targets[leg]
        return target, stance_velocity(cmd.scaled(factor(touchdown_t)), target)

    def _next_touchdown(self, leg: int, t: float) -> float:
        """First time > t at which the leg's phase wraps to 0 (touchdown), or the touchdown of a swing of the
        gait before a switch."""
        if self._finish_lift[leg] <= t < self._finish[leg]:
            return float(self._finish[leg])
        cycles = (t - self.start_time) / self.period + self.offsets[leg]
        return self.start_time + (math.floor(cycles + 1e-12) + 1 - self.offsets[leg]) * self.period

    def _event_time(self, leg: int, t0: float, t1: float) -> float:
        """Time of the lift-off (phase = duty) or touchdown (phase = 0) between t0 and t1."""
        if t0 < self._finish[leg] <= t1 + 1e-12:  # a swing of the gait before a switch lands
            return float(self._finish[leg])
        base = (t0 - self.start_time) / self.period + self.offsets[leg]
        for boundary in (self.gait.duty, 1.0):
            k = math.floor(base - boundary) + 1  # next crossing of phase == boundary (mod 1)
            t_cross = self.start_time + (k + boundary - self.offsets[leg]) * self.period
            if t0 < t_cross <= t1 + 1e-12:
                return t_cross
        return max(t0, self.start_time)  # the gait clock starting inside the step

    def _state_at(self, cmd, leg, stance, t_state, state, t):
        """(position, velocity, acceleration) of the leg's target at t, continuing the segment that started at
        t_state in `state` (the same three; a stance's acceleration is taken as zero).

        The same closed forms as `stance_path` and `hermite`, in plain floats (called a few times a chunk).
        """
        p_state, v_state, a_state = state
        px, py = float(p_state[0]), float(p_state[1])
        vx, vy, w = cmd.vx, cmd.vy, cmd.yaw_rate
        if stance:
            tau = self._warp(t) - self._warp(t_state)
            if w == 0.0:
                x, y = px - vx * tau, py - vy * tau
            else:  # as stance_path, without the centre of rotation or a division by w
                angle = w * tau
                c, s = math.cos(angle), math.sin(angle)
                half = 0.5 * angle
                sinc_half = math.sin(half) / half if half else 1.0
                big_s = tau * (s / angle if angle else 1.0)
                big_c = 0.5 * w * tau * tau * sinc_half * sinc_half
                x = c * px + s * py - (big_s * vx + big_c * vy)
                y = -s * px + c * py + (big_c * vx - big_s * vy)
            f = self._warp.factor(t)
            return np.array([x, y]), np.array([f * (-vx + w * y), f * (-vy - w * x)]), np.zeros(2)
        touchdown_t = self._next_touchdown(leg, t_state)
        duration = touchdown_t - t_state
        target, target_v = self._swing_target(cmd, leg, touchdown_t, lifting=False)
        u = (t - t_state) / duration
        if self.profile == "cubic":
            h00, h10, h01, h11 = 2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u, -2 * u**3 + 3 * u**2, u**3 - u**2
            d00, d10, d01, d11 = 6 * u**2 - 6 * u, 3 * u**2 - 4 * u + 1, -6 * u**2 + 6 * u, 3 * u**2 - 2 * u
            p = h00 * p_state + h10 * duration * v_state + h01 * target + h11 * duration * target_v
            v = (d00 * p_state + d01 * target) / duration + d10 * v_state + d11 * target_v
            return p, v, np.zeros(2)
        h, d, dd = quintic(u)
        terms = (target - p_state, duration * v_state, duration * target_v, duration**2 * a_state)
        p = p_state + sum(k * x for k, x in zip(h, terms, strict=True))
        v = sum(k * x for k, x in zip(d, terms, strict=True)) / duration
        return p, v, sum(k * x for k, x in zip(dd, terms, strict=True)) / duration**2


__all__ = ["GAITS", "GAITS_BY_LEGS", "Command", "Gait", "GaitPlanner", "gaits_for"]
