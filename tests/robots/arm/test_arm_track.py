"""arm-track: any arm tracks a path in MuJoCo; the tracking error is measured from MuJoCo's own tool site."""

import math
import pickle
from pathlib import Path

import mujoco
import numpy as np
import pytest
from helpers import cli

import hexabot_sim as hs
from hexabot_sim import api, models, params
from hexabot_sim.errors import UsageError
from hexabot_sim.robots.arm import track
from hexabot_sim.robots.arm.path import RAMP_TIME
from hexabot_sim.robots.arm.path import Path as TaskPath

# A 7-DOF arm (a KUKA LBR iiwa-like DH table: d = 0.36, 0.42, 0.4, 0.126 m), written as a user would.
SEVEN = [
    (0.36, -90, 170),
    (0.0, 90, 120),
    (0.42, 90, 170),
    (0.0, -90, 120),
    (0.4, -90, 170),
    (0.0, 90, 120),
    (0.126, 0, 175),
]
TARGET_RMS = 1e-3  # [m] issue 20: a 10 cm circle at 0.1 m/s within 1 mm RMS


def robot_file(folder: Path, rows=SEVEN, name: str = "arm7", extra: str = "") -> Path:
    lines = [f'name = "{name}"', 'convention = "standard"', 'angles = "deg"', ""]
    for i, (d, alpha, limit) in enumerate(rows, start=1):
        lines += [
            "[[joints]]",
            f'name = "q{i}"',
            'type = "revolute"',
            "a = 0.0",
            f"alpha = {alpha}.0",
            f"d = {d}",
            "theta = 0.0",
            f"lower = {-limit}.0",
            f"upper = {limit}.0",
            extra,
            "",
        ]
    path = folder / f"{name}.toml"
    path.write_text("\n".join(lines))
    return path


def short(robot, **overrides):
    """A circle of 10 cm at 0.1 m/s: the ramp and a third of the circle."""
    return hs.run("arm-track", robot=str(robot), duration=1.5, **overrides)


@pytest.mark.parametrize("robot", ["scara", "elbow"])
def test_circle_within_1_mm_rms_and_the_jacobian_check(robot):
    result = short(robot)
    m = result.metrics
    assert m["tracking_error_rms"].value < TARGET_RMS
    assert m["tracking_error_max"].value < 2 * TARGET_RMS
    assert m["jacobian_max_diff"].value < 1e-12  # analytic J against mj_jacSite at every control period
    assert m["fk_max_diff"].value < 1e-12  # our FK of MuJoCo's qpos is its tool site: qpos = DH q
    assert m["sigma_min"].value > 0.1 and m["joint_limit_hits"].value == 0
    # The error column is MuJoCo's tool site against the path, recomputed here from the columns.
    c = result.columns
    tool = np.stack([c["x"], c["y"], c["z"]], axis=1)
    path = TaskPath("circle", 0.1, 0.1, np.array(m["centre"].value), (np.eye(3)[0], np.eye(3)[1]))
    desired, _ = path.at(c["t"])
    assert np.allclose(np.linalg.norm(tool - desired, axis=1), c["error"], atol=1e-15)
    assert m["orientation_error_max"].value is None  # position only below 6 joints


def test_a_seven_dof_file_tracks_the_circle_and_holds_the_tool_orientation(tmp_path):
    result = hs.run("arm-track", robot=robot_file(tmp_path), duration=1.5)  # a Path from Python
    assert result.params["robot"] == str(tmp_path / "arm7.toml")
    m = result.metrics
    assert m["joints"].value == 7
    assert m["tracking_error_rms"].value < TARGET_RMS
    assert m["orientation_error_max"].value < 1e-3  # [rad]
    assert m["jacobian_max_diff"].value < 1e-12


def test_the_jacobian_check_catches_a_wrong_jacobian(monkeypatch):
    """The in-run check compares with MuJoCo: a Jacobian off by 1e-6 in one entry is reported as such."""
    real = track.pose_and_jacobian

    def wrong(chain):
        evaluate = real(chain)

        def perturbed(q):
            pose, jac = evaluate(q)
            jac = jac.copy()
            jac[4, 1] += 1e-6
            return pose, jac

        return perturbed

    monkeypatch.setattr(track, "pose_and_jacobian", wrong)
    p = params.resolve(track.ArmTrackParams, {}, {"robot": "elbow", "duration": 0.05})
    assert track.run("arm-track", p).metrics["jacobian_max_diff"].value == pytest.approx(1e-6, rel=1e-6)


def test_the_robot_file_is_read_once_when_the_parameters_are_made(tmp_path):
    """A run uses the version of its robot file that was checked: removed (or edited) after its parameters were made,
    the run goes on as checked (it used to read the file again at run time: a FileNotFoundError from os.stat)."""
    path = robot_file(tmp_path)
    prepared = api.prepare("arm-track", {"robot": str(path), "duration": 1.5})
    path.unlink()
    result = prepared.run()
    assert result.metrics["joints"].value == 7
    assert result.metrics["tracking_error_rms"].value < TARGET_RMS
    path.write_text(path.name)  # now not a robot file at all
    assert prepared.run().metrics["tracking_error_rms"].value == result.metrics["tracking_error_rms"].value
    # Pickled (a sweep's worker gets its parameters so), the checked version travels with them.
    again = api.Prepared(prepared.entry, pickle.loads(pickle.dumps(prepared.params)))
    assert again.run().metrics["tracking_error_rms"].value == result.metrics["tracking_error_rms"].value


def test_gravity_acts_and_the_feedforward_is_the_gravity_torque():
    """No gravcomp: the feedforward at rest is the gravity torque, dV/dq of the links' potential energy (central
    differences of MuJoCo's body centres of mass and masses, not its qfrc_bias)."""
    p = params.resolve(track.ArmTrackParams, {}, {"robot": "stanford", "duration": 0.01})
    loop = track.prepare(p)
    model = loop.model
    assert np.all(model.body_gravcomp == 0) and model.opt.gravity[2] == pytest.approx(-9.81)
    data = mujoco.MjData(model)

    def potential(q):
        data.qpos[loop.qadr] = q
        mujoco.mj_kinematics(model, data)
        return -float(np.sum(model.body_mass * (data.xipos @ model.opt.gravity)))

    q0, h = loop.plan.q_start, 1e-6
    grad = [(potential(q0 + h * e) - potential(q0 - h * e)) / (2 * h) for e in np.eye(len(q0))]
    bias = [model.actuator(f"{name}_bias").id for name in loop.names]
    assert np.allclose(loop.data.ctrl[bias], grad, atol=1e-6)


def test_servo_gains_come_from_the_mass_matrix():
    p = params.resolve(track.ArmTrackParams, {}, {"robot": "scara", "duration": 0.01, "servo_bandwidth": 7.0})
    loop = track.prepare(p)
    model, data = loop.model, mujoco.MjData(loop.model)
    data.qpos[loop.qadr] = loop.plan.q_start
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    omega = 2 * math.pi * 7.0
    for name, dof in zip(loop.names, loop.dadr, strict=True):
        assert model.actuator(name).gainprm[0] == pytest.approx(full[dof, dof] * omega**2, rel=1e-12)
        assert model.actuator(f"{name}_velocity").gainprm[0] == pytest.approx(2 * full[dof, dof] * omega, rel=1e-12)


@pytest.mark.parametrize("kind", ["circle", "line", "figure8"])
def test_paths_velocity_is_the_derivative_and_the_peak_speed_is_speed(kind):
    path = TaskPath(kind, 0.1, 0.1, np.array([0.1, 0.2, 0.3]), (np.eye(3)[0], np.eye(3)[2]))
    t = np.linspace(0, RAMP_TIME + path.period, 20001)
    pos, vel = path.at(t)
    h = 1e-6
    numeric = (path.at(t + h)[0] - path.at(t - h)[0]) / (2 * h)
    assert np.allclose(vel, numeric, atol=1e-8)
    assert np.linalg.norm(vel, axis=1).max() == pytest.approx(0.1, rel=1e-6)
    assert np.allclose(pos[:, 1], 0.2)  # in the xz plane
    assert np.linalg.norm(vel[0]) == 0  # from rest
    if kind == "circle":
        assert np.allclose(np.linalg.norm(pos - path.centre, axis=1), 0.05)


def test_same_inputs_give_the_same_run():
    first, second = (hs.run("arm-track", robot="scara", path="figure8", duration=0.2) for _ in range(2))
    assert all(np.array_equal(first.columns[k], second.columns[k]) for k in first.columns)


@pytest.mark.slow
def test_a_sweep_over_robots_by_name_and_file(capsys, tmp_path):
    path = robot_file(tmp_path)
    out = tmp_path / "sweep"
    code, _, err = cli(capsys, "sweep", "arm-track", "--grid", f"robot=elbow,{path}", "--set", "duration=0.3",
                       "--out", str(out), "--workers", "1", "--no-plots")  # fmt: skip
    assert code == 0, err
    rows = (out / "sweep.csv").read_text().splitlines()
    assert rows[1].startswith("elbow,") and rows[2].startswith(f"{path},") and len(rows) == 3


def test_the_run_model_passes_the_replay_check(tmp_path):
    result = hs.run("arm-track", robot="elbow", duration=0.05)
    path = tmp_path / "model.xml"
    path.write_text(result.raw.model_xml)
    assert models.read_run_model(path) == result.raw.model_xml


def test_live_steps_the_controller():
    live = track.live(params.resolve(track.ArmTrackParams, {}, {"robot": "scara", "duration": 0.05}))
    start = live.data.site("tool").xpos.copy()
    for _ in range(100):  # past the end of the run: the viewer keeps stepping
        live.step()
    assert live.data.time == pytest.approx(0.1) and np.isfinite(live.data.qpos).all()
    assert 0 < np.linalg.norm(live.data.site("tool").xpos - start) < 0.01


# --- refusals: one line, exit 2, before the run, nothing written -------------------------------------------------


def refused(capsys, tmp_path, *sets):
    out = tmp_path / "out"
    code, _, err = cli(capsys, "run", "arm-track", *[a for s in sets for a in ("--set", s)], "--out", str(out))
    assert code == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert not out.exists()
    return err.strip()


def test_bad_robot_name(capsys, tmp_path):
    err = refused(capsys, tmp_path, "robot=stanfrod")
    assert "parameter 'robot' must be one of rrp, elbow, stanford, scara, leg, or the path of a robot file" in err
    assert "'stanfrod' (no such name or file)" in err


def test_bad_robot_file_names_the_file_joint_and_field(capsys, tmp_path):
    path = robot_file(tmp_path, extra="lenght = 0.3")
    err = refused(capsys, tmp_path, f"robot={path}")
    assert f"parameter 'robot': robot file {path}: joint 1 ('q1'): unknown key 'lenght'" in err


@pytest.mark.parametrize(
    ("rows", "fragment"),
    [
        (SEVEN[:2], "needs 3 or more joints; it has 2"),
        (SEVEN[:3], "its tool cannot move in every direction at any of 513 poses"),  # q3 turns about the tool
        (SEVEN[:5], None),  # a valid 5-joint file: the elbow q4 moves the tool at d5
    ],
)
def test_files_arm_track_cannot_move(capsys, tmp_path, rows, fragment):
    path = robot_file(tmp_path, rows=rows)
    if fragment is None:
        assert hs.run("arm-track", robot=str(path), duration=0.01).metrics["joints"].value == len(rows)
    else:
        assert fragment in refused(capsys, tmp_path, f"robot={path}")


@pytest.mark.parametrize("suffix", ["_velocity", "_bias"])
def test_a_joint_named_as_another_joints_servo_is_refused(capsys, tmp_path, suffix):
    """Joints q1 and q1_velocity: the scene's actuators q1, q1_velocity, q1_bias and q1_velocity (joint q1_velocity's
    position servo) clashed, and MuJoCo's "repeated name 'q1_velocity' in actuator" was an internal error."""
    path = robot_file(tmp_path)
    path.write_text(path.read_text().replace('name = "q2"', f'name = "q1{suffix}"'))
    err = refused(capsys, tmp_path, f"robot={path}")
    assert f"arm-track on arm7 ({path}): joint 'q1{suffix}' has the name arm-track gives the " in err
    assert "of joint 'q1' in its model; rename one of them" in err


def test_a_path_out_of_reach_is_refused_before_the_run(capsys, tmp_path):
    err = refused(capsys, tmp_path, "robot=elbow", "offset_z=2")
    assert "arm-track on elbow: the path's first point, (-0.08336, -0.2892, 2.524) m: no solution" in err
    assert "(closest: 1.49 m away)" in err and "lower 'size' or move the path" in err
    # The SCARA's circle moved out until its far side is 0.05 mm beyond the 0.65 m reach (a1 + a2).
    err = refused(capsys, tmp_path, "robot=scara", "offset_x=0.29276", "offset_y=-0.06992")
    assert "arm-track on scara: the path at t = " in err and "is out of reach within the joint ranges" in err


def test_a_default_duration_beyond_its_range_is_refused_naming_what_sets_it(capsys, tmp_path):
    """duration = 0 is the ramp and one cycle: at speed 1e-9 m/s 3.14e8 s, refused by the cost check with "raise
    'timestep' or lower 'duration'" (neither helps: duration was 0); at 1e-5 m/s and timestep 0.01 s it ran 31,416 s,
    beyond the parameter's 3600 s."""
    for sets in (("speed=1e-9",), ("speed=1e-5", "timestep=0.01", "servo_bandwidth=5")):
        err = refused(capsys, tmp_path, *sets)
        assert "parameter 'duration' = 0 runs the 0.5 s ramp and one cycle of the path, here 3.14e+" in err, err
        assert "more than 3600 s: raise 'speed', lower 'size' or give a 'duration'" in err


def test_the_python_api_gives_the_same_message(capsys, tmp_path):
    err = refused(capsys, tmp_path, "robot=elbow", "offset_z=2")
    with pytest.raises(UsageError) as info:
        hs.run("arm-track", robot="elbow", offset_z=2)
    assert err == f"hexabot-sim: error: {info.value}"


def test_six_joints_that_cannot_turn_the_tool_about_every_axis_track_the_position_only(tmp_path):
    """A base turn and five parallel elbows: 6 joints, 2 axis directions; no held orientation, the position tracked."""
    rows = [("0.0", "90.0", "0.3")] + [("0.15", "0.0", "0.0")] * 5  # (a, alpha, d)
    text = ['name = "planar6"', 'convention = "standard"', 'angles = "deg"']
    for i, (a, alpha, d) in enumerate(rows, start=1):
        text += ["[[joints]]", f'name = "q{i}"', 'type = "revolute"', f"a = {a}", f"alpha = {alpha}", f"d = {d}",
                 "theta = 0.0", "lower = -150.0", "upper = 150.0"]  # fmt: skip
    path = tmp_path / "planar6.toml"
    path.write_text("\n".join(text))
    m = hs.run("arm-track", robot=str(path), duration=1.0).metrics
    assert m["joints"].value == 6 and m["orientation_error_max"].value is None
    assert m["tracking_error_rms"].value < TARGET_RMS


@pytest.mark.parametrize(("name", "value"), [("size", "5e-324"), ("size", "1e-320"), ("speed", "1e-320")])
def test_a_size_or_speed_whose_path_rate_underflows_is_refused(tmp_path, capsys, name, value):
    """size=5e-324 was a ZeroDivisionError (an internal error), speed=1e-320 ran with numpy's warnings on stderr and
    a path of NaN phases (found by fuzzing): the rate speed / (size / 2) underflows."""
    code, _, err = cli(capsys, "run", "arm-track", "--set", f"{name}={value}", "--out", str(tmp_path / "r"))
    assert code == 2 and err.count("\n") == 1 and f"parameter '{name}' must be a number with " in err, err
    assert list(tmp_path.iterdir()) == []
