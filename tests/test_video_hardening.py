"""Issue 17: an encoder that makes no playable file is detected; Result.video() fails in one clear line."""

import json
import os
import sys

import pytest

import hexabot_sim as hs
from hexabot_sim import output
from hexabot_sim.__main__ import main
from hexabot_sim.errors import OutputError, UsageError

FAKES = {
    # reads every frame, exits 0, writes nothing
    "writes-nothing": "sys.stdin.buffer.read()\n",
    # reads every frame, exits 0, writes bytes that are no MP4
    "writes-garbage": "sys.stdin.buffer.read()\nopen(sys.argv[-1], 'wb').write(b'\\x00' * 5000)\n",
    # an MP4 that was never finished: 'ftyp' and then nothing
    "unfinished": "sys.stdin.buffer.read()\n"
    "open(sys.argv[-1], 'wb').write((24).to_bytes(4, 'big') + b'ftypisom' + bytes(12))\n",
}


@pytest.fixture(params=sorted(FAKES))
def fake_encoder(request, tmp_path, monkeypatch, gl_backend):
    fake = tmp_path / f"{request.param}-ffmpeg"
    fake.write_text(
        f"#!{sys.executable}\nimport sys\n"
        "if sys.argv[1:] == ['-version']:\n    print('ffmpeg version 6.0 (a fake)')\n    sys.exit(0)\n"
        + FAKES[request.param]
    )
    fake.chmod(0o755)
    monkeypatch.setenv("IMAGEIO_FFMPEG_EXE", str(fake))
    return request.param


@pytest.mark.slow
def test_a_run_whose_encoder_made_no_video_says_so(fake_encoder, tmp_path, capsys):
    out = tmp_path / "r"
    code = main(["run", "pendulum", "--set", "duration=0.2", "--video", "--size", "64x64", "--fps", "10",
                 "--out", str(out), "--no-plots"])  # fmt: skip
    assert code == 0
    record = json.loads((out / "run.json").read_text())
    assert record["video"]["written"] is False and "encoder failed" in record["video"]["reason"]
    assert not (out / "video.mp4").exists() and (out / "timeseries.csv").exists()
    assert "no video" in capsys.readouterr().err


@pytest.mark.slow
def test_result_video_whose_encoder_made_nothing_raises(fake_encoder, tmp_path):
    result = hs.run("pendulum", duration=0.2)
    with pytest.raises(OutputError, match="encoder failed"):
        result.video(tmp_path / "v.mp4", size=(64, 64), fps=10)
    assert list(tmp_path.glob("*.mp4")) == [] and list(tmp_path.glob(".*")) == []


def test_result_video_into_a_missing_folder_is_a_clear_error(tmp_path, gl_backend):
    result = hs.run("pendulum", duration=0.1)
    with pytest.raises(UsageError, match="does not exist"):
        result.video(tmp_path / "no" / "such" / "v.mp4", size=(64, 64), fps=10)


def test_result_video_into_a_folder_it_cannot_write_is_a_clear_error(tmp_path, monkeypatch, gl_backend):
    result = hs.run("pendulum", duration=0.1)
    monkeypatch.setattr(os, "access", lambda *a, **k: False)
    with pytest.raises(OutputError, match="cannot be written"):
        result.video(tmp_path / "v.mp4", size=(64, 64), fps=10)


def test_a_real_video_passes_the_mp4_check(tmp_path, gl_backend):
    path = hs.run("pendulum", duration=0.2).video(tmp_path / "v.mp4", size=(64, 64), fps=10)
    assert output.mp4_problem(path) is None
    path.write_bytes(path.read_bytes()[:-100])
    assert "truncated" in output.mp4_problem(path)


def test_result_video_never_replaces_a_file_without_force(tmp_path, gl_backend):
    result = hs.run("pendulum", duration=0.1)
    users = tmp_path / "results.csv"
    users.write_text("the user's data\n")
    with pytest.raises(UsageError, match="exists; pass force=True"):
        result.video(users, size=(64, 64), fps=10)
    assert users.read_text() == "the user's data\n"
    os.mkfifo(tmp_path / "fifo")
    with pytest.raises(UsageError, match="not a regular file"):
        result.video(tmp_path / "fifo", size=(64, 64), fps=10, force=True)
    assert (tmp_path / "fifo").is_fifo()
    with pytest.raises(UsageError, match="True or False"):
        result.video(users, size=(64, 64), fps=10, force="no")
    assert output.mp4_problem(result.video(users, size=(64, 64), fps=10, force=True)) is None
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fifo", "results.csv"]  # no partial file left


def test_result_video_to_a_250_byte_name_is_written(tmp_path, gl_backend):
    """Found by fuzzing: its staging name '.NAME.partial-PID.mp4' went over 255 bytes, a raw OSError (ENAMETOOLONG)."""
    path = hs.run("pendulum", duration=0.05).video(tmp_path / ("v" * 250 + ".mp4"), size=(64, 64), fps=10)
    assert output.mp4_problem(path) is None and [p.name for p in tmp_path.iterdir()] == [path.name]


@pytest.mark.parametrize("path", ["a" * 300 + ".mp4", "/".join(["b" * 200] * 30), "v\0.mp4"])
def test_result_video_to_an_impossible_name_is_a_usage_error(tmp_path, monkeypatch, path):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(UsageError, match=r"too long|NUL"):
        hs.run("pendulum", duration=0.05).video(path, size=(64, 64), fps=10)


@pytest.mark.parametrize("flag", ["force", "plots", "video"])
def test_result_save_flags_are_bools(tmp_path, flag):
    # force="no" is true in Python: it replaced a user's non-empty folder
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "keep").write_text("user")
    with pytest.raises(UsageError, match="True or False"):
        hs.run("pendulum", duration=0.05).save(tmp_path / "out", **{flag: "no"})
    assert (tmp_path / "out" / "keep").read_text() == "user"


def test_video_options_without_video_are_warned_of(tmp_path, capsys):
    """--fps 60 --quality high without --video were ignored without a word (found by fuzzing); alone, no warning."""
    argv = ["run", "pendulum", "--set", "duration=0.05", "--no-plots"]
    assert main([*argv, "--fps", "60", "--quality", "high", "--out", str(tmp_path / "a")]) == 0
    err = capsys.readouterr().err
    assert "warning: --quality, --fps shape a video; without --video none is written" in err
    assert not (tmp_path / "a" / "video.mp4").exists()
    assert main([*argv, "--out", str(tmp_path / "b")]) == 0
    assert "warning" not in capsys.readouterr().err


@pytest.mark.slow
def test_an_encoder_that_quits_early_is_named(tmp_path, monkeypatch, capsys, gl_backend):
    """An encoder that read a few frames and exited: "rendering failed: OSError: [Errno 32] Broken pipe"."""
    fake = tmp_path / "quitting-ffmpeg"
    fake.write_text(
        f"#!{sys.executable}\nimport sys\n"
        "if sys.argv[1:] == ['-version']:\n    print('ffmpeg version 6.0 (a fake)')\n    sys.exit(0)\n"
        "sys.stdin.buffer.read(100000)\nsys.exit(1)\n"
    )
    fake.chmod(0o755)
    monkeypatch.setenv("IMAGEIO_FFMPEG_EXE", str(fake))
    out = tmp_path / "r"
    argv = ["run", "pendulum", "--set", "duration=2", "--video", "--size", "640x480", "--out", str(out), "--no-plots"]
    assert main(argv) == 0
    reason = json.loads((out / "run.json").read_text())["video"]["reason"]
    assert "the video encoder stopped after" in reason and "Broken pipe" not in reason, reason
    assert "no video" in capsys.readouterr().err and not (out / "video.mp4").exists()
