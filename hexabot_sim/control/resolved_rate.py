"""Resolved-rate control of the leg's foot: dq = J^-1 (v_des + K (x_des - x)), damped near singularities.

Pure Python floats in the loop (no numpy): at 1 kHz a 3x3 problem is dominated by call overhead,
and this keeps the controller cheaper than the MuJoCo step it drives (scripts/bench.py).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

from hexabot_sim.kinematics.leg import LegGeometry, foot_and_jacobian

Vec3 = tuple[float, float, float]
Mat3 = tuple[Vec3, Vec3, Vec3]
Reference = Callable[[float], Vec3]  # t [s] -> desired foot position in the hip frame [m]


@dataclasses.dataclass(frozen=True)
class ResolvedRateGains:
    """Tuning of the resolved-rate loop.

    Attributes:
        task_gain: K in [1/s]: how fast a foot position error decays; removes integration drift.
        sigma_threshold: Smallest singular value of J [m/rad] below which damping switches on.
        max_damping: Damping lambda [m/rad] reached exactly at a singularity.
        max_joint_speed: Limit on every |dq_i| [rad/s]; dq is scaled as a whole to keep its direction.
        max_joint_acceleration: Limit on every |ddq_i| [rad/s^2] of the command, so servos can follow it.
    """

    task_gain: float = 50.0
    sigma_threshold: float = 0.01
    max_damping: float = 0.01
    max_joint_speed: float = 5.0
    max_joint_acceleration: float = math.inf


def sigma_min(jac: Mat3, rho: float, l3: float, sin_q3: float, l2: float) -> float:
    """Smallest singular value of the leg Jacobian [m/rad], in closed form.

    Column 1 is rho (-s1, c1, 0), orthogonal to columns 2 and 3 (the leg's vertical plane), so the
    singular values are |rho| and those of the planar 2x2 block, whose Frobenius norm^2 F and
    determinant D = l2 l3 sin q3 give sigma^2 = 2 D^2 / (F + sqrt(F^2 - 4 D^2)).
    """
    f = jac[0][1] ** 2 + jac[1][1] ** 2 + jac[2][1] ** 2 + jac[0][2] ** 2 + jac[1][2] ** 2 + jac[2][2] ** 2
    d = l2 * l3 * sin_q3
    disc = math.sqrt(max(f * f - 4 * d * d, 0.0))
    planar = math.sqrt(2 * d * d / (f + disc)) if f > 0 else 0.0
    return min(abs(rho), planar)


def _solve3(a: Mat3, b: Vec3) -> Vec3:
    """Solves a x = b by Cramer's rule (a non-singular)."""
    (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = a
    c0 = a11 * a22 - a12 * a21
    c1 = a12 * a20 - a10 * a22
    c2 = a10 * a21 - a11 * a20
    det = a00 * c0 + a01 * c1 + a02 * c2
    b0, b1, b2 = b
    return (
        (b0 * c0 + b1 * (a02 * a21 - a01 * a22) + b2 * (a01 * a12 - a02 * a11)) / det,
        (b0 * c1 + b1 * (a00 * a22 - a02 * a20) + b2 * (a02 * a10 - a00 * a12)) / det,
        (b0 * c2 + b1 * (a01 * a20 - a00 * a21) + b2 * (a00 * a11 - a01 * a10)) / det,
    )


def damped_solve(jac: Mat3, u: Vec3, lam: float) -> Vec3:
    """dq = J^T (J J^T + lam^2 I)^-1 u; exactly J^-1 u when lam = 0."""
    if lam == 0.0:
        return _solve3(jac, u)
    l2 = lam * lam
    r0, r1, r2 = jac
    a = (
        (r0[0] * r0[0] + r0[1] * r0[1] + r0[2] * r0[2] + l2, r0[0] * r1[0] + r0[1] * r1[1] + r0[2] * r1[2],
         r0[0] * r2[0] + r0[1] * r2[1] + r0[2] * r2[2]),
        (r1[0] * r0[0] + r1[1] * r0[1] + r1[2] * r0[2], r1[0] * r1[0] + r1[1] * r1[1] + r1[2] * r1[2] + l2,
         r1[0] * r2[0] + r1[1] * r2[1] + r1[2] * r2[2]),
        (r2[0] * r0[0] + r2[1] * r0[1] + r2[2] * r0[2], r2[0] * r1[0] + r2[1] * r1[1] + r2[2] * r1[2],
         r2[0] * r2[0] + r2[1] * r2[1] + r2[2] * r2[2] + l2),
    )  # fmt: skip
    w0, w1, w2 = _solve3(a, u)
    return (
        r0[0] * w0 + r1[0] * w1 + r2[0] * w2,
        r0[1] * w0 + r1[1] * w1 + r2[1] * w2,
        r0[2] * w0 + r1[2] * w1 + r2[2] * w2,
    )


@dataclasses.dataclass
class StepInfo:
    """What the controller saw and did at the last call (for recording)."""

    sigma: float = math.inf  # smallest singular value of J [m/rad]
    damping: float = 0.0  # lambda used [m/rad]
    speed_scale: float = 1.0  # < 1 when the joint speed limit was active


class ResolvedRateController:
    """Integrates dq = J^+ (v_des + K (x_des - x)) into a joint command q_cmd.

    The foot error is measured from the joint angles the controller is given (MuJoCo's qpos), so
    integration drift and servo lag are fed back instead of accumulating. Near a singularity
    (sigma_min < threshold) damped least squares with lambda^2 = lambda_max^2 (1 - (sigma/threshold)^2)
    trades exact tracking for bounded joint speeds; joint speeds and ranges are always respected.
    """

    def __init__(
        self,
        geometry: LegGeometry,
        gains: ResolvedRateGains,
        reference: Reference,
        q_start: Vec3,
        q_lower: Vec3,
        q_upper: Vec3,
    ) -> None:
        self.geometry = geometry
        self.gains = gains
        self.reference = reference
        self.q_cmd: list[float] = list(q_start)
        self.dq: Vec3 = (0.0, 0.0, 0.0)
        self.q_lower = q_lower
        self.q_upper = q_upper
        self.info = StepInfo()

    def update(self, q: Vec3, t: float, dt: float) -> None:
        """Advances q_cmd from t to t + dt given the measured joint angles q at time t."""
        g, k = self.geometry, self.gains
        (x, y, z), jac = foot_and_jacobian(q[0], q[1], q[2], g.l1, g.l2, g.l3)
        # Feedforward: the reference's exact mean velocity over the step; feedback: K times the error.
        xd0, yd0, zd0 = self.reference(t)
        xd1, yd1, zd1 = self.reference(t + dt)
        u = (
            (xd1 - xd0) / dt + k.task_gain * (xd0 - x),
            (yd1 - yd0) / dt + k.task_gain * (yd0 - y),
            (zd1 - zd0) / dt + k.task_gain * (zd0 - z),
        )
        # Damping grows only inside the singular neighbourhood.
        rho = -jac[0][0] * math.sin(q[0]) + jac[1][0] * math.cos(q[0])
        sigma = sigma_min(jac, rho, g.l3, math.sin(q[2]), g.l2)
        ratio = sigma / k.sigma_threshold
        lam = k.max_damping * math.sqrt(1.0 - ratio * ratio) if ratio < 1.0 else 0.0
        dq = list(damped_solve(jac, u, lam))
        # Joint ranges: no speed further into a limit the command already sits at.
        for i in range(3):
            if (self.q_cmd[i] <= self.q_lower[i] and dq[i] < 0) or (self.q_cmd[i] >= self.q_upper[i] and dq[i] > 0):
                dq[i] = 0.0
        # Joint speed limit, applied to dq as a whole so the foot keeps its direction.
        fastest = max(abs(dq[0]), abs(dq[1]), abs(dq[2]))
        scale = k.max_joint_speed / fastest if fastest > k.max_joint_speed else 1.0
        dq = [dq[0] * scale, dq[1] * scale, dq[2] * scale]
        # Joint acceleration limit on the change of the command, again as a whole.
        change = [dq[i] - self.dq[i] for i in range(3)]
        largest = max(abs(change[0]), abs(change[1]), abs(change[2]))
        limit = k.max_joint_acceleration * dt
        if largest > limit:
            dq = [self.dq[i] + change[i] * limit / largest for i in range(3)]
        self.dq = (dq[0], dq[1], dq[2])
        for i in range(3):
            self.q_cmd[i] = min(max(self.q_cmd[i] + self.dq[i] * dt, self.q_lower[i]), self.q_upper[i])
        self.info.sigma, self.info.damping, self.info.speed_scale = sigma, lam, scale
