"""Resolved-rate control of any serial arm's tool: dq = J^+ (v_des + K e), damped near singularities, limited."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

# Smallest damping lambda [m/rad] used where sigma_min is below the threshold, whatever max_damping asks for: J J^T +
# lambda^2 I stays invertible in floating point at an exact singularity (as control/resolved_rate.MIN_DAMPING).
MIN_DAMPING: float = 1e-5
LIMIT_TOL: float = 1e-6  # [rad or m] a command this close to a range end is at it (a "limit hit")
Kinematics = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]  # q (n,) -> tool pose (4, 4), J (6, n)


@dataclasses.dataclass(frozen=True)
class ArmRateGains:
    """Tuning of the resolved-rate loop of an arm.

    Attributes:
        task_gain: K in [1/s]: how fast a tool position (and orientation) error decays.
        sigma_threshold: Smallest singular value of the task Jacobian below which damping switches on.
        max_damping: Damping lambda reached exactly at a singularity (at least MIN_DAMPING is used).
        max_speed: Limit on each |dq_i|, (n,) [rad/s or m/s]; dq is scaled as a whole to keep its direction.
        max_acceleration: Limit on each |ddq_i| of the command, (n,) [rad/s^2 or m/s^2]: braking before a range end.
        nullspace_gain: [1/s] pull toward the reference pose in the null space of a redundant task (n > rows).
    """

    task_gain: float
    sigma_threshold: float
    max_damping: float
    max_speed: np.ndarray
    max_acceleration: np.ndarray
    nullspace_gain: float = 0.0


def rotation_error(rot: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """Rotation vector (3,) [rad] taking `rot` (3, 3) to `goal` (3, 3) in the world frame: log(goal rotᵀ)."""
    delta = goal @ rot.T  # (3, 3)
    axial = 0.5 * np.array([delta[2, 1] - delta[1, 2], delta[0, 2] - delta[2, 0], delta[1, 0] - delta[0, 1]])
    sin = float(np.linalg.norm(axial))
    angle = math.atan2(sin, 0.5 * (float(np.trace(delta)) - 1.0))
    return axial * (angle / sin) if sin > 1e-300 else axial


class ArmRateController:
    """Integrates dq = J^+ (v_des + K (x_des - x(q))) into a joint command q_cmd for joint servos.

    The tool error is measured from the joint values the controller is given (MuJoCo's qpos), so servo lag and
    integration drift are fed back. The task is the tool position (3 rows), plus the tool orientation (6 rows)
    when `orientation` is set. Near a singularity (sigma_min < threshold) damped least squares with
    lambda^2 = lambda_max^2 (1 - (sigma/threshold)^2). A joint at a range end that the step would drive further out
    is held and the task solved by the others (clamping); joint speeds are limited as a whole, the command brakes
    before a range end at max_acceleration and is clipped into the range (a "limit hit").
    """

    def __init__(
        self,
        kinematics: Kinematics,
        gains: ArmRateGains,
        q_start: np.ndarray,
        lower: np.ndarray,
        upper: np.ndarray,
        orientation: bool,
        q_rest: np.ndarray | None = None,
    ) -> None:
        self.kinematics = kinematics
        self.gains = gains
        self.q_cmd = np.array(q_start, dtype=float)  # (n,)
        self.dq = np.zeros_like(self.q_cmd)  # (n,) the rate q_cmd moved at in the last step
        self.lower, self.upper = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)  # (n,) (+-inf: none)
        self.rows = 6 if orientation else 3
        self.q_rest = self.q_cmd.copy() if q_rest is None else np.asarray(q_rest, dtype=float)
        self.sigma_min = math.nan  # of the task Jacobian at the last measured q
        self.clipped = np.zeros(len(self.q_cmd), dtype=bool)  # (n,) joints whose command hit a range end last step
        self.jacobian = np.zeros((6, len(self.q_cmd)))  # (6, n) at the last measured q
        self.pose = np.eye(4)  # (4, 4) tool pose at the last measured q

    def update(
        self, q: np.ndarray, p_des: np.ndarray, v_des: np.ndarray, rot_des: np.ndarray | None, dt: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """Advances q_cmd by one control period from the measured joint values q.

        Args:
            q: Measured joint values (n,) [rad or m].
            p_des: Desired tool position (3,) [m] at the time of q (the start of the period).
            v_des: Desired tool velocity (3,) [m/s]: the desired position's mean rate over the period, so that
                p_des + v_des dt is the next desired position and the error decays as (1 - K dt) per period.
            rot_des: Desired tool orientation (3, 3) (held; zero angular velocity), or None for position only.
            dt: Control period [s].

        Returns:
            (q_cmd, dq): the new joint command and the rate it moved at, each (n,).
        """
        g = self.gains
        self.pose, self.jacobian = pose, jac = self.kinematics(q)
        # Task-space rate: the reference velocity plus K times the error.
        u = np.empty(self.rows)  # (m,)
        u[:3] = v_des + g.task_gain * (p_des - pose[:3, 3])
        if self.rows == 6:  # no goal orientation: none is corrected
            u[3:] = g.task_gain * rotation_error(pose[:3, :3], pose[:3, :3] if rot_des is None else rot_des)
        task = jac[: self.rows]  # (m, n)
        dq, self.sigma_min = self._damped(task, u, q, np.ones(task.shape[1]))
        # A joint at a range end that dq drives further out is held there and the others solve the task (clamping).
        room_low = np.maximum(self.q_cmd - self.lower, 0.0)
        room_high = np.maximum(self.upper - self.q_cmd, 0.0)
        free = np.ones(task.shape[1])  # (n,) 1: the joint takes part, 0: held at its range end
        for _ in range(task.shape[1]):
            blocked = (free > 0) & (((room_low <= LIMIT_TOL) & (dq < 0)) | ((room_high <= LIMIT_TOL) & (dq > 0)))
            if not blocked.any():
                break
            free[blocked] = 0.0
            dq, _ = self._damped(task, u, q, free)
        # Joint speed limit, on dq as a whole so the tool keeps its direction.
        over = np.max(np.abs(dq) / g.max_speed)
        if over > 1.0:
            dq /= over
        # Range ends: never faster toward one than braking at max_acceleration can stop, sqrt(2 a room).
        dq = np.clip(dq, -np.sqrt(2 * g.max_acceleration * room_low), np.sqrt(2 * g.max_acceleration * room_high))
        # Integrate inside the ranges; the rate recorded is what q_cmd actually did.
        target = self.q_cmd + dq * dt
        new = np.clip(target, self.lower, self.upper)
        self.clipped = (new != target) | (new <= self.lower + LIMIT_TOL) | (new >= self.upper - LIMIT_TOL)
        self.dq = (new - self.q_cmd) / dt
        self.q_cmd = new
        return self.q_cmd, self.dq

    def _damped(self, task: np.ndarray, u: np.ndarray, q: np.ndarray, free: np.ndarray) -> tuple[np.ndarray, float]:
        """dq (n,) = Jᵀ (J Jᵀ + λ² I)⁻¹ u with the columns of held joints (free = 0) zeroed, λ = 0 far from
        singularities, plus the null-space pull of a redundant task; and sigma_min of that Jacobian."""
        g = self.gains
        jac = task * free  # (m, n)
        sigma = np.linalg.svd(jac, compute_uv=False)
        sigma_min = float(sigma[-1]) if len(sigma) == self.rows else 0.0
        ratio = sigma_min / g.sigma_threshold
        lam = max(g.max_damping * math.sqrt(max(1.0 - ratio * ratio, 0.0)), MIN_DAMPING) if ratio < 1.0 else 0.0
        gram = jac @ jac.T + lam * lam * np.eye(self.rows)  # (m, m)
        dq = jac.T @ np.linalg.solve(gram, u)  # (n,)
        if g.nullspace_gain > 0 and free.sum() > self.rows:
            # Pull toward the rest pose in the null space of the task: (I - J⁺ J) K_n (q_rest - q).
            pull = g.nullspace_gain * (self.q_rest - q) * free
            dq += pull - jac.T @ np.linalg.solve(gram, jac @ pull)
        return dq, sigma_min
