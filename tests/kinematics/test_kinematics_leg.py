"""The hexabot leg's DH frames, Jacobians, singularities and IK against closed forms, SVD, FD and scipy."""

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics import dh
from hexabot_sim.kinematics.leg import (
    IKError,
    LegGeometry,
    condition_number,
    det_jacobian,
    fk,
    foot_and_jacobian,
    ik,
    intermediate_transforms,
    jacobian,
    jacobian_direct,
    jacobian_numerical,
    manipulability,
    rpy,
    singular_families,
    singular_values,
    transforms,
)

GEOM = LegGeometry()
L1, L2, L3 = GEOM.l1, GEOM.l2, GEOM.l3
N = 1000  # random configurations per property


@pytest.fixture
def qs() -> np.ndarray:
    """N random joint configurations in [rad], uniform in (-π, π]^3."""
    return np.random.default_rng(20240601).uniform(-math.pi, math.pi, size=(N, 3))  # (N, 3)


# Elementary homogeneous transforms, written out independently of dh.py.
def rot_x(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def rot_y(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s, 0], [0, 1, 0, 0], [-s, 0, c, 0], [0, 0, 0, 1.0]])


def rot_z(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def trans(x=0.0, y=0.0, z=0.0):
    t = np.eye(4)
    t[:3, 3] = x, y, z
    return t


def report_t04(q):
    """Report 000's printed foot pose T04, typed in from the formula."""
    c1, s1 = math.cos(q[0]), math.sin(q[0])
    s2 = math.sin(q[1])
    c23, s23 = math.cos(q[1] + q[2]), math.sin(q[1] + q[2])
    rho = L1 + L2 * math.cos(q[1]) + L3 * c23
    return np.array(
        [
            [c1 * c23, -c1 * s23, -s1, c1 * rho],
            [s1 * c23, -s1 * s23, c1, s1 * rho],
            [-s23, -c23, 0.0, -L2 * s2 - L3 * s23],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def rho_zero_config(q3: float, q1: float = 0.4) -> np.ndarray:
    """A configuration with the foot on the coxa axis (rho = 0) for a given knee angle q3.

    L2 c2 + L3 c23 = A c2 + B s2 = R cos(q2 - phi) with A = L2 + L3 c3, B = -L3 s3; set it to -L1.
    """
    a, b = L2 + L3 * math.cos(q3), -L3 * math.sin(q3)
    q2 = math.atan2(b, a) + math.acos(-L1 / math.hypot(a, b))
    return np.array([q1, q2, q3])


def same_angles(a, b, tol=1e-9) -> bool:
    return bool(np.all(np.abs((np.asarray(a) - b + math.pi) % (2 * math.pi) - math.pi) < tol))


# --- DH transforms ---------------------------------------------------------------------------------------------


def test_dh_transforms_are_their_elementary_products():
    rng = np.random.default_rng(1)
    for alpha, d, theta, r in rng.uniform(-3, 3, size=(50, 4)):
        np.testing.assert_allclose(
            dh.modified(alpha, d, theta, r), rot_x(alpha) @ trans(x=d) @ rot_z(theta) @ trans(z=r), atol=1e-15
        )
    for theta, d, a, alpha in rng.uniform(-3, 3, size=(50, 4)):
        np.testing.assert_allclose(
            dh.standard(theta, d, a, alpha), rot_z(theta) @ trans(z=d) @ trans(x=a) @ rot_x(alpha), atol=1e-15
        )


def test_dh_transforms_broadcast():
    theta = np.linspace(-1, 1, 7)
    batch = dh.modified(-math.pi / 2, 0.05, theta, 0.0)
    assert batch.shape == (7, 4, 4)
    for k, t in enumerate(theta):
        np.testing.assert_array_equal(batch[k], dh.modified(-math.pi / 2, 0.05, t, 0.0))
    assert dh.chain([]) == []


def test_both_conventions_give_the_same_foot_pose(qs):
    modified_foot = transforms(qs, GEOM, "modified")[-1]  # (N, 4, 4)
    standard_foot = transforms(qs, GEOM, "standard")[-1]  # (N, 4, 4)
    assert modified_foot.shape == standard_foot.shape == (N, 4, 4)
    np.testing.assert_allclose(modified_foot, standard_foot, rtol=0, atol=1e-15)


def test_intermediate_frames_differ_between_conventions():
    q = np.array([0.3, -0.4, 0.9])
    modified_frames = transforms(q, GEOM, "modified")
    standard_frames = transforms(q, GEOM, "standard")
    assert len(modified_frames) == 4 and len(standard_frames) == 3
    assert len(intermediate_transforms(q, GEOM, "modified")) == 4
    # Modified frame 1 is on the coxa axis; standard frame 1 already carries the coxa link to the femur axis.
    np.testing.assert_allclose(modified_frames[0][:3, 3], 0.0, atol=1e-15)
    np.testing.assert_allclose(standard_frames[0][:3, 3], [L1 * math.cos(0.3), L1 * math.sin(0.3), 0.0], atol=1e-15)


def test_report_t04_equals_the_last_frame(qs):
    frames = transforms(qs, GEOM)[-1]  # (N, 4, 4)
    for q, t in zip(qs, frames, strict=True):
        np.testing.assert_allclose(t, report_t04(q), rtol=0, atol=1e-15)


def test_fk_is_the_foot_position_for_single_and_batch(qs):
    feet = fk(qs, GEOM)
    assert feet.shape == (N, 3)
    np.testing.assert_allclose(feet, transforms(qs, GEOM)[-1][:, :3, 3], rtol=0, atol=1e-15)
    assert fk(qs[0]).shape == (3,)
    assert fk(qs.reshape(10, 100, 3)).shape == (10, 100, 3)
    np.testing.assert_allclose(fk([0.0, 0.0, 0.0]), [L1 + L2 + L3, 0.0, 0.0], atol=1e-15)


# --- Jacobians ---------------------------------------------------------------------------------------------------


def test_analytic_direct_and_numerical_jacobians_agree(qs):
    analytic = jacobian(qs, GEOM)  # (N, 3, 3)
    assert analytic.shape == (N, 3, 3)
    for q, jac in zip(qs, analytic, strict=True):
        np.testing.assert_allclose(jacobian_direct(q, GEOM), jac, rtol=0, atol=1e-12)
        np.testing.assert_allclose(jacobian_numerical(q, GEOM), jac, rtol=0, atol=1e-8)


def test_geometric_jacobian_of_a_scara_with_a_prismatic_joint():
    # SCARA, standard DH (theta, d, a, alpha): (q1, 0, a1, 0), (q2, 0, a2, π), (0, q3, 0, 0); joint i acts on z_{i-1}.
    a1, a2 = 0.3, 0.2

    def frames(q):
        links = [dh.standard(q[0], 0, a1, 0), dh.standard(q[1], 0, a2, math.pi), dh.standard(0, q[2], 0, 0)]
        return [np.eye(4), *dh.chain(links)]

    q = np.array([0.4, -1.1, 0.05])
    f = frames(q)
    jac = dh.geometric_jacobian(f, [0, 1, 2], f[-1][:3, 3], prismatic=[False, False, True])
    assert jac.shape == (6, 3)
    np.testing.assert_allclose(jac[:3], dh.numerical_jacobian(lambda x: frames(x)[-1][:3, 3], q), atol=1e-9)
    np.testing.assert_allclose(jac[3:], [[0, 0, 0], [0, 0, 0], [1, 1, 0]], atol=1e-15)


def test_det_formula_matches_numpy(qs):
    np.testing.assert_allclose(det_jacobian(qs, GEOM), np.linalg.det(jacobian(qs, GEOM)), rtol=0, atol=1e-16)
    np.testing.assert_allclose(manipulability(qs, GEOM), np.abs(np.linalg.det(jacobian(qs, GEOM))), atol=1e-16)
    assert isinstance(det_jacobian(qs[0]), float)


def test_singular_values_match_svd(qs):
    knee = np.array([[0.2, 0.5, 0.0], [1.0, -0.3, math.pi], [-2.0, 0.1, -math.pi]])
    axis = np.array([rho_zero_config(q3) for q3 in (0.7, 1.5707963, -2.0)])
    configs = np.concatenate([qs, knee, axis])
    small, big = singular_values(configs, GEOM)
    sv = np.linalg.svd(jacobian(configs, GEOM), compute_uv=False)  # (n, 3), descending
    np.testing.assert_allclose(small, sv[:, -1], rtol=0, atol=1e-15)
    np.testing.assert_allclose(big, sv[:, 0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(condition_number(qs, GEOM), sv[: len(qs), 0] / sv[: len(qs), -1], rtol=1e-9)


@pytest.mark.parametrize("q3", [0.0, math.pi, -math.pi, 2 * math.pi])
def test_stretched_or_folded_knee_is_singular(q3):
    q = np.array([0.3, -0.6, q3])
    sv = np.linalg.svd(jacobian(q, GEOM), compute_uv=False)
    assert sv[-1] < 1e-15 * sv[0] * 10 and sv[1] > 1e-3  # rank 2
    assert singular_families(q, GEOM) == {"knee": True, "coxa_axis": False}
    assert abs(det_jacobian(q, GEOM)) < 1e-17


def test_foot_on_the_coxa_axis_is_singular_with_the_knee_bent():
    """The family report 000 missed: q3 = π/2, far from kπ, yet J has rank 2 (the coxa turns the foot in place)."""
    q = rho_zero_config(math.pi / 2)
    foot = fk(q, GEOM)
    assert math.hypot(foot[0], foot[1]) < 1e-16
    jac = jacobian(q, GEOM)
    sv = np.linalg.svd(jac, compute_uv=False)
    assert sv[-1] < 1e-15 and sv[1] > 1e-2  # rank 2
    np.testing.assert_allclose(jac[:, 0], 0.0, atol=1e-16)  # the null direction is the coxa
    assert abs(math.sin(q[2])) == 1.0
    assert singular_families(q, GEOM) == {"knee": False, "coxa_axis": True}
    assert manipulability(q, GEOM) < 1e-17
    assert condition_number(q, GEOM) > 1e13


def test_generic_configuration_is_not_singular():
    q = np.array([0.1, 0.4, 1.2])
    assert singular_families(q, GEOM) == {"knee": False, "coxa_axis": False}
    assert 1.0 <= condition_number(q, GEOM) < 10.0


def test_condition_number_is_inf_not_nan_where_exactly_singular():
    assert condition_number([0.0, 0.0, 0.0], GEOM) == math.inf
    batch = condition_number(np.array([[0.0, 0.3, 0.0], [0.0, 0.3, 1.0]]), GEOM)
    assert batch[0] == np.inf and np.isfinite(batch[1]) and not np.any(np.isnan(batch))


# --- Inverse kinematics -----------------------------------------------------------------------------------------


def test_ik_round_trip_returns_every_branch_including_the_original(qs):
    four = 0
    for q in qs[:300]:
        p = fk(q, GEOM)
        solutions = ik(p, GEOM)
        # Coxa towards the foot: femur axis at distance hypot(|xy| - L1, z) from the foot, always reachable here.
        # Coxa turned away: at hypot(|xy| + L1, z); two more branches when that is within L2 + L3.
        backward = math.hypot(math.hypot(p[0], p[1]) + L1, p[2]) < L2 + L3
        assert len(solutions) == (4 if backward else 2)
        four += len(solutions) == 4
        for sol in solutions:
            assert sol.shape == (3,) and np.all(sol > -math.pi) and np.all(sol <= math.pi)
            np.testing.assert_allclose(fk(sol, GEOM), p, rtol=0, atol=1e-12)
        assert any(same_angles(sol, q) for sol in solutions)
        assert not any(same_angles(a, b) for i, a in enumerate(solutions) for b in solutions[i + 1 :])
    assert four > 100  # the generic case with the foot under the hip has all 4


def test_ik_stretched_leg_returns_the_coinciding_branch_once():
    q = np.array([0.5, 0.3, 0.0])
    solutions = ik(fk(q, GEOM), GEOM)
    forward = [s for s in solutions if same_angles(s[0], 0.5)]
    assert len(forward) == 1 and same_angles(forward[0], q)
    for sol in solutions:
        np.testing.assert_allclose(fk(sol, GEOM), fk(q, GEOM), rtol=0, atol=1e-12)


@pytest.mark.parametrize("p", [(0.3, 0.0, 0.0), (0.1, 0.2, -0.3), (0.0, 0.0, -1.0)])
def test_ik_unreachable_raises_one_line_error(p):
    with pytest.raises(IKError, match="out of reach") as excinfo:
        ik(p, GEOM)
    message = str(excinfo.value)
    assert "\n" not in message and "reachable 0 to 0.2 m" in message and f"{p[2]:.6g}" in message
    assert isinstance(excinfo.value, UsageError)


def test_ik_on_the_coxa_axis_needs_q1():
    p = fk(rho_zero_config(1.0), GEOM)
    p[:2] = 0.0
    with pytest.raises(IKError, match="coxa axis") as excinfo:
        ik(p, GEOM)
    assert "\n" not in str(excinfo.value)
    solutions = ik(p, GEOM, q1=0.7)
    assert len(solutions) == 2
    for sol in solutions:
        assert sol[0] == 0.7
        np.testing.assert_allclose(fk(sol, GEOM), p, rtol=0, atol=1e-12)


def test_ik_just_outside_the_shell_is_clamped_onto_it():
    p = np.array([L1 + (L2 + L3) * (1 + 1e-14), 0.0, 0.0])
    (sol,) = [s for s in ik(p, GEOM) if abs(s[0]) < 1e-12]
    np.testing.assert_allclose(sol, 0.0, atol=1e-12)


# --- Euler angles, scalar path, input checks --------------------------------------------------------------------


def test_rpy_matches_scipy_and_rebuilds_the_matrix():
    rotations = Rotation.random(500, random_state=7)
    matrices = rotations.as_matrix()  # (500, 3, 3)
    roll, pitch, yaw = rpy(matrices)
    # Intrinsic Z-Y'-X'' and extrinsic x-y-z both mean R = Rz(yaw) Ry(pitch) Rx(roll).
    np.testing.assert_allclose(np.stack([yaw, pitch, roll], axis=-1), rotations.as_euler("ZYX"), atol=1e-12)
    np.testing.assert_allclose(np.stack([roll, pitch, yaw], axis=-1), rotations.as_euler("xyz"), atol=1e-12)
    for k in range(20):
        rebuilt = rot_z(yaw[k]) @ rot_y(pitch[k]) @ rot_x(roll[k])
        np.testing.assert_allclose(rebuilt[:3, :3], matrices[k], atol=1e-14)


@pytest.mark.parametrize("pitch", [math.pi / 2, -math.pi / 2])
def test_rpy_at_gimbal_lock_still_rebuilds_the_matrix(pitch):
    matrix = (rot_z(0.8) @ rot_y(pitch) @ rot_x(-0.3))[:3, :3]
    roll, pitch_out, yaw = rpy(matrix)
    assert roll == 0.0 and pitch_out == pytest.approx(pitch)
    np.testing.assert_allclose((rot_z(yaw) @ rot_y(pitch_out) @ rot_x(roll))[:3, :3], matrix, atol=1e-12)


def test_rpy_of_the_foot_frame():
    # T04 = Rz(q1) Rx(-π/2) Rz(q2 + q3) = Rz(q1) Ry(q2 + q3) Rx(-π/2), since Rx(-π/2) maps z to y.
    roll, pitch, yaw = rpy(transforms([0.4, 0.3, 0.5], GEOM)[-1])
    assert (roll, pitch, yaw) == pytest.approx((-math.pi / 2, 0.8, 0.4), abs=1e-12)


def test_scalar_and_numpy_paths_of_foot_and_jacobian_agree(qs):
    p_np, jac_np = fk(qs, GEOM), jacobian(qs, GEOM)
    for q, p_ref, jac_ref in zip(qs[:200], p_np[:200], jac_np[:200], strict=True):
        p, jac = foot_and_jacobian(*(float(v) for v in q), L1, L2, L3)
        assert all(isinstance(v, float) for v in p)
        np.testing.assert_allclose(p, p_ref, rtol=0, atol=1e-16)
        np.testing.assert_allclose(np.array(jac, dtype=float), jac_ref, rtol=0, atol=1e-16)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: fk([0.0, 0.0]), "3 joint angles"),
        (lambda: fk([0.0, math.nan, 0.0]), "finite"),
        (lambda: jacobian_direct(np.zeros((2, 3))), r"shape \(3,\)"),
        (lambda: transforms([0.0, 0.0, 0.0], convention="craig"), "known: modified, standard"),
        (lambda: ik([0.1, 0.0]), "shape"),
        (lambda: ik([0.1, 0.0, 0.0], LegGeometry(l3=0.0)), "l2, l3 > 0"),
        (lambda: rpy(np.eye(2)), "rotation matrix"),
        (lambda: dh.numerical_jacobian(np.sin, [0.0], eps=0.0), "eps"),
    ],
)
def test_bad_input_raises_usage_error(call, match):
    with pytest.raises(UsageError, match=match):
        call()
