"""rrp-velocity: the tool twist against the exact time derivative of report 001's H, and against MuJoCo."""

import json

import numpy as np
import pytest

from hexabot_sim import params, registry
from hexabot_sim.__main__ import main
from hexabot_sim.kinematics.robots import rrp_report_pose


@pytest.fixture(scope="module")
def result():
    s = registry.get("rrp-velocity")
    return s.runner("rrp-velocity", params.resolve(s.params_type, s.defaults))


def _rotation_vector(rot):
    angle = np.arccos(np.clip((np.trace(rot) - 1) / 2, -1, 1))
    axial = np.array([rot[2, 1] - rot[1, 2], rot[0, 2] - rot[2, 0], rot[1, 0] - rot[0, 1]]) / 2
    return axial if angle < 1e-12 else axial * angle / np.sin(angle)


@pytest.mark.slow
def test_linear_and_angular_velocity_are_the_time_derivative_of_the_reports_pose(result):
    c = result.columns
    t = c["t"]
    assert t[0] == 0 and t[-1] == pytest.approx(20.0)
    h = 1e-5
    worst_v, worst_w = 0.0, 0.0
    for i in range(0, len(t), 97):  # every 97th sample: ~200 instants over 0..20 s
        # q(t) of the report, written here independently, and H at t +- h.
        def q_at(s):
            return np.array([np.sin(s), np.cos(2 * s), np.sin(3 * s)])

        plus, minus = rrp_report_pose(q_at(t[i] + h), 1.0, 1.0), rrp_report_pose(q_at(t[i] - h), 1.0, 1.0)
        v = (plus[:3, 3] - minus[:3, 3]) / (2 * h)
        w = _rotation_vector(plus[:3, :3] @ minus[:3, :3].T) / (2 * h)
        worst_v = max(worst_v, np.max(np.abs(v - [c["vx"][i], c["vy"][i], c["vz"][i]])))
        worst_w = max(worst_w, np.max(np.abs(w - [c["wx"][i], c["wy"][i], c["wz"][i]])))
    assert worst_v <= 1e-6 and worst_w <= 1e-6


def test_matches_mujocos_site_velocity(result):
    c = result.columns
    for axis in ("vx", "vy", "vz", "wx", "wy", "wz"):
        assert np.max(np.abs(c[axis] - c[f"{axis}_mujoco"])) <= 1e-10, axis
    assert result.metrics["max_linear_diff_mujoco"].value <= 1e-10


def test_det_and_singular_instants(result):
    c = result.columns
    from hexabot_sim.kinematics import robots

    chain = robots.get("rrp").chain()
    for i in range(0, len(c["t"]), 1000):
        q = [c["q1"][i], c["q2"][i], c["d3"][i]]
        assert c["det_jv"][i] == pytest.approx(np.linalg.det(chain.jacobian(q)[:3]), abs=1e-12)
    # a2 + d3 = 1 + sin 3t vanishes at t = pi/2 + 2k pi/3: the reach-zero singularity, inside 0..20 s.
    expected = [np.pi / 2 + 2 * k * np.pi / 3 for k in range(10) if np.pi / 2 + 2 * k * np.pi / 3 <= 20]
    found = result.metrics["zero_reach_times"].value
    assert len(found) == len(expected)
    assert np.allclose(found, expected, atol=1e-3)


@pytest.mark.slow
def test_cli_run_folder(tmp_path, capsys):
    out = tmp_path / "rrp"
    assert main(["run", "rrp-velocity", "--set", "duration=2", "--out", str(out)]) == 0
    header = (out / "timeseries.csv").read_text().splitlines()[0].split(",")
    assert header[:10] == ["t", "q1", "q2", "d3", "dq1", "dq2", "dd3", "vx", "vy", "vz"]
    assert {"wx", "wy", "wz"} <= set(header)
    assert (out / "velocity.png").exists()
    record = json.loads((out / "run.json").read_text())
    assert record["params"] == {"d1": 1.0, "a2": 1.0, "duration": 2.0, "timestep": 0.001}
