"""Denavit–Hartenberg transforms (modified and standard), frame chains and Jacobians of serial chains."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike

from hexabot_sim.errors import UsageError


def _empty_transforms(*params: ArrayLike) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
    """Broadcasts the DH parameters and returns (T filled with the bottom row [0 0 0 1], the parameters)."""
    arrays = np.broadcast_arrays(*(np.asarray(p, dtype=float) for p in params))
    out = np.zeros((*arrays[0].shape, 4, 4))  # (..., 4, 4)
    out[..., 3, 3] = 1.0
    return out, arrays


def modified(alpha: ArrayLike, d: ArrayLike, theta: ArrayLike, r: ArrayLike) -> np.ndarray:
    """Modified (Khalil/Craig) DH transform from frame i-1 to frame i: Rx(alpha) Tx(d) Rz(theta) Tz(r).

    Args:
        alpha: Angle between z_{i-1} and z_i about x_{i-1} in [rad].
        d: Distance between z_{i-1} and z_i along x_{i-1} in [m].
        theta: Angle between x_{i-1} and x_i about z_i in [rad].
        r: Distance between x_{i-1} and x_i along z_i in [m].

    Returns:
        Homogeneous transform, (4, 4); the parameters broadcast, so arrays of shape S give (*S, 4, 4).
    """
    t, (alpha, d, theta, r) = _empty_transforms(alpha, d, theta, r)
    ca, sa, ct, st = np.cos(alpha), np.sin(alpha), np.cos(theta), np.sin(theta)
    t[..., 0, 0], t[..., 0, 1], t[..., 0, 3] = ct, -st, d
    t[..., 1, 0], t[..., 1, 1], t[..., 1, 2], t[..., 1, 3] = st * ca, ct * ca, -sa, -r * sa
    t[..., 2, 0], t[..., 2, 1], t[..., 2, 2], t[..., 2, 3] = st * sa, ct * sa, ca, r * ca
    return t


def standard(theta: ArrayLike, d: ArrayLike, a: ArrayLike, alpha: ArrayLike) -> np.ndarray:
    """Standard (classic) DH transform from frame i-1 to frame i: Rz(theta) Tz(d) Tx(a) Rx(alpha).

    Args:
        theta: Angle between x_{i-1} and x_i about z_{i-1} in [rad].
        d: Distance between x_{i-1} and x_i along z_{i-1} in [m].
        a: Distance between z_{i-1} and z_i along x_i in [m].
        alpha: Angle between z_{i-1} and z_i about x_i in [rad].

    Returns:
        Homogeneous transform, (4, 4); the parameters broadcast, so arrays of shape S give (*S, 4, 4).
    """
    t, (theta, d, a, alpha) = _empty_transforms(theta, d, a, alpha)
    ca, sa, ct, st = np.cos(alpha), np.sin(alpha), np.cos(theta), np.sin(theta)
    t[..., 0, 0], t[..., 0, 1], t[..., 0, 2], t[..., 0, 3] = ct, -st * ca, st * sa, a * ct
    t[..., 1, 0], t[..., 1, 1], t[..., 1, 2], t[..., 1, 3] = st, ct * ca, -ct * sa, a * st
    t[..., 2, 1], t[..., 2, 2], t[..., 2, 3] = sa, ca, d
    return t


def chain(transforms: Sequence[np.ndarray]) -> list[np.ndarray]:
    """Cumulative products [T01, T02 = T01 T12, T03, ...] of the link transforms [T01, T12, T23, ...].

    Args:
        transforms: Link transforms, each (4, 4) or a stack (..., 4, 4) broadcastable with the others.

    Returns:
        The transforms from the base frame to each frame, in order; [] for no transforms.
    """
    out: list[np.ndarray] = []
    for t in transforms:
        t = np.asarray(t, dtype=float)
        if t.shape[-2:] != (4, 4):
            raise UsageError(f"a homogeneous transform must have shape (4, 4); got {t.shape}")
        out.append(t.copy() if not out else out[-1] @ t)
    return out


def geometric_jacobian(
    frames: Sequence[np.ndarray],
    joint_frame_index: Sequence[int],
    p_end: ArrayLike,
    prismatic: Sequence[bool] | None = None,
) -> np.ndarray:
    """Geometric Jacobian of a serial chain by the direct method (joint axes and origins in the base frame).

    Joint j moves along or about the z-axis of frame `frames[joint_frame_index[j]]`, whose origin is o_j:
    a revolute joint gives the column (z_j × (p_end − o_j), z_j), a prismatic one (z_j, 0). With modified
    DH, joint i acts on z_i, so pass [T01, T02, ...] and indices [0, 1, ...]; with standard DH, joint i
    acts on z_{i-1}, so pass [I, T01, T02, ...] and indices [0, 1, ...].

    Args:
        frames: Base-frame transforms, each (4, 4).
        joint_frame_index: For each of the n joints, the index in `frames` of the frame whose z-axis is its axis.
        p_end: End-effector point in the base frame in [m], (3,).
        prismatic: For each joint, True if prismatic; None means all revolute.

    Returns:
        The Jacobian (6, n): rows 0-2 map joint rates to the linear velocity of p_end in [m/s],
        rows 3-5 to the angular velocity in [rad/s].
    """
    n = len(joint_frame_index)
    if prismatic is None:
        prismatic = [False] * n
    if len(prismatic) != n:
        raise UsageError(f"prismatic must have one flag per joint ({n}); got {len(prismatic)}")
    p = np.asarray(p_end, dtype=float)
    if p.shape != (3,):
        raise UsageError(f"p_end must be a point of shape (3,); got {p.shape}")
    jac = np.zeros((6, n))  # (6, n)
    for j, (k, is_prismatic) in enumerate(zip(joint_frame_index, prismatic, strict=True)):
        if not -len(frames) <= k < len(frames):
            raise UsageError(f"joint {j}: frame index {k} is out of range; {len(frames)} frames given")
        t = np.asarray(frames[k], dtype=float)
        if t.shape != (4, 4):
            raise UsageError(f"frame {k} must be a homogeneous transform of shape (4, 4); got {t.shape}")
        z, o = t[:3, 2], t[:3, 3]  # (3,), (3,)
        if is_prismatic:
            jac[:3, j] = z
        else:
            # z × (p − o), written out: np.cross on 3-vectors cost a third of rrp-velocity's 20,001-row run
            z0, z1, z2 = z.tolist()
            r0, r1, r2 = (p - o).tolist()
            jac[:3, j] = (z1 * r2 - z2 * r1, z2 * r0 - z0 * r2, z0 * r1 - z1 * r0)
            jac[3:, j] = z
    return jac


def numerical_jacobian(f: Callable[[np.ndarray], ArrayLike], q: ArrayLike, eps: float = 1e-6) -> np.ndarray:
    """Jacobian of a vector function by central differences, (f(q + eps e_j) − f(q − eps e_j)) / (2 eps).

    Args:
        f: Function of a vector (n,) returning a vector (m,).
        q: Point at which to differentiate, (n,).
        eps: Step in the units of q; the truncation error is O(eps²), the rounding error O(1e-16 / eps).

    Returns:
        The Jacobian df/dq, (m, n).
    """
    if not eps > 0:
        raise UsageError(f"eps must be a number > 0; got {eps!r}")
    q = np.asarray(q, dtype=float)
    if q.ndim != 1:
        raise UsageError(f"q must be a vector of shape (n,); got {q.shape}")
    if q.size == 0:
        return np.zeros((np.asarray(f(q)).size, 0))
    columns = []
    for j in range(q.size):
        step = np.zeros_like(q)  # (n,)
        step[j] = eps
        diff = np.asarray(f(q + step), dtype=float) - np.asarray(f(q - step), dtype=float)
        columns.append(diff.reshape(-1) / (2.0 * eps))
    return np.stack(columns, axis=-1)  # (m, n)
