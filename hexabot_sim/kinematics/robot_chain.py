"""A robot file's checked rows (robot_file.py) as a SerialChain: the joints' DH rows, fixed rows after the last joint
multiplied into the tool, the base and tool frames, with the lengths' values (the file's or those --set gives)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics.chain import Joint, SerialChain


def cos_sin(angle: float, unit: str) -> tuple[float, float]:
    """cos and sin, exact at quarter turns (a tool turned by 90 deg has exact 0 and 1 entries)."""
    quarter = angle / (90.0 if unit == "deg" else math.pi / 2)
    if quarter == round(quarter):
        return ((1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0))[round(quarter) % 4]
    rad = math.radians(angle) if unit == "deg" else angle
    return math.cos(rad), math.sin(rad)


def rx(c: float, s: float) -> np.ndarray:
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def ry(c: float, s: float) -> np.ndarray:
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rz(c: float, s: float) -> np.ndarray:
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def value(field: float | tuple[float, str], values: Mapping[str, Any]) -> float:
    """A distance field's value in [m]: a number, or ± a named length (a Length's default, or a value by name)."""
    if isinstance(field, tuple):
        sign, ref = field
        length = values[ref]
        return sign * getattr(length, "default", length)  # a Length's default, or a value by name
    return field


def joint(row: Mapping[str, Any], values: Mapping[str, float]) -> Joint:
    kind = "revolute" if row["type"] == "fixed" else row["type"]
    lower = upper = None
    if "lower" in row:
        lower, upper = value(row["lower"], values), value(row["upper"], values)
    return Joint(row["name"], kind, row["theta"], value(row["d"], values), value(row["a"], values), row["alpha"],
                 lower, upper)  # fmt: skip


def transform(frame: tuple[tuple[Any, ...], np.ndarray], values: Mapping[str, float]) -> np.ndarray:
    xyz, rot = frame
    t = np.eye(4)  # (4, 4)
    t[:3, :3] = rot
    t[:3, 3] = [value(v, values) for v in xyz]
    return t + 0.0  # no -0.0 entries (they would print as -0.0 in JSON)


def build(
    name: str,
    convention: str,
    rows: tuple[dict[str, Any], ...],
    tool: tuple[tuple[Any, ...], np.ndarray],
    base: tuple[tuple[Any, ...], np.ndarray],
    values: Mapping[str, float],
    source: str,
) -> SerialChain:
    """The chain: the joints' rows; fixed rows after the last joint are multiplied into the tool."""
    for row in rows:  # a slide's range between named lengths, with the lengths --set gives (the file's are checked)
        if "lower" in row and not value(row["lower"], values) < value(row["upper"], values):
            lo, hi = value(row["lower"], values), value(row["upper"], values)
            raise UsageError(
                f"robot file {source}: {row['where']}: with these lengths its range is empty: 'lower' ({lo:g} m) "
                f"must be less than 'upper' ({hi:g} m)"
            )
    joints = tuple(joint(row, values) for row in rows if row["type"] != "fixed")
    tool_t = transform(tool, values)
    fixed = [joint(row, values).transform(0.0, convention) for row in rows if row["type"] == "fixed"]
    if fixed:
        tool_t = np.linalg.multi_dot([*fixed, tool_t]) if len(fixed) > 1 else fixed[0] @ tool_t
        tool_t = tool_t + 0.0
    return SerialChain(name, joints, convention, base=transform(base, values), tool=tool_t)


def check_not_degenerate(chain: SerialChain, source: str, least: float) -> SerialChain:
    """`chain`, unless its links, offsets, strokes and tool offset are all zero (or add up to less than LENGTH_MIN):
    then it cannot move its tool, and it is refused (with the file's lengths, or with those set by --set)."""
    size = sum(abs(j.a) + abs(j.d) for j in chain.joints) + float(np.linalg.norm(chain.tool[:3, 3]))
    size += sum(abs(j.upper or 0.0) + abs(j.lower or 0.0) for j in chain.joints if j.prismatic)
    if size == 0 and not any(j.prismatic for j in chain.joints):
        raise UsageError(
            f"robot file {source}: every link length, offset and tool offset is 0, so the tool point never moves; "
            "give at least one 'a', 'd' or tool 'xyz' a length"
        )
    if 0 < size < least and not any(j.prismatic for j in chain.joints):  # e.g. a = 1e-300: a point, no arm
        raise UsageError(
            f"robot file {source}: the link lengths, offsets and tool offset add up to {size:.3g} m, less than "
            f"{least * 1000:g} mm: the tool point barely moves and no tolerance means anything at that scale"
        )
    return chain
