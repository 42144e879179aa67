"""What the test modules share (tests/ is on sys.path: pyproject's [tool.pytest.ini_options] pythonpath)."""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from hexabot_sim import params
from hexabot_sim.cli import main


def cli(capsys: Any, *argv: str) -> tuple[int, str, str]:
    """Runs the command line in this process: (exit code, stdout, stderr)."""
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def walk_params(**overrides: Any) -> Any:
    """hexabot-walk's parameters with these overrides, checked as a run checks them."""
    from hexabot_sim.robots.hexabot.walk import HexabotParams

    return params.resolve(HexabotParams, {}, overrides)


def walk(**overrides: Any) -> Any:
    """A hexabot-walk run (ScenarioResult) with these parameters."""
    from hexabot_sim.robots.hexabot import walk as scenario

    return scenario.run("hexabot-walk", walk_params(**overrides))


def quat_to_matrix(q: Any) -> np.ndarray:
    """MuJoCo's rotation matrix (3, 3) of a quaternion (w, x, y, z)."""
    m = np.zeros(9)
    mujoco.mju_quat2Mat(m, np.asarray(q, float))
    return m.reshape(3, 3)
