"""Task-space paths (line, circle, figure-8) and an arm-track run's plan: reference pose, start pose, reach check."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from hexabot_sim.control.arm_rate import rotation_error
from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics import numeric_ik
from hexabot_sim.kinematics.chain import SerialChain
from hexabot_sim.kinematics.mjcf import home_pose
from hexabot_sim.kinematics.numeric_ik import batch_pose_and_jacobian, pose_and_jacobian, task_rows

PATHS: tuple[str, ...] = ("circle", "line", "figure8")
PLANES: dict[str, tuple[int, int]] = {"xy": (0, 1), "xz": (0, 2), "yz": (1, 2)}  # the path's two world axes
RAMP_TIME: float = 0.5  # [s] the path speed rises from 0 as (1 - cos(pi t / RAMP_TIME)) / 2: no step in velocity
CANDIDATES: int = 512  # random configurations the reference pose is chosen among (plus the home pose)
RANGE_MARGIN: float = 0.15  # candidates keep this fraction of each joint range from its ends
SEED: int = 20  # the candidates are the same on every call: the same robot gets the same reference pose
TRIES: int = 8  # with no offset, the next-best reference poses are tried while the path is out of reach from one
SAMPLES: int = 200  # points of the path checked for reach before the run (one period or the duration)
REACH_TOL: float = 1e-6  # [m and rad] a sample the tool reaches closer than this is reached
RANK_TOL: float = 1e-9  # sigma_min below this fraction of the largest singular value is 0 (rank deficient)
NEWTON_STEPS: int = 200  # damped Gauss-Newton iterations to the start point; per later sample: NEWTON_STEPS // 10


@dataclasses.dataclass(frozen=True)
class Path:
    """A closed task-space path, traversed from rest with a smooth ramp (RAMP_TIME), world frame.

    The tool's peak speed along it is `speed`: circle of diameter `size` at constant speed; line: back and forth
    over `size` along the plane's first axis, p = a sin(phi); figure8 (lemniscate of Gerono):
    p = a (sin phi, sin phi cos phi), a = size / 2.
    """

    kind: str
    size: float  # [m]
    speed: float  # [m/s] peak tool speed
    centre: np.ndarray  # (3,) [m]
    axes: tuple[np.ndarray, np.ndarray]  # the plane's unit vectors e1, e2

    @property
    def rate(self) -> float:
        """d(phi)/dt after the ramp [rad/s]."""
        a = self.size / 2
        return self.speed / (a * math.sqrt(2.0) if self.kind == "figure8" else a)

    @property
    def period(self) -> float:
        """Time of one cycle after the ramp [s]."""
        return 2 * math.pi / self.rate

    def phase(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """phi(t) and d(phi)/dt, each shaped as t (the ramp's integral, then rate * (t - RAMP_TIME / 2))."""
        t = np.asarray(t, dtype=float)
        ramp = t < RAMP_TIME
        w = math.pi / RAMP_TIME
        phi = np.where(ramp, 0.5 * t - np.sin(w * t) / (2 * w), t - RAMP_TIME / 2) * self.rate
        dphi = np.where(ramp, 0.5 * (1 - np.cos(w * t)), 1.0) * self.rate
        return phi, dphi

    def at(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Desired tool position and velocity at times t (k,): each (k, 3) [m], [m/s]."""
        phi, dphi = self.phase(np.atleast_1d(t))
        a = self.size / 2
        s, c = np.sin(phi), np.cos(phi)
        if self.kind == "circle":
            u, v, du, dv = a * c, a * s, -a * s, a * c
        elif self.kind == "line":
            u, v, du, dv = a * s, 0 * s, a * c, 0 * s
        else:
            u, v, du, dv = a * s, a * s * c, a * c, a * np.cos(2 * phi)
        e1, e2 = self.axes
        pos = self.centre + u[:, None] * e1 + v[:, None] * e2
        vel = (du * dphi)[:, None] * e1 + (dv * dphi)[:, None] * e2
        return pos, vel


@dataclasses.dataclass(frozen=True)
class Plan:
    """What an arm-track run starts from, found before it starts.

    Attributes:
        path: The path, centred at the reference tool point plus the offset.
        q_ref: The reference pose (n,): the best-conditioned of the candidates; the null-space rest pose.
        q_start: The joint values (n,) that put the tool on the path's first point (from q_ref).
        rot_hold: The tool orientation held (3, 3) for 6 or more joints, else None.
        rows: Task rows: 3 (position) or 6 (position and orientation).
        lower, upper: Joint ranges (n,) for the command (+-inf for an unlimited revolute joint).
        t, q, sigma: The path's reach check: sample times (k,), joint values (k, n), task sigma_min (k,).
    """

    path: Path
    q_ref: np.ndarray
    q_start: np.ndarray
    rot_hold: np.ndarray | None
    rows: int
    lower: np.ndarray
    upper: np.ndarray
    t: np.ndarray
    q: np.ndarray
    sigma: np.ndarray


def ranges(chain: SerialChain, where: str) -> tuple[np.ndarray, np.ndarray]:
    """Joint ranges (n,) each, +-inf for an unlimited revolute joint; a slide without limits is refused."""
    lower, upper = [], []
    for j in chain.joints:
        if j.lower is None or j.upper is None:
            if j.prismatic:
                raise UsageError(
                    f"{where}: joint '{j.name}' is prismatic without 'lower' and 'upper': arm-track "
                    "needs a slide's stroke"
                )
            lower.append(-math.inf)
            upper.append(math.inf)
        else:
            lower.append(j.lower)
            upper.append(j.upper)
    return np.array(lower), np.array(upper)


def sigma_scale(jac: np.ndarray) -> float:
    """The largest singular value over a batch of Jacobians (S, 6, n): the scale rank is judged against."""
    return float(np.linalg.svd(jac, compute_uv=False)[:, 0].max())


def reference_poses(chain: SerialChain, lower: np.ndarray, upper: np.ndarray, where: str) -> tuple[np.ndarray, int]:
    """The TRIES configurations with the largest task-Jacobian sigma_min among CANDIDATES random ones (and the home
    pose), best first, each joint at least RANGE_MARGIN of its range from the ends; tool above the base frame's
    origin first.

    Returns:
        (q_refs (TRIES, n), task rows): 6 (position and orientation) for 6+ joints that turn the tool about every
        axis, else 3 (position only: a 6-joint chain of parallel axes cannot hold an orientation).
    """
    lo = np.where(np.isfinite(lower), lower, -math.pi)
    hi = np.where(np.isfinite(upper), upper, math.pi)
    span = hi - lo
    rng = np.random.default_rng(SEED)
    q = lo + span * (RANGE_MARGIN + (1 - 2 * RANGE_MARGIN) * rng.random((CANDIDATES, chain.n)))  # (S, n)
    q = np.vstack([np.clip(home_pose(chain), lo + RANGE_MARGIN * span, hi - RANGE_MARGIN * span), q])
    pose, jac = batch_pose_and_jacobian(chain, q)
    for rows in (6, 3) if len(task_rows(chain)) == 6 else (3,):
        sigma = np.linalg.svd(jac[:, :rows], compute_uv=False)[:, -1]  # (S,)
        if sigma.max() > RANK_TOL * sigma_scale(jac):
            above = pose[:, 2, 3] >= np.asarray(chain.base)[2, 3]
            score = np.where(above, sigma, sigma - np.inf) if above.any() else sigma
            return q[np.argsort(-score, kind="stable")[:TRIES]], rows
    raise UsageError(
        f"{where}: its tool cannot move in every direction at any of {len(q)} poses (sigma_min of the position "
        "Jacobian is 0 at each): arm-track needs 3 independent directions of the tool point"
    )


def _solve(evaluate, q, goal_p, goal_r, lower, upper, steps):
    """Damped Gauss-Newton from q toward (goal_p, goal_r) inside the ranges: (q, position and angle residuals)."""
    for _ in range(steps + 1):
        pose, jac = evaluate(q)
        err = goal_p - pose[:3, 3]
        rows = 3
        if goal_r is not None:
            err, rows = np.concatenate([err, rotation_error(pose[:3, :3], goal_r)]), 6
        pos_res = float(np.linalg.norm(err[:3]))
        rot_res = float(np.linalg.norm(err[3:])) if rows == 6 else 0.0
        if pos_res <= 0.1 * REACH_TOL and rot_res <= 0.1 * REACH_TOL:
            break
        task = jac[:rows]
        dq = task.T @ np.linalg.solve(task @ task.T + 1e-10 * np.eye(rows), err)
        q = np.clip(q + dq, lower, upper)
    return q, pos_res, rot_res


def _point(point: np.ndarray) -> str:
    return ", ".join(f"{v:.4g}" for v in point)


def _distance(metres: float) -> str:
    return f"{metres * 1000:.3g} mm" if metres < 1 else f"{metres:.3g} m"


def _start_from_seeds(chain, evaluate, q_ref, point, rot, lower, upper, where):
    """The path's first point from numeric IK's many seeds (the solution nearest q_ref), when Gauss-Newton from q_ref
    stalls; out of reach: one line with the closest the seeds got."""
    target = point
    if rot is not None:
        target = np.eye(4)
        target[:3, :3], target[:3, 3] = rot, point
    try:
        solutions = numeric_ik.solve(chain, target, where=f"{where}: the path's first point, ({_point(point)}) m")
    except numeric_ik.IKError as e:
        raise UsageError(f"{e}; lower 'size' or move the path with 'offset_x', 'offset_y', 'offset_z'") from None
    best = min(solutions, key=lambda s: float(np.linalg.norm(s.q - q_ref)))
    return _solve(evaluate, np.clip(best.q, lower, upper), point, rot, lower, upper, NEWTON_STEPS)


def plan(
    chain: SerialChain,
    kind: str,
    size: float,
    speed: float,
    plane: str,
    offset: np.ndarray,
    duration: float,
    where: str,
) -> Plan:
    """The reference pose, the path, the start pose and the path's reach along one period (or the duration).

    The reference pose is the best-conditioned candidate (reference_poses); with no offset, the next ones are tried
    while the path is out of reach from it. The path is centred on its tool point plus `offset`.

    Raises:
        UsageError: fewer than 3 joints, a slide without limits, or a path point the tool cannot reach within the
            joint ranges (one line naming the time and the point).
    """
    if chain.n < 3:
        raise UsageError(f"{where}: arm-track moves the tool in 3-D and needs 3 or more joints; it has {chain.n}")
    names = {j.name for j in chain.joints}
    for joint in chain.joints:  # scene.build names joint q's servos q, q_velocity and q_bias: MuJoCo's "repeated name"
        for suffix, what in (("_velocity", "velocity servo"), ("_bias", "feedforward motor")):
            if joint.name + suffix in names:
                raise UsageError(
                    f"{where}: joint '{joint.name}{suffix}' has the name arm-track gives the {what} of joint "
                    f"'{joint.name}' in its model; rename one of them"
                )
    lower, upper = ranges(chain, where)
    q_refs, rows = reference_poses(chain, lower, upper, where)
    evaluate = pose_and_jacobian(chain)
    refused = None
    for q_ref in q_refs if not np.any(offset) else q_refs[:1]:  # an offset is from the best pose's tool point
        try:
            return _follow(
                chain,
                evaluate,
                q_ref,
                rows,
                Path(kind, size, speed, offset, _axes(plane)),
                duration,
                lower,
                upper,
                where,
            )
        except UsageError as e:
            refused = refused or e
    assert refused is not None
    raise refused


def _axes(plane: str) -> tuple[np.ndarray, np.ndarray]:
    e1, e2 = (np.eye(3)[i] for i in PLANES[plane])
    return e1, e2


def _follow(chain, evaluate, q_ref, rows, shape, duration, lower, upper, where) -> Plan:
    """The path `shape` moved to q_ref's tool point (its centre was the offset), followed from q_ref (see plan)."""
    pose_ref, _ = evaluate(q_ref)
    path = dataclasses.replace(shape, centre=pose_ref[:3, 3] + shape.centre)
    rot = pose_ref[:3, :3].copy() if rows == 6 else None
    end = min(duration, RAMP_TIME + path.period)
    t = np.linspace(0.0, end, SAMPLES + 1)  # (k,)
    points, _ = path.at(t)
    q = np.empty((len(t), chain.n))  # (k, n)
    sigma = np.empty(len(t))  # (k,)
    current = q_ref
    for k, point in enumerate(points):
        current, pos_res, rot_res = _solve(
            evaluate, current, point, rot, lower, upper, NEWTON_STEPS if k == 0 else NEWTON_STEPS // 10
        )
        if k == 0 and (pos_res > REACH_TOL or rot_res > REACH_TOL):  # not from q_ref: from many seeds
            current, pos_res, rot_res = _start_from_seeds(chain, evaluate, q_ref, point, rot, lower, upper, where)
        if pos_res > REACH_TOL or rot_res > REACH_TOL:
            what = "the path's first point" if k == 0 else f"the path at t = {t[k]:.3g} s"
            held = f" with the tool orientation held ({rot_res:.3g} rad off)" if rot is not None else ""
            raise UsageError(
                f"{where}: {what}, ({_point(point)}) m, is out of reach within the joint "
                f"ranges{held}: the tool stops {_distance(pos_res)} away; lower 'size' or move the path with "
                f"'offset_x', 'offset_y', 'offset_z' (the centre is {_point(path.centre)} m)"
            )
        _, jac = evaluate(current)
        q[k] = current
        sigma[k] = np.linalg.svd(jac[:rows], compute_uv=False)[-1]
    return Plan(path, q_ref, q[0].copy(), rot, rows, lower, upper, t, q, sigma)
