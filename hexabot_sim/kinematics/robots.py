"""The seed reports' kinematic chains as DH tables with named, documented link lengths."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping

import numpy as np

from hexabot_sim.errors import UsageError, lookup
from hexabot_sim.kinematics.chain import Joint, SerialChain

HALF_PI = math.pi / 2
# Every link length and offset lies in [LENGTH_MIN, LENGTH_MAX] in [m] (offsets with allow_zero may also be 0):
# from a millimetre (below it an arm is a point and relative tolerances lose meaning) to ten metres (no course
# robot is larger; products of lengths stay far from overflow and underflow).
LENGTH_MIN: float = 1e-3
LENGTH_MAX: float = 10.0


@dataclasses.dataclass(frozen=True)
class Length:
    """A link-length parameter of a robot."""

    default: float
    doc: str
    allow_zero: bool = False  # offsets may be 0; link lengths must be > 0

    def allowed(self) -> str:
        """The allowed values as text, e.g. '0 or 0.001 to 10 m'."""
        return f"{'0 or ' if self.allow_zero else ''}{LENGTH_MIN:g} to {LENGTH_MAX:g} m"

    def accepts(self, value: object) -> bool:
        """Whether `value` is an allowed length in [m]."""
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return False
        return (self.allow_zero and value == 0) or LENGTH_MIN <= value <= LENGTH_MAX


@dataclasses.dataclass(frozen=True)
class RobotSpec:
    """A robot: its parameters and the function that builds its chain from them."""

    name: str
    summary: str
    lengths: Mapping[str, Length]
    build: Callable[[Mapping[str, float]], SerialChain]
    joint_units: tuple[str, ...]  # "rad" or "m" per joint

    def chain(self, overrides: Mapping[str, float] | None = None) -> SerialChain:
        """The chain with default lengths replaced by `overrides` (validated)."""
        values = {name: spec.default for name, spec in self.lengths.items()}
        for name, value in (overrides or {}).items():
            if name not in self.lengths:
                raise UsageError(f"unknown length '{name}' for {self.name}; known: {', '.join(self.lengths)}")
            length = self.lengths[name]
            if not length.accepts(value):
                raise UsageError(f"length '{name}' of {self.name} must be {length.allowed()}; got {value!r}")
            values[name] = float(value)
        return self.build(values)


def _rrp(p: Mapping[str, float]) -> SerialChain:
    # Report 001: H = Rz(q1) Tz(d1) Ry(-q2) Tx(a2) Tx(d3). As standard DH: z1 = -y of Rz(q1) (alpha1 = +pi/2),
    # q2 turns x2 into the prismatic direction (theta offset pi/2, alpha2 = +pi/2), d3 slides with offset a2.
    joints = (
        Joint("q1", theta=0.0, d=p["d1"], a=0.0, alpha=HALF_PI),
        Joint("q2", theta=HALF_PI, d=0.0, a=0.0, alpha=HALF_PI),
        Joint("d3", kind="prismatic", d=p["a2"], lower=-p["a2"], upper=2.0),
    )
    # Tool: the report's frame Rz(q1) Ry(-q2) differs from DH frame 3 by a constant rotation (x3 = z, z3 = x,
    # y3 = -y of the report's frame); tests check fk == H at random q.
    tool = np.array([[0.0, 0.0, 1.0, 0.0], [0.0, -1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
    return SerialChain("rrp", joints, "standard", tool=tool)


def _elbow(p: Mapping[str, float]) -> SerialChain:
    # Report 003 problem 1 (Spong's elbow manipulator with a shoulder offset d); tool = wrist centre.
    joints = (
        Joint("theta1", d=p["d1"], alpha=HALF_PI),
        Joint("theta2", d=p["d"], a=p["a2"]),
        Joint("theta3", a=p["a3"]),
    )
    return SerialChain("elbow", joints, "standard")


def _stanford(p: Mapping[str, float]) -> SerialChain:
    # Report 003 problem 2: A1..A6 of the Stanford arm (d3 prismatic, spherical wrist, tool at d6).
    joints = (
        Joint("theta1", alpha=-HALF_PI),
        Joint("theta2", d=p["d2"], alpha=HALF_PI),
        Joint("d3", kind="prismatic", lower=0.0, upper=1.0),
        Joint("theta4", alpha=-HALF_PI),
        Joint("theta5", alpha=HALF_PI),
        Joint("theta6", d=p["d6"]),
    )
    return SerialChain("stanford", joints, "standard")


def _scara(p: Mapping[str, float]) -> SerialChain:
    # Standard RRPR SCARA (Spong): alpha2 = pi points z2 down, d3 slides down, theta4 turns the tool.
    joints = (
        Joint("theta1", d=p["d1"], a=p["a1"]),
        Joint("theta2", a=p["a2"], alpha=math.pi),
        Joint("d3", kind="prismatic", lower=0.0, upper=p["d1"]),
        Joint("theta4", d=p["d4"]),
    )
    return SerialChain("scara", joints, "standard")


def _leg(p: Mapping[str, float]) -> SerialChain:
    # Report 000 Table 1 (modified DH); the foot is Tx(L3) from frame 3.
    joints = (
        Joint("coxa", lower=-HALF_PI, upper=HALF_PI),
        Joint("femur", a=p["l1"], alpha=-HALF_PI, lower=-HALF_PI, upper=HALF_PI),
        Joint("tibia", a=p["l2"], lower=0.0, upper=math.radians(160)),
    )
    return SerialChain("leg", joints, "modified", tool=_tx(p["l3"]))


def _rz(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def _ry(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s, 0], [0, 1, 0, 0], [-s, 0, c, 0], [0, 0, 0, 1.0]])


def _tx(x: float) -> np.ndarray:
    t = np.eye(4)
    t[0, 3] = x
    return t


def _tz(z: float) -> np.ndarray:
    t = np.eye(4)
    t[2, 3] = z
    return t


def rrp_report_pose(q: np.ndarray, d1: float, a2: float) -> np.ndarray:
    """Report 001's H = Rz(q1) Tz(d1) Ry(-q2) Tx(a2) Tx(d3), written out as the report does (for tests)."""
    return _rz(q[0]) @ _tz(d1) @ _ry(-q[1]) @ _tx(a2) @ _tx(q[2])


ROBOTS: dict[str, RobotSpec] = {
    spec.name: spec
    for spec in (
        RobotSpec(
            "rrp",
            "RRP arm of report 001: H = Rz(q1) Tz(d1) Ry(-q2) Tx(a2) Tx(d3)",
            {"d1": Length(1.0, "height of the q2 axis above the base (report: 1 m)"),
             "a2": Length(1.0, "offset of the prismatic stage along its axis (report: 1 m)")},
            _rrp,
            ("rad", "rad", "m"),
        ),
        RobotSpec(
            "elbow",
            "elbow manipulator with shoulder offset d (report 003 problem 1); tool = wrist centre",
            {"d1": Length(0.4, "height of the shoulder"), "d": Length(0.1, "shoulder offset", allow_zero=True),
             "a2": Length(0.35, "upper arm"), "a3": Length(0.3, "forearm, elbow to wrist centre")},
            _elbow,
            ("rad", "rad", "rad"),
        ),
        RobotSpec(
            "stanford",
            "Stanford arm, 6 DOF, d3 prismatic, spherical wrist (report 003 problem 2)",
            {"d2": Length(0.154, "shoulder offset (Spong: 0.154 m)", allow_zero=True),
             "d6": Length(0.263, "wrist centre to tool (Spong: 0.263 m)", allow_zero=True)},
            _stanford,
            ("rad", "rad", "m", "rad", "rad", "rad"),
        ),
        RobotSpec(
            "scara",
            "SCARA, RRPR (report 004's title robot): two horizontal links, vertical slide, tool roll",
            {"d1": Length(0.4, "height of the first link"), "a1": Length(0.35, "first link"),
             "a2": Length(0.3, "second link"), "d4": Length(0.05, "tool length below the slide", allow_zero=True)},
            _scara,
            ("rad", "rad", "m", "rad"),
        ),
        RobotSpec(
            "leg",
            "hexabot leg of report 000 (modified DH, Table 1); tool = foot",
            {"l1": Length(0.05, "coxa"), "l2": Length(0.10, "femur"), "l3": Length(0.10, "tibia")},
            _leg,
            ("rad", "rad", "rad"),
        ),
    )
}  # fmt: skip


def get(name: str) -> RobotSpec:
    """The robot called `name`."""
    return lookup(ROBOTS, name, "robot")
