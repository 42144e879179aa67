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
    """The files a command reads: its --config, and every file a parameter names (a walk's schedule or waypoints,
    a robot file) in the layers or the grid's values; --out may not be, hold or lie inside any of them."""
    import os

    from hexabot_sim import params as params_mod

    files = [config] if config is not None else []
    takes_file = {n for n, (info, _) in params_mod.infos(cls).items() if info.table or info.name_or_file}
    values = [v for layer in layers for n, v in layer.items() if n in takes_file] + list(grid_values)
    return files + [v for v in values if isinstance(v, (str, os.PathLike)) and os.path.isfile(v)]
