"""`hexabot-sim view`: the real window under Xvfb, captured with xwd; its clock and keys; its refusals."""

from __future__ import annotations

import os
import select
import shutil
import struct
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from hexabot_sim import viewer
from hexabot_sim.__main__ import main

SCREEN = (1024, 640)  # [px] Xvfb screen; the viewer's window takes part of it
OPEN_TIMEOUT: float = 60.0  # [s] until the viewer says it is showing (imports + window on a loaded machine)
SETTLE: float = 1.0  # [s] drawing before the first capture
CAPTURE_EVERY: float = 0.3  # [s] captures are retried until the window shows a drawn frame (a loaded machine
# with software OpenGL can take seconds for the first frames), while the viewer runs


# ---------------------------------------------------------------------------------------------
# Clock and keys: no display needed.


def test_clock_plays_pauses_scrubs_and_stops_at_the_end() -> None:
    clock = viewer.Clock(0.0, 2.0, 0.0)
    clock.advance(0.5)
    assert clock.position == pytest.approx(0.5) and not clock.paused
    clock.key(viewer.KEY_SPACE)
    clock.advance(1.0)
    assert clock.position == pytest.approx(0.5) and clock.paused
    clock.key(viewer.KEY_MINUS)
    clock.key(viewer.KEY_SPACE)
    clock.advance(1.0)
    assert clock.speed == 0.5 and clock.position == pytest.approx(1.0)
    clock.key(viewer.KEY_LEFT)
    assert clock.paused and clock.position == pytest.approx(1.0 - viewer.SCRUB_FRAME)
    clock.key(viewer.KEY_UP)
    assert clock.position == pytest.approx(2.0 - viewer.SCRUB_FRAME)
    clock.key(viewer.KEY_HOME)
    assert clock.position == 0.0
    clock.key(viewer.KEY_END)
    assert clock.position == 2.0 and clock.paused
    clock.key(viewer.KEY_SPACE)  # at the end: plays again from the start
    assert clock.position == 0.0 and not clock.paused
    for _ in range(20):
        clock.key(viewer.KEY_EQUAL)
    assert clock.speed == viewer.MAX_SPEED
    clock.advance(10.0)
    assert clock.position == 2.0 and clock.paused


def test_live_clock_cannot_go_back_and_home_restarts() -> None:
    clock = viewer.Clock(0.0, 5.0, 1.0, live=True)
    for key in (viewer.KEY_LEFT, viewer.KEY_DOWN, viewer.KEY_END):
        clock.key(key)
    assert clock.position == 1.0
    clock.key(viewer.KEY_RIGHT)
    assert clock.paused and clock.position == pytest.approx(1.0 + viewer.SCRUB_FRAME)
    clock.key(viewer.KEY_HOME)
    assert clock.restart


def test_nearest_row() -> None:
    t = np.array([0.0, 0.1, 0.2, 0.3])
    assert [viewer.nearest_row(t, x) for x in (-1.0, 0.04, 0.06, 0.29, 9.0)] == [0, 0, 1, 3, 3]
    assert viewer.nearest_row(np.array([0.0]), 5.0) == 0


# ---------------------------------------------------------------------------------------------
# Refusals: exit 2, one line, before any window.


def _one_line_error(capsys: pytest.CaptureFixture[str], argv: list[str]) -> str:
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2, err
    assert err.count("\n") == 1 and "Traceback" not in err
    return err


def test_view_without_glfw_says_what_to_install(monkeypatch, capsys) -> None:
    monkeypatch.setitem(sys.modules, "glfw", None)  # import glfw raises ImportError
    err = _one_line_error(capsys, ["view", "pendulum"])
    assert 'pip install "hexabot-sim[viewer]"' in err


def test_view_without_display_says_so(monkeypatch, capsys) -> None:
    pytest.importorskip("glfw")
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    err = _one_line_error(capsys, ["view", "pendulum"])
    assert "no display" in err and "DISPLAY is not set" in err


def test_view_with_a_display_that_cannot_be_opened(monkeypatch, capsys) -> None:
    pytest.importorskip("glfw")
    monkeypatch.setenv("DISPLAY", ":987")  # no X server there
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    err = _one_line_error(capsys, ["view", "pendulum"])
    assert "cannot open the display ':987'" in err


def test_view_refuses_bad_targets(tmp_path, capsys) -> None:
    assert "unknown scenario 'pendulun'" in _one_line_error(capsys, ["view", "pendulun"])
    assert "does not exist" in _one_line_error(capsys, ["view", str(tmp_path / "nope") + os.sep])
    (tmp_path / "run.json").write_text("{}")  # a file: it "did not exist" (found by fuzzing)
    assert "is a file, not a run folder" in _one_line_error(capsys, ["view", str(tmp_path / "run.json")])
    (tmp_path / "run.json").unlink()
    (tmp_path / "grid.csv").write_text("a\n")
    assert "leg-sweep run folder" in _one_line_error(capsys, ["view", str(tmp_path)])
    (tmp_path / "grid.csv").unlink()
    assert "no trajectory.npz" in _one_line_error(capsys, ["view", str(tmp_path)])
    assert "run folder replays its own" in _one_line_error(capsys, ["view", str(tmp_path), "--set", "mass=1"])
    assert "expected a speed" in _one_line_error(capsys, ["view", "pendulum", "--speed", "0"])


def test_leg_sweep_has_no_live_view() -> None:
    with pytest.raises(viewer.UsageError, match="grid of runs"):
        viewer.live_maker("leg-sweep", None)


# ---------------------------------------------------------------------------------------------
# The real window under Xvfb.


@pytest.fixture(scope="module")
def xdisplay():
    """An Xvfb server of our own (its display number chosen by Xvfb); skips where Xvfb, xwd or glfw is absent."""
    pytest.importorskip("glfw", reason="the viewer needs glfw (pip install '.[test]' or '.[viewer]')")
    missing = [tool for tool in ("Xvfb", "xwd") if shutil.which(tool) is None]
    if missing:
        pytest.skip(f"{' and '.join(missing)} not installed (Debian: apt-get install xvfb x11-apps)")
    read_fd, write_fd = os.pipe()
    server = subprocess.Popen(
        ["Xvfb", "-displayfd", str(write_fd), "-screen", "0", f"{SCREEN[0]}x{SCREEN[1]}x24", "-nolisten", "tcp"],
        pass_fds=(write_fd,),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    os.close(write_fd)
    try:
        ready, _, _ = select.select([read_fd], [], [], 30)
        number = os.read(read_fd, 64).decode().strip() if ready else ""
        if not number:
            pytest.skip("Xvfb did not start")
        yield f":{number}"
    finally:
        os.close(read_fd)
        server.terminate()
        server.wait(10)


def read_xwd(data: bytes) -> np.ndarray:
    """(h, w, 3) uint8 RGB of an xwd dump of a TrueColor screen (24 or 32 bits per pixel)."""
    header = struct.unpack(">25I", data[:100])
    header_size, width, height, byte_order, bits, stride, ncolors = (header[i] for i in (0, 4, 5, 7, 11, 12, 19))
    k = bits // 8
    offset = header_size + 12 * ncolors  # the header, then one 12-byte XWDColor per colour
    rows = np.frombuffer(data, np.uint8, count=stride * height, offset=offset).reshape(height, stride)
    pixels = rows[:, : width * k].reshape(height, width, k)
    return np.ascontiguousarray(pixels[:, :, 2::-1] if byte_order == 0 else pixels[:, :, k - 3 :])


def drawn(image: np.ndarray) -> bool:
    """The screen shows a rendered frame (not the black root window or a window not yet drawn)."""
    return bool(image.std() > 20 and (image.max(axis=2) > 20).mean() > 0.2)


def watch(display: str, argv: list[str], shot: Path, quit_after: float = 6.0, ready=None) -> tuple[np.ndarray, str]:
    """Runs `hexabot-sim view ...` on the display, captures the screen once it draws (and `ready(image)`, e.g.
    the robot is in view: a loaded machine can show a frame drawn before the scene), returns (RGB, stdout)."""
    env = dict(os.environ, DISPLAY=display)
    env.pop("WAYLAND_DISPLAY", None)
    env.pop("MUJOCO_GL", None)
    command = [sys.executable, "-m", "hexabot_sim", "view", *argv, "--quit-after", str(quit_after)]
    proc = subprocess.Popen(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        started = time.monotonic()
        line = ""
        while "viewing" not in line and "replaying" not in line:  # the window is open and drawing
            assert time.monotonic() - started < OPEN_TIMEOUT, "the viewer did not open"
            line = proc.stderr.readline()
            assert line or proc.poll() is None, f"the viewer exited: {proc.stderr.read()}"
        time.sleep(SETTLE)
        image = np.zeros((1, 1, 3), np.uint8)
        while proc.poll() is None:  # capture until a drawn frame shows, while the viewer runs
            dump = subprocess.run(["xwd", "-root", "-silent", "-display", display], capture_output=True)
            if dump.returncode == 0:
                image = read_xwd(dump.stdout)
                if drawn(image) and (ready is None or ready(image)):
                    break
            time.sleep(CAPTURE_EVERY)
        if proc.poll() is None and shutil.which("xdotool"):  # captured: close the window (Ctrl+Q), not wait for it
            subprocess.run(["xdotool", "key", "ctrl+q"], env=env, timeout=30)
        out, err = proc.communicate(timeout=OPEN_TIMEOUT)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, err
    from PIL import Image

    Image.fromarray(image).save(shot)  # for a person to look at
    return image, out


def colour_pixels(image: np.ndarray, rgb: tuple[float, float, float], tol: float = 60.0) -> int:
    """Pixels within `tol` (RGB distance) of a robot material's colour, lit from 50 % to 110 %."""
    target = np.array(rgb) * 255
    pixels = image.reshape(-1, 3).astype(float)
    # Lambert shading scales a colour: compare directions, then require a plausible brightness.
    scale = (pixels @ target) / (target @ target)
    distance = np.linalg.norm(pixels - scale[:, None] * target, axis=1)
    return int(np.count_nonzero((distance < tol * 0.5) & (scale > 0.5) & (scale < 1.1)))


BLUE, ORANGE, GREEN = (0.20, 0.45, 0.80), (0.85, 0.55, 0.15), (0.15, 0.65, 0.45)  # link/femur, coxa, tibia


def assert_drawn(image: np.ndarray, colours: list[tuple[float, float, float]], least: int) -> None:
    assert image.std() > 20, "blank frame"
    assert (image.max(axis=2) > 20).mean() > 0.2, "mostly black frame"
    for rgb in colours:
        assert colour_pixels(image, rgb) >= least, f"robot colour {rgb} missing"


def showing(colours: list[tuple[float, float, float]], least: int):
    """A `watch` predicate: every robot colour covers at least `least` pixels."""
    return lambda image: all(colour_pixels(image, rgb) >= least for rgb in colours)


@pytest.mark.slow
def test_pendulum_live_is_drawn(xdisplay, tmp_path) -> None:
    image, out = watch(xdisplay, ["pendulum"], tmp_path / "pendulum_live.png", ready=showing([BLUE], 300))
    assert_drawn(image, [BLUE], least=300)
    assert "last state shown: t =" in out


@pytest.mark.slow
def test_leg_step_live_is_drawn(xdisplay, tmp_path) -> None:
    image, out = watch(
        xdisplay, ["leg-step", "--set", "mode=kinematic"], tmp_path / "leg_live.png",
        ready=showing([BLUE, ORANGE, GREEN], 100),
    )  # fmt: skip
    assert_drawn(image, [BLUE, ORANGE, GREEN], least=100)
    t = float(out.split("t = ")[1].split()[0])
    assert 0.5 < t < 12.6  # it advanced in real time, not to the end


@pytest.mark.slow
def test_hexabot_replay_reaches_the_final_state(xdisplay, tmp_path) -> None:
    folder = tmp_path / "walk"
    assert main(["run", "hexabot-walk", "--set", "duration=2", "--out", str(folder), "--no-plots"]) == 0
    with np.load(folder / "trajectory.npz") as npz:
        t = npz["t"]
    image, out = watch(
        xdisplay,
        [str(folder), "--speed", "4"],
        tmp_path / "hexabot_replay.png",
        ready=showing([BLUE, ORANGE, GREEN], 100),
    )
    assert_drawn(image, [BLUE, ORANGE, GREEN], least=100)
    assert f"t = {t[-1]:.6g} s (row {len(t) - 1} of {len(t) - 1}, the final state)" in out
