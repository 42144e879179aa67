"""models/leg.xml against the analytic kinematics, MuJoCo's own Jacobians, finite differences and closed forms."""

import math
import re

import mujoco
import numpy as np
import pytest

from hexabot_sim import models
from hexabot_sim.kinematics import leg
from hexabot_sim.robots.leg import parameters as leg_parameters
from hexabot_sim.robots.leg.step import GEOMETRY

JOINTS = ("coxa", "femur", "tibia")
BODIES = ("coxa", "femur", "tibia")  # bodies whose frames are the modified-DH frames 1, 2, 3
N = 1000  # random configurations per property
HEADER = models.model_path("leg").read_text().split("-->", 1)[0]  # the comment that states every number

# Stated in the leg.xml header: "bandwidth f_n = 20 Hz ... damping ratio zeta = 1".
F_N = 20.0  # [Hz]
ZETA = 1.0
# Stated in the header: link masses [kg], lengths [m] and the tube radius [m] of the rod inertias.
MASS = {"coxa": 0.030, "femur": 0.060, "tibia": 0.040}
LENGTH = {"coxa": 0.05, "femur": 0.10, "tibia": 0.10}
TUBE_RADIUS = 0.010
ARMATURE = 2e-5  # [kg m^2]
HOME_FOOT = (0.05, 0.0, -0.08)  # [m] hip frame: "hip frame x = 50 mm, z = -80 mm"


def load(name: str = "leg") -> tuple[mujoco.MjModel, mujoco.MjData]:
    model = mujoco.MjModel.from_xml_path(str(models.model_path(name)))
    return model, mujoco.MjData(model)


def joint_ranges(model: mujoco.MjModel) -> tuple[np.ndarray, np.ndarray]:
    ranges = np.array([model.jnt_range[model.joint(j).id] for j in JOINTS])  # (3, 2)
    return ranges[:, 0], ranges[:, 1]


def set_q(model: mujoco.MjModel, data: mujoco.MjData, q: np.ndarray) -> None:
    """qpos = q by joint name, then positions, orientations and com-based quantities for the Jacobians."""
    for name, value in zip(JOINTS, q, strict=True):
        data.qpos[model.joint(name).qposadr[0]] = value
    mujoco.mj_kinematics(model, data)
    mujoco.mj_comPos(model, data)


def hip_frame(data: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
    """World pose of the hip site (DH frame 0): position (3,), rotation (3, 3)."""
    return data.site("hip").xpos.copy(), data.site("hip").xmat.reshape(3, 3).copy()


def site_jacobian(model: mujoco.MjModel, data: mujoco.MjData, site: str) -> tuple[np.ndarray, np.ndarray]:
    """mj_jacSite (translational, rotational), world frame, columns in joint order coxa, femur, tibia."""
    jacp = np.zeros((3, model.nv))  # (3, nv)
    jacr = np.zeros((3, model.nv))  # (3, nv)
    mujoco.mj_jacSite(model, data, jacp, jacr, model.site(site).id)
    cols = [model.joint(j).dofadr[0] for j in JOINTS]
    return jacp[:, cols], jacr[:, cols]


def dof(model: mujoco.MjModel, joint: str) -> int:
    return int(model.joint(joint).dofadr[0])


@pytest.fixture(scope="module")
def leg_model():
    return load()


@pytest.fixture(scope="module")
def q_inside(leg_model):
    """N random configurations inside the joint ranges, (N, 3) [rad]."""
    lower, upper = joint_ranges(leg_model[0])
    return np.random.default_rng(7).uniform(lower, upper, size=(N, 3))


@pytest.fixture(scope="module")
def q_outside(leg_model):
    """N random configurations with at least one joint outside its range, (N, 3) [rad]."""
    lower, upper = joint_ranges(leg_model[0])
    q = np.random.default_rng(8).uniform(-3 * math.pi, 3 * math.pi, size=(4 * N, 3))
    q = q[np.any((q < lower) | (q > upper), axis=1)][:N]
    assert len(q) == N
    return q


@pytest.fixture(scope="module", params=["inside", "outside"])
def qs(request, q_inside, q_outside):
    return q_inside if request.param == "inside" else q_outside


def test_hip_site_is_frame_0_at_0_3_m_axes_aligned(leg_model):
    model, data = leg_model
    mujoco.mj_kinematics(model, data)
    pos, rot = hip_frame(data)
    assert np.array_equal(pos, [0, 0, 0.3])
    assert np.array_equal(rot, np.eye(3))


def test_qpos_is_the_dh_q_foot_position(leg_model, qs):
    model, data = leg_model
    worst = 0.0
    for q in qs:
        set_q(model, data, q)
        hip_pos, hip_rot = hip_frame(data)
        foot = hip_rot.T @ (data.site("foot").xpos - hip_pos)  # (3,) hip frame
        worst = max(worst, np.max(np.abs(foot - leg.fk(q, GEOMETRY))))
    assert worst <= 1e-12


def test_body_frames_are_the_modified_dh_frames(leg_model, qs):
    model, data = leg_model
    worst = 0.0
    for q in qs:
        set_q(model, data, q)
        hip_pos, hip_rot = hip_frame(data)
        frames = leg.transforms(q, GEOMETRY, "modified")  # T01, T02, T03, T04
        for body, t in zip(BODIES, frames[:3], strict=True):
            pos = hip_pos + hip_rot @ t[:3, 3]
            rot = hip_rot @ t[:3, :3]
            worst = max(worst, np.max(np.abs(data.body(body).xpos - pos)))
            worst = max(worst, np.max(np.abs(data.body(body).xmat.reshape(3, 3) - rot)))
        # The foot site is frame 4: same origin as fk, orientation of T04.
        foot_rot = hip_rot.T @ data.site("foot").xmat.reshape(3, 3)
        worst = max(worst, np.max(np.abs(foot_rot - frames[3][:3, :3])))
        worst = max(worst, np.max(np.abs(hip_rot.T @ (data.site("foot").xpos - hip_pos) - frames[3][:3, 3])))
    assert worst <= 1e-12


def test_analytic_jacobian_is_mj_jacsite(leg_model, qs):
    model, data = leg_model
    worst_lin, worst_ang = 0.0, 0.0
    for q in qs:
        set_q(model, data, q)
        _, hip_rot = hip_frame(data)
        jacp, jacr = site_jacobian(model, data, "foot")
        worst_lin = max(worst_lin, np.max(np.abs(hip_rot.T @ jacp - leg.jacobian(q, GEOMETRY))))
        # Angular part: column j is the joint axis z_j of DH frame j (hinges only).
        frames = leg.transforms(q, GEOMETRY, "modified")
        axes = np.stack([t[:3, 2] for t in frames[:3]], axis=1)  # (3, 3)
        worst_ang = max(worst_ang, np.max(np.abs(hip_rot.T @ jacr - axes)))
    assert worst_lin <= 1e-12
    assert worst_ang <= 1e-12


def test_mj_jacsite_matches_central_differences_of_the_site_position(leg_model, q_inside):
    """Checks the checker: MuJoCo's Jacobian against its own kinematics, no analytic formula involved."""
    model, data = leg_model
    h = 1e-6  # [rad]; truncation ~h^2 |p'''| ~ 1e-13 m, rounding ~1e-16 / h ~ 1e-10
    worst = 0.0
    for q in q_inside[:200]:
        set_q(model, data, q)
        jacp, _ = site_jacobian(model, data, "foot")
        numeric = np.zeros((3, 3))  # (3, 3)
        for i in range(3):
            step = np.zeros(3)
            step[i] = h
            set_q(model, data, q + step)
            plus = data.site("foot").xpos.copy()
            set_q(model, data, q - step)
            numeric[:, i] = (plus - data.site("foot").xpos) / (2 * h)
        worst = max(worst, np.max(np.abs(numeric - jacp)))
    assert worst <= 1e-8


def test_det_closed_form_is_det_of_the_mujoco_jacobian(leg_model, qs):
    model, data = leg_model
    worst = 0.0
    for q in qs[:300]:
        set_q(model, data, q)
        _, hip_rot = hip_frame(data)
        jacp, _ = site_jacobian(model, data, "foot")
        worst = max(worst, abs(np.linalg.det(hip_rot.T @ jacp) - leg.det_jacobian(q, GEOMETRY)))
    assert worst <= 1e-15  # |det J| ~ 1e-3 m^3; rounding of a 3x3 determinant of O(0.1) entries


def coxa_axis_configuration(q1: float, q3: float) -> np.ndarray:
    """q with the foot on the coxa axis: rho = l1 + l2 c2 + l3 c(2+3) = 0, i.e. R cos(q2 + phi) = -l1."""
    g = GEOMETRY
    radius = math.hypot(g.l2 + g.l3 * math.cos(q3), g.l3 * math.sin(q3))
    phi = math.atan2(g.l3 * math.sin(q3), g.l2 + g.l3 * math.cos(q3))
    return np.array([q1, math.acos(-g.l1 / radius) - phi, q3])


def test_both_singular_families_give_rank_2_mujoco_jacobians(leg_model):
    model, data = leg_model
    rng = np.random.default_rng(3)
    knee = [np.array([rng.uniform(-1.5, 1.5), rng.uniform(-1.5, 1.5), 0.0]) for _ in range(50)]
    axis = [coxa_axis_configuration(rng.uniform(-1.5, 1.5), rng.uniform(0.5, 2.4)) for _ in range(50)]
    for q in axis:  # the construction really puts the foot on the coxa axis, knee well bent
        assert math.hypot(*leg.fk(q, GEOMETRY)[:2]) <= 1e-15 and abs(math.sin(q[2])) > 0.45
    for q in knee + axis:
        set_q(model, data, q)
        jacp, _ = site_jacobian(model, data, "foot")
        sv = np.linalg.svd(jacp, compute_uv=False)
        assert sv[2] < 1e-12 and sv[1] > 1e-3, (q, sv)
        assert np.linalg.matrix_rank(jacp, tol=1e-10) == 2
    # A generic configuration is not singular: the check can fail.
    set_q(model, data, np.array([0.2, 0.4, 1.5]))
    assert np.linalg.svd(site_jacobian(model, data, "foot")[0], compute_uv=False)[2] > 1e-2


def test_link_lengths_are_the_scenario_geometry(leg_model):
    model, _ = leg_model
    g = GEOMETRY
    assert np.array_equal(model.body("coxa").pos, [0, 0, 0])
    assert np.array_equal(model.body("femur").pos, [g.l1, 0, 0])
    assert np.array_equal(model.body("tibia").pos, [g.l2, 0, 0])
    assert np.array_equal(model.site("foot").pos, [g.l3, 0, 0])
    assert np.array_equal(model.site("hip").pos, [0, 0, 0])
    # femur quat = Rx(-pi/2): the modified-DH alpha_2 = -pi/2.
    assert model.body("femur").quat == pytest.approx([math.cos(math.pi / 4), -math.sin(math.pi / 4), 0, 0], abs=1e-15)
    assert (g.l1, g.l2, g.l3) == (LENGTH["coxa"], LENGTH["femur"], LENGTH["tibia"])


def test_joint_ranges_are_the_stated_ones_and_the_scenarios(leg_model):
    """Coxa and femur within +-90 deg, tibia 0..160 deg (knee out only), as the scenario's messages say."""
    model, _ = leg_model
    lower, upper = joint_ranges(model)
    assert np.array_equal(lower, [-math.pi / 2, -math.pi / 2, 0.0])
    assert upper == pytest.approx([math.pi / 2, math.pi / 2, math.radians(160)], abs=1e-15)
    assert all(model.jnt_limited[model.joint(j).id] for j in JOINTS)
    # the scenario's own copy of the ranges (used for its reach)
    assert np.array_equal(leg_parameters.JOINT_LOWER, lower) and np.array_equal(leg_parameters.JOINT_UPPER, upper)


def test_inertials_are_the_stated_rods(leg_model):
    model, _ = leg_model
    for body in BODIES:
        b = model.body(body)
        m, length = MASS[body], LENGTH[body]
        assert b.mass[0] == pytest.approx(m, rel=1e-12), body
        assert b.ipos == pytest.approx([length / 2, 0, 0], abs=1e-15), body
        assert b.iquat == pytest.approx([1, 0, 0, 0], abs=1e-15), body
        i_perp, i_axial = m * length**2 / 12, m * TUBE_RADIUS**2 / 2
        assert b.inertia == pytest.approx([i_axial, i_perp, i_perp], rel=1e-9), body
    for joint in JOINTS:
        assert model.dof_armature[dof(model, joint)] == ARMATURE
        assert model.dof_damping[dof(model, joint)] == 0


def home_mass_matrix(model: mujoco.MjModel) -> np.ndarray:
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    mass = np.zeros((model.nv, model.nv))  # (nv, nv)
    mujoco.mj_fullM(model, data, mass)
    return mass


def test_home_mass_matrix_diagonal_is_the_closed_form(leg_model):
    """M_ii from the stated rods (parallel axis theorem) + armature, and the values the header prints."""
    model, _ = leg_model
    mass = home_mass_matrix(model)
    print("M_ii [kg m^2] at home:", {j: f"{mass[dof(model, j), dof(model, j)]:.6g}" for j in JOINTS})
    _, q2, q3 = model.key("home").qpos
    l1, l2 = LENGTH["coxa"], LENGTH["femur"]
    (mc, mf, mt), (lc, lf, lt) = MASS.values(), LENGTH.values()
    perp = {b: MASS[b] * LENGTH[b] ** 2 / 12 for b in BODIES}
    axial = {b: MASS[b] * TUBE_RADIUS**2 / 2 for b in BODIES}
    s2, c2, s23, c23 = math.sin(q2), math.cos(q2), math.sin(q2 + q3), math.cos(q2 + q3)
    # Coxa axis (vertical): a rod along unit u has I = I_perp + (I_axial - I_perp) (u.z)^2 about a vertical
    # axis through its centre; plus m d^2 with d the horizontal distance of the centre from the axis.
    m11 = (
        ARMATURE
        + perp["coxa"]
        + mc * (lc / 2) ** 2
        + perp["femur"]
        + (axial["femur"] - perp["femur"]) * s2**2
        + mf * (l1 + lf / 2 * c2) ** 2
        + perp["tibia"]
        + (axial["tibia"] - perp["tibia"]) * s23**2
        + mt * (l1 + l2 * c2 + lt / 2 * c23) ** 2
    )
    # Femur axis (horizontal, perpendicular to both rods): tibia centre at |(l2 + lt/2 c3, lt/2 s3)|.
    m22 = ARMATURE + perp["femur"] + mf * (lf / 2) ** 2 + perp["tibia"]
    m22 += mt * (l2**2 + (lt / 2) ** 2 + 2 * l2 * (lt / 2) * math.cos(q3))
    m33 = ARMATURE + perp["tibia"] + mt * (lt / 2) ** 2
    closed = {"coxa": m11, "femur": m22, "tibia": m33}
    found = re.search(r"M_ii \[kg m\^2\]: coxa ([\d.e-]+), femur ([\d.e-]+), tibia ([\d.e-]+)", HEADER)
    stated = dict(zip(JOINTS, map(float, found.groups()), strict=True))
    for j in JOINTS:
        m_ii = mass[dof(model, j), dof(model, j)]
        assert m_ii == pytest.approx(closed[j], rel=1e-12), j
        assert m_ii == pytest.approx(stated[j], rel=1e-5), j  # the header prints 6 significant digits


def test_actuator_gains_follow_from_bandwidth_and_damping_ratio(leg_model):
    model, _ = leg_model
    assert f"f_n = {F_N:g} Hz" in HEADER and f"zeta = {ZETA:g}" in HEADER
    w_n = 2 * math.pi * F_N  # [rad/s]
    mass = home_mass_matrix(model)
    for joint in JOINTS:
        m_ii = mass[dof(model, joint), dof(model, joint)]
        position, velocity = model.actuator(joint), model.actuator(f"{joint}_velocity")
        kp, kv = position.gainprm[0], velocity.gainprm[0]
        assert kp == pytest.approx(m_ii * w_n**2, rel=1e-4), joint
        assert kv == pytest.approx(2 * ZETA * m_ii * w_n, rel=1e-4), joint
        # tau = kp (ctrl - q) and kv (ctrl - dq) on this joint: bias (0, -kp, 0) and (0, 0, -kv).
        assert list(position.biasprm[:3]) == [0, -kp, 0] and list(velocity.biasprm[:3]) == [0, 0, -kv], joint
        for act in (position, velocity):
            assert act.trntype[0] == mujoco.mjtTrn.mjTRN_JOINT and act.trnid[0] == model.joint(joint).id, joint
        assert np.array_equal(position.ctrlrange, model.jnt_range[model.joint(joint).id]), joint


def test_home_keyframe_puts_the_foot_at_the_stated_point(leg_model):
    model, _ = leg_model
    key = model.key("home")
    q = np.array([key.qpos[model.joint(j).qposadr[0]] for j in JOINTS])
    lower, upper = joint_ranges(model)
    assert np.all((lower <= q) & (q <= upper))
    assert leg.fk(q, GEOMETRY) == pytest.approx(HOME_FOOT, abs=1e-12)
    assert min(np.max(np.abs(q - b)) for b in leg.ik(HOME_FOOT, GEOMETRY)) <= 1e-12
    assert q[2] > 0  # the knee-out branch the header names
    # ctrl holds q_cmd = q on the position servos and zero velocity feedforward.
    for joint, value in zip(JOINTS, q, strict=True):
        assert key.ctrl[model.actuator(joint).id] == value
        assert key.ctrl[model.actuator(f"{joint}_velocity").id] == 0


def potential_energy(model: mujoco.MjModel, data: mujoco.MjData, q: np.ndarray) -> float:
    """-sum m_b g . c_b over the bodies [J], from MuJoCo's body centres of mass."""
    set_q(model, data, q)
    return -float(np.sum(model.body_mass[:, None] * data.xipos * model.opt.gravity))


def released_at_home(gravcomp: bool) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """The leg at the home pose, at rest, with zero actuator torque."""
    model, data = load()
    model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_ACTUATION
    if not gravcomp:
        model.body_gravcomp[:] = 0
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    return model, data


def test_gravity_compensation_holds_the_leg_at_rest():
    model, data = released_at_home(gravcomp=True)
    assert all(model.body_gravcomp[model.body(b).id] == 1 for b in BODIES)
    assert np.max(np.abs(data.qacc)) < 1e-9
    q0 = data.qpos.copy()
    for _ in range(1000):
        mujoco.mj_step(model, data)
    assert np.max(np.abs(data.qpos - q0)) < 1e-9 and np.max(np.abs(data.qvel)) < 1e-9


def test_without_gravity_compensation_the_leg_falls_as_the_potential_says():
    model, data = released_at_home(gravcomp=False)
    q0 = np.array([data.qpos[model.joint(j).qposadr[0]] for j in JOINTS])
    qacc = np.array([data.qacc[dof(model, j)] for j in JOINTS])
    # Generalised gravity force by central differences of the potential energy: independent of MuJoCo's RNE.
    h = 1e-6
    scratch = mujoco.MjData(model)
    tau_g = np.array(
        [
            -(potential_energy(model, scratch, q0 + h * e) - potential_energy(model, scratch, q0 - h * e)) / (2 * h)
            for e in np.eye(3)
        ]
    )
    mass = home_mass_matrix(model)
    cols = [dof(model, j) for j in JOINTS]
    assert qacc == pytest.approx(np.linalg.solve(mass[np.ix_(cols, cols)], tau_g), rel=1e-6)
    # At home the femur points 24 deg below horizontal and the centre of mass of femur + tibia lies
    # outboard of the femur axis, so gravity turns the femur down: positive q2 lowers the foot.
    assert qacc[0] == pytest.approx(0, abs=1e-12)  # the coxa axis is vertical: gravity has no moment about it
    assert qacc[1] > 1.0  # [rad/s^2]
    for _ in range(100):
        mujoco.mj_step(model, data)
    set_q(model, scratch, q0)
    foot_start = scratch.site("foot").xpos[2]
    assert data.site("foot").xpos[2] < foot_start - 1e-4  # the foot has dropped


def test_the_leg_never_touches_the_floor_and_has_no_contacts():
    model, data = load("leg_scene")
    floor = model.geom("floor").id
    assert model.geom_type[floor] == mujoco.mjtGeom.mjGEOM_PLANE
    assert np.array_equal(model.geom_pos[floor], [0, 0, 0])
    assert np.all(model.geom_contype == 0) and np.all(model.geom_conaffinity == 0)
    foot_radius = model.geom_size[model.geom("foot").id, 0]
    moving = [g for g in range(model.ngeom) if model.body(model.geom_bodyid[g]).name in BODIES]
    lower, upper = joint_ranges(model)
    lowest_foot, lowest_any = math.inf, math.inf
    for q in np.random.default_rng(11).uniform(lower, upper, size=(N, 3)):
        set_q(model, data, q)
        mujoco.mj_forward(model, data)
        assert data.ncon == 0
        lowest_foot = min(lowest_foot, data.site("foot").xpos[2] - foot_radius)
        # Bounding sphere of every moving geom: a conservative lowest point.
        lowest_any = min(lowest_any, float(np.min(data.geom_xpos[moving, 2] - model.geom_rbound[moving])))
    assert lowest_foot > 0
    assert lowest_any > 0
    # The stretched leg pointing straight down (q2 = +90 deg, in range) is the lowest the foot can get.
    set_q(model, data, np.array([0.0, math.pi / 2, 0.0]))
    assert data.site("foot").xpos[2] == pytest.approx(0.3 - LENGTH["femur"] - LENGTH["tibia"], abs=1e-12)
