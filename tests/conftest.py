"""Shared fixtures: headless GL chosen before MuJoCo is imported, one GL probe per session; numba's cache warmed
once before the test processes start."""

import contextlib
import os

os.environ.setdefault("MUJOCO_GL", "egl")  # must precede any `import mujoco`

import pytest

from hexabot_sim import gl


@pytest.fixture(scope="session", autouse=True)
def _dask_scratch(tmp_path_factory: pytest.TempPathFactory):
    """Dask's scratch files (a scheduler's and its workers' dask-scratch-space, in this process and in the dask
    commands the cluster tests start) in the session's temporary folder: they were left in /tmp."""
    path = str(tmp_path_factory.mktemp("dask"))
    before = os.environ.get("DASK_TEMPORARY_DIRECTORY")
    os.environ["DASK_TEMPORARY_DIRECTORY"] = path  # read by the dask commands started from here
    try:
        import dask
    except ImportError:
        dask = None
    with dask.config.set({"temporary-directory": path}) if dask is not None else contextlib.nullcontext():
        yield
    if before is None:
        os.environ.pop("DASK_TEMPORARY_DIRECTORY", None)
    else:
        os.environ["DASK_TEMPORARY_DIRECTORY"] = before


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


# The modules of 12 s or more, slowest first (seconds summed from `pytest --durations=0`, 2 cores, 2026-11-27):
# pytest-xdist hands out whole modules (--dist loadscope) in collection order (--no-loadscope-reorder), so these go
# first and the short modules fill in at the end. xdist's own order (most tests first) left modules of a few long
# tests (the human windows, 31 s; the steered viewer, 14 s) for last on one core while the other sat idle (11 s).
SLOWEST_MODULES = [
    "tests/robots/hexabot/test_terrain_walks.py",  # 51 (the 20 s rough walks on two processes of their own)
    "tests/envs/test_render_human.py",  # 49
    "tests/test_figures.py",  # 39
    "tests/cli/test_run_streams.py",  # 35
    "tests/test_api.py",  # 30
    "tests/test_viewer.py",  # 30
    "tests/robots/hexabot/test_hexabot.py",  # 28
    "tests/robots/leg/test_leg_step.py",  # 26
    "tests/control/test_controller_kernels.py",  # 21
    "tests/test_sweep.py",  # 18
    "tests/envs/test_joints.py",  # 18
    "tests/test_viewer_steering.py",  # 18
    "tests/cli/test_run_signals.py",  # 18
    "tests/test_sweep_cluster.py",  # 16
    "tests/walking/test_terrain_map.py",  # 16
    "tests/control/test_force_control.py",  # 12 (five walks of 14-20 s at period=3)
    "tests/robots/hexabot/test_schedule_waypoints.py",  # 16
    "tests/envs/test_ars_example.py",  # 16
    "tests/envs/test_command.py",  # 15
    "tests/test_scenarios.py",  # 15
    "tests/cli/test_hardening_folders.py",  # 14
    "tests/robots/rrp/test_rrp_velocity.py",  # 14
    "tests/robots/leg/test_leg_sweep.py",  # 14
    "tests/test_param_limits.py",  # 13
    "tests/test_report.py",  # 12
]


@pytest.hookimpl(hookwrapper=True)
def pytest_collection(session: pytest.Session):
    """Collection without Python's cyclic garbage collector: rewriting the test modules' asserts builds ~10^6 AST
    nodes on top of a large heap (MuJoCo, numba, scipy imported), and the full collections it set off cost each
    process ~2-3 s of its ~14 s collection (pytest --collect-only -n0, alternating: 14.6 s -> 11.7 s, 3 runs each).
    Nothing collected is cyclic garbage worth reclaiming meanwhile; the collector is back on before the tests."""
    import gc

    gc.disable()
    try:
        yield
    finally:
        gc.enable()


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """The slowest modules first, in SLOWEST_MODULES' order; the others after them as collected (a stable sort:
    each module's tests keep their order)."""
    rank = {module: k for k, module in enumerate(SLOWEST_MODULES)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::", 1)[0], len(rank)))


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
