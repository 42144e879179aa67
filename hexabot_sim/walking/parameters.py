"""A walk's parameters and what the robot can walk: ranges, gait feasibility, terrain refusals (any legged robot)."""

from __future__ import annotations

import dataclasses
import math
from typing import Any, ClassVar

import numpy as np

from hexabot_sim.control.gait import GAITS, Command, Gait, GaitPlanner, gaits_for
from hexabot_sim.kinematics import leg as leg_kin
from hexabot_sim.kinematics import legged
from hexabot_sim.params import allowed, apart, check_run_cost, param
from hexabot_sim.simulate import step_count
from hexabot_sim.terrain import Ground, Kerb, Limits, RoughPatch, Slope, Stairs
from hexabot_sim.terrain.heightfield import CELL as HFIELD_CELL
from hexabot_sim.terrain.heightfield import MARGIN as HFIELD_MARGIN
from hexabot_sim.terrain.heightfield import MAX_POINTS as HFIELD_MAX_POINTS
from hexabot_sim.terrain.kerb import KERB_LENGTH, KERB_WIDTH
from hexabot_sim.walking import commands

INTEGRATORS = ("implicitfast", "RK4", "Euler", "implicit")


STAND_HEIGHT_MIN: float = 0.02  # [m] the lowest stand_height a walk takes

SETTLE_TIME: float = 0.5  # [s] standing on the neutral stance before the gait clock starts

SPEED_MARGIN: float = 0.9  # planned joint speeds must stay below this fraction of max_joint_speed

LOADED_FRACTION: float = 0.05  # a foot counts as loaded above this fraction of the robot's weight


CSV_FIXED_COLUMNS: int = 13  # columns of timeseries.csv besides the legs' (6 each: contact, 2 forces, 3 joints)

# Cost of a run for params.check_run_cost, measured on the 2-core development machine (10 s vs 60 s
# walks): seconds per physics step (controller + mj_step: 25 us in bench.py, with a margin for a loaded
# machine), seconds per recorded row (contact replay, derived columns; the CSV is counted apart), peak
# bytes per recorded row.
RUN_COST: tuple[float, float, float] = (30e-6, 40e-6, 2000.0)

# Seconds per physics step with terrain or the ground-finding controller (rough ground: 42-44 us in bench.py).
TERRAIN_STEP_SECONDS: float = 50e-6

KERB_PLATE_CLEARANCE: float = 0.005  # [m] a kerb stays this far below the plate's underside at the stand height

MEASURE_TIME: float = 0.1  # [s] shortest walk after the ramp that the metrics are measured over

FALL_TILT_DEG: float = 45.0  # body tilt beyond which the robot has fallen over

# NoSlip iterations on uneven ground. MuJoCo's soft friction lets a foot under a steady tangential
# load creep: the standing robot slid down a 10 deg slope at 0.9-1.8 mm/s with the defaults. Two
# NoSlip passes (MuJoCo's remedy for slow slippage, run after the main solve) bring that to 0.005 mm/s
# and 0.001-0.004 mm/s on 1 cm rough ground; impratio=100 did it too (0.009 mm/s) but its elliptic
# cones took 6.7 Newton iterations and 73 line searches a step: bare mj_step 69 us on rough ground
# against 31.5 us with NoSlip (median of 15 walks, 3 gaits x 5 seeds). The flat floor keeps the
# defaults (its published results were measured with them; there is no steady tangential load there).
TERRAIN_NOSLIP_ITERATIONS: int = 2

SCENE_EXTENT: float = 2.0  # [m] <statistic extent> of a scene with terrain (what MuJoCo computes for the flat one)

SLOPE_CAMERA_DISTANCE: float = 0.9  # [m] the slope video's camera: beside the body, across the slope

SLOPE_CAMERA_HEIGHT: float = 0.08  # [m] above the body's centre of mass (low: the ground's tilt shows)

# Limit on the commanded joint acceleration (resolved-rate step). It smooths what the position feedback
# asks when a foot is stopped short (a kerb's edge, a bump): with 400 rad/s^2 the 3 cm kerb walk stumbled
# (16 deg of roll), with 200 it climbs. But it must never clip the gait's own plan: the wave gait's 1/6-period
# swing needs 266 rad/s^2 at 0.05 m/s and 364 at 0.095 m/s (period 1 s). Clipped at 200, the wave at
# 0.095 m/s lost 5.0 % of its speed on flat ground (-0.6 % unclipped), and 6.8..8.5 % with up to 2.8 deg of
# pitch on 1 cm rough ground (-2.0..-3.6 %, <= 1.2 deg unclipped; measured). A servo's 1.5 N*m gives a swinging leg
# 336, 414 and 479 rad/s^2 (coxa, femur, tibia: torque over the mass-matrix diagonal, armature included).
ACCELERATION_LIMIT: float = 200.0  # [rad/s^2] the limit, unless the planned cycle needs more

REFLEX_LIFT: float = 1.0  # the elevator reflex lifts a blocked swing foot this many step heights higher

ACCELERATION_HEADROOM: float = 1.2  # the limit is at least this times the planned cycle's peak joint acceleration


@dataclasses.dataclass(frozen=True)
class WalkingRobot:
    """What the walking scenarios need to know of a robot besides its parameters.

    Attributes:
        name: The robot's name, e.g. "hexabot".
        layout: Its legs and body (kinematics.legged.Layout).
        scene: The model file (models/<scene>.xml) of the robot on a floor, with cameras and a "home" keyframe.
        torque_limit: The joints' actuatorfrcrange [N m].
        replace: Files the scene includes, replaced by MJCF text (a robot file's model, generated at run time).
    """

    name: str
    layout: legged.Layout
    scene: str
    torque_limit: float
    replace: tuple[tuple[str, str], ...] = ()


@dataclasses.dataclass(frozen=True)
class WalkParams:
    """Parameters of a walk (body frame: x forward, y left, z up). Each robot's subclass sets ROBOT, and the
    gait's choices and default (its gaits are the ones for its number of legs, control.gait.gaits_for)."""

    ROBOT: ClassVar[WalkingRobot]

    gait: str = param("tripod", "", "which legs swing when", choices=tuple(GAITS))
    vx: float = param(0.1, "m/s", "commanded forward speed", ge=-1.0, le=1.0, typo=("mm/s", 1e-3))
    vy: float = param(0.0, "m/s", "commanded sideways speed (left positive)", ge=-1.0, le=1.0, typo=("mm/s", 1e-3))
    yaw_rate: float = param(0.0, "rad/s", "commanded turning rate (counter-clockwise positive)", ge=-3.0, le=3.0)
    period: float = param(1.0, "s", "gait cycle: every leg swings once per period", ge=0.2, le=10.0)
    duty: float = param(0.0, "1", "stance fraction of the cycle; 0 = the gait's own (1/2, 2/3, 5/6)", ge=0.0, lt=1.0)
    step_height: float = param(0.03, "m", "foot lift at mid-swing", ge=0.002, le=0.1, typo=("mm", 1e-3))
    stand_height: float = param(
        0.0, "m", "foot depth below the hips while standing (body height - foot radius); 0 = the robot's own "
        "(the hexabot's 0.09, a robot file's [stance] height)", ge=0.0, le=0.19, typo=("mm", 1e-3),
    )  # fmt: skip
    friction: float = param(1.0, "1", "foot-floor friction coefficient", ge=0.05, le=3.0)
    heading_hold: str = param("off", "", "correct the yaw rate from the IMU's heading", choices=("off", "on"))
    trim_error_deg: float = param(0.0, "deg", "servo zero errors, uniform in +-this (seeded)", ge=0.0, le=10.0)
    com_offset: float = param(
        0.0, "m", "centre-of-mass offset of the body, in a seeded direction", ge=0.0, le=0.05, typo=("mm", 1e-3)
    )
    friction_spread: float = param(0.0, "1", "foot friction varies by +-this fraction (seeded)", ge=0.0, le=0.9)
    seed: int = param(0, "1", "random seed of the perturbations and of the rough terrain", ge=0, le=2**32 - 1)
    max_joint_speed: float = param(
        10.0, "rad/s", "joint speed limit (a standard digital hobby servo: 0.1 s/60 deg)", gt=0.0, le=50.0
    )
    task_gain: float = param(50.0, "1/s", "K: feedback on each foot's position error", ge=0.0, le=200.0)
    duration: float = param(20.0, "s", "simulated time", gt=0.0, le=3600.0)
    timestep: float = param(
        0.002, "s", "physics and control step (the feet's contact time constant is 6 ms)", ge=1e-4, le=0.002
    )
    integrator: str = param("implicitfast", "", "MuJoCo integrator", choices=INTEGRATORS)
    slope_deg: float = param(0.0, "deg", "floor tilt (0: flat)", ge=0.0, le=45.0)
    slope_heading: str = param(
        "uphill", "", "the walking direction relative to the slope", choices=("uphill", "downhill", "across")
    )
    roughness: float = param(
        0.0, "m", "peak height of a seeded heightfield of ~5 cm bumps (0: none)", ge=0.0, le=0.05, typo=("mm", 1e-3)
    )
    kerb_height: float = param(
        0.0, "m", "a step up across the path (0: none)", ge=0.0, le=0.1, typo=("mm", 1e-3)
    )  # fmt: skip
    kerb_distance: float = param(0.5, "m", "distance of the kerb's edge ahead of the start", ge=0.3, le=100.0)
    stairs_rise: float = param(
        0.0, "m", "stairs across the path: the rise of each step (0: none)", ge=0.0, le=0.1, typo=("mm", 1e-3)
    )
    stairs_run: float = param(0.25, "m", "depth of each stair step along the path", ge=0.05, le=2.0)
    stairs_count: int = param(3, "1", "steps up before the landing", ge=1, le=50)
    stairs_distance: float = param(0.5, "m", "distance of the first step's edge ahead of the start", ge=0.3, le=100.0)
    touchdown: str = param(
        "planned", "", "swing ends at the planned phase, or when the foot's touch sensor fires (sensed)",
        choices=("planned", "sensed"),
    )  # fmt: skip
    level_body: str = param("off", "", "keep the body level from the IMU (on) or follow the ground (off)",
                            choices=("off", "on"))  # fmt: skip
    reflex: str = param(
        "on", "", "with sensed touchdown, a swing foot that meets an obstacle early lifts higher and reaches again "
        "(elevator reflex)", choices=("on", "off"),
    )  # fmt: skip
    load_sharing: str = param(
        "off", "", "stance legs yield to their touch sensors' force error, sharing the load (admittance), or hold "
        "their planned height (off)", choices=("admittance", "off"),
    )  # fmt: skip
    schedule: tuple = param((), "", commands.SCHEDULE_DOC, table=(commands.SCHEDULE_ALLOWED, commands.read_schedule))
    waypoints: tuple = param(
        (), "", commands.WAYPOINTS_DOC, table=(commands.WAYPOINTS_ALLOWED, commands.read_waypoints)
    )
    schedule_scale: float = param(1.0, "1", "the schedule's vx, vy and yaw_rate times this", ge=0.0, le=10.0)
    path_speed: float = param(0.1, "m/s", "the path follower's walking speed (waypoints)", gt=0.0, le=1.0)
    path_yaw_rate: float = param(0.5, "rad/s", "the path follower's largest yaw rate (waypoints)", gt=0.0, le=3.0)

    def __post_init__(self) -> None:
        if not self.stand_height:  # the robot's own (resolved here: everything downstream reads the number)
            object.__setattr__(self, "stand_height", self.ROBOT.layout.stand_height)
        if self.stand_height < STAND_HEIGHT_MIN:
            raise ValueError(
                f"parameter 'stand_height' must be 0 (the robot's own) or {STAND_HEIGHT_MIN:g} to 0.19 m; got "
                f"{self.stand_height:g}"
            )
        if self.duty and not self.gait_duty_range()[0] <= self.duty < 1.0:
            lo = self.gait_duty_range()[0]
            raise ValueError(
                f"parameter 'duty' for the {self.gait} gait must be {allowed(lo, 'up')} to < 1 (or 0); got {self.duty}"
            )
        shortest = SETTLE_TIME + self.period + MEASURE_TIME
        if self.duration < shortest - 1e-9:
            raise ValueError(
                f"parameter 'duration' must be at least the settling time, one period (the ramp) and "
                f"{MEASURE_TIME:g} s to measure the walk: {shortest:.15g} s; got {self.duration}"
            )
        n = step_count(self.duration, self.timestep)
        step_s, row_s, row_bytes = RUN_COST
        if self.on_ground() or self.slope_deg or self.roughness or self.kerb_height or self.stairs_rise:
            step_s = TERRAIN_STEP_SECONDS
        check_run_cost(
            n, n + 1, csv_columns(self.ROBOT), step_s, row_s, row_bytes, "lower 'duration' or raise 'timestep'"
        )
        problem = feasibility(self)
        if problem:
            raise ValueError(problem)
        problem = commands.problem(self, feasibility, neutral(self), SETTLE_TIME)  # a schedule's or waypoints'
        if problem:
            raise ValueError(problem)
        problem = terrain_problem(self)
        if problem:
            raise ValueError(problem)

    def gait_duty_range(self) -> tuple[float, float]:
        """Smallest duty that keeps the robot statically supported with this gait's phase pattern."""
        base = self.gaits()[self.gait].duty
        return base, 1.0

    def the_gait(self) -> Gait:
        g = self.gaits()[self.gait]
        return g if not self.duty else dataclasses.replace(g, duty=self.duty)

    def gaits(self) -> dict[str, Gait]:
        """The gaits of a robot with this many legs, by name."""
        return gaits_for(self.ROBOT.layout.n_legs)

    def command(self) -> Command:
        return Command(self.vx, self.vy, self.yaw_rate)

    def on_ground(self) -> bool:
        """The run uses the ground-finding controller (sensed touchdown or a levelled body)."""
        return self.touchdown == "sensed" or self.level_body == "on"


def neutral(p: WalkParams) -> np.ndarray:
    """Neutral foot centres (6, 3) in the body frame for the run's stand height."""
    layout = dataclasses.replace(p.ROBOT.layout, stand_height=p.stand_height)
    return layout.neutral_feet_body()


def _plan_cycle(p: WalkParams, cmd: Command, samples: int = 240) -> tuple[np.ndarray, float]:
    """Targets (n, 6, 3) in the hip frames over two steady gait cycles, and their time step."""
    dt = p.period / samples
    planner = GaitPlanner(p.the_gait(), p.period, p.step_height, neutral(p), dt)
    chunks = [planner.plan(cmd, planner.max_chunk)]
    while planner.time < 3 * p.period - 1e-9:
        chunks.append(planner.plan(cmd, planner.max_chunk)[1:])
    body = np.concatenate(chunks)[int(samples * 1.0) :]  # drop the first cycle (start-up from neutral)
    layout = p.ROBOT.layout
    hip = np.einsum("lji,klj->kli", layout.hip_rotations(), body - layout.hip_positions())
    return hip, dt


# _cycle_problem's answers by what the cycle depends on: a sweep checks each gait for each of its other values.
_CYCLE_PROBLEMS: dict[tuple[Any, ...], str] = {}

CYCLE_CACHE_SIZE: int = 1 << 14


def _cycle_problem(p: WalkParams, cmd: Command) -> str:
    """'' if every leg can follow the planned cycle, else why not (reach, joint range or joint speed)."""
    key = (p.ROBOT, p.gait, p.duty, p.period, p.step_height, p.stand_height, p.max_joint_speed, cmd)
    problem = _CYCLE_PROBLEMS.get(key)
    if problem is None:
        if len(_CYCLE_PROBLEMS) >= CYCLE_CACHE_SIZE:
            _CYCLE_PROBLEMS.clear()
        problem = _CYCLE_PROBLEMS[key] = _cycle_problem_computed(p, cmd)
    return problem


def _cycle_problem_computed(p: WalkParams, cmd: Command) -> str:
    hip, dt = _plan_cycle(p, cmd)
    q, ok = legged.ik_hip_batch(p.ROBOT.layout, hip)
    if not ok.all():
        leg = p.ROBOT.layout.legs[int(np.argwhere(~ok)[0][1])]
        return f"foot {leg} would leave its reachable workspace or joint ranges"
    speed = np.abs(np.diff(q, axis=0)).max() / dt
    if speed > SPEED_MARGIN * p.max_joint_speed:
        return f"joints would turn at {speed:.3g} rad/s, above {SPEED_MARGIN:g} x max_joint_speed"
    return ""


def feasibility(p: WalkParams) -> str:
    """'' if the legs can deliver the command, else a one-line reason with the largest feasible command."""
    if not math.isfinite(p.vx + p.vy + p.yaw_rate):
        return "vx, vy and yaw_rate must be finite"
    standing = _cycle_problem(p, Command())
    if standing:
        faster = " (or raise 'max_joint_speed')" if standing.startswith("joints would turn") else ""
        return (
            f"even stepping in place is infeasible with the {p.gait} gait at period {p.period:g} s "
            f"(stand_height {p.stand_height:g} m, step_height {p.step_height:g} m): {standing}; "
            f"lengthen 'period' or lower 'step_height'{faster}"
        )
    cmd = p.command()
    problem = _cycle_problem(p, cmd)
    if not problem:
        return ""
    lo, hi = 0.0, 1.0  # bisect the largest feasible fraction of the command
    for _ in range(30):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if not _cycle_problem(p, cmd.scaled(mid)) else (lo, mid)
    best = cmd.scaled(lo)
    named = (("vx", best.vx, "m/s"), ("vy", best.vy, "m/s"), ("yaw_rate", best.yaw_rate, "rad/s"))
    parts = [f"{name} = {allowed(value, 'zero')} {unit}" for name, value, unit in named if value]
    duty = p.the_gait().duty
    stride = math.hypot(p.vx, p.vy) * duty * p.period
    if problem.startswith("joints would turn"):
        # The swing covers the stance's stride in (1 - duty) / duty of its time, whatever the period.
        advice = (
            f"the {p.gait} gait's swing moves the foot over the ground {duty / (1 - duty):.2g}x as fast as the body at "
            "any period (a longer one only slows the lift): a gait with less stance is faster"
            + (" (ripple, tripod)" if p.gait == "wave" else " (tripod)" if p.gait == "ripple" else "")
        )
    else:
        advice = "a shorter 'period' shortens the stride"
    return (
        f"the legs cannot deliver this command at period {p.period:g} s (stride {stride:.3g} m): {problem}; "
        f"the largest feasible in this direction is {', '.join(parts) or 'standing still'}; {advice}"
    )


def walking_direction(p: WalkParams) -> np.ndarray:
    """Horizontal unit vector (2,) of the commanded walk in the world at the start (+x when standing or turning)."""
    speed = math.hypot(p.vx, p.vy)
    return np.array([p.vx, p.vy]) / speed if speed > 0 else np.array([1.0, 0.0])


def terrain(p: WalkParams) -> Ground:
    """The run's ground: slope direction from the walking direction, heightfield over the walk's area."""
    along = walking_direction(p)
    uphill = {"uphill": along, "downhill": -along, "across": np.array([-along[1], along[0]])}[p.slope_heading]
    speed = math.hypot(p.vx, p.vy)
    if p.schedule or p.waypoints:  # a box holding the course (the schedule's planned path)
        extent = commands.extent(p, SETTLE_TIME, HFIELD_MARGIN)
    elif p.yaw_rate:  # an arc (or turning on the spot): a box about the start holding the circle
        half = min(speed * p.duration, 2 * speed / abs(p.yaw_rate)) + HFIELD_MARGIN
        extent = (-half, half, -half, half)
    else:
        end = np.array([p.vx, p.vy]) * p.duration
        extent = (
            min(0.0, end[0]) - HFIELD_MARGIN, max(0.0, end[0]) + HFIELD_MARGIN,
            min(0.0, end[1]) - HFIELD_MARGIN, max(0.0, end[1]) + HFIELD_MARGIN,
        )  # fmt: skip
    if p.slope_deg:  # the patch lies in the ground frame: a world distance d is d / cos(slope) along the slope
        extent = tuple(v / math.cos(math.radians(p.slope_deg)) for v in extent)
    extent = tuple(round(v / HFIELD_CELL) * HFIELD_CELL for v in extent)
    along_xy = (float(along[0]), float(along[1]))
    # The kerb's pavement runs on beyond the walk: 20 m, or as far as this walk could go (a 0.2 m/s walk of 200 s
    # stepped down off its end at 20.5 m, where the terrain's heights still had the kerb).
    reach = speed * p.duration / math.cos(math.radians(p.slope_deg)) + HFIELD_MARGIN
    kerb_length, kerb_width = max(KERB_LENGTH, reach - p.kerb_distance), max(KERB_WIDTH, 2 * reach)
    obstacles: tuple[Kerb | Stairs, ...] = ()
    if p.kerb_height:
        obstacles += (Kerb(p.kerb_height, p.kerb_distance, along_xy, kerb_length, kerb_width),)
    if p.stairs_rise:
        landing = max(KERB_LENGTH, reach - p.stairs_distance - (p.stairs_count - 1) * p.stairs_run)
        obstacles += (
            Stairs(p.stairs_rise, p.stairs_run, p.stairs_count, p.stairs_distance, along_xy, landing, kerb_width),
        )
    return Ground(
        slope=Slope(p.slope_deg, (float(uphill[0]), float(uphill[1])), p.slope_heading),
        rough=RoughPatch(p.roughness, p.seed, extent) if p.roughness else None,
        obstacles=obstacles,
    )


def depth_range(p: WalkParams) -> tuple[float, float]:
    """(smallest, largest) depth [m] of the stance feet below the hips that keeps every planned target reachable.

    The steady cycle of the command (stance and swing, with the lift) is shifted up and down as a whole:
    the stance depth may move by as much as every target of the cycle stays inside the reach and the
    joint ranges (bisection to 0.1 mm).
    """
    hip, _ = _plan_cycle(p, p.command())

    def ok(shift: float) -> bool:
        shifted = hip.copy()
        shifted[..., 2] += shift
        return bool(legged.ik_hip_batch(p.ROBOT.layout, shifted)[1].all())

    limits = []
    for sign in (1.0, -1.0):
        lo, hi = 0.0, p.stand_height + 0.2
        while hi - lo > 1e-4:
            mid = (lo + hi) / 2
            lo, hi = (mid, hi) if ok(sign * mid) else (lo, mid)
        limits.append(lo)
    return p.stand_height - limits[0], p.stand_height + limits[1]


def largest_climbable_kerb(p: WalkParams) -> float:
    """Highest kerb [m] the walk can climb: a swing clears it and the legs can hold the cycle raised by it.

    Clearing: the foot lifts step_height above the ground it left (with sensed touchdown and the elevator
    reflex, a blocked foot lifts REFLEX_LIFT step heights more), and its centre must pass the kerb's
    edge at least a foot radius above it (measured: a 30 mm kerb with step_height 0.03 m made the
    robot stumble, 15 deg of roll; with 0.04 m it walked up cleanly). Holding: the whole planned cycle
    raised by the kerb height stays inside the reach and the joint ranges (depth_range).
    """
    lift = p.step_height * (1.0 + REFLEX_LIFT) if reflex_on(p) else p.step_height
    return min(lift - p.ROBOT.layout.foot_radius, p.stand_height - depth_range(p)[0])


def reflex_on(p: WalkParams) -> bool:
    """The walk's swing feet have the elevator reflex (it needs the touch sensors: sensed touchdown)."""
    return p.touchdown == "sensed" and p.reflex == "on"


def _climb_hint(p: WalkParams) -> str:
    """What raises the largest climbable kerb: the lift while the swing limits it, else the legs' reach above the
    stance (a deeper stance: it said "raise 'step_height'" where that could not help)."""
    swing = p.step_height * (1.0 + REFLEX_LIFT if reflex_on(p) else 1.0) - p.ROBOT.layout.foot_radius
    return "raise 'step_height'" if swing <= p.stand_height - depth_range(p)[0] else "raise 'stand_height'"


def terrain_problem(p: WalkParams) -> str:
    """'' if the ground can be walked as asked, else a one-line reason (the terrain types' own refusals, with
    what this robot can take, and a level body's reach on a slope)."""
    ground = terrain(p)
    layout = p.ROBOT.layout
    underside = p.stand_height + layout.foot_radius - layout.plate[2]  # the plate's underside above the ground
    limits = Limits(
        friction=p.friction,
        climbable=largest_climbable_kerb(p) if ground.obstacles else math.inf,
        climbable_why=(
            f"the foot lifts step_height = {p.step_height:g} m"
            + (f" and its reflex {REFLEX_LIFT:g} x more" if reflex_on(p) else "")
            + ", less a foot radius of clearance; the legs reach "
            f"{(p.stand_height - depth_range(p)[0]) * 1000:.0f} mm above the stance"
        ) if ground.obstacles else "",
        climbable_hint=_climb_hint(p) + (" or lower 'roughness'" if p.roughness else "") if ground.obstacles else "",
        underside=underside,
        underside_why=f"at stand_height {p.stand_height:g} m",
        underside_hint="raise 'stand_height'",
        clearance=KERB_PLATE_CLEARANCE,
        max_points=HFIELD_MAX_POINTS,
    )  # fmt: skip
    problem = ground.problem(limits)
    if problem:
        return problem
    if not (p.slope_deg and p.level_body == "on"):
        return start_problem(p, ground)
    # A level body on a slope: the stance feet reach down or up by x tan(slope) (x along the uphill).
    tan = math.tan(math.radians(p.slope_deg))
    reach = float(np.abs(neutral(p)[:, :2] @ ground.slope.uphill).max()) * tan
    lo, hi = depth_range(p)
    if p.stand_height - reach < lo or p.stand_height + reach > hi:
        steepest = math.degrees(math.atan(min(p.stand_height - lo, hi - p.stand_height) / (reach / tan)))
        slope, steepest_text = apart(p.slope_deg, steepest, "down")
        return (
            f"a level body on a {slope} deg slope needs the feet {reach * 1000:.0f} "
            f"mm above and below the neutral stance, beyond the legs' workspace (stance depth {lo:.3f} to "
            f"{hi:.3f} m with this gait); the steepest levelled slope is {steepest_text} deg "
            "(or set level_body=off)"
        )
    return start_problem(p, ground)


def start_pose(p: WalkParams, ground: Ground) -> tuple[list[float], np.ndarray]:
    """The body's start pose (7,: position, quaternion w x y z) and joint angles (n_legs, 3) on a ground not flat.

    With the ground-finding controller the body starts level, its feet on the ground under their
    neutral points (IK). With the planned controller it starts parallel to a slope, or level on its
    neutral stance above the highest ground under a foot (it settles onto the feet that touch).
    """
    layout = p.ROBOT.layout
    feet = neutral(p)
    q0, _ = legged.ik_hip_batch(layout, legged.body_to_hip(layout, feet))
    r = layout.foot_radius
    normal = ground.normal()
    if p.on_ground() and not (ground.slope.tilted and p.level_body == "off"):
        # Level body; every foot centre r (along the normal) above the ground under its neutral point.
        g = ground.height(feet[:, 0], feet[:, 1]) + r / normal[2]  # (n_legs,)
        z0 = p.stand_height + float(g.mean())
        target = feet.copy()
        target[:, 2] = g - z0
        q = legged.ik_body(layout, target)
        return [0.0, 0.0, z0, 1.0, 0.0, 0.0, 0.0], q
    if ground.slope.tilted:  # parallel to the slope, above whatever stands on it under the feet
        lift = max(0.0, float(ground.surface(feet[:, 0], feet[:, 1]).max()))
        pos = normal * (p.stand_height + r + lift)
        return [*pos, *ground.slope.floor_quat()], q0
    z0 = p.stand_height + r + float(ground.height(feet[:, 0], feet[:, 1]).max())
    return [0.0, 0.0, z0, 1.0, 0.0, 0.0, 0.0], q0


PLATE_SAMPLES: int = 41  # points along each side of the plate's underside checked against the ground at the start


def start_problem(p: WalkParams, ground: Ground) -> str:
    """'' if the plate starts above the ground, else why not (one line): a bump of rough ground, or the uphill
    side of a slope under a levelled body, may rise above the plate's underside where the body starts."""
    if ground.flat:
        return ""
    layout = p.ROBOT.layout
    try:
        pose, _ = start_pose(p, ground)
    except leg_kin.IKError as e:  # a level start: a foot cannot reach the ground under its neutral point
        hints = ["lower 'roughness'", "try another 'seed'"] if ground.rough is not None else []
        hints += ["lower 'slope_deg'"] if ground.slope.tilted else []
        hints = ["change 'stand_height'", *hints, "set touchdown=planned and level_body=off"]
        return f"the legs cannot stand level on this ground at the start ({e}); {', '.join(hints[:-1])} or {hints[-1]}"
    w, x, y, z = pose[3:]
    rotation = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])  # fmt: skip
    px, py, pz = layout.plate
    u, v = np.meshgrid(np.linspace(-px, px, PLATE_SAMPLES), np.linspace(-py, py, PLATE_SAMPLES))
    corners = np.stack([u.ravel(), v.ravel(), np.full(u.size, -pz)], axis=1) @ rotation.T + np.array(pose[:3])
    gap = float((corners[:, 2] - ground.height(corners[:, 0], corners[:, 1])).min())
    if gap >= 0:
        return ""
    causes = [f"the rough ground ({ground.rough.label()}) rises"] if ground.rough is not None else []
    causes += ["the slope rises under the level body"] if ground.slope.tilted and p.level_body == "on" else []
    hints = ["raise 'stand_height'"] + (["lower 'roughness'", "try another 'seed'"] if ground.rough else [])
    hints += ["set level_body=off"] if ground.slope.tilted and p.level_body == "on" else []
    hints = [", ".join(hints[:-1]), hints[-1]] if len(hints) > 1 else hints
    return (
        f"the body would start in the ground: {' and '.join(causes) or 'the ground rises'} {-gap * 1000:.3g} mm "
        f"above the plate's underside (stand_height {p.stand_height:g} m); {' or '.join(hints)}"
    )


def csv_columns(robot: WalkingRobot) -> int:
    """Columns of a walk's timeseries.csv (the run-cost estimate counts them)."""
    return CSV_FIXED_COLUMNS + 6 * robot.layout.n_legs
