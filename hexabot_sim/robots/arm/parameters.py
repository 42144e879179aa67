"""The arm-track scenario's parameters and plan, apart from the simulation: `hexabot-sim list` reads them
without MuJoCo (the scenario module is arm/track.py)."""

from __future__ import annotations

import dataclasses
import functools
import math
import os

import numpy as np

from hexabot_sim.budget import check_duration, check_run_cost, step_count
from hexabot_sim.kinematics import robots
from hexabot_sim.params import NameOrFile, apart, infos, param
from hexabot_sim.robots.arm.path import PATHS, PLANES, RAMP_TIME, Path, Plan, plan

ROBOT = NameOrFile(tuple(robots.ROBOTS), "robot file (.toml)", robots.resolve)
MM: tuple[str, float] = ("mm", 1e-3)  # the unit users type by mistake for a length in m
MAX_SERVO_STEP: float = 0.5  # largest 2 pi bandwidth * timestep: the servo's stiffness is integrated explicitly
# Cost of a run for budget.check_run_cost, measured on the 2-core development machine: seconds per control period
# (controller, mj_step1/2, the Jacobian check: 0.22-0.31 ms quiet, 0.55-0.7 ms under load, scara to 7 joints; the
# worst is taken), per recorded row (site replay, columns: 10-40 us), bytes per row.
RUN_COST: tuple[float, float, float] = (7e-4, 4e-5, 1500.0)


@dataclasses.dataclass(frozen=True)
class ArmTrackParams:
    """Parameters of the arm-track scenario (world frame: z up; the path's centre is the reference pose's tool
    point plus the offset)."""

    robot: str = param("stanford", "", "which arm (your own: docs/robot-files.md)", name_or_file=ROBOT)
    path: str = param("circle", "", "circle (diameter size), line (back and forth), figure8", choices=PATHS)
    plane: str = param("xy", "", "the world plane the path lies in", choices=tuple(PLANES))
    size: float = param(0.1, "m", "circle diameter, line length, figure-8 width", ge=1e-4, le=2.0, typo=MM)
    speed: float = param(0.1, "m/s", "peak tool speed along the path", ge=1e-12, le=2.0, typo=("mm/s", 1e-3))
    offset_x: float = param(0.0, "m", "path centre from the reference tool point, x", ge=-5.0, le=5.0, typo=MM)
    offset_y: float = param(0.0, "m", "path centre from the reference tool point, y", ge=-5.0, le=5.0, typo=MM)
    offset_z: float = param(0.0, "m", "path centre from the reference tool point, z", ge=-5.0, le=5.0, typo=MM)
    duration: float = param(0.0, "s", "simulated time; 0 = the 0.5 s ramp and one cycle of the path", ge=0.0, le=3600.0)
    timestep: float = param(0.001, "s", "control period and MuJoCo timestep", ge=1e-5, le=0.01)
    task_gain: float = param(20.0, "1/s", "K: feedback on the tool error; K * timestep <= 1", ge=0.0, le=1e4)
    servo_bandwidth: float = param(
        10.0, "Hz", "natural frequency of each servo on its joint's inertia (mj_fullM)", ge=0.1, le=200.0
    )
    servo_damping: float = param(1.0, "1", "damping ratio of each servo", ge=0.05, le=10.0)
    max_joint_speed: float = param(
        3.0, "rad/s", "limit on every revolute joint speed", ge=1e-3, le=100.0, typo=("deg/s", math.pi / 180)
    )
    max_slide_speed: float = param(1.0, "m/s", "limit on every prismatic joint speed", ge=1e-3, le=100.0)
    max_joint_acceleration: float = param(
        50.0, "rad/s^2", "braking before a range end (m/s^2 for a slide)", ge=1e-2, le=1e5
    )
    sigma_threshold: float = param(
        0.01, "", "task Jacobian sigma_min below which DLS damps (m/rad rows)", ge=1e-6, le=1.0
    )
    max_damping: float = param(0.01, "", "DLS damping lambda reached at a singularity", ge=0.0, le=1.0)
    nullspace_gain: float = param(
        1.0, "1/s", "pull toward the reference pose in a redundant arm's null space", ge=0.0, le=100.0
    )

    @property
    def SPEC(self):
        """The arm (kinematics.robot_file.RobotSpec), read once when the parameters were made: a robot file changed or
        removed since changes nothing (the run used to read it again)."""
        spec = self.__dict__.get("_spec")
        return spec if spec is not None else robots.resolve(self.robot)

    @property
    def PLAN(self) -> Plan:
        """The run's plan (plan_for), made when the parameters were made."""
        made = self.__dict__.get("_plan")
        return made if made is not None else plan_for(self)

    def __post_init__(self) -> None:
        object.__setattr__(self, "_spec", robots.resolve(self.robot))  # the file's version checked here
        if self.task_gain * self.timestep > 1:
            product, limit = apart(self.task_gain * self.timestep, 1.0, "down")
            raise ValueError(f"parameters 'task_gain' * 'timestep' must be <= {limit}; got {product}")
        if 2 * math.pi * self.servo_bandwidth * self.timestep > MAX_SERVO_STEP:
            shown, limit = apart(self.servo_bandwidth, MAX_SERVO_STEP / (2 * math.pi * self.timestep), "down")
            raise ValueError(
                f"parameter 'servo_bandwidth' must be <= {limit} Hz at timestep {self.timestep!r} s "
                f"(2 pi f timestep <= {MAX_SERVO_STEP}); got {shown}"
            )
        run_plan = plan_for(self)
        if self.duration == 0:
            auto, longest = RAMP_TIME + run_plan.path.period, infos(ArmTrackParams)["duration"][0].le
            if auto > longest:  # a slow or long path: the cost check's "lower 'duration'" did not apply to 0
                raise ValueError(
                    f"parameter 'duration' = 0 runs the {RAMP_TIME:g} s ramp and one cycle of the path, here "
                    f"{auto:.3g} s at speed {self.speed:g} m/s, more than {longest:g} s: raise 'speed', lower 'size' "
                    "or give a 'duration'"
                )
            object.__setattr__(self, "duration", auto)
        check_duration(self.duration, self.timestep)
        n = step_count(self.duration, self.timestep)
        check_run_cost(n, n + 1, 60, *RUN_COST, "raise 'timestep' or lower 'duration'")
        object.__setattr__(self, "_plan", run_plan)


def _file_key(robot: str) -> tuple:
    """The robot, and for a file its size and modification time (a changed file is planned again)."""
    if robot in robots.ROBOTS:
        return (robot,)
    info = os.stat(robot)
    return (os.path.abspath(robot), info.st_size, info.st_mtime_ns)


def plan_for(p: ArmTrackParams) -> Plan:
    """The run's plan (reference pose, path, start pose, reach check), made once per robot and path."""
    offset = (p.offset_x, p.offset_y, p.offset_z)
    cycle = RAMP_TIME + Path(p.path, p.size, p.speed, np.zeros(3), (np.zeros(3), np.zeros(3))).period
    checked = 0.0 if p.duration == 0 or p.duration >= cycle else p.duration  # 0: the ramp and one cycle
    return _plan(_file_key(p.robot), p.robot, p.path, p.size, p.speed, p.plane, offset, checked)


@functools.lru_cache(maxsize=16)
def _plan(key: tuple, robot: str, kind: str, size: float, speed: float, plane: str, offset: tuple, duration: float):
    spec = robots.resolve(robot)
    where = f"arm-track on {spec.name}" + (f" ({spec.source})" if spec.source and not spec.builtin else "")
    return plan(spec.chain(), kind, size, speed, plane, np.array(offset), duration or math.inf, where)
