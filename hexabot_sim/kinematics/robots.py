"""The package's robots: the seed reports' chains, each a robot file in kinematics/arms/ (one source of truth)."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from hexabot_sim.errors import UsageError, printable
from hexabot_sim.kinematics import robot_file
from hexabot_sim.kinematics.robot_file import LENGTH_MAX, LENGTH_MIN, Length, RobotSpec

__all__ = ["LENGTH_MAX", "LENGTH_MIN", "ROBOTS", "Length", "RobotSpec", "get", "resolve", "rrp_report_pose"]

ORDER = ("rrp", "elbow", "stanford", "scara", "leg")  # as listed to the user (reports 001, 003, 004, 000)


def _load() -> dict[str, RobotSpec]:
    files = robot_file.builtin_files()
    missing = [name for name in ORDER if name not in files]
    if missing:  # a broken install, not a user error
        raise ImportError(f"hexabot_sim's robot files are missing: {', '.join(missing)} in {robot_file.ARMS_DIR}")
    names = [*ORDER, *sorted(set(files) - set(ORDER))]
    return {name: robot_file.read(files[name], builtin=True) for name in names}


ROBOTS: dict[str, RobotSpec] = _load()


def get(name: str) -> RobotSpec:
    """The package's robot called `name`."""
    try:
        return ROBOTS[name]
    except KeyError:
        raise UsageError(f"unknown robot '{printable(name)}'; known: {', '.join(ROBOTS)}") from None


def resolve(robot: str | os.PathLike[str] | RobotSpec) -> RobotSpec:
    """A robot by name (the package's) or by the path of a robot file (.toml), read and checked once.

    Raises:
        UsageError: An unknown name, or any problem with the file (one line naming the file and the field).
    """
    if isinstance(robot, RobotSpec):
        return robot
    text = os.fspath(robot) if isinstance(robot, (str, os.PathLike)) else None
    if not isinstance(text, str):  # an int, None, bytes: pathlib's TypeError, not one line
        raise UsageError(
            f"a robot is one of {', '.join(ROBOTS)}, the path of a robot file (str or os.PathLike) or a RobotSpec; "
            f"got {type(robot).__name__}"
        )
    if text in ROBOTS:
        return ROBOTS[text]
    path = Path(text)
    if text.endswith(".toml") or os.sep in text or (os.altsep and os.altsep in text) or path.exists():
        if not path.exists():
            raise UsageError(f"robot file {printable(text)}: no such file")
        return robot_file.read(path)
    raise UsageError(
        f"unknown robot '{printable(text)}'; known: {', '.join(ROBOTS)}, or the path of a robot file (.toml)"
    )


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
