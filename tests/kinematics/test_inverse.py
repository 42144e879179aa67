"""Closed-form IK of the seed robots against their chains' FK; singular sets against SVD rank and closed-form dets."""

import math
from collections.abc import Callable

import numpy as np
import pytest

from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics import leg, robots
from hexabot_sim.kinematics.inverse import (
    SINGULAR_SETS,
    TASK_ROWS,
    IKError,
    det_or_manipulability,
    ik,
    singularities,
)

N = 200  # random configurations per robot
FK_TOL = 1e-10  # [m] (and rotation entries for the Stanford arm)
Q_TOL = 1e-8  # [rad or m]: the sampled q is among the branches
RANK_TOL = 1e-12  # sigma_min / sigma_max below this: rank lost
MARGIN = 0.05  # generic samples keep |sin|, |cos| and reaches above this from their singular values
RNG_SEED = 20240602

ROBOT_NAMES = ("rrp", "elbow", "scara", "stanford", "leg")
ELBOW = {name: spec.default for name, spec in robots.get("elbow").lengths.items()}
SCARA = {name: spec.default for name, spec in robots.get("scara").lengths.items()}
RRP = {name: spec.default for name, spec in robots.get("rrp").lengths.items()}
STANFORD = {name: spec.default for name, spec in robots.get("stanford").lengths.items()}
LEG = {name: spec.default for name, spec in robots.get("leg").lengths.items()}


# ---------------------------------------------------------------------------------------------------------------
# Generic configurations (inside the joint ranges, away from every singular set) and the targets they reach.


def _angle(rng: np.random.Generator) -> float:
    return float(rng.uniform(-math.pi, math.pi))


def _generic_rrp(rng: np.random.Generator, p: dict[str, float]) -> np.ndarray:
    while True:
        q = np.array([_angle(rng), _angle(rng), rng.uniform(-p["a2"], 2.0)])
        if abs(math.cos(q[1])) > MARGIN and p["a2"] + q[2] > MARGIN:
            return q


def _generic_elbow(rng: np.random.Generator, p: dict[str, float]) -> np.ndarray:
    while True:
        q = np.array([_angle(rng), _angle(rng), _angle(rng)])
        reach = p["a2"] * math.cos(q[1]) + p["a3"] * math.cos(q[1] + q[2])
        if abs(math.sin(q[2])) > MARGIN and abs(reach) > MARGIN * (p["a2"] + p["a3"]):
            return q


def _generic_scara(rng: np.random.Generator, p: dict[str, float]) -> np.ndarray:
    while True:
        q = np.array([_angle(rng), _angle(rng), rng.uniform(0.0, p["d1"]), _angle(rng)])
        if abs(math.sin(q[1])) > MARGIN:
            return q


def _generic_stanford(rng: np.random.Generator, p: dict[str, float]) -> np.ndarray:
    while True:
        q = np.array([_angle(rng), _angle(rng), rng.uniform(MARGIN, 1.0), _angle(rng), _angle(rng), _angle(rng)])
        if abs(math.sin(q[1])) > MARGIN and abs(math.sin(q[4])) > MARGIN:
            return q


def _generic_leg(rng: np.random.Generator, p: dict[str, float]) -> np.ndarray:
    while True:
        limit = math.pi / 2 - MARGIN
        q = np.array([rng.uniform(-limit, limit), rng.uniform(-limit, limit), rng.uniform(MARGIN, math.radians(155))])
        rho = p["l1"] + p["l2"] * math.cos(q[1]) + p["l3"] * math.cos(q[1] + q[2])
        if abs(rho) > MARGIN * (p["l1"] + p["l2"] + p["l3"]):
            return q


GENERIC: dict[str, Callable[[np.random.Generator, dict[str, float]], np.ndarray]] = {
    "rrp": _generic_rrp,
    "elbow": _generic_elbow,
    "scara": _generic_scara,
    "stanford": _generic_stanford,
    "leg": _generic_leg,
}


def _target(robot: str, pose: np.ndarray, with_yaw: bool = True) -> np.ndarray:
    """What ik() takes for a tool pose: the pose (Stanford), (x, y, z, yaw) (SCARA) or the position."""
    if robot == "stanford":
        return pose
    if robot == "scara" and with_yaw:
        return np.array([*pose[:3, 3], math.atan2(pose[1, 0], pose[0, 0])])
    return pose[:3, 3].copy()


def _fk_error(robot: str, chain, q: np.ndarray, pose: np.ndarray, with_yaw: bool = True) -> float:
    """Max deviation of FK(q) from the target: full pose (Stanford, SCARA with yaw: x axis too), else position."""
    reached = chain.fk(q)
    if robot == "stanford":
        return float(np.max(np.abs(reached - pose)))
    error = float(np.max(np.abs(reached[:3, 3] - pose[:3, 3])))
    if robot == "scara" and with_yaw:
        error = max(error, float(np.max(np.abs(reached[:3, :3] - pose[:3, :3]))))
    return error


def _distance(q: np.ndarray, other: np.ndarray, prismatic: list[bool]) -> float:
    """Max joint difference, angles compared mod 2π."""
    diff = q - other
    revolute = ~np.array(prismatic)
    diff[revolute] = (diff[revolute] + math.pi) % (2 * math.pi) - math.pi
    return float(np.max(np.abs(diff)))


def _expected_count(robot: str, q: np.ndarray, p: dict[str, float], chain) -> int:
    """Branch count from the geometry alone (not from ik): 2 per side with two solutions, 1 where they merge."""
    pose = chain.fk(q)
    x, y, z = pose[:3, 3]
    if robot == "rrp":
        return 2  # q1 and q1 + π, d3 = distance − a2 shared; a2 + d3 >= 0 (slide limit) rules out the rest
    if robot == "elbow":
        shoulder = 2 if x * x + y * y > p["d"] ** 2 else 1
        dist = math.hypot(math.sqrt(max(x * x + y * y - p["d"] ** 2, 0.0)), z - p["d1"])
        elbow = 2 if abs(p["a2"] - p["a3"]) < dist < p["a2"] + p["a3"] else 1
        return shoulder * elbow
    if robot == "scara":
        return 2 if abs(p["a1"] - p["a2"]) < math.hypot(x, y) < p["a1"] + p["a2"] else 1
    if robot == "stanford":
        centre = pose[:3, 3] - p["d6"] * pose[:3, 2]
        shoulder = 2 if centre[0] ** 2 + centre[1] ** 2 > p["d2"] ** 2 else 1
        return shoulder * 2  # θ5 and −θ5 (d3 >= 0 by its range: θ2, d3 unique per shoulder)
    # Leg: q1 and q1 + π cannot both lie in (−π/2, π/2), nor q3 and −q3 in [0, 160°]: one branch survives.
    return 1


@pytest.mark.slow
@pytest.mark.parametrize(
    ("robot", "lengths"),
    [("rrp", {}), ("elbow", {}), ("elbow", {"d": 0.0}), ("scara", {}), ("stanford", {}), ("stanford", {"d2": 0.0}),
     ("leg", {})],
)  # fmt: skip
def test_every_branch_reaches_the_target_and_the_sample_is_among_them(robot: str, lengths: dict[str, float]) -> None:
    spec = robots.get(robot)
    chain = spec.chain(lengths)
    p = {name: float(lengths.get(name, length.default)) for name, length in spec.lengths.items()}
    rng = np.random.default_rng(RNG_SEED)
    for _ in range(N):
        q = GENERIC[robot](rng, p)
        pose = chain.fk(q)
        branches = ik(robot, _target(robot, pose), lengths)
        assert len(branches) == _expected_count(robot, q, p, chain), (q, branches)
        for branch in branches:
            assert branch.shape == (chain.n,)
            assert _fk_error(robot, chain, branch, pose) < FK_TOL, (q, branch)
            revolute = [not j.prismatic for j in chain.joints]
            assert np.all(branch[revolute] > -math.pi) and np.all(branch[revolute] <= math.pi)
        assert min(_distance(q, b, chain.prismatic) for b in branches) < Q_TOL, (q, branches)


def test_scara_without_yaw_sets_theta4_to_zero() -> None:
    chain = robots.get("scara").chain()
    q = np.array([0.4, -1.1, 0.2, 0.7])
    pose = chain.fk(q)
    branches = ik("scara", pose[:3, 3])
    assert len(branches) == 2
    for branch in branches:
        assert branch[3] == 0.0
        assert _fk_error("scara", chain, branch, pose, with_yaw=False) < FK_TOL
    assert any(np.allclose(b[:3], q[:3]) for b in branches)


def test_stanford_wrist_branches_are_the_known_pair() -> None:
    # (θ4, θ5, θ6) and (θ4 + π, −θ5, θ6 + π) give the same R36 (Spong): both come back for each shoulder.
    chain = robots.get("stanford").chain()
    q = np.array([0.3, 0.8, 0.6, -0.4, 1.1, 2.0])
    branches = ik("stanford", chain.fk(q))
    mate = q + np.array([0, 0, 0, math.pi, -2 * q[4], math.pi])
    assert min(_distance(mate, b, chain.prismatic) for b in branches) < Q_TOL


# ---------------------------------------------------------------------------------------------------------------
# Branches that merge: the count drops, the duplicates are returned once.


@pytest.mark.parametrize(
    ("robot", "target", "count"),
    [
        ("elbow", (ELBOW["d"], 0.0, ELBOW["d1"] + 0.5), 2),  # x² + y² = d²: r = 0, the two shoulders merge
        ("elbow", (0.2, -0.3, ELBOW["d1"] + 0.0), None),  # r > 0: count from the geometry (4 or 2)
        ("scara", (SCARA["a1"] + SCARA["a2"], 0.0, 0.1), 1),  # stretched
        ("scara", (0.0, SCARA["a1"] - SCARA["a2"], 0.1), 1),  # folded
        ("rrp", (0.0, 1.5, RRP["d1"]), 2),
    ],
)
def test_merged_branches_are_returned_once(robot: str, target: tuple[float, ...], count: int | None) -> None:
    chain = robots.get(robot).chain()
    branches = ik(robot, np.array(target))
    if count is None:
        dist = math.hypot(math.sqrt(target[0] ** 2 + target[1] ** 2 - ELBOW["d"] ** 2), target[2] - ELBOW["d1"])
        count = 4 if abs(ELBOW["a2"] - ELBOW["a3"]) < dist < ELBOW["a2"] + ELBOW["a3"] else 2
    assert len(branches) == count
    for branch in branches:
        assert np.max(np.abs(chain.fk(branch)[:3, 3] - np.array(target))) < FK_TOL


def test_stanford_shoulders_merge_on_the_offset_cylinder() -> None:
    chain = robots.get("stanford").chain()
    q = np.array([0.5, 0.0, 0.7, 0.3, 0.9, -1.2])  # θ2 = 0: the wrist centre straight above o2
    pose = chain.fk(q)
    branches = ik("stanford", pose)
    assert len(branches) == 2
    assert all(_fk_error("stanford", chain, b, pose) < FK_TOL for b in branches)


# ---------------------------------------------------------------------------------------------------------------
# Unreachable and singular targets: one-line IKError, never NaN or an empty list.


def _stanford_pose(q: tuple[float, ...], lengths: dict[str, float] | None = None) -> np.ndarray:
    return robots.get("stanford").chain(lengths).fk(np.array(q))


BAD_TARGETS = [
    ("rrp", (4.0, 0.0, 1.0), {}, "d3 = 3 m outside"),  # distance 4 > a2 + 2
    ("rrp", (0.0, 0.0, 2.0), {}, "z0 axis"),
    ("rrp", (0.0, 0.0, RRP["d1"]), {}, "z0 axis"),  # a2 + d3 = 0 as well
    ("elbow", (2.0, 0.0, 0.4), {}, "out of reach"),
    ("elbow", (ELBOW["d"], 0.0, ELBOW["d1"] + 0.01), {}, "out of reach"),  # inside the inner shell |a2 − a3|
    ("elbow", (0.05, 0.0, 0.4), {}, "shoulder offset"),  # x² + y² < d²
    ("elbow", (0.0, 0.0, 0.5), {"d": 0.0}, "z0 axis"),
    ("scara", (1.0, 0.0, 0.1), {}, "out of reach"),
    ("scara", (0.01, 0.0, 0.1), {}, "out of reach"),  # inside the inner circle |a1 − a2|
    ("scara", (0.5, 0.0, SCARA["d1"]), {}, "d3 = -0.05 m outside"),  # above the slide's top
    ("scara", (0.0, 0.0, 0.1), {"a1": 0.3, "a2": 0.3}, "z0 axis"),
    ("stanford", _stanford_pose((0.3, 0.8, 1.5, 0.1, 0.7, 0.2)), {}, "d3 = 1.5 m outside"),
    ("stanford", np.eye(4), {}, "shoulder offset"),  # wrist centre (0, 0, -d6): closer to z0 than d2
    ("stanford", _stanford_pose((0.3, 0.8, 0.6, 0.1, 0.0, 0.2)), {}, "wrist is singular"),
    ("stanford", _stanford_pose((0.3, 0.8, 0.0, 0.1, 0.7, 0.2)), {}, "θ2 is arbitrary"),
    ("stanford", _stanford_pose((0.3, 0.0, 0.6, 0.1, 0.7, 0.2), {"d2": 0.0}), {"d2": 0.0}, "z0 axis"),
    ("leg", (1.0, 0.0, 0.0), {}, "out of reach"),
    ("leg", (0.0, 0.0, -0.1), {}, "coxa axis"),
    ("leg", (0.0, 0.0, -1.0), {}, "out of reach"),  # on the axis and out of reach: the reach is the problem
]


@pytest.mark.parametrize(("robot", "target", "lengths", "why"), BAD_TARGETS)
def test_unreachable_and_singular_targets_raise_one_line(robot: str, target, lengths, why: str) -> None:
    with pytest.raises(IKError) as err:
        ik(robot, np.asarray(target, dtype=float), lengths)
    message = str(err.value)
    assert "\n" not in message and "nan" not in message.lower()
    assert why in message, message


def test_all_branches_outside_the_joint_ranges() -> None:
    # The leg's coxa at 2.5 rad is outside ±π/2; its mirror (q1 − π, rho < 0) is out of reach, q3 < 0 outside.
    pose = robots.get("leg").chain().fk(np.array([2.5, 0.3, 0.5]))
    with pytest.raises(IKError, match=r"every solution is outside the joint ranges \(coxa = 2.5 rad outside"):
        ik("leg", pose[:3, 3])


def test_ik_error_is_the_leg_one_and_bad_input_is_a_usage_error() -> None:
    assert IKError is leg.IKError and issubclass(IKError, UsageError)
    with pytest.raises(UsageError, match="unknown robot"):
        ik("puma", np.zeros(3))
    with pytest.raises(UsageError, match="target must be"):
        ik("rrp", np.zeros(4))
    with pytest.raises(UsageError, match="target must be"):
        ik("elbow", np.array([np.nan, 0.0, 0.0]))
    with pytest.raises(UsageError, match="homogeneous pose"):
        ik("stanford", 2 * np.eye(4))
    with pytest.raises(UsageError, match="4x4"):
        ik("stanford", np.zeros(3))
    with pytest.raises(UsageError, match="shape"):
        singularities("scara", np.zeros(3))


# ---------------------------------------------------------------------------------------------------------------
# Singular sets: every named condition loses rank, generic configurations keep it.


def _elbow_theta2_over_shoulder(theta3: float, a2: float, a3: float) -> float:
    """θ2 with a2 cos θ2 + a3 cos(θ2 + θ3) = 0 (the wrist centre's horizontal reach r = 0)."""
    return math.atan2(a2 + a3 * math.cos(theta3), a3 * math.sin(theta3))


def _leg_q2_on_axis(q3: float, p: dict[str, float]) -> float:
    """q2 with rho = l1 + l2 cos q2 + l3 cos(q2 + q3) = 0: R cos(q2 + φ) = −l1."""
    big, phi = (
        math.hypot(p["l2"] + p["l3"] * math.cos(q3), p["l3"] * math.sin(q3)),
        math.atan2(p["l3"] * math.sin(q3), p["l2"] + p["l3"] * math.cos(q3)),
    )
    return math.acos(-p["l1"] / big) - phi


SINGULAR_CASES = [
    ("rrp", {}, (0.3, math.pi / 2, 0.4), "cos_q2_zero"),
    ("rrp", {}, (0.3, -math.pi / 2, 0.4), "cos_q2_zero"),
    ("rrp", {}, (0.3, 0.5, -RRP["a2"]), "zero_reach"),
    ("elbow", {}, (0.3, 0.5, 0.0), "elbow_stretched_or_folded"),
    ("elbow", {}, (0.3, 0.5, math.pi), "elbow_stretched_or_folded"),
    ("elbow", {"d": 0.0}, (0.3, _elbow_theta2_over_shoulder(1.0, ELBOW["a2"], ELBOW["a3"]), 1.0), "wrist_centre_on_z0"),
    ("elbow", {}, (0.3, _elbow_theta2_over_shoulder(1.0, ELBOW["a2"], ELBOW["a3"]), 1.0),
     "wrist_centre_on_offset_cylinder"),
    ("scara", {}, (0.3, 0.0, 0.1, 0.5), "arm_stretched_or_folded"),
    ("scara", {}, (0.3, math.pi, 0.1, 0.5), "arm_stretched_or_folded"),
    ("stanford", {}, (0.3, 0.8, 0.6, 0.1, 0.0, 0.2), "wrist_sin_theta5_zero"),
    ("stanford", {}, (0.3, 0.8, 0.6, 0.1, math.pi, 0.2), "wrist_sin_theta5_zero"),
    ("stanford", {}, (0.3, 0.0, 0.6, 0.1, 0.7, 0.2), "arm_sin_theta2_zero"),
    ("stanford", {"d2": 0.0}, (0.3, math.pi, 0.6, 0.1, 0.7, 0.2), "arm_sin_theta2_zero"),
    ("stanford", {}, (0.3, 0.8, 0.0, 0.1, 0.7, 0.2), "d3_zero"),
    ("leg", {}, (0.3, 0.5, 0.0), "knee"),
    ("leg", {}, (0.3, _leg_q2_on_axis(1.2, LEG), 1.2), "coxa_axis"),
]  # fmt: skip


def _rank_ratio(robot: str, chain, q: np.ndarray) -> float:
    """sigma_min / sigma_max of the task Jacobian (3xn linear rows, SCARA + wz, Stanford 6x6)."""
    sigma = np.linalg.svd(chain.jacobian(q)[list(TASK_ROWS[robot])], compute_uv=False)
    return float(sigma[-1] / sigma[0])


@pytest.mark.parametrize(("robot", "lengths", "q", "condition"), SINGULAR_CASES)
def test_each_named_condition_loses_rank(robot: str, lengths, q: tuple[float, ...], condition: str) -> None:
    chain = robots.get(robot).chain(lengths)
    qa = np.array(q)
    flags = singularities(robot, qa, lengths)
    assert flags[condition], flags
    assert _rank_ratio(robot, chain, qa) < RANK_TOL
    # Linear rows too, for position robots: the 3xn block (rank < 3 even where n > 3 would not tell).
    if robot in ("rrp", "elbow", "leg"):
        assert np.linalg.matrix_rank(chain.jacobian(qa)[:3], tol=1e-12) < 3


def test_every_named_condition_is_tested_and_described() -> None:
    for robot in ROBOT_NAMES:
        names = set(singularities(robot, np.ones(robots.get(robot).chain().n) * 0.3))
        assert names == {c for r, _, _, c in SINGULAR_CASES if r == robot}
        assert len(SINGULAR_SETS[robot]) == len(names)
        assert all(f"({name})" in " ".join(SINGULAR_SETS[robot]) for name in names)
    assert set(SINGULAR_SETS) == set(robots.ROBOTS) == set(TASK_ROWS)


@pytest.mark.parametrize(("robot", "lengths"), [("rrp", {}), ("elbow", {}), ("elbow", {"d": 0.0}), ("scara", {}),
                                                ("stanford", {}), ("leg", {})])  # fmt: skip
def test_generic_configurations_have_full_rank_and_no_flag(robot: str, lengths: dict[str, float]) -> None:
    spec = robots.get(robot)
    chain = spec.chain(lengths)
    p = {name: float(lengths.get(name, length.default)) for name, length in spec.lengths.items()}
    rng = np.random.default_rng(RNG_SEED + 1)
    for _ in range(N):
        q = GENERIC[robot](rng, p)
        assert not any(singularities(robot, q, lengths).values()), q
        assert _rank_ratio(robot, chain, q) > 1e-6, q


def test_results_are_plain_python_values() -> None:
    # The CLI writes them as JSON: bools and floats, not numpy scalars.
    for robot in ROBOT_NAMES:
        q = np.full(robots.get(robot).chain().n, 0.3)
        assert all(type(flag) is bool for flag in singularities(robot, q).values())
        assert type(det_or_manipulability(robot, q)[1]) is float


def test_tolerance_of_the_flags() -> None:
    # SINGULAR_TOL = 1e-9 on sines and cosines: 1e-10 away is singular, 1e-6 away is not.
    assert singularities("scara", np.array([0.0, 1e-10, 0.1, 0.0]))["arm_stretched_or_folded"]
    assert not singularities("scara", np.array([0.0, 1e-6, 0.1, 0.0]))["arm_stretched_or_folded"]
    assert not singularities("rrp", np.array([0.0, math.pi / 2 - 1e-6, 0.5]))["cos_q2_zero"]


# ---------------------------------------------------------------------------------------------------------------
# Determinants: the module's closed forms and the test's own against np.linalg.det of chain.jacobian.


@pytest.mark.parametrize("robot", ROBOT_NAMES)
def test_det_matches_the_numerical_determinant(robot: str) -> None:
    chain = robots.get(robot).chain()
    rng = np.random.default_rng(RNG_SEED + 2)
    for _ in range(N):
        q = rng.uniform(-math.pi, math.pi, chain.n)
        kind, value = det_or_manipulability(robot, q)
        assert kind == "det"
        jac = chain.jacobian(q)[list(TASK_ROWS[robot])]
        assert jac.shape[0] == jac.shape[1]
        assert value == pytest.approx(np.linalg.det(jac), rel=1e-9, abs=1e-13)
        # And its magnitude is Yoshikawa's measure of the same rows.
        assert abs(value) == pytest.approx(math.sqrt(max(np.linalg.det(jac @ jac.T), 0.0)), rel=1e-6, abs=1e-7)


def _test_det(robot: str, chain, q: np.ndarray) -> float:
    """det of the task Jacobian from this test's own derivation, in terms of frame origins and FK positions.

    rrp: p − (0, 0, d1) = ρ u with u the radial unit vector; columns ρ c2 e_φ, ρ e_θ, u with [e_φ e_θ u] = +1:
        det = ρ² c2 = ρ (x c1 + y s1).
    elbow: column 1 = r e_φ + (component in the arm plane), columns 2, 3 in the arm plane (radial, z) with planar
        det a2 a3 s3, and [e_φ radial z] = −1: det = −a2 a3 s3 r, r = x c1 + y s1 (the in-plane reach).
    leg: the same structure, but its planar (q2, q3) block has det −l2 l3 s3 in (radial, z), as z = −h:
        det = l2 l3 s3 rho.
    scara: block-triangular in (x, y | z | wz): det = (o1 × (p − o1))_z · (−1) · (−1) = a1 a2 s2.
    """
    frames = chain.frames(q)
    x, y, _ = frames[-1][:3, 3]
    if robot == "rrp":
        rho = float(np.linalg.norm(frames[-1][:3, 3] - np.array([0.0, 0.0, RRP["d1"]])))
        return rho * (x * math.cos(q[0]) + y * math.sin(q[0]))
    if robot == "elbow":
        return -ELBOW["a2"] * ELBOW["a3"] * math.sin(q[2]) * (x * math.cos(q[0]) + y * math.sin(q[0]))
    if robot == "leg":
        return LEG["l2"] * LEG["l3"] * math.sin(q[2]) * (x * math.cos(q[0]) + y * math.sin(q[0]))
    o1, tip = frames[1][:3, 3], frames[-1][:3, 3]
    return float(o1[0] * (tip - o1)[1] - o1[1] * (tip - o1)[0])


@pytest.mark.parametrize("robot", ["rrp", "elbow", "scara", "leg"])
def test_closed_form_determinants_of_the_position_robots(robot: str) -> None:
    chain = robots.get(robot).chain()
    rng = np.random.default_rng(RNG_SEED + 3)
    lower = [-math.pi if j.lower is None else j.lower for j in chain.joints]
    upper = [math.pi if j.upper is None else j.upper for j in chain.joints]
    for _ in range(N):
        q = rng.uniform(lower, upper)  # (n,) inside the joint ranges (rrp: a2 + d3 >= 0, so ρ = a2 + d3)
        expected = np.linalg.det(chain.jacobian(q)[list(TASK_ROWS[robot])])
        assert _test_det(robot, chain, q) == pytest.approx(expected, rel=1e-9, abs=1e-13)


def test_stanford_determinant_factors_into_arm_and_wrist() -> None:
    # det J = det(J11) det[z3 z4 z5]: J11 = d(wrist centre)/d(θ1, θ2, d3) = −d3² s2, det[z3 z4 z5] = −s5.
    chain = robots.get("stanford").chain()
    rng = np.random.default_rng(RNG_SEED + 4)
    for _ in range(N):
        q = rng.uniform(-math.pi, math.pi, 6)
        frames = chain.frames(q)  # [T00, T01, ..., T06, tool]
        arm = robots.get("stanford").chain()
        centre_jac = np.zeros((3, 3))  # (3, 3)
        for i in range(3):
            step = np.zeros(6)
            step[i] = 1e-6
            centre_jac[:, i] = (arm.frames(q + step)[3][:3, 3] - arm.frames(q - step)[3][:3, 3]) / 2e-6
        wrist = np.column_stack([frames[i][:3, 2] for i in (3, 4, 5)])  # (3, 3) z3 z4 z5
        assert np.linalg.det(centre_jac) == pytest.approx(-(q[2] ** 2) * math.sin(q[1]), abs=1e-8)
        assert np.linalg.det(wrist) == pytest.approx(-math.sin(q[4]), abs=1e-12)
        assert np.linalg.det(chain.jacobian(q)) == pytest.approx(q[2] ** 2 * math.sin(q[1]) * math.sin(q[4]), abs=1e-12)
