"""Numbers and rotations as the text of XML attributes (MJCF and URDF): exact, and -0.0 written as 0.0."""

from __future__ import annotations

import math

import numpy as np


def quat(rot: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a rotation matrix (Shepperd's method: the largest pivot), (4,)."""
    trace = np.trace(rot)
    pivots = [trace, rot[0, 0], rot[1, 1], rot[2, 2]]
    i = int(np.argmax(pivots))
    if i == 0:
        w = math.sqrt(1 + trace) / 2
        q = [w, (rot[2, 1] - rot[1, 2]) / (4 * w), (rot[0, 2] - rot[2, 0]) / (4 * w), (rot[1, 0] - rot[0, 1]) / (4 * w)]
    elif i == 1:
        x = math.sqrt(1 + rot[0, 0] - rot[1, 1] - rot[2, 2]) / 2
        q = [(rot[2, 1] - rot[1, 2]) / (4 * x), x, (rot[0, 1] + rot[1, 0]) / (4 * x), (rot[0, 2] + rot[2, 0]) / (4 * x)]
    elif i == 2:
        y = math.sqrt(1 - rot[0, 0] + rot[1, 1] - rot[2, 2]) / 2
        q = [(rot[0, 2] - rot[2, 0]) / (4 * y), (rot[0, 1] + rot[1, 0]) / (4 * y), y, (rot[1, 2] + rot[2, 1]) / (4 * y)]
    else:
        z = math.sqrt(1 - rot[0, 0] - rot[1, 1] + rot[2, 2]) / 2
        q = [(rot[1, 0] - rot[0, 1]) / (4 * z), (rot[0, 2] + rot[2, 0]) / (4 * z), (rot[1, 2] + rot[2, 1]) / (4 * z), z]
    quat = np.array(q)  # (4,)
    return quat if quat[0] >= 0 else -quat


def num(value: float) -> str:
    """Full precision (repr round-trips exactly); -0.0 written as 0.0."""
    return repr(float(value) + 0.0)


def nums(values: np.ndarray | list[float] | tuple[float, ...]) -> str:
    return " ".join(num(v) for v in values)


def comment_line(text: str) -> str:
    """`text` safe inside an XML comment, which may not contain "--": joint names such as "x--" (robot file names
    allow letters, digits, _ . -) are written "x- -"."""
    while "--" in text:
        text = text.replace("--", "- -")
    return text
