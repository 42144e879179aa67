"""A sweep's --grid axis as typed: a list of values, a linear range or a log range (sweep.py plans the grid)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from hexabot_sim import params as params_mod
from hexabot_sim.errors import UsageError

MAX_AXIS_POINTS: int = 10_000  # values of one --grid axis


def _number(text: str, what: str, spec: str) -> float:
    value = params_mod._to_float(text)
    if value is None or not math.isfinite(value):
        raise UsageError(f"--grid {spec!r}: {what} must be a finite number; got {text!r}")
    return value


def parse_axis(spec: str) -> tuple[str, list[Any], bool]:
    """Parses PARAM=V1,V2,... | PARAM=START:STOP:N | PARAM=log:START:STOP:N into (name, raw values, log).

    Raises:
        UsageError: for a malformed spec, a count below 2 or above MAX_AXIS_POINTS, or a log range not > 0.
    """
    shown = spec if len(spec) <= params_mod.MAX_SHOWN else spec[: params_mod.MAX_SHOWN - 3] + "..."
    name, sep, text = spec.partition("=")
    name, text = name.strip(), text.strip()
    if not sep or not name or not text:
        raise UsageError(
            f"malformed --grid {shown!r}: expected PARAM=V1,V2,... or PARAM=START:STOP:N or PARAM=log:START:STOP:N"
        )
    if ":" not in text:
        items = [v.strip() for v in text.split(",", MAX_AXIS_POINTS)]
        if any(not v for v in items):
            raise UsageError(f"--grid {shown!r}: empty value in the list (two commas, or one at an end)")
        if len(items) > MAX_AXIS_POINTS:
            raise UsageError(f"--grid {shown!r}: at most {MAX_AXIS_POINTS} values per axis")
        return name, items, False
    parts = text.split(":")
    log = parts[0].strip().casefold() == "log"
    parts = parts[1:] if log else parts
    if len(parts) != 3:
        raise UsageError(f"malformed --grid {shown!r}: a range is START:STOP:N or log:START:STOP:N")
    start, stop = _number(parts[0], "START", shown), _number(parts[1], "STOP", shown)
    count = params_mod._to_float(parts[2])  # None, nan and inf fail the range test (int() would raise)
    if count is None or not 2 <= count <= MAX_AXIS_POINTS or count != int(count):
        raise UsageError(
            f"--grid {shown!r}: N must be a whole number from 2 to {MAX_AXIS_POINTS} (the number of values, "
            f"both ends included); got {parts[2].strip()[: params_mod.MAX_SHOWN]!r}"
        )
    if start == stop:
        raise UsageError(f"--grid {shown!r}: START and STOP are equal; give the value with --set instead")
    if log and (start <= 0 or stop <= 0):
        raise UsageError(f"--grid {shown!r}: a log range needs START > 0 and STOP > 0")
    n = int(count)
    with np.errstate(all="ignore"):  # a span past the largest float (-1e308:1e308): no warning on stderr
        if log:
            values = np.geomspace(start, stop, n)
        elif math.isfinite(stop - start):
            values = np.linspace(start, stop, n)
        else:
            t = np.linspace(0.0, 1.0, n)
            values = start * (1 - t) + stop * t
    values[0], values[-1] = start, stop  # exactly as typed
    if not np.isfinite(values).all():
        raise UsageError(f"--grid {shown!r}: the values between START and STOP are not all finite numbers")
    return name, [float(v) for v in values], log
