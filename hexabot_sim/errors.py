"""Exception types that the CLI turns into exit codes and one-line messages."""

from __future__ import annotations


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


def lookup(table: dict, name: str, what: str):
    """table[name], or a UsageError "unknown <what> '<name>'; known: ..." listing the allowed names."""
    try:
        return table[name]
    except KeyError:
        raise UsageError(f"unknown {what} '{name}'; known: {', '.join(table)}") from None
