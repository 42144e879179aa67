"""Issue 17: --scheduler addresses that are not a Dask scheduler's, or a scheduler that cannot run anything,
are one line on stderr within a bounded wait."""

import pytest

from hexabot_sim import dask_cluster, pool
from hexabot_sim.__main__ import main

GRID = ["--grid", "damping=0,0.01", "--set", "duration=0.05", "--no-plots"]


@pytest.mark.parametrize(
    "address",
    ["ucx://127.0.0.1:8786", "tls://127.0.0.1:8786", "tcp://", "tcp://:x", "::::", "tcp://127.0.0.1:99999", "",
     "tcp://h\u00f6st:1", "x" * 5000, "http://127.0.0.1:80"],
)  # fmt: skip
def test_an_address_that_is_no_dask_scheduler_is_one_line(tmp_path, capsys, address):
    code = main(["sweep", "pendulum", *GRID, "--scheduler", address, "--out", str(tmp_path / "s")])
    err = capsys.readouterr().err
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1 and "internal error" not in err and "Traceback" not in err
    assert len(err) < 400 and not (tmp_path / "s").exists()


def test_a_scheduler_without_workers_is_one_line_after_a_bounded_wait(tmp_path, capsys, monkeypatch):
    distributed = pytest.importorskip("distributed", reason="the 'cluster' extra (distributed) is not installed")
    monkeypatch.setattr(pool, "WORKER_WAIT", 1.0)
    with distributed.LocalCluster(n_workers=0, processes=True, dashboard_address=None, silence_logs=50) as cluster:
        code = main(["sweep", "pendulum", *GRID, "--scheduler", cluster.scheduler_address, "--out",
                     str(tmp_path / "s")])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and "has no workers" in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "s").exists()


def test_a_plain_address_is_given_its_protocol():
    assert dask_cluster.scheduler_address("127.0.0.1:8786") == "tcp://127.0.0.1:8786"
    assert dask_cluster.scheduler_address("tcp://[::1]:8786") == "tcp://[::1]:8786"


def test_progress_speaks_while_no_cell_finishes(monkeypatch):
    """A cell that takes longer than a heartbeat: the progress is called again meanwhile, and a log line is
    written once PLAIN_SECONDS have passed without one (docs/studies.md promises a line at least once a minute)."""
    import concurrent.futures
    import io
    import time

    from hexabot_sim.cli.progress import SweepProgress

    monkeypatch.setattr(pool, "HEARTBEAT", 0.05)
    monkeypatch.setattr(SweepProgress, "PLAIN_SECONDS", 0.1)
    stream = io.StringIO()
    progress = SweepProgress("sweep-test", stream)
    with concurrent.futures.ThreadPoolExecutor(1) as executor:
        futures = [executor.submit(time.sleep, 0.5)]
        progress(0, 1)
        assert list(pool._completed(futures, 1, progress)) == futures
    lines = stream.getvalue().splitlines()
    assert len([line for line in lines if line.startswith("sweep-test: 0% (0/1 cells")]) >= 3, lines


@pytest.mark.slow
def test_a_peer_that_accepts_but_is_no_scheduler_is_refused_in_bounded_time():
    """A TCP server on loopback that accepts and says nothing: Client() alone waited until the peer hung up."""
    import socket
    import time

    pytest.importorskip("distributed", reason="the 'cluster' extra (distributed) is not installed")
    from hexabot_sim.errors import UsageError

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(8)
    started = time.monotonic()
    try:
        with pytest.raises(UsageError, match="no answer as a Dask scheduler"):
            with dask_cluster.dask_executor(f"tcp://127.0.0.1:{server.getsockname()[1]}", timeout=1.0):
                pass
    finally:
        server.close()
    assert time.monotonic() - started < 10


@pytest.mark.slow  # ~2.3 s: a fresh interpreter imports distributed
def test_a_peer_that_answers_but_is_no_scheduler_is_one_line_at_once(tmp_path):
    """A TCP server that answers with bytes of its own (an HTTP error here; a proxy on an unroutable address did it):
    the refusal was 'Unable to allocate 3.07 EiB ...', then 20 s later "Exception ignored in: Client.__del__" and a
    traceback (the half-built Client closing itself at exit). Found by fuzzing. A separate process: at its exit."""
    import os
    import socket
    import subprocess
    import sys
    import threading
    import time

    pytest.importorskip("distributed", reason="the 'cluster' extra (distributed) is not installed")
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(8)

    def answer() -> None:
        while True:
            try:
                peer, _ = server.accept()
            except OSError:
                return
            with peer:
                peer.sendall(b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n" * 4)

    threading.Thread(target=answer, daemon=True).start()
    address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    argv = ["sweep", "pendulum", *GRID, "--scheduler", address, "--out", str(tmp_path / "s")]
    started = time.monotonic()
    try:
        run = subprocess.run([sys.executable, "-m", "hexabot_sim", *argv], capture_output=True, text=True, env=env,
                             timeout=60)  # fmt: skip
    finally:
        server.close()
    assert run.returncode == 2 and run.stderr.count("\n") == 1, run.stderr
    assert "the peer answered, but not as a Dask scheduler" in run.stderr
    assert time.monotonic() - started < 15 and not (tmp_path / "s").exists()


class _FakeClient:
    def __init__(self, nthreads):
        self._nthreads, self.status = nthreads, "running"
        self.scheduler = type("S", (), {"address": "tcp://127.0.0.1:1"})()

    def nthreads(self, callback_timeout=None):
        return self._nthreads()


@pytest.mark.parametrize("case", ["no workers", "scheduler gone"])
def test_a_cluster_that_loses_its_workers_or_scheduler_mid_sweep_fails_in_bounded_time(monkeypatch, case):
    """A cell that never finishes on a cluster with no worker left (or no scheduler): WorkerFailed, not a hang."""
    import concurrent.futures

    def gone():
        raise OSError("Connection refused")

    monkeypatch.setattr(pool, "HEARTBEAT", 0.02)
    monkeypatch.setattr(pool, "WORKER_WAIT", 0.1)
    executor = type("E", (), {})()
    executor._client = _FakeClient(dict if case == "no workers" else gone)
    never = concurrent.futures.Future()
    with pytest.raises(pool.WorkerFailed, match=r"no worker for|lost the Dask scheduler"):
        list(pool._completed([never], 1, None, executor))


@pytest.mark.parametrize("noticed", [False, True])
def test_a_scheduler_slow_to_answer_the_worker_count_is_asked_again_unless_the_client_lost_it(noticed):
    """nthreads() timing out: a client still connected is asked again at the next heartbeat (None); one that has
    meanwhile noticed the loss (reconnecting) ends the sweep."""
    client = _FakeClient(None)

    def slow():
        client.status = "connecting" if noticed else "running"
        raise TimeoutError("timed out after 2 s.")

    client._nthreads = slow
    if noticed:
        with pytest.raises(pool.WorkerFailed, match="lost the Dask scheduler"):
            pool._dask_workers(client)
    else:
        assert pool._dask_workers(client) is None
    client.status = "closed"
    with pytest.raises(pool.WorkerFailed, match="lost the Dask scheduler"):
        pool._dask_workers(client)


@pytest.mark.slow
def test_the_worker_count_of_a_killed_scheduler_is_refused_within_the_bound(tmp_path):
    """Asked in the instant after its scheduler died, Dask's nthreads() waited for the client's whole reconnect
    timeout (10 s: a CI failure); the count is bounded by SCHEDULER_ANSWER."""
    import json
    import signal
    import time

    distributed = pytest.importorskip("distributed", reason="the 'cluster' extra (distributed) is not installed")
    file, log = tmp_path / "scheduler.json", open(tmp_path / "dask.log", "wb")
    scheduler = _dask_cli("scheduler", "--port", "0", "--scheduler-file", str(file), "--no-dashboard", "--host",
                          "127.0.0.1", log=log)  # fmt: skip
    try:
        address, deadline = None, time.monotonic() + 15
        while address is None and time.monotonic() < deadline:
            try:
                address = json.loads(file.read_text())["address"]
            except (OSError, ValueError, KeyError):
                time.sleep(0.1)
        assert address, "the dask scheduler wrote no address in 15 s"
        dask_cluster._silence_logs("distributed", "tornado", "asyncio")
        with distributed.Client(address, set_as_default=False, timeout=10) as client:
            assert pool._dask_workers(client) == 0
            scheduler.send_signal(signal.SIGKILL)
            scheduler.wait(timeout=10)
            started = time.monotonic()
            with pytest.raises(pool.WorkerFailed, match="lost the Dask scheduler"):
                pool._dask_workers(client)
            assert time.monotonic() - started < 6.0  # the reconnect timeout is 10 s; SCHEDULER_ANSWER 2 s
    finally:
        scheduler.kill()
        scheduler.wait(timeout=10)
        log.close()


def _dask_cli(*args, log):
    """A `dask` command-line process on loopback, its output in `log` (the scheduler or a worker)."""
    import shutil
    import subprocess
    import sys

    dask = shutil.which("dask") or str(__import__("pathlib").Path(sys.executable).with_name("dask"))
    return subprocess.Popen([dask, *args], stdout=log, stderr=subprocess.STDOUT, start_new_session=True)


@pytest.mark.slow
@pytest.mark.parametrize("victim", ["worker", "scheduler"])
def test_kill_9_of_a_real_worker_or_scheduler_mid_sweep_is_one_line_in_bounded_time(tmp_path, victim):
    """A real `dask scheduler` and `dask worker --no-nanny` on 127.0.0.1; once the worker runs a cell, one of them
    is killed with SIGKILL. The sweep (a separate process, its waits shortened) ends with exit 1 and one line on
    stderr, no traceback (distributed.client printed one when the scheduler went), and writes nothing."""
    import json
    import os
    import signal
    import subprocess
    import sys
    import time

    distributed = pytest.importorskip("distributed", reason="the 'cluster' extra (distributed) is not installed")
    file, log = tmp_path / "scheduler.json", open(tmp_path / "dask.log", "wb")
    common = ["--no-dashboard", "--host", "127.0.0.1"]
    processes = [_dask_cli("scheduler", "--port", "0", "--scheduler-file", str(file), *common, log=log)]
    try:
        deadline = time.monotonic() + 15
        address = None
        while address is None and time.monotonic() < deadline:  # the file exists before the scheduler fills it
            try:
                address = json.loads(file.read_text())["address"]
            except (OSError, ValueError, KeyError):
                time.sleep(0.1)
        told = (tmp_path / "dask.log").read_text(errors="replace")[-500:]
        assert address, f"the dask scheduler wrote no address in 15 s: {told}"
        processes.append(_dask_cli("worker", address, "--no-nanny", "--nthreads", "1", *common, log=log))
        code = (
            "import sys; from hexabot_sim import pool; pool.HEARTBEAT = 0.2; pool.WORKER_WAIT = 1.0\n"
            "from hexabot_sim.__main__ import main; sys.exit(main(sys.argv[1:]))"
        )
        argv = ["sweep", "pendulum", "--grid", "damping=0,0.01", "--set", "duration=3000", "--no-plots",
                "--scheduler", address, "--out", str(tmp_path / "s")]  # fmt: skip
        env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
        run = subprocess.Popen([sys.executable, "-c", code, *argv], stderr=subprocess.PIPE, text=True, env=env)
        with distributed.Client(address, set_as_default=False, timeout=10) as client:
            while not any(client.processing().values()) and time.monotonic() < deadline:
                time.sleep(0.1)
            assert any(client.processing().values()), "no cell started on the worker"
        started = time.monotonic()
        processes[1 if victim == "worker" else 0].send_signal(signal.SIGKILL)
        _, err = run.communicate(timeout=20)
        assert time.monotonic() - started < 10
    finally:
        for process in processes:
            process.kill()
            process.wait(timeout=10)
        log.close()
    assert run.returncode == 1, err
    assert len(err.strip().splitlines()) == 2 and "Traceback" not in err, err  # the 0% progress line, the error
    assert ("no worker for" if victim == "worker" else "lost the Dask scheduler") in err, err
    assert not (tmp_path / "s").exists() and [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []
