"""Parameter sweeps: a full-factorial grid of one scenario's runs on any concurrent.futures.Executor."""

from __future__ import annotations

import csv
import dataclasses
import math
import os
import platform
import tempfile
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from hexabot_sim import budget, pool, registry, unused
from hexabot_sim import params as params_mod
from hexabot_sim.errors import UsageError, encodable
from hexabot_sim.pool import WALL_CLOCK_METRICS, CellJob, CellResult
from hexabot_sim.sweep_grid import parse_axis

CSV_NAME = "sweep.csv"
JSON_NAME = "sweep.json"
CELLS_DIR = "cells"  # --keep-runs: cells/cell-0000 ... one run folder per row of sweep.csv
ERROR_COLUMN = "error"
WARNINGS_COLUMN = "warnings"  # a cell's run warnings (Result.warnings), joined by " | "

MAX_CELLS: int = 100_000  # cells of one sweep (a cell is one run)
MAX_WORKERS: int = 256  # local worker processes
MAX_SWEEP_SECONDS: float = 24 * budget.MAX_SECONDS  # estimated wall time of a whole sweep (a run: 1 h)
CHECK_QUIET_SECONDS: float = 2.0  # checking the cells longer than this reports its progress ...
CHECK_REPORT_SECONDS: float = 1.0  # ... at most this often (the printer throttles its lines further)
COUNT_SECONDS: float = 10.0  # after a cell that cannot run, counting the others stops after this long


# Scenarios that are themselves grids of runs: a sweep sweeps their single-run scenario instead.
NOT_SWEEPABLE: dict[str, str] = {
    "leg-sweep": "leg-sweep is itself a grid of leg-step runs; sweep leg-step instead, "
    "e.g. --grid amplitude=0.02:0.1:5 --grid omega=log:0.5:3:6",
}


# ---------------------------------------------------------------------------------------------
# The plan: every cell resolved and validated before anything runs


@dataclasses.dataclass(frozen=True)
class Axis:
    """One swept parameter: its name, the text the user gave and its resolved values in grid order."""

    name: str
    spec: str
    values: tuple[Any, ...]
    log: bool  # given as log:START:STOP:N (drawn on a log axis)


@dataclasses.dataclass(frozen=True)
class Plan:
    """A validated sweep: scenario, axes, the fixed parameters and one parameter object per cell.

    Cells run in row-major order of the axes (the last --grid varies fastest), the order of sweep.csv.
    """

    scenario: str
    axes: tuple[Axis, ...]
    base: Any  # the scenario's parameters with --config/--set applied, before the grid (else cells[0])
    cells: tuple[Any, ...]  # (n,) resolved parameter objects
    costs: tuple[float, ...] | None = None  # (n,) estimated wall time of each cell [s]; None: no cost model

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(a.values) for a in self.axes)

    def cell_values(self, index: int) -> tuple[Any, ...]:
        """The swept values of cell `index`."""
        return tuple(getattr(self.cells[index], a.name) for a in self.axes)


def _label(names: Sequence[str], values: Sequence[Any]) -> str:
    return ", ".join(f"{n} = {cell_text(v)}" for n, v in zip(names, values, strict=True))


def plan(
    scenario_name: str,
    grid: Sequence[str],
    config: Mapping[str, Any],
    sets: Mapping[str, str],
    progress: Callable[[int, int], None] | None = None,
) -> Plan:
    """Resolves and validates every cell of the grid (nothing runs).

    A value is checked on its own (type, range) on its axis; whether it can run with the other
    parameters (cross-parameter rules, feasibility, run cost) is checked per cell, with the values
    it meets there: gait=wave is refused only where it meets a speed it cannot walk.

    Args:
        scenario_name: Scenario to sweep.
        grid: --grid specs, in order: the first is the slowest-varying axis.
        config: Parameters from --config.
        sets: Parameters from --set (fixed in every cell).
        progress: Called with (cells checked, cells) when checking takes longer than CHECK_QUIET_SECONDS,
            at most every CHECK_REPORT_SECONDS and once at the end.

    Raises:
        UsageError: naming the bad spec, value or cell and what is allowed; if any cell cannot run,
            how many cannot, the first of them and its reason.
    """
    scenario = registry.get(scenario_name)
    if scenario.name in NOT_SWEEPABLE:
        raise UsageError(NOT_SWEEPABLE[scenario.name])
    if not grid:
        raise UsageError("give at least one --grid PARAM=V1,V2,... (or START:STOP:N, log:START:STOP:N)")
    cls = scenario.params_type
    fixed = params_mod.converted(cls, scenario.defaults, config, sets)  # each on its own; together: per cell
    known = params_mod.infos(cls)
    kinds = {f.name: type(f.default) for f in dataclasses.fields(cls)}
    parsed: list[tuple[str, str, list[Any], bool]] = []
    for spec in grid:
        name, raw, log = parse_axis(spec)
        shown = spec if len(spec) <= params_mod.MAX_SHOWN else spec[: params_mod.MAX_SHOWN - 3] + "..."
        if name not in known:
            raise UsageError(f"--grid {shown!r}: unknown parameter {params_mod._show(name)}; known: {', '.join(known)}")
        if kinds[name] is tuple:
            raise UsageError(f"--grid {shown!r}: parameter {name!r} is a list and cannot be swept")
        if name in sets:
            raise UsageError(f"parameter {name!r} is given both with --set and with --grid; keep one")
        if any(name == other for other, *_ in parsed):
            raise UsageError(f"parameter {name!r} is given twice with --grid; give all its values in one")
        parsed.append((name, shown, raw, log))

    # Each value on its own first: the message names the parameter's range, not a cell.
    axes = []
    for name, shown, raw, log in parsed:
        values = []
        for value in raw:
            try:
                values.append(params_mod.converted(cls, {}, {name: value})[name])
            except UsageError as e:
                raise UsageError(f"--grid {shown!r}: {e}") from None
        seen: dict[Any, Any] = {}
        for text, value in zip(raw, values, strict=True):
            if value in seen:
                a, b = (str(t)[: params_mod.MAX_SHOWN] for t in (seen[value], text))
                same = "" if a == b else f" ({a} and {b} read as the same value)"
                raise UsageError(f"--grid {shown!r}: the value {cell_text(value)} appears twice{same}")
            seen[value] = text
        axes.append(Axis(name, grid[len(axes)], tuple(values), log))

    shape = [len(a.values) for a in axes]
    count = math.prod(shape)
    if count > MAX_CELLS:
        raise UsageError(
            f"the grid has {' x '.join(map(str, shape))} = {count} cells; the limit is {MAX_CELLS}: "
            "split the study into several sweeps"
        )
    cells, costs = _check_cells(cls, fixed, axes, progress)
    given = unused.given(cls, [config, sets]) | {a.name for a in axes}
    unused.check(cells, scenario.defaults, given)  # ignored by every cell
    try:
        base = params_mod.build(cls, fixed)
    except UsageError:  # the fixed values fail only with the swept ones' defaults: no cell has those
        base = cells[0]
    return Plan(scenario.name, tuple(axes), base, tuple(cells), costs)


def _check_cells(
    cls: type, fixed: Mapping[str, Any], axes: Sequence[Axis], progress: Callable[[int, int], None] | None
) -> tuple[list[Any], tuple[float, ...] | None]:
    """Every cell's parameter object and estimated wall time (None without a cost model), in grid order.

    Raises:
        UsageError: if a cell cannot run: how many cannot, a value no cell can run with, the first cell and why.
    """
    names = [a.name for a in axes]
    shape = [len(a.values) for a in axes]
    total = math.prod(shape)
    runs = [np.zeros(n, dtype=bool) for n in shape]  # [axis][value]: some cell with this value can run
    cells: list[Any] = []
    costs: list[float] = []
    modelled = True
    failed, checked = 0, total
    first: tuple[list[Any], str, float] | None = None  # the first cell that cannot run: values, why, when
    started = last = time.monotonic()
    reported = False
    with budget.estimates() as seconds:
        for k, index in enumerate(np.ndindex(*shape)):
            if first is not None and time.monotonic() - first[2] > COUNT_SECONDS:
                checked = k  # a walk's refusal bisects its fastest command (~60 ms): 1e5 of them take hours
                break
            values = {a.name: a.values[i] for a, i in zip(axes, index, strict=True)}
            del seconds[:]
            try:
                cells.append(params_mod.build(cls, {**fixed, **values}))
            except UsageError as e:  # a cross-parameter check (e.g. the leg's omega * timestep)
                failed += 1
                first = first or (list(values.values()), " ".join(str(e).split()), time.monotonic())
            else:
                for axis, i in enumerate(index):
                    runs[axis][i] = True
                modelled = modelled and bool(seconds)
                costs.append(float(sum(seconds)))
            if progress is not None and k % 64 == 63:
                now = time.monotonic()
                if now - started >= CHECK_QUIET_SECONDS and now - last >= CHECK_REPORT_SECONDS:
                    progress(k + 1, total)
                    last, reported = now, True
    if progress is not None and reported:
        progress(checked, total)
    if first is None:
        return cells, tuple(costs) if modelled else None
    values, reason, _ = first
    if checked < total:
        what = f"at least {failed} of {total} grid cells cannot run ({failed} of the first {checked} checked)"
        raise UsageError(f"{what}; the first, {_label(names, values)}: {reason.rstrip('.')}; shrink the grid")
    if failed == 1:
        raise UsageError(f"grid cell {_label(names, values)}: {reason}")
    dead = [(a, a.values[i]) for a, ok in zip(axes, runs, strict=True) for i in np.flatnonzero(~ok)]
    if failed == total:
        what, fix = "no grid cell can run", "change the fixed parameters or the grid"
    elif dead:
        a, value = dead[0]
        what = f"{failed} of {total} grid cells cannot run, every one with {a.name} = {cell_text(value)} among them"
        fix = f"leave {a.name} = {cell_text(value)} out of its --grid" + (
            f" ({len(dead)} values of the grid have no cell that can run)" if len(dead) > 1 else ""
        )
    else:
        what = f"{failed} of {total} grid cells cannot run"
        fix = "every value can run in some cell: split the study into sweeps whose cells all can"
    raise UsageError(f"{what}; the first, {_label(names, values)}: {reason.rstrip('.')}; {fix}")


def _time(seconds: float) -> str:
    return f"{seconds / 86400:.3g} days" if seconds >= 2 * 86400 else budget.time_text(seconds)


def check_cost(p: Plan, workers: int, where: str) -> float | None:
    """The sweep's estimated wall time on `workers` workers [s] (None without a cost model), or UsageError.

    The estimate is the scenarios' own run-cost model (what refuses a single run over MAX_SECONDS),
    summed over the cells and shared among the workers; a sweep may take MAX_SWEEP_SECONDS.
    """
    if p.costs is None:
        return None
    seconds = max(sum(p.costs) / max(workers, 1), max(p.costs, default=0.0))
    if seconds > MAX_SWEEP_SECONDS:
        shown, limit = budget.over(seconds, MAX_SWEEP_SECONDS, _time, 3600.0, " h")
        raise UsageError(
            f"this sweep would take ~{shown} ({len(p.cells)} cells, ~{_time(sum(p.costs))} of runs, on "
            f"{where}); the limit is {limit}: fewer cells, shorter runs (e.g. 'duration') "
            "or more workers (--workers, --scheduler)"
        )
    return seconds


# ---------------------------------------------------------------------------------------------
# One cell, in a worker process (local pool or Dask worker): only plain data travels back


# ---------------------------------------------------------------------------------------------
# Executors: a process pool here, or a Dask cluster; the sweep only sees concurrent.futures


def jobs(p: Plan, keep_runs: bool = False, plots: bool = True) -> list[CellJob]:
    """One job per cell of the plan (`keep_runs`: each cell's run folder comes back; `plots`: with its figures)."""
    runner = registry.get(p.scenario).runner
    keep = kept_run if keep_runs else None
    return [CellJob(i, p.scenario, cell, runner, keep, plots) for i, cell in enumerate(p.cells)]


def kept_run(job: CellJob, result: Any, sim_seconds: float) -> dict[str, bytes]:
    """A cell's run folder (--keep-runs), as relative path -> content: written in the worker by output.write_run,
    the writer of `hexabot-sim run` (figures, no video), in a private temporary folder named <CELL_PREFIX><pid>-...,
    since the worker may be on another machine than the sweep folder."""
    from hexabot_sim import folders, output

    try:
        with tempfile.TemporaryDirectory(prefix=f"{folders.CELL_PREFIX}{os.getpid()}-") as tmp:
            pool.CELL_FOLDERS.append(tmp)  # removed by the worker's signal handler if the sweep stops it
            try:
                folder = Path(tmp)
                output.write_run(folder, registry.get(job.scenario), job.params, result, sim_seconds=sim_seconds,
                                 plots=job.plots, no_video_reason="not made in a sweep")  # fmt: skip
                return {path.relative_to(folder).as_posix(): path.read_bytes() for path in sorted(folder.rglob("*"))
                        if path.is_file()}  # fmt: skip
            finally:
                pool.CELL_FOLDERS.remove(tmp)
    except OSError as e:  # the worker's disk, not the cell: every other cell would fail the same way
        raise pool.WorkerFailed(
            f"a worker ({platform.node()}) cannot write a kept run folder in its temporary folder "
            f"{tempfile.gettempdir()}: {e.strerror or e}"
        ) from None


def cell_folder(index: int, count: int) -> str:
    """The kept run folder of a row: cells/cell-0007 (zero-padded to the number of cells)."""
    return f"{CELLS_DIR}/cell-{index:0{max(4, len(str(count - 1)))}d}"


# ---------------------------------------------------------------------------------------------
# The table: sweep.csv and sweep.json


def cell_text(value: Any) -> str:
    """A value as written in sweep.csv: floats exactly (shortest round-trip form), booleans true/false, None empty."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        text = repr(value)  # the shortest text that reads back as exactly this float
        return text[:-2] if text.endswith(".0") else text
    # A file name that is not UTF-8 (robot=\xff.toml) holds lone surrogates: written as \xff (UnicodeEncodeError).
    return encodable(str(value))


@dataclasses.dataclass(frozen=True)
class Table:
    """sweep.csv in memory: the swept columns, then the metric columns, then `warnings` and `error`."""

    swept: tuple[str, ...]
    metrics: tuple[str, ...]  # column names (a metric named like a swept parameter gets a 'metric_' prefix)
    metric_names: tuple[str, ...]  # the metric each metric column holds
    rows: tuple[tuple[Any, ...], ...]  # (n, len(swept) + len(metrics) + 1), Python values
    units: dict[str, str]  # column -> unit
    docs: dict[str, str]  # metric column -> meaning

    @property
    def header(self) -> tuple[str, ...]:
        return (*self.swept, *self.metrics, WARNINGS_COLUMN, ERROR_COLUMN)

    def column(self, name: str) -> list[Any]:
        k = self.header.index(name)
        return [row[k] for row in self.rows]


def table(p: Plan, results: Sequence[CellResult]) -> Table:
    """Tabulates the results: metric columns are the union over cells, in order of first appearance."""
    swept = tuple(a.name for a in p.axes)
    names: dict[str, None] = {}
    units: dict[str, str] = {}
    docs: dict[str, str] = {}
    for r in results:
        for name in r.metrics:
            names.setdefault(name, None)
            units.setdefault(name, r.units.get(name, ""))
            docs.setdefault(name, r.docs.get(name, ""))
    metric_names = tuple(names)
    columns = tuple(f"metric_{n}" if n in swept else n for n in metric_names)
    rows = tuple(
        (*p.cell_values(r.index), *(r.metrics.get(n) for n in metric_names), " | ".join(r.warnings), r.error or "")
        for r in results
    )
    param_units = params_mod.units(type(p.base))
    column_units = {a: param_units[a] for a in swept}
    column_units |= {c: units[n] for c, n in zip(columns, metric_names, strict=True)}
    column_docs = {c: docs[n] for c, n in zip(columns, metric_names, strict=True)}
    return Table(swept, columns, metric_names, rows, column_units, column_docs)


def write_csv(path: Path, t: Table) -> None:
    """Writes sweep.csv: one row per cell in grid order, values exact, empty where a metric is missing."""
    with open(path, "w", newline="") as stream:
        writer = csv.writer(stream, lineterminator="\n")
        writer.writerow(t.header)
        for row in t.rows:
            writer.writerow([cell_text(v) for v in row])


def record(p: Plan, t: Table, results: Sequence[CellResult], executor: Mapping[str, Any], wall: float) -> dict:
    """The content of sweep.json: grid, fixed parameters, units, executor, timing."""
    swept = {a.name for a in p.axes}
    fixed, derived = {}, []
    for name in params_mod.as_dict(p.base):
        if name in swept:
            continue
        values = {getattr(cell, name) for cell in p.cells}
        if len(values) == 1:
            fixed[name] = getattr(p.cells[0], name)
        else:  # set per cell from a swept value (e.g. leg-step's duration 0 = two periods of omega)
            derived.append(name)
    seconds = [r.seconds for r in results]
    failed = [r.index for r in results if r.error]
    warned = [r.index for r in results if r.warnings]
    return {
        "scenario": p.scenario,
        "description": registry.get(p.scenario).summary,
        "grid": [{"name": a.name, "spec": a.spec, "values": list(a.values), "log": a.log} for a in p.axes],
        "cells": len(p.cells),
        "order": "row-major: the first --grid varies slowest; row i of sweep.csv is cell i",
        "failed_cells": failed,
        "warned_cells": warned,
        "fixed": fixed,
        "derived": derived,
        "columns": list(t.header),
        "units": {"params": params_mod.units(type(p.base)), "columns": t.units},
        "metric_docs": t.docs,
        "left_out": {"wall-clock metrics (differ from run to run)": sorted(WALL_CLOCK_METRICS)},
        "executor": dict(executor),
        "timing": {
            "wall_time": wall,
            "cell_time_sum": float(sum(seconds)),
            "cell_time_mean": float(np.mean(seconds)) if seconds else 0.0,
            "cell_time_max": float(max(seconds, default=0.0)),
            "parallel_speedup": float(sum(seconds) / wall) if wall > 0 else None,
        },
    }


def keeper(folder: Path, count: int) -> tuple[Callable[[CellResult], None], list[int]]:
    """(on_result for pool.run_cells that writes each --keep-runs cell's run folder under `folder`/cells/,
    a one-item list counting the folders written)."""
    kept = [0]

    def keep(result: CellResult) -> None:
        if result.files:
            cell = folder / cell_folder(result.index, count)
            cell.mkdir(parents=True)
            for relative, content in result.files.items():
                (cell / relative).parent.mkdir(parents=True, exist_ok=True)
                (cell / relative).write_bytes(content)
            kept[0] += 1

    return keep, kept


def write_folder(
    folder: Path,
    p: Plan,
    results: Sequence[CellResult],
    executor: Mapping[str, Any],
    wall: float,
    *,
    figures: Callable[[Plan, Table], Mapping[str, Any]] | None,
    kept: int | None,
) -> tuple[Table, list[str]]:
    """Writes the sweep folder's files (sweep.csv, the figures, sweep.json, report.html) into `folder`, a staging
    folder (`figures`: sweep_figures.figures, or None for no figures; `kept`: the --keep-runs folders written,
    None without --keep-runs); returns the table and the files."""
    from hexabot_sim import output, report

    t = table(p, results)
    write_csv(folder / CSV_NAME, t)
    files = [CSV_NAME, JSON_NAME]
    if figures is not None:
        with output.package_style():
            files += output.write_figures(figures(p, t), folder)
    out = record(p, t, results, executor, wall)
    out |= {"kept_runs": f"{CELLS_DIR}/ ({kept} folders)" if kept is not None else None}
    out["versions"] = output.versions()
    out["files"] = [*files, "report.html"]
    output.write_json(folder / JSON_NAME, out)
    docs = {name: info.doc for name, (info, _) in params_mod.infos(type(p.base)).items()}
    (folder / "report.html").write_text(report.sweep_page(out, docs, folder))
    return t, files
