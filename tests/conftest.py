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


@pytest.fixture(autouse=True)
def fresh_stop_state():
    """The command line's stop-signal bookkeeping (hexabot_sim.signals) is per process: reset for every test, since
    many tests run commands in this one process."""
    from hexabot_sim import signals

    signals.RECEIVED_SIGNALS.clear()
    signals.PENDING_SIGNALS.clear()
    signals.HOLD[0] = 0
    signals.PUBLISHED[0] = False
