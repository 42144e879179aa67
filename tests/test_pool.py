"""The local cell pool stops promptly: a stop request a library swallowed, a worker deaf to SIGTERM."""

import signal
import time

import pytest

from hexabot_sim import pool, signals

# The pool's own thread must not fail either (its traceback would reach the command line's stderr).
pytestmark = pytest.mark.filterwarnings("error::pytest.PytestUnhandledThreadExceptionWarning")


def sleeper(name, seconds):
    """A cell's runner that only takes time."""
    time.sleep(seconds)
    raise AssertionError("the cell should have been stopped")


def deaf_sleeper(name, seconds):
    """A cell's runner inside a long call that runs no SIGTERM handler (as a worker inside a C kernel)."""
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    time.sleep(seconds)
    raise AssertionError("the cell should have been stopped")


def _jobs(runner, count=4, seconds=60.0):
    return [pool.CellJob(i, "test", seconds, runner) for i in range(count)]


@pytest.fixture
def clean_signals():
    signals.reset()
    yield
    signals.reset()


def test_a_stop_request_whose_exception_was_swallowed_stops_the_sweep(clean_signals):
    """The command line's handler records every stop request; one whose exception Python swallowed (a SIGTERM that
    lands in logging's after-fork hook while the pool forks its workers: a leg-sweep went on with all 60 cells, about
    1 run in 30 under load) must still stop the sweep within a poll, and leave no worker."""
    executor = pool.local_executor(2)
    signals.RECEIVED_SIGNALS.append(signal.SIGTERM)  # received; its exception never reached the sweep
    started = time.monotonic()
    with pytest.raises(signals.Interrupted) as raised:
        pool.run_cells(executor, _jobs(sleeper))
    assert raised.value.signum == signal.SIGTERM
    assert time.monotonic() - started < pool.STOP_GRACE + 3.0
    assert not any(p.is_alive() for p in getattr(executor, "_processes", None) or {})


def test_a_worker_deaf_to_sigterm_is_killed_after_the_grace(clean_signals, monkeypatch):
    monkeypatch.setattr(pool, "STOP_GRACE", 0.5)
    executor = pool.local_executor(2)
    futures = [executor.submit(pool.run_cell, job) for job in _jobs(deaf_sleeper, count=2)]
    time.sleep(1.0)  # both workers are in their cell, deaf to SIGTERM
    processes = list(executor._processes.values())
    assert len(processes) == 2 and all(p.is_alive() for p in processes)
    started = time.monotonic()
    pool.stop(executor, futures)
    assert time.monotonic() - started < 0.5 + 3.0  # not the cells' 60 s
    assert not any(p.is_alive() for p in processes)


def test_a_worker_stopped_before_its_initializer_ends_without_a_word(tmp_path):
    """A forked worker inherits the command line's stop handler until its initializer replaces it: a SIGTERM from the
    stopping sweep then ended it with "Exception in initializer:" and a traceback on the command line's stderr (found
    by fuzzing a sweep stopped as it started). The child ends at once, 128 + N, silent."""
    import subprocess
    import sys

    code = (
        "import os, signal\n"
        "from hexabot_sim import signals\n"
        "signal.signal(signal.SIGTERM, signals.raise_interrupted)\n"
        "ready, told = os.pipe()\n"
        "pid = os.fork()\n"
        "if pid == 0:  # a worker still in its start-up: the parent's handler is still in force\n"
        "    os.write(told, b'x')\n"
        "    while True:\n"
        "        sum(range(100))\n"
        "os.read(ready, 1)\n"
        "os.kill(pid, signal.SIGTERM)\n"
        "print(os.waitstatus_to_exitcode(os.waitpid(pid, 0)[1]), signals.RECEIVED_SIGNALS)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, cwd=tmp_path)
    assert done.stdout.split() == [str(128 + signal.SIGTERM), "[]"], done.stdout + done.stderr
    assert done.stderr == "" and done.returncode == 0


def quick(name, seconds):
    """A cell's runner that returns at once."""
    return None


def test_the_pool_is_started_and_fed_under_the_signal_hold(clean_signals):
    """A stop signal while the pool forks its workers and takes the cells is recorded and raised once every submit
    returned: raised inside multiprocessing's Finalize.__init__ it left a half-made finalizer that printed
    "Exception ignored ... AttributeError: 'Finalize' object has no attribute '_key'" on stderr (found by fuzzing)."""
    executor = pool.local_executor(1)
    held, workers = [], []
    submit = executor.submit

    def submit_as_a_sigterm_lands(*args, **kwargs):
        held.append(signals.HOLD[0])
        signals.raise_interrupted(signal.SIGTERM, None)  # the command line's handler, as the signal lands here
        future = submit(*args, **kwargs)
        workers.extend(executor._processes.values())
        return future

    executor.submit = submit_as_a_sigterm_lands
    with pytest.raises(signals.Interrupted):
        pool.run_cells(executor, _jobs(quick, count=2, seconds=0.0))
    assert held == [1, 1]  # both submitted, under the hold; the stop raised after them
    assert workers and not any(p.is_alive() for p in workers)
