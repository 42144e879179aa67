"""A walk's scene: MJCF of robot and ground, perturbations, and its controller."""

from __future__ import annotations

import mujoco
import numpy as np

from hexabot_sim import models
from hexabot_sim.control.commands import CommandSource
from hexabot_sim.control.compliance import AdmittanceSettings
from hexabot_sim.control.force_control import for_walk
from hexabot_sim.control.gait import Command, GaitPlanner
from hexabot_sim.control.resolved_rate import ResolvedRateGains
from hexabot_sim.control.walk_settings import GroundSettings, WalkSettings
from hexabot_sim.control.walker import GroundController, WalkingController
from hexabot_sim.kinematics import legged
from hexabot_sim.kinematics.legged_mjcf import FOOT_PAD_MARGIN, FOOT_PAD_SOLIMP, FOOT_PAD_SOLREF
from hexabot_sim.terrain import Ground
from hexabot_sim.walking import commands
from hexabot_sim.walking.constants import (
    ACCELERATION_HEADROOM,
    ACCELERATION_LIMIT,
    PAD_EARLY_BAND,
    REFLEX_LIFT,
    SCENE_EXTENT,
    SETTLE_TIME,
    SLOPE_CAMERA_DISTANCE,
    SLOPE_CAMERA_HEIGHT,
    TERRAIN_NOSLIP_ITERATIONS,
)
from hexabot_sim.walking.ground import _plan_cycle, depth_range, neutral, start_pose, terrain, terrain_map
from hexabot_sim.walking.parameters import WalkParams, unchecked
from hexabot_sim.walking.perturb import perturbations


def build_xml(p: WalkParams, ground: Ground | None = None) -> str:
    """The robot's scene with the run's options, stance, friction, perturbations and ground written in.

    `ground`: another ground than the run's `terrain(p)` (a Gymnasium environment's patch, hexabot_sim/envs).
    """
    layout = p.ROBOT.layout
    root = models.load_tree(p.ROBOT.scene, dict(p.ROBOT.replace))
    if p.ROBOT.replace:  # a robot file's model, generated at run time, in the scene of the committed robot
        root.set("model", f"{p.ROBOT.name} scene")
    models.find(root, "option").attrib.update(timestep=models.fmt(p.timestep), integrator=p.integrator)
    _, com, friction = perturbations(p)
    torso = models.find(root, "body", "torso")
    torso.find("inertial").set("pos", models.fmt(com))
    feet = neutral(p)
    q0, _ = legged.ik_hip_batch(layout, legged.body_to_hip(layout, feet))
    z0 = p.stand_height + layout.foot_radius
    pose = [0.0, 0.0, z0, 1.0, 0.0, 0.0, 0.0]
    ground = terrain(p) if ground is None else ground
    if not ground.flat:
        pose, q0 = _add_terrain(root, p, ground)
    torso.set("pos", models.fmt(pose[:3]))
    for leg, factor in zip(layout.legs, friction, strict=True):
        foot = models.find(root, "geom", f"{leg}_foot")
        foot.set("friction", models.fmt([p.friction * factor, 0.005, 0.0001]))
        if p.feet == "pad":  # the compliant foot pad (legged_mjcf.FOOT_PAD_SOLREF explains)
            pad = {"solref": FOOT_PAD_SOLREF, "solimp": FOOT_PAD_SOLIMP, "margin": FOOT_PAD_MARGIN}
            foot.attrib.update({name: models.fmt(value) for name, value in pad.items()})
    key = models.find(root, "key", "home")
    key.set("qpos", models.fmt([*pose, *q0.ravel()]))
    key.set("ctrl", models.fmt([*q0.ravel(), *np.zeros(q0.size)]))
    return models.to_xml(root)


def _add_terrain(root, p: WalkParams, ground: Ground):
    """Writes the ground into the scene tree; the start pose (7,) and joint angles (n_legs, 3) standing on it.

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
    for name, value in ground.floor().items():  # turned with a slope; under a rough patch, lowered scenery
        floor.set(name, value if isinstance(value, str) else models.fmt(value))
    if ground.slope.tilted:
        # From the chase camera a 10 deg tilt hardly shows: the video looks along the slope's contour lines
        # instead, low, with the uphill to the right, so the ground's line rises across the frame.
        uphill = np.array([*ground.slope.uphill, 0.0])
        eye = SLOPE_CAMERA_DISTANCE * np.array([uphill[1], -uphill[0], 0.0]) + np.array([0.0, 0.0, SLOPE_CAMERA_HEIGHT])
        forward = -eye / np.linalg.norm(eye)  # toward the body
        right = np.cross(forward, [0.0, 0.0, 1.0])
        right /= np.linalg.norm(right)
        xyaxes = np.r_[right, np.cross(right, forward)]
        models.find(root, "body", "torso").append(
            ET.Element("camera", name="slope", mode="trackcom", pos=models.fmt(eye), xyaxes=models.fmt(xyaxes))
        )
    return start_pose(p, ground)


def _row_walks(p: WalkParams) -> list[tuple[WalkParams, Command]]:
    """Each distinct row of a schedule as a walk of its own with its twist (not checked again: commands.
    schedule_problem checked each row so); none without a schedule."""
    walks: dict[tuple, tuple[WalkParams, Command]] = {}
    for row in commands.setpoints(p):
        c = row.command
        key = (c.vx, c.vy, c.yaw_rate, row.gait, row.step_height, row.stand_height)
        if key not in walks:
            q = unchecked(p, vx=c.vx, vy=c.vy, yaw_rate=c.yaw_rate, gait=row.gait, step_height=row.step_height,
                          stand_height=row.stand_height, schedule=())  # fmt: skip
            walks[key] = (q, c)
    return list(walks.values())


def _follower_walks(p: WalkParams) -> list[tuple[WalkParams, Command]]:
    """The path follower's fastest twists (commands.follower_twists) as walks of their own; none without waypoints."""
    return [(unchecked(p, vx=c.vx, vy=c.vy, yaw_rate=c.yaw_rate, waypoints=()), c) for c in commands.follower_twists(p)]


def _commanded_walks(p: WalkParams) -> list[tuple[WalkParams, Command]]:
    """The walks a run commands, each with its twist: the walk's own vx, vy, yaw_rate; with a schedule or waypoints,
    which replace them, stepping in place (before the first row, or at the course's end) and the rows' or the
    follower's twists."""
    if not (p.schedule or p.waypoints):
        return [(p, p.command())]
    return [(p, Command()), *_row_walks(p), *_follower_walks(p)]


def _walk_depth_range(p: WalkParams) -> tuple[float, float]:
    """The ground-finding controller's depth range: the narrowest over the walks the run commands (each planned as a
    walk of its own; ground.depth_range steps in place for the walk with a schedule or waypoints), not the walk's
    own vx, vy and yaw_rate a schedule replaces (an ignored vx = 1 m/s left (0.09, 0.09) m: no room to find the
    ground)."""
    ranges = [depth_range(q) for q, _ in _commanded_walks(p)]
    return max(lo for lo, _ in ranges), min(hi for _, hi in ranges)


def acceleration_limit(p: WalkParams) -> float:
    """Commanded joint-acceleration limit [rad/s^2]: ACCELERATION_LIMIT, or more where the steady cycle needs it
    (the most any walk the run commands needs: not a twist a schedule or waypoints replace)."""
    peak = 0.0
    for q_params, cmd in _commanded_walks(p):
        hip, dt = _plan_cycle(q_params, cmd)
        q, _ = legged.ik_hip_batch(p.ROBOT.layout, hip)  # (n, n_legs, 3)
        peak = max(peak, float(np.abs(np.diff(q, 2, axis=0)).max()) / dt**2)
    return max(ACCELERATION_LIMIT, ACCELERATION_HEADROOM * peak)


def make_controller(
    p: WalkParams, model: mujoco.MjModel, data: mujoco.MjData, source: CommandSource | None = None
) -> WalkingController:
    """The walking controller of a run (the ground-finding one for sensed touchdown or a levelled body); its
    command from `source` (the viewer's steering), else the walk's schedule or waypoints, else vx, vy, yaw_rate."""
    trims, _, _ = perturbations(p)
    gait = commands.start_gait(p)  # a schedule's first row's gait replaces the walk's
    planner = GaitPlanner(
        gait, p.period, p.step_height, neutral(p), p.timestep, start_time=SETTLE_TIME, profile=p.swing
    )
    source = commands.source(p, SETTLE_TIME) if source is None else source
    overlap = (gait.duty - p.gaits()[gait.name].duty) * p.period  # a duty above the gait's own [s]
    settings = WalkSettings(
        p.command(), settle_time=SETTLE_TIME, ramp_time=p.period if source is None else 0.0,
        heading_hold=p.heading_hold == "on", trims=tuple(trims.tolist()),
        admittance=AdmittanceSettings() if p.load_sharing == "admittance" else None,
        force=for_walk(p.period, overlap) if p.load_sharing == "force" else None,
    )  # fmt: skip
    gains = ResolvedRateGains(p.task_gain, 0.01, 0.01, p.max_joint_speed, acceleration_limit(p))
    q0 = model.key("home").qpos[7:].reshape(-1, 3)
    if not p.on_ground():
        return WalkingController(model, data, p.ROBOT.layout, planner, gains, settings, q0, source)
    ground = GroundSettings(
        sensed=p.touchdown == "sensed", level=p.level_body == "on", stand_height=p.stand_height,
        depth_range=_walk_depth_range(p), reflex_lift=p.step_height * REFLEX_LIFT if p.reflex == "on" else 0.0,
        early_band=PAD_EARLY_BAND if p.feet == "pad" else 0.0, terrain_map=terrain_map(p),
    )  # fmt: skip
    return GroundController(model, data, p.ROBOT.layout, planner, gains, settings, q0, ground, source)
