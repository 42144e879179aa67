"""What every command shares: the program's name, one-line messages on stderr, what is done so far."""

from __future__ import annotations

import contextlib
import sys

from hexabot_sim.errors import printable

PROG = "hexabot-sim"

# What was completed before standard output failed, for the error message (e.g. the run folder).
COMPLETED: list[str] = []

# What a command that is no run had already done when it was stopped (clean: the folders it removed).
DONE_SO_FAR: list[str] = []


def eprint(text: str) -> None:
    """One line on stderr; a closed or full stderr must not change the exit code (nothing else can be told).

    Control characters (a path or a run.json name holding a newline, CR or ESC) are shown as \\xNN: one line, and
    nothing that rewrites the terminal.
    """
    text = printable(text)
    try:
        print(text, file=sys.stderr, flush=True)
    except UnicodeEncodeError:  # e.g. a path in a non-UTF-8 locale
        with contextlib.suppress(OSError, ValueError):
            print(text.encode("ascii", "backslashreplace").decode(), file=sys.stderr, flush=True)
    except (OSError, ValueError):
        pass


def inputs(config: str | None, cls: type, layers: list[dict], grid_values: list = ()) -> list[str]:
    """The files a command reads (params.input_files): --out may not be, hold or lie inside any of them."""
    from hexabot_sim import params as params_mod

    return params_mod.input_files(config, cls, layers, grid_values)
