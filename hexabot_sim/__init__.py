"""hexabot-sim: robotics-course kinematics and dynamics exercises on MuJoCo.

Python API (see the README): `scenarios()` lists the scenarios and their parameters, `run(name, **params)`
runs one and returns a `Result` (params, metrics, columns, to_pandas(), figures(), save(dir), video(path));
`export(robot, mjcf=..., urdf=...)` writes a robot's (or robot file's) MJCF and URDF.
Importing the package imports neither MuJoCo nor matplotlib's pyplot and never picks a matplotlib backend.
"""

from __future__ import annotations

import os as _os

from hexabot_sim._version import __version__

# MuJoCo picks its OpenGL backend when it is first imported: default to headless EGL.
USER_MUJOCO_GL: str | None = _os.environ.get("MUJOCO_GL")  # what the user had set, for `hexabot-sim check`
_os.environ.setdefault("MUJOCO_GL", "egl")

# The API lives in hexabot_sim.api and is imported on first use, so `import hexabot_sim` stays cheap
# and MuJoCo is not imported before the CLI has chosen its OpenGL backend.
_API = ("run", "scenarios", "export", "Result", "ScenarioInfo", "Parameter", "Columns", "Metric")
__all__ = ["__version__", *_API]


TYPE_CHECKING = False  # typing is not imported at run time: a Ctrl-C at start-up finds the CLI's handler sooner
if TYPE_CHECKING:
    from typing import Any as _Any


def __getattr__(name: str) -> _Any:
    if name in _API:
        from hexabot_sim import api

        return getattr(api, name)
    raise AttributeError(f"module 'hexabot_sim' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_API])
