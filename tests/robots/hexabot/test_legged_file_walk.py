"""hexabot-walk with robot=FILE: a user's hexapod (examples/my_hexapod.toml) walks; bad or infeasible robot files are
refused in one line before the run; the default robot is still the hexabot."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from helpers import cli, walk_params

import hexabot_sim as hs
from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics import legged_file
from hexabot_sim.robots.hexabot.walk import HEXABOT

EXAMPLE = Path(__file__).resolve().parents[3] / "examples" / "my_hexapod.toml"


def test_the_default_robot_is_the_hexabot_at_its_own_stand_height() -> None:
    p = walk_params()
    assert p.robot == "hexabot" and p.ROBOT is HEXABOT and p.stand_height == 0.09
    assert walk_params(stand_height=0.1).stand_height == 0.1
    with pytest.raises(
        UsageError,
        match=r"'stand_height' must be 0 \(the robot's own\) or 0.02 to 20 m \(within the legs' reach\); got 0.01",
    ):
        walk_params(stand_height=0.01)


def test_the_example_hexapod_walks_at_the_commanded_speed() -> None:
    """A 3.4 s walk (settling, the 1 s ramp, two cycles measured) of the user's hexapod in its generated model."""
    result = hs.run("hexabot-walk", robot=str(EXAMPLE), duration=3.4)
    robot = legged_file.read(EXAMPLE)
    model = result.raw.model
    assert model.body_subtreemass[model.body("torso").id] == pytest.approx(robot.layout.total_mass, rel=1e-12)
    assert model.site("lf_hip").pos.tolist() == [0.16, 0.09, 0.0]  # the file's hips, not the hexabot's
    assert result.params["stand_height"] == 0.1  # the file's stance
    assert result.metrics["fell"].value is False
    assert abs(result.metrics["vx_error"].value) < 0.02  # relative: (mean_vx - vx) / |vx|


def _variant(tmp_path: Path, old: str, new: str) -> Path:
    text = EXAMPLE.read_text()
    assert old in text
    path = tmp_path / "robot.toml"
    path.write_text(text.replace(old, new, 1))
    return path


def test_a_leg_without_a_coxa_compiles_and_stands(tmp_path: Path) -> None:
    """l1 = 0 is allowed (docs/robot-files.md) but was an internal error: a NaN in the servo inertia (a rod of length
    0) and MuJoCo's 'fromto points too close in geom lf_coxa'. Found by fuzzing."""
    path = _variant(tmp_path, "l1 = 0.04", "l1 = 0.0")
    result = hs.run("hexabot-walk", robot=str(path), duration=1.6)
    model = result.raw.model
    assert np.isfinite(model.actuator_gainprm).all() and np.isfinite(model.actuator_biasprm).all()
    assert result.metrics["fell"].value is False


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("l2 = 0.08", "l2 = true", "[leg]: 'l2' must be a finite number [m]; got True"),
        ("height = 0.10", "height = 0.3", "[stance]: the legs cannot reach the ground at height 0.3 m"),
        ("torque_limit = 1.5", "torque_limit = 0.5", "[leg]: the servos are too weak to stand"),
        ('rows = ["f", "m", "r"]', 'rows = ["f", "r"]', "4 legs; the hexabot's scenarios walk 6-legged robots"),
        # A bidi override or ESC went raw to the terminal and the MJCF comment (found by fuzzing):
        ('summary = "six', 'summary = "a\\u202eb six', "'summary' must be one line of text"),
        ('summary = "six', 'summary = "a\\u001b[2J six', "'summary' must be one line of text"),
    ],
)
def test_bad_robot_files_exit_2_with_one_line_and_nothing_written(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], old: str, new: str, message: str
) -> None:
    path = _variant(tmp_path, old, new)
    if new.startswith("rows"):  # a quadruped: two hips and two yaws per row
        text = path.read_text().replace("[0.0, 0.10], ", "").replace("90.0, ", "")
        path.write_text(text)
    out = tmp_path / "out"
    code, stdout, err = cli(capsys, "run", "hexabot-walk", "--set", f"robot={path}", "--out", str(out))
    assert code == 2 and stdout == ""
    assert err.count("\n") == 1 and f"parameter 'robot': robot file {path}: {message}" in err, err
    assert not out.exists()


def test_a_missing_file_or_unknown_name_is_refused(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    code, _, err = cli(capsys, "run", "hexabot-walk", "--set", "robot=quadbot", "--out", str(tmp_path / "o"))
    assert code == 2 and err.count("\n") == 1
    assert "parameter 'robot' must be one of hexabot, or the path of a legged-robot file (.toml) with six legs" in err


def test_a_stand_height_that_puts_a_thick_plate_on_the_ground_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The file's own [stance] height is checked against its plate, but stand_height (or a schedule row's) was not:
    a 10 cm plate at stand_height 0.02 m started 22 mm inside the floor and the walk was written out as fallen."""
    path = _variant(tmp_path, "size = [0.36, 0.20, 0.03]", "size = [0.36, 0.20, 0.1]")
    assert walk_params(robot=str(path), stand_height=0.0421).stand_height == 0.0421  # 0.1 mm above the ground
    out = tmp_path / "out"
    code, stdout, err = cli(capsys, "run", "hexabot-walk", "--set", f"robot={path}", "--set", "stand_height=0.02",
                            "--out", str(out))  # fmt: skip
    assert code == 2 and stdout == "" and err.count("\n") == 1 and not out.exists()
    assert "'stand_height' = 0.02 m puts the plate of my_hexapod on the ground: its underside is 0.05 m" in err
    assert "stand_height must be more than 0.042 m" in err
    schedule = tmp_path / "schedule.csv"
    schedule.write_text("t,vx,vy,yaw_rate,stand_height\n0,0.05,0,0,0.1\n2,0.05,0,0,0.03\n")
    code, stdout, err = cli(capsys, "run", "hexabot-walk", "--set", f"robot={path}", "--set", f"schedule={schedule}",
                            "--set", "duration=4", "--out", str(out))  # fmt: skip
    assert code == 2 and err.count("\n") == 1 and not out.exists()
    assert "schedule row 2 (t = 2 s): parameter 'stand_height' = 0.03 m puts the plate of my_hexapod on the" in err


def _named(order: list[str]) -> str:
    """The example's legs listed by 'names' in this order, each with its own hip and yaw."""
    hips = {"lf": (0.16, 0.09), "lm": (0.0, 0.10), "lr": (-0.16, 0.09)}
    yaws = {"lf": 45.0, "lm": 90.0, "lr": 135.0}
    for leg in list(hips):
        hips["r" + leg[1]], yaws["r" + leg[1]] = (hips[leg][0], -hips[leg][1]), -yaws[leg]
    text = EXAMPLE.read_text()
    return text[: text.index("[legs]")] + (
        f"[legs]\nnames = {order}\nhips = {[list(hips[n]) for n in order]}\nyaws = {[yaws[n] for n in order]}\n"
    ).replace("'", '"')


def test_legs_listed_out_of_the_gaits_order_are_refused_not_walked_on_one_side(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The gaits take the legs in the file's order: names = [lf, rf, lm, rm, lr, rr] stood the tripod on the three
    left feet (189 mm beside the body's centre) and the walk was written out at -0.013 m/s for 0.1."""
    path = tmp_path / "named.toml"
    path.write_text(_named(["lf", "lm", "lr", "rf", "rm", "rr"]))
    assert walk_params(robot=str(path)).ROBOT.layout.legs == ("lf", "lm", "lr", "rf", "rm", "rr")
    path.write_text(_named(["lf", "rf", "lm", "rm", "lr", "rr"]))
    out = tmp_path / "out"
    code, stdout, err = cli(capsys, "run", "hexabot-walk", "--set", f"robot={path}", "--out", str(out))
    assert code == 2 and stdout == "" and err.count("\n") == 1 and not out.exists()
    assert "the tripod gait stands on lf, lm, lr at once, and their feet do not surround the body's centre" in err
    assert "(it is at least 189 mm outside them at the neutral stance)" in err and "reorder 'names'" in err


def test_a_stand_height_the_servos_cannot_hold_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The servo check was at the file's own [stance] height only: 0.59 N m servos hold the example at 0.1 m (it
    needs 0.585) but need 0.605 at stand_height 0.03 m, where the walk fell and was written out."""
    path = _variant(tmp_path, "torque_limit = 1.5", "torque_limit = 0.59")
    assert walk_params(robot=str(path), vx=0.05).stand_height == 0.1
    out = tmp_path / "out"
    code, stdout, err = cli(capsys, "run", "hexabot-walk", "--set", f"robot={path}", "--set", "stand_height=0.03",
                            "--set", "vx=0.05", "--out", str(out))  # fmt: skip
    assert code == 2 and stdout == "" and err.count("\n") == 1 and not out.exists()
    assert "'stand_height' = 0.03 m: the servos of my_hexapod are too weak to stand there: holding 1.98 kg on 3" in err
    assert "needs 0.605 N m, above its torque_limit = 0.59 N m" in err


def test_a_file_stance_below_the_walks_lowest_names_the_file_not_a_parameter(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A file's [stance] height of 0.01 m (allowed in the file) was refused as "parameter 'stand_height' must be 0
    (the robot's own) or 0.02 to 0.19 m; got 0.01": a parameter the user had not set."""
    path = _variant(tmp_path, "height = 0.10", "height = 0.01")
    path.write_text(path.read_text().replace("size = [0.36, 0.20, 0.03]", "size = [0.36, 0.20, 0.01]"))
    out = tmp_path / "out"
    code, stdout, err = cli(capsys, "run", "hexabot-walk", "--set", f"robot={path}", "--out", str(out))
    assert code == 2 and stdout == "" and err.count("\n") == 1 and not out.exists()
    assert "my_hexapod stands 0.01 m below its hips (its file's [stance] height), lower than the walk's lowest" in err
    assert "parameter 'stand_height'" not in err


def test_stand_height_is_bounded_by_the_legs_reach_not_by_the_hexabots(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """stand_height stopped at 0.19 m for every robot: a file with 0.15 / 0.20 m legs standing at 0.25 m could not be
    set to 0.28 m. The bound is the legs' reach at the neutral stance: a foot `reach` out from its hip, the femur
    axis l1 further in, reaches at most sqrt((l2 + l3)^2 - (reach - l1)^2) below it (the hexabot's 0.1833 m, where
    0.19 m was refused as "even stepping in place is infeasible ...; lengthen 'period' or lower 'step_height'",
    which did not help)."""
    tall = _variant(tmp_path, "l2 = 0.08", "l2 = 0.15")
    tall.write_text(tall.read_text().replace("l3 = 0.12", "l3 = 0.20").replace("height = 0.10", "height = 0.25"))
    reach = np.sqrt(0.35**2 - (0.14 - 0.04) ** 2)  # 0.3354 m
    assert walk_params(robot=str(tall), vx=0.02).stand_height == 0.25
    assert walk_params(robot=str(tall), vx=0.02, stand_height=0.28).stand_height == 0.28
    hexabot = np.sqrt(0.2**2 - (0.13 - 0.05) ** 2)
    assert walk_params(vx=0.0, stand_height=np.floor(hexabot * 1e4) / 1e4).stand_height == 0.1833
    for robot, name, top in ((str(tall), "my_hexapod", reach), ("hexabot", "hexabot", hexabot)):
        out = tmp_path / "out"
        code, stdout, err = cli(capsys, "run", "hexabot-walk", "--set", f"robot={robot}", "--set",
                                f"stand_height={top + 2e-4:.4f}", "--out", str(out))  # fmt: skip
        assert code == 2 and stdout == "" and err.count("\n") == 1 and not out.exists()
        assert f"is out of the legs' reach: {name}'s feet" in err
        assert f"at most {np.floor(top * 1e4) / 1e4:g} m below the hips; give a lower stand_height (0: the" in err
