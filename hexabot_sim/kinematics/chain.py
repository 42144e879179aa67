"""Serial chains from a DH table (standard or modified, revolute or prismatic, tool offset): FK and Jacobians."""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics import dh

CONVENTIONS = ("standard", "modified")


@dataclasses.dataclass(frozen=True)
class Joint:
    """One row of a DH table. The joint variable q adds to `theta` (revolute) or to the offset (prismatic).

    Standard DH (Rz(theta) Tz(d) Tx(a) Rx(alpha)): the joint acts along/about z_{i-1}; prismatic adds q to d.
    Modified DH (Rx(alpha) Tx(a) Rz(theta) Tz(d)): the joint acts along/about z_i; prismatic adds q to d.
    Here `a` is the distance along x (Khalil's d) and `d` the distance along z (Khalil's r) in both.

    Attributes:
        name: Joint name (used in the MJCF).
        kind: "revolute" or "prismatic".
        theta: Constant angle [rad] (revolute: offset added to q).
        d: Constant distance along z [m] (prismatic: offset added to q).
        a: Distance along x [m].
        alpha: Twist [rad].
        lower, upper: Joint range (rad or m); None for unlimited.
    """

    name: str
    kind: str = "revolute"
    theta: float = 0.0
    d: float = 0.0
    a: float = 0.0
    alpha: float = 0.0
    lower: float | None = None
    upper: float | None = None

    def __post_init__(self) -> None:
        if self.kind not in ("revolute", "prismatic"):
            raise UsageError(f"joint '{self.name}': kind must be revolute or prismatic; got {self.kind!r}")
        if (self.lower is None) != (self.upper is None):
            raise UsageError(f"joint '{self.name}': give both lower and upper limits, or neither")
        if self.lower is not None and self.upper is not None and not self.lower <= self.upper:
            raise UsageError(f"joint '{self.name}': lower limit {self.lower} exceeds upper limit {self.upper}")

    @property
    def prismatic(self) -> bool:
        return self.kind == "prismatic"

    def transform(self, q: ArrayLike, convention: str) -> np.ndarray:
        """Link transform for joint value q (scalar or array), (..., 4, 4)."""
        q = np.asarray(q, dtype=float)
        theta = self.theta + (0.0 if self.prismatic else q)
        d = self.d + (q if self.prismatic else 0.0)
        if convention == "standard":
            return dh.standard(theta, d, self.a, self.alpha)
        return dh.modified(self.alpha, self.a, theta, d)


@dataclasses.dataclass(frozen=True)
class SerialChain:
    """A serial chain: base transform, DH rows, tool transform.

    Attributes:
        name: Robot name.
        joints: DH rows, base to tip.
        convention: "standard" or "modified".
        base: Fixed transform from the world to frame 0, (4, 4).
        tool: Fixed transform from the last DH frame to the tool frame, (4, 4).
    """

    name: str
    joints: tuple[Joint, ...]
    convention: str = "standard"
    base: np.ndarray = dataclasses.field(default_factory=lambda: np.eye(4))
    tool: np.ndarray = dataclasses.field(default_factory=lambda: np.eye(4))

    def __post_init__(self) -> None:
        if self.convention not in CONVENTIONS:
            raise UsageError(f"convention must be one of {', '.join(CONVENTIONS)}; got {self.convention!r}")

    @property
    def n(self) -> int:
        return len(self.joints)

    @property
    def prismatic(self) -> list[bool]:
        return [j.prismatic for j in self.joints]

    def _q(self, q: ArrayLike) -> np.ndarray:
        q = np.asarray(q, dtype=float)
        if q.shape[-1:] != (self.n,):
            raise UsageError(f"{self.name} has {self.n} joints; got {q.shape[-1] if q.ndim else 0} values")
        if not np.all(np.isfinite(q)):
            raise UsageError(f"joint values must be finite numbers; got {q}")
        return q

    def frames(self, q: ArrayLike) -> list[np.ndarray]:
        """Base-frame transforms [T00, T01, ..., T0n, T0tool] (world = base · ...), each (..., 4, 4)."""
        q = self._q(q)
        out = [np.broadcast_to(self.base, (*q.shape[:-1], 4, 4)).copy()]
        for i, joint in enumerate(self.joints):
            out.append(out[-1] @ joint.transform(q[..., i], self.convention))
        out.append(out[-1] @ self.tool)
        return out

    def fk(self, q: ArrayLike) -> np.ndarray:
        """Tool pose in the world, (..., 4, 4)."""
        return self.frames(q)[-1]

    def joint_axes(self, frames: Sequence[np.ndarray]) -> list[np.ndarray]:
        """For each joint, the frame (from `frames`) whose z-axis it moves along or about."""
        offset = 0 if self.convention == "standard" else 1  # standard: z_{i-1}; modified: z_i
        return [frames[i + offset] for i in range(self.n)]

    def jacobian(self, q: ArrayLike) -> np.ndarray:
        """Geometric Jacobian (6, n) of the tool point, world frame: rows v (linear), then w (angular).

        Direct method: revolute column (z_j × (o_tool − o_j), z_j), prismatic (z_j, 0).
        """
        frames = self.frames(q)
        axes = self.joint_axes(frames)
        return dh.geometric_jacobian(axes, list(range(self.n)), frames[-1][:3, 3], self.prismatic)

    def jacobian_fk_derivative(self, q: ArrayLike) -> np.ndarray:
        """Jacobian (6, n) by differentiating the FK product exactly: dT/dq_i = T_0^{i-1} dA_i/dq_i T_i^tool.

        Linear rows: the translation of dT/dq_i; angular rows: the axial vector of (dR/dq_i) R^T.
        """
        q = self._q(q)
        links = [j.transform(q[i], self.convention) for i, j in enumerate(self.joints)]
        jac = np.zeros((6, self.n))  # (6, n)
        pose = self.fk(q)
        for i, joint in enumerate(self.joints):
            d_link = _link_derivative(joint, q[i], self.convention)
            d_pose = np.linalg.multi_dot([self.base, *links[:i], d_link, *links[i + 1 :], self.tool])  # (4, 4)
            jac[:3, i] = d_pose[:3, 3]
            w = d_pose[:3, :3] @ pose[:3, :3].T  # skew-symmetric
            jac[3:, i] = (w[2, 1], w[0, 2], w[1, 0])
        return jac

    def jacobian_numerical(self, q: ArrayLike, eps: float = 1e-6) -> np.ndarray:
        """Jacobian (6, n) by central differences of the tool pose: positions, and log(R(q+h) R(q-h)^T) / 2h."""
        q = self._q(q)
        jac = np.zeros((6, self.n))  # (6, n)
        for i in range(self.n):
            step = np.zeros(self.n)
            step[i] = eps
            plus, minus = self.fk(q + step), self.fk(q - step)
            jac[:3, i] = (plus[:3, 3] - minus[:3, 3]) / (2 * eps)
            jac[3:, i] = _rotation_log(plus[:3, :3] @ minus[:3, :3].T) / (2 * eps)
        return jac

    def manipulability(self, q: ArrayLike, rows: slice = slice(0, 3)) -> float:
        """Yoshikawa's measure sqrt(det(J J^T)) of the selected rows (default: linear velocity)."""
        jac = self.jacobian(q)[rows]
        return float(np.sqrt(max(np.linalg.det(jac @ jac.T), 0.0)))


def _link_derivative(joint: Joint, q: float, convention: str) -> np.ndarray:
    """d(link transform)/dq, exactly: the generator of the joint's motion applied where it acts."""
    generator = np.zeros((4, 4))  # (4, 4)
    if joint.prismatic:
        generator[2, 3] = 1.0  # translation along z
    else:
        generator[0, 1], generator[1, 0] = -1.0, 1.0  # rotation about z
    if convention == "standard":  # Rz(theta) Tz(d) act first: dA = G A
        return generator @ joint.transform(q, convention)
    # Modified: A = Rx(alpha) Tx(a) · Rz(theta) Tz(d): the joint acts after the fixed part.
    fixed = dh.modified(joint.alpha, joint.a, 0.0, 0.0)
    moving = np.linalg.solve(fixed, joint.transform(q, convention))
    return fixed @ generator @ moving


def _rotation_log(rot: np.ndarray) -> np.ndarray:
    """Rotation vector (axis * angle) of a rotation matrix near the identity, (3,)."""
    cos = np.clip((np.trace(rot) - 1) / 2, -1.0, 1.0)
    angle = np.arccos(cos)
    axial = np.array([rot[2, 1] - rot[1, 2], rot[0, 2] - rot[2, 0], rot[1, 0] - rot[0, 1]]) / 2
    return axial if angle < 1e-12 else axial * angle / np.sin(angle)
