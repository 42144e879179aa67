"""Exception types that the CLI turns into exit codes and one-line messages, and its stop-signal bookkeeping."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

_CONTROLS = {code: f"\\x{code:02x}" for code in (*range(0x20), *range(0x7F, 0xA0))}  # C0, DEL, C1


def printable(text: str) -> str:
    """`text` (a path, possibly with bytes that are not UTF-8: shown as \\xNN) as text printable anywhere.

    Control characters are shown as \\xNN too: a folder named with ESC or CR would recolour or overwrite the terminal.
    """
    return text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace").translate(_CONTROLS)


class HexabotError(Exception):
    """Base class of every error hexabot-sim raises on purpose."""

    exit_code = 1


class UsageError(HexabotError, ValueError):
    """Bad input from the user: unknown name, malformed or out-of-range value, unwritable path.

    A ValueError too, so Python callers of the API (`hexabot_sim.run`) can catch it as one.
    """

    exit_code = 2


class SimulationError(HexabotError):
    """The simulation went unstable (MuJoCo warning or non-finite state)."""

    exit_code = 1


class OutputError(HexabotError):
    """The run folder could not be written (disk full, permissions changed, taken by another run)."""

    exit_code = 1


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
    import signal

    return KeyboardInterrupt() if signum == signal.SIGINT else Interrupted(signum)


@contextlib.contextmanager
def signals_held() -> Iterator[None]:
    """Delays Ctrl-C, SIGTERM and SIGHUP until the block is done, then raises the stop request.

    Works with the command line's handler (hexabot_sim.__main__), which only records a signal while
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


def lookup(table: dict, name: str, what: str):
    """table[name], or a UsageError "unknown <what> '<name>'; known: ..." listing the allowed names."""
    try:
        return table[name]
    except KeyError:
        raise UsageError(f"unknown {what} '{name}'; known: {', '.join(table)}") from None
