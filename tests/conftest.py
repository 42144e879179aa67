"""Shared fixtures: headless GL chosen before MuJoCo is imported, one GL probe per session."""

import os

os.environ.setdefault("MUJOCO_GL", "egl")  # must precede any `import mujoco`

import pytest

from hexabot_sim import gl


@pytest.fixture(scope="session")
def gl_backend() -> str:
    """The working OpenGL backend; skips the test, with the reason, where none works."""
    backend, reason, _notice = gl.choose()
    if backend is None:
        pytest.skip(f"rendering unavailable here: {reason}")
    return backend
