"""Cells of a study run on any concurrent.futures.Executor (a local process pool or a Dask cluster's)."""

from __future__ import annotations

import concurrent.futures
import contextlib
import dataclasses
import math
import multiprocessing
import os
import shutil
import signal
import sys
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from typing import Any

import numpy as np

from hexabot_sim.errors import HexabotError
from hexabot_sim.signals import RECEIVED_SIGNALS, signals_held, stop_request

WORKER_WAIT: float = 30.0  # [s] how long a cluster without workers is given to get one
STOP_GRACE: float = 2.0  # [s] how long a stopped local worker is given to clean up before it is killed


# Metrics that measure the computer, not the physics (wall time): left out of sweep.csv, whose bytes
# must not depend on the machine, the load or the executor.
WALL_CLOCK_METRICS: frozenset[str] = frozenset({"real_time_factor"})


class WorkerFailed(HexabotError):
    """A worker could not run a cell at all (process died, package missing on a cluster worker)."""

    exit_code = 1


@dataclasses.dataclass(frozen=True)
class CellJob:
    """What a worker needs to run one cell (pickled to it: functions travel by their module and name).

    Attributes:
        index: Row of the cell in its study.
        scenario: Scenario name, handed to `runner`.
        params: The scenario's resolved parameters for this cell.
        runner: The scenario module's `run(name, params)`.
        keep: Optional `keep(job, result, seconds) -> {relative path: bytes}`: files of the cell's run folder
            to send back (the sweep's --keep-runs), or None.
        plots: Whether a kept run folder has the scenario's figures.
    """

    index: int
    scenario: str
    params: Any
    runner: Callable[..., Any]
    keep: Callable[..., dict[str, bytes]] | None = None
    plots: bool = True


@dataclasses.dataclass
class CellResult:
    """What one cell sends back: its scalar metrics (JSON-clean), or the error that stopped it."""

    index: int
    metrics: dict[str, Any]
    units: dict[str, str]
    docs: dict[str, str]
    error: str | None
    seconds: float  # wall time in the worker [s]
    files: dict[str, bytes] | None = None  # --keep-runs: relative path -> content of the cell's run folder
    warnings: list[str] = dataclasses.field(default_factory=list)  # the run's Result.warnings (run.json's)


def _scalar(value: Any) -> tuple[bool, Any]:
    """(is a scalar, JSON-clean value): numpy numbers become Python numbers, non-finite floats None."""
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return True, None
    return value is None or isinstance(value, (bool, int, float, str)), value


def _collect(metrics: Mapping[str, Any], units: Mapping[str, str], docs: Mapping[str, str]) -> tuple[dict, dict, dict]:
    out = {}
    for name, value in metrics.items():
        ok, clean = _scalar(value)
        if ok and name not in WALL_CLOCK_METRICS:
            out[name] = clean
    return out, {k: units.get(k, "") for k in out}, {k: docs.get(k, "") for k in out}


def run_cell(job: CellJob) -> CellResult:
    """Runs one cell; a cell that fails (diverges, or anything else) is a result with its message, not a crash."""
    started = time.perf_counter()
    try:
        result = job.runner(job.scenario, job.params)
        metrics, units, docs = _collect(
            {k: m.value for k, m in result.metrics.items()},
            {k: m.unit for k, m in result.metrics.items()},
            {k: m.doc for k, m in result.metrics.items()},
        )
        files = job.keep(job, result, time.perf_counter() - started) if job.keep is not None else None
        return CellResult(job.index, metrics, units, docs, None, time.perf_counter() - started, files,
                          list(result.warnings))  # fmt: skip
    except (KeyboardInterrupt, MemoryError, WorkerFailed):
        raise
    except HexabotError as e:
        message = " ".join(str(e).split())
    except Exception as e:  # one cell's failure must not cost the other cells
        message = f"internal error: {type(e).__name__}: {' '.join(str(e).split())[:300]} (a bug, please report it)"
    return CellResult(job.index, {}, {}, {}, message, time.perf_counter() - started)


# Folders a worker is writing for a cell (a kept run folder): removed if the worker is stopped. `hexabot-sim
# clean` removes those of workers killed with SIGKILL (see folders.CELL_PREFIX).
CELL_FOLDERS: list[str] = []  # the kept-run folder this worker is writing, if any


def _worker_stopped(signum: int, frame: Any) -> None:
    """SIGTERM/SIGHUP in a worker (the sweep stopping it): remove the cell folder it was writing, exit at once."""
    for path in list(CELL_FOLDERS):
        shutil.rmtree(path, ignore_errors=True)
    os._exit(128 + signum)


def _worker_init() -> None:
    """Worker processes leave Ctrl-C to the parent (which stops them) and die with it (Linux)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, _worker_stopped)
    signal.signal(signal.SIGHUP, _worker_stopped)
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            pr_set_pdeathsig = 1
            ctypes.CDLL(None, use_errno=True).prctl(pr_set_pdeathsig, signal.SIGKILL)
        except (OSError, AttributeError):
            pass


def local_executor(workers: int) -> concurrent.futures.ProcessPoolExecutor:
    """A pool of `workers` processes that ignore Ctrl-C and die with this process."""
    # fork is cheap and safe here (no GL, no threads yet); spawn elsewhere.
    methods = multiprocessing.get_all_start_methods()
    context = multiprocessing.get_context("fork" if "fork" in methods else "spawn")
    return concurrent.futures.ProcessPoolExecutor(max_workers=workers, mp_context=context, initializer=_worker_init)


def stop(executor: concurrent.futures.Executor, futures: Sequence[concurrent.futures.Future]) -> None:
    """Cancels what has not started and stops what is running: local workers are terminated at once."""
    if isinstance(executor, concurrent.futures.ProcessPoolExecutor):
        # No future is cancelled here: the pool marks every unfinished one broken when its workers die, and Python
        # 3.11's pool raised InvalidStateError in its own thread (a traceback on stderr) on one cancelled before.
        processes = list((getattr(executor, "_processes", None) or {}).values())
        for process in processes:
            with contextlib.suppress(OSError, ValueError):
                process.terminate()
        # A worker inside a long C call (a compile, a kernel) runs its SIGTERM handler only when the call returns:
        # it is given STOP_GRACE, then killed, so the pool's own shutdown below never waits on a live worker.
        deadline = time.monotonic() + STOP_GRACE
        for process in processes:
            with contextlib.suppress(OSError, ValueError, AssertionError):
                process.join(timeout=max(0.0, deadline - time.monotonic()))
                if process.is_alive():
                    process.kill()
                    process.join(timeout=1.0)
        executor.shutdown(wait=True)
    else:  # Dask: cancel the tasks on the scheduler; its workers stay up for the next job
        for future in futures:
            future.cancel()
        executor.shutdown(wait=False)


def run_cells(
    executor: concurrent.futures.Executor,
    jobs: Sequence[CellJob],
    progress: Callable[[int, int], None] | None = None,
    on_result: Callable[[CellResult], None] | None = None,
) -> list[CellResult]:
    """Runs every job on the executor; results come back in job order whatever order they finish in.

    `on_result` sees each result as it arrives (e.g. to write its kept run folder). On any exception
    in the caller's thread (Ctrl-C, SIGTERM) every worker is stopped before it propagates.

    Raises:
        WorkerFailed: if a worker could not run a cell at all (it died, or cannot import hexabot_sim).
    """
    results: list[CellResult | None] = [None] * len(jobs)
    futures: list[concurrent.futures.Future] = []
    finished = False
    try:
        # Started (the workers forked) and fed under the hold: a stop signal is raised once every submit returned. One
        # that landed in multiprocessing's Finalize.__init__ as a worker started left a half-made finalizer whose
        # callback printed "Exception ignored ... AttributeError: 'Finalize' object has no attribute '_key'" on stderr
        # after the one-line message (found by fuzzing); one in logging's after-fork hook was swallowed.
        with signals_held():
            futures = [executor.submit(run_cell, job) for job in jobs]
        if progress is not None:
            progress(0, len(jobs))
        for done, future in enumerate(_completed(futures, len(jobs), progress, executor), start=1):
            try:
                result = future.result()
            except concurrent.futures.CancelledError:
                client = getattr(executor, "_client", None)  # Dask cancels every future when its scheduler is gone
                if client is not None and getattr(client, "status", "running") != "running":
                    raise WorkerFailed(f"lost the Dask scheduler at {client.scheduler.address}") from None
                raise WorkerFailed("a cell was cancelled by the executor (cluster shut down?)") from None
            except WorkerFailed:
                raise
            except Exception as e:
                text = " ".join(str(e).split())[:300]
                hint = " (is the same hexabot-sim installed on every worker?)" if isinstance(e, ImportError) else ""
                raise WorkerFailed(f"a worker failed: {type(e).__name__}: {text}{hint}") from None
            if on_result is not None:
                on_result(result)
            result.files = None
            results[result.index] = result
            if progress is not None:
                progress(done, len(jobs))
        finished = True
    finally:
        with signals_held():  # a second Ctrl-C must not leave workers behind
            if finished:
                executor.shutdown(wait=True)
            else:
                stop(executor, futures)
    return results  # type: ignore[return-value]


HEARTBEAT: float = 15.0  # [s] while no cell finishes, the progress is called again this often (it speaks each minute)
POLL: float = 0.1  # [s] the longest a stop request waits while the sweep waits for its cells


def _completed(
    futures: Sequence[concurrent.futures.Future],
    total: int,
    progress: Callable[[int, int], None] | None,
    executor: concurrent.futures.Executor | None = None,
) -> Iterator[concurrent.futures.Future]:
    """The futures as they complete; while none does for HEARTBEAT seconds, `progress` hears the count again, so a
    sweep whose cells take minutes still says where it is (at least once a minute) instead of falling silent.

    Raises:
        WorkerFailed: a Dask cluster that has had no worker for WORKER_WAIT seconds, or whose scheduler is gone.
    """
    pending, done = set(futures), 0
    client = getattr(executor, "_client", None)  # a Dask ClientExecutor's client
    workerless_since: float | None = None
    quiet_since = time.monotonic()
    while pending:
        # Short waits, held: a stop signal is raised here, between two waits, never inside concurrent.futures' own
        # locks (a future left locked hangs the pool's shutdown); and one whose exception Python swallowed (a
        # finalizer, an after-fork hook: the leg-sweep once went on with all its cells) is seen within POLL.
        with signals_held():
            finished, pending = concurrent.futures.wait(
                pending, timeout=POLL, return_when=concurrent.futures.FIRST_COMPLETED
            )
        if RECEIVED_SIGNALS:  # a stop request whose exception was swallowed (simulate's check)
            raise stop_request(RECEIVED_SIGNALS[-1])
        for future in finished:
            done += 1
            yield future
        now = time.monotonic()
        if finished or now - quiet_since < HEARTBEAT:
            quiet_since = now if finished else quiet_since
            continue
        quiet_since = now
        if progress is not None:
            progress(done, total)
        if client is not None:
            workers = _dask_workers(client)
            if workers is None:  # a live scheduler slow to answer: asked again at the next heartbeat
                continue
            now = time.monotonic()
            workerless_since = None if workers else (workerless_since or now)
            if workerless_since is not None and now - workerless_since >= WORKER_WAIT:
                raise WorkerFailed(
                    f"the Dask cluster has had no worker for {WORKER_WAIT:g} s, with {len(pending)} cells unfinished"
                )


SCHEDULER_ANSWER: float = 2.0  # [s] the longest the heartbeat waits for the Dask scheduler's worker count


def _dask_workers(client: Any) -> int | None:
    """The Dask cluster's number of workers, or None if its scheduler, still connected, did not answer within
    SCHEDULER_ANSWER. A client that lost its scheduler blocked `nthreads()` for its whole reconnect timeout (10 s,
    seen in CI when the count was asked in the instant before the client noticed the loss): the wait is bounded.

    Raises:
        WorkerFailed: the scheduler is gone (the client is reconnecting or closed, or the call failed).
    """
    lost = WorkerFailed(f"lost the Dask scheduler at {client.scheduler.address}")
    if getattr(client, "status", "running") != "running":
        raise lost
    try:
        return len(client.nthreads(callback_timeout=SCHEDULER_ANSWER))
    except TimeoutError:
        if getattr(client, "status", "running") != "running":
            raise lost from None
        return None
    except Exception:
        raise lost from None


def workers_default() -> int:
    """All cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1
