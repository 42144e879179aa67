"""The feet and the ground of a walk: the neutral stance and the planned cycle's reach, the run's ground (slope,
rough patch, kerb, stairs), what the robot can climb, where the body starts, and the terrain's refusals.

Functions of a walk's parameters (walking.parameters.WalkParams, which checks its terrain with terrain_problem).
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np

from hexabot_sim.control.gait import Command, GaitPlanner
from hexabot_sim.kinematics import leg as leg_kin
from hexabot_sim.kinematics import legged
from hexabot_sim.params import apart
from hexabot_sim.terrain import Ground, Kerb, Limits, RoughPatch, Slope, Stairs, heightmap
from hexabot_sim.terrain.heightfield import CELL as HFIELD_CELL
from hexabot_sim.terrain.heightfield import MARGIN as HFIELD_MARGIN
from hexabot_sim.terrain.heightfield import MAX_POINTS as HFIELD_MAX_POINTS
from hexabot_sim.terrain.heightmap import HeightMap
from hexabot_sim.terrain.kerb import KERB_LENGTH, KERB_WIDTH
from hexabot_sim.walking import commands
from hexabot_sim.walking.constants import KERB_PLATE_CLEARANCE, REFLEX_LIFT, SETTLE_TIME
from hexabot_sim.walking.perturb import perturbations

if TYPE_CHECKING:
    from hexabot_sim.walking.parameters import WalkParams


def neutral(p: WalkParams) -> np.ndarray:
    """Neutral foot centres (6, 3) in the body frame for the run's stand height."""
    layout = dataclasses.replace(p.ROBOT.layout, stand_height=p.stand_height)
    return layout.neutral_feet_body()


def plan_steady(p: WalkParams, cmd: Command, samples: int = 240) -> tuple[np.ndarray, np.ndarray, float]:
    """The plan of two steady gait cycles at this command: foot targets (n, legs, 3) in the body frame, the planned
    stance (n, legs) and their time step. The first two cycles, the start-up from neutral, are dropped: a leg's first
    swing starts from wherever its first stance (from neutral, up to a cycle long) left it and can end in the second
    cycle (the ripple gait's last first swing ends at 7/6 of a cycle, 47 % faster than a steady one at 0.17 m/s)."""
    dt = p.period / samples
    planner = GaitPlanner(p.the_gait(), p.period, p.step_height, neutral(p), dt, profile=p.swing)
    chunks = [planner.plan(cmd, planner.max_chunk)]
    while planner.time < 4 * p.period - 1e-9:
        chunks.append(planner.plan(cmd, planner.max_chunk)[1:])
    body = np.concatenate(chunks)
    stance = planner.in_stance(np.arange(len(body)) * dt)
    return body[2 * samples :], stance[2 * samples :], dt


def _plan_cycle(p: WalkParams, cmd: Command, samples: int = 240) -> tuple[np.ndarray, float]:
    """Targets (n, 6, 3) in the hip frames over two steady gait cycles, and their time step."""
    body, _, dt = plan_steady(p, cmd, samples)
    layout = p.ROBOT.layout
    hip = np.einsum("lji,klj->kli", layout.hip_rotations(), body - layout.hip_positions())
    return hip, dt


def walking_direction(p: WalkParams, course: np.ndarray | None = None) -> np.ndarray:
    """Horizontal unit vector (2,) of the commanded walk in the world at the start (+x when standing or turning);
    with a schedule or waypoints, the direction their course (commands.path, if already planned) sets out in."""
    if p.schedule or p.waypoints:
        return commands.direction(commands.path(p, SETTLE_TIME) if course is None else course)
    speed = math.hypot(p.vx, p.vy)
    return np.array([p.vx, p.vy]) / speed if speed > 0 else np.array([1.0, 0.0])


def _walk_area(p: WalkParams, course: np.ndarray | None) -> tuple[tuple[float, float, float, float], float]:
    """The world box (x_min, x_max, y_min, y_max) [m] the walk covers, HFIELD_MARGIN beyond its course on every side,
    and the farthest it goes from its start [m]."""
    speed = math.hypot(p.vx, p.vy)
    distance = speed * p.duration
    if course is not None:  # a box holding the course (the schedule's planned path)
        extent = commands.extent(course, HFIELD_MARGIN)
        distance = float(np.hypot(course[:, 0], course[:, 1]).max())
    elif p.yaw_rate:  # an arc (or turning on the spot): a box about the start holding the circle
        half = min(speed * p.duration, 2 * speed / abs(p.yaw_rate)) + HFIELD_MARGIN
        extent = (-half, half, -half, half)
    else:
        end = np.array([p.vx, p.vy]) * p.duration
        extent = (
            min(0.0, end[0]) - HFIELD_MARGIN, max(0.0, end[0]) + HFIELD_MARGIN,
            min(0.0, end[1]) - HFIELD_MARGIN, max(0.0, end[1]) + HFIELD_MARGIN,
        )  # fmt: skip
    return extent, distance


def terrain(p: WalkParams) -> Ground:
    """The run's ground: slope direction from the walking direction, heightfield over the walk's area."""
    course = commands.path(p, SETTLE_TIME) if p.schedule or p.waypoints else None  # planned once, used thrice
    along = walking_direction(p, course)
    uphill = {"uphill": along, "downhill": -along, "across": np.array([-along[1], along[0]])}[p.slope_heading]
    extent, distance = _walk_area(p, course)
    if p.slope_deg:  # the patch lies in the ground frame: a world distance d is d / cos(slope) along the slope
        extent = tuple(v / math.cos(math.radians(p.slope_deg)) for v in extent)
    extent = tuple(round(v / HFIELD_CELL) * HFIELD_CELL for v in extent)

    def facing(distance: float) -> tuple[float, float]:
        """An edge `distance` ahead faces the way to where the course first gets that far (so the course meets
        it there, square on if straight; a short crab before a long walk ahead pointed a kerb 47 deg off it)."""
        ahead = along if course is None else commands.direction(course, distance)
        return float(ahead[0]), float(ahead[1])

    # The kerb's pavement runs on beyond the walk: 20 m, or as far as this walk could go (a 0.2 m/s walk of 200 s
    # stepped down off its end at 20.5 m, where the terrain's heights still had the kerb).
    reach = distance / math.cos(math.radians(p.slope_deg)) + HFIELD_MARGIN
    kerb_length, kerb_width = max(KERB_LENGTH, reach - p.kerb_distance), max(KERB_WIDTH, 2 * reach)
    obstacles: tuple[Kerb | Stairs, ...] = ()
    if p.kerb_height:
        obstacles += (Kerb(p.kerb_height, p.kerb_distance, facing(p.kerb_distance), kerb_length, kerb_width),)
    if p.stairs_rise:
        landing = max(KERB_LENGTH, reach - p.stairs_distance - (p.stairs_count - 1) * p.stairs_run)
        obstacles += (
            Stairs(
                p.stairs_rise,
                p.stairs_run,
                p.stairs_count,
                p.stairs_distance,
                facing(p.stairs_distance),
                landing,
                kerb_width,
            ),
        )
    return Ground(
        slope=Slope(p.slope_deg, (float(uphill[0]), float(uphill[1])), p.slope_heading),
        rough=RoughPatch(p.roughness, p.seed, extent) if p.roughness else None,
        obstacles=obstacles,
    )


def terrain_map(p: WalkParams) -> HeightMap | None:
    """The robot's map of the run's ground over the walk's area (terrain_map=on, with its map_error), else None."""
    if p.terrain_map != "on":
        return None
    return HeightMap.sample(terrain(p), _map_extent(p), p.map_error, p.seed)


def _map_extent(p: WalkParams) -> tuple[float, float, float, float]:
    """The world box the terrain map covers: the walk's area (its planned course, with a schedule or waypoints)."""
    course = commands.path(p, SETTLE_TIME) if p.schedule or p.waypoints else None
    return _walk_area(p, course)[0]


def _map_problem(p: WalkParams) -> str:
    """'' unless the terrain map's parameters are given without what they apply to."""
    if p.terrain_map == "on" and p.touchdown != "sensed":
        return (
            "parameter 'terrain_map' = on needs touchdown=sensed: the swings land on the map's ground and the feet's "
            "touch sensors end the swings the map got wrong"
        )
    if p.map_error and p.terrain_map != "on":
        return "parameter 'map_error' is the terrain map's error: it needs terrain_map=on (and touchdown=sensed)"
    if p.terrain_map == "on":
        extent = _map_extent(p)
        nx, ny = heightmap.grid_size(extent)
        if nx * ny > heightmap.MAX_POINTS:
            return (
                f"the terrain map of this walk's area ({extent[1] - extent[0]:.3g} m x {extent[3] - extent[2]:.3g} m) "
                f"needs {nx * ny:,} points at its {heightmap.CELL * 100:g} cm grid, more than "
                f"{heightmap.MAX_POINTS:,}: "
                + ("bring the waypoints closer together" if p.waypoints else "shorten 'duration' or lower the speed")
            )
    return ""


def depth_range(p: WalkParams) -> tuple[float, float]:
    """(smallest, largest) depth [m] of the stance feet below the hips that keeps every planned target reachable.

    The steady cycle of the command (stance and swing, with the lift) is shifted up and down as a whole:
    the stance depth may move by as much as every target of the cycle stays inside the reach and the
    joint ranges (bisection to 0.1 mm). With a schedule or waypoints the walk's own twist is never commanded: the
    cycle is stepping in place (their commands are checked as walks of their own: walking/commands.py).
    """
    hip, _ = _plan_cycle(p, Command() if p.schedule or p.waypoints else p.command())

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
    from hexabot_sim.walking.parameters import _bound

    swing = p.step_height * (1.0 + REFLEX_LIFT if reflex_on(p) else 1.0) - p.ROBOT.layout.foot_radius
    if swing > p.stand_height - depth_range(p)[0]:
        return "raise 'stand_height'"
    if p.step_height < _bound(type(p), "step_height"):
        return "raise 'step_height'"
    # The lift at its largest (it said "raise 'step_height'" at 0.1 m): the reflex lifts a blocked foot higher.
    if not reflex_on(p):
        needed = (("touchdown=sensed", p.touchdown != "sensed"), ("reflex=on", p.reflex == "off"))
        sets = [setting for setting, unset in needed if unset]
        return f"set {' and '.join(sets)} (the elevator reflex lifts a blocked foot higher)"
    return "lower " + " or ".join(f"'{name}'" for name in ("kerb_height", "stairs_rise") if getattr(p, name))


def _least_friction(p: WalkParams) -> tuple[float, str]:
    """The friction a slope's check takes, and how it follows (""): with friction_spread, the least mean of the seeded
    frictions (walking/perturb.py) over the feet the gait stands on at once; each carrying an equal share, they hold
    while tan(slope) is below that mean (the check took friction alone: 0.2 +- 50 % on a 10 deg slope passed)."""
    if not p.friction_spread:
        return p.friction, ""
    frictions = p.friction * perturbations(p)[2]
    down = min(p.the_gait().stance_sets(), key=lambda feet: float(frictions[list(feet)].mean()))
    least = float(frictions[list(down)].mean())
    legs = ", ".join(p.ROBOT.layout.legs[i] for i in down)
    return least, (
        f"the mean over {legs}, which the {p.gait} gait stands on at once: friction {p.friction:g} +- friction_spread "
        f"{p.friction_spread:g}, seed {p.seed}"
    )


def terrain_problem(p: WalkParams) -> str:
    """'' if the ground can be walked as asked, else a one-line reason (the terrain types' own refusals, with
    what this robot can take, and a level body's reach on a slope)."""
    problem = _map_problem(p)
    if problem:
        return problem
    ground = terrain(p)
    layout = p.ROBOT.layout
    underside = p.stand_height + layout.foot_radius - layout.plate[2]  # the plate's underside above the ground
    friction, friction_why = _least_friction(p) if ground.slope.tilted else (p.friction, "")  # only a slope's check
    limits = Limits(
        friction=friction,
        friction_why=friction_why,
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
        # A course's field covers its waypoints whatever the duration or speed (they were advised, and did nothing).
        points_hint="bring the waypoints closer together" if p.waypoints else "shorten 'duration' or lower the speed",
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
