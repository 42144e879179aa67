"""Resolved-rate control of the leg's foot: dq = J^-1 (v_des + K (x_des - x)), damped near singularities.

Pure Python floats in the loop (no numpy): at 1 kHz a 3x3 problem is dominated by call overhead,
and this keeps the controller cheaper than the MuJoCo step it drives (scripts/bench.py). The walking
robots run `rate_steps` compiled by numba (control/kernels.py): its source must stay in the
subset numba compiles (floats, indexing, math; no helper that is not compiled too).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

from hexabot_sim.kinematics.leg import LegGeometry

Vec3 = tuple[float, float, float]
Mat3 = tuple[Vec3, Vec3, Vec3]
Reference = Callable[[float], Vec3]  # t [s] -> desired foot position in the hip frame [m]
# Smallest damping lambda [m/rad] the singular neighbourhood uses, whatever max_damping asks for.
# J J^T + lambda^2 I must stay invertible in floating point: with |J|^2 ~ 0.06 m^2/rad^2 for this
# leg, lambda^2 = 1e-10 is 1e-9 of it (far above rounding, 1e-16), so the solve keeps ~7 digits at an
# exact singularity (q3 at its 0 limit), where a smaller lambda would divide by zero. It changes
# dq only where it is capped by max_joint_speed anyway (|dq| ~ |u| / lambda there).
MIN_DAMPING: float = 1e-5


@dataclasses.dataclass(frozen=True)
class ResolvedRateGains:
    """Tuning of the resolved-rate loop.

    Attributes:
        task_gain: K in [1/s]: how fast a foot position error decays; removes integration drift.
        sigma_threshold: Smallest singular value of J [m/rad] below which damping switches on.
        max_damping: Damping lambda [m/rad] reached exactly at a singularity (at least MIN_DAMPING is used).
        max_joint_speed: Limit on every |dq_i| [rad/s]; dq is scaled as a whole to keep its direction.
        max_joint_acceleration: Limit on every |ddq_i| [rad/s^2] of the command, so servos can follow it.
    """

    task_gain: float = 50.0
    sigma_threshold: float = 0.01
    max_damping: float = 0.01
    max_joint_speed: float = 5.0
    max_joint_acceleration: float = math.inf


def sigma_min(rho: float, sin_q3: float, cos_q3: float, l2: float, l3: float) -> float:
    """Smallest singular value of the leg Jacobian [m/rad], in closed form.

    Column 1 is rho (-s1, c1, 0), orthogonal to columns 2 and 3 (the leg's vertical plane), so the
    singular values are |rho| and those of the planar 2x2 block. That block has Frobenius norm^2
    F = |femur axis to foot|^2 + l3^2 = l2^2 + 2 l3^2 + 2 l2 l3 cos q3 and determinant D = l2 l3 sin q3,
    so sigma^2 = 2 D^2 / (F + sqrt(F^2 - 4 D^2)).
    """
    f = l2 * l2 + 2 * l3 * l3 + 2 * l2 * l3 * cos_q3
    d = l2 * l3 * sin_q3
    planar = math.sqrt(2 * d * d / (f + math.sqrt(max(f * f - 4 * d * d, 0.0))))
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
        self._next_t = math.nan  # time and reference point of the next expected call
        self._next_ref: Vec3 = (0.0, 0.0, 0.0)
        self._k = step_constants(geometry, gains, q_lower, q_upper)

    def update(self, q: Vec3, t: float, dt: float) -> tuple[float, ...]:
        """Advances q_cmd from t to t + dt given the measured joint angles q at time t.

        Returns:
            (q_cmd..., dq...): the new joint command [rad] and the joint velocity [rad/s] it moves at.
        """
        # The reference at t (cached from the previous call when it asked for this t) and at t + dt.
        if t == self._next_t:
            xd0, yd0, zd0 = self._next_ref
        else:
            xd0, yd0, zd0 = self.reference(t)
        self._next_t = t + dt
        self._next_ref = xd1, yd1, zd1 = self.reference(self._next_t)
        dq = list(self.dq)
        rate = [0.0, 0.0, 0.0]
        feed(self.gains.task_gain, (xd0, yd0, zd0), (xd1, yd1, zd1), dt, rate)
        rate_steps(self._k, list(q), self.q_cmd, dq, rate, dt)
        self.dq = (dq[0], dq[1], dq[2])
        return (*self.q_cmd, *dq)


# Constants of one leg for rate_steps, unpacked once per call (attribute lookups dominate a pure-Python loop).
StepConstants = tuple[float, ...]


def step_constants(geometry: LegGeometry, gains: ResolvedRateGains, q_lower: Vec3, q_upper: Vec3) -> StepConstants:
    """(l1, l2, l3, K, sigma threshold, lambda max, speed limit, acceleration limit, braking zone, lower, upper,
    lower + zone, upper - zone)."""
    zone = gains.max_joint_speed**2 / (2 * gains.max_joint_acceleration)  # [rad]
    return (
        geometry.l1, geometry.l2, geometry.l3, gains.task_gain, gains.sigma_threshold, gains.max_damping,
        gains.max_joint_speed, gains.max_joint_acceleration, zone, *q_lower, *q_upper,
        *(lo + zone for lo in q_lower), *(hi - zone for hi in q_upper),
    )  # fmt: skip


def feed(gain: float, target0, target1, dt: float, out) -> None:
    """The target part of the task-space rate, (x_des(t + dt) - x_des(t)) / dt + K x_des(t), for rate_steps,
    into `out` (as many values as it holds; compiled as kernels.feed for a walking robot's rows)."""
    inv = 1.0 / dt
    for i in range(len(out)):
        out[i] = (target1[i] - target0[i]) * inv + gain * target0[i]


def rate_steps(
    k: StepConstants,
    q: list[float],
    cmd: list[float],
    dq: list[float],
    feed: list[float],
    dt: float,
) -> None:
    """One resolved-rate step of each of len(q) // 3 legs: dq = J^+ (v_des + K (x_des - x)), limited, integrated.

    The leg's Jacobian has a block structure that gives its inverse in closed form: column 1 is
    rho (-s1, c1, 0), orthogonal to the leg plane spanned by columns 2 and 3, so the tangential rate
    is u_t / rho and the (femur, tibia) rates solve the planar 2x2 block B (det B = -l2 l3 sin q3).
    Near a singularity (sigma_min < threshold) damped least squares J^T (J J^T + lambda^2 I)^-1 u
    decouples the same way. Then: the joint speed limit on dq as a whole (the foot keeps its
    direction), braking before a range limit, the acceleration limit on the change of dq, and the
    integration inside the ranges. Pure Python floats for one leg (leg-step), cheaper than numpy's
    per-call overhead; compiled for a walking robot's legs (kernels.rate_steps, on arrays).

    Args:
        k: step_constants of the legs (the same for all).
        q: Measured joint angles [rad] at t, 3 per leg (coxa, femur, tibia).
        cmd: Joint command q_cmd [rad] at t; replaced by q_cmd at t + dt (in place).
        dq: Joint rates of the previous step [rad/s]; replaced by the rates q_cmd moved at (in place).
        feed: v_des + K x_des [m/s], 3 per leg, each in its leg's hip frame: the reference's mean velocity
            over the step plus K times the desired foot position at t (see `feed`); the task-space rate
            is feed - K x(q).
        dt: Control period [s].
    """
    l1, l2, l3, gain, threshold, max_damping, max_speed, max_acc, zone, lo1, lo2, lo3, hi1, hi2, hi3 = k[:15]
    lz1, lz2, lz3, hz1, hz2, hz3 = k[15:]
    thr2, limit, sin, cos, sqrt = threshold * threshold, max_acc * dt, math.sin, math.cos, math.sqrt
    for j in range(0, len(q), 3):
        q1, q2, q3 = q[j], q[j + 1], q[j + 2]
        s1, co1 = sin(q1), cos(q1)
        s2, co2 = sin(q2), cos(q2)
        q23 = q2 + q3
        s23, c23 = sin(q23), cos(q23)
        rho = l1 + l2 * co2 + l3 * c23  # horizontal distance of the foot from the coxa axis
        h = l2 * s2 + l3 * s23  # depth of the foot below the hip
        # Task-space rate: the reference's mean velocity over the step plus K times the position error.
        grho = gain * rho
        ux = feed[j] - co1 * grho
        uy = feed[j + 1] - s1 * grho
        uz = feed[j + 2] + gain * h
        # Tangential part (coxa column) and the leg plane (radial, vertical).
        ut = co1 * uy - s1 * ux
        ur = co1 * ux + s1 * uy
        b11, b12, b21, b22 = -h, -l3 * s23, -(l2 * co2 + l3 * c23), -l3 * c23
        det = b11 * b22 - b12 * b21
        frob = b11 * b11 + b12 * b12 + b21 * b21 + b22 * b22
        # sigma_min >= min(|rho|, |det| / sqrt(frob)): far from every singularity, the exact inverse.
        if (rho >= threshold or rho <= -threshold) and det * det >= thr2 * frob:
            d1 = ut / rho
            d2 = (b22 * ur - b12 * uz) / det
            d3 = (b11 * uz - b21 * ur) / det
        else:
            planar = sqrt(2 * det * det / (frob + sqrt(max(frob * frob - 4 * det * det, 0.0))))
            ratio = min(abs(rho), planar) / threshold
            lam = max(max_damping * sqrt(max(1.0 - ratio * ratio, 0.0)), MIN_DAMPING) if ratio < 1.0 else 0.0
            lam2 = lam * lam
            d1 = rho * ut / (rho * rho + lam2) if rho * rho + lam2 > 0 else 0.0
            a11, a12, a22 = b11 * b11 + b12 * b12 + lam2, b11 * b21 + b12 * b22, b21 * b21 + b22 * b22 + lam2
            da = a11 * a22 - a12 * a12
            w1, w2 = (a22 * ur - a12 * uz) / da, (a11 * uz - a12 * ur) / da
            d2, d3 = b11 * w1 + b21 * w2, b12 * w1 + b22 * w2
        # Joint speed limit, applied to dq as a whole so the foot keeps its direction.
        if not (-max_speed <= d1 <= max_speed and -max_speed <= d2 <= max_speed and -max_speed <= d3 <= max_speed):
            scale = max_speed / max(abs(d1), abs(d2), abs(d3))
            d1, d2, d3 = d1 * scale, d2 * scale, d3 * scale
        # Joint ranges: never faster toward a limit than braking at max_acc can stop, sqrt(2 a room).
        c1, c2, c3 = cmd[j], cmd[j + 1], cmd[j + 2]
        if not (lz1 <= c1 <= hz1 and lz2 <= c2 <= hz2 and lz3 <= c3 <= hz3):
            brake = 2.0 * max_acc
            if c1 - lo1 < zone or hi1 - c1 < zone:
                d1 = min(max(d1, -sqrt(brake * max(c1 - lo1, 0.0))), sqrt(brake * max(hi1 - c1, 0.0)))
            if c2 - lo2 < zone or hi2 - c2 < zone:
                d2 = min(max(d2, -sqrt(brake * max(c2 - lo2, 0.0))), sqrt(brake * max(hi2 - c2, 0.0)))
            if c3 - lo3 < zone or hi3 - c3 < zone:
                d3 = min(max(d3, -sqrt(brake * max(c3 - lo3, 0.0))), sqrt(brake * max(hi3 - c3, 0.0)))
        # Joint acceleration limit on the change of the command, as a whole.
        p1, p2, p3 = dq[j], dq[j + 1], dq[j + 2]
        e1, e2, e3 = d1 - p1, d2 - p2, d3 - p3
        if not (-limit <= e1 <= limit and -limit <= e2 <= limit and -limit <= e3 <= limit):
            f = limit / max(abs(e1), abs(e2), abs(e3))
            d1, d2, d3 = p1 + e1 * f, p2 + e2 * f, p3 + e3 * f
        # Integrate inside the ranges; the rate recorded is what q_cmd actually did.
        n1, n2, n3 = c1 + d1 * dt, c2 + d2 * dt, c3 + d3 * dt
        if not (lo1 <= n1 <= hi1 and lo2 <= n2 <= hi2 and lo3 <= n3 <= hi3):
            n1, n2, n3 = min(max(n1, lo1), hi1), min(max(n2, lo2), hi2), min(max(n3, lo3), hi3)
        cmd[j], cmd[j + 1], cmd[j + 2] = n1, n2, n3
        dq[j], dq[j + 1], dq[j + 2] = (n1 - c1) / dt, (n2 - c2) / dt, (n3 - c3) / dt
