"""A Dask distributed scheduler as the sweep's executor: connecting, checked addresses, one-line failures."""

from __future__ import annotations

import concurrent.futures
import contextlib
import logging
import re
from collections.abc import Iterator
from typing import Any

from hexabot_sim import pool
from hexabot_sim.errors import UsageError


@contextlib.contextmanager
def dask_executor(address: str, timeout: float = 10.0) -> Iterator[tuple[concurrent.futures.Executor, int]]:
    """The Executor of a Dask distributed scheduler at `address`, and its current number of worker threads.

    Raises:
        UsageError: if `distributed` is not installed or the scheduler cannot be reached within `timeout` [s].
    """
    try:
        from distributed import Client
    except ImportError:
        raise UsageError("--scheduler needs the 'distributed' package: pip install \"hexabot-sim[cluster]\"") from None
    address = scheduler_address(address)
    _silence_logs("distributed", "tornado", "asyncio", "bokeh")  # Dask's own log lines are not the user's business
    try:
        client = _connect(Client, address, timeout)
    except MemoryError:  # its first bytes read as a frame length: "Unable to allocate 3.07 EiB ..."
        raise UsageError(
            f"cannot reach the Dask scheduler at {address!r}: the peer answered, but not as a Dask scheduler (is it "
            "one?)"
        ) from None
    except Exception as e:
        text = " ".join(str(e).split())[:200]
        raise UsageError(f"cannot reach the Dask scheduler at {address!r}: {text or type(e).__name__}") from None
    try:
        threads = sum(client.nthreads().values())
        if threads == 0:
            try:
                client.wait_for_workers(1, timeout=pool.WORKER_WAIT)
            except Exception:
                raise UsageError(
                    f"the Dask scheduler at {address!r} has no workers (waited {pool.WORKER_WAIT:g} s): start some "
                    f"with 'dask worker {address}'"
                ) from None
            threads = sum(client.nthreads().values())
        yield client.get_executor(pure=False), threads
    finally:
        with contextlib.suppress(Exception):
            client.close(timeout=5)


def _silence_logs(*prefixes: str) -> None:
    """Silences these loggers and every child logger: Dask's configuration gives some children (distributed.client)
    their own level and stderr handler, so silencing the parent alone let a lost scheduler print a traceback."""
    names = [n for n in list(logging.root.manager.loggerDict) if n.split(".")[0] in prefixes]
    for name in {*prefixes, *names}:
        logging.getLogger(name).setLevel(logging.CRITICAL + 1)


def _connect(client_type: Any, address: str, timeout: float) -> Any:
    """client_type(address) within 2 x `timeout` seconds: a peer that accepts the connection but never answers as
    a Dask scheduler would block Client() until it hangs up (a daemon thread is left to it, not the user)."""
    import threading

    box: list[Any] = []

    def connect() -> None:
        try:
            box.append(client_type(address, timeout=timeout, set_as_default=False))
        except BaseException as e:
            _disarm(e, client_type)
            box.append(e)

    thread = threading.Thread(target=connect, name="hexabot-sim-dask-connect", daemon=True)
    thread.start()
    thread.join(2 * timeout)
    if not box:
        raise TimeoutError(f"no answer as a Dask scheduler within {2 * timeout:g} s (is it one?)")
    if isinstance(box[0], BaseException):
        raise box[0]
    return box[0]


def _disarm(error: BaseException, client_type: Any) -> None:
    """Marks closed the Client whose constructor raised `error`: collected, it closed itself against a scheduler
    that never was, waited 2 x its timeout (20 s) and printed "Exception ignored in: Client.__del__" with a
    traceback (a peer that answers but is no scheduler, found by fuzzing). Its event loop is stopped here."""
    tb = error.__traceback__
    while tb is not None:
        owner = tb.tb_frame.f_locals.get("self")
        if isinstance(owner, client_type):
            with contextlib.suppress(Exception):
                owner.status = "closed"
                owner._loop_runner.stop()
        tb = tb.tb_next


def scheduler_address(text: str) -> str:
    """'tcp://host:port' (or 'host:port') checked: UsageError in one line for anything else."""
    match = re.fullmatch(r"(?:tcp://)?([A-Za-z0-9._-]+|\[[0-9A-Fa-f:.]+\]):([0-9]{1,5})", text)
    if "://" in text and not text.startswith("tcp://"):
        scheme = text.split("://", 1)[0][:20]
        raise UsageError(
            f"--scheduler {scheme}:// is not supported: give a Dask scheduler's tcp://HOST:PORT address "
            "(tls:// needs a certificate configuration this command does not take)"
        )
    if match is None or not 1 <= int(match.group(2)) <= 65535:
        shown = text if len(text) <= 80 else text[:77] + "..."
        raise UsageError(f"--scheduler {shown!r} is not an address: expected tcp://HOST:PORT, PORT from 1 to 65535")
    return text if text.startswith("tcp://") else f"tcp://{text}"
