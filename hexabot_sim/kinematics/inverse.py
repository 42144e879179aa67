"""Closed-form IK (all branches), singular sets and Jacobian determinants of the seed robots in `robots.py`."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping

import numpy as np
from numpy.typing import ArrayLike

from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics import leg, robots
from hexabot_sim.kinematics.chain import SerialChain
from hexabot_sim.kinematics.leg import IKError  # one IKError for the package: re-exported here

__all__ = [
    "IK_AXIS_TOL",
    "IK_DEDUP_TOL",
    "IK_RANGE_TOL",
    "IK_REACH_TOL",
    "SINGULAR_SETS",
    "SINGULAR_TOL",
    "TASK_ROWS",
    "IKError",
    "det_or_manipulability",
    "ik",
    "ik_branches",
    "singularities",
]

# A target closer than this fraction of the robot's size (sum of its DH lengths and prismatic strokes) to the
# z0 axis counts as on it (IK: q1 arbitrary); a squared distance short of a reach limit by less than this
# fraction of size² is moved onto the limit instead of being declared unreachable.
IK_AXIS_TOL: float = 1e-12
IK_REACH_TOL: float = 1e-12
# Branches whose joint values all agree within this [rad or m] (angles mod 2π) are one solution. Branches merge at
# square-root folds (stretched arm, r = sqrt(x² + y² − d²) = 0): a target rounded by 1e-16 there gives two branches
# 1e-8 apart, so the tolerance must be well above 1e-8; either branch solves the target to rounding.
IK_DEDUP_TOL: float = 1e-6
# Slack on joint ranges [rad or m]: a branch this far outside a range still counts as inside.
IK_RANGE_TOL: float = 1e-12
# singularities(): a sine or cosine with |value| <= SINGULAR_TOL counts as zero; a length counts as zero when
# |value| <= SINGULAR_TOL * size (size as above, in [m]).
SINGULAR_TOL: float = 1e-9
# A Stanford target pose whose rotation block R has |R Rᵀ - I| or |det R - 1| above this is rejected.
ROTATION_TOL: float = 1e-9

# Rows of the geometric Jacobian (vx, vy, vz, wx, wy, wz) that form each robot's square task Jacobian.
TASK_ROWS: dict[str, tuple[int, ...]] = {
    "rrp": (0, 1, 2),
    "elbow": (0, 1, 2),
    "scara": (0, 1, 2, 5),  # x, y, z and the tool yaw rate: the SCARA's 4 joints against its 4 task coordinates
    "stanford": (0, 1, 2, 3, 4, 5),
    "leg": (0, 1, 2),
}

SINGULAR_SETS: dict[str, list[str]] = {
    "rrp": [
        "cos q2 = 0 (cos_q2_zero): the arm points straight up or down, the tool is on the z0 axis and q1 turns "
        "it about its own position; det Jv = (a2 + d3)² cos q2",
        "a2 + d3 = 0 (zero_reach): the tool sits on the q2 axis at (0, 0, d1), neither q1 nor q2 moves it "
        "(rank 1); d3 = -a2 is the slide's lower limit",
    ],
    "elbow": [
        "sin θ3 = 0 (elbow_stretched_or_folded): the arm is stretched or folded, the wrist centre on the "
        "boundary of its shell; det Jv = -a2 a3 sin θ3 (a2 cos θ2 + a3 cos(θ2 + θ3))",
        "a2 cos θ2 + a3 cos(θ2 + θ3) = 0 with d = 0 (wrist_centre_on_z0): the wrist centre is on the z0 axis, "
        "θ1 turns it about itself (IK: θ1 arbitrary)",
        "a2 cos θ2 + a3 cos(θ2 + θ3) = 0 with d > 0 (wrist_centre_on_offset_cylinder): the wrist centre is on "
        "the cylinder x² + y² = d² (straight above or below the shoulder), where the two shoulder solutions merge",
    ],
    "scara": [
        "sin θ2 = 0 (arm_stretched_or_folded): the two horizontal links are in line, the tool on the boundary "
        "of its annulus; det of the (vx, vy, vz, wz) rows = a1 a2 sin θ2",
    ],
    "stanford": [
        "sin θ5 = 0 (wrist_sin_theta5_zero): z3 and z5 are aligned, θ4 and θ6 turn about the same axis "
        "(only θ4 + θ6 is determined); det J = d3² sin θ2 sin θ5",
        "sin θ2 = 0 (arm_sin_theta2_zero): the wrist centre is on the vertical line through o2, at distance d2 "
        "from z0 (on z0 if d2 = 0), where the two θ1 solutions merge; det of the wrist-centre Jacobian = "
        "-d3² sin θ2",
        "d3 = 0 (d3_zero): the wrist centre is at o2 on the θ2 axis, θ2 does not move it (IK: θ2 arbitrary); "
        "d3 = 0 is the slide's lower limit",
    ],
    "leg": [
        "sin q3 = 0 (knee): the leg is stretched or folded; det J = l2 l3 sin q3 rho",
        "rho = l1 + l2 cos q2 + l3 cos(q2 + q3) = 0 (coxa_axis): the foot is on the coxa axis z0, q1 turns it "
        "about itself (IK: q1 arbitrary)",
    ],
}

_TWO_PI = 2.0 * math.pi


def _wrap(angle: float) -> float:
    """Angle wrapped to (-π, π] in [rad]; angles already in that range are returned unchanged."""
    if -math.pi < angle <= math.pi:
        return angle
    return math.pi - (math.pi - angle) % _TWO_PI


def _setup(
    robot: str, lengths: Mapping[str, float] | None, chain: SerialChain | None = None
) -> tuple[robots.RobotSpec, SerialChain, dict[str, float]]:
    """The robot's spec, its chain (validates `lengths`; `chain`: the caller's, already built from them) and every
    length by name in [m]."""
    spec = robots.get(robot)
    chain = spec.chain(lengths) if chain is None else chain
    values = {name: float((lengths or {}).get(name, length.default)) for name, length in spec.lengths.items()}
    return spec, chain, values


def _size(chain: SerialChain) -> float:
    """Length scale of a chain in [m]: its DH distances plus its prismatic strokes (for relative tolerances)."""
    size = sum(abs(j.a) + abs(j.d) for j in chain.joints) + float(np.linalg.norm(chain.tool[:3, 3]))
    for j in chain.joints:
        if j.prismatic:
            size += max(abs(j.lower or 0.0), abs(j.upper or 0.0))
    return size


def _joint_values(chain: SerialChain, q: ArrayLike) -> np.ndarray:
    """q as a finite float array of shape (n,)."""
    q = np.asarray(q, dtype=float)
    if q.shape != (chain.n,):
        raise UsageError(f"{chain.name} has {chain.n} joints; q must have shape ({chain.n},), got {q.shape}")
    if not np.all(np.isfinite(q)):
        raise UsageError(f"joint values of {chain.name} must be finite numbers; got {q.tolist()}")
    return q


def _position(robot: str, target: ArrayLike, sizes: tuple[int, ...] = (3,)) -> np.ndarray:
    """A finite position target (x, y, z [, yaw]) of one of the allowed `sizes`."""
    p = np.asarray(target, dtype=float)
    if p.ndim != 1 or p.shape[0] not in sizes or not np.all(np.isfinite(p)):
        form = "(x, y, z) in [m]" if sizes == (3,) else "(x, y, z) in [m] or (x, y, z, yaw) in [m, rad]"
        raise UsageError(f"{robot} target must be a finite position {form}; got {p.tolist()}")
    return p


def _point(p: ArrayLike) -> str:
    """'(x, y, z) m' for messages."""
    x, y, z = (float(v) for v in np.asarray(p, dtype=float)[:3])
    return f"({x:.6g}, {y:.6g}, {z:.6g}) m"


def _where(robot: str, p: ArrayLike) -> str:
    """'rrp target (x, y, z) m' for messages."""
    return f"{robot} target {_point(p)}"


def _two_link(r: float, s: float, a: float, b: float) -> list[tuple[float, float]] | float:
    """(u, v) with a (cos u, sin u) + b (cos(u + v), sin(u + v)) = (r, s), v >= 0 first; the distance if unreachable.

    v = ±2 atan2(sqrt((a + b)² − D²), sqrt(D² − (a − b)²)) with D = |(r, s)| is the half-angle form of
    acos((D² − a² − b²) / (2 a b)), accurate near the stretched and folded arm where acos loses half the digits.
    """
    dist = math.hypot(r, s)
    outer = (a + b - dist) * (a + b + dist)  # 2 a b (1 - cos v)
    inner = (dist - (a - b)) * (dist + (a - b))  # 2 a b (1 + cos v)
    slack = 2.0 * a * b * IK_REACH_TOL
    if outer < -slack or inner < -slack:
        return dist
    v = 2.0 * math.atan2(math.sqrt(max(outer, 0.0)), math.sqrt(max(inner, 0.0)))
    return [(math.atan2(s, r) - math.atan2(b * math.sin(w), a + b * math.cos(w)), w) for w in (v, -v)]


def _out_of_reach(where: str, dist: float, what: str, lo: float, hi: float) -> IKError:
    return IKError(f"{where} is out of reach: {dist:.6g} m from {what}, reachable {lo:.6g} to {hi:.6g} m")


def _ik_rrp(target: ArrayLike, p: Mapping[str, float], size: float) -> list[tuple[float, ...]]:
    """RRP: p = (c1 c2 ρ, s1 c2 ρ, d1 + s2 ρ) with ρ = a2 + d3 >= 0 (d3 >= -a2 is the slide's lower limit).

    Branches: q1 = atan2(y, x) with q2 = elevation, then q1 + π with q2 = π − elevation; same d3.
    """
    pos = _position("rrp", target)
    x, y, z = (float(v) for v in pos)
    radial, height = math.hypot(x, y), z - p["d1"]
    if radial <= IK_AXIS_TOL * size:
        raise IKError(f"{_where('rrp', pos)} is on the z0 axis (x = y = 0): q1 is arbitrary")
    heading, elevation = math.atan2(y, x), math.atan2(height, radial)
    d3 = math.hypot(radial, height) - p["a2"]
    return [(heading, elevation, d3), (heading + math.pi, math.pi - elevation, d3)]


def _ik_elbow(target: ArrayLike, p: Mapping[str, float], size: float) -> list[tuple[float, ...]]:
    """Elbow with shoulder offset d: (x, y) = Rz(θ1) (r, -d), z = d1 + s, (r, s) = a2 (c2, s2) + a3 (c23, s23).

    r = ±sqrt(x² + y² − d²). Branches: r >= 0 (elbow θ3 >= 0, then < 0), then r < 0 (the same).
    """
    pos = _position("elbow", target)
    x, y, z = (float(v) for v in pos)
    where, d, radial = _where("elbow", pos), p["d"], math.hypot(x, y)
    if d <= IK_AXIS_TOL * size and radial <= IK_AXIS_TOL * size:
        raise IKError(
            f"{where}: the wrist centre is on the z0 axis (x = y = 0) with no shoulder offset: θ1 is arbitrary"
        )
    r_squared = (radial - d) * (radial + d)
    if r_squared < -IK_REACH_TOL * size * size:
        raise IKError(
            f"{where} is out of reach: {radial:.6g} m from the z0 axis, closer than the shoulder offset d = {d:.6g} m"
        )
    r, s = math.sqrt(max(r_squared, 0.0)), z - p["d1"]
    out: list[tuple[float, ...]] = []
    for r_branch in (r, -r):
        planar = _two_link(r_branch, s, p["a2"], p["a3"])
        if isinstance(planar, float):
            lo, hi = abs(p["a2"] - p["a3"]), p["a2"] + p["a3"]
            raise _out_of_reach(where, planar, "the shoulder (θ2 axis) in the arm plane", lo, hi)
        theta1 = math.atan2(y, x) - math.atan2(-d, r_branch)
        out += [(theta1, theta2, theta3) for theta2, theta3 in planar]
    return out


def _ik_scara(target: ArrayLike, p: Mapping[str, float], size: float) -> list[tuple[float, ...]]:
    """SCARA: (x, y) = a1 (c1, s1) + a2 (c12, s12), z = d1 − d3 − d4, tool yaw = θ1 + θ2 − θ4.

    Without a yaw in the target θ4 = 0 (θ4 does not move the tool point). Branches: θ2 >= 0, then θ2 < 0.
    """
    pos = _position("scara", target, (3, 4))
    x, y, z = (float(v) for v in pos[:3])
    where, a1, a2 = _where("scara", pos), p["a1"], p["a2"]
    if abs(a1 - a2) <= IK_AXIS_TOL * size and math.hypot(x, y) <= IK_AXIS_TOL * size:
        raise IKError(f"{where} is on the z0 axis (x = y = 0) with a1 = a2, the arm folded: θ1 is arbitrary")
    planar = _two_link(x, y, a1, a2)
    if isinstance(planar, float):
        raise _out_of_reach(where, planar, "the z0 axis", abs(a1 - a2), a1 + a2)
    d3 = p["d1"] - p["d4"] - z
    yaw = float(pos[3]) if pos.shape[0] == 4 else None
    return [(t1, t2, d3, 0.0 if yaw is None else t1 + t2 - yaw) for t1, t2 in planar]


def _ik_stanford(target: ArrayLike, p: Mapping[str, float], size: float, chain: SerialChain) -> list[tuple[float, ...]]:
    """Stanford arm, decoupled: wrist centre c = p − d6 z, then (θ1, θ2, d3), then the wrist (θ4, θ5, θ6).

    (xc, yc) = Rz(θ1) (r, d2) with r = s2 d3 = ±sqrt(xc² + yc² − d2²), zc = c2 d3; d3 = |(r, zc)| >= 0 (its
    lower limit), so θ2 = atan2(r, zc). R36 = R03ᵀ R: θ5 = ±atan2(sqrt(r13² + r23²), r33), θ4 = atan2(±r23,
    ±r13), θ6 = atan2(±r32, ∓r31). Branches: r >= 0 then r < 0, each with θ5 >= 0 then θ5 < 0.
    """
    pose = np.asarray(target, dtype=float)
    if pose.shape != (4, 4) or not np.all(np.isfinite(pose)):
        raise UsageError(f"stanford target must be a finite 4x4 homogeneous pose; got shape {pose.shape}")
    rot = pose[:3, :3]  # (3, 3)
    orthonormal = np.max(np.abs(rot @ rot.T - np.eye(3))) <= ROTATION_TOL
    if not (orthonormal and abs(np.linalg.det(rot) - 1.0) <= ROTATION_TOL and np.allclose(pose[3], (0, 0, 0, 1))):
        raise UsageError(
            "stanford target must be a homogeneous pose: rotation block orthonormal with det +1, last row 0 0 0 1"
        )
    centre = pose[:3, 3] - p["d6"] * rot[:, 2]  # (3,) wrist centre
    xc, yc, zc = (float(v) for v in centre)
    d2, radial = p["d2"], math.hypot(xc, yc)
    where = f"stanford target pose with wrist centre {_point(centre)}"
    if d2 <= IK_AXIS_TOL * size and radial <= IK_AXIS_TOL * size:
        raise IKError(f"{where}: the wrist centre is on the z0 axis (x = y = 0) with d2 = 0: θ1 is arbitrary")
    r_squared = (radial - d2) * (radial + d2)
    if r_squared < -IK_REACH_TOL * size * size:
        raise IKError(
            f"{where} is out of reach: {radial:.6g} m from the z0 axis, closer than the shoulder offset d2 = {d2:.6g} m"
        )
    r = math.sqrt(max(r_squared, 0.0))
    d3 = math.hypot(r, zc)
    if d3 <= IK_AXIS_TOL * size:
        raise IKError(f"{where}: the wrist centre is at o2 on the θ2 axis (d3 = 0): θ2 is arbitrary")
    out: list[tuple[float, ...]] = []
    for r_branch in (r, -r):
        theta1 = math.atan2(yc, xc) - math.atan2(d2, r_branch)
        theta2 = math.atan2(r_branch, zc)
        arm = np.linalg.multi_dot(
            [j.transform(v, "standard") for j, v in zip(chain.joints[:3], (theta1, theta2, d3), strict=True)]
        )
        wrist = arm[:3, :3].T @ rot  # (3, 3) R36
        s5 = math.hypot(wrist[0, 2], wrist[1, 2])
        if s5 <= SINGULAR_TOL:
            raise IKError(f"{where}: the wrist is singular there (sin θ5 = {s5:.1e}): only θ4 + θ6 is determined")
        theta5 = math.atan2(s5, wrist[2, 2])
        theta4 = math.atan2(wrist[1, 2], wrist[0, 2])
        theta6 = math.atan2(wrist[2, 1], -wrist[2, 0])
        out.append((theta1, theta2, d3, theta4, theta5, theta6))
        out.append((theta1, theta2, d3, theta4 + math.pi, -theta5, theta6 + math.pi))
    return out


def _ik_leg(target: ArrayLike, p: Mapping[str, float], size: float) -> list[tuple[float, ...]]:
    """The hexabot leg: leg.ik (up to 4 branches), with its on-axis message worded for this API."""
    geom = leg.LegGeometry(p["l1"], p["l2"], p["l3"])
    pos = _position("leg", target)
    if math.hypot(pos[0], pos[1]) <= leg.IK_AXIS_TOL * (geom.l1 + geom.l2 + geom.l3):
        leg.ik(pos, geom, q1=0.0)  # raises IKError if the point is out of reach as well
        raise IKError(f"{_where('leg', pos)} is on the coxa axis (x = y = 0): q1 is arbitrary")
    return [tuple(float(v) for v in q) for q in leg.ik(pos, geom)]


_SOLVERS: dict[str, Callable[[ArrayLike, Mapping[str, float], float], list[tuple[float, ...]]]] = {
    "rrp": _ik_rrp,
    "elbow": _ik_elbow,
    "scara": _ik_scara,
    "leg": _ik_leg,
}


def _in_range(spec: robots.RobotSpec, chain: SerialChain, q: np.ndarray) -> str | None:
    """None if q is inside every joint range, else the first violation as text."""
    for joint, unit, value in zip(chain.joints, spec.joint_units, q, strict=True):
        lo = -math.inf if joint.lower is None else joint.lower
        hi = math.inf if joint.upper is None else joint.upper
        if not lo - IK_RANGE_TOL <= value <= hi + IK_RANGE_TOL:
            return f"{joint.name} = {value:.6g} {unit} outside [{lo:.6g}, {hi:.6g}] {unit}"
    return None


def ik_branches(
    robot: str, target: ArrayLike, lengths: Mapping[str, float] | None = None, chain: SerialChain | None = None
) -> tuple[list[np.ndarray], list[tuple[np.ndarray, str]]]:
    """Like `ik`, but also returns the branches the joint ranges dropped, and never raises for that alone.

    Returns:
        (solutions, dropped): the solutions `ik` returns (possibly empty here), and each distinct branch outside
        a joint range with its first violation as text, e.g. "coxa = 2.67795 rad outside [-1.5708, 1.5708] rad".

    Raises:
        IKError, UsageError: As `ik`, except when every branch is outside the joint ranges.
    """
    spec, chain, p = _setup(robot, lengths, chain)
    size = _size(chain)
    if robot == "stanford":
        candidates = _ik_stanford(target, p, size, chain)
    else:
        candidates = _SOLVERS[robot](target, p, size)
    revolute = np.array([not j.prismatic for j in chain.joints])
    solutions: list[np.ndarray] = []
    dropped: list[tuple[np.ndarray, str]] = []
    for candidate in candidates:
        q = np.array([_wrap(v) if rev else v for v, rev in zip(candidate, revolute, strict=True)])  # (n,)
        if any(_same(q, s, revolute) for s in solutions):
            continue
        violation = _in_range(spec, chain, q)
        if violation is None:
            solutions.append(q)
        elif not any(_same(q, d, revolute) for d, _ in dropped):
            dropped.append((q, violation))
    # A dropped branch that coincides with a kept one (a fold at the edge of a range) was not really dropped.
    dropped = [(q, why) for q, why in dropped if not any(_same(q, s, revolute) for s in solutions)]
    return solutions, dropped


def ik(robot: str, target: ArrayLike, lengths: Mapping[str, float] | None = None) -> list[np.ndarray]:
    """Every closed-form joint solution that puts the robot's tool at `target`.

    Angles are wrapped to (-π, π]; coinciding branches (e.g. a stretched arm's two elbows) are returned once;
    branches outside a joint's range (where the chain's Joint has lower/upper) are left out. Branch order:
        rrp: q1 = atan2(y, x), then q1 + π (q2 mirrored to π − q2); generically 2.
        elbow: r = +sqrt(x² + y² − d²) with θ3 >= 0, θ3 < 0, then r = −sqrt(...) likewise; generically 4.
        scara: θ2 >= 0, then θ2 < 0; generically 2. θ4 solves the yaw if given, else θ4 = 0.
        stanford: θ1 for r = s2 d3 >= 0 then < 0 (d3 >= 0 by its range, so θ2 and d3 are unique), each with
            θ5 > 0 then θ5 < 0 (θ4 + π, θ6 + π); generically 4.
        leg: leg.ik's order; its joint ranges keep generically 1 of its 4 branches.

    Args:
        robot: "rrp", "elbow", "scara", "stanford" or "leg".
        target: Tool (wrist centre for the elbow, foot for the leg) position (x, y, z) in [m], (3,);
            scara: also (x, y, z, yaw) in [m, rad], (4,), with yaw = atan2(R[1, 0], R[0, 0]) = θ1 + θ2 − θ4;
            stanford: the tool pose, a homogeneous transform (4, 4).
        lengths: Link-length overrides in [m] (see robots.py), or None for the defaults.

    Returns:
        Joint values in [rad] or [m] (the robot's joint_units), each (n,); never empty.

    Raises:
        IKError: The target is out of reach, outside the joint ranges, or at a singular point where the
            solutions are not isolated (e.g. on the z0 axis, where q1 is arbitrary). One line, no NaN.
        UsageError: Unknown robot or length, or a malformed target.
    """
    solutions, dropped = ik_branches(robot, target, lengths)
    if not solutions:
        if robot == "stanford":
            where = f"stanford target pose at {_point(np.asarray(target, dtype=float)[:3, 3])}"
        else:
            where = _where(robot, np.asarray(target, dtype=float))
        rejected = list(dict.fromkeys(why for _, why in dropped))
        raise IKError(f"{where}: every solution is outside the joint ranges ({'; '.join(rejected)})")
    return solutions


def _same(q: np.ndarray, other: np.ndarray, revolute: np.ndarray) -> bool:
    """Whether two solutions agree within IK_DEDUP_TOL (revolute joints mod 2π)."""
    diff = q - other
    diff[revolute] = (diff[revolute] + math.pi) % _TWO_PI - math.pi
    return bool(np.max(np.abs(diff)) <= IK_DEDUP_TOL)


def singularities(
    robot: str, q: ArrayLike, lengths: Mapping[str, float] | None = None, chain: SerialChain | None = None
) -> dict[str, bool]:
    """Which of the robot's singular conditions (SINGULAR_SETS) hold at q; each one drops the task Jacobian's rank.

    A sine or cosine counts as zero when |value| <= SINGULAR_TOL; a length (a2 + d3, the elbow's horizontal
    reach r, the Stanford d3) when |value| <= SINGULAR_TOL * size, size = the chain's DH lengths plus prismatic
    strokes in [m]. The leg uses leg.singular_families with its default tolerance (1e-9, same rule).

    Args:
        robot: "rrp", "elbow", "scara", "stanford" or "leg".
        q: Joint values in [rad] or [m], (n,).
        lengths: Link-length overrides in [m], or None for the defaults.

    Returns:
        rrp: cos_q2_zero, zero_reach; elbow: elbow_stretched_or_folded, wrist_centre_on_z0,
        wrist_centre_on_offset_cylinder; scara: arm_stretched_or_folded; stanford: wrist_sin_theta5_zero,
        arm_sin_theta2_zero, d3_zero; leg: knee, coxa_axis.
    """
    _, chain, p = _setup(robot, lengths, chain)
    q = [float(v) for v in _joint_values(chain, q)]  # Python floats: the flags are plain bools (JSON-ready)
    small = SINGULAR_TOL * _size(chain)
    if robot == "rrp":
        return {"cos_q2_zero": abs(math.cos(q[1])) <= SINGULAR_TOL, "zero_reach": abs(p["a2"] + q[2]) <= small}
    if robot == "elbow":
        reach = p["a2"] * math.cos(q[1]) + p["a3"] * math.cos(q[1] + q[2])  # r: horizontal reach in the arm plane
        no_offset = p["d"] <= small
        return {
            "elbow_stretched_or_folded": abs(math.sin(q[2])) <= SINGULAR_TOL,
            "wrist_centre_on_z0": no_offset and abs(reach) <= small,
            "wrist_centre_on_offset_cylinder": not no_offset and abs(reach) <= small,
        }
    if robot == "scara":
        return {"arm_stretched_or_folded": abs(math.sin(q[1])) <= SINGULAR_TOL}
    if robot == "stanford":
        return {
            "wrist_sin_theta5_zero": abs(math.sin(q[4])) <= SINGULAR_TOL,
            "arm_sin_theta2_zero": abs(math.sin(q[1])) <= SINGULAR_TOL,
            "d3_zero": abs(q[2]) <= small,
        }
    families = leg.singular_families(np.array(q), leg.LegGeometry(p["l1"], p["l2"], p["l3"]))
    return {name: bool(flag) for name, flag in families.items()}


def det_or_manipulability(
    robot: str, q: ArrayLike, lengths: Mapping[str, float] | None = None, chain: SerialChain | None = None
) -> tuple[str, float]:
    """Determinant of the robot's square task Jacobian (rows TASK_ROWS[robot] of chain.jacobian) in closed form.

    Every robot here has a square task Jacobian, so the kind is always "det" ("manipulability", sqrt(det(J Jᵀ)),
    is kept in the return type for chains whose task rows are not square):
        rrp: det Jv = (a2 + d3)² cos q2 [m²/rad²]
        elbow: det Jv = −a2 a3 sin θ3 (a2 cos θ2 + a3 cos(θ2 + θ3)) [m³/rad³]
        scara: det of rows (vx, vy, vz, wz) = a1 a2 sin θ2 [m²/rad²]; its magnitude is also the position-only
            manipulability sqrt(det(Jv Jvᵀ)), since θ4 does not move the tool point and d3 only moves it in z
        stanford: det J (6x6) = d3² sin θ2 sin θ5 = det(wrist-centre Jv) · det[z3 z4 z5] = (−d3² s2)(−s5) [m²]
        leg: det Jv = l2 l3 sin q3 rho (leg.det_jacobian) [m³/rad³]

    Args:
        robot: "rrp", "elbow", "scara", "stanford" or "leg".
        q: Joint values in [rad] or [m], (n,).
        lengths: Link-length overrides in [m], or None for the defaults.

    Returns:
        ("det", value).
    """
    _, chain, p = _setup(robot, lengths, chain)
    q = _joint_values(chain, q)
    if robot == "rrp":
        value = (p["a2"] + q[2]) ** 2 * math.cos(q[1])
    elif robot == "elbow":
        reach = p["a2"] * math.cos(q[1]) + p["a3"] * math.cos(q[1] + q[2])
        value = -p["a2"] * p["a3"] * math.sin(q[2]) * reach
    elif robot == "scara":
        value = p["a1"] * p["a2"] * math.sin(q[1])
    elif robot == "stanford":
        value = q[2] ** 2 * math.sin(q[1]) * math.sin(q[4])
    else:
        value = float(leg.det_jacobian(q, leg.LegGeometry(p["l1"], p["l2"], p["l3"])))
    return "det", float(value)
