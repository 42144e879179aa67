"""Command line: `hexabot-sim list | run | view | sweep | compare | check | kin | export | clean`; the only place errors
become exit codes (a shell over the Python API)."""

from __future__ import annotations

import atexit
import contextlib
import errno
import os
import signal
import sys
from collections.abc import Sequence
from typing import Any, NoReturn

from hexabot_sim import signals
from hexabot_sim.cli import commands, study
from hexabot_sim.cli.common import COMPLETED, DONE_SO_FAR, PROG, eprint
from hexabot_sim.cli.parser import build_parser
from hexabot_sim.errors import HexabotError, printable
from hexabot_sim.signals import PENDING_SIGNALS, PUBLISHED, RECEIVED_SIGNALS, Interrupted, stop_request

__all__ = ["build_parser", "console", "main"]


class _StdoutError(Exception):
    """Standard output could not be written (closed, full, I/O error)."""

    def __init__(self, error: OSError) -> None:
        super().__init__(error)
        self.error = error


class _GuardedStdout:
    """Wraps sys.stdout so a failing write is told apart from every other OSError (a closed pipe stays quiet)."""

    def __init__(self, stream: Any) -> None:
        self._stream = stream

    def write(self, text: str) -> int:
        try:
            return self._stream.write(text)
        except BrokenPipeError:
            raise
        except OSError as e:
            raise _StdoutError(e) from None

    def flush(self) -> None:
        try:
            self._stream.flush()
        except BrokenPipeError:
            raise
        except OSError as e:
            raise _StdoutError(e) from None

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


class _ClosedStdout:
    """Standard output when the process was started with it closed: every write fails with EBADF."""

    def write(self, text: str) -> int:
        raise OSError(errno.EBADF, "standard output is closed")

    def flush(self) -> None:
        pass

    def isatty(self) -> bool:
        return False


def _debug_requested(argv: Sequence[str]) -> bool:
    return "--debug" in argv or os.environ.get("HEXABOT_SIM_DEBUG", "") not in ("", "0")


def main(argv: Sequence[str] | None = None) -> int:
    """Runs the CLI; returns the exit code (0 ok, 1 simulation or output failed, 2 bad input, 128+N signal N)."""
    if argv is not None:  # called from Python (tests, scripts): no stop request carries over from before
        signals.reset()
    argv = list(sys.argv[1:] if argv is None else argv)
    stdout, sys.stdout = sys.stdout, _GuardedStdout(sys.stdout)
    COMPLETED.clear()
    DONE_SO_FAR.clear()
    try:
        code = _main(argv)
        sys.stdout.flush()
        return code
    except _StdoutError as e:
        done = f" ({COMPLETED[0]})" if COMPLETED else ""
        eprint(f"{PROG}: error: cannot write to standard output: {e.error.strerror or e.error}{done}")
        return 1
    finally:
        sys.stdout = stdout


def _main(argv: list[str]) -> int:
    try:
        # --debug is honoured wherever it is typed (before or after the sub-command).
        args = build_parser().parse_args([a for a in argv if a != "--debug"])
        if args.command == "view":  # draws in a window: GLFW, chosen inside cmd_view
            return commands.cmd_view(args)
        if not (args.command == "run" and args.video):
            from hexabot_sim import gl

            gl.disable_if_unused()  # nothing is drawn: a broken MUJOCO_GL must not matter
        if args.command == "list":
            return commands.cmd_list()
        if args.command == "check":
            return commands.cmd_check()
        command = {
            "kin": commands.cmd_kin,
            "export": commands.cmd_export,
            "clean": commands.cmd_clean,
            "sweep": study.cmd_sweep,
            "compare": study.cmd_compare,
            "run": commands.cmd_run,
        }[args.command]
        return command(args)
    except HexabotError as e:
        eprint(f"{PROG}: error: {e}")
        return e.exit_code
    except (_StdoutError, BrokenPipeError):
        raise
    except KeyboardInterrupt as e:
        return _interrupted(e)
    except SystemExit as e:  # argparse's --help / --version
        return e.code if isinstance(e.code, int) else 0
    except (Exception, RecursionError) as e:
        cause = _interruption_in(e)
        if cause is None and RECEIVED_SIGNALS:  # a library swallowed the stop request and failed after it
            cause = stop_request(RECEIVED_SIGNALS[-1])
        if cause is not None:  # e.g. Ctrl-C while a C extension was being imported (ImportError from it)
            return _interrupted(cause)
        if _debug_requested(argv):
            raise
        if isinstance(e, OSError) and e.errno == errno.ENAMETOOLONG:  # a path typed (or built from one typed) too long
            shown = printable(os.fsdecode(e.filename)) if e.filename is not None else "a path given"
            eprint(f"{PROG}: error: {shown!r}: name too long (a file or folder name is at most 255 bytes, a path 4095)")
            return 2
        text = " ".join(str(e).split())[:300]
        eprint(
            f"{PROG}: internal error: {type(e).__name__}{': ' + text if text else ''} -- this is a bug in "
            f"{PROG}, please report it with the output of the same command plus --debug"
        )
        return 1


def _interruption_in(error: BaseException) -> KeyboardInterrupt | None:
    """The Ctrl-C or signal behind an exception (a C extension may wrap it in its own error), if any."""
    seen = set()
    while error is not None and id(error) not in seen:
        seen.add(id(error))
        if isinstance(error, KeyboardInterrupt):
            return error
        error = error.__cause__ or error.__context__
    return None


def _interrupted(error: KeyboardInterrupt) -> int:
    """The one line and exit code of a run stopped by Ctrl-C (130) or SIGTERM/SIGHUP (128 + N)."""
    what = DONE_SO_FAR[0] if DONE_SO_FAR else "nothing written"
    if isinstance(error, Interrupted):
        eprint(f"{PROG}: stopped by {signal.Signals(error.signum).name}; {what}")
        return 128 + error.signum
    eprint(f"{PROG}: interrupted; {what}")
    return 130


def _ensure_std_streams() -> None:
    """Opens /dev/null on a closed stdin/stdout/stderr, so no file we create takes their numbers.

    Inheritable, as the standard streams are: os.open's are not, and a child (glfw's library probe, the GL probes,
    ffmpeg) started without a stderr fails (glfw's made `view` say that glfw is not installed).
    """
    for fd in (0, 1, 2):
        try:
            os.fstat(fd)
        except OSError:
            os.set_inheritable(os.open(os.devnull, os.O_RDWR), True)  # takes the lowest free number: this one
    if sys.stdout is None:  # started with stdout closed: say so at the first write
        sys.stdout = _ClosedStdout()
    if sys.stderr is None:
        sys.stderr = open(os.devnull, "w")


def console() -> NoReturn:
    """Entry point of the `hexabot-sim` console script."""
    _ensure_std_streams()
    try:
        os.environ["MPLBACKEND"] = "Agg"  # the command line draws off-screen, whatever the environment says
        signals.quiet_interruptions()
        # SIGTERM and SIGHUP stop a run exactly like Ctrl-C: clean up, exit 128 + N.
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
            if signal.getsignal(sig) is not signal.SIG_IGN:  # e.g. Ctrl-C stays ignored in a background job
                signal.signal(sig, signals.raise_interrupted)
        code = main()
        sys.stdout.flush()
    except BrokenPipeError:  # e.g. `hexabot-sim list | head`: the reader left; not an error of ours
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        code = 0
    except OSError as e:  # stdout full at the final flush
        eprint(f"{PROG}: error: cannot write to standard output: {e.strerror or e}")
        code = 1
    except KeyboardInterrupt as e:
        # A stop outside main's own handling: as the command ended (flushing a `kin`'s output into a slow pipe), or
        # before our handlers (_entry's, which raises a plain KeyboardInterrupt for SIGTERM too). It was a traceback.
        if not isinstance(e, Interrupted) and RECEIVED_SIGNALS:
            e = stop_request(RECEIVED_SIGNALS[-1])
        code = _interrupted(e)
    finally:
        signals.HOLD[0] += 1  # the outcome is decided: a stop request from now on is only recorded
    # A stop request now must not kill the exit either (Python's shutdown puts the default handlers back, which
    # would end a published run with 128 + N and no word).
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, signal.SIG_IGN)
    signals.stop_redelivering()  # a redelivery timer still running must not end the exit by SIGALRM
    if PUBLISHED[0] and PENDING_SIGNALS:
        name = signal.Signals(PENDING_SIGNALS[-1]).name
        eprint(f"{PROG}: {name} came after the results were published; they are complete")
    if RECEIVED_SIGNALS and not PUBLISHED[0]:
        # Stopped: exactly 128 + N. A KeyboardInterrupt that passed through one of the interpreter's own code runners
        # on its way to us leaves a flag that turns the exit into a death by SIGINT (-2, after the one line: about 1
        # run in 40 stopped while loading under load, `python -m` and the console script alike). The exit handlers
        # run as at a normal exit (workers, windows); only the interpreter's own teardown, which reads the flag, not.
        atexit._run_exitfuncs()
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(Exception):
                stream.flush()
        os._exit(code if isinstance(code, int) else 1)
    sys.exit(code)
