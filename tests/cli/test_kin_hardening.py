"""`hexabot-sim kin` against anything a user types: negative values, degrees, range warnings, absurd numbers."""

import json
import math
import random
import re
import sys

import numpy as np
import pytest

import hexabot_sim.kinematics
from hexabot_sim import kinreport
from hexabot_sim.__main__ import build_parser, main
from hexabot_sim.kinematics import inverse, robots

ROBOTS = ["rrp", "elbow", "stanford", "scara", "leg"]
pytestmark = pytest.mark.filterwarnings("error")  # a numpy RuntimeWarning anywhere is a failure


def kin(capsys, *argv):
    """(exit code, stdout, stderr lines) of `hexabot-sim kin ...`."""
    code = main(["kin", *argv])
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    return code, out, err.splitlines()


def kin_json(capsys, *argv):
    code, out, err = kin(capsys, *argv, "--json")
    assert code == 0, err
    report = json.loads(out)
    assert report["warnings"] == [line.removeprefix("hexabot-sim: warning: ") for line in err]
    return report


def numbers(values) -> str:
    return ",".join(repr(float(v)) for v in values)


def assert_one_line_error(code, out, err, fragment):
    assert code == 2 and not out and len(err) == 1, (out, err)
    assert err[0].startswith("hexabot-sim: error: ") and fragment in err[0], err[0]


# --- negative values as users type them ---------------------------------------------------------------------


@pytest.mark.parametrize(
    ("robot", "option", "value"),
    [
        ("leg", "--q", "-1,0.5,0.2"),
        ("leg", "--q", "-.5,-0.25,1"),
        ("rrp", "--q", "-1e-3,-0.4,-0.5"),
        ("leg", "--target", "0.1,-0.05,-0.08"),
        ("elbow", "--target", "-0.3,-0.2,-0.1"),
        ("stanford", "--target", "-0.3,0.2,-0.1,-0.5,0.2,-1"),
        ("scara", "--target", "-0.4,0.2,0.1,-0.7"),
    ],
)
def test_negative_values_are_taken_as_typed(capsys, robot, option, value):
    spaced = kin_json(capsys, robot, option, value)
    joined = kin_json(capsys, robot, f"{option}={value}")
    assert spaced == joined
    key = "q" if option == "--q" else "target"
    assert spaced[key] == [float(v) for v in value.split(",")]


def test_negative_infinity_is_named_not_taken_for_an_option(capsys):
    assert_one_line_error(*kin(capsys, "leg", "--q", "-inf,0,0"), "--q must be finite numbers; got '-inf,0,0'")
    assert_one_line_error(*kin(capsys, "leg", "--q", "-1 0.5 0.2"), "--q must be comma-separated numbers")


def test_typographic_minus_is_a_minus(capsys):
    assert kin_json(capsys, "leg", "--q", "\u22121,0.5,0.2")["q"] == [-1.0, 0.5, 0.2]


# --- degrees ---------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("robot", ROBOTS)
def test_deg_gives_the_same_pose_and_solutions_in_degrees(capsys, robot):
    spec = robots.get(robot)
    chain = spec.chain()
    q = np.array([0.3, 0.5, 0.4, 0.6, 0.7, 0.2][: chain.n])  # inside every range
    in_deg = [math.degrees(v) if u == "rad" else v for v, u in zip(q, spec.joint_units, strict=True)]
    rad, deg = kin_json(capsys, robot, "--q", numbers(q)), kin_json(capsys, robot, "--q", numbers(in_deg), "--deg")
    assert rad["angle_unit"] == "rad" and deg["angle_unit"] == "deg"
    assert np.allclose(deg["T0n"], rad["T0n"], atol=1e-14) and np.allclose(deg["J"], rad["J"], atol=1e-14)
    assert deg["q"] == in_deg and deg["det"] == pytest.approx(rad["det"], rel=1e-12, abs=1e-15)
    joint_rows = [row for row in deg["dh"] if row["kind"] != "fixed"]  # the leg's foot row has no unit
    for row, unit in zip(joint_rows, spec.joint_units, strict=True):
        assert row["unit"] == ("deg" if unit == "rad" else "m")
    assert [r["alpha"] for r in deg["dh"]] == pytest.approx([math.degrees(r["alpha"]) for r in rad["dh"]])

    pose = chain.fk(q)
    target = list(pose[:3, 3])
    if robot == "stanford":
        rot = pose[:3, :3]
        angles = [math.atan2(rot[2, 1], rot[2, 2]), -math.asin(rot[2, 0]), math.atan2(rot[1, 0], rot[0, 0])]
        target_rad, target_deg = target + angles, target + [math.degrees(a) for a in angles]
    else:
        target_rad = target_deg = target
    rad = kin_json(capsys, robot, "--target", numbers(target_rad))
    deg = kin_json(capsys, robot, "--target", numbers(target_deg), "--deg")
    assert len(rad["solutions"]) == len(deg["solutions"]) >= 1
    for a, b in zip(rad["solutions"], deg["solutions"], strict=True):
        expected = [math.degrees(v) if u == "rad" else v for v, u in zip(a["q"], spec.joint_units, strict=True)]
        assert b["q"] == pytest.approx(expected, abs=1e-9)


def test_deg_text_names_the_units(capsys):
    code, out, _ = kin(capsys, "scara", "--q", "30,-45,0.1,90", "--deg", "--target", "0.4,0.2,0.1,-45")
    assert code == 0
    assert "theta [deg]" in out and "q = [30.0, -45.0, 0.1, 90.0] [deg, deg, m, deg]" in out
    assert re.search(r"IK for target \[0.4, 0.2, 0.1, -45.0\]: 2 solution\(s\) \[deg, deg, m, deg\]", out)


# --- warnings --------------------------------------------------------------------------------------------------


def test_q_outside_the_joint_ranges_warns_one_line_each(capsys):
    report = kin_json(capsys, "leg", "--q", "100,-30,200", "--deg")
    assert report["warnings"] == [
        "coxa = 100 deg is outside its joint range [-90, 90] deg",
        "tibia = 200 deg is outside its joint range [0, 160] deg",
    ]
    code, _, err = kin(capsys, "leg", "--q", "100,-30,200", "--deg")
    assert code == 0 and len(err) == 2 and all(line.startswith("hexabot-sim: warning: ") for line in err)


def test_range_uses_the_lengths_given(capsys):
    # rrp's slide cannot retract past -a2: with a2 = 0.5, d3 = -0.8 is outside, with the default a2 = 1 it is not.
    assert kin_json(capsys, "rrp", "--q", "0,0,-0.8")["warnings"] == []
    warnings = kin_json(capsys, "rrp", "--set", "a2=0.5", "--q", "0,0,-0.8")["warnings"]
    assert warnings == ["d3 = -0.8 m is outside its joint range [-0.5, 2] m"]


def test_radians_beyond_a_turn_hint_at_deg(capsys):
    (warning,) = kin_json(capsys, "rrp", "--q", "90,0,0")["warnings"]
    assert warning == "q1 = 90 rad is more than a full turn; revolute values are in rad (add --deg to type degrees)"
    assert kin_json(capsys, "rrp", "--q", "90,0,0", "--deg")["warnings"] == []


def test_dropped_ik_branches_are_counted_and_named(capsys):
    report = kin_json(capsys, "leg", "--target", "0.1,0.05,-0.08")
    assert len(report["solutions"]) == 1 and len(report["dropped"]) == 3
    (warning,) = report["warnings"]
    assert warning.startswith("IK: 3 of 4 branches dropped by the joint ranges: q = (")
    assert warning.count("q = (") == 3 and "femur = 1.9539 outside [-1.5708, 1.5708] rad" in warning
    for branch in report["dropped"]:
        assert "outside" in branch["outside"] and len(branch["q"]) == 3
    assert kin_json(capsys, "elbow", "--target", "0.3,0.2,0.5")["warnings"] == []  # elbow has no ranges


def test_every_branch_dropped_is_an_error_that_counts_them(capsys):
    code, out, err = kin(capsys, "leg", "--target", "-0.1,0.05,-0.08", "--deg")
    assert_one_line_error(code, out, err, "leg target (-0.1, 0.05, -0.08) m: all 4 IK branch(es) are outside")
    assert "coxa = 153.435 outside [-90, 90] deg" in err[0]


def test_ik_branches_reports_what_ik_drops():
    target = np.array([0.1, 0.05, -0.08])
    solutions, dropped = inverse.ik_branches("leg", target)
    assert len(solutions) == 1 and len(dropped) == 3
    assert np.allclose(solutions, inverse.ik("leg", target))
    with pytest.raises(inverse.IKError, match="every solution is outside the joint ranges"):
        inverse.ik("leg", np.array([-0.1, 0.05, -0.08]))


# --- absurd numbers: refused with the allowed range, or computed exactly ---------------------------------------


@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        (["leg", "--q", "1e308,1e308,1e308"], "--q: coxa = 1e+308 rad is outside the allowed ±1000 rad"),
        (["rrp", "--q", "0,0,1e308", "--json"], "--q: d3 = 1e+308 m is outside the allowed ±100 m"),
        (["stanford", "--q", "0,0,0,0,1e6,0", "--deg"], "theta5 = 1e+06 deg is outside the allowed ±57295.7 deg"),
        (["rrp", "--q", "1e309,0,0"], "--q must be finite numbers"),
        (["elbow", "--q", "nan,0,0", "--json"], "--q must be finite numbers"),
        (["elbow", "--target", "1e300,0,0"], "--target: x = 1e+300 m is outside the allowed ±1000 m"),
        (["scara", "--target", "0.4,0.2,0.1,1e300"], "--target: angle 1e+300 rad is outside the allowed ±1000 rad"),
        (["stanford", "--target", "0.3,0.2,0.1,0,inf,0"], "--target must be finite numbers"),
        (["leg", "--set", "l2=1e308", "--q", "0,0,0"], "length 'l2' of leg must be 0.001 to 10 m; got 1e+308"),
        (["leg", "--set", "l2=1e-300", "--json"], "length 'l2' of leg must be 0.001 to 10 m; got 1e-300"),
        (["scara", "--set", "d4=1e-9"], "length 'd4' of scara must be 0 or 0.001 to 10 m; got 1e-09"),
        (["stanford", "--set", "d6=nan"], "length 'd6' must be a finite number"),
        (["rrp", "--set", "d1=1,2"], "length 'd1' takes one number in [m]; got '1,2'"),
        (["rrp", "--set", "d1="], "length 'd1' must be comma-separated numbers; got ''"),
        (["scara", "--target", "0.4,0.2", "--deg"], "scara needs --target x,y,z[,yaw] (m, deg); got 2 values"),
        (["leg", "--symbolic", "--q", "1,2"], "leg has 3 joints (coxa [rad], femur [rad], tibia [rad]); got 2"),
    ],
)
def test_absurd_input_is_refused_with_the_allowed_range(capsys, argv, fragment):
    assert_one_line_error(*kin(capsys, *argv), fragment)


@pytest.mark.parametrize("robot", ROBOTS)
@pytest.mark.parametrize("extreme", ["small", "large"])
def test_extreme_allowed_values_compute_finite_results(capsys, robot, extreme):
    spec = robots.get(robot)
    chain = spec.chain()
    length = robots.LENGTH_MIN if extreme == "small" else robots.LENGTH_MAX
    sets = [a for name in spec.lengths for a in ("--set", f"{name}={length!r}")]
    q = [
        (kinreport.PRISMATIC_MAX if extreme == "large" else 5e-324) * (-1) ** i
        if joint.prismatic
        else (kinreport.ANGLE_MAX if extreme == "large" else 1e-300) * (-1) ** i
        for i, joint in enumerate(chain.joints)
    ]
    for flags in ([], ["--deg"]):
        shown = [math.degrees(v) if u == "rad" and flags else v for v, u in zip(q, spec.joint_units, strict=True)]
        report = kin_json(capsys, robot, *sets, "--q", numbers(shown), *flags)
        assert np.all(np.isfinite(report["T0n"])) and np.all(np.isfinite(report["J"]))
        if report["det"] == 0.0:
            assert report["is_singular"]
        code, out, err = kin(capsys, robot, *sets, "--q", numbers(shown), *flags)
        assert code == 0 and not re.search(r"\b(nan|inf)\b", out, re.IGNORECASE)
        assert not re.search(r"det = 0\nsingular: no", out)
    far = [kinreport.TARGET_MAX, -kinreport.TARGET_MAX, kinreport.TARGET_MAX, 0.0, 0.0, 0.0][
        : 6 if robot == "stanford" else 3
    ]
    for target in (far, [1e-300, -1e-300, 5e-324, 0.0, 0.0, 0.0][: len(far)]):
        code, out, err = kin(capsys, robot, *sets, "--target", numbers(target), "--json")
        assert code in (0, 2) and not re.search(r"\b(nan|inf)\b", " ".join(err), re.IGNORECASE), err
        if code == 0:
            json.loads(out)
        else:
            assert_one_line_error(code, out, err, "")


def test_tiny_lengths_do_not_make_everything_singular(capsys):
    # With every length at 1 mm the tolerances scale with the robot: a generic q is not singular.
    report = kin_json(capsys, "rrp", "--set", "d1=0.001", "--set", "a2=0.001", "--q", "0.3,0.2,0.0005")
    assert not report["is_singular"] and report["det"] > 0


# --- symbolic --------------------------------------------------------------------------------------------------


def test_missing_sympy_names_the_extra(capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "sympy", None)
    monkeypatch.delitem(sys.modules, "hexabot_sim.kinematics.symbolic", raising=False)
    monkeypatch.delattr(hexabot_sim.kinematics, "symbolic", raising=False)  # `from ... import` looks here first
    code, out, err = kin(capsys, "leg", "--symbolic")
    assert_one_line_error(code, out, err, "--symbolic needs sympy (the extra 'symbolic')")
    assert 'pip install ".[symbolic]"' in err[0]


# --- help and a small seeded fuzz ------------------------------------------------------------------------------


def test_help_states_the_ranges_the_code_enforces():
    kin_parser = build_parser()._subparsers._group_actions[0].choices["kin"]
    text = " ".join(kin_parser.format_help().split())
    assert f"link lengths {robots.LENGTH_MIN:g} to {robots.LENGTH_MAX:g} m" in text
    assert f"<= {kinreport.ANGLE_MAX:g} rad" in text and f"<= {kinreport.PRISMATIC_MAX:g} m" in text
    assert f"target <= {kinreport.TARGET_MAX:g} m" in text and "--deg" in text and "LaTeX" in text
    assert kin_parser._negative_number_matcher.pattern == kinreport.NUMBER_LIST.pattern


TOKENS = ["0", "-0", "1", "-1", "-0.5", "3.14159", "-1.5708", "1e-300", "-5e-324", "999.9", "-1000", "1000.001",
          "100", "-100.5", "90", "-180", "1e308", "inf", "-nan", "", "x", "1e-9", "-2.79"]  # fmt: skip
LENGTHS = ["0.001", "10", "0", "1e-300", "1e308", "-1", "0.05", "2", "nan"]


def test_seeded_fuzz(capsys):
    rng = random.Random(8)
    for _ in range(150):
        robot = rng.choice(ROBOTS)
        spec = robots.get(robot)
        n = len(spec.joint_units)
        argv = [robot]
        for name in rng.sample(list(spec.lengths), rng.randint(0, len(spec.lengths))):
            argv += ["--set", f"{name}={rng.choice(LENGTHS)}"]
        if rng.random() < 0.7:
            argv += [
                "--q",
                ",".join(rng.choice(TOKENS) if rng.random() < 0.3 else repr(rng.uniform(-4, 4)) for _ in range(n)),
            ]
        if rng.random() < 0.7:
            k = {"stanford": 6, "scara": 4}.get(robot, 3)
            argv += [
                "--target",
                ",".join(rng.choice(TOKENS) if rng.random() < 0.2 else repr(rng.uniform(-0.6, 0.6)) for _ in range(k)),
            ]
        argv += [flag for flag in ("--deg", "--json") if rng.random() < 0.4]
        code, out, err = kin(capsys, *argv)
        assert code in (0, 2), (argv, err)
        if code == 2:
            assert_one_line_error(code, out, err, "")
            continue
        assert all(line.startswith("hexabot-sim: warning: ") for line in err), (argv, err)
        if "--json" in argv:
            assert len(json.loads(out)["warnings"]) == len(err)
        else:
            assert not re.search(r"\b(nan|inf)\b", out, re.IGNORECASE) and "det = 0\nsingular: no" not in out
