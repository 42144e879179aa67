"""Signals stop a run cleanly: SIGINT and SIGTERM at any stage (loading, compiling, stepping, publishing) end in
one line and leave no half-written folder; a stop request is never lost."""

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from helpers import cli, staging_left

from hexabot_sim import folders

FAST = ["--set", "duration=0.05", "--no-plots"]


@pytest.fixture(autouse=True)
def _children_get_default_stop_signals():
    """The runs started here must see Ctrl-C, SIGTERM and SIGHUP as a terminal would deliver them, however the test
    run itself was started: a signal this process ignores (SIGHUP under `nohup`, SIGINT in a background job) stays
    ignored in its children, and the command line rightly keeps going through an ignored signal (tested below).
    A handler that does nothing is reset to the default in a child (exec), and leaves this process as it was."""
    before = {}
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        if signal.getsignal(sig) is signal.SIG_IGN:
            before[sig] = signal.signal(sig, lambda signum, frame: None)
    yield
    for sig, handler in before.items():
        signal.signal(sig, handler)


def _start(tmp_path, *argv):
    return subprocess.Popen(
        [sys.executable, "-m", "hexabot_sim", *argv],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _wait_for_staging(tmp_path, proc, timeout=60.0):
    deadline = time.monotonic() + timeout
    while not staging_left(tmp_path):
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline
        time.sleep(0.02)


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP, signal.SIGINT])
def test_signals_stop_the_run_and_clean_up(tmp_path, sig):
    proc = _start(tmp_path, "run", "pendulum", "--set", "duration=3000", "--set", "timestep=0.001", "--out", "out")
    _wait_for_staging(tmp_path, proc)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=30)
    # A shell shows 128 + N either way; rarely the interpreter ends by the signal itself (-N) after our
    # clean-up and message, when a library swallowed and re-delivered Ctrl-C.
    assert proc.returncode in (128 + sig, -sig), err
    assert "Traceback" not in err and "nothing written" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_ctrl_c_while_the_walking_kernels_compile_stops_the_run_cleanly(tmp_path):
    """The first hexabot run on a machine compiles the numba kernels (seconds, a minute under load): Ctrl-C then must
    stop the run promptly in one line, not break numba's compiler ("no compiled object yet", an internal error)."""
    cache = tmp_path / "numba-cache"  # empty: this run compiles
    proc = subprocess.Popen(
        [sys.executable, "-m", "hexabot_sim", "run", "hexabot-rough", "--set", "duration=3", "--out", "out"],
        cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env={**os.environ, "NUMBA_CACHE_DIR": str(cache)},
    )  # fmt: skip
    deadline = time.monotonic() + 120
    while not any(cache.rglob("*.nbi")):  # the first kernel is compiled: the others are being compiled now
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline
        time.sleep(0.01)
    proc.send_signal(signal.SIGINT)
    sent = time.monotonic()
    _, err = proc.communicate(timeout=120)
    # Within seconds, not when the compile is done (it was held: a minute under load, found by fuzzing)
    assert time.monotonic() - sent < 5.0, err
    assert proc.returncode in (130, -signal.SIGINT), err
    assert err.strip() == "hexabot-sim: interrupted; nothing written"
    assert not (tmp_path / "out").exists()


_SWALLOWED = """
import os, signal, sys, time
from hexabot_sim import signals
signals.quiet_interruptions()
signal.signal(signal.SIG{name}, signals.raise_interrupted)


class Dropped:
    def __del__(self):
        os.kill(os.getpid(), signal.SIG{name})  # its handler runs here: Python drops the exception ("ignored")


{hold}
Dropped()
started = time.monotonic()
try:
    while time.monotonic() - started < 3.0:  # work with no check of RECEIVED_SIGNALS (plots, a compile...)
        sum(range(100))
except KeyboardInterrupt as e:
    print("stopped", getattr(e, "signum", 2), signals.RECEIVED_SIGNALS[0], round(time.monotonic() - started, 3))
else:
    print("went on", signals.RECEIVED_SIGNALS)
"""


@pytest.mark.parametrize("name", ["TERM", "INT", "HUP"])
def test_a_stop_request_swallowed_in_a_del_is_raised_again_at_once(name):
    """A stop signal whose handler runs in a __del__ (or a weakref callback, an after-fork hook) raises where Python
    only drops the exception: it is raised again milliseconds later where the program is (numba's compiler went on
    for a minute after one; a sweep ran all its cells). Nothing is printed."""
    done = subprocess.run([sys.executable, "-c", _SWALLOWED.format(name=name, hold="")], capture_output=True,
                          text=True, timeout=60)  # fmt: skip
    number = int(getattr(signal, f"SIG{name}"))
    words = done.stdout.split()
    assert words[:3] == ["stopped", str(number), str(number)] and float(words[3]) < 0.5, done.stdout + done.stderr
    assert done.returncode == 0 and done.stderr == ""


def test_a_stop_request_swallowed_before_a_hold_waits_for_the_hold():
    """Swallowed just before a hold (publishing) begins, a stop request is redelivered inside it: recorded only, and
    raised when the hold ends."""
    code = _SWALLOWED.split("{hold}")[0].format(name="TERM") + (
        "Dropped()\n"
        "try:\n"
        "    with signals.signals_held():\n"
        "        time.sleep(0.3)  # the redelivery comes here\n"
        "        print('held', signals.PENDING_SIGNALS == [signal.SIGTERM])\n"
        "except KeyboardInterrupt as e:\n"
        "    print('stopped', e.signum)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.stdout.split() == ["held", "True", "stopped", str(int(signal.SIGTERM))], done.stdout + done.stderr
    assert done.stderr == ""


@pytest.mark.parametrize("when", ["loading", "before our handlers", "as the command ends"])
def test_a_stop_at_the_command_lines_edges_ends_in_one_line(tmp_path, when):
    """SIGTERM as _entry installs its import-time handlers, while that handler is still the one in force as the
    command line installs its own, or once `kin` has printed and its output is being flushed (a slow pipe): one line
    and 143, not a traceback out of console()."""
    code = (
        "import os, signal, sys\n"
        "from hexabot_sim import cli, signals\n"
        f"when = {when!r}\n"
        "calls = []\n"
        "def stop(real, call):\n"
        "    def wrapped(*args):\n"
        "        calls.append(1)\n"
        "        result = real(*args)\n"
        "        if len(calls) == call:\n"
        "            os.kill(os.getpid(), signal.SIGTERM)\n"
        "        return result\n"
        "    return wrapped\n"
        "if when == 'as the command ends':\n"
        "    cli.main = stop(cli.main, 1)\n"
        "else:  # called by _entry, then by the command line\n"
        "    signals.quiet_interruptions = stop(signals.quiet_interruptions, 1 if when == 'loading' else 2)\n"
        "from hexabot_sim._entry import console\n"
        "sys.argv = ['hexabot-sim', 'kin', 'stanford']\n"
        "console()\n"
    )
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=60)
    assert done.returncode == 128 + signal.SIGTERM, done.stderr
    assert done.stderr == "hexabot-sim: stopped by SIGTERM; nothing written\n"


@pytest.mark.slow
def test_leg_sweep_stops_promptly_and_leaves_no_worker(tmp_path):
    proc = _start(tmp_path, "run", "leg-sweep", "--set", "workers=2", "--out", "sweep")
    _wait_for_staging(tmp_path, proc)
    time.sleep(1.0)  # the workers are busy now
    children = subprocess.run(["pgrep", "-P", str(proc.pid)], capture_output=True, text=True).stdout.split()
    assert children, "the sweep should run in worker processes"
    started = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=30)
    assert time.monotonic() - started < 5.0
    assert proc.returncode == 128 + signal.SIGTERM, err
    assert "Traceback" not in err and "Exception in thread" not in err
    time.sleep(0.2)
    for pid in children:
        assert not Path(f"/proc/{pid}").exists() or "zombie" in Path(f"/proc/{pid}/status").read_text()
    assert list(tmp_path.iterdir()) == []


def test_signals_are_held_during_publish_even_with_other_threads():
    """A signal during a held block (publish, clean-up) stops the run only once the block is done."""
    import threading

    from hexabot_sim.signals import Interrupted
    from hexabot_sim.signals import raise_interrupted as _raise_interrupted

    seen = []
    stop = threading.Event()
    idle = threading.Thread(target=stop.wait)  # the kernel may deliver the signal to this thread
    idle.start()
    previous = signal.signal(signal.SIGHUP, _raise_interrupted)
    try:
        with pytest.raises(Interrupted):
            with folders.signals_held():
                os.kill(os.getpid(), signal.SIGHUP)
                time.sleep(0.05)
                seen.append("block done")
    finally:
        signal.signal(signal.SIGHUP, previous)
        stop.set()
        idle.join()
    assert seen == ["block done"]


@pytest.mark.slow
@pytest.mark.parametrize("when", ["before", "after"])
def test_a_stop_request_during_the_publish_does_not_deny_the_published_run(tmp_path, when):
    """SIGTERM while the run folder is being published (held) or just after: the run is complete, so the command
    says so and exits 0 (it said "stopped by SIGTERM; nothing written" with the run in place, found by fuzzing)."""
    out = tmp_path / "out"
    code = (
        "import os, signal, sys\n"
        "from hexabot_sim import folders, output\n"
        "real = folders._publish\n"
        "def publish(*args, **kwargs):\n"
        f"    if {when == 'before'}:\n"
        "        os.kill(os.getpid(), signal.SIGTERM)\n"
        "    final = real(*args, **kwargs)\n"
        f"    if {when == 'after'}:\n"
        "        os.kill(os.getpid(), signal.SIGTERM)\n"
        "    return final\n"
        "folders._publish = publish\n"
        "from hexabot_sim.__main__ import console\n"
        f"sys.argv = ['hexabot-sim', 'run', 'pendulum', '--set', 'duration=0.5', '--no-plots', '--out', {str(out)!r}]\n"
        "console()\n"
    )
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "-> " in done.stdout and "files:" in done.stdout
    last = done.stderr.strip().splitlines()[-1]  # after the progress line
    assert last == "hexabot-sim: SIGTERM came after the results were published; they are complete", done.stderr
    assert "nothing written" not in done.stderr and "Traceback" not in done.stderr
    assert (out / "run.json").is_file() and (out / "timeseries.csv").is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]  # no staging or replaced folder left


def _our_handlers_in(proc: subprocess.Popen, timeout: float = 60.0) -> bool:
    """Waits until the child has installed hexabot-sim's stop handlers (its SIGTERM handler: Python itself catches
    only SIGINT) and says whether MuJoCo was already loaded then.

    The signal is sent a set time after this, not after the spawn: before it lies the interpreter's own start-up,
    where no program can act, and on a loaded machine that start-up alone took over 0.12 s (a traceback from
    importing runpy, seen under pytest -n 2).
    """
    status, maps = Path(f"/proc/{proc.pid}/status"), Path(f"/proc/{proc.pid}/maps")
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        assert proc.poll() is None, proc.communicate()
        caught = int(re.search(r"SigCgt:\s*([0-9a-f]+)", status.read_text()).group(1), 16)
        if caught & (1 << (signal.SIGTERM - 1)):
            return "mujoco" in maps.read_text()
        time.sleep(0.001)
    raise AssertionError("the child never installed its stop handlers")


def test_ctrl_c_while_loading_ends_in_one_line(tmp_path):
    """Ctrl-C while numpy and MuJoCo are still being imported: no traceback, exit 130, nothing written.

    (The interpreter's own start-up, the first ~30 ms, is before any code of ours can act.)
    """
    script = [sys.executable, "-c", "import sys; from hexabot_sim._entry import console; sys.argv[0] = 'x'; console()"]
    for n, delay in enumerate((0.0, 0.05, 0.1, 0.2, 0.3)):
        out = tmp_path / f"r{n}"
        argv = [*script, "run", "pendulum", "--set", "duration=30", "--no-plots", "--out", str(out)]
        proc = subprocess.Popen(argv, cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        assert not _our_handlers_in(proc), "the handlers came after MuJoCo was loaded"
        time.sleep(delay)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
        assert b"Traceback" not in err and b"internal error" not in err, (delay, err)
        assert proc.returncode == 130 and not out.exists(), (delay, proc.returncode, err)
    assert staging_left(tmp_path) == []


@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_python_m_stopped_while_loading_ends_in_one_line(tmp_path, sig, code):
    """`python -m hexabot_sim` stopped while numpy and MuJoCo are still being imported: one line, exit 130 / 143
    (its __main__ imported the command line before any handler: a traceback, or a silent death by SIGTERM)."""
    for n, delay in enumerate((0.0, 0.08, 0.16)):
        out = tmp_path / f"r{n}"
        argv = [sys.executable, "-m", "hexabot_sim", "run", "pendulum", "--set", "duration=30", "--no-plots"]
        proc = subprocess.Popen(
            [*argv, "--out", str(out)], cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
        )
        assert not _our_handlers_in(proc), "the handlers came after MuJoCo was loaded"
        time.sleep(delay)
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
        # Exactly 128 + N: the interpreter once turned a SIGTERM's exit into a death by SIGINT (-2) after the line
        assert proc.returncode == code and len(err.splitlines()) == 1, (delay, proc.returncode, err)
        assert b"Traceback" not in err and not out.exists()


# The console script with the loading of the command line held for 2 s, saying "loading" on stdout when it begins.
_SLOW_LOADING = """import sys, time
from hexabot_sim._entry import console
class Slow:
    def find_spec(self, name, path=None, target=None):
        if name == "hexabot_sim.cli":
            print("loading", flush=True)
            time.sleep(2)
sys.meta_path.insert(0, Slow())
sys.argv[0] = "x"
console()
"""


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP])
def test_a_stop_signal_while_loading_ends_in_one_line(tmp_path, sig):
    """SIGTERM or SIGHUP while the console script loads: it killed the process without a word (a signal death)."""
    out = tmp_path / "r"
    argv = [
        sys.executable,
        "-c",
        _SLOW_LOADING,
        "run",
        "pendulum",
        "--set",
        "duration=30",
        "--no-plots",
        "--out",
        str(out),
    ]
    proc = subprocess.Popen(argv, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert proc.stdout.readline() == b"loading\n"
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + sig and not out.exists(), (proc.returncode, err)
    assert err.decode().strip() == f"hexabot-sim: stopped by {sig.name}; nothing written", err


def test_a_run_started_with_sighup_ignored_keeps_going_through_it(tmp_path):
    """Under `nohup` (SIGHUP ignored) a hangup does not stop a run: it publishes its folder and exits 0."""
    before = signal.signal(signal.SIGHUP, signal.SIG_IGN)
    try:
        proc = _start(tmp_path, "run", "pendulum", "--set", "duration=60", "--no-plots", "--out", "out")  # ~2 s
    finally:
        signal.signal(signal.SIGHUP, before)
    _wait_for_staging(tmp_path, proc)
    proc.send_signal(signal.SIGHUP)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    assert (tmp_path / "out" / "run.json").is_file() and staging_left(tmp_path) == []


def test_staging_left_by_a_killed_run_is_ignored_and_cleaned(tmp_path, capsys):
    proc = _start(tmp_path, "run", "pendulum", "--set", "duration=3000", "--out", "out")
    _wait_for_staging(tmp_path, proc)
    proc.kill()
    proc.communicate()
    assert len(staging_left(tmp_path)) == 1
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(tmp_path / "out"))
    assert code == 0, err
    code, out, _ = cli(capsys, "clean", str(tmp_path))
    assert code == 0 and "removed" in out
    assert staging_left(tmp_path) == [] and (tmp_path / "out" / "run.json").exists()
