"""The walking hexabot (report 000): six DH legs on a free body, tripod/ripple/wave gaits on contact physics."""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Any

import mujoco
import numpy as np

from hexabot_sim import models
from hexabot_sim.control.gait import GAITS, Command, Gait, GaitPlanner
from hexabot_sim.control.hexabot import GroundController, GroundSettings, HexabotController, WalkSettings
from hexabot_sim.control.resolved_rate import ResolvedRateGains
from hexabot_sim.kinematics import hexabot as hx
from hexabot_sim.kinematics.hexabot_terrain import HFIELD_CELL, HFIELD_MARGIN, HFIELD_MAX_POINTS, Terrain
from hexabot_sim.params import allowed, apart, check_run_cost, param
from hexabot_sim.scenarios.base import Live, Metric, Progress, ScenarioResult, at_home
from hexabot_sim.simulate import simulate, step_count

INTEGRATORS = ("implicitfast", "RK4", "Euler", "implicit")
LAYOUT = hx.DEFAULT_LAYOUT
SETTLE_TIME: float = 0.5  # [s] standing on the neutral stance before the gait clock starts
SPEED_MARGIN: float = 0.9  # planned joint speeds must stay below this fraction of max_joint_speed
LOADED_FRACTION: float = 0.05  # a foot counts as loaded above this fraction of the robot's weight
TORQUE_LIMIT: float = 1.5  # [N m] the joints' actuatorfrcrange (models/hexabot.xml)
CSV_COLUMNS: int = 37  # columns of timeseries.csv
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
ACCELERATION_HEADROOM: float = 1.2  # the limit is at least this times the planned cycle's peak joint acceleration


@dataclasses.dataclass(frozen=True)
class HexabotParams:
    """Parameters of the walking-hexabot scenarios (body frame: x forward, y left, z up)."""

    gait: str = param("tripod", "", "which legs swing when", choices=tuple(GAITS))
    vx: float = param(0.1, "m/s", "commanded forward speed", ge=-1.0, le=1.0, typo=("mm/s", 1e-3))
    vy: float = param(0.0, "m/s", "commanded sideways speed (left positive)", ge=-1.0, le=1.0, typo=("mm/s", 1e-3))
    yaw_rate: float = param(0.0, "rad/s", "commanded turning rate (counter-clockwise positive)", ge=-3.0, le=3.0)
    period: float = param(1.0, "s", "gait cycle: every leg swings once per period", ge=0.2, le=10.0)
    duty: float = param(0.0, "1", "stance fraction of the cycle; 0 = the gait's own (1/2, 2/3, 5/6)", ge=0.0, lt=1.0)
    step_height: float = param(0.03, "m", "foot lift at mid-swing", ge=0.002, le=0.1, typo=("mm", 1e-3))
    stand_height: float = param(
        0.09, "m", "foot depth below the hips while standing (body height - foot radius)", ge=0.02, le=0.19,
        typo=("mm", 1e-3),
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
    touchdown: str = param(
        "planned", "", "swing ends at the planned phase, or when the foot's touch sensor fires (sensed)",
        choices=("planned", "sensed"),
    )  # fmt: skip
    level_body: str = param("off", "", "keep the body level from the IMU (on) or follow the ground (off)",
                            choices=("off", "on"))  # fmt: skip

    def __post_init__(self) -> None:
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
        if self.on_ground() or self.slope_deg or self.roughness or self.kerb_height:
            step_s = TERRAIN_STEP_SECONDS
        check_run_cost(n, n + 1, CSV_COLUMNS, step_s, row_s, row_bytes, "lower 'duration' or raise 'timestep'")
        problem = feasibility(self)
        if problem:
            raise ValueError(problem)
        problem = terrain_problem(self)
        if problem:
            raise ValueError(problem)

    def gait_duty_range(self) -> tuple[float, float]:
        """Smallest duty that keeps the robot statically supported with this gait's phase pattern."""
        base = GAITS[self.gait].duty
        return base, 1.0

    def the_gait(self) -> Gait:
        g = GAITS[self.gait]
        return g if not self.duty else dataclasses.replace(g, duty=self.duty)

    def command(self) -> Command:
        return Command(self.vx, self.vy, self.yaw_rate)

    def on_ground(self) -> bool:
        """The run uses the ground-finding controller (sensed touchdown or a levelled body)."""
        return self.touchdown == "sensed" or self.level_body == "on"


def neutral(p: HexabotParams) -> np.ndarray:
    """Neutral foot centres (6, 3) in the body frame for the run's stand height."""
    layout = dataclasses.replace(LAYOUT, stand_height=p.stand_height)
    return layout.neutral_feet_body()


def _plan_cycle(p: HexabotParams, cmd: Command, samples: int = 240) -> tuple[np.ndarray, float]:
    """Targets (n, 6, 3) in the hip frames over two steady gait cycles, and their time step."""
    dt = p.period / samples
    planner = GaitPlanner(p.the_gait(), p.period, p.step_height, neutral(p), dt)
    chunks = [planner.plan(cmd, planner.max_chunk)]
    while planner.time < 3 * p.period - 1e-9:
        chunks.append(planner.plan(cmd, planner.max_chunk)[1:])
    body = np.concatenate(chunks)[int(samples * 1.0) :]  # drop the first cycle (start-up from neutral)
    hip = np.einsum("lji,klj->kli", LAYOUT.hip_rotations(), body - LAYOUT.hip_positions())
    return hip, dt


# _cycle_problem's answers by what the cycle depends on: a sweep checks each gait for each of its other values.
_CYCLE_PROBLEMS: dict[tuple[Any, ...], str] = {}
CYCLE_CACHE_SIZE: int = 1 << 14


def _cycle_problem(p: HexabotParams, cmd: Command) -> str:
    """'' if every leg can follow the planned cycle, else why not (reach, joint range or joint speed)."""
    key = (p.gait, p.duty, p.period, p.step_height, p.stand_height, p.max_joint_speed, cmd)
    problem = _CYCLE_PROBLEMS.get(key)
    if problem is None:
        if len(_CYCLE_PROBLEMS) >= CYCLE_CACHE_SIZE:
            _CYCLE_PROBLEMS.clear()
        problem = _CYCLE_PROBLEMS[key] = _cycle_problem_computed(p, cmd)
    return problem


def _cycle_problem_computed(p: HexabotParams, cmd: Command) -> str:
    hip, dt = _plan_cycle(p, cmd)
    q, ok = hx.ik_hip_batch(LAYOUT, hip)
    if not ok.all():
        leg = hx.LEGS[int(np.argwhere(~ok)[0][1])]
        return f"foot {leg} would leave its reachable workspace or joint ranges"
    speed = np.abs(np.diff(q, axis=0)).max() / dt
    if speed > SPEED_MARGIN * p.max_joint_speed:
        return f"joints would turn at {speed:.3g} rad/s, above {SPEED_MARGIN:g} x max_joint_speed"
    return ""


def feasibility(p: HexabotParams) -> str:
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


def walking_direction(p: HexabotParams) -> np.ndarray:
    """Horizontal unit vector (2,) of the commanded walk in the world at the start (+x when standing or turning)."""
    speed = math.hypot(p.vx, p.vy)
    return np.array([p.vx, p.vy]) / speed if speed > 0 else np.array([1.0, 0.0])


def terrain(p: HexabotParams) -> Terrain:
    """The run's ground: slope direction from the walking direction, heightfield over the walk's area."""
    along = walking_direction(p)
    uphill = {"uphill": along, "downhill": -along, "across": np.array([-along[1], along[0]])}[p.slope_heading]
    speed = math.hypot(p.vx, p.vy)
    if p.yaw_rate:  # an arc (or turning on the spot): a box about the start holding the circle
        half = min(speed * p.duration, 2 * speed / abs(p.yaw_rate)) + HFIELD_MARGIN
        extent = (-half, half, -half, half)
    else:
        end = np.array([p.vx, p.vy]) * p.duration
        extent = (
            min(0.0, end[0]) - HFIELD_MARGIN, max(0.0, end[0]) + HFIELD_MARGIN,
            min(0.0, end[1]) - HFIELD_MARGIN, max(0.0, end[1]) + HFIELD_MARGIN,
        )  # fmt: skip
    extent = tuple(round(v / HFIELD_CELL) * HFIELD_CELL for v in extent)
    return Terrain(
        slope_deg=p.slope_deg, uphill=(float(uphill[0]), float(uphill[1])), roughness=p.roughness, seed=p.seed,
        extent=extent, kerb_height=p.kerb_height, kerb_distance=p.kerb_distance,
        along=(float(along[0]), float(along[1])),
    )  # fmt: skip


def depth_range(p: HexabotParams) -> tuple[float, float]:
    """(smallest, largest) depth [m] of the stance feet below the hips that keeps every planned target reachable.

    The steady cycle of the command (stance and swing, with the lift) is shifted up and down as a whole:
    the stance depth may move by as much as every target of the cycle stays inside the reach and the
    joint ranges (bisection to 0.1 mm).
    """
    hip, _ = _plan_cycle(p, p.command())

    def ok(shift: float) -> bool:
        shifted = hip.copy()
        shifted[..., 2] += shift
        return bool(hx.ik_hip_batch(LAYOUT, shifted)[1].all())

    limits = []
    for sign in (1.0, -1.0):
        lo, hi = 0.0, p.stand_height + 0.2
        while hi - lo > 1e-4:
            mid = (lo + hi) / 2
            lo, hi = (mid, hi) if ok(sign * mid) else (lo, mid)
        limits.append(lo)
    return p.stand_height - limits[0], p.stand_height + limits[1]


def largest_climbable_kerb(p: HexabotParams) -> float:
    """Highest kerb [m] the walk can climb: a swing clears it and the legs can hold the cycle raised by it.

    Clearing: the foot lifts step_height above the ground it left, and its centre must pass the kerb's
    edge at least a foot radius above it (measured: a 30 mm kerb with step_height 0.03 m made the
    robot stumble, 15 deg of roll; with 0.04 m it walked up cleanly). Holding: the whole planned cycle
    raised by the kerb height stays inside the reach and the joint ranges (depth_range).
    """
    return min(p.step_height - LAYOUT.foot_radius, p.stand_height - depth_range(p)[0])


def terrain_problem(p: HexabotParams) -> str:
    """'' if the ground can be walked as asked, else a one-line reason."""
    features = [name for name in ("slope_deg", "roughness", "kerb_height") if getattr(p, name)]
    if len(features) > 1:
        return f"one terrain feature at a time: {', '.join(features)} are set; keep one, set the others to 0"
    if p.slope_deg:
        tan = math.tan(math.radians(p.slope_deg))
        if tan > p.friction:
            friction, least = apart(p.friction, tan, "up")
            slope, steepest = apart(p.slope_deg, math.degrees(math.atan(p.friction)), "down")
            return (
                f"a {slope} deg slope needs a friction coefficient of at least tan(slope) = "
                f"{least} to hold the feet; friction is {friction} (the steepest slope it holds is {steepest} deg)"
            )
        if p.level_body == "on":
            # A level body on a slope: the stance feet reach down or up by x tan(slope) (x along the uphill).
            reach = float(np.abs(neutral(p)[:, :2] @ terrain(p).uphill).max()) * tan
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
    if p.kerb_height:
        underside = p.stand_height + LAYOUT.foot_radius - LAYOUT.plate[2]  # the plate's underside above the ground
        if p.kerb_height > underside - KERB_PLATE_CLEARANCE:
            kerb_mm, highest_mm = apart(p.kerb_height * 1000, (underside - KERB_PLATE_CLEARANCE) * 1000, "down")
            return (
                f"a {kerb_mm} mm kerb would hit the plate: at stand_height {p.stand_height:g} m its "
                f"underside is {underside * 1000:.0f} mm above the ground, and the kerb must stay "
                f"{KERB_PLATE_CLEARANCE * 1000:g} mm below it (at most {highest_mm} mm); raise 'stand_height'"
            )
        largest = largest_climbable_kerb(p)
        if p.kerb_height > largest:
            kerb_mm, largest_mm = apart(p.kerb_height * 1000, largest * 1000, "down")
            return (
                f"a {kerb_mm} mm kerb is above the largest climbable, {largest_mm} mm "
                f"(the foot lifts step_height = {p.step_height:g} m, less a foot radius of clearance; the legs reach "
                f"{(p.stand_height - depth_range(p)[0]) * 1000:.0f} mm above the stance); raise 'step_height'"
            )
    if p.roughness:
        t = terrain(p)
        x0, x1, y0, y1 = t.extent
        points = ((x1 - x0) / HFIELD_CELL + 1) * ((y1 - y0) / HFIELD_CELL + 1)
        if points > HFIELD_MAX_POINTS:
            shown, most = apart(points, HFIELD_MAX_POINTS, "down")
            return (
                f"the rough ground under this walk would be a {x1 - x0:.3g} x {y1 - y0:.3g} m heightfield of "
                f"{shown} points (at most {most}); shorten 'duration' or lower the speed"
            )
    return ""


def _perturbations(p: HexabotParams) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Seeded servo trims (18,) [rad], body CoM offset (3,) [m] and per-foot friction factors (6,)."""
    rng = np.random.default_rng(p.seed)
    trims = rng.uniform(-1.0, 1.0, 18) * math.radians(p.trim_error_deg)
    angle = rng.uniform(0.0, 2 * math.pi)
    com = np.array([math.cos(angle), math.sin(angle), 0.0]) * p.com_offset
    friction = 1.0 + rng.uniform(-1.0, 1.0, 6) * p.friction_spread
    return trims, com, friction


def build_xml(p: HexabotParams) -> str:
    """The hexabot scene with the run's options, stance, friction, perturbations and ground written in."""
    root = models.load_tree("hexabot_scene")
    models.find(root, "option").attrib.update(timestep=models.fmt(p.timestep), integrator=p.integrator)
    _, com, friction = _perturbations(p)
    torso = models.find(root, "body", "torso")
    torso.find("inertial").set("pos", models.fmt(com))
    feet = neutral(p)
    q0, _ = hx.ik_hip_batch(LAYOUT, hx.body_to_hip(LAYOUT, feet))
    z0 = p.stand_height + LAYOUT.foot_radius
    pose = [0.0, 0.0, z0, 1.0, 0.0, 0.0, 0.0]
    ground = terrain(p)
    if not ground.flat:
        pose, q0 = _add_terrain(root, p, ground, feet, q0)
    torso.set("pos", models.fmt(pose[:3]))
    for leg, factor in zip(hx.LEGS, friction, strict=True):
        foot = models.find(root, "geom", f"{leg}_foot")
        foot.set("friction", models.fmt([p.friction * factor, 0.005, 0.0001]))
    key = models.find(root, "key", "home")
    key.set("qpos", models.fmt([*pose, *q0.ravel()]))
    key.set("ctrl", models.fmt([*q0.ravel(), *np.zeros(18)]))
    return models.to_xml(root)


def _add_terrain(root, p: HexabotParams, ground: Terrain, feet: np.ndarray, q0: np.ndarray):
    """Writes the ground into the scene tree; the start pose (7,) and joint angles (6, 3) standing on it.

    With the ground-finding controller the body starts level, its feet on the ground under their
    neutral points (IK). With the planned controller it starts parallel to a slope, or level on its
    neutral stance above the highest ground under a foot (it settles onto the feet that touch).
    """
    import xml.etree.ElementTree as ET

    assets, geoms = ground.mjcf()
    asset = root.findall("asset")[-1]  # the scene's (the robot's comes first)
    for text in assets:
        asset.append(ET.fromstring(text))
    world = root.findall("worldbody")[-1]
    for text in geoms:
        world.append(ET.fromstring(text))
    floor = models.find(root, "geom", "floor")
    models.find(root, "option").set("noslip_iterations", str(TERRAIN_NOSLIP_ITERATIONS))
    # MuJoCo sizes the scene from its geoms unless told: the 20 m kerb or floor ring made it 28-67 m, and the
    # renderer's near plane (znear x extent) clipped the ground in front of the chase camera. The robot's scale:
    root.insert(0, ET.Element("statistic", extent=models.fmt(SCENE_EXTENT), center="0 0 0.1"))
    if ground.slope_deg:
        floor.set("quat", models.fmt(ground.floor_quat()))
        # From the chase camera a 10 deg tilt hardly shows: the video looks along the slope's contour lines
        # instead, low, with the uphill to the right, so the ground's line rises across the frame.
        uphill = np.array([*ground.uphill, 0.0])
        eye = SLOPE_CAMERA_DISTANCE * np.array([uphill[1], -uphill[0], 0.0]) + np.array([0.0, 0.0, SLOPE_CAMERA_HEIGHT])
        forward = -eye / np.linalg.norm(eye)  # toward the body
        right = np.cross(forward, [0.0, 0.0, 1.0])
        right /= np.linalg.norm(right)
        xyaxes = np.r_[right, np.cross(right, forward)]
        models.find(root, "body", "torso").append(
            ET.Element("camera", name="slope", mode="trackcom", pos=models.fmt(eye), xyaxes=models.fmt(xyaxes))
        )
    if ground.roughness:  # the heightfield replaces the floor under the walk; the plane stays as scenery below
        floor.attrib.update(conaffinity="0", pos=models.fmt([0.0, 0.0, -ground.roughness - 0.002]))
    r = LAYOUT.foot_radius
    normal = ground.normal()
    if p.on_ground() and not (ground.slope_deg and p.level_body == "off"):
        # Level body; every foot centre r (along the normal) above the ground under its neutral point.
        g = ground.height(feet[:, 0], feet[:, 1]) + r / normal[2]  # (6,)
        z0 = p.stand_height + float(g.mean())
        target = feet.copy()
        target[:, 2] = g - z0
        q = hx.ik_body(LAYOUT, target)
        return [0.0, 0.0, z0, 1.0, 0.0, 0.0, 0.0], q
    if ground.slope_deg:
        pos = normal * (p.stand_height + r)
        return [*pos, *ground.floor_quat()], q0
    z0 = p.stand_height + r + float(ground.height(feet[:, 0], feet[:, 1]).max())
    return [0.0, 0.0, z0, 1.0, 0.0, 0.0, 0.0], q0


def acceleration_limit(p: HexabotParams) -> float:
    """Commanded joint-acceleration limit [rad/s^2]: ACCELERATION_LIMIT, or more where the steady cycle needs it."""
    hip, dt = _plan_cycle(p, p.command())
    q, _ = hx.ik_hip_batch(LAYOUT, hip)  # (n, 6, 3)
    peak = float(np.abs(np.diff(q, 2, axis=0)).max()) / dt**2
    return max(ACCELERATION_LIMIT, ACCELERATION_HEADROOM * peak)


def make_controller(p: HexabotParams, model: mujoco.MjModel, data: mujoco.MjData) -> HexabotController:
    """The walking controller of a run (the ground-finding one for sensed touchdown or a levelled body)."""
    trims, _, _ = _perturbations(p)
    planner = GaitPlanner(p.the_gait(), p.period, p.step_height, neutral(p), p.timestep, start_time=SETTLE_TIME)
    settings = WalkSettings(
        p.command(), settle_time=SETTLE_TIME, ramp_time=p.period, heading_hold=p.heading_hold == "on",
        trims=tuple(trims.tolist()),
    )  # fmt: skip
    gains = ResolvedRateGains(p.task_gain, 0.01, 0.01, p.max_joint_speed, acceleration_limit(p))
    q0 = model.key("home").qpos[7:].reshape(6, 3)
    if not p.on_ground():
        return HexabotController(model, data, LAYOUT, planner, gains, settings, q0)
    ground = GroundSettings(
        sensed=p.touchdown == "sensed", level=p.level_body == "on", stand_height=p.stand_height,
        depth_range=depth_range(p),
    )  # fmt: skip
    return GroundController(model, data, LAYOUT, planner, gains, settings, q0, ground)


def run(name: str, p: HexabotParams, progress: Progress | None = None) -> ScenarioResult:
    """Stands the robot on its neutral stance, then walks with the command and records everything."""
    xml = build_xml(p)
    model, data = at_home(xml)
    controller = make_controller(p, model, data)
    n_steps = step_count(p.duration, p.timestep)
    started = time.perf_counter()
    traj = simulate(model, data, n_steps, controller=controller, progress=progress, record_ctrl=True)
    wall = time.perf_counter() - started
    return analyse(name, p, model, xml, traj, controller, wall)


# ---------------------------------------------------------------------------------------------
# Analysis: everything below recomputes from the recorded state (t, qpos, qvel, ctrl) and model.


def rpy_from_quat(quat: np.ndarray) -> np.ndarray:
    """Roll, pitch, yaw (..., 3) [rad] (z-y-x Euler angles) of unit quaternions (..., 4) (w, x, y, z)."""
    w, x, y, z = (quat[..., i] for i in range(4))
    roll = np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = np.arcsin(np.clip(2 * (w * y - z * x), -1.0, 1.0))
    yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return np.stack([roll, pitch, yaw], axis=-1)


@dataclasses.dataclass(frozen=True)
class Contacts:
    """Per recorded row: foot loads, contact-point slip, joint torques, body-ground contact."""

    load: np.ndarray  # (n, 6) normal force of each foot [N]
    slip: np.ndarray  # (n, 6) horizontal speed of the foot's material point at its contact [m/s]
    point: np.ndarray  # (n, 6, 3) contact point [m] (NaN where the foot is off the ground)
    torque: np.ndarray  # (n, 18) joint actuator torque [N m]
    body_contact: np.ndarray  # (n,) the plate touches the ground

    def loaded(self, total_mass: float) -> np.ndarray:
        """(n, 6) the feet that carry load: more than LOADED_FRACTION of a sixth of the robot's weight."""
        return self.load > LOADED_FRACTION * total_mass * 9.81 / 6


def replay_contacts(
    model: mujoco.MjModel, t: np.ndarray, qpos: np.ndarray, qvel: np.ndarray, ctrl: np.ndarray
) -> Contacts:
    """Recomputes contacts, slip and torques at every recorded row with mj_forward (the recorded state in)."""
    data = mujoco.MjData(model)
    n = len(t)
    foot_geoms = {model.geom(f"{leg}_foot").id: i for i, leg in enumerate(hx.LEGS)}
    tibia = [model.body(f"{leg}_tibia").id for leg in hx.LEGS]
    torso_geom = model.geom("torso").id
    load = np.zeros((n, 6))
    slip = np.zeros((n, 6))
    point = np.full((n, 6, 3), np.nan)
    torque = np.empty((n, 18))
    body_contact = np.zeros(n, dtype=bool)
    force = np.zeros(6)
    jacp = np.zeros((3, model.nv))  # (3, nv)
    for k in range(n):
        data.qpos[:], data.qvel[:], data.ctrl[:] = qpos[k], qvel[k], ctrl[min(k + 1, n - 1)]
        data.time = t[k]
        mujoco.mj_forward(model, data)
        torque[k] = data.qfrc_actuator[6:24]
        for c in range(data.ncon):
            contact = data.contact[c]
            leg = foot_geoms.get(contact.geom1, foot_geoms.get(contact.geom2))
            if contact.geom1 == torso_geom or contact.geom2 == torso_geom:
                body_contact[k] = True
            if leg is None:
                continue
            mujoco.mj_contactForce(model, data, c, force)
            load[k, leg] += force[0]
            # Velocity of the foot's material point at the contact: the tibia body's Jacobian at that point.
            mujoco.mj_jac(model, data, jacp, None, contact.pos, tibia[leg])
            v = jacp @ data.qvel
            slip[k, leg] = math.hypot(v[0], v[1])
            point[k, leg] = contact.pos
    return Contacts(load=load, slip=slip, point=point, torque=torque, body_contact=body_contact)


def steady_window(p: HexabotParams, t: np.ndarray) -> np.ndarray:
    """Rows of the steady walk: after settling, the ramp and one more period, whole cycles to the end."""
    start = SETTLE_TIME + 2 * p.period
    cycles = math.floor((t[-1] - start) / p.period + 1e-9)
    if cycles < 1:  # a short run: whatever follows the ramp
        start, end = SETTLE_TIME + p.period, t[-1]
    else:
        end = start + cycles * p.period
    return (t >= start - 1e-9) & (t <= end + 1e-9)


# A ratio is reported only where its denominator is well above what it is measured against (else null, with why).
# The standing robot creeps at ~0.05 mm/s and its body sways a few mm within every gait cycle, so a relative speed
# error needs a command of at least 1 mm/s (1 mrad/s for turning), and a per-metre figure 0.1 m of travel.
LEAST_SPEED: float = 1e-3  # [m/s] or [rad/s]
LEAST_TRAVEL: float = 0.1  # [m]


def _relative_error(measured: float, commanded: float) -> float | None:
    return None if abs(commanded) < LEAST_SPEED else (measured - commanded) / abs(commanded)


def _per_travel(amount: float, travelled: float) -> float | None:
    return amount / travelled if travelled >= LEAST_TRAVEL else None


def _null_why(metric: Metric, why: str) -> Metric:
    """`metric` with the reason appended to its doc when its value is null."""
    return metric if metric.value is not None else dataclasses.replace(metric, doc=f"{metric.doc}; null here: {why}")


def walking_metrics(
    p: HexabotParams, t: np.ndarray, qpos: np.ndarray, qvel: np.ndarray, contacts: Contacts, total_mass: float
) -> dict[str, Metric]:
    """The walking metrics of a run, from its recorded state and contacts."""
    window = steady_window(p, t)
    dt = p.timestep
    rpy = rpy_from_quat(qpos[:, 3:7])
    yaw = np.unwrap(rpy[:, 2])
    w = np.flatnonzero(window)
    i0, i1 = w[0], w[-1]
    duration = t[i1] - t[i0]
    # Body-frame velocity: world displacement over the window, rotated into the mean heading... per step.
    vel_world = np.diff(qpos[:, :2], axis=0) / np.diff(t)[:, None]  # (n-1, 2)
    mid_yaw = 0.5 * (yaw[1:] + yaw[:-1])
    c, s = np.cos(mid_yaw), np.sin(mid_yaw)
    v_body = np.stack([c * vel_world[:, 0] + s * vel_world[:, 1], -s * vel_world[:, 0] + c * vel_world[:, 1]], -1)
    steps = slice(i0, i1)
    mean_vx, mean_vy = (float(v) for v in v_body[steps].mean(axis=0))
    mean_yaw_rate = float((yaw[i1] - yaw[i0]) / duration)
    # Drift: along / across the commanded direction in the world, over the window.
    disp = qpos[i1, :2] - qpos[i0, :2]
    distance = float(np.hypot(*disp))
    speed_cmd = math.hypot(p.vx, p.vy)
    if speed_cmd > 0 and p.yaw_rate == 0:
        heading0 = yaw[0]
        along = np.array([p.vx, p.vy]) / speed_cmd
        along = np.array([math.cos(heading0) * along[0] - math.sin(heading0) * along[1],
                          math.sin(heading0) * along[0] + math.cos(heading0) * along[1]])  # fmt: skip
        across = np.array([-along[1], along[0]])
        path = qpos[i0 : i1 + 1, :2] - qpos[i0, :2]
        travelled = float(path[-1] @ along)
        lateral = float(path[-1] @ across)
        lateral_drift = _per_travel(lateral, travelled)
        heading_drift = _per_travel(float(np.degrees(yaw[i1] - yaw[i0])), travelled)
        short = f"travelled {travelled:.3g} m along the command, under the {LEAST_TRAVEL:g} m a per-metre figure needs"
    else:
        lateral_drift = heading_drift = None
        short = "not a straight walk (no speed commanded, or turning)"
    slow = f"commanded under {LEAST_SPEED:g} (m/s or rad/s): the robot's own creep would dominate the ratio"
    # Height and attitude.
    height_cmd = p.stand_height + LAYOUT.foot_radius
    z = qpos[window, 2]
    roll, pitch = np.degrees(rpy[window, 0]), np.degrees(rpy[window, 1])
    # Slip of loaded feet, per stance.
    loaded = contacts.loaded(total_mass)
    slip_loaded = contacts.slip[window][loaded[window]]
    slip_distance = float((contacts.slip[window] * loaded[window]).sum() * dt)
    touchdowns = int((np.diff(loaded[window].astype(int), axis=0) == 1).sum())
    # Energy: positive and negative joint work both cost (hobby servos do not recover energy).
    power = np.abs(contacts.torque * qvel[:, 6:24]).sum(axis=1)
    work = float(power[window].sum() * dt)
    tilt = np.degrees(np.arccos(np.clip(1 - 2 * (qpos[:, 4] ** 2 + qpos[:, 5] ** 2), -1.0, 1.0)))
    fell = bool(contacts.body_contact.any() or (tilt > FALL_TILT_DEG).any())
    peak_torque = float(np.abs(contacts.torque).max())
    return {
        "mean_vx": Metric(mean_vx, "m/s", "mean body-frame forward speed over the steady walk"),
        "mean_vy": Metric(mean_vy, "m/s", "mean body-frame sideways speed over the steady walk"),
        "mean_yaw_rate": Metric(mean_yaw_rate, "rad/s", "mean turning rate over the steady walk"),
        "vx_error": _null_why(Metric(_relative_error(mean_vx, p.vx), "1", "(mean_vx - vx) / |vx|"), slow),
        "vy_error": _null_why(Metric(_relative_error(mean_vy, p.vy), "1", "(mean_vy - vy) / |vy|"), slow),
        "yaw_rate_error": _null_why(
            Metric(_relative_error(mean_yaw_rate, p.yaw_rate), "1", "(mean_yaw_rate - yaw_rate) / |yaw_rate|"), slow
        ),
        "speed_abs_error": Metric(
            float(math.hypot(mean_vx - p.vx, mean_vy - p.vy)), "m/s", "|mean planar velocity - command|"
        ),
        "distance": Metric(distance, "m", "straight-line distance covered over the steady walk"),
        "lateral_drift": _null_why(Metric(
            None if lateral_drift is None else lateral_drift * 1000,
            "mm/m",
            "sideways deviation from the commanded direction per metre travelled (straight walks)",
        ), short),  # fmt: skip
        "heading_drift": _null_why(
            Metric(heading_drift, "deg/m", "heading change per metre travelled (straight walks)"), short
        ),
        "body_height_mean": Metric(float(z.mean()), "m", "mean body height over the steady walk"),
        "body_height_sag": Metric(float(height_cmd - z.mean()), "m", "planned body height minus the mean height"),
        "body_height_ptp": Metric(float(np.ptp(z)), "m", "peak-to-peak body height over the steady walk"),
        "roll_ptp": Metric(float(np.ptp(roll)), "deg", "peak-to-peak body roll over the steady walk"),
        "pitch_ptp": Metric(float(np.ptp(pitch)), "deg", "peak-to-peak body pitch over the steady walk"),
        "slip_mean": Metric(
            float(slip_loaded.mean()) if slip_loaded.size else 0.0,
            "m/s",
            "mean speed of the loaded feet's contact points (material point of the foot)",
        ),
        "slip_p95": Metric(
            float(np.percentile(slip_loaded, 95)) if slip_loaded.size else 0.0,
            "m/s",
            "95th percentile of the loaded feet's contact-point speed",
        ),
        "slip_per_stance": Metric(
            slip_distance / touchdowns * 1000 if touchdowns else 0.0, "mm", "contact-point sliding distance per stance"
        ),
        "cost_of_transport": _null_why(Metric(
            work / (total_mass * 9.81 * distance) if distance >= LEAST_TRAVEL else None,
            "1",
            "joint work |tau dq| / (m g distance) over the steady walk",
        ), f"covered {distance:.3g} m, under the {LEAST_TRAVEL:g} m a per-distance figure needs"),  # fmt: skip
        "peak_joint_torque": Metric(peak_torque, "N*m", "largest joint torque of the run"),
        "torque_limit_fraction": Metric(
            peak_torque / TORQUE_LIMIT, "1", f"peak_joint_torque / the {TORQUE_LIMIT} N*m limit"
        ),
        "fell": Metric(fell, "", f"the plate touched the ground or tilted beyond {FALL_TILT_DEG:g} deg"),
    }


TOUCHDOWN_TOLERANCE: float = 0.02  # [s] a touchdown further than this from the plan counts as early or late


def terrain_metrics(
    p: HexabotParams,
    ground: Terrain,
    t: np.ndarray,
    qpos: np.ndarray,
    controller: HexabotController,
    bearing: np.ndarray,
    planned: np.ndarray,
) -> dict[str, Metric]:
    """Attitude relative to gravity, height above the local ground, progress, touchdowns, levelling limits,
    and how often the feet the plan has in stance (`planned`, (n, 6)) carry load (`bearing`: loaded and planned)."""
    window = steady_window(p, t)
    rpy = np.degrees(rpy_from_quat(qpos[window, 3:7]))  # z-y-x angles: roll and pitch are relative to gravity
    roll, pitch = rpy[:, 0], rpy[:, 1]
    above = qpos[window, 2] - ground.height(qpos[window, 0], qpos[window, 1])
    w = np.flatnonzero(window)
    i0, i1 = w[0], w[-1]
    along = walking_direction(p)
    made_good = float((qpos[i1, :2] - qpos[i0, :2]) @ along)
    speed = math.hypot(p.vx, p.vy)
    speed_made_good = made_good / (t[i1] - t[i0])
    events = [e for e in getattr(controller, "events", []) if e.planned > SETTLE_TIME]
    touched = np.array([e.touched - e.planned for e in events if math.isfinite(e.touched)])
    updates = getattr(controller, "updates", 0)
    bearing, planned = bearing[window], planned[window]
    per_leg = bearing.sum(axis=0) / np.maximum(planned.sum(axis=0), 1)
    return {
        "roll_peak": Metric(float(np.abs(roll).max()), "deg", "largest |body roll| relative to gravity (steady walk)"),
        "pitch_peak": Metric(float(np.abs(pitch).max()), "deg", "largest |body pitch| relative to gravity"),
        "roll_rms": Metric(float(np.sqrt(np.mean(roll**2))), "deg", "RMS body roll relative to gravity"),
        "pitch_rms": Metric(float(np.sqrt(np.mean(pitch**2))), "deg", "RMS body pitch relative to gravity"),
        "height_above_ground_mean": Metric(
            float(above.mean()), "m", "body origin above the ground straight under it (mean over the steady walk)"
        ),
        "height_above_ground_ptp": Metric(float(np.ptp(above)), "m", "peak-to-peak height above the local ground"),
        "distance_made_good": Metric(
            made_good, "m", "horizontal progress along the commanded direction over the steady walk"
        ),
        "speed_made_good": Metric(speed_made_good, "m/s", "distance_made_good / its time"),
        "speed_made_good_error": _null_why(Metric(
            _relative_error(speed_made_good, speed), "1", "(speed_made_good - |command|) / |command|"
        ), f"commanded under {LEAST_SPEED:g} m/s: the robot's own creep would dominate the ratio"),  # fmt: skip
        "touchdowns": Metric(len(events), "1", "swings that ended after the settling time"),
        "touchdown_error_mean": Metric(
            float(touched.mean()) if touched.size else None, "s", "touch time - planned touchdown, mean"
        ),
        "touchdown_error_max": Metric(
            float(np.abs(touched).max()) if touched.size else None, "s", "largest |touch time - planned touchdown|"
        ),
        "early_touchdowns": Metric(
            int((touched < -TOUCHDOWN_TOLERANCE).sum()),
            "1",
            f"feet that touched more than {TOUCHDOWN_TOLERANCE * 1000:g} ms before the plan",
        ),
        "late_touchdowns": Metric(
            int((touched > TOUCHDOWN_TOLERANCE).sum()),
            "1",
            f"feet that touched more than {TOUCHDOWN_TOLERANCE * 1000:g} ms after the plan",
        ),
        "feet_without_ground": Metric(
            len(events) - int(touched.size), "1", "swings that found no ground by the end of the leg's reach"
        ),
        "stance_loaded_fraction": Metric(
            float(bearing.sum() / max(planned.sum(), 1)),
            "1",
            f"share of the planned stance time in which the feet carry load (> {LOADED_FRACTION:g} of a sixth of "
            "the weight), all feet",
        ),
        "stance_loaded_fraction_min": Metric(
            float(per_leg.min()), "1", "stance_loaded_fraction of the foot that carries load least often"
        ),
        "level_clipped_fraction": Metric(
            controller.clipped_updates / updates if updates else 0.0,
            "1",
            "fraction of stance-height updates clipped to the legs' workspace",
        ),
        "largest_climbable_kerb": Metric(
            largest_climbable_kerb(p), "m", "highest kerb this gait can climb (step height and workspace)"
        ),
    }


def analyse(name, p, model, xml, traj, controller, wall) -> ScenarioResult:
    """Columns, metrics and figure data of a walk."""
    t, qpos, qvel, ctrl = traj.t, traj.qpos, traj.qvel, traj.ctrl
    contacts = replay_contacts(model, t, qpos, qvel, ctrl)
    total_mass = float(model.body_subtreemass[model.body("torso").id])
    metrics = walking_metrics(p, t, qpos, qvel, contacts, total_mass)
    gait = p.the_gait()
    metrics |= {
        "stride": Metric(math.hypot(p.vx, p.vy) * gait.duty * p.period, "m", "body travel per stance at the command"),
        "duty": Metric(gait.duty, "1", "stance fraction of the gait cycle"),
        "real_time_factor": Metric(t[-1] / wall, "1", "simulated time / wall time of the simulation loop"),
    }
    ground = terrain(p)
    loaded = contacts.loaded(total_mass)
    planned = controller.planner.in_stance(t)  # (n, 6)
    if not ground.flat or p.on_ground():  # flat runs with the planned controller keep their metrics as they were
        metrics |= terrain_metrics(p, ground, t, qpos, controller, loaded & planned, planned)
    rpy = rpy_from_quat(qpos[:, 3:7])
    # Command in force at every row: the chunk's command (re-planned every chunk) times the ramp's factor.
    plan_t = np.array([c[0] for c in controller.commands])
    idx = np.clip(np.searchsorted(plan_t, t, side="right") - 1, 0, len(plan_t) - 1)
    plan = np.array([c[1:] for c in controller.commands])[idx] * np.asarray(controller.scale(t))[:, None]
    c, s = np.cos(rpy[:, 2]), np.sin(rpy[:, 2])
    vx_b = c * qvel[:, 0] + s * qvel[:, 1]
    vy_b = -s * qvel[:, 0] + c * qvel[:, 1]
    columns: dict[str, np.ndarray] = {"t": t, "x": qpos[:, 0], "y": qpos[:, 1], "z": qpos[:, 2]}
    columns |= {"roll": rpy[:, 0], "pitch": rpy[:, 1], "yaw": np.unwrap(rpy[:, 2])}
    columns |= {"vx_body": vx_b, "vy_body": vy_b, "yaw_rate": qvel[:, 5]}
    columns |= {"cmd_vx": plan[:, 0], "cmd_vy": plan[:, 1], "cmd_yaw_rate": plan[:, 2]}
    for i, leg in enumerate(hx.LEGS):
        columns[f"contact_{leg}"] = loaded[:, i].astype(float)
    for i, leg in enumerate(hx.LEGS):
        for j, joint in enumerate(hx.JOINTS):
            columns[f"q_{leg}_{joint}"] = qpos[:, 7 + 3 * i + j]
    units = {"t": "s", "x": "m", "y": "m", "z": "m", "roll": "rad", "pitch": "rad", "yaw": "rad"}
    units |= {"vx_body": "m/s", "vy_body": "m/s", "yaw_rate": "rad/s", "cmd_vx": "m/s", "cmd_vy": "m/s"}
    units |= {"cmd_yaw_rate": "rad/s"}
    units |= {k: ("1" if k.startswith("contact_") else "rad") for k in columns if k not in units}
    trail = qpos[:, :3].copy()
    trail[:, 2] = ground.height(trail[:, 0], trail[:, 1]) + 0.002  # the body's path drawn on the ground
    period_rows = max(1, round(p.period / p.timestep))
    speed = np.hypot(_moving_mean(vx_b, period_rows), _moving_mean(vy_b, period_rows))
    overlay = [
        lambda k: f"{p.gait} gait, speed {speed[k] * 1000:.0f} mm/s (command {math.hypot(*plan[k, :2]) * 1000:.0f})",
        lambda k: "feet down: " + " ".join(leg for i, leg in enumerate(hx.LEGS) if loaded[k, i]),
    ]
    return ScenarioResult(
        scenario=name,
        params=p,
        model=model,
        model_xml=xml,
        trajectory=traj,
        columns=columns,
        column_units=units,
        metrics=metrics,
        summary=["mean_vx", "mean_vy", "mean_yaw_rate", "lateral_drift", "heading_drift", "slip_per_stance", "fell"],
        camera="slope" if p.slope_deg else "track",
        trail=trail,
        overlay=overlay,
        extras={
            "contacts": contacts,
            "planned_stance": planned,
            "window": steady_window(p, t),
            "terrain": ground,
            "touchdowns": getattr(controller, "events", []),
        },
    )


# ---------------------------------------------------------------------------------------------
# Figures.

LEG_COLOURS = {
    "lf": "tab:blue",
    "lm": "tab:orange",
    "lr": "tab:green",
    "rf": "tab:red",
    "rm": "tab:purple",
    "rr": "tab:brown",
}


def _title(result: ScenarioResult, text: str) -> str:
    p = result.params
    return (
        f"{result.scenario}: {text}\n{p.gait} gait, period {p.period:g} s, command vx {p.vx:g} m/s, "
        f"vy {p.vy:g} m/s, yaw rate {p.yaw_rate:g} rad/s"
    )


def _moving_mean(values: np.ndarray, n: int) -> np.ndarray:
    """Centred moving mean over n samples (edges: shorter windows)."""
    n = max(1, min(n, len(values)))
    kernel = np.ones(n)
    return np.convolve(values, kernel, "same") / np.convolve(np.ones_like(values), kernel, "same")


def figures(result: ScenarioResult) -> dict[str, Any]:
    """Path with footprints, gait diagram, commanded vs achieved velocity, body height and attitude, foot slip."""
    from hexabot_sim import plots

    p, c = result.params, result.columns
    contacts: Contacts = result.extras["contacts"]
    t = c["t"]
    out: dict[str, Any] = {}

    # Path seen from above, with the footprints (where each foot touched down) and the heading.
    points = np.concatenate([np.c_[c["x"], c["y"]], contacts.point[..., :2].reshape(-1, 2)])
    points = points[np.isfinite(points).all(axis=1)]
    span_x, span_y = np.ptp(points, axis=0) + 0.1
    height = float(np.clip(7.0 * span_y / span_x, 3.0, 8.0))  # equal axes, a frame that fits the walk
    fig, ax = plots.figure(figsize=(10, height + 1.2))
    ax.plot(c["x"], c["y"], color="k", lw=1.5, label="body (plate centre)")
    loaded = np.stack([c[f"contact_{leg}"] for leg in hx.LEGS], axis=1) > 0.5
    for i, leg in enumerate(hx.LEGS):
        down = np.flatnonzero(np.diff(loaded[:, i].astype(int)) == 1) + 1
        pts = contacts.point[down, i]
        ax.plot(pts[:, 0], pts[:, 1], "o", ms=3.5, mfc="none", color=LEG_COLOURS[leg], label=f"{leg} touchdowns")
    every = max(1, round(p.period / p.timestep))
    heading = c["yaw"][::every]
    ax.quiver(
        c["x"][::every], c["y"][::every], np.cos(heading), np.sin(heading),
        angles="xy", scale_units="xy", scale=12, width=0.004, color="0.4", label="heading (every period)",
    )  # fmt: skip
    ax.plot(c["x"][0], c["y"][0], "g^", ms=9, label="start")
    ax.plot(c["x"][-1], c["y"][-1], "rs", ms=8, label="end")
    ax.set_aspect("equal", adjustable="datalim")
    ax.margins(0.03)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, alpha=0.3)
    plots.legend_right(ax)
    fig.suptitle(_title(result, "path seen from above"), fontsize=plots.TITLE_FONTSIZE)
    out["path"] = fig

    # Gait diagram: measured stance (loaded foot) as bars, the plan as thin lines, over four cycles.
    planned = result.extras["planned_stance"]
    start = SETTLE_TIME + 2 * p.period
    show = (t >= start) & (t <= start + 4 * p.period)
    if not show.any():
        show = t >= 0
    fig, ax = plots.figure(figsize=(9, 4.5))
    for i, leg in enumerate(hx.LEGS):
        y = len(hx.LEGS) - 1 - i
        ts = t[show]
        ax.fill_between(ts, y - 0.35, y + 0.35, where=loaded[show, i], step="post", color=LEG_COLOURS[leg], alpha=0.8,
                        label="stance (foot loaded)" if i == 0 else None)  # fmt: skip
        ax.fill_between(ts, y + 0.38, y + 0.45, where=planned[show, i], step="post", color="k",
                        label="planned stance" if i == 0 else None)  # fmt: skip
    ax.set_yticks(range(len(hx.LEGS)), list(reversed(hx.LEGS)))
    ax.set_xlabel("t [s]")
    ax.set_xlim(t[show][0], t[show][-1])
    plots.legend_above(ax, ncol=2)
    fig.suptitle(_title(result, "gait diagram (bars: measured stance; black: plan)"), fontsize=plots.TITLE_FONTSIZE)
    out["gait_diagram"] = fig

    # Commanded vs achieved body velocity (body frame), raw and averaged over one gait period.
    fig, axes = plots.figure(3, 1, figsize=(9, 8), sharex=True)
    n = max(1, round(p.period / p.timestep))
    for ax, key, cmd, label, unit in (
        (axes[0], "vx_body", "cmd_vx", "forward speed", "m/s"),
        (axes[1], "vy_body", "cmd_vy", "sideways speed", "m/s"),
        (axes[2], "yaw_rate", "cmd_yaw_rate", "yaw rate", "rad/s"),
    ):
        ax.plot(t, c[key], color="0.75", lw=0.6, label="measured")
        ax.plot(t, _moving_mean(c[key], n), color="tab:blue", lw=1.5, label="measured, mean over one period")
        ax.plot(t, c[cmd], **plots.TARGET_STYLE, label="command (with ramp and heading hold)")
        ax.set_ylabel(f"{label} [{unit}]")
        ax.grid(True, alpha=0.3)
    plots.legend_above(axes[0])
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(_title(result, "commanded vs achieved velocity (body frame)"), fontsize=plots.TITLE_FONTSIZE)
    out["velocity"] = fig

    # Body height and attitude.
    fig, axes = plots.figure(2, 1, figsize=(9, 6), sharex=True)
    planned_h = (p.stand_height + LAYOUT.foot_radius) * 1000
    axes[0].plot(t, c["z"] * 1000, color="tab:blue", label="body height")
    axes[0].axhline(planned_h, **plots.TARGET_STYLE, label="planned height")
    axes[0].set_ylabel("height [mm]")
    plots.plain(axes[0])
    plots.min_span(axes[0], 2.0)
    axes[1].plot(t, np.degrees(c["roll"]), label="roll")
    axes[1].plot(t, np.degrees(c["pitch"]), label="pitch")
    axes[1].set_ylabel("attitude [deg]")
    plots.min_span(axes[1], 0.5)
    for ax in axes:
        ax.grid(True, alpha=0.3)
        plots.legend_right(ax)
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(_title(result, "body height and attitude"), fontsize=plots.TITLE_FONTSIZE)
    out["body"] = fig

    # Foot slip: contact-point speed of the loaded feet.
    fig, ax = plots.figure(figsize=(9, 4.5))
    for i, leg in enumerate(hx.LEGS):
        slip = np.where(loaded[:, i], contacts.slip[:, i] * 1000, np.nan)
        ax.plot(t, slip, lw=0.8, color=LEG_COLOURS[leg], label=leg)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("contact-point speed while loaded [mm/s]")
    ax.grid(True, alpha=0.3)
    plots.legend_right(ax)
    m = result.metrics
    fig.suptitle(
        _title(
            result,
            f"foot slip: mean {m['slip_mean'].value * 1000:.3g} mm/s, {m['slip_per_stance'].value:.3g} mm per stance",
        ),
        fontsize=plots.TITLE_FONTSIZE,
    )
    out["slip"] = fig
    ground: Terrain = result.extras["terrain"]
    if not ground.flat:
        out["terrain"] = _terrain_figure(result, ground)
    return out


def _foot_centres(result: ScenarioResult, every: int) -> tuple[np.ndarray, np.ndarray]:
    """Rows (k,) of the recording, one in `every`, and the world position of each foot centre there (k, 6, 3)."""
    model, traj = result.model, result.trajectory
    data = mujoco.MjData(model)
    sites = [model.site(f"{leg}_foot").id for leg in hx.LEGS]
    rows = np.arange(0, len(traj.t), every)
    feet = np.empty((len(rows), 6, 3))
    for k, row in enumerate(rows):
        data.qpos[:] = traj.qpos[row]
        mujoco.mj_kinematics(model, data)
        feet[k] = data.site_xpos[sites]
    return rows, feet


def _terrain_figure(result: ScenarioResult, ground: Terrain) -> Any:
    """Side view: the ground under the body and the body's height; per leg, the ground along that foot's own track,
    the sole's path over it and the touchdowns (contact points), so every point is drawn over the ground under it."""
    from hexabot_sim import plots

    p, c = result.params, result.columns
    contacts: Contacts = result.extras["contacts"]
    t = c["t"]
    # Horizontal axis: distance along the commanded direction for a straight walk, else time.
    straight = math.hypot(p.vx, p.vy) > 0 and p.yaw_rate == 0
    along = walking_direction(p)

    def axis(xy: np.ndarray, times: np.ndarray) -> np.ndarray:
        return xy @ along if straight else times

    rows, feet = _foot_centres(result, max(1, round(0.01 / p.timestep)))  # every 10 ms
    r = LAYOUT.foot_radius
    fig, axes = plots.figure(
        1 + len(hx.LEGS), 1, figsize=(10, 11), sharex=True, gridspec_kw={"height_ratios": [1.6] + [1.0] * 6}
    )
    ax = axes[0]
    s_body = axis(np.c_[c["x"], c["y"]], t)
    under = ground.height(c["x"], c["y"]) * 1000
    floor = float(min(under.min(), (feet[..., 2].min() - r) * 1000)) - 15.0  # [mm] bottom of the ground fill
    ax.fill_between(s_body, under, floor, color="0.82", label="ground under the body")
    ax.plot(s_body, c["z"] * 1000, color="k", lw=1.2, label="body origin (plate centre)")
    ax.set_ylabel("height [mm]")
    plots.legend_above(ax, ncol=2)
    loaded = np.stack([c[f"contact_{leg}"] for leg in hx.LEGS], axis=1) > 0.5
    low, high = np.inf, -np.inf
    for i, leg in enumerate(hx.LEGS):
        ax = axes[1 + i]
        s_foot = axis(feet[:, i, :2], t[rows])
        g = ground.height(feet[:, i, 0], feet[:, i, 1]) * 1000
        sole = (feet[:, i, 2] - r) * 1000
        ax.plot(s_foot, g, color="0.35", lw=1.6, label="ground under the foot (along its own track)")
        ax.plot(s_foot, sole, color=LEG_COLOURS[leg], lw=0.8, label="sole (foot centre - radius)")
        down = np.flatnonzero(np.diff(loaded[:, i].astype(int)) == 1) + 1
        pts = contacts.point[down, i]
        ok = np.isfinite(pts).all(axis=1)
        ax.plot(axis(pts[ok, :2], t[down][ok]), pts[ok, 2] * 1000, "o", ms=4, mfc=LEG_COLOURS[leg], mec="k", mew=0.5,
                label="touchdown (contact point)")  # fmt: skip
        ax.set_ylabel(f"{leg} [mm]")
        low, high = min(low, g.min(), sole.min()), max(high, g.max(), sole.max())
        ax.grid(True, alpha=0.3)
    margin = 0.05 * (high - low) + 2.0
    for ax in axes[1:]:
        ax.set_ylim(low - margin, high + margin)
    axes[0].grid(True, alpha=0.3)
    plots.legend_above(axes[1], ncol=3)
    axes[-1].set_xlabel("distance along the commanded direction [m]" if straight else "t [s]")
    if p.slope_deg:
        kind = f"{p.slope_deg:g} deg slope ({p.slope_heading})"
    elif p.roughness:
        kind = f"roughness {p.roughness * 1000:g} mm, seed {p.seed}"
    else:
        kind = f"{p.kerb_height * 1000:g} mm kerb at {p.kerb_distance:g} m"
    fig.suptitle(
        _title(result, f"terrain: {kind}, touchdown {p.touchdown}, level_body {p.level_body}"),
        fontsize=plots.TITLE_FONTSIZE,
    )
    return fig


def live(p: HexabotParams) -> Live:
    """The hexabot on its neutral stance with its walking controller, for the interactive viewer."""
    model, data = at_home(build_xml(p))
    controller = make_controller(p, model, data)  # the same controller a run uses (terrain, levelling)

    def step() -> None:
        controller(model, data)
        mujoco.mj_step(model, data)

    def speed_text(d: mujoco.MjData) -> str:
        return f"{p.gait} gait, speed {math.hypot(d.qvel[0], d.qvel[1]) * 1000:4.0f} mm/s, x = {d.qpos[0]:6.3f} m"

    ground = terrain(p)

    def trail(d: mujoco.MjData) -> np.ndarray:
        return np.array([d.qpos[0], d.qpos[1], float(ground.height(d.qpos[0], d.qpos[1])) + 0.002])

    return Live(
        model, data, step, p.timestep, p.duration, camera="slope" if p.slope_deg else "track", track_body="torso",
        trail=trail, overlay=[speed_text],
    )  # fmt: skip
