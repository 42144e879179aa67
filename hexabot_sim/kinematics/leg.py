"""The 3-DOF hexabot leg of report 000 (modified DH, Khalil): FK, Jacobians, singularities, IK."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics import dh


@dataclasses.dataclass(frozen=True)
class LegGeometry:
    """Link lengths in [m] (report 000, Table 1)."""

    l1: float = 0.05  # coxa: hip axis to femur axis
    l2: float = 0.10  # femur
    l3: float = 0.10  # tibia: knee axis to foot


def foot_and_jacobian(
    q1: Any, q2: Any, q3: Any, l1: float, l2: float, l3: float, sin: Any = math.sin, cos: Any = math.cos
):
    """Foot position p = (x, y, z) in the hip frame and J = dp/dq (report eq. 15), as nested tuples.

    Works on floats (math.sin/cos, fast enough for a 1 kHz control loop) and on numpy arrays of
    any shape (pass sin=np.sin, cos=np.cos): one formula serves the controller and the batch code.

        rho = l1 + l2 cos q2 + l3 cos(q2 + q3)   horizontal distance of the foot from the coxa axis
        h   = l2 sin q2 + l3 sin(q2 + q3)        depth of the foot below the hip (z = -h)
    """
    s1, c1 = sin(q1), cos(q1)
    s2, c2 = sin(q2), cos(q2)
    s23, c23 = sin(q2 + q3), cos(q2 + q3)
    rho = l1 + l2 * c2 + l3 * c23
    h = l2 * s2 + l3 * s23
    v = l2 * c2 + l3 * c23  # d(-h)/dq2 = -v
    p = (c1 * rho, s1 * rho, -h)
    jac = (
        (-s1 * rho, -c1 * h, -c1 * l3 * s23),
        (c1 * rho, -s1 * h, -s1 * l3 * s23),
        (0.0 * q1, -v, -l3 * c23),
    )
    return p, jac


class IKError(UsageError):
    """No joint angles reach the requested foot position, or q1 is undetermined (foot on the coxa axis)."""


DEFAULT_GEOMETRY = LegGeometry()
CONVENTIONS = ("modified", "standard")

# Tolerance on cos q3 for a target just outside the reachable shell: within it, the target is moved onto the
# shell (by 5e-14 m at full stretch for the default leg); beyond it, ik raises IKError.
IK_REACH_TOL: float = 1e-12
# A target closer than this fraction of the leg's reach (l1 + l2 + l3) to the coxa axis counts as on it.
IK_AXIS_TOL: float = 1e-12
# IK branches whose joint angles all agree within this [rad] (mod 2π) are one solution (e.g. q3 = 0 twice).
IK_DEDUP_TOL: float = 1e-9


def _joints(q: ArrayLike, single: bool = False) -> np.ndarray:
    """Joint angles as a finite float array (..., 3), or exactly (3,) if `single`."""
    q = np.asarray(q, dtype=float)
    if single and q.shape != (3,):
        raise UsageError(f"q must be the 3 joint angles (coxa, femur, tibia) of shape (3,); got shape {q.shape}")
    if q.ndim == 0 or q.shape[-1] != 3:
        raise UsageError(f"q must hold the 3 joint angles (coxa, femur, tibia) on its last axis; got shape {q.shape}")
    if not np.all(np.isfinite(q)):
        raise UsageError("q must be finite joint angles in [rad]; got NaN or inf")
    return q


def _scalar_or_array(x: np.ndarray) -> float | np.ndarray:
    """A 0-d result as a Python float, anything else unchanged."""
    return float(x) if np.ndim(x) == 0 else x


def _wrap(angle: float) -> float:
    """Angle wrapped to (-π, π] in [rad]; angles already in that range are returned unchanged."""
    if -math.pi < angle <= math.pi:
        return angle
    return math.pi - (math.pi - angle) % (2.0 * math.pi)


def _wrap_array(angle: np.ndarray) -> np.ndarray:
    """Angles wrapped to [-π, π) in [rad] (for comparing angles mod 2π)."""
    return (angle + np.pi) % (2.0 * np.pi) - np.pi


def modified_dh_table(geom: LegGeometry = DEFAULT_GEOMETRY) -> list[tuple[float, float, float, float]]:
    """Modified DH rows (alpha [rad], d [m], theta offset [rad], r [m]) of frames 1-4 (report 000, Table 1).

    Frames 1-3 turn with the coxa, femur and tibia joints (theta_i = q_i + offset); frame 4 is the foot.
    """
    return [
        (0.0, 0.0, 0.0, 0.0),
        (-math.pi / 2, geom.l1, 0.0, 0.0),
        (0.0, geom.l2, 0.0, 0.0),
        (0.0, geom.l3, 0.0, 0.0),
    ]


def standard_dh_table(geom: LegGeometry = DEFAULT_GEOMETRY) -> list[tuple[float, float, float, float]]:
    """Standard DH rows (theta offset [rad], d [m], a [m], alpha [rad]) of links 1-3; frame 3 is the foot."""
    return [
        (0.0, 0.0, geom.l1, -math.pi / 2),
        (0.0, 0.0, geom.l2, 0.0),
        (0.0, 0.0, geom.l3, 0.0),
    ]


def intermediate_transforms(
    q: ArrayLike, geom: LegGeometry = DEFAULT_GEOMETRY, convention: str = "modified"
) -> list[np.ndarray]:
    """Link transforms: modified [T01, T12, T23, T34], standard [A1, A2, A3].

    Args:
        q: Joint angles (coxa, femur, tibia) in [rad], (3,) or (..., 3).
        geom: Link lengths.
        convention: "modified" (Khalil/Craig, as in report 000) or "standard" (classic DH).

    Returns:
        Transforms, each (4, 4), or (..., 4, 4) for a batch of configurations.
    """
    q = _joints(q)
    if convention == "modified":
        angles = [q[..., 0], q[..., 1], q[..., 2], np.zeros_like(q[..., 0])]
        return [
            dh.modified(alpha, d, angle + offset, r)
            for (alpha, d, offset, r), angle in zip(modified_dh_table(geom), angles, strict=True)
        ]
    if convention == "standard":
        return [
            dh.standard(q[..., i] + offset, d, a, alpha)
            for i, (offset, d, a, alpha) in enumerate(standard_dh_table(geom))
        ]
    raise UsageError(f"unknown DH convention {convention!r}; known: {', '.join(CONVENTIONS)}")


def transforms(q: ArrayLike, geom: LegGeometry = DEFAULT_GEOMETRY, convention: str = "modified") -> list[np.ndarray]:
    """Frames in the hip frame 0: modified [T01, T02, T03, T04], standard [T01, T02, T03]; the last is the foot.

    Both conventions give the same foot pose (position and orientation); the intermediate frames differ
    (e.g. the standard frame 1 sits on the femur axis, the modified frame 1 on the coxa axis).

    Args:
        q: Joint angles (coxa, femur, tibia) in [rad], (3,) or (..., 3).
        geom: Link lengths.
        convention: "modified" or "standard".

    Returns:
        Transforms, each (4, 4), or (..., 4, 4) for a batch of configurations.
    """
    return dh.chain(intermediate_transforms(q, geom, convention))


def fk(q: ArrayLike, geom: LegGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """Foot position in the hip frame in [m].

    Args:
        q: Joint angles (coxa, femur, tibia) in [rad], (3,) or (..., 3).
        geom: Link lengths.

    Returns:
        p = (c1 rho, s1 rho, -h), (3,) or (..., 3).
    """
    q = _joints(q)
    p, _ = foot_and_jacobian(q[..., 0], q[..., 1], q[..., 2], geom.l1, geom.l2, geom.l3, sin=np.sin, cos=np.cos)
    return np.stack(p, axis=-1)  # (..., 3)


def jacobian(q: ArrayLike, geom: LegGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """Foot Jacobian J = dp/dq by differentiating the FK formula (indirect method, report eq. 15).

    Args:
        q: Joint angles (coxa, femur, tibia) in [rad], (3,) or (..., 3).
        geom: Link lengths.

    Returns:
        J in [m/rad], (3, 3) or (..., 3, 3).
    """
    q = _joints(q)
    _, jac = foot_and_jacobian(q[..., 0], q[..., 1], q[..., 2], geom.l1, geom.l2, geom.l3, sin=np.sin, cos=np.cos)
    return np.stack([np.stack(row, axis=-1) for row in jac], axis=-2)  # (..., 3, 3)


def jacobian_direct(q: ArrayLike, geom: LegGeometry = DEFAULT_GEOMETRY) -> np.ndarray:
    """Foot Jacobian by the direct (geometric) method on the modified-DH frames: column j = z_j × (O_E − O_j).

    Args:
        q: Joint angles (coxa, femur, tibia) in [rad], (3,).
        geom: Link lengths.

    Returns:
        J in [m/rad], (3, 3).
    """
    frames = transforms(_joints(q, single=True), geom, "modified")  # T01, T02, T03, T04
    return dh.geometric_jacobian(frames, [0, 1, 2], frames[-1][:3, 3])[:3]  # (3, 3)


def jacobian_numerical(q: ArrayLike, geom: LegGeometry = DEFAULT_GEOMETRY, eps: float = 1e-6) -> np.ndarray:
    """Foot Jacobian by central differences of fk with step eps in [rad], (3, 3); q is (3,)."""
    return dh.numerical_jacobian(lambda x: fk(x, geom), _joints(q, single=True), eps)


def _rho_h_planar(q: np.ndarray, geom: LegGeometry) -> tuple[np.ndarray, ...]:
    """rho, h and the 2x2 planar block [[a, b], [c, d]] of J (columns 2-3 in the radial/vertical basis)."""
    q2, q3 = q[..., 1], q[..., 2]
    s2, c2, s23, c23 = np.sin(q2), np.cos(q2), np.sin(q2 + q3), np.cos(q2 + q3)
    rho = geom.l1 + geom.l2 * c2 + geom.l3 * c23
    h = geom.l2 * s2 + geom.l3 * s23
    v = geom.l2 * c2 + geom.l3 * c23
    return rho, h, -h, -geom.l3 * s23, -v, -geom.l3 * c23


def det_jacobian(q: ArrayLike, geom: LegGeometry = DEFAULT_GEOMETRY) -> float | np.ndarray:
    """det J = l2 l3 sin q3 rho in [m³/rad³]: zero at q3 = kπ (knee) and at rho = 0 (foot on the coxa axis).

    Args:
        q: Joint angles (coxa, femur, tibia) in [rad], (3,) or (..., 3).
        geom: Link lengths.

    Returns:
        A float for q of shape (3,), else an array (...).
    """
    q = _joints(q)
    rho = _rho_h_planar(q, geom)[0]
    return _scalar_or_array(geom.l2 * geom.l3 * np.sin(q[..., 2]) * rho)


def singular_values(
    q: ArrayLike, geom: LegGeometry = DEFAULT_GEOMETRY
) -> tuple[float | np.ndarray, float | np.ndarray]:
    """Smallest and largest singular values of J in [m/rad], in closed form.

    J's first column rho (-s1, c1, 0) is orthogonal to the vertical plane of the leg, which columns 2 and 3
    span, so the singular values are |rho| and those of the 2x2 planar block B:
    sigma_max(B) = (|(a + d, c − b)| + |(a − d, c + b)|) / 2 and sigma_min(B) = |det B| / sigma_max(B),
    with |det B| = l2 l3 |sin q3|.

    Args:
        q: Joint angles (coxa, femur, tibia) in [rad], (3,) or (..., 3).
        geom: Link lengths.

    Returns:
        (sigma_min, sigma_max): floats for q of shape (3,), else arrays (...).
    """
    q = _joints(q)
    rho, _, a, b, c, d = _rho_h_planar(q, geom)
    big = 0.5 * (np.hypot(a + d, c - b) + np.hypot(a - d, c + b))
    det_b = np.abs(geom.l2 * geom.l3 * np.sin(q[..., 2]))
    small = np.divide(det_b, big, out=np.zeros_like(big), where=big > 0)
    abs_rho = np.abs(rho)
    return _scalar_or_array(np.minimum(abs_rho, small)), _scalar_or_array(np.maximum(abs_rho, big))


def manipulability(q: ArrayLike, geom: LegGeometry = DEFAULT_GEOMETRY) -> float | np.ndarray:
    """Yoshikawa manipulability sqrt(det(J Jᵀ)) = |det J| in [m³/rad³]; float for (3,), else array (...)."""
    return _scalar_or_array(np.abs(det_jacobian(q, geom)))


def condition_number(q: ArrayLike, geom: LegGeometry = DEFAULT_GEOMETRY) -> float | np.ndarray:
    """sigma_max / sigma_min of J, >= 1; inf where sigma_min is exactly 0 (never NaN).

    Near a singularity that floating point does not hit exactly (e.g. sin(π) = 1.2e-16) it is large but finite.
    """
    small, big = (np.asarray(s) for s in singular_values(q, geom))
    cond = np.divide(big, small, out=np.full_like(big, np.inf), where=small > 0)
    return _scalar_or_array(cond)


def singular_families(q: ArrayLike, geom: LegGeometry = DEFAULT_GEOMETRY, tol: float = 1e-9) -> dict[str, bool]:
    """Which singular families the configuration belongs to (J loses rank in either).

    Args:
        q: Joint angles (coxa, femur, tibia) in [rad], (3,).
        geom: Link lengths.
        tol: "knee" when |sin q3| <= tol (leg stretched or folded); "coxa_axis" when
            |rho| <= tol (l1 + l2 + l3), i.e. the foot is on the coxa axis z0 and q1 does not move it.

    Returns:
        {"knee": bool, "coxa_axis": bool}.
    """
    q = _joints(q, single=True)
    rho = float(_rho_h_planar(q, geom)[0])
    reach = geom.l1 + geom.l2 + geom.l3
    return {"knee": abs(math.sin(q[2])) <= tol, "coxa_axis": abs(rho) <= tol * reach}


def _planar_ik(r: float, h: float, l2: float, l3: float) -> list[tuple[float, float]] | float:
    """(q2, q3) with l2 (c2, s2) + l3 (c23, s23) = (r, h), knee-positive first; the distance if out of reach.

    q3 = ±2 atan2(sqrt((l2 + l3)² − d²), sqrt(d² − (l2 − l3)²)) is the half-angle form of acos(c3),
    accurate near the stretched and folded leg where acos loses half the digits.
    """
    d = math.hypot(r, h)
    outer = (l2 + l3 - d) * (l2 + l3 + d)  # 2 l2 l3 (1 - c3)
    inner = (d - (l2 - l3)) * (d + (l2 - l3))  # 2 l2 l3 (1 + c3)
    slack = 2.0 * l2 * l3 * IK_REACH_TOL
    if outer < -slack or inner < -slack:
        return d
    q3 = 2.0 * math.atan2(math.sqrt(max(outer, 0.0)), math.sqrt(max(inner, 0.0)))
    out = []
    for q3_branch in (q3, -q3):
        q2 = math.atan2(h, r) - math.atan2(l3 * math.sin(q3_branch), l2 + l3 * math.cos(q3_branch))
        out.append((q2, q3_branch))
    return out


def ik(p: ArrayLike, geom: LegGeometry = DEFAULT_GEOMETRY, q1: float | None = None) -> list[np.ndarray]:
    """All joint angles that put the foot at p, in closed form (up to 4 branches).

    Branches, in this order: coxa towards the foot (q1 = atan2(y, x), rho > 0) with q3 >= 0, then q3 < 0;
    coxa turned away (q1 + π, rho < 0) with q3 >= 0, then q3 < 0. Unreachable branches are left out and
    coinciding ones (e.g. q3 = 0 twice) are returned once. Angles are wrapped to (-π, π].

    Args:
        p: Foot position (x, y, z) in the hip frame in [m], (3,).
        geom: Link lengths (l2 and l3 must be > 0).
        q1: Coxa angle in [rad] to use when p is on the coxa axis (x = y = 0), where every q1 reaches it;
            then only the branches with this q1 are returned. Ignored for any other p.

    Returns:
        Joint angles (coxa, femur, tibia) in [rad], each (3,); never empty.

    Raises:
        IKError: p is out of reach, or on the coxa axis and `q1` is not given.
    """
    p = np.asarray(p, dtype=float)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise UsageError(f"p must be a finite foot position (x, y, z) in [m] of shape (3,); got {p!r}")
    if not (geom.l2 > 0 and geom.l3 > 0):
        raise UsageError(f"ik needs femur and tibia lengths l2, l3 > 0 [m]; got l2={geom.l2}, l3={geom.l3}")
    x, y, z = (float(v) for v in p)
    where = f"foot target ({x:.6g}, {y:.6g}, {z:.6g}) m"
    radial = math.hypot(x, y)
    on_axis = radial <= IK_AXIS_TOL * (geom.l1 + geom.l2 + geom.l3)
    if on_axis:
        coxa = [(0.0 if q1 is None else float(q1), 0.0)]
    else:
        heading = math.atan2(y, x)
        coxa = [(heading, radial), (heading + math.pi, -radial)]

    solutions: list[np.ndarray] = []
    distances = []
    for angle1, rho in coxa:
        planar = _planar_ik(rho - geom.l1, -z, geom.l2, geom.l3)
        if isinstance(planar, float):
            distances.append(planar)
            continue
        for q2, q3 in planar:
            q = np.array([_wrap(angle1), _wrap(q2), _wrap(q3)])  # (3,)
            if all(np.max(np.abs(_wrap_array(q - s))) > IK_DEDUP_TOL for s in solutions):
                solutions.append(q)
    if not solutions:
        lo, hi = abs(geom.l2 - geom.l3), geom.l2 + geom.l3
        seen = " or ".join(f"{d:.6g}" for d in sorted(set(distances)))
        raise IKError(f"{where} is out of reach: {seen} m from the femur axis, reachable {lo:.6g} to {hi:.6g} m")
    if on_axis and q1 is None:
        raise IKError(f"{where} is on the coxa axis (x = y = 0), where q1 is arbitrary; pass q1=<angle in rad>")
    return solutions


def rpy(rot: ArrayLike) -> tuple[float | np.ndarray, float | np.ndarray, float | np.ndarray]:
    """Roll, pitch, yaw in [rad] of a rotation matrix R = Rz(yaw) Ry(pitch) Rx(roll) (ZYX Euler angles).

    Pitch is in [-π/2, π/2], roll and yaw in [-π, π]. At pitch = ±π/2 (gimbal lock) only yaw ∓ roll is
    determined; there roll = 0 is returned.

    Args:
        rot: Rotation matrix, (3, 3) or (..., 3, 3) (the rotation block of a (4, 4) transform works too).

    Returns:
        (roll, pitch, yaw): floats for one matrix, else arrays (...).
    """
    rot = np.asarray(rot, dtype=float)
    if rot.ndim < 2 or rot.shape[-2:] not in ((3, 3), (4, 4)):
        raise UsageError(f"rot must be a rotation matrix of shape (..., 3, 3) or (..., 4, 4); got {rot.shape}")
    cos_pitch = np.hypot(rot[..., 0, 0], rot[..., 1, 0])
    pitch = np.arctan2(-rot[..., 2, 0], cos_pitch)
    lock = cos_pitch < 1e-12  # cos(pitch) below rounding: roll and yaw are not separable
    roll = np.where(lock, 0.0, np.arctan2(rot[..., 2, 1], rot[..., 2, 2]))
    yaw = np.where(lock, np.arctan2(-rot[..., 0, 1], rot[..., 1, 1]), np.arctan2(rot[..., 1, 0], rot[..., 0, 0]))
    return _scalar_or_array(roll), _scalar_or_array(pitch), _scalar_or_array(yaw)


def continuous_zyx(rot: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """ZYX angles (roll, pitch, yaw) [rad] of the foot, on the branch that is continuous in time.

    The foot frame is R = Rz(q1) Rx(-pi/2) Rz(q2 + q3) = Rz(q1) Ry(q2 + q3) Rx(-pi/2): its z axis (the
    knee axis) stays horizontal, so yaw = its heading (= q1) and pitch = the tibia's angle below the
    horizontal in the leg's plane (= q2 + q3) are defined at every pose, also where the principal ZYX
    angles (rpy, pitch within +-pi/2) jump by pi at q2 + q3 = pi/2; roll then follows from R (-pi/2 here).

    Args:
        rot: (n, 3, 3) foot orientations in the hip frame, in time order.
    """
    yaw = np.unwrap(np.arctan2(-rot[:, 0, 2], rot[:, 1, 2]))  # heading of the knee axis
    cy, sy = np.cos(yaw), np.sin(yaw)
    pitch = np.unwrap(np.arctan2(-rot[:, 2, 0], rot[:, 0, 0] * cy + rot[:, 1, 0] * sy))
    # Rx(roll) = Ry(-pitch) Rz(-yaw) R; its second column is (0, cos roll, sin roll).
    n0 = cy * rot[:, 0, 1] + sy * rot[:, 1, 1]  # second column of Rz(-yaw) R
    n1 = -sy * rot[:, 0, 1] + cy * rot[:, 1, 1]
    n2 = rot[:, 2, 1]
    roll = np.unwrap(np.arctan2(np.sin(pitch) * n0 + np.cos(pitch) * n2, n1))
    return roll, pitch, yaw
