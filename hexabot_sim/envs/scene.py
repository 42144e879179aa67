"""An environment's model: a walking robot's scene on the chosen ground, and what every reset changes in it."""

from __future__ import annotations

import dataclasses
import math
import os
from typing import Any

import mujoco
import numpy as np

from hexabot_sim import params, registry
from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics import legged
from hexabot_sim.terrain import Ground, RoughPatch, Slope
from hexabot_sim.terrain.heightfield import CELL, MARGIN, MAX_POINTS
from hexabot_sim.terrain.limits import apart
from hexabot_sim.terrain.stairs import Stairs
from hexabot_sim.walking.constants import STAND_HEIGHT_MIN
from hexabot_sim.walking.ground import start_pose
from hexabot_sim.walking.parameters import WalkParams
from hexabot_sim.walking.scene import build_xml

TERRAINS: tuple[str, ...] = ("flat", "slope", "rough", "stairs")
STAIRS: tuple[float, float, int] = (0.04, 0.25, 3)  # rise [m], run [m], count: issue 19's staircase
STAIRS_DISTANCE: float = 0.5  # [m] the first step's edge ahead of the start (+x), as hexabot-stairs
EPISODE_SECONDS: float = 20.0  # [s] the registered episodes' length (max_episode_steps x control period)


def walk_reach(speed: float) -> float:
    """How far [m] from the start an episode at commanded speeds up to `speed` [m/s] in x and y may walk."""
    return speed * math.sqrt(2) * EPISODE_SECONDS


PLATE_SITE_MARGIN: float = 0.002  # [m] the plate's touch site is the plate grown by this on every side
PLATE_SITE: str = "env_plate"  # the site and touch sensor added to the torso (the fall detector)
MAX_ROUGHNESS: float = 0.03  # [m] rougher patches may rise above the plate's underside at the start
MAX_SLOPE_DEG: float = 30.0  # [deg] steeper slopes exceed the feet's friction (tan 30 deg = 0.58 < 1)


def real_number(value: object) -> bool:
    """A real number (not a bool, not a string)."""
    return not isinstance(value, bool) and isinstance(value, int | float | np.integer | np.floating)


def walking_robots() -> dict[str, tuple[type[WalkParams], dict]]:
    """Every robot with a '<robot>-walk' scenario, by name: (its parameter class, that scenario's defaults).

    A robot folder whose walk is a WalkParams scenario is an environment's robot with nothing else to write.
    """
    found = {}
    for robot in registry.ROBOTS:
        scenario = registry.SCENARIOS.get(f"{robot}-walk")
        if scenario is not None and issubclass(scenario.params_type, WalkParams):
            found[robot] = (scenario.params_type, dict(scenario.defaults))
    return found


def robot_params(robot: str, **overrides) -> WalkParams:
    """The robot's walk parameters (its '<robot>-walk' defaults, then `overrides`). `robot` is a walking robot's
    name, or the path (str or os.PathLike) of a legged-robot file (.toml), walked as that robot with as many legs walks
    its files.

    Raises:
        ValueError: for a robot without a walk, naming those there are; a file's problem in one line.
    """
    robots = walking_robots()
    if isinstance(robot, os.PathLike):  # a pathlib.Path, as hs.run takes (it was an "unknown robot")
        robot = os.fspath(robot)
    if isinstance(robot, str) and robot.lower() in robots:  # names match case-insensitively, as the CLI's
        robot = robot.lower()
    elif isinstance(robot, str) and (robot.lower().endswith(".toml") or os.path.isfile(robot)):
        return _file_params(robot, robots, overrides)  # any file, as the CLI's robot= (q.txt was an unknown robot)
    if not isinstance(robot, str) or robot not in robots:  # a list or dict: unhashable, a TypeError
        raise ValueError(
            f"unknown robot {robot!r}; known: {', '.join(robots)}, or the path of a legged-robot file (.toml)"
        )
    cls, defaults = robots[robot]
    return params.resolve(cls, defaults, overrides)


def _file_params(path: str, robots: dict[str, tuple[type[WalkParams], dict]], overrides: dict) -> WalkParams:
    """robot_params of a legged-robot file: the walk of the robot whose `robot` parameter takes its number of legs
    (the hexabot's six, the quadbot's four)."""
    from hexabot_sim.kinematics import legged_file

    try:
        layout = legged_file.read(path).layout
    except UsageError as e:
        raise ValueError(f"robot: {str(e).splitlines()[0]}") from None
    n = layout.n_legs
    if layout.stand_height < STAND_HEIGHT_MIN:  # the walk's refusal advised its stand_height: not a keyword here
        raise ValueError(
            f"robot: robot file {path}: [stance] height {layout.stand_height:g} m is lower than the walk's lowest "
            f"stance, {STAND_HEIGHT_MIN:g} m (an environment stands the robot at its file's height): give the file a "
            "taller stance"
        )
    takes = {cls.ROBOTS.legs: (cls, defaults) for cls, defaults in robots.values()}
    if n not in takes:
        legs = " or ".join(str(k) for k in sorted(takes))
        raise ValueError(f"robot: robot file {path}: {n} legs; the environments walk robot files with {legs} legs")
    cls, defaults = takes[n]
    return params.resolve(cls, defaults, {**overrides, "robot": path})


SLOPE_DEG: float = 10.0  # [deg] the slope's angle where terrain="slope" and slope_deg is not given
ROUGHNESS: float = 0.01  # [m] the bumps' peak height where terrain="rough" and roughness is not given
_TERRAIN_KEYWORDS: dict[str, tuple[str, object]] = {
    "slope_deg": ("slope", SLOPE_DEG), "roughness": ("rough", ROUGHNESS), "stairs": ("stairs", STAIRS),
}  # fmt: skip


def terrain_keywords(terrain: object, slope_deg: object, roughness: object, stairs: object) -> tuple[Any, Any, Any]:
    """(slope_deg, roughness, stairs): each terrain's keyword, its default where not given (None). A keyword given
    for another terrain is a ValueError: it would have no effect (terrain="flat", slope_deg=20 walked on the flat),
    as a walk parameter the run makes no use of is refused (hexabot_sim.unused)."""
    if not isinstance(terrain, str) or terrain not in TERRAINS:
        raise ValueError(f"unknown terrain {terrain!r}; known: {', '.join(TERRAINS)}")
    given = {"slope_deg": slope_deg, "roughness": roughness, "stairs": stairs}
    for name, value in given.items():
        own = _TERRAIN_KEYWORDS[name][0]
        if value is not None and terrain != own:
            raise ValueError(
                f"{name} is the {own} terrain's: it has no effect on terrain={terrain!r}; choose terrain={own!r} or "
                f"leave {name} out"
            )
    slope_deg, roughness, stairs = (_TERRAIN_KEYWORDS[k][1] if v is None else v for k, v in given.items())
    return slope_deg, roughness, stairs


def check_stairs(stairs) -> tuple[float, float, int]:
    """(rise [m], run [m], count) of a staircase, each in the range a walk's stairs_* parameter allows (rise > 0);
    else ValueError naming it."""
    try:
        if isinstance(stairs, str | bytes | dict):  # unpacked, they gave letters or keys as the rise
            raise TypeError
        rise, run, count = stairs
    except (TypeError, ValueError):
        raise ValueError(f"stairs must be (rise [m], run [m], count); got {stairs!r}") from None
    infos = params.infos(WalkParams)
    for name, value in (("rise", rise), ("run", run), ("count", count)):
        info = infos[f"stairs_{name}"][0]
        integer = name != "count" or (real_number(value) and float(value).is_integer())
        if not (real_number(value) and math.isfinite(value) and info.contains(value) and value > 0 and integer):
            strict = dataclasses.replace(info, gt=0.0, ge=None) if info.ge == 0 else info  # a rise of 0 is no stairs
            allowed = params.describe_range(strict, name) + (", an integer" if name == "count" else "")
            raise ValueError(f"stairs {name} must be {allowed}; got {value!r}")
    return float(rise), float(run), int(count)


def check_range(name: str, value, low: float = 0.0, high: float = math.inf) -> tuple[float, float] | None:
    """A (lo, hi) factor or value range with low <= lo <= hi <= high, or None; else ValueError naming it."""
    if value is None:
        return None
    try:
        if isinstance(value, str | bytes):  # "12" would be the pair (1.0, 2.0)
            raise TypeError(value)
        lo, hi = value
        if not (real_number(lo) and real_number(hi)):  # "0.5" and True were read as 0.5 and 1.0
            raise TypeError(value)
        lo, hi = float(lo), float(hi)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a pair (low, high) or None; got {value!r}") from None
    if not (low <= lo <= hi <= high) or not (math.isfinite(lo) and math.isfinite(hi)):
        raise ValueError(f"{name} must be (low, high) with {low:g} <= low <= high <= {high:g}; got {value!r}")
    return lo, hi


@dataclasses.dataclass(frozen=True)
class Randomization:
    """Domain randomisation, drawn from the environment's RNG at every reset (None: off).

    Attributes:
        friction: Range of the factor on each foot's sliding friction, drawn per foot.
        mass: Range of the factor on the plate's mass and rotational inertia (a payload), one per episode.
        servo_gain: Range of the factor on each servo's kp and kv together, drawn per joint.
    """

    friction: tuple[float, float] | None = None
    mass: tuple[float, float] | None = None
    servo_gain: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        for field in dataclasses.fields(self):
            checked = check_range(f"randomize_{field.name}", getattr(self, field.name), 0.01, 100.0)
            object.__setattr__(self, field.name, checked)


class EnvScene:
    """The robot's model on flat ground, a slope, a rough patch or stairs, with a touch sensor on the plate added.

    The model is compiled once; a reset writes a fresh rough patch into the heightfield (its elevation range
    fixed at +-roughness, so every patch fits the same geom), the start pose over it and the randomised
    friction, mass and servo gains, each from the nominal values kept here: an episode depends on its draws only.
    """

    def __init__(
        self,
        p: WalkParams,
        terrain: str,
        slope_deg: float,
        roughness: float,
        reach: float,
        randomization: Randomization,
        stairs: tuple[float, float, int] = STAIRS,
    ) -> None:
        if not isinstance(terrain, str) or terrain not in TERRAINS:
            raise ValueError(f"unknown terrain {terrain!r}; known: {', '.join(TERRAINS)}")
        # The values terrain_keywords gave: the chosen terrain's as given, the others' their defaults; each checked.
        if not (real_number(slope_deg) and 0.0 < slope_deg <= MAX_SLOPE_DEG):
            raise ValueError(f"slope_deg must be > 0 and <= {MAX_SLOPE_DEG:g} deg (a number); got {slope_deg!r}")
        if not (real_number(roughness) and 0.0 < roughness <= MAX_ROUGHNESS):
            raise ValueError(f"roughness must be > 0 and <= {MAX_ROUGHNESS:g} m (a number); got {roughness!r}")
        checked = check_stairs(stairs)
        self.stairs = checked if terrain == "stairs" else None
        self.p = p
        self.terrain = terrain
        self.roughness = roughness if terrain == "rough" else 0.0
        self.randomization = randomization
        # A square patch about the start that holds any episode's walk (reach [m]), the level floor beyond it.
        half = round((reach + MARGIN) / CELL) * CELL
        self.extent = (-half, half, -half, half)
        points = RoughPatch(self.roughness, 0, self.extent).points() if self.roughness else 0.0
        if points > MAX_POINTS:  # 1 m/s: 8.4e6 points, 25 s and ~1 GB to build
            fits = (math.sqrt(MAX_POINTS) - 1) * CELL / 2 - MARGIN - CELL  # the largest half-side's reach, rounded down
            speed, most = apart(reach / walk_reach(1.0), fits / walk_reach(1.0), "down")
            raise ValueError(
                f"terrain='rough' for commanded speeds up to {speed} m/s lays a {2 * half:.3g} m square heightfield "
                f"of {points:.3g} points (at most {MAX_POINTS:.3g}): keep command_range's vx and vy within "
                f"+-{most} m/s"
            )
        self.slope = Slope(slope_deg if terrain == "slope" else 0.0, (1.0, 0.0), "uphill")
        self.ground = self._ground(0)
        spec = mujoco.MjSpec.from_string(build_xml(p, self.ground))
        self._add_sensors(spec)
        if self.roughness:  # elevation range +-roughness: every seed's patch (peak |h| = roughness) fits
            spec.hfield("terrain").size[2] = 2 * self.roughness
            spec.geom("terrain").pos[2] = -self.roughness
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        self._nominal()

    def _ground(self, seed: int) -> Ground:
        rough = RoughPatch(self.roughness, seed, self.extent) if self.roughness else None
        obstacles: tuple[Stairs, ...] = ()
        if self.stairs is not None:  # up along +x from 0.5 m ahead, the landing and the width beyond any episode
            rise, run, count = self.stairs
            reach = self.extent[1]
            obstacles = (Stairs(rise, run, count, STAIRS_DISTANCE, (1.0, 0.0), landing=reach, width=2 * reach),)
        return Ground(slope=self.slope, rough=rough, obstacles=obstacles)

    def _add_sensors(self, spec: mujoco.MjSpec) -> None:
        """A box site around the plate and a touch sensor on it (the plate's contact force: a fall), the joints'
        torques and the feet's velocities."""
        px, py, pz = self.p.ROBOT.layout.plate
        m = PLATE_SITE_MARGIN
        spec.body("torso").add_site(
            name=PLATE_SITE, type=mujoco.mjtGeom.mjGEOM_BOX, size=[px + m, py + m, pz + m], group=5,
            rgba=[0, 0, 0, 0],
        )  # fmt: skip
        spec.add_sensor(
            name=PLATE_SITE, type=mujoco.mjtSensor.mjSENS_TOUCH, objtype=mujoco.mjtObj.mjOBJ_SITE, objname=PLATE_SITE
        )
        # What the reward reads, as sensors too, so a batch stepped by mujoco.rollout (vector.py) reads it from the
        # sensor data alone: each joint's actuator torque and each foot's velocity (world frame).
        layout = self.p.ROBOT.layout
        for leg in layout.legs:
            for joint in legged.JOINTS:
                spec.add_sensor(name=f"env_{leg}_{joint}_torque", type=mujoco.mjtSensor.mjSENS_JOINTACTFRC,
                                objtype=mujoco.mjtObj.mjOBJ_JOINT, objname=f"{leg}_{joint}")  # fmt: skip
        for leg in layout.legs:
            spec.add_sensor(name=f"env_{leg}_foot_velocity", type=mujoco.mjtSensor.mjSENS_FRAMELINVEL,
                            objtype=mujoco.mjtObj.mjOBJ_SITE, objname=f"{leg}_foot")  # fmt: skip

    def _nominal(self) -> None:
        """Keeps the values a reset randomises, and the addresses it writes."""
        m, legs = self.model, self.p.ROBOT.layout.legs
        self.feet = np.array([m.geom(f"{leg}_foot").id for leg in legs])
        self.torso = m.body("torso").id
        joints = [f"{leg}_{j}" for leg in legs for j in legged.JOINTS]
        self.pos_act = np.array([m.actuator(name).id for name in joints])
        self.vel_act = np.array([m.actuator(f"{name}_velocity").id for name in joints])
        self.friction0 = m.geom_friction[self.feet, 0].copy()
        self.mass0, self.inertia0 = float(m.body_mass[self.torso]), m.body_inertia[self.torso].copy()
        self.kp0, self.kv0 = m.actuator_gainprm[self.pos_act, 0].copy(), m.actuator_gainprm[self.vel_act, 0].copy()
        self.key = m.key("home").id
        if self.roughness:
            hfield = m.hfield("terrain")
            self.hfield = (int(hfield.id), int(m.hfield_adr[hfield.id]), int(m.hfield_nrow[0] * m.hfield_ncol[0]))

    def reset(self, rng: np.random.Generator) -> bool:
        """Draws this episode's ground and randomisation and puts the robot at its start; True if the ground changed.

        The draws, in order: the rough patch's seed, the feet's friction, the plate's mass, the servos' gains.
        """
        m = self.model
        changed = False
        if self.roughness:
            patch = RoughPatch(self.roughness, int(rng.integers(2**32)), self.extent)
            self.ground = Ground(slope=self.slope, rough=patch)
            norm, base, size = patch.hfield_levels()
            r = self.roughness
            _, adr, n = self.hfield
            m.hfield_data[adr : adr + n] = ((base + size * norm + r) / (2 * r)).ravel()  # row 0 at -y, as MuJoCo
            changed = True
        pose, q = start_pose(self.p, self.ground)
        nq = q.size
        m.key_qpos[self.key, :7] = pose
        m.key_qpos[self.key, 7 : 7 + nq] = q.ravel()
        m.key_ctrl[self.key, :nq] = q.ravel()
        m.key_ctrl[self.key, nq:] = 0.0
        rand = self.randomization
        if rand.friction is not None:
            m.geom_friction[self.feet, 0] = self.friction0 * rng.uniform(*rand.friction, len(self.feet))
        if rand.mass is not None:
            factor = rng.uniform(*rand.mass)
            m.body_mass[self.torso] = self.mass0 * factor
            m.body_inertia[self.torso] = self.inertia0 * factor
            mujoco.mj_setConst(m, self.data)  # the constants that depend on the masses (invweight, subtree mass)
        if rand.servo_gain is not None:
            gain = rng.uniform(*rand.servo_gain, len(self.pos_act))
            m.actuator_gainprm[self.pos_act, 0] = self.kp0 * gain
            m.actuator_biasprm[self.pos_act, 1] = -self.kp0 * gain
            m.actuator_gainprm[self.vel_act, 0] = self.kv0 * gain
            m.actuator_biasprm[self.vel_act, 2] = -self.kv0 * gain
        mujoco.mj_resetDataKeyframe(m, self.data, self.key)
        return changed
