"""Legged-robot files (kinematics/legged_file.py): the example read, its MJCF against the layout's FK, the statics
of the torque check against MuJoCo, and one-line refusals of bad or infeasible files."""

from __future__ import annotations

import os
import re
from pathlib import Path

import mujoco
import numpy as np
import pytest
from helpers import foot_and_jacobian_errors, quat_to_matrix

from hexabot_sim import models
from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics import legged, legged_file

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "my_hexapod.toml"


def test_example_reads_into_a_mirrored_layout() -> None:
    robot = legged_file.read(EXAMPLE)
    layout = robot.layout
    assert robot.name == "my_hexapod" and layout.legs == ("lf", "lm", "lr", "rf", "rm", "rr")
    g = layout.geometry
    assert (g.l1, g.l2, g.l3) == (0.04, 0.08, 0.12)
    assert layout.plate == pytest.approx((0.18, 0.10, 0.015), abs=1e-15)
    assert layout.hips[3] == (0.16, -0.09) and layout.yaws_deg[5] == -135.0
    assert (layout.stand_height, layout.neutral_reach, robot.torque_limit, robot.stance_legs) == (0.1, 0.14, 1.5, 3)


def test_mjcf_feet_and_jacobians_agree_with_the_layout() -> None:
    robot = legged_file.read(EXAMPLE)
    xml = robot.robot_xml()
    err_p, err_j = foot_and_jacobian_errors("", robot.layout, 40, xml=xml)
    assert err_p < 1e-12 and err_j < 1e-12
    model = mujoco.MjModel.from_xml_string(xml)
    assert model.body_subtreemass[model.body("torso").id] == pytest.approx(robot.layout.total_mass, rel=1e-12)
    assert np.all(model.jnt_actfrcrange[1:] == [-1.5, 1.5])


def test_gravity_torques_equal_mujocos_bias_forces() -> None:
    """Link weights' torques (gravity x lever arms) against MuJoCo's qfrc_bias at rest, body level, random q."""
    robot = legged_file.read(EXAMPLE)
    layout = robot.layout
    model = mujoco.MjModel.from_xml_string(robot.robot_xml())
    data = mujoco.MjData(model)
    rng = np.random.default_rng(3)
    for _ in range(20):
        q = rng.uniform(legged.JOINT_LOWER, legged.JOINT_UPPER, size=(layout.n_legs, 3))
        yaw = rng.uniform(-np.pi, np.pi)  # a turn about the vertical changes no lever arm
        data.qpos[:] = np.r_[rng.uniform(-1, 1, 3), np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2), q.ravel()]
        data.qvel[:] = 0.0
        mujoco.mj_forward(model, data)
        for i in range(layout.n_legs):
            assert data.qfrc_bias[6 + 3 * i : 9 + 3 * i] == pytest.approx(
                legged_file.gravity_torques(layout, q[i]), abs=1e-12
            )


def test_stance_torques_equal_mujocos_servo_torques_when_standing() -> None:
    """Standing on the floor: the statics tau = G - J^T f with MuJoCo's own contact forces gives the torques its
    servos apply (qfrc_actuator), leg by leg."""
    robot = legged_file.read(EXAMPLE)
    layout = robot.layout
    xml = models.to_xml(models.load_tree("hexabot_scene", {"hexabot.xml": robot.robot_xml()}))
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    for _ in range(1000):  # 2 s: settled
        mujoco.mj_step(model, data)
    mujoco.mj_forward(model, data)
    assert np.abs(data.qvel).max() < 1e-4
    body = quat_to_matrix(data.qpos[3:7])
    hips = layout.hip_rotations()
    force = np.zeros(6)
    worst = 0.0
    for i, leg in enumerate(layout.legs):
        foot = model.geom(f"{leg}_foot").id
        f_world = np.zeros(3)
        for c in range(data.ncon):
            contact = data.contact[c]
            if foot in (contact.geom1, contact.geom2):
                mujoco.mj_contactForce(model, data, c, force)
                f = contact.frame.reshape(3, 3).T @ force[:3]
                f_world += f if f[2] > 0 else -f  # on the foot: the ground pushes it up
        q = data.qpos[7 + 3 * i : 10 + 3 * i]
        f_hip = (body @ hips[i]).T @ f_world
        tau = legged_file.stance_torques(layout, q, f_hip)
        worst = max(worst, float(np.abs(data.qfrc_actuator[6 + 3 * i : 9 + 3 * i] - tau).max()))
    assert worst < 1e-8  # N m, of ~0.27 N m at the femurs (measured: 1.3e-10)
    # The refusal's number: the weight shared equally by the six feet of this symmetric layout gives the largest
    # torque MuJoCo's servos apply standing (measured 0.2652 N m against 0.2610: the feet share it almost evenly);
    # the check itself loads half the feet (a tripod), the worst case of the gaits.
    standing = np.abs(data.qfrc_actuator[6:]).max()
    assert standing == pytest.approx(legged_file.standing_torque(layout, 6), rel=0.03)
    assert standing < legged_file.standing_torque(layout, robot.stance_legs)


BAD = [
    ("l1 = 0.04", "l1 = 0.04\nlenght = 1", r"\[leg\]: unknown key 'lenght'; allowed: l1, l2, l3"),
    ("l2 = 0.08", 'l2 = "long"', r"\[leg\]: 'l2' must be a finite number \[m\]; got 'long'"),
    ("l3 = 0.12", "l3 = nan", r"\[leg\]: 'l3' must be a finite number \[m\]; got nan"),
    ("masses = [0.03, 0.05, 0.05]", "masses = [0.03, 0.05]", r"\[leg\]: 'masses' must be a list of 3 numbers"),
    ("[stance]", "[stanse]", r"unknown key 'stanse'; allowed: name, summary, leg, body, stance, legs"),
    (
        'rows = ["f", "m", "r"]',
        'rows = ["f", "m", "r"]\nnames = ["a"]',
        r"\[legs\]: give 'rows' .* or 'names' .*not both",
    ),
    # Neither was told "not both" (found by fuzzing).
    ('rows = ["f", "m", "r"]', "", r"\[legs\]: give 'rows' .* or 'names' \(every leg\), one of them is needed$"),
    ("[0.0, 0.10]", "[0.0, -0.10]", r"\[legs\]: with 'rows', 'hips' are the left row's: each y must be > 0"),
    # A hip 10 m from the plate was accepted: a leg standing on nothing (no bracket is drawn).
    (
        "[0.16, 0.09]",
        "[10.0, 0.09]",
        r"\[legs\]: leg lf's hip \(10, 0.09\) m is off the 0.36 x 0.2 m plate "
        r"\(\|x\| <= 0.18, \|y\| <= 0.1 m\): a leg is mounted on the body; move it in 'hips' or enlarge "
        r"\[body\] 'size'$",
    ),
    ("[0.0, 0.10]", "[0.0, 0.1015]", r"\[legs\]: leg lm's hip \(0, 0.1015\) m is off"),
    ("height = 0.10", "height = 0.25", r"\[stance\]: the legs cannot reach the ground at height 0.25 m"),
    ("size = [0.36, 0.20, 0.03]", "size = [0.36, 0.20, 0.3]", r"\[stance\]: the plate would touch the ground"),
    ("torque_limit = 1.5", "torque_limit = 0.3", r"\[leg\]: the servos are too weak to stand: .* needs 0.58\d N m"),
]


@pytest.mark.parametrize(("old", "new", "message"), BAD, ids=[b[1].split("\n")[-1].split("=")[0].strip() for b in BAD])
def test_bad_files_are_refused_in_one_line(tmp_path: Path, old: str, new: str, message: str) -> None:
    text = EXAMPLE.read_text()
    assert old in text
    path = tmp_path / "bad.toml"
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(UsageError) as e:
        legged_file.read(path)
    text = str(e.value)
    assert "\n" not in text and text.startswith(f"robot file {path}: ")
    assert re.search(message, text), text


def test_unreadable_and_oversized_files_are_refused(tmp_path: Path) -> None:
    with pytest.raises(UsageError, match="is a folder"):
        legged_file.read(tmp_path)
    big = tmp_path / "big.toml"
    big.write_text("#" * (2 << 20))
    with pytest.raises(UsageError, match="larger than 1024 KiB"):
        legged_file.read(big)


def test_a_pipe_a_nested_document_and_a_byte_order_mark_as_robot_files_do(tmp_path: Path) -> None:
    """Read as robot_file reads a DH table (one reader): a FIFO is refused at once (it waited for a writer forever),
    deep nesting is one line (a RecursionError), and a Windows editor's BOM is no error."""
    fifo = tmp_path / "pipe.toml"
    os.mkfifo(fifo)
    with pytest.raises(UsageError, match="not a regular file"):
        legged_file.read(fifo)
    nested = tmp_path / "nested.toml"
    nested.write_text("x = " + "[" * 5000 + "]" * 5000 + "\n")
    with pytest.raises(UsageError, match="nested too deeply"):
        legged_file.read(nested)
    bom = tmp_path / "bom.toml"
    bom.write_bytes(b"\xef\xbb\xbf" + EXAMPLE.read_bytes())
    assert legged_file.read(bom).layout == legged_file.read(EXAMPLE).layout
    # TOML integers have any number of digits: an OverflowError in math.isfinite, a ValueError from tomllib.
    for digits, message in ((400, r"\[leg\]: 'l1' must be a finite number \[m\]"), (5000, "more than 4300 digits")):
        big = tmp_path / "big_int.toml"
        big.write_text(re.sub(r"(?m)^l1 = \S+", "l1 = 1" + "0" * digits, EXAMPLE.read_text()))
        with pytest.raises(UsageError, match=message) as e:
            legged_file.read(big)
        assert "\n" not in str(e.value)


def test_a_leg_with_a_one_millimetre_coxa_compiles(tmp_path: Path) -> None:
    """l1 = 0.001 m (the file's smallest) was an internal error: MuJoCo refused the coxa's rod inertia."""
    tiny = tmp_path / "tiny.toml"
    tiny.write_text(re.sub(r"(?m)^l1 = \S+", "l1 = 0.001", EXAMPLE.read_text()))
    mujoco.MjModel.from_xml_string(legged_file.read(tiny).robot_xml())


def test_an_arm_file_given_as_a_legged_one_and_the_reverse_say_which_kind_they_are(capsys) -> None:
    """Not "unknown key 'convention'; allowed: name, summary, leg, ..." (the walk's robot=) nor "unknown key 'leg'"
    (kin, export): the two kinds of robot file name each other."""
    from hexabot_sim.kinematics import robot_file

    arm = Path(robot_file.__file__).parent / "arms" / "scara.toml"
    with pytest.raises(UsageError, match=r"is a serial-arm \(DH\) robot file, not a legged-robot file") as e:
        legged_file.read(arm)
    assert "\n" not in str(e.value)
    with pytest.raises(UsageError, match=r"is a legged-robot file, not a serial-arm \(DH\) robot file") as e:
        robot_file.read(EXAMPLE)
    assert "\n" not in str(e.value)
    # A four-legged file was told "walk it with hexabot-walk --set robot=FILE", which refuses four legs:
    with pytest.raises(UsageError) as e:
        robot_file.read(Path(legged_file.__file__).parents[1] / "robots" / "quadbot" / "quadbot.toml")
    assert "walk it with --set robot=FILE in hexabot-walk (six legs) or quadbot-walk (four legs)" in str(e.value)
