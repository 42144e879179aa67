"""Exception types that the CLI turns into exit codes and one-line messages."""

from __future__ import annotations

_CONTROLS = {code: f"\\x{code:02x}" for code in (*range(0x20), *range(0x7F, 0xA0))}  # C0, DEL, C1


def encodable(text: str) -> str:
    """`text` with the bytes of a name that is not UTF-8 (Python's lone surrogates) shown as \\xNN, so that it can be
    written as UTF-8 (a report page, a CSV cell: they raised UnicodeEncodeError)."""
    return text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")


def printable(text: str) -> str:
    """`text` (a path, possibly with bytes that are not UTF-8: shown as \\xNN) as text printable anywhere.

    Control characters are shown as \\xNN too: a folder named with ESC or CR would recolour or overwrite the terminal.
    """
    return encodable(text).translate(_CONTROLS)


class RunWarning(UserWarning):
    """A run that finished but whose figures say something is physically off (`Result.warnings` holds the text).

    `result` is the run's Result: under `warnings.simplefilter("error")` the warning is raised after the run, and the
    result is not lost with it.
    """

    def __init__(self, message: str, result: object = None) -> None:
        super().__init__(message)
        self.result = result

    def __reduce__(self) -> tuple:
        return RunWarning, (str(self),)  # the text crosses processes; a Result (a compiled model) does not pickle


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


class InstallError(HexabotError):
    """The installation is incomplete: a file the package ships (its MJCF models) is missing."""

    exit_code = 1


def lookup(table: dict, name: str, what: str):
    """table[name], or a UsageError "unknown <what> '<name>'; known: ..." listing the allowed names."""
    if not isinstance(name, str):  # a list was a TypeError (unhashable); a Path "unknown 'pendulum'; known: pendulum"
        raise UsageError(f"{what} must be a name (a string); got {type(name).__name__} {name!r}")
    try:
        return table[name]
    except KeyError:
        raise UsageError(f"unknown {what} '{name}'; known: {', '.join(table)}") from None
