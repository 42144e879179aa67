"""The walking hexabot: model vs the leg's DH maths, contact, gait timing, tracking, drift, perturbations, CLI."""

import json
import math

import mujoco
import numpy as np
import pytest
from helpers import foot_and_jacobian_errors, walk

from hexabot_sim import models, params
from hexabot_sim.__main__ import main
from hexabot_sim.control.gait import GAITS, Command, GaitPlanner
from hexabot_sim.kinematics import leg as leg_kin
from hexabot_sim.robots.hexabot import model as hexabot_mjcf
from hexabot_sim.robots.hexabot import model as hx
from hexabot_sim.robots.hexabot.walk import HexabotParams
from hexabot_sim.walking import constants as walking_constants
from hexabot_sim.walking import ground as walking_ground
from hexabot_sim.walking import parameters as hexabot_parameters
from hexabot_sim.walking.perturb import perturbations

LEGS = hx.LEGS


# --- the model -------------------------------------------------------------------------------------


def test_committed_models_are_the_generator_output():
    assert models.model_path("hexabot").read_text() == hexabot_mjcf.robot_xml()
    assert models.model_path("hexabot_scene").read_text() == hexabot_mjcf.scene_xml()


def test_names_masses_limits_and_collisions():
    model = mujoco.MjModel.from_xml_path(str(models.model_path("hexabot_scene")))
    assert model.joint("root").type == mujoco.mjtJoint.mjJNT_FREE
    for leg in LEGS:
        for joint in hx.JOINTS:
            assert model.joint(f"{leg}_{joint}").type == mujoco.mjtJoint.mjJNT_HINGE
            assert tuple(model.jnt_actfrcrange[model.joint(f"{leg}_{joint}").id]) == (-1.5, 1.5)
        model.site(f"{leg}_hip"), model.site(f"{leg}_foot")
    total = model.body_subtreemass[model.body("torso").id]
    assert 1.0 <= total <= 2.5
    assert model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
    # Only the feet and the plate can touch the floor; no leg link touches anything.
    floor = model.geom("floor").id
    touching = {
        model.geom(g).name
        for g in range(model.ngeom)
        if g != floor
        and (
            model.geom_contype[g] & model.geom_conaffinity[floor]
            or model.geom_contype[floor] & model.geom_conaffinity[g]
        )
    }
    assert touching == {"torso", *(f"{leg}_foot" for leg in LEGS)}
    for g in range(model.ngeom):  # and nothing of the robot touches itself
        for h in range(model.ngeom):
            if floor not in (g, h):
                assert not (model.geom_contype[g] & model.geom_conaffinity[h])


def test_every_foot_and_jacobian_equal_the_legs_dh_maths():
    """Foot sites and mj_jacSite against the leg's analytic FK and Jacobian, rotated onto each hip."""
    worst_p, worst_j = foot_and_jacobian_errors("hexabot_scene", hx.DEFAULT_LAYOUT, 100)
    assert worst_p < 1e-12 and worst_j < 1e-12


def test_servo_gains_use_the_legs_joint_space_inertia():
    """The leg part of loaded_joint_inertia equals MuJoCo's mass-matrix diagonal (mj_fullM)."""
    model = mujoco.MjModel.from_xml_path(str(models.model_path("hexabot_scene")))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    layout = hx.DEFAULT_LAYOUT
    q0 = model.key("home").qpos[7:10]
    ours = hexabot_mjcf.loaded_joint_inertia(layout, q0)
    _, jac = leg_kin.foot_and_jacobian(*q0, layout.geometry.l1, layout.geometry.l2, layout.geometry.l3)
    body_share = layout.total_mass / hexabot_mjcf.STANCE_LEGS * np.sum(np.array(jac) ** 2, axis=0)
    np.testing.assert_allclose(ours - body_share, np.diag(full)[6:9], rtol=1e-10)
    inertia, _kp, _kv = hexabot_mjcf.servo_gains(layout)
    w = 2 * math.pi * hexabot_mjcf.SERVO_BANDWIDTH_HZ
    np.testing.assert_allclose(model.actuator_gainprm[:3, 0], np.round(inertia * w**2, 4), rtol=1e-12)


def test_standing_contact_sinks_little_and_does_not_slide():
    model = mujoco.MjModel.from_xml_path(str(models.model_path("hexabot_scene")))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    warnings = []
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(warnings.append)
    try:
        for _ in range(1000):
            mujoco.mj_step(model, data)
    finally:
        mujoco.set_mju_user_warning(previous)
    assert warnings == [] and all(w.number == 0 for w in data.warning)
    assert data.ncon == 6
    depth = -np.array([data.contact[i].dist for i in range(data.ncon)])
    assert (depth > 0).all() and depth.max() < 0.3e-3  # MuJoCo's defaults would let it sink ~0.5 mm
    force = np.zeros(6)
    total = 0.0
    for i in range(data.ncon):
        mujoco.mj_contactForce(model, data, i, force)
        total += force[0]
    weight = model.body_subtreemass[model.body("torso").id] * 9.81
    assert total == pytest.approx(weight, rel=1e-3)  # static equilibrium
    assert np.abs(data.qvel).max() < 1e-4


# --- the gait generator and planner ---------------------------------------------------------------


def test_gait_tables_keep_the_robot_supported():
    for gait in GAITS.values():
        phases = np.mod(np.linspace(0, 1, 601)[:, None] + np.array(gait.offsets), 1.0)
        down = phases < gait.duty
        assert down.sum(axis=1).min() >= 3, gait.name  # never fewer than three feet on the ground
        assert down.mean() == pytest.approx(gait.duty, abs=0.01)
        # Each side keeps a foot down at all times (no side unsupported).
        assert down[:, :3].any(axis=1).all() and down[:, 3:].any(axis=1).all()


def test_foot_pitch_is_q2_plus_q3_of_the_inverse_kinematics():
    layout = hx.DEFAULT_LAYOUT
    rng = np.random.default_rng(1)
    points = rng.uniform([-0.05, -0.2, -0.17], [0.25, 0.2, -0.03], size=(5000, 3))
    q, ok = hx.ik_hip_batch(layout, points)
    assert ok.sum() > 1000
    np.testing.assert_allclose(hx.foot_pitch(layout, points)[ok], (q[:, 1] + q[:, 2])[ok], atol=1e-12)


@pytest.mark.parametrize("cmd", [Command(0.1, 0.0, 0.0), Command(0.05, -0.05, 0.3)])
def test_planned_stance_moves_with_the_ramped_command_and_targets_stay_smooth(cmd):
    """Chunk by chunk, with the command ramping inside the chunks: every stance target moves at the
    ground-fixed velocity -s(t) (v + w x p) (the body twist scaled by the ramp, by finite differences),
    and chunk boundaries leave no mark (the same walk planned in other chunks is the same)."""
    dt, settle, ramp_time = 0.002, 0.5, 1.0
    planner = GaitPlanner(GAITS["tripod"], 1.0, 0.03, walking_ground.neutral(params.resolve(HexabotParams, {}, {})),
                          dt, start_time=settle)  # fmt: skip

    def scale(t):
        return np.clip((np.asarray(t) - settle) / ramp_time, 0.0, 1.0)

    chunks = [planner.plan(cmd, 250, scale) for _ in range(8)]  # 2 s: settle, ramp, walk
    rows = np.concatenate([chunks[0]] + [c[1:] for c in chunks[1:]])  # (n + 1, 6, 3)
    t = dt * np.arange(len(rows))
    stance = planner.in_stance(t)
    # Mean velocity over each step vs the analytic one at the step's midpoint, where the foot is in
    # stance at both ends (and the ramp's factor, which enters linearly).
    mid = 0.5 * (rows[1:] + rows[:-1])
    s_mid = scale(t[:-1] + 0.5 * dt)[:, None]
    expected = (
        np.stack([-cmd.vx + cmd.yaw_rate * mid[..., 1], -cmd.vy - cmd.yaw_rate * mid[..., 0]], -1) * s_mid[..., None]
    )
    measured = np.diff(rows[..., :2], axis=0) / dt
    both = stance[1:] & stance[:-1]
    assert both.mean() > 0.5
    np.testing.assert_allclose(measured[both], expected[both], atol=1e-6)  # [m/s]
    # Chunking changes nothing: the same 2 s planned in chunks of 100 steps (boundaries elsewhere).
    again = GaitPlanner(planner.gait, 1.0, 0.03, planner.neutral, dt, start_time=settle)
    small = [again.plan(cmd, 100, scale) for _ in range(20)]
    np.testing.assert_allclose(np.concatenate([small[0]] + [c[1:] for c in small[1:]]), rows, atol=1e-12)
    # No jumps: the targets' acceleration stays that of the swing arcs (~6 stride / swing time^2).
    assert np.abs(np.diff(measured, axis=0)).max() / dt < 3.0  # [m/s^2]


def test_stance_plane_fit_is_least_squares_and_refuses_collinear_feet():
    from hexabot_sim.control.walker import fit_plane

    rng = np.random.default_rng(3)
    for n in (3, 4, 5, 6):
        xy = rng.uniform(-0.2, 0.2, (n, 2))
        z = rng.uniform(-0.12, -0.06, n)
        expected = np.linalg.lstsq(np.c_[np.ones(n), xy], z, rcond=None)[0]
        np.testing.assert_allclose(fit_plane([tuple(p) for p in xy], list(z)), expected, atol=1e-12)
    assert fit_plane([(0.0, 0.0), (0.1, 0.1), (0.2, 0.2)], [-0.1, -0.1, -0.1]) is None
    assert fit_plane([(0.0, 0.0), (0.1, 0.0)], [-0.1, -0.1]) is None


# --- walking --------------------------------------------------------------------------------------


def test_command_columns_show_the_settle_and_the_ramp():
    result = walk(vx=0.1, vy=0.05, duration=2.0, period=1.0)
    t = result.columns["t"]
    factor = np.clip((t - walking_constants.SETTLE_TIME) / 1.0, 0.0, 1.0)  # the ramp lasts one gait period
    np.testing.assert_allclose(result.columns["cmd_vx"], 0.1 * factor, atol=1e-12)
    np.testing.assert_allclose(result.columns["cmd_vy"], 0.05 * factor, atol=1e-12)
    assert not result.columns["cmd_yaw_rate"].any()


@pytest.fixture(scope="module")
def forward_walk():
    """6 m on flat ground at 0.15 m/s, the symmetric robot (the drift test needs the distance)."""
    return walk(vx=0.15, duration=45.0)


@pytest.mark.slow
def test_flat_ground_drift_slip_sag_attitude(forward_walk):
    m = forward_walk.metrics
    assert m["distance"].value >= 6.0
    assert abs(m["lateral_drift"].value) <= 2.0  # mm per metre
    assert abs(m["heading_drift"].value) <= 0.1  # deg per metre
    assert m["slip_per_stance"].value <= 1.0  # mm
    assert abs(m["body_height_sag"].value) <= 0.002
    assert m["roll_ptp"].value <= 1.0 and m["pitch_ptp"].value <= 1.0
    assert abs(m["vx_error"].value) <= 0.02
    assert m["fell"].value is False
    assert m["peak_joint_torque"].value <= 1.5 + 1e-9


def test_gait_timing_matches_the_plan(forward_walk):
    """Which feet carry load when: the measured contacts follow the planned stance phases."""
    result = forward_walk
    window = result.extras["window"]
    measured = np.stack([result.columns[f"contact_{leg}"] for leg in LEGS], axis=1)[window] > 0.5
    planned = result.extras["planned_stance"][window]
    assert (measured == planned).mean() > 0.95
    # A planned swing never carries load in its middle half (no foot drags through its swing).
    phase = np.mod(
        (result.columns["t"][window, None] - walking_constants.SETTLE_TIME) + np.array(GAITS["tripod"].offsets), 1.0
    )
    mid_swing = (phase > 0.625) & (phase < 0.875)
    assert not (measured & mid_swing).any()


@pytest.mark.slow
@pytest.mark.parametrize(
    ("overrides", "tolerance"),
    [
        ({"vx": 0.05}, 0.02),
        ({"vx": 0.15}, 0.02),
        ({"vx": 0.0, "vy": 0.1}, 0.02),
        ({"vx": 0.1, "vy": -0.1}, 0.02),
        ({"vx": -0.1}, 0.02),
        ({"vx": 0.3, "period": 0.7}, 0.05),
        ({"vx": 0.1, "gait": "ripple"}, 0.02),
        ({"vx": 0.05, "gait": "wave"}, 0.02),
        ({"vx": 0.0, "yaw_rate": 0.3}, 0.02),
        ({"vx": 0.1, "yaw_rate": -0.2}, 0.02),
    ],
)
def test_speed_and_yaw_rate_tracking(overrides, tolerance):
    m = walk(duration=8.5, **overrides).metrics
    for key, error in (("vx", "vx_error"), ("vy", "vy_error"), ("yaw_rate", "yaw_rate_error")):
        commanded = overrides.get(key, 0.1 if key == "vx" else 0.0)
        if commanded:
            assert abs(m[error].value) <= tolerance, (key, m[error].value)
        else:
            measured = {"vx": "mean_vx", "vy": "mean_vy", "yaw_rate": "mean_yaw_rate"}[key]
            assert abs(m[measured].value) <= 0.003, (key, m[measured].value)
    assert m["fell"].value is False


@pytest.mark.slow
@pytest.mark.parametrize(
    "overrides",
    [
        {"gait": "tripod", "vx": 0.25, "friction": 0.3, "timestep": 0.002},
        {"gait": "tripod", "vx": 0.05, "friction": 0.3, "timestep": 0.001},
        {"gait": "ripple", "vx": 0.2, "friction": 0.3, "timestep": 0.002},
        {"gait": "wave", "vx": 0.05, "friction": 0.3, "timestep": 0.002},
        {"gait": "wave", "vx": 0.1, "friction": 0.3, "timestep": 0.001, "period": 1.5},
    ],
)
def test_no_fall_low_friction_and_timesteps(overrides):
    m = walk(duration=6.0, **overrides).metrics
    assert m["fell"].value is False
    assert abs(m["vx_error"].value) <= 0.05


@pytest.mark.slow
def test_heading_hold_removes_the_drift_of_an_imperfect_robot():
    """+-1 deg servo trims, 1 cm CoM offset, +-20 % friction: heading hold keeps the path straight."""
    perturbed = {"vx": 0.15, "duration": 25.0, "trim_error_deg": 1.0, "com_offset": 0.01, "friction_spread": 0.2}
    held = walk(heading_hold="on", **perturbed).metrics
    free = walk(heading_hold="off", **perturbed).metrics
    assert abs(held["lateral_drift"].value) <= 10.0  # mm per metre
    assert abs(held["heading_drift"].value) <= 0.1  # deg per metre
    assert abs(free["heading_drift"].value) > 5 * abs(held["heading_drift"].value)  # why heading hold exists


@pytest.mark.slow
@pytest.mark.parametrize("overrides", [{"vy": 0.1}, {"vx": 0.0, "vy": -0.1}, {"vx": 0.1, "yaw_rate": 0.1}])
def test_heading_hold_on_a_symmetric_robot_walks_every_direction(overrides):
    """Heading hold asks for yaw-rate corrections as small as 1e-19 rad/s at the start: the plan stays sane."""
    m = walk(heading_hold="on", duration=12.0, **overrides).metrics
    assert m["fell"].value is False
    for axis in ("vx", "vy"):
        if overrides.get(axis, 0.1 if axis == "vx" else 0.0):
            assert abs(m[f"{axis}_error"].value) <= 0.02
    if "yaw_rate" in overrides:
        assert abs(m["yaw_rate_error"].value) <= 0.02
    else:
        assert abs(m["lateral_drift"].value) <= 2.0 and abs(m["heading_drift"].value) <= 0.1


@pytest.mark.parametrize("w", [0.3, -1.2, 1e-19, 5e-324, -5e-324, 0.0])
def test_stance_path_solves_the_ground_fixed_point_ode(w):
    """p' = -v - w x p against a high-accuracy ODE solve, including yaw rates far below rounding."""
    from scipy.integrate import solve_ivp

    from hexabot_sim.control.gait import stance_path

    cmd = Command(0.1, -0.07, w)
    start = np.array([[0.12, 0.2], [-0.1, -0.15]])
    tau = np.array([-0.5, -0.1, 0.25, 1.0])
    got = stance_path(cmd, start, tau)  # (2, 4, 2)
    for i, p0 in enumerate(start):
        for k, end in enumerate(tau):
            sol = solve_ivp(
                lambda _t, p: [-cmd.vx + w * p[1], -cmd.vy - w * p[0]], (0.0, end), p0, rtol=1e-12, atol=1e-14
            )
            np.testing.assert_allclose(got[i, k], sol.y[:, -1], atol=1e-10)


def test_a_yaw_rate_that_underflows_walks_straight():
    """w = 5e-324 (the smallest float): w tau underflows to 0, and the walk is the straight one (it stood still)."""
    tiny = walk(yaw_rate=5e-324, duration=4.0).metrics
    assert abs(tiny["vx_error"].value) <= 0.02
    assert tiny["mean_vx"].value == pytest.approx(walk(duration=4.0).metrics["mean_vx"].value, rel=1e-6)


def test_perturbations_are_seeded():
    a = perturbations(params.resolve(HexabotParams, {}, {"trim_error_deg": 1, "seed": 3}))
    b = perturbations(params.resolve(HexabotParams, {}, {"trim_error_deg": 1, "seed": 3}))
    c = perturbations(params.resolve(HexabotParams, {}, {"trim_error_deg": 1, "seed": 4}))
    assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    assert not np.array_equal(a[0], c[0])
    assert np.abs(a[0]).max() <= math.radians(1.0)


# --- the run folder and metrics recomputed independently ---------------------------------------------


@pytest.mark.slow
def test_cli_run_folder_and_metrics_recomputed_from_the_trajectory(tmp_path, capsys):
    out = tmp_path / "walk"
    code = main(["run", "hexabot-walk", "--set", "duration=6", "--out", str(out)])
    _, err = capsys.readouterr()
    assert code == 0, err
    record = json.loads((out / "run.json").read_text())
    names = {p.name for p in out.iterdir()}
    assert {"run.json", "model.xml", "timeseries.csv", "trajectory.npz", "path.png", "gait_diagram.png"} <= names
    assert {"velocity.png", "body.png", "slip.png"} <= names
    header = (out / "timeseries.csv").read_text().splitlines()[0].split(",")
    assert header[:7] == ["t", "x", "y", "z", "roll", "pitch", "yaw"]
    assert len(header) == hexabot_parameters.csv_columns(HexabotParams().ROBOT)  # the run-cost estimate counts these
    assert {f"contact_{leg}" for leg in LEGS} <= set(header)
    assert {f"q_{leg}_{j}" for leg in LEGS for j in hx.JOINTS} <= set(header)

    # Recompute from model.xml + trajectory.npz alone, by other means than the scenario's code.
    model = mujoco.MjModel.from_xml_path(str(out / "model.xml"))
    data = mujoco.MjData(model)
    traj = np.load(out / "trajectory.npz")
    t, qpos, qvel, ctrl = traj["t"], traj["qpos"], traj["qvel"], traj["ctrl"]
    assert ctrl.shape == (len(t), 36)
    metrics = record["metrics"]
    period, settle = record["params"]["period"], walking_constants.SETTLE_TIME
    cycles = math.floor((t[-1] - settle - 2 * period) / period + 1e-9)
    i0 = np.searchsorted(t, settle + 2 * period - 1e-9)
    i1 = np.searchsorted(t, settle + (2 + cycles) * period - 1e-9)
    # Mean forward speed: displacement along the (nearly constant) heading over whole cycles.
    yaw = np.array([math.atan2(2 * (q[0] * q[3] + q[1] * q[2]), 1 - 2 * (q[2] ** 2 + q[3] ** 2)) for q in qpos[:, 3:7]])
    heading = yaw[i0:i1].mean()
    disp = qpos[i1, :2] - qpos[i0, :2]
    vx = (disp[0] * math.cos(heading) + disp[1] * math.sin(heading)) / (t[i1] - t[i0])
    assert vx == pytest.approx(metrics["mean_vx"], rel=2e-3)
    assert metrics["distance"] == pytest.approx(float(np.hypot(*disp)), rel=1e-9)
    assert metrics["body_height_mean"] == pytest.approx(qpos[i0 : i1 + 1, 2].mean(), rel=1e-6)
    # Slip: the foot's material-point velocity from the foot site's 6-D velocity (mj_objectVelocity).
    weight = model.body_subtreemass[model.body("torso").id] * 9.81
    slips, loads = [], []
    foot_slip, foot_load = np.zeros((i1 + 1 - i0, 6)), np.zeros((i1 + 1 - i0, 6))  # per row and foot
    force, vel = np.zeros(6), np.zeros(6)
    for k in range(i0, i1 + 1):
        data.qpos[:], data.qvel[:], data.ctrl[:] = qpos[k], qvel[k], ctrl[min(k + 1, len(t) - 1)]
        mujoco.mj_forward(model, data)
        for c in range(data.ncon):
            contact = data.contact[c]
            name = (
                model.geom(contact.geom2).name
                if model.geom(contact.geom2).name.endswith("_foot")
                else model.geom(contact.geom1).name
            )
            if not name.endswith("_foot"):
                continue
            mujoco.mj_contactForce(model, data, c, force)
            site = model.site(name).id
            mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_SITE, site, vel, 0)  # world frame
            v = vel[3:] + np.cross(vel[:3], contact.pos - data.site_xpos[site])
            slips.append(math.hypot(v[0], v[1]))
            loads.append(force[0])
            foot_slip[k - i0, LEGS.index(name[:2])] = slips[-1]
            foot_load[k - i0, LEGS.index(name[:2])] += force[0]
    slips, loads = np.array(slips), np.array(loads)
    loaded = loads > walking_constants.LOADED_FRACTION * weight / 6
    assert slips[loaded].mean() == pytest.approx(metrics["slip_mean"], rel=1e-6)
    # Slip per stance: the loaded feet's sliding distance over the stances of the gait plan in the window (its
    # touchdowns, from the legs' phases); a foot that bounces does not make more stances.
    planned = GaitPlanner(GAITS["tripod"], period, 0.03, np.zeros((6, 3)), 0.002, start_time=settle)
    stance = planned.in_stance(t[i0 : i1 + 1])
    touchdowns = int((np.diff(stance.astype(int), axis=0) == 1).sum())
    distance = (foot_slip * (foot_load > walking_constants.LOADED_FRACTION * weight / 6)).sum() * (t[1] - t[0])
    assert metrics["slip_per_stance"] == pytest.approx(distance / touchdowns * 1000, rel=1 / touchdowns)
    assert metrics["fell"] is False and qpos[:, 2].min() > 0.05
    assert record["units"]["metrics"]["lateral_drift"] == "mm/m"


@pytest.mark.slow
def test_rolling_feet_correction_is_what_makes_the_speed_right(monkeypatch):
    """A sphere foot rolling without slip moves its centre by r dtheta: uncorrected, the body runs ~3 % fast."""
    from hexabot_sim.control import walker as control

    corrected = walk(vx=0.1, duration=8.5).metrics
    original = control.WalkingController.__init__

    def without_rolling(self, *args, **kwargs):
        original(self, *args, **kwargs)
        self.foot_radius = 0.0  # plan as if the foot were a point

    monkeypatch.setattr(control.WalkingController, "__init__", without_rolling)
    uncorrected = walk(vx=0.1, duration=8.5).metrics
    assert abs(corrected["vx_error"].value) < 0.005
    assert uncorrected["vx_error"].value > 0.015  # r = 8 mm times the foot's pitch change per stance
    assert uncorrected["slip_per_stance"].value > 2 * corrected["slip_per_stance"].value
