"""A legged robot built of N copies of the 3-DOF DH leg: where each leg sits on the body, body-frame FK/IK of all feet.

Shared by every legged robot (the hexabot's layout is robots/hexabot/model.py). Nothing here knows how many
legs there are: it comes from the layout (`len(layout.legs)`), and every array is (n_legs, ...).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from hexabot_sim.kinematics import leg as leg_kin

JOINTS: tuple[str, ...] = ("coxa", "femur", "tibia")
# Joint ranges of one leg [rad] (coxa, femur, tibia): the leg's DH table (hexabot_sim.kinematics.robots "leg").
JOINT_LOWER = (-math.pi / 2, -math.pi / 2, 0.0)
JOINT_UPPER = (math.pi / 2, math.pi / 2, math.radians(160.0))
MIN_LEGS: int = 3  # fewer feet span no support polygon (and no stance plane)


@dataclasses.dataclass(frozen=True)
class Layout:
    """Geometry and masses of a legged robot (body frame: x forward, y left, z up, origin at the plate centre).

    Each leg is the 3-DOF leg of models/leg.xml (modified DH, L1 = 50 mm, L2 = L3 = 100 mm), its
    frame 0 (site `<leg>_hip`) at `hips[i]` in the plate's mid-plane, turned by `yaws[i]` about z.

    Attributes:
        legs: Leg names, at least MIN_LEGS, unique. For a robot with two rows of legs: the left row front
            to rear, then the right row front to rear (the order the gaits of control/gait.py use).
        hips: Hip positions (x, y) [m] in the body frame, one per leg.
        yaws_deg: Hip yaw of each leg about z [deg] (0: the leg points forward, 90: to the left).
    """

    legs: tuple[str, ...]
    hips: tuple[tuple[float, float], ...]
    yaws_deg: tuple[float, ...]
    geometry: leg_kin.LegGeometry = leg_kin.DEFAULT_GEOMETRY
    plate: tuple[float, float, float] = (0.15, 0.08, 0.015)  # half sizes [m] of the body plate
    body_mass: float = 1.0  # [kg] plate, electronics and battery
    link_masses: tuple[float, float, float] = (0.03, 0.06, 0.04)  # [kg] coxa, femur, tibia (as leg.xml)
    foot_radius: float = 0.008  # [m] sphere foot (as leg.xml)
    neutral_reach: float = 0.13  # [m] horizontal hip-to-foot distance of the neutral stance
    stand_height: float = 0.09  # [m] depth of the foot centre below the hip in the neutral stance

    def __post_init__(self) -> None:
        n = len(self.legs)
        if n < MIN_LEGS:
            raise ValueError(f"a legged robot needs at least {MIN_LEGS} legs; got {n} ({', '.join(self.legs)})")
        if len(set(self.legs)) != n:
            raise ValueError(f"leg names must be unique; got {', '.join(self.legs)}")
        if len(self.hips) != n or len(self.yaws_deg) != n:
            raise ValueError(f"{n} legs need {n} hips and {n} yaws; got {len(self.hips)} and {len(self.yaws_deg)}")

    @property
    def n_legs(self) -> int:
        return len(self.legs)

    @property
    def yaws(self) -> np.ndarray:
        return np.radians(self.yaws_deg)

    @property
    def total_mass(self) -> float:
        return self.body_mass + self.n_legs * sum(self.link_masses)

    def hip_positions(self) -> np.ndarray:
        """Hip origins in the body frame, (n_legs, 3) [m]."""
        return np.array([[x, y, 0.0] for x, y in self.hips])

    def hip_rotations(self) -> np.ndarray:
        """Rotation from each hip frame to the body frame, (n_legs, 3, 3)."""
        c, s = np.cos(self.yaws), np.sin(self.yaws)
        rot = np.zeros((self.n_legs, 3, 3))
        rot[:, 0, 0], rot[:, 0, 1], rot[:, 1, 0], rot[:, 1, 1], rot[:, 2, 2] = c, -s, s, c, 1.0
        return rot

    def neutral_feet_hip(self) -> np.ndarray:
        """Neutral foot centres in each hip frame, (n_legs, 3) [m]."""
        return np.tile([self.neutral_reach, 0.0, -self.stand_height], (self.n_legs, 1))

    def neutral_feet_body(self) -> np.ndarray:
        """Neutral foot centres in the body frame, (n_legs, 3) [m]."""
        return hip_to_body(self, self.neutral_feet_hip())

    def body_height(self) -> float:
        """Height of the body origin above flat ground in the neutral stance [m]."""
        return self.stand_height + self.foot_radius


def mirrored(
    rows: Sequence[str], hips: Sequence[tuple[float, float]], yaws_deg: Sequence[float]
) -> tuple[tuple[str, ...], tuple[tuple[float, float], ...], tuple[float, ...]]:
    """(legs, hips, yaws_deg) of a robot with two mirrored rows of legs, from its left row (front to rear).

    Args:
        rows: Row letters of the left legs, front to rear ("f", "m", "r"): legs l<row>, then r<row>.
        hips: Left hips (x, y > 0) [m]; the right ones are (x, -y).
        yaws_deg: Left yaws [deg]; the right ones are their negatives.
    """
    if not len(rows) == len(hips) == len(yaws_deg):
        raise ValueError(f"one hip and one yaw per row; got {len(rows)} rows, {len(hips)} hips, {len(yaws_deg)} yaws")
    legs = tuple(f"l{r}" for r in rows) + tuple(f"r{r}" for r in rows)
    right = tuple((float(x), -float(y)) for x, y in hips)
    left = tuple((float(x), float(y)) for x, y in hips)
    return legs, left + right, tuple(float(a) for a in yaws_deg) + tuple(-float(a) for a in yaws_deg)


def hip_to_body(layout: Layout, points: ArrayLike) -> np.ndarray:
    """Points (n_legs, 3) given in each leg's hip frame, expressed in the body frame."""
    points = np.asarray(points, dtype=float)
    return np.einsum("lij,lj->li", layout.hip_rotations(), points) + layout.hip_positions()


def body_to_hip(layout: Layout, points: ArrayLike) -> np.ndarray:
    """Points (n_legs, 3) given in the body frame, expressed in each leg's hip frame."""
    points = np.asarray(points, dtype=float)
    return np.einsum("lji,lj->li", layout.hip_rotations(), points - layout.hip_positions())


def feet_body(layout: Layout, q: ArrayLike) -> np.ndarray:
    """Foot centres in the body frame for joint angles q (n_legs, 3) [rad] -> (n_legs, 3) [m]."""
    q = np.asarray(q, dtype=float).reshape(layout.n_legs, 3)
    g = layout.geometry
    p, _ = leg_kin.foot_and_jacobian(q[:, 0], q[:, 1], q[:, 2], g.l1, g.l2, g.l3, sin=np.sin, cos=np.cos)
    return hip_to_body(layout, np.stack(p, axis=-1))


def jacobians_body(layout: Layout, q: ArrayLike) -> np.ndarray:
    """d(foot in body frame)/dq of each leg, (n_legs, 3, 3), from the leg's analytic Jacobian rotated by the hip yaw."""
    n = layout.n_legs
    q = np.asarray(q, dtype=float).reshape(n, 3)
    g = layout.geometry
    _, jac = leg_kin.foot_and_jacobian(q[:, 0], q[:, 1], q[:, 2], g.l1, g.l2, g.l3, sin=np.sin, cos=np.cos)
    jac_hip = np.stack([np.stack([np.broadcast_to(np.asarray(v, float), (n,)) for v in row], -1) for row in jac], 1)
    return np.einsum("lij,ljk->lik", layout.hip_rotations(), jac_hip)


def ik_body(layout: Layout, feet: ArrayLike) -> np.ndarray:
    """Joint angles (n_legs, 3) putting each foot at `feet` (n_legs, 3) in the body frame: coxa toward the foot,
    knee up.

    Raises:
        leg.IKError: if a foot is out of reach or the branch leaves the joint ranges.
    """
    hip = body_to_hip(layout, feet)
    q = np.empty((layout.n_legs, 3))
    for i, point in enumerate(hip):
        branches = leg_kin.ik(point, layout.geometry, q1=0.0)
        inside = [
            b
            for b in branches
            if np.all(b >= np.array(JOINT_LOWER) - 1e-12) and np.all(b <= np.array(JOINT_UPPER) + 1e-12)
        ]
        if not inside:
            where = ", ".join(f"{round(float(v), 6) + 0.0:.4g}" for v in point)
            raise leg_kin.IKError(f"foot {layout.legs[i]} at ({where}) m (hip frame) is outside the joint ranges")
        q[i] = inside[0]
    return q


def tallest_stance(layout: Layout) -> float:
    """The largest stand height [m] (foot centre below the hip) up to which every foot reaches its neutral point
    (`neutral_reach` out from its hip) on the walking branch from the robot's own stance height (bisection, rounded
    down to 0.1 mm); the own height itself if even that is out of reach."""
    lo, hi = layout.stand_height, layout.geometry.l1 + layout.geometry.l2 + layout.geometry.l3
    if not ik_hip_batch(layout, [layout.neutral_reach, 0.0, -lo])[1] or hi <= lo:
        return lo
    while hi - lo > 1e-5:
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if ik_hip_batch(layout, [layout.neutral_reach, 0.0, -mid])[1] else (lo, mid)
    return math.floor(lo * 1e4) / 1e4


def ik_hip_batch(layout: Layout, points: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Vectorised IK in the hip frame, the walking branch (coxa toward the foot, knee up: q3 >= 0).

    Args:
        points: Foot centres (..., 3) in a hip frame [m].

    Returns:
        (q (..., 3) [rad], ok (...,)): ok is False where the point is out of reach or a joint leaves its range.
    """
    p = np.asarray(points, dtype=float)
    g = layout.geometry
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    q1 = np.arctan2(y, x)
    r = np.hypot(x, y) - g.l1
    h = -z
    d2 = r * r + h * h
    outer = (g.l2 + g.l3) ** 2 - d2  # 2 l2 l3 (1 - c3)
    inner = d2 - (g.l2 - g.l3) ** 2  # 2 l2 l3 (1 + c3)
    reach = (outer >= 0) & (inner >= 0)
    q3 = 2.0 * np.arctan2(np.sqrt(np.maximum(outer, 0.0)), np.sqrt(np.maximum(inner, 0.0)))
    q2 = np.arctan2(h, r) - np.arctan2(g.l3 * np.sin(q3), g.l2 + g.l3 * np.cos(q3))
    q = np.stack([q1, q2, q3], axis=-1)
    lower, upper = np.array(JOINT_LOWER), np.array(JOINT_UPPER)
    ok = reach & np.all((q >= lower - 1e-12) & (q <= upper + 1e-12), axis=-1)
    return q, ok


def foot_pitch(layout: Layout, points: ArrayLike) -> np.ndarray:
    """Pitch q2 + q3 [rad] of the tibia at foot centres (..., 3) in a hip frame, on ik_hip_batch's branch (q3 >= 0)."""
    p = np.asarray(points, dtype=float)
    g = layout.geometry
    return pitch_of(p[..., 0], p[..., 1], p[..., 2], g.l1, g.l2, g.l3)


def pitch_of(x, y, z, l1: float, l2: float, l3: float):
    """Pitch q2 + q3 [rad] of the tibia at a foot centre (x, y, z) in a hip frame [m] (arrays or floats; numba
    compiles it for the rolling feet, control/plan_kernels.py), on ik_hip_batch's branch (q3 >= 0).

    Cheaper than the whole IK (no coxa angle, two arctangents): q2 = atan2(h, r) - atan2(l3 s3, l2 + l3 c3)
    and q3 - atan2(l3 s3, l2 + l3 c3) = atan2(l2 s3, l3 + l2 c3) (the argument of e^{i q3} conj(l2 + l3 e^{i q3})).
    Points out of reach get the pitch of the nearest reachable stretch (c3 clipped to [-1, 1]).
    """
    r = np.hypot(x, y) - l1
    h = -z
    c3 = np.minimum(np.maximum((r * r + h * h - l2 * l2 - l3 * l3) / (2 * l2 * l3), -1.0), 1.0)
    s3 = np.sqrt(1.0 - c3 * c3)
    return np.arctan2(h, r) + np.arctan2(l2 * s3, l3 + l2 * c3)
