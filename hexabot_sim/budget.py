"""What one run may cost, checked before it starts: steps, memory, output and wall time against fixed limits,
with the run's own cost model (each scenario's measured seconds per step and per recorded row)."""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator
from typing import Any

from hexabot_sim.params import apart

# What one run may cost, checked before it starts (check_budget). Measured on the 2-core
# development machine (numbers in the report of issue 8): a pendulum mj_step costs 7.5-10 us,
# a leg control period with its controller 17 us; writing the CSV costs 4-9 us per value
# (np.savetxt) and a recorded row holds 400-600 bytes in memory until the run folder is written.
MAX_STEPS: int = 20_000_000  # physics steps (substeps included): ~3-6 min of bare stepping
MAX_MEMORY_BYTES: float = 2e9  # recorded arrays, derived columns and the CSV table
MAX_OUTPUT_BYTES: float = 2e9  # CSV text
MAX_SECONDS: float = 3600.0  # estimated wall time of the run including the CSV
CSV_BYTES_PER_VALUE: int = 25  # '%.17g' plus a comma
CSV_SECONDS_PER_VALUE: float = 8e-6  # np.savetxt with '%.17g', measured


def step_count(duration: float, timestep: float) -> int:
    """Number of steps that covers `duration` (the last recorded time is >= duration)."""
    return max(1, math.ceil(duration / timestep - 1e-9))


def check_duration(duration: float, timestep: float) -> None:
    """Cross-field check shared by time-stepped scenarios (raises ValueError, reported as a usage error)."""
    if timestep > duration:
        shown, limit = apart(timestep, duration, "down")
        raise ValueError(f"parameter 'timestep' must not exceed 'duration' ({limit} s); got {shown}")


def size_text(n: float) -> str:
    if n >= 1e11:
        return f"{n / 1e9:,.0f} GB"
    return f"{n / 1e9:.3g} GB" if n >= 1e8 else f"{n / 1e6:.3g} MB"


def time_text(seconds: float) -> str:
    if seconds >= 3600:
        return f"{seconds / 3600:.3g} h"
    return f"{seconds / 60:.2g} min" if seconds >= 60 else f"{seconds:.2g} s"


def over(value: float, limit: float, show: Any, scale: float, unit: str) -> tuple[str, str]:
    """show(value) and show(limit), or, where a value over its limit would read the same ("~1 h; the limit is
    1 h"), both in `unit` (of size `scale`) with apart()'s digits."""
    text, limit_text = show(value), show(limit)
    if value <= limit or text != limit_text:
        return text, limit_text
    shown, bound = apart(value / scale, limit / scale, "down")
    return f"{shown}{unit}", f"{bound}{unit}"


# While estimates() is active: the estimated seconds of every run checked by check_budget (a sweep's cost).
_ESTIMATES: list[float] | None = None


@contextlib.contextmanager
def estimates() -> Iterator[list[float]]:
    """Collects the estimated wall time [s] of each parameter object built in the block (check_budget's)."""
    global _ESTIMATES
    outer, _ESTIMATES = _ESTIMATES, []
    try:
        yield _ESTIMATES
    finally:
        _ESTIMATES = outer


def check_budget(steps: float, memory_bytes: float, output_bytes: float, seconds: float, fix: str) -> None:
    """Refuses, before it starts, a run that would not fit in memory or on disk or would take hours.

    Args:
        steps: Physics steps (MuJoCo steps or kinematic updates) of the whole run.
        memory_bytes: Estimated peak memory of the recorded and derived arrays [bytes].
        output_bytes: Estimated size of the CSV [bytes].
        seconds: Estimated wall time on the development machine [s].
        fix: What to change, e.g. "raise 'timestep' or lower 'duration'".

    Raises:
        ValueError: (reported as a usage error) with the estimates and the limits.
    """
    if _ESTIMATES is not None:
        _ESTIMATES.append(seconds)
    fits = steps <= MAX_STEPS and memory_bytes <= MAX_MEMORY_BYTES and output_bytes <= MAX_OUTPUT_BYTES
    if fits and seconds <= MAX_SECONDS:
        return
    step_text, step_limit = over(steps, MAX_STEPS, lambda n: f"{n:.3g}", 1.0, "")
    output_text, output_limit = over(output_bytes, MAX_OUTPUT_BYTES, size_text, 1e9, " GB")
    memory_text, memory_limit = over(memory_bytes, MAX_MEMORY_BYTES, size_text, 1e9, " GB")
    time_shown, time_limit = over(seconds, MAX_SECONDS, time_text, 3600.0, " h")
    raise ValueError(
        f"this run would take {step_text} steps (~{output_text} of output, ~{memory_text} in memory, "
        f"~{time_shown}); the limit is {step_limit} steps, {output_limit} of output, "
        f"{memory_limit} in memory and {time_limit}: {fix}"
    )


def check_run_cost(
    steps: int, rows: int, columns: int, step_seconds: float, row_seconds: float, row_bytes: float, fix: str
) -> None:
    """check_budget for one recorded run: `rows` CSV rows of `columns` values after `steps` physics steps.

    Args:
        step_seconds: Measured cost of one physics step [s].
        row_seconds: Measured cost of recording and post-processing one row, the CSV excluded [s].
        row_bytes: Measured peak memory per recorded row [bytes].
    """
    output = float(rows) * columns * CSV_BYTES_PER_VALUE
    seconds = steps * step_seconds + rows * (row_seconds + columns * CSV_SECONDS_PER_VALUE)
    check_budget(steps, float(rows) * row_bytes, output, seconds, fix)


def most_rows(columns: int, step_seconds: float, row_seconds: float, row_bytes: float) -> int:
    """The most CSV rows a run recording one row per physics step can have within check_run_cost's limits
    (steps, memory, output, time): the inverse of its cost model, n + 1 rows after n steps."""
    rows = min(
        MAX_MEMORY_BYTES / row_bytes,
        MAX_OUTPUT_BYTES / (columns * CSV_BYTES_PER_VALUE),
        (MAX_SECONDS + step_seconds) / (step_seconds + row_seconds + columns * CSV_SECONDS_PER_VALUE),
        MAX_STEPS + 1,
    )
    return math.floor(rows)
