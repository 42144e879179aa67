"""Run folders never destroy or lose anything: --out checks, concurrency, full disk, stdout."""

import errno
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest
from helpers import cli, staging_left

from hexabot_sim import folders, output, params, registry
from hexabot_sim.__main__ import main
from hexabot_sim.errors import OutputError, UsageError
from hexabot_sim.robots.pendulum.pendulum import PendulumParams

FAST = ["--set", "duration=0.05", "--no-plots"]


def one_line_error(err: str) -> str:
    """The single error line of stderr, progress lines ('pendulum: 50% (5/10)') aside."""
    lines = [line for line in err.strip().splitlines() if not re.match(r"^[\w-]+: \d+% \(\d+/\d+\)$", line)]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]


@pytest.mark.parametrize("target", [".", "..", "a/b/..", "a/.", "./", "sub/../.."])
def test_out_that_normalises_elsewhere_is_refused_even_with_force(tmp_path, monkeypatch, capsys, target):
    (tmp_path / "a" / "b").mkdir(parents=True)
    (tmp_path / "a" / "keep.txt").write_text("mine")
    (tmp_path / "thesis.tex").write_text("mine")
    monkeypatch.chdir(tmp_path)
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", target, "--force")
    assert code == 2
    assert "--out" in one_line_error(err) or "folder" in err
    assert (tmp_path / "a" / "keep.txt").read_text() == "mine"
    assert (tmp_path / "thesis.tex").read_text() == "mine"


def test_out_that_is_the_working_folder_or_its_parent_is_refused(tmp_path, monkeypatch, capsys):
    work = tmp_path / "project" / "here"
    work.mkdir(parents=True)
    (work / "notes.txt").write_text("mine")
    monkeypatch.chdir(work)
    for target in (str(work), str(tmp_path / "project"), "../here", "../../project"):
        code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", target, "--force")
        assert code == 2, target
        assert "working folder" in one_line_error(err)
    assert (work / "notes.txt").read_text() == "mine"


def test_symlinked_out_is_refused(tmp_path, capsys):
    real = tmp_path / "real"
    real.mkdir()
    (real / "data.txt").write_text("mine")
    (tmp_path / "link").symlink_to(real)
    (tmp_path / "dangling").symlink_to(tmp_path / "nowhere")
    for name in ("link", "dangling"):
        code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(tmp_path / name), "--force")
        assert code == 2
        assert "symbolic link" in one_line_error(err)
    assert (real / "data.txt").read_text() == "mine"
    assert not (tmp_path / "nowhere").exists()


def test_non_empty_out_needs_force_and_force_replaces_it(tmp_path, capsys):
    out = tmp_path / "run"
    out.mkdir()
    (out / "old.txt").write_text("old")
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(out))
    assert code == 2 and "not empty" in one_line_error(err)
    assert (out / "old.txt").exists()
    code, _, _ = cli(capsys, "run", "pendulum", *FAST, "--out", str(out), "--force")
    assert code == 0
    assert not (out / "old.txt").exists() and (out / "run.json").exists()
    assert staging_left(tmp_path) == []


def test_file_created_in_out_during_the_run_is_never_deleted(tmp_path, monkeypatch, capsys):
    """`run ... --out out &` then the user writes out/thesis.tex: the run must not delete it."""
    out = tmp_path / "out"
    scenario = registry.get("pendulum")
    real_runner = scenario.runner

    def runner_meanwhile_user_writes(*args, **kwargs):
        out.mkdir()
        (out / "thesis.tex").write_text("three years of work")
        return real_runner(*args, **kwargs)

    monkeypatch.setattr(type(scenario), "runner", property(lambda self: runner_meanwhile_user_writes))
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(out))
    assert code == 1
    assert "filled by someone else" in one_line_error(err)
    assert (out / "thesis.tex").read_text() == "three years of work"
    assert sorted(p.name for p in out.iterdir()) == ["thesis.tex"]
    assert staging_left(tmp_path) == []


def test_two_runs_publishing_to_the_same_out_never_replace_each_other(tmp_path):
    out = tmp_path / "same"
    with pytest.raises(OutputError, match="filled by someone else"):
        with folders.run_folder(out) as first:
            (first.path / "run.json").write_text("first")
            with folders.run_folder(out) as second:
                (second.path / "run.json").write_text("second")
    assert (out / "run.json").read_text() == "second"  # the one that finished first keeps its folder
    assert staging_left(tmp_path) == []


def test_runs_in_the_same_second_get_their_own_folders(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(folders, "default_out", lambda scenario, root=Path("runs"): root / f"{scenario}-STAMP")
    for _ in range(3):
        code, out, _ = cli(capsys, "run", "pendulum", *FAST)
        assert code == 0
    assert sorted(p.name for p in (tmp_path / "runs").iterdir()) == [
        "pendulum-STAMP",
        "pendulum-STAMP-2",
        "pendulum-STAMP-3",
    ]
    assert "pendulum-STAMP-3" in out  # the summary names the folder the run really went to


@pytest.mark.slow
def test_concurrent_default_runs_all_survive(tmp_path):
    """Four processes started together, no --out: four complete, distinct run folders."""
    procs = [
        subprocess.Popen(
            [sys.executable, "-m", "hexabot_sim", "run", "pendulum", *FAST],
            cwd=tmp_path,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
        )
        for _ in range(4)
    ]
    for proc in procs:
        _, err = proc.communicate(timeout=120)
        assert proc.returncode == 0, err
    folders = list((tmp_path / "runs").iterdir())
    assert len(folders) == 4
    assert all((folder / "run.json").exists() for folder in folders)
    assert staging_left(tmp_path) == []


def test_over_long_names(tmp_path, capsys):
    ok = tmp_path / ("r" * 255)  # the longest valid name: the staging name must not push it over
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(ok))
    assert code == 0, err
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(tmp_path / ("r" * 256)))
    assert code == 2 and "255" in one_line_error(err)


def test_unwritable_parent(capsys):
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", "/proc/hexabot-sim-test/run")
    assert code == 2
    assert "cannot be written" in one_line_error(err)


def test_full_disk_leaves_nothing_and_removes_created_parents(tmp_path, monkeypatch, capsys):
    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(output, "write_csv", full)
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(tmp_path / "deep" / "nested" / "run"))
    assert code == 1
    assert "No space left on device" in one_line_error(err)
    assert list(tmp_path.iterdir()) == []  # deep/ and deep/nested/ were ours: gone again
    # Removing them is no move by someone else (it said "the folder ... was moved or removed during the run")
    assert "moved" not in err and "writing the run folder failed" in err


def test_default_runs_folder_removed_when_the_run_fails(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    code, _, err = cli(capsys, "run", "pendulum", "--set", "stiffness=1e4", "--set", "timestep=0.05", "--no-plots")
    assert code == 1, err
    assert "diverged" in one_line_error(err)
    assert list(tmp_path.iterdir()) == []


def test_existing_parents_are_kept_on_failure(tmp_path, monkeypatch, capsys):
    (tmp_path / "runs").mkdir()
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(output, "write_csv", lambda *a: (_ for _ in ()).throw(OSError(errno.EIO, "I/O error")))
    code, _, _ = cli(capsys, "run", "pendulum", *FAST)
    assert code == 1
    assert (tmp_path / "runs").is_dir() and list((tmp_path / "runs").iterdir()) == []


def test_check_out_names_what_is_wrong(tmp_path):
    (tmp_path / "file").write_text("x")
    with pytest.raises(UsageError, match="not a folder"):
        folders.check_out(tmp_path / "file")
    with pytest.raises(UsageError, match="not a folder"):
        folders.check_out(tmp_path / "file" / "run")


def test_unexpected_exception_is_one_line_and_debug_shows_it(tmp_path, monkeypatch, capsys):
    scenario = registry.get("pendulum")

    def broken(*args, **kwargs):
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr(type(scenario), "runner", property(lambda self: broken))
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(tmp_path / "r"))
    assert code == 1
    line = one_line_error(err)
    assert "internal error" in line and "ZeroDivisionError" in line and "--debug" in line
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(ZeroDivisionError):
        main(["run", "pendulum", *FAST, "--out", str(tmp_path / "r"), "--debug"])
    monkeypatch.setenv("HEXABOT_SIM_DEBUG", "1")
    with pytest.raises(ZeroDivisionError):
        main(["run", "pendulum", *FAST, "--out", str(tmp_path / "r")])


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


@pytest.mark.slow
def test_an_encoder_that_stops_reading_does_not_hang_the_run(tmp_path, monkeypatch, capsys):
    """An 'ffmpeg' that answers -version and then never reads its frames: the stuck write is stopped after
    FRAME_TIMEOUT, the run keeps its CSV and says why there is no video, and the encoder is gone."""
    from hexabot_sim import render

    fake = tmp_path / "stuck-ffmpeg"
    fake.write_text(
        f"#!{sys.executable}\nimport sys, time\n"
        "if sys.argv[1:] == ['-version']:\n    print('ffmpeg version 6.0 (a stuck fake)')\n    sys.exit(0)\n"
        "time.sleep(600)\n"
    )
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
    assert not [p for p in Path("/proc").glob("[0-9]*") if str(fake).encode() in _cmdline(p)]  # killed, not left


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


def test_force_never_replaces_home_or_its_parents(tmp_path, monkeypatch, capsys):
    home = tmp_path / "home" / "user"
    (home / "docs").mkdir(parents=True)
    (home / "docs" / "thesis.tex").write_text("mine")
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    monkeypatch.setenv("HOME", str(home))
    for target in (home, home.parent):
        code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(target), "--force")
        assert code == 2 and "home folder" in one_line_error(err)
    assert (home / "docs" / "thesis.tex").read_text() == "mine"


def test_out_inside_another_runs_staging_folder_is_refused(tmp_path, capsys):
    staging = tmp_path / f"{folders.STAGING_PREFIX}123-abcd{folders.STAGING_SUFFIX}"
    staging.mkdir()
    for target in (staging, staging / "b"):
        code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(target), "--force")
        assert code == 2 and "staging folder" in one_line_error(err)


def test_force_leaves_a_folder_that_changed_during_the_run_alone(tmp_path, monkeypatch, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "old.txt").write_text("old")
    scenario = registry.get("pendulum")
    real_runner = scenario.runner

    def runner_meanwhile_user_writes(*args, **kwargs):
        (out / "thesis.tex").write_text("written during the run")
        return real_runner(*args, **kwargs)

    monkeypatch.setattr(type(scenario), "runner", property(lambda self: runner_meanwhile_user_writes))
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(out), "--force")
    assert code == 1 and "changed during the run" in one_line_error(err)
    assert sorted(p.name for p in out.iterdir()) == ["old.txt", "thesis.tex"]
    assert staging_left(tmp_path) == []


def test_parent_moved_during_the_run_leaves_nothing(tmp_path, monkeypatch, capsys):
    parent = tmp_path / "pp"
    parent.mkdir()
    scenario = registry.get("pendulum")
    real_runner = scenario.runner

    def runner_meanwhile_parent_moves(*args, **kwargs):
        parent.rename(tmp_path / "pp.moved")
        return real_runner(*args, **kwargs)

    monkeypatch.setattr(type(scenario), "runner", property(lambda self: runner_meanwhile_parent_moves))
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(parent / "o"))
    assert code == 1, err
    assert list((tmp_path / "pp.moved").iterdir()) == []


def test_run_folder_permissions_follow_the_umask(tmp_path, capsys):
    previous = os.umask(0o022)
    try:
        code, _, _ = cli(capsys, "run", "pendulum", *FAST, "--out", str(tmp_path / "r"))
    finally:
        os.umask(previous)
    assert code == 0 and (tmp_path / "r").stat().st_mode & 0o777 == 0o755


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


def test_config_edge_cases(tmp_path, capsys):
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--config", "", "--out", str(tmp_path / "r"))
    assert code == 2 and "empty" in one_line_error(err)
    bom = tmp_path / "bom.toml"
    bom.write_bytes(b"\xef\xbb\xbfmass = 0.2\n")
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--config", str(bom), "--out", str(tmp_path / "r"))
    assert code == 0, err


def test_a_mount_point_is_refused_before_the_run(tmp_path, monkeypatch):
    """A run is published by renaming onto --out, which a mount point refuses (EBUSY): say so before simulating."""
    mounted = tmp_path / "mnt"
    mounted.mkdir()
    real = os.path.ismount
    monkeypatch.setattr(os.path, "ismount", lambda p: Path(p) == mounted or real(p))
    with pytest.raises(UsageError, match="is a mount point; give a new folder inside it"):
        folders.check_out(mounted)
    folders.check_out(mounted / "run")  # inside it: fine


def test_publishers_in_one_folder_take_turns(tmp_path):
    """Two runs publishing into the same folder hold a lock while they compare --out with what it was and rename,
    so two --force runs cannot both find it unchanged and both replace it."""
    import threading

    first, second = (os.open(tmp_path, os.O_RDONLY | os.O_DIRECTORY) for _ in range(2))
    times = {}

    def publish(name, fd, hold):
        with folders._publishing(fd):
            times[name] = time.monotonic()
            time.sleep(hold)

    try:
        a = threading.Thread(target=publish, args=("a", first, 0.4))
        a.start()
        time.sleep(0.1)
        b = threading.Thread(target=publish, args=("b", second, 0.0))
        b.start()
        a.join()
        b.join()
    finally:
        os.close(first)
        os.close(second)
    assert times["b"] - times["a"] >= 0.35


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
