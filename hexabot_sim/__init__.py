"""hexabot-sim: robotics-course kinematics and dynamics exercises on MuJoCo."""

import os as _os

# MuJoCo picks its OpenGL backend when it is first imported: default to headless EGL.
_os.environ.setdefault("MUJOCO_GL", "egl")

__version__ = "0.1.0"
