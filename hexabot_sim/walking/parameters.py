"""A walk's parameters and what the robot can walk: ranges, gait feasibility (any legged robot); the terrain's
refusals are walking.ground's."""

from __future__ import annotations

import dataclasses
import math
from typing import Any, ClassVar

import numpy as np

from hexabot_sim import params
from hexabot_sim.budget import check_run_cost, most_rows, step_count
from hexabot_sim.control.gait import GAITS, PROFILES, Command, Gait, gaits_for
from hexabot_sim.kinematics import legged
from hexabot_sim.params import allowed, param
from hexabot_sim.walking import commands
from hexabot_sim.walking.constants import (
    CSV_FIXED_COLUMNS,
    FORCE_LEVEL_MARGIN,
    INTEGRATORS,
    MEASURE_TIME,
    RUN_COST,
    SETTLE_TIME,
    SPEED_MARGIN,
    STAND_HEIGHT_MAX,
    STAND_HEIGHT_MIN,
    TERRAIN_STEP_SECONDS,
)
from hexabot_sim.walking.ground import _plan_cycle, neutral, terrain_problem
from hexabot_sim.walking.support import least_support_margin, support_problem


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
    """Parameters of a walk (body frame: x forward, y left, z up). Each robot's subclass sets ROBOTS and `robot`, and
    the gait's choices and default (its gaits are the ones for its number of legs, control.gait.gaits_for)."""

    # The robots a walk takes (walking.robot_choice.RobotChoice: the built-in one, or a file with as many legs), and
    # the `robot` parameter naming one: each robot's subclass sets both.
    ROBOTS: ClassVar[Any]
    robot: ClassVar[str]

    gait: str = param("tripod", "", "which legs swing when", choices=tuple(GAITS))
    vx: float = param(0.1, "m/s", "commanded forward speed", ge=-1.0, le=1.0, typo=("mm/s", 1e-3))
    vy: float = param(0.0, "m/s", "commanded sideways speed (left positive)", ge=-1.0, le=1.0, typo=("mm/s", 1e-3))
    yaw_rate: float = param(0.0, "rad/s", "commanded turning rate (counter-clockwise positive)", ge=-3.0, le=3.0)
    period: float = param(1.0, "s", "gait cycle: every leg swings once per period", ge=0.2, le=10.0)
    duty: float = param(0.0, "1", "stance fraction of the cycle; 0 = the gait's own (1/2, 2/3, 5/6)", ge=0.0, lt=1.0)
    step_height: float = param(0.03, "m", "foot lift at mid-swing", ge=0.002, le=0.1, typo=("mm", 1e-3))
    stand_height: float = param(
        0.0, "m", "foot depth below the hips while standing (body height - foot radius); 0 = the robot's own "
        "(the hexabot's 0.09, a robot file's [stance] height)", ge=0.0, le=STAND_HEIGHT_MAX, typo=("mm", 1e-3),
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
    terrain_map: str = param(
        "off", "", "with sensed touchdown, each swing lands on the ground a terrain map gives under its landing point "
        "(a robot's elevation map: here the run's ground itself, off by map_error), not on the stance feet's plane",
        choices=("off", "on"),
    )  # fmt: skip
    # At most 1 cm, the rough ground's own bumps: measured (8 s), 1 cm walked (the quadbot's rough trot rolling 9.4 deg
    # peak to peak, its crawl 5.8), 2 cm did not (the trot fell, the crawl rolled 20 deg; the hexabot walked to 5 cm).
    map_error: float = param(
        0.0, "m", "the terrain map's error: Gaussian noise of this standard deviation on each of its 1 cm grid "
        "points (seed)", ge=0.0, le=0.01, typo=("mm", 1e-3),
    )  # fmt: skip
    load_sharing: str = param(
        "off", "", "stance legs yield to their touch sensors' force error, sharing the load (admittance), or hold "
        "their planned height (off), or push with a force distribution's forces through their servos (force: with "
        "feet=pad swing=quintic; not on stairs or a kerb, nor in a gait with two feet down)",
        choices=("admittance", "force", "off"),
    )  # fmt: skip
    feet: str = param(
        "rigid", "", "the feet's contact: rigid, or a compliant 0.8 mm pad (no contact bounces; use with "
        "swing=quintic)", choices=("rigid", "pad"),
    )  # fmt: skip
    swing: str = param(
        "cubic", "", "the swing's horizontal arc: cubic Hermite, or quintic (zero acceleration at lift-off and "
        "touchdown; ~20 % lower top speeds)", choices=PROFILES,
    )  # fmt: skip
    schedule: tuple = param((), "", commands.SCHEDULE_DOC, table=(commands.SCHEDULE_ALLOWED, commands.read_schedule))
    waypoints: tuple = param(
        (), "", commands.WAYPOINTS_DOC, table=(commands.WAYPOINTS_ALLOWED, commands.read_waypoints)
    )
    schedule_scale: float = param(1.0, "1", "the schedule's vx, vy and yaw_rate times this", ge=0.0, le=10.0)
    path_speed: float = param(0.1, "m/s", "the path follower's walking speed (waypoints)", gt=0.0, le=1.0)
    path_yaw_rate: float = param(0.5, "rad/s", "the path follower's largest yaw rate (waypoints)", gt=0.0, le=3.0)

    def _run_cost(self) -> tuple[float, float, float]:
        """RUN_COST: (seconds per physics step, seconds per row, bytes per row), on terrain its step's cost."""
        step_s, row_s, row_bytes = RUN_COST
        if self.on_ground() or self.slope_deg or self.roughness or self.kerb_height or self.stairs_rise:
            step_s = TERRAIN_STEP_SECONDS
        return step_s, row_s, row_bytes

    @property
    def ROBOT(self) -> WalkingRobot:
        """The robot this walk walks, read once when the parameters were made: a robot file changed or removed since
        changes nothing (an environment's resets had put the old model in the new file's stance, or refused)."""
        robot = self.__dict__.get("_robot")
        return robot if robot is not None else self.ROBOTS.resolve(self.robot)

    def longest_duration(self) -> float:
        """The longest walk [s] at this timestep that params.check_run_cost takes (its steps, memory, output and
        time limits, one row per step), at most the duration's upper bound."""
        rows = most_rows(csv_columns(self.ROBOT), *self._run_cost())
        return min((rows - 1) * self.timestep, _bound(type(self), "duration"))

    def __post_init__(self) -> None:
        object.__setattr__(self, "_robot", self.ROBOTS.resolve(self.robot))  # the file's version checked here
        own = not self.stand_height or self.stand_height == self.ROBOT.layout.stand_height
        if not self.stand_height:  # the robot's own (resolved here: everything downstream reads the number)
            object.__setattr__(self, "stand_height", self.ROBOT.layout.stand_height)
        if own and self.stand_height < STAND_HEIGHT_MIN:  # a robot file's [stance] height: not a value the user set
            raise ValueError(
                f"{self.ROBOT.name} stands {self.stand_height:g} m below its hips (its file's [stance] height), lower "
                f"than the walk's lowest stance, {STAND_HEIGHT_MIN:g} m: set stand_height ({STAND_HEIGHT_MIN:g} m or "
                "more, within the legs' reach) or give the file a taller stance"
            )
        if self.stand_height < STAND_HEIGHT_MIN:
            raise ValueError(
                f"parameter 'stand_height' must be 0 (the robot's own) or {STAND_HEIGHT_MIN:g} to "
                f"{STAND_HEIGHT_MAX:g} m (within the legs' reach); got "
                f"{self.stand_height:g}"
            )
        layout = self.ROBOT.layout  # a robot file's thick plate: the legged file checks its own [stance] height only
        if self.stand_height + layout.foot_radius <= layout.plate[2]:
            raise ValueError(
                f"parameter 'stand_height' = {self.stand_height:g} m puts the plate of {self.ROBOT.name} on the "
                f"ground: its underside is {layout.plate[2]:g} m below the hips, the ground "
                f"{self.stand_height + layout.foot_radius:g} m (stand_height + foot radius); stand_height must be more "
                f"than {layout.plate[2] - layout.foot_radius:g} m"
            )
        if self.stand_height != layout.stand_height:  # the robot's own stance is checked with its file
            self._check_servos(dataclasses.replace(layout, stand_height=self.stand_height))
        if self.duty and not self.gait_duty_range()[0] <= self.duty < 1.0:
            lo = self.gait_duty_range()[0]
            raise ValueError(
                f"parameter 'duty' for the {self.gait} gait must be {allowed(lo, 'up')} to < 1 (or 0); got {self.duty}"
            )
        if self.load_sharing == "force" and (self.stairs_rise or self.kerb_height):
            where = "stairs" if self.stairs_rise else "a kerb"
            raise ValueError(
                f"parameter 'load_sharing' = force is not for {where}: with feet on two levels its height and slope "
                "errors step (measured: the tripod fell on hexabot-stairs' steps on rigid feet; with the pad the "
                "ripple gait rolled up to 30 deg there and 15 deg at a 3 cm kerb); use load_sharing=off or admittance"
            )
        if self.terrain_map == "on":
            self._check_map_gaits()
        if self.load_sharing == "force":
            self._check_force_gaits()
            if self.level_body == "on":
                self._check_force_level()
        shortest = SETTLE_TIME + self.period + MEASURE_TIME
        if self.duration < shortest - 1e-9:
            raise ValueError(
                f"parameter 'duration' must be at least the settling time, one period (the ramp) and "
                f"{MEASURE_TIME:g} s to measure the walk: {shortest:.15g} s; got {self.duration}"
            )
        n = step_count(self.duration, self.timestep)
        step_s, row_s, row_bytes = self._run_cost()
        # The advice names what can change: the longest walk that fits, and 'timestep' only below its largest
        # (it suggested raising the timestep already at its 0.002 s maximum).
        longest = self.longest_duration()
        fix = f"lower 'duration' to at most {allowed(longest, 'down')} s at timestep {self.timestep:g} s"
        if self.timestep < _bound(type(self), "timestep"):
            fix += " or raise 'timestep'"
        check_run_cost(n, n + 1, csv_columns(self.ROBOT), step_s, row_s, row_bytes, fix)
        problem = feasibility(self)
        if problem:
            raise ValueError(problem)
        problem = commands.problem(self, feasibility, neutral(self), SETTLE_TIME)  # a schedule's or waypoints'
        if problem:
            raise ValueError(problem)
        problem = terrain_problem(self)
        if problem:
            raise ValueError(problem)

    def _fewest_down(self) -> tuple[str, int]:
        """The gait walked with the fewest feet down at once, and how many: the walk's, or with a schedule its rows'
        (a row without a gait keeps the one before; a first row's gait replaces the walk's from the start:
        walking/scene.make_controller)."""
        gaits = self.gaits()
        names = [row.gait for row in commands.setpoints(self)] if self.schedule else [self.gait]
        # An unknown gait is left out: the schedule's check refuses it, with its row.
        walked = [
            (n, gaits[n].least_down(self.duty if n == self.gait else 0.0)) for n in dict.fromkeys(names) if n in gaits
        ]
        return min(walked, key=lambda item: item[1], default=(self.gait, 3))

    def _check_map_gaits(self) -> None:
        """terrain_map=on lands the swings on the ground as the body sees it: with two feet down no stance plane
        corrects the body's tilt, which the map's landings then keep; with level_body=on the IMU levels it."""
        name, down = self._fewest_down()
        if down < 3 and self.level_body != "on":
            raise ValueError(
                f"parameter 'terrain_map' = on in a gait with {down} feet down (the {name} gait) needs level_body=on: "
                "the swings land on the map's ground as the tilted body sees it and two feet span no plane that "
                "levels it (measured on flat quadbot-trot at 0.1 m/s, 8 s: roll peak 7.4 deg against 0.4 without the "
                "map; with level_body=on 0.7 deg)"
            )

    def _check_force_gaits(self) -> None:
        """load_sharing=force distributes the weight and the body's moments over the feet down: it needs three
        (two span no plane), in every gait walked."""
        name, down = self._fewest_down()
        if down < 3:
            raise ValueError(
                f"parameter 'load_sharing' = force needs three feet down to carry the body's weight and "
                f"moments, and the {name} gait has {down} (measured on quadbot-trot at 0.1 m/s: 99 foot bounces "
                "against 42, roll 2.1 deg against 1.0, speed -3.3 % against -1.3 %); use load_sharing=off or "
                "admittance"
            )

    def _check_force_level(self) -> None:
        """load_sharing=force with level_body=on levels the body by the feet's forces alone: a gait whose planned
        body centre comes within FORCE_LEVEL_MARGIN of the edge of the feet down (the quadbot's crawl reaches it, a
        crawl without a body shift) is refused, at the walk's command and a schedule's rows'."""
        walks = [(self.gait, Command() if self.schedule or self.waypoints else self.command())]
        walks += [(row.gait, row.command) for row in commands.setpoints(self)] if self.schedule else []
        for name, cmd in dict.fromkeys(walks):
            if name not in self.gaits():
                continue  # an unknown gait is refused, with its row, by the schedule's check
            q = self if name == self.gait else unchecked(self, gait=name, duty=0.0)
            margin = least_support_margin(q, cmd)
            if margin < FORCE_LEVEL_MARGIN:
                # Outside them (a crawl on a trapezoid: 15 mm) was told "comes within 0.0 mm of their edge".
                where = (
                    f"comes within {max(margin, 0.0) * 1000:.1f} mm of their edge" if margin > -5e-5
                    else f"leaves its centre {-margin * 1000:.1f} mm outside them"
                )  # fmt: skip
                raise ValueError(
                    f"parameter 'load_sharing' = force with level_body=on needs the body's centre at least "
                    f"{FORCE_LEVEL_MARGIN * 1000:g} mm inside the feet down all through the gait, and the {name} gait "
                    f"of {self.ROBOT.name} {where} (measured on "
                    "quadbot-walk's crawl: at 0 and 1.2 mm it rolled 15-32 deg and lost 64-76 % of its speed, at 2.4 "
                    "mm and more it walked); use level_body=off, load_sharing=off or admittance, or a higher 'duty'"
                )

    def _own_height(self) -> str:
        """' (0: the robot's own)' where stand_height takes 0 (not the quadbot's, whose range starts at 0.02 m)."""
        low = params.infos(type(self))["stand_height"][0].ge
        return " (0: the robot's own)" if low == 0 else ""

    def _check_servos(self, layout: legged.Layout) -> None:
        """Refuses a stand_height at which the servos cannot hold the robot up (a robot file's torque check is at its
        own [stance] height: 0.59 N m servos that hold my_hexapod at 0.1 m gave way at stand_height 0.03 m)."""
        from hexabot_sim.kinematics import legged_file
        from hexabot_sim.kinematics.leg import IKError

        feet = max(1, layout.n_legs // 2)
        try:
            need = legged_file.standing_torque(layout, feet)
        except IKError:
            tallest = legged.tallest_stance(self.ROBOT.layout)
            if self.stand_height <= tallest:
                return  # out of reach lower down: the gait's feasibility check says so, with what to change
            # Beyond the legs' reach: stepping in place's "lengthen 'period' or lower 'step_height'" did not help.
            raise ValueError(
                f"parameter 'stand_height' = {self.stand_height:g} m is out of the legs' reach: {self.ROBOT.name}'s "
                f"feet reach their neutral points ({layout.neutral_reach:g} m out from the hips) at most "
                f"{tallest:g} m below the hips; give a lower stand_height{self._own_height()}"
            ) from None
        if need > self.ROBOT.torque_limit:
            raise ValueError(
                f"parameter 'stand_height' = {self.stand_height:g} m: the servos of {self.ROBOT.name} are too weak to "
                f"stand there: holding {layout.total_mass:.3g} kg on {feet} feet needs {need:.3g} N m, above its "
                f"torque_limit = {self.ROBOT.torque_limit:g} N m; give another stand_height{self._own_height()}"
            )

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

    def ignored(self) -> dict[str, str]:
        """The parameters this walk makes no use of, each with why and what would use it (hexabot_sim.unused refuses
        one the user set)."""
        out: dict[str, str] = {}
        if not self.stairs_rise:
            out |= dict.fromkeys(("stairs_run", "stairs_count", "stairs_distance"), "without stairs: set stairs_rise")
        if not self.kerb_height:
            out["kerb_distance"] = "without a kerb: set kerb_height"
        if not self.slope_deg:
            out["slope_heading"] = "on level ground: set slope_deg"
        if self.touchdown != "sensed":
            out["reflex"] = "with planned touchdown (the reflex reads the touch sensors): set touchdown=sensed"
        if not self.schedule:
            out["schedule_scale"] = "without a schedule: give one"
        if not self.waypoints:
            out |= dict.fromkeys(("path_speed", "path_yaw_rate"), "without waypoints: give them")
        if self.schedule or self.waypoints:
            why = (
                "with a schedule: its rows give the commands; set them there"
                if self.schedule
                else "with waypoints: the path follower gives the commands; set path_speed and path_yaw_rate"
            )
            out |= dict.fromkeys(("vx", "vy", "yaw_rate"), why)
        return out


# _cycle_problem's answers by what the cycle depends on: a sweep checks each gait for each of its other values.
_CYCLE_PROBLEMS: dict[tuple[Any, ...], str] = {}

CYCLE_CACHE_SIZE: int = 1 << 14


def _cycle_problem(p: WalkParams, cmd: Command) -> str:
    """'' if every leg can follow the planned cycle, else why not (reach, joint range or joint speed)."""
    key = (p.ROBOT, p.gait, p.duty, p.period, p.step_height, p.stand_height, p.max_joint_speed, p.swing, cmd)
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


def unchecked(p: WalkParams, **changes: object) -> WalkParams:
    """`p` with `changes`, not checked again: a schedule row's walk (rows are checked as walks of their own by
    commands.schedule_problem; dataclasses.replace would check each again, ~12 ms a row)."""
    q = object.__new__(type(p))
    for field in dataclasses.fields(p):
        object.__setattr__(q, field.name, changes.get(field.name, getattr(p, field.name)))
    if "robot" not in changes:
        object.__setattr__(q, "_robot", p.ROBOT)
    return q


def feasibility(p: WalkParams) -> str:
    """'' if the legs can deliver the command (vx, vy, yaw_rate; only stepping in place with a schedule or waypoints,
    which replace them), else a one-line reason with the largest feasible command."""
    if not math.isfinite(p.vx + p.vy + p.yaw_rate):
        return "vx, vy and yaw_rate must be finite"
    first = commands.setpoints(p)[0].gait if p.schedule else p.gait
    if first != p.gait:  # the walk starts in its schedule's first gait, at that gait's duty (scene.make_controller)
        if first not in p.gaits():
            return ""  # refused, with its row, by the schedule's check
        p = unchecked(p, gait=first, duty=0.0)  # `p` in that gait at its own duty
    support = support_problem(p)
    if support:
        return support
    standing = _cycle_problem(p, Command())
    if standing:
        faster = " (or raise 'max_joint_speed')" if standing.startswith("joints would turn") else ""
        # A duty of one's own shortens the swing to (1 - duty) x period: say so (duty=0.99 was blamed on the rest).
        duty = f", duty {p.duty:g}: a swing of {(1 - p.duty) * p.period:.3g} s" if p.duty else ""
        fixes = (  # 'lower duty' only above the gait's own, the least it takes
            "lengthen 'period', lower 'duty' or lower 'step_height'"
            if p.duty > p.gaits()[p.gait].duty
            else ("lengthen 'period' or lower 'step_height'")
        )
        return (
            f"even stepping in place is infeasible with the {p.gait} gait at period {p.period:g} s "
            f"(stand_height {p.stand_height:g} m, step_height {p.step_height:g} m{duty}): {standing}; {fixes}{faster}"
        )
    if p.schedule or p.waypoints:  # they replace vx, vy and yaw_rate (commands.problem checks their commands)
        return ""
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
    # The longest stride: the foot whose ground velocity (the body's, plus the turn's at its neutral point) is fastest.
    feet = neutral(p)
    stride = float(np.max(np.hypot(p.vx - p.yaw_rate * feet[:, 1], p.vy + p.yaw_rate * feet[:, 0]))) * duty * p.period
    if problem.startswith("joints would turn"):
        # The swing covers the stance's stride in (1 - duty) / duty of its time, whatever the period.
        # A duty of one's own: lowering it is the first fix (a tripod at duty 0.8 was told of other gaits only); the
        # gaits with less stance are named from the robot's (the crawl was told of none; the tripod, which has none,
        # was told to take one).
        own = p.gaits()[p.gait].duty
        faster = [name for name, g in sorted(p.gaits().items(), key=lambda item: -item[1].duty) if g.duty < own]
        fixes = [f"a lower 'duty' (the gait's own: {own:.3g})"] * (p.duty > own)
        fixes += ["a gait with less stance"] * bool(faster)
        # The swing's lift turns the joints too: step_height=0.1 was told only of the command (found by fuzzing).
        slowest = f"no gait has less stance than the {p.gait}: lower the command or 'step_height', or raise "
        slowest += "'max_joint_speed'"
        advice = (
            f"the {p.gait} gait's swing moves the foot over the ground {duty / (1 - duty):.2g}x as fast as the body "
            "whatever the period: "
            + (f"{' or '.join(fixes)} is faster" if fixes else slowest)
            + (f" ({', '.join(faster)})" if faster else "")
        )
    else:
        advice = "a shorter 'period' shortens the stride" + (" (the turn's arc)" if p.yaw_rate else "")
    return (
        f"the legs cannot deliver this command at period {p.period:g} s (stride {stride:.3g} m): {problem}; "
        f"the largest feasible in this direction is {', '.join(parts) or 'standing still'}; {advice}"
    )


def _bound(cls: type, name: str) -> float:
    """A parameter's upper bound (its `le`), as `hexabot-sim list` shows it."""
    return params.infos(cls)[name][0].le


def csv_columns(robot: WalkingRobot) -> int:
    """Columns of a walk's timeseries.csv (the run-cost estimate counts them)."""
    return CSV_FIXED_COLUMNS + 6 * robot.layout.n_legs
