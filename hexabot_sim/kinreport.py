"""What `hexabot-sim kin ROBOT` reports: DH table, T0n, J, det or manipulability, singular flags, IK branches."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics import inverse, robots


def parse_numbers(text: str, what: str) -> list[float]:
    """'0.1,0.2,-1' -> [0.1, 0.2, -1.0]; a one-line UsageError naming `what` otherwise."""
    parts = [p.strip() for p in text.split(",")]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise UsageError(f"{what} must be comma-separated numbers; got {text!r}") from None
    if not all(math.isfinite(v) for v in values):
        raise UsageError(f"{what} must be finite numbers; got {text!r}")
    return values


def describe(robot: str, lengths: Mapping[str, float]) -> dict[str, Any]:
    """The robot's DH table, lengths and singular sets."""
    spec = robots.get(robot)
    chain = spec.chain(lengths)
    rows = []
    for joint, unit in zip(chain.joints, spec.joint_units, strict=True):
        rows.append(
            {"joint": joint.name, "kind": joint.kind, "unit": unit, "theta": joint.theta, "d": joint.d,
             "a": joint.a, "alpha": joint.alpha, "lower": joint.lower, "upper": joint.upper}
        )  # fmt: skip
    return {
        "robot": robot,
        "summary": spec.summary,
        "convention": chain.convention,
        "lengths": _lengths(spec, lengths),
        "dh": rows,
        "tool": chain.tool.tolist(),
        "singular_sets": inverse.SINGULAR_SETS[robot],
    }


def _lengths(spec: robots.RobotSpec, overrides: Mapping[str, float]) -> dict[str, float]:
    return {name: float(overrides.get(name, length.default)) for name, length in spec.lengths.items()}


def at_configuration(robot: str, q: Sequence[float], lengths: Mapping[str, float]) -> dict[str, Any]:
    """T0n, the 6xn Jacobian, det or manipulability, and which singular conditions hold at q."""
    spec = robots.get(robot)
    chain = spec.chain(lengths)
    if len(q) != chain.n:
        names = ", ".join(f"{j.name} [{u}]" for j, u in zip(chain.joints, spec.joint_units, strict=True))
        raise UsageError(f"{robot} has {chain.n} joints ({names}); got {len(q)} values")
    qa = np.array(q, dtype=float)
    kind, value = inverse.det_or_manipulability(robot, qa, lengths)
    flags = inverse.singularities(robot, qa, lengths)
    return {
        "q": qa.tolist(),
        "T0n": chain.fk(qa).tolist(),
        "J": chain.jacobian(qa).tolist(),
        kind: value,
        "singular": flags,
        "is_singular": any(flags.values()),
    }


def solve(robot: str, target: Sequence[float], lengths: Mapping[str, float]) -> dict[str, Any]:
    """Every closed-form IK branch for `target`, each with its FK residual."""
    spec = robots.get(robot)
    chain = spec.chain(lengths)
    goal: np.ndarray
    if robot == "stanford":
        if len(target) != 6:
            raise UsageError(f"stanford needs --target x,y,z,roll,pitch,yaw (m, rad: R = Rz Ry Rx); got {len(target)}")
        goal = _pose(target)
    else:
        allowed = (3, 4) if robot == "scara" else (3,)
        if len(target) not in allowed:
            form = "x,y,z[,yaw]" if robot == "scara" else "x,y,z"
            raise UsageError(f"{robot} needs --target {form} (m, rad); got {len(target)} values")
        goal = np.array(target, dtype=float)
    branches = inverse.ik(robot, goal, lengths)
    out = []
    for q in branches:
        position = chain.fk(q)[:3, 3]
        residual = np.linalg.norm(position - (goal[:3, 3] if goal.ndim == 2 else goal[:3]))
        out.append({"q": np.asarray(q).tolist(), "position_residual": float(residual)})
    return {"target": list(target), "solutions": out}


def _pose(values: Sequence[float]) -> np.ndarray:
    x, y, z, roll, pitch, yaw = values
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch), math.cos(yaw),
                              math.sin(yaw))  # fmt: skip
    pose = np.eye(4)
    pose[:3, :3] = [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
    pose[:3, 3] = x, y, z
    return pose


def format_matrix(m: Sequence[Sequence[float]], indent: str = "  ") -> str:
    """Rows of fixed-width numbers, exact zeros printed as 0."""
    return "\n".join(indent + " ".join(f"{v:11.6f}" if abs(v) > 5e-16 else f"{0:11d}" for v in row) for row in m)


def text(report: dict[str, Any]) -> str:
    """Human-readable form of describe/at_configuration/solve output merged into one dict."""
    lines = [f"{report['robot']}: {report['summary']}", f"  {report['convention']} DH, lengths [m]: "
             + ", ".join(f"{k} = {v:g}" for k, v in report["lengths"].items())]  # fmt: skip
    lines.append("  joint      kind       theta        d            a            alpha")
    for row in report["dh"]:
        var = "+q" if row["kind"] == "revolute" else "  "
        dvar = "+q" if row["kind"] == "prismatic" else "  "
        lines.append(
            f"  {row['joint']:<10} {row['kind']:<10} {row['theta']:9.6f}{var} {row['d']:9.6f}{dvar} "
            f"{row['a']:9.6f}    {row['alpha']:9.6f}"
        )
    lines.append("  singular sets:")
    lines += [f"    - {s}" for s in report["singular_sets"]]
    if "T0n" in report:
        lines.append(f"q = {report['q']}")
        lines.append("T0n (tool pose in the base frame):")
        lines.append(format_matrix(report["T0n"]))
        lines.append("J (6 x n, rows vx vy vz wx wy wz, base frame):")
        lines.append(format_matrix(report["J"]))
        for key in ("det", "manipulability"):
            if key in report:
                lines.append(f"{key} = {report[key]:.6g}")
        flagged = [name for name, on in report["singular"].items() if on]
        lines.append(f"singular: {', '.join(flagged) if flagged else 'no'}")
    if "solutions" in report:
        lines.append(f"IK for target {report['target']}: {len(report['solutions'])} solution(s)")
        for i, sol in enumerate(report["solutions"], start=1):
            qs = ", ".join(f"{v:.9g}" for v in sol["q"])
            lines.append(f"  {i}: q = ({qs})   |FK(q) - target| = {sol['position_residual']:.1e} m")
    return "\n".join(lines)
