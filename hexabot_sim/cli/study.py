"""The commands over many runs: sweep (a grid of runs on a local pool or a Dask cluster) and compare."""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import time
from typing import Any

from hexabot_sim import params as params_mod
from hexabot_sim import registry
from hexabot_sim.cli.common import COMPLETED, PROG, eprint, inputs
from hexabot_sim.cli.progress import SweepProgress
from hexabot_sim.errors import UsageError


def cmd_sweep(args: argparse.Namespace) -> int:
    from hexabot_sim import dask_cluster, folders, pool, sweep

    sets = params_mod.parse_assignments(args.sets)
    cls = registry.get(args.scenario).params_type
    config = params_mod.read_config(args.config, cls) if args.config is not None else {}
    if args.scheduler is not None and args.workers is not None:
        raise UsageError("--workers is for the local pool; with --scheduler the cluster's workers run the cells")
    name = f"sweep-{registry.get(args.scenario).name}"
    checking = SweepProgress(f"{name}: checking")  # speaks only if checking the cells takes seconds
    plan = sweep.plan(args.scenario, args.grid, config, sets, checking)  # every cell validated: nothing runs before
    overridden = [axis.name for axis in plan.axes if axis.name in config]  # (--set and --grid together: refused)
    if overridden:  # a config file's value replaced without a word
        names = ", ".join(f"'{name}'" for name in overridden)
        eprint(f"{PROG}: warning: --grid sweeps {names}, which --config {args.config} also sets: the grid's values "
               "are used")  # fmt: skip
    if args.out is not None:
        cls = registry.get(args.scenario).params_type
        grid_values = [v for axis in plan.axes for v in axis.values]
        folders.check_not_input(args.out, inputs(args.config, cls, [config, sets], grid_values))
        folders.check_out(args.out, force=args.force)
    if args.scheduler is not None:
        # Connects now: an unreachable scheduler writes nothing.
        executors: Any = dask_cluster.dask_executor(args.scheduler)
    else:
        workers = min(args.workers or pool.workers_default(), len(plan.cells))
        cores = os.cpu_count() or 1  # more processes than cores share them: they were counted as running at once
        on = f" on {cores} core{'s' if cores > 1 else ''}" if workers > cores else ""
        sweep.check_cost(plan, min(workers, cores), f"{workers} local process{'es' if workers > 1 else ''}{on}")
        executors = contextlib.nullcontext((pool.local_executor(workers), workers))
    started = time.perf_counter()
    with executors as (executor, workers), folders.run_folder(args.out, name, force=args.force) as run:
        threads = f"{workers} worker thread{'s' if workers != 1 else ''}"
        where = f"Dask scheduler {args.scheduler} ({threads})" if args.scheduler else None
        if where:  # the cluster's size is known once connected (the staging folder goes with the refusal)
            sweep.check_cost(plan, workers, where)
        where = where or f"{workers} local process{'es' if workers > 1 else ''}"
        keep, kept = sweep.keeper(run.path, len(plan.cells))
        jobs = sweep.jobs(plan, args.keep_runs, plots=not args.no_plots)
        results = pool.run_cells(executor, jobs, SweepProgress(name), keep)
        wall = time.perf_counter() - started
        executor_record = {"kind": "dask" if args.scheduler else "local processes", "workers": workers}
        executor_record |= {"scheduler": args.scheduler} if args.scheduler else {}
        figures = None
        if not args.no_plots:
            from hexabot_sim import plots, sweep_figures

            plots.use_agg()
            figures = sweep_figures.figures
        table, files = sweep.write_folder(run.path, plan, results, executor_record, wall, figures=figures,
                                          kept=kept[0] if args.keep_runs else None)  # fmt: skip
    assert run.final is not None
    total = time.perf_counter() - started
    failed = [r for r in results if r.error]
    shape = " x ".join(f"{len(a.values)} {a.name}" for a in plan.axes)
    COMPLETED[:] = [f"the sweep folder {folders.display_path(run.final)} is complete"]

    def label(index: int) -> str:  # a cell by its swept values
        values = plan.cell_values(index)
        return ", ".join(f"{n} = {sweep.cell_text(v)}" for n, v in zip(table.swept, values, strict=True))

    if failed:
        first = failed[0]
        print(
            f"{PROG}: warning: {len(failed)} of {len(results)} cells failed (rows with an 'error' in "
            f"{sweep.CSV_NAME}); the first, {label(first.index)}: {first.error}",
            file=sys.stderr,
        )
    warned = [r for r in results if r.warnings]
    if warned:  # each cell's run warnings are in sweep.csv; said here as a failed cell is
        eprint(f"{PROG}: warning: {len(warned)} of {len(results)} cells warned (the '{sweep.WARNINGS_COLUMN}' column "
               f"of {sweep.CSV_NAME}); the first, {label(warned[0].index)}: {warned[0].warnings[0]}")  # fmt: skip
    cell_time = sum(r.seconds for r in results)
    print(
        f"{name}: {len(results)} cells ({shape}) on {where} in {total:.2f} s "
        f"(cells {cell_time:.2f} s in all) -> {folders.display_path(run.final)}"
    )
    print(
        f"  cells ok: {len(results) - len(failed)}, failed: {len(failed)}"
        + (f", warned: {len(warned)}" if warned else "")
    )
    figures = [f for f in files if f.endswith(".png")]
    print(f"  files: {sweep.CSV_NAME}, {sweep.JSON_NAME}, {len(figures)} figures" + (
        f", {sweep.CELLS_DIR}/ ({kept[0]} run folders)" if args.keep_runs else ""))  # fmt: skip
    return 0


def cmd_compare(args: argparse.Namespace) -> int:
    from hexabot_sim import compare, folders, output

    runs = compare.load_all(args.runs)  # refuses anything that is not a run folder, before writing
    # The default runs/compare-<stamp> too: from inside a run folder (cd r2; compare . ../r1) it was written into it.
    folders.check_not_input(folders.default_out("compare") if args.out is None else args.out, args.runs)
    if args.out is not None:
        folders.check_out(args.out, force=args.force)
    table = compare.rows(runs)
    shared = compare.shared_columns([compare.header(r) for r in runs])
    with folders.run_folder(args.out, "compare", force=args.force) as run:
        compare.write_csv(run.path / compare.CSV_NAME, runs, table)
        files = [compare.CSV_NAME, compare.JSON_NAME]
        if not args.no_plots:
            from hexabot_sim import plots

            plots.use_agg()
            with output.package_style():
                files += output.write_figures(compare.figures(runs, eprint), run.path)
        output.write_json(run.path / compare.JSON_NAME, compare.record(runs, table, shared, files))
    assert run.final is not None
    COMPLETED[:] = [f"the compare folder {folders.display_path(run.final)} is complete"]
    print(compare.text(runs, table), end="")
    overlaid = f"{len(shared) - 1} shared columns overlaid" if len(shared) > 1 else "no shared columns to overlay"
    if args.no_plots:  # their CSVs were not read: nothing was overlaid
        overlaid = f"{max(len(shared) - 1, 0)} shared columns, not plotted (--no-plots)"
    print(f"compare: {len(runs)} runs, {overlaid} -> {folders.display_path(run.final)}")
    print(f"  files: {', '.join(files)}")
    return 0
