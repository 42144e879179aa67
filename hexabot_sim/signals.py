"""Stop requests (Ctrl-C, SIGTERM, SIGHUP): what was received, holds over publishing, the command line's handler."""

from __future__ import annotations

import contextlib
import os
import signal
import sys
from collections.abc import Iterator
from typing import Any

# Signals the command line received (Ctrl-C, SIGTERM, SIGHUP), newest last. A library may catch the
# exception a signal raised in the middle of an import (and fall back silently): the run checks this
# before it publishes anything, so a stop request is never lost.
RECEIVED_SIGNALS: list[int] = []
# While HOLD[0] > 0 (publishing, cleaning up) the command line's handler only records a signal in
# PENDING_SIGNALS; the hold raises it when it ends (see signals_held).
HOLD: list[int] = [0]
PENDING_SIGNALS: list[int] = []
# True once the run folder is published: a stop request after that comes too late to stop anything, so the
# command line's handler only records it (the run completes and says so) and no hold raises it.
PUBLISHED: list[bool] = [False]


def stop_request(signum: int) -> KeyboardInterrupt:
    """The exception a stop signal raises: KeyboardInterrupt for Ctrl-C, Interrupted(N) for SIGTERM/SIGHUP."""
    return KeyboardInterrupt() if signum == signal.SIGINT else Interrupted(signum)


@contextlib.contextmanager
def signals_held() -> Iterator[None]:
    """Delays Ctrl-C, SIGTERM and SIGHUP until the block is done, then raises the stop request.

    Works with the command line's handler (raise_interrupted below), which only records a signal while
    a hold is on: no handler is swapped, and the kernel may hand the signal to any thread. (Outside
    the command line Python's own Ctrl-C handler is in force and the hold does nothing.)
    """
    HOLD[0] += 1
    try:
        yield
    finally:
        HOLD[0] -= 1
        if HOLD[0] == 0 and PENDING_SIGNALS and not PUBLISHED[0]:
            signum = PENDING_SIGNALS[-1]
            PENDING_SIGNALS.clear()
            raise stop_request(signum)


class Interrupted(KeyboardInterrupt):
    """Ctrl-C, SIGTERM or SIGHUP: the run stops, cleans up and exits with 128 + the signal number."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum


# The process whose stop requests these are: a child forked from it (a sweep's worker) inherits the handler below
# until its pool initializer replaces it, and must not raise the parent's stop request in its own start-up.
_OWNER: list[int] = [os.getpid()]


def raise_interrupted(signum: int, frame: Any) -> None:
    """Ctrl-C, SIGTERM and SIGHUP stop the run; while a publish or clean-up is held, only after it.

    In a forked child that has not put its own handlers in place yet (a pool worker still starting, which the
    stopping sweep terminates) the child just ends, at once and without a word: raising there printed the worker's
    "Exception in initializer:" traceback on the command line's stderr (found by fuzzing).
    """
    if os.getpid() != _OWNER[0]:
        os._exit(128 + signum)
    RECEIVED_SIGNALS.append(signum)
    if HOLD[0] > 0 or PUBLISHED[0]:  # held, or too late: the results are published
        PENDING_SIGNALS.append(signum)
        return
    raise stop_request(signum)


def reset() -> None:
    """Forgets every stop request (a new command called from Python starts clean)."""
    RECEIVED_SIGNALS.clear()
    PENDING_SIGNALS.clear()
    PUBLISHED[0] = False


REDELIVERY_DELAY: float = 0.005  # [s] a swallowed stop request is raised again this long after

# True once quiet_interruptions has its SIGALRM handler (the command line's): swallowed stop requests are redelivered.
REDELIVERING: list[bool] = [False]


def quiet_interruptions() -> None:
    """A stop request raised where Python cannot propagate it (a weakref callback of the import system, a __del__,
    an after-fork hook) is not printed as "Exception ignored ... Traceback": it is recorded, and raised again
    REDELIVERY_DELAY later (by SIGALRM), where the program is by then (again if it lands in such a place once more).

    Polling RECEIVED_SIGNALS catches it only where a loop looks: numba's compiler frees thousands of LLVM objects in
    __del__ and went on compiling for a minute; the pool's fork swallowed one in logging's after-fork hook.
    """
    default = sys.unraisablehook

    def hook(unraisable: sys.UnraisableHookArgs) -> None:
        if not isinstance(unraisable.exc_value, KeyboardInterrupt):
            default(unraisable)
        elif REDELIVERING[0]:
            with contextlib.suppress(OSError, ValueError):
                signal.setitimer(signal.ITIMER_REAL, REDELIVERY_DELAY)

    sys.unraisablehook = hook
    if hasattr(signal, "setitimer") and signal.getsignal(signal.SIGALRM) in (signal.SIG_DFL, _redelivered):
        signal.signal(signal.SIGALRM, _redelivered)  # main thread only: the command line's start
        REDELIVERING[0] = True


def _redelivered(signum: int, frame: Any) -> None:
    """SIGALRM after a stop request was swallowed: the stop signal's handler again (it records the request again and
    raises it, or only records it while a hold is on or once the results are published)."""
    if not RECEIVED_SIGNALS:
        return
    stop = RECEIVED_SIGNALS[-1]
    handler = signal.getsignal(stop)
    if callable(handler):
        handler(stop, frame)


def stop_redelivering() -> None:
    """No swallowed stop request is raised again from now on (the command line's outcome is decided)."""
    if REDELIVERING[0]:
        with contextlib.suppress(OSError, ValueError):
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, signal.SIG_IGN)
        REDELIVERING[0] = False
