"""The command line through main([...]): run folders, exit codes, one-line errors, determinism."""

import json
import subprocess
import sys

import mujoco
import numpy as np
import pytest

from hexabot_sim import gl
from hexabot_sim.__main__ import main
from hexabot_sim.budget import step_count
from hexabot_sim.simulate import simulate

SHORT = ["--set", "duration=1"]


def run_ok(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    assert code == 0, err
    return out, err


@pytest.mark.slow
def test_run_folder_contents(tmp_path, capsys):
    out_dir = tmp_path / "run"
    out, _ = run_ok(capsys, "run", "pendulum", "--out", str(out_dir))
    names = {p.name for p in out_dir.iterdir()}
    assert names == {
        "timeseries.csv",
        "run.json",
        "model.xml",
        "trajectory.npz",
        "angle_velocity.png",
        "phase.png",
        "energy.png",
        "report.html",
    }
    record = json.loads((out_dir / "run.json").read_text())
    assert {"scenario", "params", "metrics", "versions"} <= set(record)
    assert record["scenario"] == "pendulum"
    assert record["params"]["damping"] == 0.01 and record["units"]["params"]["damping"] == "N*m*s/rad"
    assert record["versions"]["mujoco"] == mujoco.__version__
    assert record["video"]["written"] is False
    assert abs(record["metrics"]["final_theta_deg"] - record["metrics"]["rest_angle_predicted_deg"]) < 1e-3
    header = (out_dir / "timeseries.csv").read_text().splitlines()[0].split(",")
    assert header[:3] == ["t", "theta", "omega"]
    assert {"energy_kinetic", "energy_gravity", "energy_spring", "energy_dissipated", "energy_total"} <= set(header)
    assert record["units"]["columns"]["t"] == "s"
    # The summary names the folder and the key metrics.
    assert "rest_angle_predicted_deg" in out and str(out_dir.name) in out
    # The full recorded state, reloadable with numpy alone.
    traj = np.load(out_dir / "trajectory.npz")
    assert set(traj.files) == {"t", "qpos", "qvel", "ctrl"} and traj["qpos"].shape == (len(traj["t"]), 1)
    table = np.loadtxt(out_dir / "timeseries.csv", delimiter=",", skiprows=1)
    assert np.array_equal(traj["qpos"][:, 0], table[:, 1]) and np.array_equal(traj["t"], table[:, 0])
    for png in ("angle_velocity.png", "phase.png", "energy.png"):
        assert (out_dir / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_model_xml_reproduces_the_run(tmp_path, capsys):
    out_dir = tmp_path / "run"
    run_ok(capsys, "run", "pendulum", "--out", str(out_dir), "--no-plots", "--set", "mass=0.123456789", *SHORT)
    table = np.loadtxt(out_dir / "timeseries.csv", delimiter=",", skiprows=1)
    model = mujoco.MjModel.from_xml_path(str(out_dir / "model.xml"))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    traj = simulate(model, data, step_count(1.0, model.opt.timestep))
    assert np.array_equal(traj.qpos[:, 0], table[:, 1])
    assert np.array_equal(traj.qvel[:, 0], table[:, 2])


def test_same_command_twice_gives_identical_csv(tmp_path, capsys):
    for name in ("a", "b"):
        run_ok(capsys, "run", "pendulum-damped", "--out", str(tmp_path / name), "--no-plots", *SHORT)
    assert (tmp_path / "a" / "timeseries.csv").read_bytes() == (tmp_path / "b" / "timeseries.csv").read_bytes()


def test_config_file_and_set_precedence(tmp_path, capsys):
    config = tmp_path / "c.toml"
    config.write_text("mass = 0.2\nduration = 0.5\nstiffness = 1.0\n")
    run_ok(
        capsys,
        "run",
        "pendulum",
        "--config",
        str(config),
        "--set",
        "mass=0.3",
        "--out",
        str(tmp_path / "r"),
        "--no-plots",
    )
    record = json.loads((tmp_path / "r" / "run.json").read_text())
    assert (
        record["params"]["mass"] == 0.3 and record["params"]["stiffness"] == 1.0 and record["params"]["duration"] == 0.5
    )


@pytest.mark.slow
def test_a_config_reads_the_schedule_beside_it_from_any_working_folder(tmp_path, capsys, monkeypatch):
    study = tmp_path / "study"
    study.mkdir()
    (study / "sched.csv").write_text("t, vx, vy, yaw_rate\n0, 0.05, 0, 0\n2, 0.08, 0, 0\n")
    (study / "walk.toml").write_text('schedule = "sched.csv"\nduration = 2.5\n')
    monkeypatch.chdir(tmp_path)
    run_ok(capsys, "run", "hexabot-walk", "--config", "study/walk.toml", "--out", "r", "--no-plots")
    record = json.loads((tmp_path / "r" / "run.json").read_text())
    assert [row[:4] for row in record["params"]["schedule"]] == [[0.0, 0.05, 0.0, 0.0], [2.0, 0.08, 0.0, 0.0]]


def test_default_folder_under_runs(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    run_ok(capsys, "run", "pendulum-undamped", "--no-plots", *SHORT)
    (folder,) = (tmp_path / "runs").iterdir()
    assert folder.name.startswith("pendulum-undamped-") and (folder / "timeseries.csv").is_file()


def _bad_inputs(tmp_path):
    not_a_dir = tmp_path / "plain-file"
    not_a_dir.write_text("x")
    bad_toml = tmp_path / "bad.toml"
    bad_toml.write_text("mass = = 2\n")
    return [
        (["run", "pendulum-typo"], "unknown scenario 'pendulum-typo'; known: pendulum-undamped"),
        (["run", "pendulum", "--set", "dampin=0.1"], "unknown parameter 'dampin'; known:"),
        (["run", "pendulum", "--set", "damping"], "malformed --set 'damping': expected name=value"),
        (
            ["run", "pendulum", "--set", "mass=heavy"],
            "'mass' must be a number with 0.001 <= mass <= 1000 kg; got 'heavy'",
        ),
        (["run", "pendulum", "--set", "mass=nan"], "'mass' must be a number with 0.001 <= mass <= 1000 kg; got 'nan'"),
        (
            ["run", "pendulum", "--set", "length=inf"],
            "'length' must be a number with 0.01 <= length <= 100 m; got 'inf'",
        ),
        (["run", "pendulum", "--set", "damping=-0.01"], "'damping' must be a number with 0 <= damping"),
        (["run", "pendulum", "--set", "duration=0"], "'duration' must be a number with 0 < duration"),
        (["run", "pendulum", "--set", "timestep=0"], "'timestep' must be a number with 1e-06 <= timestep"),
        (["run", "pendulum", "--set", "mass=-1"], "'mass' must be a number with 0.001 <= mass"),
        (["run", "pendulum", "--set", "integrator=RK45"], "'integrator' must be one of RK4, Euler"),
        (["run", "pendulum", "--config", str(tmp_path / "missing.toml")], "missing.toml' not found"),
        (["run", "pendulum", "--config", str(bad_toml)], "is not valid TOML"),
        (["run", "pendulum", "--out", str(not_a_dir / "sub")], "is not a folder"),
        (["run", "pendulum", "--out", str(not_a_dir)], "exists and is not a folder"),
        (["run", "pendulum", "--quality", "ultra"], "invalid choice: 'ultra'"),
        (["run", "pendulum", "--size", "big"], "expected WIDTHxHEIGHT"),
        (["run", "pendulum", "--fps", "0"], "frames per second from 1 to 240"),
        (["run"], "the following arguments are required: scenario"),
        (["fly"], "invalid choice: 'fly'"),
        # A value option given twice: argparse kept the last without a word (the first --out was dropped).
        (["run", "pendulum", "--out", "a", "--out", "b"], "argument --out: given more than once; give it once"),
        (["kin", "elbow", "--q", "0,0,0", "--q", "1,1,1"], "argument --q: given more than once; give it once"),
        (["sweep", "pendulum", "--grid", "mass=1,2", "--workers", "1", "--workers", "2"], "argument --workers: given"),
    ]


def test_bad_input_exit_2_one_line_nothing_written(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for argv, fragment in _bad_inputs(tmp_path):
        before = sorted(p.name for p in tmp_path.rglob("*"))
        code = main([*argv, "--no-plots"] if argv[0] == "run" and len(argv) > 1 else argv)
        _out, err = capsys.readouterr()
        assert code == 2, (argv, err)
        assert err.startswith("hexabot-sim: error: "), (argv, err)
        assert err.count("\n") == 1 and "Traceback" not in err, (argv, err)
        assert fragment in err, (argv, err)
        assert sorted(p.name for p in tmp_path.rglob("*")) == before, argv  # nothing written


def test_non_empty_out_is_refused_unless_forced(tmp_path, capsys):
    out_dir = tmp_path / "r"
    out_dir.mkdir()
    (out_dir / "keep.txt").write_text("mine")
    assert main(["run", "pendulum", "--out", str(out_dir), "--no-plots", *SHORT]) == 2
    assert "is not empty" in capsys.readouterr().err
    assert (out_dir / "keep.txt").exists()
    run_ok(capsys, "run", "pendulum", "--out", str(out_dir), "--no-plots", "--force", *SHORT)
    assert not (out_dir / "keep.txt").exists() and (out_dir / "timeseries.csv").exists()


def test_divergence_exit_1_names_time_and_cause_writes_nothing(tmp_path, capsys):
    out_dir = tmp_path / "r"
    code = main(["run", "pendulum", "--set", "stiffness=1e6", "--set", "timestep=0.01", "--out", str(out_dir)])
    _, err = capsys.readouterr()
    assert code == 1
    assert err.count("\n") == 1 and "simulation diverged after t = 0.01 s" in err and "QVEL" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_without_gl_csv_and_plots_are_still_written(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(gl, "choose", lambda: (None, "no working OpenGL (egl: test says no)", ""))
    out_dir = tmp_path / "r"
    code = main(["run", "pendulum-undamped", "--video", "--out", str(out_dir), *SHORT])
    _, err = capsys.readouterr()
    assert code == 0
    assert "no video: no working OpenGL (egl: test says no)" in err
    assert (out_dir / "timeseries.csv").exists() and (out_dir / "phase.png").exists()
    assert not (out_dir / "video.mp4").exists()
    record = json.loads((out_dir / "run.json").read_text())
    assert record["video"] == {"written": False, "reason": "no working OpenGL (egl: test says no)"}


def test_list_shows_scenarios_parameters_units(capsys):
    out, _ = run_ok(capsys, "list")
    for name in ("pendulum-undamped", "pendulum-damped", "pendulum"):
        assert f"\n{name}\n" in f"\n{out}"
    assert "mass" in out and "[kg]" in out and "[N*m*s/rad]" in out and "one of RK4" in out


@pytest.mark.slow
def test_check_reports_versions(capsys):
    out, _ = run_ok(capsys, "check")
    assert mujoco.__version__ in out and "gl egl" in out and "ffmpeg" in out


def test_real_process_bad_input_has_no_traceback(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "hexabot_sim", "run", "pendulum", "--set", "timestep=nan"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert proc.returncode == 2
    assert (
        proc.stderr
        == "hexabot-sim: error: parameter 'timestep' must be a number with 1e-06 <= timestep <= 0.1 s; got 'nan'\n"
    )
    assert list(tmp_path.iterdir()) == []
