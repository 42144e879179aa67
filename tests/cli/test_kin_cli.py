"""`hexabot-sim kin ROBOT`: T0n, J, singular flags and IK branches, text and JSON, and its bad input."""

import json

import numpy as np
import pytest

from hexabot_sim.__main__ import main
from hexabot_sim.kinematics import robots


def run_json(capsys, *argv):
    code = main(["kin", *argv, "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    return json.loads(out)


@pytest.mark.parametrize("robot", ["rrp", "elbow", "stanford", "scara", "leg"])
def test_configuration_report_matches_the_chain(capsys, robot):
    chain = robots.get(robot).chain()
    q = np.linspace(0.1, 0.6, chain.n)
    report = run_json(capsys, robot, "--q", ",".join(repr(float(v)) for v in q))
    assert np.allclose(report["T0n"], chain.fk(q), atol=1e-15)
    assert np.allclose(report["J"], chain.jacobian(q), atol=1e-15)
    assert ("det" in report) != ("manipulability" in report)
    assert isinstance(report["singular"], dict) and report["singular_sets"]


def test_rrp_singular_flag_at_zero_reach(capsys):
    report = run_json(capsys, "rrp", "--q", "0.3,0.2,-1")  # a2 + d3 = 0
    assert report["is_singular"] and report["det"] == pytest.approx(0.0, abs=1e-15)


def test_ik_branches_reach_the_target(capsys):
    chain = robots.get("elbow").chain()
    target = chain.fk([0.4, 0.5, -0.7])[:3, 3]
    report = run_json(capsys, "elbow", "--target", ",".join(repr(float(v)) for v in target))
    assert len(report["solutions"]) == 4
    for sol in report["solutions"]:
        assert np.allclose(chain.fk(sol["q"])[:3, 3], target, atol=1e-10)


def test_lengths_via_set(capsys):
    report = run_json(capsys, "rrp", "--set", "d1=2", "--q", "0,0,0")
    assert report["lengths"]["d1"] == 2.0 and report["T0n"][2][3] == pytest.approx(2.0)


def test_text_output(capsys):
    assert main(["kin", "scara", "--q", "0.1,0.2,0.1,0.3"]) == 0
    out = capsys.readouterr().out
    assert "T0n" in out and "J (6 x n" in out and "singular" in out


@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        (["kin", "puma"], "unknown robot 'puma'; known: rrp, elbow, stanford, scara, leg"),
        (["kin", "rrp", "--q", "0.1,0.2"], "rrp has 3 joints (q1 [rad], q2 [rad], d3 [m]); got 2 values"),
        (["kin", "rrp", "--q", "a,b,c"], "--q must be comma-separated numbers"),
        (["kin", "rrp", "--q", "nan,0,0"], "--q must be finite numbers"),
        (["kin", "rrp", "--q", "1_0,0,0"], "--q must be comma-separated numbers; got '1_0,0,0'"),  # float(): 10
        (["kin", "rrp", "--set", "d1=0_5"], "length 'd1' must be comma-separated numbers; got '0_5'"),  # was 5 m
        (["kin", "elbow", "--target", "5,5,5"], "out of reach"),
        (["kin", "rrp", "--set", "d9=1"], "unknown length 'd9' for rrp"),
        (["kin", "rrp", "--set", "d1=-1"], "length 'd1' of rrp must be 0.001 to 10 m; got -1.0"),
        (["kin", "elbow", "--set", "d=1e-300"], "length 'd' of elbow must be 0 or 0.001 to 10 m; got 1e-300"),
        (["kin", "stanford", "--target", "0.1,0.2,0.3"], "stanford needs --target x,y,z,roll,pitch,yaw"),
    ],
)
def test_bad_input_exit_2_one_line(capsys, argv, fragment):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("hexabot-sim: error: ") and err.count("\n") == 1 and fragment in err, err


def test_symbolic_output(capsys):
    pytest.importorskip("sympy")
    report = run_json(capsys, "leg", "--symbolic")
    assert "c23" in report["symbolic"]["T0n"] and "c_{23}" in report["symbolic"]["T0n_latex"]
    assert "s1" in report["symbolic"]["J"]


def test_symbolic_text_output_has_latex_too(capsys):
    pytest.importorskip("sympy")
    assert main(["kin", "leg", "--symbolic"]) == 0
    out = capsys.readouterr().out
    assert "symbolic T0n:" in out and "c23" in out and "T0n (LaTeX):" in out and "c_{23}" in out
