"""Parameters a user gave that the run makes no use of (a kerb's distance with no kerb): refused in one line.

A parameter class may define `ignored(self) -> dict[str, str]`: the parameters it makes no use of with its other
values, each with why and what would use it ("without stairs: set stairs_rise"). A parameter
is refused only when the user gave it (a config file, --set, a keyword of `api.run`, a sweep's axis) a value
other than the scenario's default and no run uses it (in a sweep: no cell), and a sweep whose cells with stairs use
stairs_run is not. A layer that gives every parameter (a run.json's "params", `Result.params`, a TOML written from
them) repeats a run: its values are not the user's choice, so a sweep's cell without stairs, which records the
sweep's stairs_count, or a run from before this check, repeats as it ran (only the other layers' are checked).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Collection, Mapping, Sequence
from typing import Any

from hexabot_sim import params
from hexabot_sim.errors import UsageError


def given(cls: type, layers: Sequence[Mapping[str, Any]]) -> set[str]:
    """The names of the parameters the user set in `layers`, less those of a layer that gives every parameter of
    `cls` (a repeat of a run from its recorded parameters)."""
    every = set(params.infos(cls))
    return {name for layer in layers if not every <= set(layer) for name in layer}


def check(runs: Sequence[Any], defaults: Mapping[str, Any], given: Collection[str]) -> None:
    """Raises UsageError for the first parameter (in declaration order) in `given` that every one of `runs` (the
    parameter objects of a run, or of a sweep's cells) ignores, set in some of them to other than its default
    (the class's, then the scenario's `defaults`)."""
    if not runs or not hasattr(type(runs[0]), "ignored"):
        return
    unused = set(given)
    for p in runs:
        unused &= set(p.ignored())
        if not unused:
            return
    cls = type(runs[0])
    default = {f.name: f.default for f in dataclasses.fields(cls)} | params.converted(cls, defaults)
    for name in params.infos(cls):
        if name not in unused:
            continue
        for p in runs:
            value = getattr(p, name)
            if value != default[name]:
                shown = str(value)
                if isinstance(value, float):  # exactly: 0.5000001 shown as 0.5, the default, was refused "= 0.5"
                    shown = f"{value:g}" if float(f"{value:g}") == value else repr(value)
                raise UsageError(f"parameter {name!r} = {shown} has no effect {p.ignored()[name]}, or leave it out")
