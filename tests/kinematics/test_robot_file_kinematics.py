"""FK and J of random robot files against an independent implementation; numeric IK round trips and refusals.

The independent implementation: each row as a product of elementary 4x4 matrices (Rz, Tz, Tx, Rx in the order
of its convention), evaluated in forward-mode automatic differentiation (dual numbers carrying d/dq), so the
linear rows of J are dp/dq and the angular rows the axial vector of (dR/dq) Rᵀ, exact to rounding. It shares
no code with hexabot_sim.kinematics (no DH matrix formula, no z × (p − o) columns).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import cli, random_q, random_table, to_toml

from hexabot_sim.kinematics import numeric_ik, robot_file
from hexabot_sim.kinematics.leg import IKError

TOL = 1e-12


class Dual:
    """A value and its gradient with respect to the n joint values."""

    def __init__(self, value: float, grad: np.ndarray) -> None:
        self.value, self.grad = value, grad

    def __add__(self, other):
        if isinstance(other, Dual):
            return Dual(self.value + other.value, self.grad + other.grad)
        return Dual(self.value + other, self.grad)

    __radd__ = __add__

    def __mul__(self, other):
        if isinstance(other, Dual):
            return Dual(self.value * other.value, self.grad * other.value + other.grad * self.value)
        return Dual(self.value * other, self.grad * other)

    __rmul__ = __mul__

    def __neg__(self):
        return Dual(-self.value, -self.grad)


def cos(x):
    return Dual(math.cos(x.value), -math.sin(x.value) * x.grad) if isinstance(x, Dual) else math.cos(x)


def sin(x):
    return Dual(math.sin(x.value), math.cos(x.value) * x.grad) if isinstance(x, Dual) else math.sin(x)


def matmul(a, b):
    return [[sum((a[i][k] * b[k][j] for k in range(4)), 0.0) for j in range(4)] for i in range(4)]


def rot_z(t):
    return [[cos(t), -sin(t), 0.0, 0.0], [sin(t), cos(t), 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]


def rot_x(t):
    return [[1.0, 0.0, 0.0, 0.0], [0.0, cos(t), -sin(t), 0.0], [0.0, sin(t), cos(t), 0.0], [0.0, 0.0, 0.0, 1.0]]


def trans(x, y, z):
    return [[1.0, 0.0, 0.0, x], [0.0, 1.0, 0.0, y], [0.0, 0.0, 1.0, z], [0.0, 0.0, 0.0, 1.0]]


def rpy_matrix(roll, pitch, yaw):
    c, s = math.cos, math.sin
    rz = np.array([[c(yaw), -s(yaw), 0], [s(yaw), c(yaw), 0], [0, 0, 1]])
    ry = np.array([[c(pitch), 0, s(pitch)], [0, 1, 0], [-s(pitch), 0, c(pitch)]])
    rx = np.array([[1, 0, 0], [0, c(roll), -s(roll)], [0, s(roll), c(roll)]])
    return rz @ ry @ rx


def independent_fk_and_jacobian(table: dict, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Tool pose (4, 4) and geometric J (6, n) from the table as written in the file (angles in its unit)."""
    n = len(q)
    scale = math.pi / 180 if table["angles"] == "deg" else 1.0
    variables = [Dual(float(v), np.eye(n)[i]) for i, v in enumerate(q)]
    pose = _fixed(table["base"], scale)
    for row, var in zip(table["joints"], variables, strict=True):
        theta = row["theta"] * scale + (var if row["type"] == "revolute" else 0.0)
        d = row["d"] + (var if row["type"] == "prismatic" else 0.0)
        alpha, a = row["alpha"] * scale, row["a"]
        if table["convention"] == "standard":
            parts = [rot_z(theta), trans(0.0, 0.0, d), trans(a, 0.0, 0.0), rot_x(alpha)]
        else:
            parts = [rot_x(alpha), trans(a, 0.0, 0.0), rot_z(theta), trans(0.0, 0.0, d)]
        for part in parts:
            pose = matmul(pose, part)
    pose = matmul(pose, _fixed(table["tool"], scale))
    value = np.array([[e.value if isinstance(e, Dual) else e for e in row] for row in pose])  # (4, 4)
    grad = np.array([[e.grad if isinstance(e, Dual) else np.zeros(n) for e in row] for row in pose])  # (4, 4, n)
    jac = np.zeros((6, n))
    jac[:3] = grad[:3, 3]
    rot = value[:3, :3]
    for j in range(n):
        omega = grad[:3, :3, j] @ rot.T  # skew-symmetric
        jac[3:, j] = omega[2, 1], omega[0, 2], omega[1, 0]
    return value, jac


def _fixed(frame: dict, scale: float):
    t = np.eye(4)
    t[:3, :3] = rpy_matrix(*(v * scale for v in frame["rpy"]))
    t[:3, 3] = frame["xyz"]
    return t.tolist()


@pytest.mark.parametrize("convention", ["standard", "modified"])
def test_fk_and_jacobian_of_random_files_equal_the_independent_implementation(convention):
    rng = np.random.default_rng(7 if convention == "standard" else 8)
    worst_fk = worst_jac = 0.0
    for k in range(28):  # 1 to 7 joints, 4 tables each, half in degrees
        table = random_table(rng, 1 + k % 7, convention, "deg" if k % 2 else "rad")
        chain = robot_file.parse(to_toml(table)).chain()
        for _ in range(3):
            q = random_q(table, rng)
            pose, jac = independent_fk_and_jacobian(table, q)
            worst_fk = max(worst_fk, np.max(np.abs(chain.fk(q) - pose)))
            worst_jac = max(worst_jac, np.max(np.abs(chain.jacobian(q) - jac)))
    assert worst_fk <= TOL and worst_jac <= TOL, (worst_fk, worst_jac)


def test_the_independent_implementation_sees_a_wrong_sign():
    """The check can fail: a table read with one twist negated differs from the file's own."""
    rng = np.random.default_rng(3)
    table = random_table(rng, 4, "standard", "rad")
    q = random_q(table, rng)
    chain = robot_file.parse(to_toml(table)).chain()
    table["joints"][1]["alpha"] *= -1
    pose, jac = independent_fk_and_jacobian(table, q)
    assert np.max(np.abs(chain.fk(q) - pose)) > 1e-3 or np.max(np.abs(chain.jacobian(q) - jac)) > 1e-3


@pytest.mark.parametrize("n", [3, 6])
def test_numeric_ik_recovers_the_configuration_of_random_targets(n):
    """Targets made by FK of random in-range q: the q is among the solutions, each within RESIDUAL_TOL."""
    rng = np.random.default_rng(11 + n)
    recovered = total = 0
    for k in range(12):
        table = random_table(rng, n, ("standard", "modified")[k % 2], "rad")
        chain = robot_file.parse(to_toml(table)).chain()
        q = random_q(table, rng)
        target = chain.fk(q) if n == 6 else chain.fk(q)[:3, 3]
        solutions = numeric_ik.solve(chain, target)
        revolute = np.array([not j.prismatic for j in chain.joints])
        for s in solutions:
            assert s.position_residual <= numeric_ik.RESIDUAL_TOL
            assert np.linalg.norm(chain.fk(s.q)[:3, 3] - (target[:3, 3] if n == 6 else target)) <= 1e-10
            if n == 6:
                assert s.orientation_residual is not None and s.orientation_residual <= numeric_ik.RESIDUAL_TOL
            lo = np.array([j.lower for j in chain.joints])
            hi = np.array([j.upper for j in chain.joints])
            assert np.all(s.q >= lo - 1e-12) and np.all(s.q <= hi + 1e-12)
        recovered += any(numeric_ik._same(q.copy(), s.q.copy(), revolute) for s in solutions)
        total += 1
    assert recovered >= total - 1  # scripts/ik_check.py measures the rate on 1,000 cases


def test_numeric_ik_refuses_an_unreachable_target_in_one_line():
    table = random_table(np.random.default_rng(5), 3, "standard", "rad")
    chain = robot_file.parse(to_toml(table)).chain()
    with pytest.raises(IKError, match=r"no solution within the joint ranges from \d+ seeds \(closest: ") as info:
        numeric_ik.solve(chain, np.array([50.0, 0.0, 0.0]))
    assert "\n" not in str(info.value)


def test_kin_file_text_and_json(tmp_path, capsys):
    rng = np.random.default_rng(9)
    table = random_table(rng, 6, "modified", "deg")
    path = tmp_path / "six.toml"
    path.write_text(to_toml(table))
    chain = robot_file.read(path).chain()
    q = random_q(table, rng)
    pose = chain.fk(q)
    rot = pose[:3, :3]
    rpy = [math.atan2(rot[2, 1], rot[2, 2]), -math.asin(rot[2, 0]), math.atan2(rot[1, 0], rot[0, 0])]
    target = ",".join(repr(float(v)) for v in [*pose[:3, 3], *rpy])
    code, out, err = cli(
        capsys, "kin", str(path), "--json", "--q", ",".join(repr(float(v)) for v in q), f"--target={target}"
    )
    assert code == 0, err
    import json

    report = json.loads(out)
    assert report["file"] == str(path) and len(report["dh"]) == 6 and "det" in report and "sigma_min" in report
    np.testing.assert_allclose(report["T0n"], pose, atol=1e-15)
    assert report["solutions"] and all(s["orientation_residual"] <= 1e-10 for s in report["solutions"])
    code, out, err = cli(capsys, "kin", str(path), "--target=0.1,0.2,0.3")
    assert code == 2 and "needs --target x,y,z,roll,pitch,yaw" in err and err.count("\n") == 1


@pytest.mark.parametrize("q3", [0.0, math.pi])
def test_a_stretched_or_folded_arm_is_one_solution_per_branch_not_a_cluster(q3):
    """The elbow arm as a file, stretched (q3 = 0) or folded (q3 = pi): its two shoulder branches each meet their
    elbow-up and elbow-down twins there. The seeds stopped anywhere within ~1e-5 rad of the singular solution (the
    error grows quadratically away from it) and kin listed 16 "distinct solutions" instead of 2."""
    chain = robot_file.read(robot_file.builtin_files()["elbow"]).chain()
    target = chain.fk(np.array([0.3, 0.2, q3]))[:3, 3]
    solutions = numeric_ik.solve(chain, target)
    assert len(solutions) == 2
    for s in solutions:
        assert s.position_residual <= numeric_ik.RESIDUAL_TOL and s.sigma_min < 1e-5
        assert s.near_singular  # sigma_min / sigma_max ~2e-6 there: 1e-6 missed it
        assert abs(math.remainder(s.q[2] - q3, 2 * math.pi)) < 1e-4


def test_solutions_away_from_a_singularity_are_not_flagged():
    """The solution flag's threshold is the solver's resolution (~1e-5 rad) at a singular solution, not a band around
    it: the elbow bent by 0.06 deg (q3 = 1e-3) is not flagged, nor at 0.5 rad."""
    chain = robot_file.read(robot_file.builtin_files()["elbow"]).chain()
    for q3 in (1e-3, 0.5):
        solutions = numeric_ik.solve(chain, chain.fk(np.array([0.3, 0.2, q3]))[:3, 3])
        assert len(solutions) == 4 and not any(s.near_singular for s in solutions)
