"""Shared fixtures: headless GL chosen before MuJoCo is imported, one GL probe per session; numba's cache warmed
once before the test processes start."""

import os

os.environ.setdefault("MUJOCO_GL", "egl")  # must precede any `import mujoco`

import pytest

from hexabot_sim import gl


def pytest_sessionstart(session: pytest.Session) -> None:
    """Compiles the walking kernels into numba's on-disk cache once, in the process that starts the session (pytest-
    xdist's controller, before its workers), so the workers and the commands the tests run in subprocesses load
    them (~2 s) instead of each compiling them (~20 s a process on a machine's first run, two at once under xdist).
    Tests of a cold cache set their own NUMBA_CACHE_DIR."""
    if hasattr(session.config, "workerinput"):  # an xdist worker: the controller has warmed the cache
        return
    import subprocess
    import sys

    from hexabot_sim.control import compliance_kernels, force_kernels, kernels

    # On both cores: a walk's own kernels (the gait plan's and the servo step's, ~20 s cold) in a second process while
    # this one compiles the force control's and the admittance's (~19 s); then every group here, loaded from the cache
    # (37 s cold in one process: CI's first run). Measured alternating on 2 idle cores, cold: 25.2 and 27.9 s against
    # 29.4 and 31.4 s for the split before (the gait plan alone in the second process, the servo step's after both).
    walk = subprocess.Popen([sys.executable, "-c", "from hexabot_sim.control import kernels; kernels.warm_up('walk')"])
    try:
        force_kernels.compile_all()
        compliance_kernels.compile_all()
    finally:
        walk.wait()
    kernels.warm_up(*kernels.GROUPS)


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
