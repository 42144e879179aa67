"""Headless video: real-time length, size, content; skipped with the reason where no GL works."""

import io
import json

import numpy as np
import pytest

from hexabot_sim.cli import main
from hexabot_sim.cli.progress import ProgressBar


def test_frame_indices_are_real_time():
    from hexabot_sim.render import frame_indices

    t = np.arange(0, 2001) * 0.001  # 2 s at 1 ms
    idx = frame_indices(t, 30)
    assert len(idx) == 61  # video duration = simulated duration
    assert np.allclose(t[idx], np.arange(61) / 30, atol=0.0005)


def _read(path):
    import imageio.v2 as imageio

    reader = imageio.get_reader(str(path))
    try:
        first = reader.get_data(0)
        count = reader.count_frames()
        fps = reader.get_meta_data()["fps"]
    finally:
        reader.close()
    return first, count, fps


def test_video_is_written_real_time_and_shows_the_link(tmp_path, capsys, gl_backend):
    out_dir = tmp_path / "r"
    code = main(["run", "pendulum", "--video", "--no-plots", "--out", str(out_dir), "--set", "duration=1"])
    assert code == 0, capsys.readouterr().err
    first, count, fps = _read(out_dir / "video.mp4")
    assert count == 31 and fps == 30  # 1 s of simulation -> 1 s of video
    assert first.shape == (480, 640, 3)
    # At t = 0 the link is horizontal toward +x: its blue pixels lie right of the pivot, at its height,
    # and the camera frames the swept disc, so the link (length L) spans a good part of the frame.
    import mujoco

    model = mujoco.MjModel.from_xml_path(str(out_dir / "model.xml"))
    camera = model.camera("side").id
    pivot = model.body("link").pos - model.cam_pos[camera]  # the side camera looks along +y, x right, z up
    focal = 240 / np.tan(np.radians(model.cam_fovy[camera]) / 2)  # [px]
    u, v = 320 + focal * pivot[0] / pivot[1], 240 - focal * pivot[2] / pivot[1]
    r, g, b = (first[..., i].astype(int) for i in range(3))
    blue = (b > 150) & (b > r + 60) & (b > g + 30)
    ys, xs = np.nonzero(blue)
    assert xs.size > 200
    assert xs.min() >= u - 10 and abs(ys.mean() - v) < 15
    assert xs.max() - xs.min() > 0.3 * 640
    record = json.loads((out_dir / "run.json").read_text())
    assert (
        record["video"]["written"] and record["video"]["frames"] == 31 and record["video"]["gl_backend"] == gl_backend
    )


@pytest.mark.slow
def test_high_quality_preset_and_custom_size(tmp_path, capsys, gl_backend):
    out_dir = tmp_path / "r"
    argv = ["run", "pendulum-undamped", "--video", "--quality", "high", "--size", "320x240", "--fps", "10"]
    code = main([*argv, "--no-plots", "--out", str(out_dir), "--set", "duration=0.5"])
    assert code == 0, capsys.readouterr().err
    first, count, _ = _read(out_dir / "video.mp4")
    assert first.shape == (240, 320, 3) and count == 6


def test_progress_bar_redraws_on_a_terminal_and_prints_plain_lines_elsewhere():
    class Tty(io.StringIO):
        def isatty(self):
            return True

    tty, pipe = Tty(), io.StringIO()
    for stream in (tty, pipe):
        bar = ProgressBar("video", stream)
        for i in range(1, 11):
            bar(i, 10)
    assert "100% (10/10)" in tty.getvalue() and "\r" in tty.getvalue()
    # In a log: a plain line on the first call and each time a quarter is crossed, never a carriage return.
    assert pipe.getvalue().splitlines() == [f"video: {p}% ({p // 10}/10)" for p in (10, 30, 50, 80, 100)]
    assert pipe.getvalue().splitlines()[-1] == "video: 100% (10/10)"


@pytest.mark.parametrize("platform", ["osmesa", "bogus"])
def test_a_pyopengl_platform_set_to_another_backend_still_renders(tmp_path, gl_backend, platform):
    """`check` said video works with PYOPENGL_PLATFORM set (its probe drops the variable), and the run then wrote
    no video: "Cannot use EGL rendering platform. The PYOPENGL_PLATFORM environment variable is set to ..."."""
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k != "MUJOCO_GL"} | {"PYOPENGL_PLATFORM": platform}
    out_dir = tmp_path / "r"
    argv = ["run", "pendulum", "--video", "--no-plots", "--set", "duration=0.1", "--out", str(out_dir)]
    proc = subprocess.run([sys.executable, "-m", "hexabot_sim", *argv], env=env, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert json.loads((out_dir / "run.json").read_text())["video"]["written"], proc.stderr
