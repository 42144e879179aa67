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

Targets are planned in chunks (compiled: control/plan_kernels.py holds the maths, this module the planner's
state); between chunks the command may change (heading hold), and every leg continues from where its target
is, so the targets stay continuous in position and velocity.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

CHUNK_TIME: float = 1.0  # [s] targets planned at once
# [s] every foot down at a gait switch before the new gait lifts its first foot: the load the landing feet take
# over settles before it is handed on (0.1 s: no bounce across tripod <-> wave, measured in docs/hexabot.md)
SETTLE: float = 0.1
# Columns of GaitPlanner.timing (plan_kernels' `timing`): phase offset [cycles], the swing under way at the last
# switch [lift-off, touchdown) [s], no lift-off before [s], latest touchdown [s].
OFFSET, FINISH_LIFT, FINISH, NO_LIFT, TOUCHDOWN = range(5)
NTIMING = 5


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

    def stance_sets(self, duty: float = 0.0) -> list[tuple[int, ...]]:
        """The distinct sets of feet (the layout's leg indices) down at once in a cycle, at `duty` (0: its own)."""
        duty = duty or self.duty
        offsets = np.asarray(self.offsets, dtype=float)
        # The set changes only where a leg's phase crosses 0 or duty: look just after each of those instants.
        events = np.mod(np.concatenate([-offsets, duty - offsets]), 1.0) + 1e-9
        phases = np.mod(events[:, None] + offsets[None, :], 1.0)
        return list(dict.fromkeys(tuple(int(i) for i in np.flatnonzero(row)) for row in phases < duty))

    def least_down(self, duty: float = 0.0) -> int:
        """The fewest feet down at any time of a cycle, at `duty` (0: the gait's own)."""
        return min(len(down) for down in self.stance_sets(duty))


# The gaits of each leg count. Offsets follow the legs' order in the layout: the left row front to rear,
# then the right row (kinematics/legged.Layout).
HEXAPOD_GAITS: tuple[Gait, ...] = (  # lf, lm, lr, rf, rm, rr
    Gait("tripod", (0.0, 0.5, 0.0, 0.5, 0.0, 0.5), 0.5, "two alternating tripods (lf, rm, lr) and (rf, lm, rr)"),
    # The ripple and the wave are forward waves: on each side the swings run rear to front (the wave gait of
    # McGhee and Frank, and of walking insects), the sides half a cycle apart. A foot lands as the next lifts, so at
    # each hand-over the body stands for a moment on the feet down on both sides of it; walking forward, a wave that
    # runs rear to front keeps the body's centre inside them (wave 4.9 mm, ripple 4.7 mm at the speeds),
    # front to rear (the backward wave, these gaits until 2026-11-27) left it outside (-4.8, -5.0 mm), and the
    # feet's loads jumped at every hand-over (tests/test_legged.py, docs/hexabot.md).
    Gait(
        "ripple",
        (4 / 6, 0.0, 2 / 6, 1 / 6, 3 / 6, 5 / 6),
        2 / 3,
        "a wave rear to front on each side, the sides half a cycle apart: four feet down",
    ),
    Gait(
        "wave",
        (2 / 6, 3 / 6, 4 / 6, 5 / 6, 0.0, 1 / 6),
        5 / 6,
        "one leg at a time, rear to front, left then right: five feet down",
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


def _kernels():
    """control/plan_kernels.py, imported on first use and compiled with the walking kernels (importing numba takes
    ~0.15 s, which `hexabot-sim list` should not pay: it imports this module for the gait tables)."""
    if _KERNELS:
        return _KERNELS[0]
    from hexabot_sim.control import kernels, plan_kernels

    kernels.warm_up()  # not under the signal hold: a cold compile takes tens of seconds (see kernels.warm_up)
    _KERNELS.append(plan_kernels)
    return plan_kernels


_KERNELS: list = []


def stance_path(cmd: Command, start: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Body-frame positions (..., n, 2) of ground-fixed points that are at `start` (..., 2), tau [s] (n,) later.

    The closed form is plan_kernels.stance_point's: p(tau) = R(-w tau) p0 - [[S, C], [-C, S]] v with
    S = sin(w tau) / w and C = (1 - cos(w tau)) / w, without a division by w.
    """
    start = np.asarray(start, dtype=float)
    tau = np.ascontiguousarray(tau, dtype=float).reshape(-1)
    points = np.ascontiguousarray(start.reshape(-1, 2))
    out = np.empty((points.shape[0], tau.shape[0], 2))
    _kernels().stance_points(float(cmd.vx), float(cmd.vy), float(cmd.yaw_rate), points, tau, out)
    return out.reshape(start.shape[:-1] + out.shape[1:])


PROFILES: tuple[str, ...] = ("cubic", "quintic")  # the swing's horizontal arc (GaitPlanner.profile)

Scale = Callable[[np.ndarray], np.ndarray]  # t [s] (array) -> fraction of the command in force


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
        self.stance_time = self.gait.duty * self.period
        self.swing_time = (1 - self.gait.duty) * self.period
        # The legs' clocks (plan_kernels' `timing`): the gait's phase offsets; after a gait switch (switch()), the
        # previous gait's swings under way, [lift-off, touchdown) [s], and the time before which a leg does not lift
        # under the new gait's clock (-inf: none); each leg's latest touchdown [s].
        self.timing = np.full((n, NTIMING), -np.inf)
        self.timing[:, OFFSET] = self.gait.offsets
        self.timing[:, TOUCHDOWN] = self.start_time
        # State of every foot target at the planner's time: position (n, 3), planar velocity and acceleration
        # (n, 2) (a stance's acceleration, which turning gives, is taken as zero: a quintic swing starts from it).
        self.time = 0.0
        self.pos = self.neutral.copy()
        self.vel = np.zeros((n, 2))
        self.acc = np.zeros((n, 2))
        # The touchdown point (n, 2) of each swing under way, chosen at its lift-off, where `landing_set` is True.
        self.landing = np.zeros((n, 2))
        self.landing_set = np.zeros(n, dtype=bool)
        # Steps planned at once. The command (heading hold) changes between chunks; with 1 s chunks heading hold
        # keeps an imperfect robot as straight as with 0.5 s (measured); a chunk costs ~20 us plus ~1 us a step
        # (scripts/bench.py's env line plans chunks of 50 steps).
        self.max_chunk = max(1, round(CHUNK_TIME / self.dt))
        self.switches: list[tuple[float, str]] = []  # (time, gait) of each switch

    @property
    def offsets(self) -> np.ndarray:
        """The gait's phase offsets (n_legs,) [cycles] in force (a view of `timing`)."""
        return self.timing[:, OFFSET]

    @property
    def swing_targets(self) -> list[np.ndarray | None]:
        """The touchdown point (2,) of each leg's swing under way (the latest chosen), None where none was yet."""
        return [self.landing[i].copy() if self.landing_set[i] else None for i in range(self.n_legs)]

    def _clock(self) -> np.ndarray:
        """plan_kernels' `clock`: the gait clock's start, period, duty, whether it switched, the step height, the
        stance and swing times."""
        return np.array([
            self.start_time, self.period, self.gait.duty, 1.0 if self.switches else 0.0, self.step_height,
            self.stance_time, self.swing_time,
        ])  # fmt: skip

    def _times(self, t: np.ndarray | float) -> tuple[np.ndarray, tuple[int, ...]]:
        t = np.asarray(t, dtype=float)
        return np.ascontiguousarray(t.reshape(-1)), (*t.shape, self.n_legs)

    def phase(self, t: np.ndarray | float) -> np.ndarray:
        """Gait phase in [0, 1) of each leg (..., n_legs); stance while phase < duty."""
        times, shape = self._times(t)
        out = np.empty((times.size, self.n_legs))
        _kernels().fractions(times, np.empty((0, self.n_legs), dtype=bool), self._clock(), self.timing, out)
        return out.reshape(shape)

    def in_stance(self, t: np.ndarray | float) -> np.ndarray:
        """True where the plan has the foot on the ground (..., n_legs).

        Every foot is down before start_time, and a swing whose lift-off would have come before it is
        skipped (that foot stays down until its next lift-off): no foot is snatched up mid-swing. After a gait
        switch, the previous gait's swings finish and the new gait's that would lift before they have landed are
        skipped.
        """
        return self.flags(t, fractions=False)[0]

    def swing_fraction(self, t: np.ndarray, stance: np.ndarray) -> np.ndarray:
        """How far each swing has come (..., n_legs) in [0, 1) at times t (...,); 0 in stance."""
        times, shape = self._times(t)
        out = np.empty((times.size, self.n_legs))
        flags = np.ascontiguousarray(np.broadcast_to(stance, shape).reshape(times.size, self.n_legs), dtype=bool)
        _kernels().fractions(times, flags, self._clock(), self.timing, out)
        return out.reshape(shape)

    def flags(self, t: np.ndarray | float, fractions: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """(in_stance(t), swing_fraction(t, in_stance(t))) (each (..., n_legs)) at once."""
        times, shape = self._times(t)
        stance = np.empty((times.size, self.n_legs), dtype=bool)
        swing_s = np.empty((times.size if fractions else 0, self.n_legs))
        _kernels().flags(times, self._clock(), self.timing, stance, swing_s)
        return stance.reshape(shape), swing_s.reshape(shape) if fractions else swing_s

    def switch_swing(self, leg: int) -> tuple[float, float]:
        """(lift-off, touchdown) [s] of the leg's swing under way at the last switch (-inf, -inf: none)."""
        return float(self.timing[leg, FINISH_LIFT]), float(self.timing[leg, FINISH])

    def switch(self, gait: Gait, min_down: int = 3, candidates: int = 48, settle: float = SETTLE) -> None:
        """Walks with another gait (same period) from the planner's time on (the next chunk).

        Every leg's swing and stance stay continuous: a swing under way finishes at its planned touchdown; no leg
        lifts under the new gait's clock before t and before every such swing has landed and `settle` [s] has passed
        with every foot down (a swing the new clock would have begun earlier is skipped: the foot stays down until its
        next lift-off; otherwise a tripod's swing under way and the new gait's first swings would leave too few feet
        down; without the settling time the load a landing tripod takes over is handed on at once, docs/hexabot.md).
        The new clock's phase is chosen among `candidates` shifts of a period: the one whose longest stance across
        the switch (from a foot's last touchdown to its first lift-off under the new gait) is shortest (the foot
        travels least far), then whose shortest is longest, with at least `min_down` feet down at every time of the
        next two periods.
        """
        if len(gait.offsets) != self.n_legs:
            raise ValueError(f"the {gait.name} gait is for {len(gait.offsets)} legs; the robot has {self.n_legs}")
        # The planner's own clock (its phases and events agree on it), and no earlier than the gait clock's start.
        n, t = self.n_legs, max(self.time, self.start_time)
        if self.time < self.start_time:  # standing before the clock starts (no foot has lifted): walk the new gait
            self._set_gait(gait)  # from the start, as if it had been the first (its swings were planned mid-swing)
            self.switches.append((t, gait.name))
            self.clock_from = t
            return
        stance = self.in_stance(np.array(t))
        finish, lift = self.timing[:, FINISH].copy(), self.timing[:, FINISH_LIFT].copy()
        touched = self.timing[:, TOUCHDOWN].copy()
        for leg in np.flatnonzero(~stance).tolist():
            if not lift[leg] <= t < finish[leg]:  # a swing of the current gait
                coming = self._next_touchdown(leg, t)
                if coming - t > self.swing_time + 1e-9:  # its phase a rounding error short of 1: it lands at t
                    stance[leg], touched[leg] = True, t
                    continue
                # Under way at t: lifted at or before it (touchdown less the swing time can round to after t, and a
                # swing lifting inside the next chunk would not be planned until the chunk after it, mid-swing).
                finish[leg], lift[leg] = coming, min(coming - self.swing_time, t)
        landed = np.where(stance, touched, finish)  # (n,) each foot's latest (or coming) touchdown
        # The new gait lifts no foot before the last has landed and every foot has been down for `settle`.
        no_lift = np.full(n, max(float(finish.max()), t) + settle)
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
        self._set_gait(gait)
        self.start_time = best[1]  # type: ignore[index]
        self.timing[:, FINISH], self.timing[:, FINISH_LIFT], self.timing[:, NO_LIFT] = finish, lift, no_lift
        self.switches.append((t, gait.name))
        self.clock_from = float(no_lift[0])  # [s] the old gait's swings have landed: the new gait's may begin

    def _set_gait(self, gait: Gait) -> None:
        self.gait = gait
        self.timing[:, OFFSET] = gait.offsets
        self.stance_time, self.swing_time = gait.duty * self.period, (1 - gait.duty) * self.period

    def plan(self, cmd: Command, n_steps: int, scale: Scale | None = None) -> np.ndarray:
        """Targets (n_steps + 1, n_legs, 3) at time, time + dt, ..., time + n_steps dt; advances the planner n_steps dt.

        Row 0 equals the last row of the previous chunk (continuity); n_steps <= max_chunk. A foot in stance stays
        fixed on the ground; a swing's landing point is chosen from the command at lift-off and kept for the whole
        swing (re-aiming a foot late in its swing, when the command changes, would take a jolt), its landing velocity
        follows the command (plan_kernels.targets).

        Args:
            cmd: Body twist of the chunk.
            n_steps: Steps to plan.
            scale: Fraction of `cmd` in force at time t (vectorised over t; default 1): a command that ramps
                inside the chunk. The body twist s(t) cmd moves ground-fixed points along the same paths as
                cmd does, in the warped time tau = integral of s dt, so stances are exact for any s(t) linear
                between the rows.
        """
        if not 1 <= n_steps <= self.max_chunk:
            raise ValueError(f"a chunk must have 1 to {self.max_chunk} steps; got {n_steps}")
        before = round((self.start_time - self.time) / self.dt)
        if 0 < before < n_steps:  # the gait clock starts inside: stand still up to it, then walk
            standing = self.plan(Command(), before)
            return np.concatenate([standing, self.plan(cmd, n_steps - before, scale)[1:]])
        times = self.time + self.dt * np.arange(n_steps + 1)  # (n+1,)
        if times[-1] <= self.start_time:  # standing still before the gait starts
            self.time = float(times[-1])
            return np.repeat(self.pos[None], n_steps + 1, axis=0)
        K = _kernels()
        clock = self._clock()
        rows = (self.n_legs, n_steps + 1, K.NSEG)
        seg, count = np.empty(rows) if scale is None else np.zeros(rows), np.empty(self.n_legs, dtype=np.int64)
        K.segments(times, clock, self.timing, seg, count)
        s, factors = times, seg  # unused without a ramp
        if scale is not None:  # the ramp's factor at the rows and at the times the segments ask for it
            s = np.ascontiguousarray(scale(times), dtype=float)
            queries = seg[:, : int(count.max()), K.QUERY : K.QUERY + 2]
            factors = np.empty(queries.shape)  # (n_legs, segments, 2)
            factors[...] = scale(queries)
        out = np.empty((n_steps + 1, self.n_legs, 3))
        command = np.array([cmd.vx, cmd.vy, cmd.yaw_rate], dtype=float)
        K.targets(command, times, s, scale is not None, clock, self.timing, self.neutral, seg, count,
                  factors, self.pos, self.vel, self.acc, self.profile == "quintic", self.landing, self.landing_set,
                  out)  # fmt: skip
        self.time = float(times[-1])
        return out

    def _next_touchdown(self, leg: int, t: float) -> float:
        """First time > t at which the leg's phase wraps to 0 (touchdown), or the touchdown of a swing of the
        gait before a switch."""
        return float(_kernels().next_touchdown(float(t), self._clock(), self.timing, leg))


__all__ = ["GAITS", "GAITS_BY_LEGS", "Command", "Gait", "GaitPlanner", "gaits_for"]
