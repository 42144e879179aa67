"""hexabot-sim: robotics-course kinematics and dynamics exercises on MuJoCo."""

import os as _os

# MuJoCo picks its OpenGL backend when it is first imported: default to headless EGL.
USER_MUJOCO_GL: str | None = _os.environ.get("MUJOCO_GL")  # what the user had set, for `hexabot-sim check`
_os.environ.setdefault("MUJOCO_GL", "egl")

__version__ = "0.1.0"
