"""A run's output streams and helpers: full or closed stdout and stderr, broken GL, a missing or failing video encoder,
progress lines, the version."""

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest
from helpers import cli, one_line_error

from hexabot_sim import output, params, registry
from hexabot_sim.__main__ import main
from hexabot_sim.robots.pendulum.pendulum import PendulumParams

FAST = ["--set", "duration=0.05", "--no-plots"]


def _run_cli(tmp_path, *argv, env=None, **kwargs):
    streams = {} if "stdout" in kwargs else {"stdout": subprocess.PIPE}
    return subprocess.run(
        [sys.executable, "-m", "hexabot_sim", *argv],
        cwd=tmp_path,
        stderr=subprocess.PIPE,
        text=True,
        **streams,
        env=dict(os.environ, **(env or {})),
        timeout=300,
        **kwargs,
    )


@pytest.mark.slow
def test_stdout_full_or_closed(tmp_path):
    with open("/dev/full", "w") as full:
        proc = _run_cli(tmp_path, "run", "pendulum", *FAST, "--out", "r", stdout=full)
    assert proc.returncode == 1
    assert "standard output" in one_line_error(proc.stderr) and "complete" in proc.stderr
    assert (tmp_path / "r" / "run.json").exists()
    with open("/dev/full", "w") as full:
        proc = _run_cli(tmp_path, "list", stdout=full)
    assert proc.returncode == 1 and "No space left" in one_line_error(proc.stderr)
    proc = subprocess.run(
        f"{sys.executable} -m hexabot_sim list >&-", shell=True, cwd=tmp_path, capture_output=True, text=True
    )
    assert proc.returncode == 1 and "closed" in one_line_error(proc.stderr)
    proc = subprocess.run(
        f"{sys.executable} -m hexabot_sim list | head -1", shell=True, cwd=tmp_path, capture_output=True, text=True
    )
    assert proc.returncode == 0 and proc.stderr == ""


@pytest.mark.slow
def test_broken_mujoco_gl_does_not_break_commands_without_video(tmp_path):
    for value in ("nonsense", "osmesa"):
        env = {"MUJOCO_GL": value}
        for argv in (["list"], ["check"], ["run", "pendulum", *FAST, "--out", f"r-{value}"], ["kin", "leg"]):
            proc = _run_cli(tmp_path, *argv, env=env)
            assert proc.returncode == 0, (argv, proc.stderr)
            assert "Traceback" not in proc.stderr
    assert not (tmp_path / "MUJOCO_LOG.TXT").exists()


@pytest.mark.slow
def test_broken_mujoco_gl_falls_back_for_video_and_says_so(tmp_path):
    from hexabot_sim import gl

    if gl.probe("egl") is not None:
        pytest.skip("no EGL here to fall back to")
    proc = _run_cli(tmp_path, "run", "pendulum", *FAST, "--video", "--out", "r", env={"MUJOCO_GL": "nonsense"})
    assert proc.returncode == 0, proc.stderr
    assert "MUJOCO_GL='nonsense' does not work" in proc.stderr and "rendering with egl" in proc.stderr
    assert json.loads((tmp_path / "r" / "run.json").read_text())["video"]["gl_backend"] == "egl"
    assert not (tmp_path / "MUJOCO_LOG.TXT").exists()


@pytest.mark.slow
def test_missing_ffmpeg_still_gives_csv_and_plots(tmp_path):
    proc = _run_cli(
        tmp_path, "run", "pendulum", "--set", "duration=0.2", "--video", "--out", "r",
        env={"IMAGEIO_FFMPEG_EXE": str(tmp_path / "no-ffmpeg")},
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    lines = [line for line in proc.stderr.splitlines() if "no video" in line]
    assert len(lines) == 1 and "ffmpeg" in lines[0]
    record = json.loads((tmp_path / "r" / "run.json").read_text())
    assert record["video"]["written"] is False and "ffmpeg" in record["video"]["reason"]
    assert {"timeseries.csv", "angle_velocity.png"} <= {p.name for p in (tmp_path / "r").iterdir()}
    assert not (tmp_path / "r" / "video.mp4").exists()


STUCK_ENCODERS = {
    "python": f"#!{sys.executable}\nimport sys, time\n"
    "if sys.argv[1:] == ['-version']:\n    print('ffmpeg version 6.0 (a stuck fake)')\n    sys.exit(0)\n"
    "time.sleep(600)\n",
    # Found by fuzzing: an encoder that exec's something else was not recognised (argv no longer the encoder's), and
    # a wrapper's child holding the pipe kept the run blocked after the wrapper was killed.
    "exec": '#!/bin/sh\n[ "$1" = -version ] && { echo "ffmpeg version 6.0 (a stuck fake)"; exit 0; }\nexec sleep 613\n',
    "wrapper": '#!/bin/sh\n[ "$1" = -version ] && { echo "ffmpeg version 6.0 (a stuck fake)"; exit 0; }\nsleep 613\n',
}


@pytest.mark.slow
@pytest.mark.parametrize("kind", sorted(STUCK_ENCODERS))
def test_an_encoder_that_stops_reading_does_not_hang_the_run(tmp_path, monkeypatch, capsys, kind):
    """An 'ffmpeg' that answers -version and then never reads its frames: the stuck write is stopped after
    FRAME_TIMEOUT, the run keeps its CSV and says why there is no video, and the encoder is gone."""
    from hexabot_sim import render

    fake = tmp_path / "stuck-ffmpeg"
    fake.write_text(STUCK_ENCODERS[kind])
    fake.chmod(0o755)
    monkeypatch.setenv("IMAGEIO_FFMPEG_EXE", str(fake))
    monkeypatch.setattr(render, "FRAME_TIMEOUT", 1.0)
    started = time.monotonic()
    out = str(tmp_path / "r")
    assert main(["run", "pendulum", "--set", "duration=0.5", "--video", "--out", out, "--no-plots"]) == 0
    assert time.monotonic() - started < 60
    record = json.loads((tmp_path / "r" / "run.json").read_text())
    assert record["video"] == {
        "written": False,
        "reason": "rendering failed: RuntimeError: the video encoder took no frame for 1 s and was stopped",
    }
    assert (tmp_path / "r" / "timeseries.csv").exists() and not (tmp_path / "r" / "video.mp4").exists()
    assert "no video: rendering failed" in capsys.readouterr().err
    left = [
        p for p in Path("/proc").glob("[0-9]*") if str(fake).encode() in _cmdline(p) or _cmdline(p) == b"sleep\0613\0"
    ]
    assert not left  # killed, not left


def _cmdline(proc: Path) -> bytes:
    try:
        return (proc / "cmdline").read_bytes()
    except OSError:
        return b""


@pytest.mark.slow
def test_no_mujoco_log_dropped_on_divergence(tmp_path):
    proc = _run_cli(tmp_path, "run", "pendulum", "--set", "stiffness=1e4", "--set", "timestep=0.05", "--out", "r")
    assert proc.returncode == 1 and "diverged" in one_line_error(proc.stderr)
    assert list(tmp_path.iterdir()) == []


def test_version(capsys):
    import hexabot_sim

    code, out, _ = cli(capsys, "--version")
    assert code == 0 and out.strip() == f"hexabot-sim {hexabot_sim.__version__}"


@pytest.mark.parametrize("size", ["641x481", "640x48", "48x640", "10x10", "4000x2000", "640x", "axb"])
def test_video_size_refused(tmp_path, capsys, size):
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--video", "--size", size, "--out", str(tmp_path / "r"))
    assert code == 2
    assert "--size" in one_line_error(err) or "WIDTHxHEIGHT" in err or "even" in err or "aspect" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_progress_lines_when_stderr_is_not_a_terminal(tmp_path):
    proc = _run_cli(tmp_path, "run", "leg-step", "--set", "mode=kinematic", "--no-plots", "--out", "r")
    assert proc.returncode == 0, proc.stderr
    progress = [line for line in proc.stderr.splitlines() if line.startswith("leg-step:")]
    assert 2 <= len(progress) <= 6 and progress[-1].startswith("leg-step: 100%")
    assert "\r" not in proc.stderr


@pytest.mark.slow
def test_closed_stderr_keeps_the_exit_code(tmp_path):
    read, write = os.pipe()
    os.close(read)
    try:
        proc = subprocess.run(
            [sys.executable, "-m", "hexabot_sim", "run", "pendulum", "--set", "dampin=1"], cwd=tmp_path, stderr=write
        )
    finally:
        os.close(write)
    assert proc.returncode == 2


@pytest.mark.parametrize("full", [True, False])
def test_an_encoder_failure_on_a_full_disk_fails_the_run(tmp_path, monkeypatch, full):
    """ffmpeg that runs out of disk dies with a broken pipe, which does not say why: with the disk full the run
    fails as out of disk (nothing written); otherwise the run keeps its CSV and names the first line of the error
    (it named the last, 'FFMPEG STDERR OUTPUT:', found by fuzzing)."""
    from hexabot_sim import render

    def broken(*args, **kwargs):
        raise OSError("[Errno 32] Broken pipe\n\nFFMPEG COMMAND:\nffmpeg -y ...\n\nFFMPEG STDERR OUTPUT:\n")

    monkeypatch.setattr(render, "render_video", broken)
    monkeypatch.setattr(output, "disk_full", lambda folder: full)  # what write_run calls
    result = registry.get("pendulum").runner("pendulum", params.resolve(PendulumParams, {}, {"duration": 0.2}))
    folder = tmp_path / "r"
    folder.mkdir()
    settings = output.VideoSettings()
    if full:
        with pytest.raises(OSError, match="No space left on device"):
            output.write_video(folder, result, settings, "egl")
    else:
        video, _ = output.write_video(folder, result, settings, "egl")
        assert video == {"written": False, "reason": "rendering failed: OSError: [Errno 32] Broken pipe"}


def test_closed_standard_streams_are_reopened_for_children_too(tmp_path):
    # os.open's descriptors are not inheritable: a child started with no stderr fails (glfw's library probe did,
    # and `view` with stderr closed said that glfw was not installed).
    code = (
        "import subprocess, sys\n"
        "from hexabot_sim.cli import _ensure_std_streams\n"
        "_ensure_std_streams()\n"
        "probe = 'import os, sys; [os.fstat(fd) for fd in (0, 1, 2)]; input(); sys.stderr.write(\"x\")'\n"
        "sys.exit(subprocess.run([sys.executable, '-c', probe], input=b'\\n', stdout=subprocess.PIPE).returncode)\n"
    )
    proc = subprocess.run(f"{sys.executable} -c \"$CODE\" 2>&- <&-", shell=True, cwd=tmp_path,
                          env={**os.environ, "CODE": code}, timeout=120)  # fmt: skip
    assert proc.returncode == 0


def test_run_progress_in_logs_speaks_at_least_once_a_minute(monkeypatch):
    """Issue 17: a run may take up to an hour, and its log lines came only at every quarter (15 min of silence)."""
    import io
    import time

    from hexabot_sim.cli.progress import ProgressBar

    monkeypatch.setattr(ProgressBar, "PLAIN_SECONDS", 0.5)
    stream = io.StringIO()
    bar = ProgressBar("slow", stream)
    bar(0, 1000)
    time.sleep(0.6)
    bar(3, 1000)
    bar(4, 1000)  # not again at once
    assert stream.getvalue().splitlines() == ["slow: 0% (0/1000)", "slow: 0% (3/1000)"], stream.getvalue()
