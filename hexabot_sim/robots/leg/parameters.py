"""The leg scenarios' parameters (leg-step, leg-sweep) and the workspace check they make, apart from the
simulation: `hexabot-sim list` reads them without MuJoCo (the scenario modules are leg/step.py, leg/step_sweep.py)."""

from __future__ import annotations

import dataclasses
import math
import os

import numpy as np

from hexabot_sim.budget import CSV_BYTES_PER_VALUE, check_budget, check_duration, check_run_cost, step_count
from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics import leg as leg_kin
from hexabot_sim.kinematics import robots
from hexabot_sim.params import apart, param
from hexabot_sim.robots.leg.model import LEG_ROBOT, MAX_LENGTH, MIN_LENGTH, leg_geometry

GEOMETRY = leg_kin.LegGeometry()  # the default lengths, those models/leg.xml is written with (tested against it)
INTEGRATORS = ("RK4", "implicitfast", "Euler", "implicit")
# Parameter ranges. Each link is 10 mm to 1 m long, so a start point is at most 3 m from the hip (the
# cross-check then asks whether the given lengths reach it); the default leg at 5 rad/s moves its foot
# at most ~1.2 m/s: a commanded foot speed above 1 m/s is no step (100 typed for 100 mm/s would be 100 m/s).
REACH: float = 3 * MAX_LENGTH  # [m] bound on each start coordinate
MM: tuple[str, float] = ("mm", 1e-3)  # the unit users type by mistake for a length in m
MAX_FOOT_SPEED: float = 1.0  # [m/s]
MIN_OMEGA, MAX_OMEGA = 0.01, 20.0  # [rad/s] periods from 0.3 s to 10.5 min
MAX_PHASE_STEP: float = 0.5  # [rad] largest omega * timestep: >= 12.6 control periods per command cycle
CSV_COLUMNS: int = 25  # columns of timeseries.csv
# Cost of a run for budget.check_run_cost, measured on the 2-core development machine: seconds per
# physics step (controller + mj_step), seconds per recorded row (site replay, derived columns; the
# CSV is counted apart), peak bytes per recorded row.
RUN_COST: tuple[float, float, float] = (15e-6, 100e-6, 600.0)


def _length_doc(link: str, default: float) -> str:
    """`hexabot-sim list`'s line of a link length: 0 is the robot's own, else at least MIN_LENGTH."""
    return f"{link} length; 0 = the robot's (leg: {default:g}), else {MIN_LENGTH:g} m or more"


DYNAMIC_ONLY: tuple[str, ...] = ("gravity_compensation", "substeps", "integrator")  # LegParams of the dynamic mode


@dataclasses.dataclass(frozen=True)
class LegParams:
    """Leg, controller and simulation settings shared by leg-step and leg-sweep (hip frame: x forward, z up)."""

    profile: str = param(
        "sine", "", "sine: v = A sin wt (report; x from x0 to x0 + 2A/w); cosine: v = A cos wt (symmetric)",
        choices=("sine", "cosine"),
    )  # fmt: skip
    mode: str = param(
        "dynamic", "", "dynamic: servos + MuJoCo dynamics; kinematic: q imposed (report's Simulink)",
        choices=("dynamic", "kinematic"),
    )  # fmt: skip
    max_joint_speed: float = param(
        5.0, "rad/s", "limit on every joint speed", ge=1e-3, le=100.0, typo=("deg/s", math.pi / 180)
    )
    max_joint_acceleration: float = param(
        50.0, "rad/s^2", "limit on every commanded joint acceleration", ge=1e-2, le=1e5
    )
    task_gain: float = param(50.0, "1/s", "K: feedback on the foot position error; K * timestep <= 1", ge=0.0, le=1e4)
    sigma_threshold: float = param(
        0.01, "m/rad", "smallest singular value of J below which DLS damps", ge=1e-6, le=0.1, typo=("mm/rad", 1e-3)
    )
    max_damping: float = param(
        0.01, "m/rad", "DLS damping lambda reached at a singularity", ge=0.0, le=0.1, typo=("mm/rad", 1e-3)
    )
    robot: str = param("leg", "", "the leg's DH table: leg (report 000) or a file of its form", name_or_file=LEG_ROBOT)
    l1: float = param(0.0, "m", _length_doc("coxa", 0.05), ge=0.0, le=MAX_LENGTH, typo=MM)
    l2: float = param(0.0, "m", _length_doc("femur", 0.1), ge=0.0, le=MAX_LENGTH, typo=MM)
    l3: float = param(0.0, "m", _length_doc("tibia", 0.1), ge=0.0, le=MAX_LENGTH, typo=MM)
    start_x: float = param(
        0.05, "m", "start foot position in the hip frame (under the femur axis)", ge=-REACH, le=REACH, typo=MM
    )
    start_y: float = param(0.0, "m", "start foot position in the hip frame", ge=-REACH, le=REACH, typo=MM)
    start_z: float = param(
        -0.08, "m", "start foot position in the hip frame (80 mm below the hip)", ge=-REACH, le=REACH, typo=MM
    )
    gravity_compensation: str = param("on", "", "servo feedforward of the exact gravity torque", choices=("on", "off"))
    timestep: float = param(0.001, "s", "control period (the controller runs once per timestep)", ge=1e-6, le=0.1)
    substeps: int = param(1, "1", "MuJoCo steps per control period (physics dt = timestep / substeps)", ge=1, le=1000)
    integrator: str = param("RK4", "", "MuJoCo integrator (dynamic mode)", choices=INTEGRATORS)

    def __post_init__(self) -> None:
        if self.task_gain * self.timestep > 1:
            product, limit = apart(self.task_gain * self.timestep, 1.0, "down")
            raise ValueError(
                f"parameters 'task_gain' * 'timestep' must be <= {limit} (the foot error would overshoot every control "
                f"period); got {self.task_gain!r} 1/s * {self.timestep!r} s = {product}"
            )
        if self.mode == "kinematic":  # q is imposed: no servos, no MuJoCo steps (they were silently ignored)
            for field in dataclasses.fields(LegParams):
                value = getattr(self, field.name)
                if field.name in DYNAMIC_ONLY and value != field.default:
                    raise ValueError(
                        f"parameter '{field.name}' = {value!r} acts in mode=dynamic only (kinematic imposes q, "
                        f"without servos or MuJoCo steps); set mode=dynamic or leave it at {field.default!r}"
                    )
        for name in ("l1", "l2", "l3"):
            if 0 < getattr(self, name) < MIN_LENGTH:
                raise ValueError(
                    f"parameter '{name}' must be 0 (the robot's) or {MIN_LENGTH:g} to {MAX_LENGTH:g} m; "
                    f"got {getattr(self, name)!r}"
                )
        robot = leg_geometry(robots.resolve(self.robot))
        geom = leg_kin.LegGeometry(*(getattr(self, n) or getattr(robot, n) for n in ("l1", "l2", "l3")))
        object.__setattr__(self, "_geometry", geom)  # resolved once: a robot file is read here, not per use
        start = (self.start_x, self.start_y, self.start_z)
        if not reachable(np.array(start), self.geometry):
            raise ValueError(
                f"parameters 'start_x', 'start_y', 'start_z': the start point {start} m is outside the workspace of "
                f"the leg l1, l2, l3 = {geom.l1!r}, {geom.l2!r}, {geom.l3!r} m or reachable only outside the joint "
                f"ranges (coxa, femur within +-90 deg, tibia 0..160 deg)"
            )

    @property
    def geometry(self) -> leg_kin.LegGeometry:
        """The leg's link lengths: the robot's, each replaced by l1, l2, l3 where they are not 0."""
        return self._geometry


@dataclasses.dataclass(frozen=True)
class LegStepParams(LegParams):
    """Parameters of the leg-step scenario."""

    amplitude: float = param(
        0.05, "m/s", "A in v_x = A sin(omega t) (report: 10, 50, 100, 80 mm/s)", ge=-MAX_FOOT_SPEED, le=MAX_FOOT_SPEED,
        typo=("mm/s", 1e-3),
    )  # fmt: skip
    omega: float = param(
        1.0, "rad/s", "omega of the velocity command (report: 1 and pi/6)", ge=MIN_OMEGA, le=MAX_OMEGA,
        typo=("deg/s", math.pi / 180),
    )  # fmt: skip
    duration: float = param(
        0.0, "s", "simulated time; 0 = two periods of the command, 4 pi / omega", ge=0.0, le=86400.0
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.duration == 0:
            object.__setattr__(self, "duration", 4 * math.pi / self.omega)
        check_command(self.omega, self.timestep)
        check_duration(self.duration, self.timestep)
        n = step_count(self.duration, self.timestep)
        check_run_cost(
            n * (self.substeps if self.mode == "dynamic" else 1), n + 1, CSV_COLUMNS, *RUN_COST,
            "raise 'timestep', lower 'duration' or 'substeps'",
        )  # fmt: skip


def check_command(omega: float, timestep: float) -> None:
    """The control period must sample the command finely enough (raises ValueError)."""
    if omega * timestep > MAX_PHASE_STEP:
        product, limit = apart(omega * timestep, MAX_PHASE_STEP, "down")
        raise ValueError(
            f"parameters 'omega' * 'timestep' must be <= {limit} rad (at least "
            f"{2 * math.pi / MAX_PHASE_STEP:.0f} control periods per cycle of the command); "
            f"got {omega!r} rad/s * {timestep!r} s = {product} rad"
        )


# Joint ranges (coxa, femur, tibia) [rad] from the leg's DH table; tests check them against models/leg.xml.
JOINT_LOWER = np.array([j.lower for j in robots.get("leg").chain().joints])
JOINT_UPPER = np.array([j.upper for j in robots.get("leg").chain().joints])


def reachable(point: np.ndarray, geom: leg_kin.LegGeometry = GEOMETRY) -> bool:
    """True if some IK branch puts the foot at `point` (hip frame) with every joint inside its range."""
    try:
        branches = leg_kin.ik(point, geom, q1=0.0)  # q1 = 0 on the coxa axis, where any q1 reaches it
    except UsageError:
        return False
    return any(np.all(q >= JOINT_LOWER - 1e-12) and np.all(q <= JOINT_UPPER + 1e-12) for q in branches)


# Grid columns written to grid.csv, from each cell's leg-step metrics.
CELL_METRICS = (
    "max_lateral_deviation",
    "max_vertical_deviation",
    "max_x_error",
    "min_abs_det_j",
    "min_sigma",
    "max_joint_speed_reached",
    "singular_duration",
    "excursion_forward",
    "reach_forward",
)


MAX_CELLS: int = 400  # grid cells (amplitudes x omegas)
MAX_WORKERS: int = 64  # parallel processes; more than the cells or the cores only costs memory


@dataclasses.dataclass(frozen=True)
class LegSweepParams(LegParams):
    """Parameters of the leg-sweep scenario: a grid of leg-step runs over amplitude x omega."""

    amplitudes: tuple = param(
        (0.01, 0.02, 0.03, 0.04, 0.05, 0.06, 0.07, 0.08, 0.09, 0.10),
        "m/s", "grid of amplitudes A (report: 10, 50, 100 mm/s at 1 rad/s, 80 mm/s at 1 and pi/6)",
        gt=0.0, le=MAX_FOOT_SPEED, typo=("mm/s", 1e-3),
    )  # fmt: skip
    omegas: tuple = param(
        (math.pi / 6, 0.75, 1.0, 1.5, 2.0, 3.0), "rad/s", "grid of omegas (comma-separated)",
        ge=MIN_OMEGA, le=MAX_OMEGA, typo=("deg/s", math.pi / 180),
    )  # fmt: skip
    periods: float = param(2.0, "1", "simulated periods of the command per cell", gt=0.0, le=100.0)
    workers: int = param(0, "1", "parallel processes; 0 = one per core", ge=0, le=MAX_WORKERS)
    mode: str = param(
        "kinematic", "", "kinematic (default here: the reports' setup, fastest) or dynamic",
        choices=("dynamic", "kinematic"),
    )  # fmt: skip

    def __post_init__(self) -> None:
        super().__post_init__()
        for name in ("amplitudes", "omegas"):  # a value twice made the same cell twice (sweep --grid refuses it)
            values = getattr(self, name)
            twice = next((v for i, v in enumerate(values) if v in values[:i]), None)
            if twice is not None:
                raise ValueError(f"parameter {name!r}: the value {twice:g} appears twice; give each value once")
        cells = len(self.amplitudes) * len(self.omegas)
        if cells > MAX_CELLS:
            raise ValueError(
                f"the grid must have at most {MAX_CELLS} cells (amplitudes x omegas); "
                f"got {len(self.amplitudes)} x {len(self.omegas)} = {cells}"
            )
        fastest = max(self.omegas)
        check_command(fastest, self.timestep)
        if self.periods * 2 * math.pi / fastest < self.timestep:
            last, least = apart(self.periods * 2 * math.pi / fastest, self.timestep, "up")
            raise ValueError(
                f"parameter 'periods' must give every cell at least one 'timestep' ({least} s); "
                f"{self.periods!r} periods at omega = {fastest!r} rad/s last {last} s"
            )
        # The whole grid's cost: cells run `parallel` at a time, each holding its own recorded rows.
        n = [step_count(self.periods * 2 * math.pi / w, self.timestep) for w in self.omegas]
        per_period = self.substeps if self.mode == "dynamic" else 1
        step_s, row_s, row_bytes = RUN_COST
        parallel = min(self.workers or os.cpu_count() or 1, cells)
        check_budget(
            len(self.amplitudes) * sum(k * per_period for k in n),
            parallel * (max(n) + 1) * row_bytes,
            cells * (len(CELL_METRICS) + 5) * CSV_BYTES_PER_VALUE,
            len(self.amplitudes) * sum(k * per_period * step_s + (k + 1) * row_s for k in n) / parallel,
            "use fewer cells, fewer 'periods' or a larger 'timestep'",
        )
        for a in self.amplitudes:  # every cell is a valid leg-step run
            for w in self.omegas:
                try:
                    self.cell(a, w)
                except ValueError as e:
                    raise ValueError(f"grid cell amplitude = {a:g} m/s, omega = {w:g} rad/s: {e}") from None

    def cell(self, amplitude: float, omega: float) -> LegStepParams:
        """The leg-step parameters of one grid cell."""
        common = {f.name: getattr(self, f.name) for f in dataclasses.fields(LegParams)}
        return LegStepParams(**common, amplitude=amplitude, omega=omega, duration=self.periods * 2 * math.pi / omega)
