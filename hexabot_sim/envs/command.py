"""Twist-level control: the policy steers the verified gait controller (HexabotCommand-v0)."""

from __future__ import annotations

import dataclasses
import itertools
import math

import mujoco
import numpy as np
from gymnasium import spaces

from hexabot_sim.control.commands import Segment
from hexabot_sim.control.gait import Command
from hexabot_sim.control.walker import WalkingController
from hexabot_sim.envs.base import COMMAND_RANGE, LeggedEnv, Reward, unknown_keywords
from hexabot_sim.envs.scene import MAX_SLOPE_DEG, check_range, check_stairs, real_number, robot_params, terrain_keywords
from hexabot_sim.walking.constants import SETTLE_TIME
from hexabot_sim.walking.parameters import WalkParams
from hexabot_sim.walking.scene import acceleration_limit, make_controller

TWIST_RANGE: tuple[tuple[float, float], ...] = ((-0.15, 0.15), (-0.1, 0.1), (-0.4, 0.4))  # vx, vy [m/s], yaw rate
STEP_HEIGHT_RANGE: tuple[float, float] = (0.015, 0.045)  # [m] foot lift at mid-swing
# [m] on stairs: with the elevator reflex a swing clears 2 x step height less a foot radius, so 3 cm climbs the
# default 4 cm rise (1.5 cm clears 22 mm)
STAIRS_STEP_HEIGHT_RANGE: tuple[float, float] = (0.03, 0.045)


def _on_stairs(base: WalkParams, rise: float, run: float, count: int, low: float) -> WalkParams:
    """The walk on the stairs, checked at the lowest step height of the range (the lowest swing climbs least); a
    refusal in this environment's arguments (the walk's names stand_height and step_height are not among them).
    A step height the legs cannot deliver at the walk's default twist is left to the ranges' corners check."""
    low_end = " (step_height_range's low end)"
    for h in (low, base.step_height):
        try:
            return dataclasses.replace(base, stairs_rise=rise, stairs_run=run, stairs_count=count, step_height=h)
        except ValueError as e:
            reason, _, hint = str(e).rpartition("; ")
            if "stair rise" not in reason and h != base.step_height:
                continue  # not the stairs: the corners' check words it
            advice = "raise step_height_range or lower the rise" if hint == "raise 'step_height'" else "lower the rise"
            raise ValueError(
                f"stairs rise {rise:g} m at step height {h:g} m{low_end if h == low else ''}: {reason or hint}; "
                f"{advice}"
            ) from None
    raise AssertionError("unreachable")  # the loop's last step height returns or raises


def _controller_params(base: WalkParams, ranges: np.ndarray) -> WalkParams:
    """The walk parameters the controller is made with: every corner of the (4, 2) ranges (vx, vy, yaw rate, step
    height) checked for feasibility, the one needing the largest joint-acceleration limit kept (the limit then covers
    them all). Raises ValueError naming the first corner the legs cannot deliver."""
    best, best_limit = base, -1.0
    for vx, vy, w, h in itertools.product(*ranges):
        try:
            p = dataclasses.replace(base, vx=float(vx), vy=float(vy), yaw_rate=float(w), step_height=float(h))
        except ValueError as e:
            reason = str(e)
            if reason.startswith("even stepping in place is infeasible"):  # its advice named the walk's period and
                reason = reason.rpartition("; ")[0] + "; lower step_height_range"  # step_height: not keywords here
            raise ValueError(
                f"twist_range and step_height_range must hold commands the legs can deliver; at vx {vx:g}, "
                f"vy {vy:g}, yaw rate {w:g}, step height {h:g}: {reason}"
            ) from None
        limit = acceleration_limit(p)
        if limit > best_limit:
            best, best_limit = p, limit
    return best


def _feasible_scale(base: WalkParams, ranges: np.ndarray) -> float:
    """The largest factor (to 1 %, at most 1) by which the twist ranges (rows 0-2 of `ranges`) can be scaled so that
    every corner is a command the legs can deliver: the default ranges of a robot slower than the hexabot (the
    quadbot's crawl). Raises ValueError if not even 1 % of them can be delivered (the corners' own message)."""

    def feasible(scale: float) -> bool:
        try:
            _controller_params(base, np.vstack([ranges[:3] * scale, ranges[3:]]))
        except ValueError:
            return False
        return True

    if feasible(1.0):
        return 1.0
    low, high = 0.0, 1.0  # feasible at low (not yet known at 0), not at high
    while high - low > 0.01:
        mid = 0.5 * (low + high)
        low, high = (mid, high) if feasible(mid) else (low, mid)
    if low == 0.0:
        _controller_params(base, np.vstack([ranges[:3] * 0.01, ranges[3:]]))  # raises, naming the corner
    return math.floor(low * 100.0) / 100.0


class ActionSource:
    """The policy's latest action as the controller's command source (control/commands.CommandSource): its twist
    holds for one control period; the step height ramps linearly over the period from the previous action's, so a
    foot in mid-swing is lifted or lowered smoothly (setting the planner's step height made its target jump by up to
    the whole range, 3 cm)."""

    def __init__(self, gait: str, step_height: float, stand_height: float, period: float) -> None:
        self.gait, self.period, self.stand_height = gait, period, stand_height
        self.command = Command()
        self._t0, self._from, self._to = 0.0, step_height, step_height

    def act(self, t: float, command: Command, step_height: float) -> None:
        """The action taken at run time t [s]: the step height ramps on from where it is at t."""
        f = min(max((t - self._t0) / self.period, 0.0), 1.0)  # heights()' ramp at t, in floats (one number)
        self._from = self._from + (self._to - self._from) * f
        self._t0, self._to, self.command = t, step_height, command

    def segment(self, t: float, pose: tuple[float, float, float]) -> Segment:
        return Segment(self.command, t + self.period, self.gait)

    def heights(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        f = np.minimum(np.maximum((np.asarray(times, dtype=float) - self._t0) / self.period, 0.0), 1.0)
        return self._from + (self._to - self._from) * f, np.full(f.shape, self.stand_height)


class LeggedCommandEnv(LeggedEnv):
    """A legged robot walking with its gait controller (control/walker.py), the policy choosing the body twist and step
    height the controller is given every control period (0.1 s): navigation and high-level learning on a gait that
    is verified (docs/hexabot.md).

    Action: Box(-1, 1, (4,)), float32: the twist (vx, vy [m/s], yaw rate [rad/s]) and the step height [m], each
    mapped affinely from [-1, 1] onto its range (`twist_range`, `step_height_range`; a at 0 is mid-range). The
    controller plans the next period with it (each foot continues from where it is; a swing keeps the landing
    point chosen at its lift-off). Out-of-range actions are clipped; a wrong shape or a NaN is a ValueError.

    Observation, reward, command and termination: as LeggedJointsEnv's (base.LeggedEnv). The controller is the
    walk scenarios' (walking/scene.make_controller): planned touchdown on flat ground; on a slope or rough ground
    the ground-finding one with sensed touchdown (and on a slope and stairs a level body), as hexabot-slope,
    hexabot-rough and hexabot-stairs (whose elevator reflex lifts a swing foot that meets a step's face).
    Every corner of the twist and step-height ranges must be a command the legs can deliver (checked as a walk's
    parameters are: walking/parameters.feasibility). Registered with 200 steps of 0.1 s (20 s).

    Args:
        robot, terrain, slope_deg, roughness, stairs, command_range, reward, randomize_*, render_mode, width,
            height, camera: as LeggedJointsEnv's.
        frame_skip: Physics steps (2 ms each, the controller running at each) per action.
        twist_range: (low, high) of the controller's vx, vy [m/s] and yaw rate [rad/s]; default TWIST_RANGE
            ((-0.15, 0.15), (-0.1, 0.1), (-0.4, 0.4)), scaled down to the largest part of it (to 1 %) whose every
            corner the robot's legs can deliver (the quadbot's crawl: 0.53 of it).
        step_height_range: (low, high) of the step height [m]; default (0.015, 0.045), on stairs (0.03, 0.045).
    """

    def __init__(
        self,
        robot: str = "hexabot",
        frame_skip: int = 50,
        terrain: str = "flat",
        slope_deg: float | None = None,
        roughness: float | None = None,
        stairs: tuple[float, float, int] | None = None,
        command_range=COMMAND_RANGE,
        twist_range=None,
        step_height_range=None,
        reward: Reward | dict | None = None,
        randomize_friction: tuple[float, float] | None = None,
        randomize_mass: tuple[float, float] | None = None,
        randomize_servo_gain: tuple[float, float] | None = None,
        render_mode: str | None = None,
        width: int = 640,
        height: int = 480,
        camera: str = "track",
        **kwargs,
    ) -> None:
        unknown_keywords(type(self), kwargs)  # a misspelt keyword: a ValueError naming the known ones, not a TypeError
        slope_deg, roughness, stairs = terrain_keywords(terrain, slope_deg, roughness, stairs)
        try:
            rows = [tuple(r) for r in (TWIST_RANGE if twist_range is None else twist_range)]
        except TypeError:
            rows = []
        if len(rows) != 3:
            raise ValueError(f"twist_range must be three (low, high) pairs: vx, vy, yaw rate; got {twist_range!r}")
        names = ("vx", "vy", "yaw rate")
        ranges = [check_range(f"twist_range {n}", r, -1.0, 1.0) for n, r in zip(names, rows, strict=True)]
        if step_height_range is None:
            step_height_range = STAIRS_STEP_HEIGHT_RANGE if terrain == "stairs" else STEP_HEIGHT_RANGE
        ranges.append(check_range("step_height_range", step_height_range, 0.002, 0.1))
        self.ranges = np.array(ranges)  # (4, 2)
        ground = {
            "flat": {}, "slope": {"touchdown": "sensed", "level_body": "on"}, "rough": {"touchdown": "sensed"},
            "stairs": {"touchdown": "sensed", "level_body": "on"},  # as hexabot-stairs: the elevator reflex climbs
        }  # fmt: skip
        overrides: dict[str, object] = dict(ground.get(terrain, {}) if isinstance(terrain, str) else {})
        if terrain == "stairs":  # the walk's own checks: a rise its legs and the reflex can climb
            rise, run, count = check_stairs(stairs)
            base = _on_stairs(robot_params(robot, **overrides), rise, run, count, float(self.ranges[3, 0]))
        else:
            base = robot_params(robot, **overrides)
        if terrain == "slope" and real_number(slope_deg) and 0.0 < slope_deg <= MAX_SLOPE_DEG:
            # The walk's own check of a level body on this slope (it was an IKError from the start pose's IK).
            try:
                dataclasses.replace(base, slope_deg=float(slope_deg))
            except ValueError as e:
                reason = str(e).removesuffix(" (or set level_body=off)")
                raise ValueError(f"slope_deg {slope_deg:g} is too steep for this controller: {reason}") from None
        if twist_range is None:  # the default: TWIST_RANGE, or the largest part of it this robot's legs can deliver
            self.ranges[:3] *= _feasible_scale(base, self.ranges)
        self.p_controller = _controller_params(base, self.ranges)
        super().__init__(
            self.p_controller, frame_skip, terrain, slope_deg, roughness, stairs, command_range, reward,
            randomize_friction, randomize_mass, randomize_servo_gain, render_mode, width, height, camera,
        )  # fmt: skip
        self.robot = robot
        self.action_space = spaces.Box(-1.0, 1.0, (4,), np.float32)
        self._ranges = [tuple(r) for r in self.ranges.tolist()]
        # Settle on the home stance up to the gait clock's start, in whole control periods.
        self._settle_steps = math.ceil(round(SETTLE_TIME / self.p_controller.timestep) / self.frame_skip) * frame_skip
        self.controller: WalkingController | None = None

    def __getstate__(self) -> dict:
        if self.controller is not None:  # its arrays are views of this MjData: a copy would drive the original's
            raise TypeError(
                f"{type(self).__name__} cannot be copied or pickled after reset() (its gait controller runs on the "
                "live physics); copy it before the first reset(), or make a new one"
            )
        return super().__getstate__()

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        self._start(seed, options)
        m, d = self.model, self.data
        mujoco.mj_forward(m, d)
        p = self.p_controller
        self.source = ActionSource(p.gait, p.step_height, p.stand_height, self.frame_skip * p.timestep)
        self.controller = controller = make_controller(p, m, d, self.source)
        controller.planner.max_chunk = self.frame_skip  # one plan per action, from the gait clock's start on
        for _ in range(self._settle_steps):
            controller(m, d)
            mujoco.mj_step(m, d)
        self._warnings = self._warned()
        if self.render_mode == "human":
            self.render()
        return self._observe(), {"command": self.command.copy()}

    def step(self, action) -> tuple[np.ndarray, float, bool, bool, dict]:
        if self.controller is None:
            raise RuntimeError("call reset() before step()")
        a = self._check_action(action, 4).tolist()
        # Clipped to [-1, 1], mapped onto the ranges (in floats: four numbers cost less than numpy's calls).
        ranges = zip(a, self._ranges, strict=True)
        vx, vy, w, h = (lo + 0.5 * (min(max(x, -1.0), 1.0) + 1.0) * (hi - lo) for x, (lo, hi) in ranges)
        controller, m, d, physics = self.controller, self.model, self.data, mujoco.mj_step
        self.source.act(d.time, Command(vx, vy, w), h)
        for _ in range(self.frame_skip):
            controller(m, d)
            physics(m, d)
        obs = self._observe()
        reward, terminated, info = self._reward(obs)
        info["twist"] = (vx, vy, w)
        info["step_height"] = h
        if self.render_mode == "human":
            self.render()
        return obs, reward, terminated, False, info
