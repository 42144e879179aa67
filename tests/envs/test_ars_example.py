"""examples/train_ars.py runs: a tiny training (one iteration of two directions) reports its returns."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("gymnasium", reason="the Gymnasium environments need gymnasium (the rl extra)")

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "train_ars.py"


@pytest.mark.slow
def test_the_ars_example_trains_and_reports(tmp_path):
    plot = tmp_path / "curve.png"
    args = ["--iterations", "1", "--directions", "2", "--top", "1", "--eval-episodes", "2", "--horizon", "3",
            "--workers", "1", "--plot", str(plot)]  # fmt: skip
    out = subprocess.run([sys.executable, str(EXAMPLE), *args], capture_output=True, text=True, timeout=600, check=True)
    assert re.search(r"^before: return -?\d+\.\d \+- \d+\.\d over 2 episodes$", out.stdout, re.M)
    assert re.search(r"^after 1 iterations .* higher in \d of 2 evaluation episodes", out.stdout, re.M)
    assert plot.stat().st_size > 1000


def test_watch_without_a_display_stops_before_the_training_in_one_line():
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    command = [sys.executable, str(EXAMPLE), "--watch"]
    out = subprocess.run(command, capture_output=True, text=True, timeout=300, env=env)
    assert out.returncode == 1 and "before:" not in out.stdout, out
    assert out.stderr.strip() == (
        "train_ars.py: --watch: render_mode='human' cannot open a window: no display is available (DISPLAY is not "
        "set): run it in a desktop session, over 'ssh -X', or under a virtual one: xvfb-run -a python your_script.py"
    )
