"""What `hexabot-sim kin ROBOT|FILE` reports: DH table, T0n, J, det or manipulability, singular flags, IK."""

from __future__ import annotations

import dataclasses
import math
import os
import re
from collections.abc import Iterable, Iterator, Mapping, Sequence
from typing import Any

import numpy as np

from hexabot_sim.errors import HexabotError, UsageError
from hexabot_sim.kinematics import inverse, numeric_ik, robots
from hexabot_sim.kinematics.chain import SerialChain
from hexabot_sim.kinematics.robot_file import RobotSpec
from hexabot_sim.params import apart

# Input ranges of `kin` beyond the link lengths (robots.LENGTH_MIN..LENGTH_MAX): wide enough for anything a
# course exercise types, narrow enough that every product and sum in FK, J, det and IK stays finite and exact.
ANGLE_MAX: float = 1000.0  # |revolute joint value| and |target angle| in [rad] (159 turns)
PRISMATIC_MAX: float = 100.0  # |prismatic joint value| in [m]: ten times the longest link
TARGET_MAX: float = 1000.0  # |x|, |y|, |z| of an IK target in [m]: far beyond every reach, still exact
# Values like `-1,0.5,0.2` or `-inf,0,0` that follow --q/--target are values, not options: the kin sub-parser's
# `_negative_number_matcher` (argparse's own accepts only a lone -1 or -.5; the attribute exists in Python 3.8
# to 3.14) is this pattern, safe while no kin option itself looks like a negative number.
NUMBER_LIST = re.compile(r"^-(?:\d|\.\d|inf|nan)", re.IGNORECASE)
SYMBOLIC_HINT = (
    "--symbolic needs sympy (the extra 'symbolic'): in the hexabot-sim folder run pip install \".[symbolic]\", "
    "or just pip install sympy"
)


def parse_numbers(text: str, what: str) -> list[float]:
    """'0.1,0.2,-1' -> [0.1, 0.2, -1.0]; a one-line UsageError naming `what` otherwise."""
    parts = [p.strip().replace("\u2212", "-") for p in text.split(",")]  # accept the typographic minus
    try:
        if any("_" in p for p in parts):  # float() reads "1_0" as 10: a slip for "1,0" or "1.0" must not be 10
            raise ValueError
        values = [float(p) for p in parts]
    except ValueError:
        raise UsageError(f"{what} must be comma-separated numbers; got {text!r}") from None
    if not all(math.isfinite(v) for v in values):
        raise UsageError(f"{what} must be {'a finite number' if len(values) == 1 else 'finite numbers'}; got {text!r}")
    return values


@dataclasses.dataclass(frozen=True)
class Robot:
    """A robot resolved once for one `kin` call: its spec (package robot or file), the lengths set, its chain."""

    spec: RobotSpec
    lengths: Mapping[str, float]
    chain: SerialChain

    @property
    def name(self) -> str:
        return self.spec.name

    @property
    def closed_form(self) -> bool:
        """One of the package's robots: closed-form IK, named singular sets, det in closed form."""
        return self.spec.builtin


def resolve(robot: str | os.PathLike[str] | RobotSpec, assignments: Mapping[str, str]) -> Robot:
    """The robot by name or file, with --set name=value strings as lengths in [m] (each checked)."""
    spec = robots.resolve(robot)
    lengths = {}
    for name, raw in assignments.items():
        if name not in spec.lengths:
            known = ", ".join(spec.lengths) or "none (the robot file has no [lengths])"
            raise UsageError(f"unknown length '{name}' for {spec.name}; known: {known}")
        values = parse_numbers(raw, f"length '{name}'")
        if len(values) != 1:
            raise UsageError(f"length '{name}' takes one number in [m]; got {raw!r}")
        lengths[name] = values[0]
    return Robot(spec, lengths, spec.chain(lengths))  # chain() validates every length against its range


def _units(robot: Robot, degrees: bool) -> list[str]:
    """Joint units as the user reads and types them: 'deg' or 'rad' for revolute joints, 'm' for prismatic ones."""
    return ["deg" if degrees and u == "rad" else u for u in robot.spec.joint_units]


def _show(values: Iterable[float], units: Iterable[str]) -> list[float]:
    """Joint values from [rad] or [m] to the user's units."""
    return [math.degrees(v) if u == "deg" else float(v) for v, u in zip(values, units, strict=True)]


def _beyond(value: float, unit: str, limit: float) -> str:
    """Says "x = 100.0000001 m is outside the allowed ±100 m": |value| over `limit` [m or rad], both shown with the
    digits it takes for them to differ (params.apart); an angle typed in degrees is compared in degrees."""
    if unit == "deg":
        shown, bound = apart(abs(value), math.degrees(limit), "down", least=6)
        allowed = f"±{bound} deg (±{limit:g} rad)"
    else:
        shown, bound = apart(abs(value), limit, "down", least=6)
        allowed = f"±{bound} {unit}"
    return f"{'-' * (value < 0)}{shown} {unit} is outside the allowed {allowed}"


def _joint_values(robot: Robot, values: Sequence[float], degrees: bool) -> np.ndarray:
    """Typed joint values (user units) -> q in [rad] or [m]; a UsageError for a wrong count or a value out of range."""
    chain = robot.chain
    units = _units(robot, degrees)
    if len(values) != chain.n:
        names = ", ".join(f"{j.name} [{u}]" for j, u in zip(chain.joints, units, strict=True))
        raise UsageError(f"{robot.name} has {chain.n} joints ({names}); got {len(values)} values")
    q = []
    for joint, unit, value in zip(chain.joints, units, values, strict=True):
        if unit == "m":
            if abs(value) > PRISMATIC_MAX:
                raise UsageError(f"--q: {joint.name} = {_beyond(value, 'm', PRISMATIC_MAX)}")
            q.append(value)
        else:
            rad = math.radians(value) if unit == "deg" else value
            if abs(rad) > ANGLE_MAX:
                raise UsageError(f"--q: {joint.name} = {_beyond(value, unit, ANGLE_MAX)}")
            q.append(rad)
    return np.array(q)  # (n,)


def _outside(value: float, lo: float, hi: float) -> tuple[str, str, str]:
    """A value outside [lo, hi] and the range, with the digits it takes for the value to differ from the bound it
    passed (6 at least): "1.5708 is outside [-1.5708, 1.5708]" said nothing."""
    if value > hi:
        text, hi_text = apart(value, hi, "nearest", least=6)
        return text, f"{lo:.6g}", hi_text
    text, lo_text = apart(value, lo, "nearest", least=6)
    return text, lo_text, f"{hi:.6g}"


def _range_warnings(robot: Robot, chain: SerialChain, q: np.ndarray, degrees: bool) -> list[str]:
    """One line per joint value outside its range (or, without a range and without --deg, beyond a full turn)."""
    units = _units(robot, degrees)
    out = []
    for joint, unit, value in zip(chain.joints, units, q, strict=True):
        shown = _show([value], [unit])[0]
        hint = (
            "; revolute values are in rad (add --deg to type degrees)"
            if unit == "rad" and abs(value) > 2 * math.pi
            else ""
        )
        if joint.lower is not None and joint.upper is not None and not joint.lower <= value <= joint.upper:
            text, lo, hi = _outside(shown, *_show([joint.lower, joint.upper], [unit, unit]))
            out.append(f"{joint.name} = {text} {unit} is outside its joint range [{lo}, {hi}] {unit}{hint}")
        elif hint:
            out.append(f"{joint.name} = {shown:.6g} rad is more than a full turn{hint}")
    return out


def describe(robot: Robot, degrees: bool = False) -> dict[str, Any]:
    """The robot's DH table (its fixed rows too), lengths and singular sets; with `degrees`, angles in [deg]."""
    spec, chain = robot.spec, robot.chain
    angle = math.degrees if degrees else float
    rows = []
    units: list[str | None] = [*_units(robot, degrees), *[None] * len(spec.fixed_rows(robot.lengths))]
    for joint, unit in zip((*chain.joints, *spec.fixed_rows(robot.lengths)), units, strict=True):
        limit = float if joint.prismatic else angle
        rows.append(
            {"joint": joint.name, "kind": "fixed" if unit is None else joint.kind, "unit": unit,
             "theta": angle(joint.theta), "d": joint.d, "a": joint.a, "alpha": angle(joint.alpha),
             "lower": None if joint.lower is None else limit(joint.lower),
             "upper": None if joint.upper is None else limit(joint.upper)}
        )  # fmt: skip
    out = {
        "robot": spec.name,
        "summary": spec.summary,
        "convention": chain.convention,
        "angle_unit": "deg" if degrees else "rad",
        "lengths": spec.values(robot.lengths),
        "dh": rows,
        "tool": chain.tool.tolist(),
        "singular_sets": inverse.SINGULAR_SETS[spec.name] if robot.closed_form else _generic_sets(chain),
    }
    if not robot.closed_form:
        out["file"] = spec.source
        out["base"] = chain.base.tolist()
    return out


def _generic_sets(chain: SerialChain) -> list[str]:
    rows = numeric_ik.task_rows(chain)
    what = "the 6 x n J" if len(rows) == 6 else "the position rows Jv (3 x n) of J"
    return [
        f"sigma_min of {what} = 0 (rank_deficient): found numerically at a configuration (--q), flagged when "
        f"sigma_min <= {numeric_ik.NEAR_SINGULAR:g} sigma_max, and at each IK solution, flagged when sigma_min <= "
        f"{numeric_ik.NEAR_SINGULAR_SOLUTION:g} sigma_max (the solver's resolution there); no closed form for a file"
    ]


def at_configuration(robot: Robot, q: Sequence[float], degrees: bool = False) -> dict[str, Any]:
    """T0n, the 6xn Jacobian, det or manipulability, and which singular conditions hold at q.

    Args:
        robot: The resolved robot.
        q: Joint values as typed: [rad] (or [deg] with `degrees`) for revolute joints, [m] for prismatic ones.
        degrees: Revolute values in and out in [deg]; T0n is in [m], J per [rad] or [m] either way.

    Returns:
        q (as typed), T0n, J, det (or manipulability), singular flags, is_singular and the range warnings; for a
        robot file also sigma_min (of the task Jacobian: all 6 rows for 6 or more joints, else the position rows).
    """
    chain = robot.chain
    qa = _joint_values(robot, q, degrees)  # (n,) in [rad] or [m]
    out: dict[str, Any] = {
        "q": [float(v) for v in q],  # as typed, so 30 deg stays 30 and not 29.999999999999996
        "T0n": chain.fk(qa).tolist(),
        "J": chain.jacobian(qa).tolist(),
    }
    if robot.closed_form:
        kind, value = inverse.det_or_manipulability(robot.name, qa, robot.lengths, chain)
        flags = inverse.singularities(robot.name, qa, robot.lengths, chain)
        out |= {kind: value}
    else:
        kind, value, sigma_min = numeric_ik.det_or_manipulability(chain, qa)
        sigma = np.linalg.svd(chain.jacobian(qa)[list(numeric_ik.task_rows(chain))], compute_uv=False)
        flags = {"rank_deficient": bool(sigma[-1] <= numeric_ik.NEAR_SINGULAR * sigma[0])}
        out |= {kind: value, "sigma_min": sigma_min}
    return out | {"singular": flags, "is_singular": any(flags.values()),
                  "warnings": _range_warnings(robot, chain, qa, degrees)}  # fmt: skip


def _target(robot: Robot, target: Sequence[float], degrees: bool) -> np.ndarray:
    """Typed target (positions [m], angles [rad] or [deg]) -> the IK goal: a position (scara: with yaw) or a pose."""
    name, unit = robot.name, "deg" if degrees else "rad"
    pose_target = name == "stanford" if robot.closed_form else robot.chain.n >= 6
    if pose_target:
        if len(target) != 6:
            raise UsageError(
                f"{name} needs --target x,y,z,roll,pitch,yaw (m, {unit}: R = Rz Ry Rx); got {len(target)} values"
            )
    else:
        scara = robot.closed_form and name == "scara"
        allowed = (3, 4) if scara else (3,)
        if len(target) not in allowed:
            form = "x,y,z[,yaw]" if scara else "x,y,z"
            unit = "m, deg" if degrees and scara else "m, rad" if scara else "m"
            below = "" if robot.closed_form else " (a chain of fewer than 6 joints gets position targets)"
            raise UsageError(f"{name} needs --target {form} ({unit}){below}; got {len(target)} values")
    values = []
    for i, value in enumerate(target):
        if i < 3:
            if abs(value) > TARGET_MAX:
                raise UsageError(f"--target: {'xyz'[i]} = {_beyond(value, 'm', TARGET_MAX)}")
            values.append(value)
        else:
            rad = math.radians(value) if degrees else value
            if abs(rad) > ANGLE_MAX:
                raise UsageError(f"--target: angle {_beyond(value, unit, ANGLE_MAX)}")
            values.append(rad)
    return _pose(values) if pose_target else np.array(values)


def _orientation_residual(robot: Robot, q: np.ndarray, goal: np.ndarray) -> float | None:
    """The angle [rad] between the tool's orientation at q and the target's, for a target with an orientation."""
    tool = robot.chain.fk(q)
    if goal.shape == (4, 4):
        delta = tool[:3, :3] @ goal[:3, :3].T
        axial = np.array([delta[2, 1] - delta[1, 2], delta[0, 2] - delta[2, 0], delta[1, 0] - delta[0, 1]])
        return float(math.atan2(np.linalg.norm(axial) / 2, (np.trace(delta) - 1) / 2))
    if goal.shape == (4,):  # scara: the yaw atan2(R[1, 0], R[0, 0])
        yaw = math.atan2(tool[1, 0], tool[0, 0])
        return abs(math.remainder(yaw - float(goal[3]), 2 * math.pi))
    return None


def solve(robot: Robot, target: Sequence[float], degrees: bool = False) -> dict[str, Any]:
    """Every IK solution for `target`, each with its FK residuals: closed-form branches (and the branches the
    ranges dropped) for the package's robots, numeric ones (numeric_ik) for a robot file.

    Args:
        robot: The resolved robot.
        target: As typed: x, y, z in [m] (stanford, or a file of 6+ joints: then roll, pitch, yaw; scara:
            optionally yaw) with angles in [rad] (or [deg] with `degrees`).
        degrees: Angles of the target and of the solutions in [deg].

    Returns:
        target (as typed), solutions (q, position_residual [m], orientation_residual [rad] for a target with an
        orientation, and for a file sigma_min), dropped (q, outside) and warnings.

    Raises:
        UsageError: Malformed target; IKError (a UsageError) when unreachable, not isolated, or when every branch
            is outside the joint ranges.
    """
    if not robot.closed_form:
        return _solve_numeric(robot, target, degrees)
    chain, name = robot.chain, robot.name
    goal = _target(robot, target, degrees)
    branches, dropped = inverse.ik_branches(name, goal, robot.lengths, chain)
    units = _units(robot, degrees)
    position = goal[:3, 3] if goal.ndim == 2 else goal[:3]
    dropped_text = [
        f"q = ({_tuple(_show(q, units))}) {_unit_list(units)}: {_violation(robot, chain, q, degrees)}"
        for q, _ in dropped
    ]
    total = len(branches) + len(dropped)
    if not branches:
        raise inverse.IKError(
            f"{name} target ({_tuple(position)}) m: all {total} IK branch(es) are outside the joint ranges: "
            + "; ".join(dropped_text)
        )
    out = []
    for q in branches:
        residual = np.linalg.norm(chain.fk(q)[:3, 3] - position)
        solution = {"q": _show(q, units), "position_residual": float(residual)}
        orientation = _orientation_residual(robot, q, goal)
        out.append(solution if orientation is None else solution | {"orientation_residual": orientation})
    warnings = []
    if dropped:
        warnings.append(
            f"IK: {len(dropped)} of {total} branches dropped by the joint ranges: " + "; ".join(dropped_text)
        )
    return {
        "target": [float(v) for v in target],
        "solutions": out,
        "dropped": [{"q": _show(q, units), "outside": _violation(robot, chain, q, degrees)} for q, _ in dropped],
        "warnings": warnings,
    }


def _solve_numeric(robot: Robot, target: Sequence[float], degrees: bool) -> dict[str, Any]:
    """solve() for a robot file: numeric_ik from many seeds; redundant chains and near-singular solutions warned."""
    goal = _target(robot, target, degrees)
    units = _units(robot, degrees)
    where = f"{robot.name} ({robot.spec.source}) target ({_tuple(goal[:3, 3] if goal.ndim == 2 else goal)}) m"
    rank = numeric_ik.structural_rank(robot.chain, where)
    solutions = numeric_ik.solve(robot.chain, goal, where, rank)
    out, warnings = [], []
    for k, sol in enumerate(solutions, start=1):
        entry = {"q": _show(sol.q, units), "position_residual": sol.position_residual}
        if sol.orientation_residual is not None:
            entry["orientation_residual"] = sol.orientation_residual
        out.append(entry | {"sigma_min": sol.sigma_min})
        if sol.near_singular:
            warnings.append(f"IK: solution {k} is at a singular configuration (sigma_min = {sol.sigma_min:.3g})")
    family = numeric_ik.family(robot.chain, robot.name, len(out), rank)
    warnings += [family] if family else []
    method = (
        f"numeric: Levenberg-Marquardt from {numeric_ik.SEEDS_PER_ROUND} seeds in the joint ranges, "
        f"residuals <= {numeric_ik.RESIDUAL_TOL:g}, duplicates within {numeric_ik.DEDUP_TOL:g} merged"
    )
    return {"target": [float(v) for v in target], "ik_method": method, "solutions": out, "dropped": [],
            "warnings": warnings}  # fmt: skip


def _violation(robot: Robot, chain: SerialChain, q: np.ndarray, degrees: bool) -> str:
    """The joints of q outside their ranges, as text in the user's units."""
    units = _units(robot, degrees)
    parts = []
    for joint, unit, value in zip(chain.joints, units, q, strict=True):
        if joint.lower is not None and joint.upper is not None:
            lo_tol, hi_tol = joint.lower - inverse.IK_RANGE_TOL, joint.upper + inverse.IK_RANGE_TOL
            if not lo_tol <= value <= hi_tol:
                text, lo, hi = _outside(*_show([value, joint.lower, joint.upper], [unit] * 3))
                parts.append(f"{joint.name} = {text} outside [{lo}, {hi}] {unit}")
    return ", ".join(parts)


def _tuple(values: Iterable[float]) -> str:
    return ", ".join(f"{v:.6g}" for v in values)


def _unit_list(units: Sequence[str]) -> str:
    return f"[{', '.join(units)}]"


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


def symbolic_forms(robot: Robot) -> dict[str, str]:
    """T0n and J derived with sympy, as text with c1/s23 abbreviations and as LaTeX; a UsageError without sympy.

    The robot's named lengths are symbols (a robot file without [lengths] keeps its numbers)."""
    try:
        from hexabot_sim.kinematics import symbolic
    except ImportError:
        raise UsageError(SYMBOLIC_HINT) from None
    chain = symbolic.symbolic_chain(robot.spec)
    pose, jac = symbolic.transforms(chain, max_ops=symbolic.MAX_OPS)[-1], symbolic.jacobian(chain)  # bounded time
    return {"T0n": symbolic.pretty(pose), "J": symbolic.pretty(jac), "T0n_latex": symbolic.latex(pose),
            "J_latex": symbolic.latex(jac)}  # fmt: skip


def report(
    robot: str | os.PathLike[str] | RobotSpec,
    assignments: Mapping[str, str],
    q: str | None = None,
    target: str | None = None,
    degrees: bool = False,
    symbolic: bool = False,
) -> dict[str, Any]:
    """Everything `hexabot-sim kin` prints, from the command line's strings; `warnings` lists what looked wrong.

    `robot` is a package robot's name, the path of a robot file, or a spec; it is resolved once, here.

    Raises:
        UsageError: Any bad input, as one line naming what is allowed.
        HexabotError: A non-finite number in the result (a bug: inputs in range never produce one).
    """
    resolved = resolve(robot, assignments)
    out = describe(resolved, degrees)
    warnings: list[str] = []
    if q is not None:
        out |= at_configuration(resolved, parse_numbers(q, "--q"), degrees)
        warnings += out.pop("warnings")
    if target is not None:
        out |= solve(resolved, parse_numbers(target, "--target"), degrees)
        warnings += out.pop("warnings")
    if symbolic:
        out["symbolic"] = symbolic_forms(resolved)
    out["warnings"] = warnings
    for where, value in _numbers(out):
        if not math.isfinite(value):
            raise HexabotError(f"internal error: kin computed {value} for {where}; please report this as a bug")
    return out


def _numbers(node: Any, where: str = "report") -> Iterator[tuple[str, float]]:
    """Every float in a nested dict/list, with its path."""
    if isinstance(node, float):
        yield where, node
    elif isinstance(node, Mapping):
        for key, value in node.items():
            yield from _numbers(value, f"{where}.{key}")
    elif isinstance(node, list):
        for i, value in enumerate(node):
            yield from _numbers(value, f"{where}[{i}]")


def format_matrix(m: Sequence[Sequence[float]], indent: str = "  ") -> str:
    """Rows of fixed-width numbers, exact zeros printed as 0."""
    return "\n".join(indent + " ".join(f"{v:11.6f}" if abs(v) > 5e-16 else f"{0:11d}" for v in row) for row in m)


def text(report: dict[str, Any]) -> str:
    """Human-readable form of `report` (or of describe/at_configuration/solve output merged into one dict)."""
    unit = report.get("angle_unit", "rad")
    head = f"{report['robot']}: {report['summary']}"
    if "file" in report:  # a robot file: where it came from; its [lengths] may be empty
        head = f"{report['robot']}: {report['summary'] or 'robot file'} ({report['file']})"
    lengths = ", ".join(f"{k} = {v:g}" for k, v in report["lengths"].items())
    lines = [head, f"  {report['convention']} DH" + (f", lengths [m]: {lengths}" if lengths else "")]
    if unit == "deg":
        lines.append("  joint      kind       theta [deg]  d [m]        a [m]        alpha [deg]")
    else:
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
    units = [row["unit"] for row in report["dh"] if row["kind"] != "fixed"]
    in_units = f" {_unit_list(units)}" if unit == "deg" else ""
    if "T0n" in report:
        lines.append(f"q = {report['q']}{in_units}")
        lines.append("T0n (tool pose in the base frame):")
        lines.append(format_matrix(report["T0n"]))
        lines.append("J (6 x n, rows vx vy vz wx wy wz, base frame):")
        lines.append(format_matrix(report["J"]))
        for key in ("det", "manipulability", "sigma_min"):
            if key in report:
                lines.append(f"{key} = {report[key]:.6g}")
        flagged = [name for name, on in report["singular"].items() if on]
        lines.append(f"singular: {', '.join(flagged) if flagged else 'no'}")
    if "solutions" in report:
        lines.append(f"IK for target {report['target']}: {len(report['solutions'])} solution(s){in_units}")
        if "ik_method" in report:
            lines.append(f"  ({report['ik_method']})")
        for i, sol in enumerate(report["solutions"], start=1):
            qs = ", ".join(f"{v:.9g}" for v in sol["q"])
            residual = f"{sol['position_residual']:.1e} m"
            if "orientation_residual" in sol:
                residual += f", {sol['orientation_residual']:.1e} rad"
            sigma = f", sigma_min = {sol['sigma_min']:.3g}" if "sigma_min" in sol else ""
            lines.append(f"  {i}: q = ({qs})   |FK(q) - target| = {residual}{sigma}")
    if "symbolic" in report:
        sym = report["symbolic"]
        lines += ["symbolic T0n:", sym["T0n"], "symbolic J:", sym["J"]]
        lines += ["T0n (LaTeX):", sym["T0n_latex"], "J (LaTeX):", sym["J_latex"]]
    return "\n".join(lines)
