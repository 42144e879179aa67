"""Steering the hexabot in `hexabot-sim view hexabot-walk`: keys sent to the real window under Xvfb with xdotool
(walking/steering.py), and the keys' effect on the command without a window."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time

import numpy as np
import pytest
from helpers import walk_params
from test_viewer import BLUE, GREEN, OPEN_TIMEOUT, ORANGE, colour_pixels, read_xwd, xdisplay  # noqa: F401

from hexabot_sim.walking import steering as keys_
from hexabot_sim.walking.walk import live


def test_keys_change_the_command_and_refuse_what_the_legs_cannot_deliver():
    sim = live(walk_params())
    steer = sim.keys
    assert steer(keys_.KEY_UP, False) and steer(keys_.KEY_LEFT, True) and steer(keys_.KEY_PAGE_UP, False)
    assert steer(keys_.KEY_RIGHT, False)
    text = sim.overlay[1](sim.data)
    assert text.startswith("steer: vx +0.12 vy +0.02 m/s, yaw -0.10 rad/s, tripod, stand 95 mm")
    assert not steer(32, False)  # space: the viewer's own
    for _ in range(30):  # far beyond the legs: refused, the command stays the last feasible one
        steer(keys_.KEY_UP, False)
    assert "refused: the legs cannot deliver this command" in sim.overlay[1](sim.data)
    assert sim.overlay[1](sim.data).startswith("steer: vx +0.")
    # A wave at the speed in force (0.1 m/s at the start's target) is more than its swing can take: refused.
    for _ in range(int(1.5 / 0.002)):
        sim.step()
    steer(keys_.KEY_KP_3, False)
    assert "wave refused at the speed in force (slow down first)" in sim.overlay[1](sim.data)


def _xdotool(display: str, *keys: str) -> None:
    env = dict(os.environ, DISPLAY=display)
    subprocess.run(["xdotool", "key", "--delay", "150", *keys], env=env, check=True, timeout=30)


@pytest.mark.slow
def test_keys_sent_to_the_window_steer_the_live_robot(xdisplay, tmp_path):  # noqa: F811
    """Down x5 (stop), keypad 3 (wave), Up x2 (0.04 m/s), shift+Left (crab left), Page Up (5 mm higher), Left (turn
    left): the viewer's last words name the command the keys asked for and the gait in force, and the body has
    turned left; the robot is still drawn (the keys did not hide its geoms, as the digits above the letters do)."""
    if shutil.which("xdotool") is None:
        pytest.skip("xdotool not installed (Debian: apt-get install xdotool)")
    env = dict(os.environ, DISPLAY=xdisplay)
    env.pop("WAYLAND_DISPLAY", None)
    env.pop("MUJOCO_GL", None)
    command = [sys.executable, "-m", "hexabot_sim", "view", "hexabot-walk", "--quit-after", "10"]
    proc = subprocess.Popen(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        started = time.monotonic()
        line = ""
        while "viewing" not in line:
            assert time.monotonic() - started < OPEN_TIMEOUT, "the viewer did not open"
            line = proc.stderr.readline()
            assert line or proc.poll() is None, f"the viewer exited: {proc.stderr.read()}"
        time.sleep(2.0)  # walking at the start's 0.1 m/s
        _xdotool(xdisplay, *["Down"] * 5)
        time.sleep(1.5)  # the twist in force reaches 0 (0.2 m/s^2)
        _xdotool(xdisplay, "KP_3", "Up", "Up", "shift+Left", "Prior", "Left")
        time.sleep(1.0)
        dump = subprocess.run(["xwd", "-root", "-silent", "-display", xdisplay], capture_output=True, timeout=30)
        time.sleep(1.5)  # turning on, then the window closed (Ctrl+Q); --quit-after is the backstop
        _xdotool(xdisplay, "ctrl+q")
        out, err = proc.communicate(timeout=OPEN_TIMEOUT)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, err
    assert "wave gait; steer: vx +0.04 vy +0.02 m/s, yaw +0.10 rad/s, wave, stand 95 mm" in out, out
    yaw = float(out.split("yaw = ")[1].split()[0])
    assert yaw > 0.05, out  # it turned left
    image = read_xwd(dump.stdout)
    from PIL import Image

    Image.fromarray(image).save(tmp_path / "steered.png")  # for a person to look at: the overlay's steer line
    for rgb in (BLUE, ORANGE, GREEN):
        assert colour_pixels(image, rgb) >= 50, f"robot colour {rgb} missing after the keys"
    assert np.isfinite(yaw)
