"""Issue 17: --scheduler addresses that are not a Dask scheduler's, or a scheduler that cannot run anything,
are one line on stderr within a bounded wait."""

import pytest

from hexabot_sim import sweep
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
    monkeypatch.setattr(sweep, "WORKER_WAIT", 1.0)
    with distributed.LocalCluster(n_workers=0, processes=True, dashboard_address=None, silence_logs=50) as cluster:
        code = main(["sweep", "pendulum", *GRID, "--scheduler", cluster.scheduler_address, "--out",
                     str(tmp_path / "s")])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and "has no workers" in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "s").exists()


def test_a_plain_address_is_given_its_protocol():
    assert sweep.scheduler_address("127.0.0.1:8786") == "tcp://127.0.0.1:8786"
    assert sweep.scheduler_address("tcp://[::1]:8786") == "tcp://[::1]:8786"
