"""`kin FILE`: a robot file's report (text and --json), numeric IK, --set, --symbolic; and the asked-for changes to
the package robots' reports (the leg's foot row, orientation residuals)."""

from __future__ import annotations

import importlib.util
import json
import math

import numpy as np
import pytest
from helpers import cli

from hexabot_sim import kinreport
from hexabot_sim.kinematics import robots

PLANAR = """\
name = "planar"
summary = "two links in a plane"
convention = "standard"
angles = "deg"
[lengths]
l1 = { value = 0.3, doc = "first link" }
l2 = { value = 0.2, doc = "second link" }
[[joints]]
name = "q1"
type = "revolute"
a = "l1"
alpha = 0.0
d = 0.0
theta = 0.0
[[joints]]
name = "q2"
type = "revolute"
a = "l2"
alpha = 0.0
d = 0.0
theta = 0.0
lower = 0.0
upper = 170.0
[[joints]]
name = "z"
type = "prismatic"
a = 0.0
alpha = 0.0
d = 0.0
theta = 0.0
lower = -0.1
upper = 0.1
"""


def write(tmp_path, text=PLANAR):
    path = tmp_path / "planar.toml"
    path.write_text(text)
    return path


def test_kin_file_json_has_the_built_ins_keys_and_the_files(tmp_path, capsys):
    path = write(tmp_path)
    code, out, err = cli(capsys, "kin", str(path), "--json", "--q", "0.3,1.0,0.05", "--set", "l2=0.25")
    assert code == 0, err
    report = json.loads(out)
    assert report["robot"] == "planar" and report["file"] == str(path) and report["lengths"] == {"l1": 0.3, "l2": 0.25}
    assert [r["kind"] for r in report["dh"]] == ["revolute", "revolute", "prismatic"] and report["dh"][1]["a"] == 0.25
    # Position rows of a 3-joint chain: det of Jv; here the arm's planar det l1 l2 sin q2 (z only slides).
    assert report["det"] == pytest.approx(0.3 * 0.25 * math.sin(1.0), rel=1e-12)
    assert report["singular"] == {"rank_deficient": False} and report["sigma_min"] > 0
    np.testing.assert_allclose(report["T0n"][0][3], 0.3 * math.cos(0.3) + 0.25 * math.cos(1.3), atol=1e-15)


def test_kin_file_ik_finds_the_elbow_in_range_and_says_how(tmp_path, capsys):
    path = write(tmp_path)
    x, y = 0.3 * math.cos(0.2) + 0.2 * math.cos(0.9), 0.3 * math.sin(0.2) + 0.2 * math.sin(0.9)
    code, out, err = cli(capsys, "kin", str(path), f"--target={x!r},{y!r},0.05", "--deg")
    assert code == 0, err
    assert "IK for target" in out and "1 solution(s)" in out and "numeric: Levenberg-Marquardt" in out
    assert "q = (11.4591559, 40.1070457, 0.05)" in out  # (0.2, 0.7) rad: the elbow with q2 >= 0, in its range
    code, out, err = cli(capsys, "kin", str(path), "--json", "--target=0.35,0.2,0.0")
    sols = json.loads(out)["solutions"]
    assert code == 0 and len(sols) == 1 and sols[0]["position_residual"] <= 1e-10


def test_kin_file_refusals_are_one_line(tmp_path, capsys):
    path = write(tmp_path)
    for argv, message in (
        (["--target=2,0,0"], "no solution within the joint ranges from 576 seeds (closest: "),
        (["--target=0.1,0.2,0.3,0,0,0"], "planar needs --target x,y,z (m) (a chain of fewer than 6 joints"),
        (["--set", "l3=0.1"], "unknown length 'l3' for planar; known: l1, l2"),
        (["--q", "1,2"], "planar has 3 joints (q1 [rad], q2 [rad], z [m]); got 2 values"),
    ):
        code, out, err = cli(capsys, "kin", str(path), *argv)
        assert code == 2 and out == "" and err.count("\n") == 1 and message in err, err
    free = write(tmp_path, PLANAR.replace("lower = -0.1\nupper = 0.1\n", ""))
    code, _, err = cli(capsys, "kin", str(free), "--target=0.3,0.2,0.0")
    assert code == 2 and f"planar ({free})" in err and "joint 'z' is prismatic without 'lower' and 'upper'" in err


ARM7 = ((0, 0.34), (-90, 0), (90, 0.4), (90, 0), (-90, 0.4), (-90, 0), (90, 0.126))  # (alpha [deg], d [m]) per row


def test_a_seven_joint_file_samples_its_family_and_warns(tmp_path, capsys):
    rows = "".join(
        f'[[joints]]\nname = "j{i}"\ntype = "revolute"\na = 0.0\nalpha = {a}\nd = {d}\ntheta = 0.0\n'
        f"lower = -170.0\nupper = 170.0\n"
        for i, (a, d) in enumerate(ARM7, start=1)
    )
    path = tmp_path / "seven.toml"
    path.write_text(f'name = "seven"\nconvention = "modified"\nangles = "deg"\n{rows}[tool]\nxyz = [0.0, 0.0, 0.05]\n')
    chain = robots.resolve(path).chain()
    q = np.radians([10, 20, 30, 40, 50, 60, 70])
    pose = chain.fk(q)
    rot = pose[:3, :3]
    rpy = [math.atan2(rot[2, 1], rot[2, 2]), -math.asin(rot[2, 0]), math.atan2(rot[1, 0], rot[0, 0])]
    target = ",".join(repr(float(v)) for v in [*pose[:3, 3], *rpy])
    code, out, err = cli(capsys, "kin", str(path), "--json", f"--target={target}")
    assert code == 0 and "seven has 7 joints for 6 task coordinates: its solutions form a family of dimension 1" in err
    report = json.loads(out)
    assert 2 <= len(report["solutions"]) <= 16 and "manipulability" not in report
    for s in report["solutions"]:
        assert s["position_residual"] <= 1e-10 and s["orientation_residual"] <= 1e-10
        np.testing.assert_allclose(chain.fk(np.array(s["q"])), pose, atol=1e-9)


@pytest.mark.parametrize(
    ("joints", "target", "span", "dimension"),
    [
        # Three revolute joints about parallel axes: x and y only (found by fuzzing: "16 solution(s)", each "singular").
        ([("revolute", 0.1, "")] * 3, "0.1,0.05,0", 2, 1),
        # Three slides along z0: z only.
        (
            [("prismatic", 0.0, "lower = 0.0\nupper = 1.0\n")] * 2 + [("prismatic", 0.1, "lower = 0.0\nupper = 1.0\n")],
            "0.1,0,0.5",
            1,
            2,
        ),
    ],
)
def test_a_chain_whose_joints_span_fewer_task_coordinates_samples_its_family(tmp_path, capsys, joints, target, span,
                                                                            dimension):  # fmt: skip
    rows = "".join(
        f'[[joints]]\nname = "j{i}"\ntype = "{kind}"\na = {a}\nalpha = 0.0\nd = 0.0\ntheta = 0.0\n{limits}'
        for i, (kind, a, limits) in enumerate(joints, start=1)
    )
    path = tmp_path / "flat.toml"
    path.write_text(f'name = "flat"\nconvention = "standard"\nangles = "deg"\n{rows}')
    code, out, err = cli(capsys, "kin", str(path), "--json", f"--target={target}")
    assert code == 0, err
    family = f"flat has 3 joints whose motions span only {span} of the 3 task coordinates: its solutions form a family"
    assert f"{family} of dimension {dimension}" in err
    assert "singular configuration" not in err  # the family's zero singular value is not a singularity
    chain = robots.resolve(path).chain()
    goal = np.array([float(v) for v in target.split(",")])
    for solution in json.loads(out)["solutions"]:
        np.testing.assert_allclose(chain.fk(np.array(solution["q"]))[:3, 3], goal, atol=1e-9)


@pytest.mark.skipif(importlib.util.find_spec("sympy") is None, reason="needs sympy (the 'symbolic' extra)")
def test_symbolic_works_for_a_file_with_its_lengths_as_symbols(tmp_path, capsys):
    code, out, err = cli(capsys, "kin", str(write(tmp_path)), "--json", "--symbolic")
    assert code == 0, err
    t0n = json.loads(out)["symbolic"]["T0n"]
    assert "c1*l1 + c12*l2" in t0n and "l1*s1 + l2*s12" in t0n and "z" in t0n


@pytest.mark.parametrize("name", ["c1", "s12", "pi", "I"])
def test_a_length_named_as_an_abbreviation_or_a_constant_is_refused(tmp_path, capsys, name):
    """A length "c1" printed "c1*c1 + c12*l2" in --symbolic (c1 times cos q1, read as cos² q1), one named "pi" as π
    in the LaTeX: refused in one line, as "l-1" is."""
    code, out, err = cli(capsys, "kin", str(write(tmp_path, PLANAR.replace("l1", name))))
    assert code == 2 and out == "" and err.count("\n") == 1, err
    assert f"[lengths]: the length name '{name}' would be misread in --symbolic, where c1, s23 are cos and sin" in err


@pytest.mark.skipif(importlib.util.find_spec("sympy") is None, reason="needs sympy (the 'symbolic' extra)")
@pytest.mark.parametrize("name", ["c1", "pi"])
def test_a_slide_named_as_an_abbreviation_or_a_constant_gets_its_index_symbol(tmp_path, capsys, name):
    """A prismatic joint's own name is its symbol: "c1" printed T0n[3, 4] = c1 (read as cos q1), "pi" as π."""
    code, out, err = cli(capsys, "kin", str(write(tmp_path, PLANAR.replace('name = "z"', f'name = "{name}"'))),
                         "--json", "--symbolic")  # fmt: skip
    assert code == 0, err
    symbolic = json.loads(out)["symbolic"]
    assert symbolic["T0n"].splitlines()[4].split()[-2:] == ["d3", "]"]
    assert "\\pi" not in symbolic["T0n_latex"] and "d_{3}" in symbolic["T0n_latex"]


@pytest.mark.skipif(importlib.util.find_spec("sympy") is None, reason="needs sympy (the 'symbolic' extra)")
def test_symbolic_adds_up_fixed_rows_and_the_tool_and_keeps_a_range_between_lengths(tmp_path, capsys):
    """A fixed row a = "l3" and [tool] xyz = ["lt", 0, 0] printed c1*(l1 + 0.566874112152667): the marker values of
    l3 + lt, not their sum; a slide's range lower = "lo", upper = "hi" with hi declared first was refused as "lower
    limit 0.247 exceeds upper limit 0.202" (the markers' values, in another order than the lengths')."""
    text = PLANAR.replace("l2 = { value", "hi = 0.15\nlo = 0.05\nl3 = 0.12\nlt = 0.05\nl2 = { value")
    text = text.replace("lower = -0.1\nupper = 0.1", 'lower = "lo"\nupper = "hi"')
    text += '[[joints]]\nname = "foot"\ntype = "fixed"\na = "l3"\nalpha = 0.0\nd = 0.0\ntheta = 0.0\n'
    text += '[tool]\nxyz = ["lt", 0.0, 0.0]\n'
    code, out, err = cli(capsys, "kin", str(write(tmp_path, text)), "--json", "--symbolic")
    assert code == 0, err
    t0n = json.loads(out)["symbolic"]["T0n"]
    assert "c1*l1 + c12*l2 + c12*l3 + c12*lt" in t0n and "l1*s1 + l2*s12 + l3*s12 + lt*s12" in t0n, t0n


@pytest.mark.skipif(importlib.util.find_spec("sympy") is None, reason="needs sympy (the 'symbolic' extra)")
def test_symbolic_stops_in_bounded_time_when_the_closed_form_explodes(tmp_path, capsys, monkeypatch):
    """General twists multiply the terms at every joint: 7 joints at 37 deg ran for minutes; now a one-line refusal
    once a T0i passes symbolic.MAX_OPS operations (made small here so the test is fast)."""
    from hexabot_sim.kinematics import symbolic

    odd = PLANAR.replace("alpha = 0.0", "alpha = 37.0").replace("theta = 0.0", "theta = 11.0")
    monkeypatch.setattr(symbolic, "MAX_OPS", 60)
    code, out, err = cli(capsys, "kin", str(write(tmp_path, odd)), "--symbolic")
    assert code == 2 and out == "" and err.count("\n") == 1, err
    assert "closed form grows too large to simplify in reasonable time: T02 already has" in err
    assert "(at most 60: each joint multiplies the terms" in err and "use --q for T0n and J at a configuration" in err


@pytest.mark.skipif(importlib.util.find_spec("sympy") is None, reason="needs sympy (the 'symbolic' extra)")
def test_the_package_robots_stay_far_below_the_symbolic_limit():
    from hexabot_sim.kinematics import symbolic

    for name in robots.ROBOTS:
        chain = symbolic.symbolic_chain(name)
        poses = symbolic.transforms(chain, max_ops=symbolic.MAX_OPS // 4)
        assert len(poses) == chain.n + 1


def test_kin_leg_lists_report_000s_foot_row(capsys):
    code, out, _ = cli(capsys, "kin", "leg", "--set", "l3=0.12")
    assert code == 0
    assert out.splitlines()[6].split() == ["foot", "fixed", "0.000000", "0.000000", "0.120000", "0.000000"]


def test_orientation_residual_is_the_angle_the_tool_is_turned_by():
    """A solution turned by delta about one wrist axis is off the target by exactly |delta| (Stanford: theta6,
    SCARA: theta4): the residual is measured, not copied from the solver."""
    for name, joint, target in (
        ("stanford", 5, [-0.4316, -0.0032, 0.6038, 0.2, -0.3, 0.4]),
        ("scara", 3, [0.6329, 0.0735, 0.25, 0.5]),
    ):
        robot = kinreport.resolve(name, {})
        solved = kinreport.solve(robot, target)
        goal = kinreport._target(robot, target, degrees=False)
        for sol in solved["solutions"]:
            assert sol["orientation_residual"] <= 1e-12
            q = np.array(sol["q"])
            q[joint] += 0.01
            assert kinreport._orientation_residual(robot, q, goal) == pytest.approx(0.01, rel=1e-9)
