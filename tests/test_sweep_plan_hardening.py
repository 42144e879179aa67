"""The sweep plan: odd --grid ranges, cells checked as a whole, progress while checking, the whole-sweep cost."""

import contextlib
import math
import os
import shutil
import warnings
from pathlib import Path

import pytest

from hexabot_sim import dask_cluster, sweep
from hexabot_sim.__main__ import main
from hexabot_sim.errors import UsageError
from hexabot_sim.walking import parameters as hexabot_parameters

FIXED = ["--set", "duration=0.05", "--set", "timestep=0.01", "--no-plots"]


def refused(tmp_path, capsys, *argv):
    """Runs `hexabot-sim sweep ...`, expects exit 2 and nothing written; returns stderr's last line."""
    out = tmp_path / "sweep"
    assert main(["sweep", *argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and "this is a bug" not in err, err
    assert list(tmp_path.iterdir()) == []
    return err.splitlines()[-1]


@pytest.mark.parametrize(
    "spec",
    ["damping=0:1:inf", "damping=0:1:-inf", "damping=0:1:nan", "damping=0:1:1e-320", "damping=0:1:0",
     "damping=0:1:-3", "damping=0:1:1e30", "damping=0:1:1e400", "damping=log:1:2:inf"],
)  # fmt: skip
def test_a_count_that_is_not_a_whole_number_in_range_is_one_line_exit_2(tmp_path, capsys, spec):
    line = refused(tmp_path, capsys, "pendulum", "--grid", spec, *FIXED)
    assert line.startswith(f"hexabot-sim: error: --grid {spec!r}: N must be a whole number from 2 to 10000"), line


def test_a_range_wider_than_the_largest_float_gives_finite_values_and_no_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy's overflow warning would be a second line on stderr
        name, values, log = sweep.parse_axis("x=-1e308:1e308:5")
    assert (name, log) == ("x", False) and values[0] == -1e308 and values[-1] == 1e308
    assert all(math.isfinite(v) for v in values) and values == sorted(values) and values[2] == 0


def test_a_value_is_checked_against_every_cell_not_the_defaults():
    # wave cannot walk the default vx = 0.1 but can walk every vx of the grid.
    p = sweep.plan("hexabot-walk", ["gait=tripod,ripple,wave", "vx=0.05,0.09"], {}, {"duration": "3"})
    assert len(p.cells) == 6 and p.cell_values(5) == ("wave", 0.09)
    # The same with the gait fixed: the fixed values only have to run with the swept ones.
    p = sweep.plan("hexabot-walk", ["vx=0.05,0.09"], {}, {"duration": "3", "gait": "wave"})
    assert [c.gait for c in p.cells] == ["wave", "wave"] and type(p.base).__name__ == "HexabotParams"


def test_infeasible_cells_are_counted_and_the_first_named(tmp_path, capsys):
    line = refused(
        tmp_path,
        capsys,
        "hexabot-walk",
        "--grid",
        "gait=tripod,ripple,wave",
        "--grid",
        "vx=0.05,0.3",
        "--set",
        "duration=3",
    )
    assert "2 of 6 grid cells cannot run; the first, gait = ripple, vx = 0.3: the legs cannot deliver" in line
    assert "every value can run in some cell" in line


def test_a_value_no_cell_can_run_with_is_named(tmp_path, capsys):
    line = refused(tmp_path, capsys, "pendulum", "--grid", "duration=0.01,1", "--grid", "timestep=0.02,0.05")
    assert line.startswith("hexabot-sim: error: 2 of 4 grid cells cannot run, every one with duration = 0.01 among")
    assert "the first, duration = 0.01, timestep = 0.02: parameter 'timestep' must not exceed" in line
    assert line.endswith("leave duration = 0.01 out of its --grid")


def test_fixed_values_no_cell_can_run_with(tmp_path, capsys):
    line = refused(tmp_path, capsys, "pendulum", "--grid", "damping=0,1", "--set", "duration=0.01", "--set",
                   "timestep=0.02")  # fmt: skip
    assert "no grid cell can run; the first, damping = 0: parameter 'timestep'" in line


def test_counting_the_cells_that_cannot_run_is_bounded_in_time(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(sweep, "COUNT_SECONDS", -1.0)  # a walk's refusal takes ~60 ms: 1e5 of them would take hours
    line = refused(tmp_path, capsys, "pendulum", "--grid", "duration=0.01,0.02,1", "--grid", "timestep=0.02,0.05")
    assert "at least 1 of 6 grid cells cannot run (1 of the first 1 checked); the first, duration = 0.01, " in line
    assert line.endswith("shrink the grid")


def test_checking_many_cells_reports_progress(monkeypatch):
    monkeypatch.setattr(sweep, "CHECK_QUIET_SECONDS", 0.0)
    monkeypatch.setattr(sweep, "CHECK_REPORT_SECONDS", 0.0)
    calls = []
    sweep.plan("pendulum", ["damping=0:1:16", "stiffness=0:1:16"], {}, {}, progress=lambda d, t: calls.append((d, t)))
    assert calls[0] == (64, 256) and calls[-1] == (256, 256) and len(calls) == 5


def test_checking_progress_on_the_command_line(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(sweep, "CHECK_QUIET_SECONDS", 0.0)
    monkeypatch.setattr(sweep, "CHECK_REPORT_SECONDS", 0.0)
    out = tmp_path / "sweep"  # two cells cannot run: refused after checking them all
    argv = ["sweep", "pendulum", "--grid", "duration=0.02:1:64", "--grid", "timestep=0.001,0.05", "--out", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err.splitlines()
    assert err[0].startswith("sweep-pendulum: checking: 50% (64/128 cells")
    assert err[-2].startswith("sweep-pendulum: checking: 100% (128/128 cells")
    assert "2 of 128 grid cells cannot run; the first, duration = 0.02, timestep = 0.05" in err[-1]


def test_the_walk_checks_a_gait_cycle_once_for_all_cells_that_share_it(monkeypatch):
    computed = []
    plan_cycle = hexabot_parameters._plan_cycle  # the gait feasibility's (walking.ground's, imported there)
    monkeypatch.setattr(
        hexabot_parameters, "_plan_cycle", lambda p, cmd, *a: computed.append(cmd) or plan_cycle(p, cmd, *a)
    )
    p = sweep.plan("hexabot-walk", ["duration=3:4:10", "seed=1:10:10"], {}, {"vx": "0.0625", "period": "0.95"})
    assert len(p.cells) == 100 and len(computed) <= 2  # standing and walking, not 200


@pytest.mark.slow
def test_a_sweep_that_would_take_too_long_is_refused_with_its_estimate(tmp_path, capsys):
    # 1,200 long flat walks (a rough cell's check builds its whole heightfield: 10,000 of them took 5 min here)
    p = sweep.plan("hexabot-walk", ["duration=1500:1800:20", "vx=0.03:0.1:60"], {}, {})
    with pytest.raises(UsageError, match=r"this sweep would take ~\d.* days \(1200 cells, .* on 2 local processes\); "
                       r"the limit is 24 h: fewer cells"):  # fmt: skip
        sweep.check_cost(p, 2, "2 local processes")
    small = sweep.plan("pendulum", ["damping=0,1"], {}, {"duration": "1"})
    seconds = sweep.check_cost(small, 2, "2 local processes")
    assert seconds == pytest.approx(max(small.costs)) and 0 < seconds < 10


def test_the_cost_refusal_on_the_command_line(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(sweep, "MAX_SWEEP_SECONDS", 1e-6, raising=False)
    line = refused(tmp_path, capsys, "pendulum", "--grid", "damping=0,1", "--workers", "1", *FIXED)
    assert "this sweep would take ~" in line and "on 1 local process)" in line


def test_more_local_workers_than_cores_are_not_counted_as_running_at_once(tmp_path, capsys, monkeypatch):
    """--workers 16 on 2 cores divided the estimate by 16: a ~27 h sweep passed the 24 h limit (found by fuzzing)."""
    import os

    small = sweep.plan("pendulum", ["damping=0:1:16"], {}, {"duration": "0.05", "timestep": "0.01"})  # FIXED's
    limit = 1.5 * sum(small.costs) / 16  # above the 16-way share, below the 2-way one
    monkeypatch.setattr(sweep, "MAX_SWEEP_SECONDS", limit, raising=False)
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    line = refused(tmp_path, capsys, "pendulum", "--grid", "damping=0:1:16", "--workers", "16", *FIXED)
    assert "this sweep would take ~" in line and "on 16 local processes on 2 cores)" in line


def test_the_cost_refusal_with_a_scheduler_counts_its_workers(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(sweep, "MAX_SWEEP_SECONDS", 1e-6, raising=False)
    monkeypatch.setattr(dask_cluster, "dask_executor", lambda address: contextlib.nullcontext((None, 7)))
    line = refused(tmp_path, capsys, "pendulum", "--grid", "damping=0,1", "--scheduler", "tcp://x:1", *FIXED)
    assert "on Dask scheduler tcp://x:1 (7 worker threads))" in line


def test_two_texts_of_one_value_are_named():
    with pytest.raises(UsageError, match=r"the value 0 appears twice \(0 and 1e-330 read as the same value\)"):
        sweep.plan("pendulum", ["damping=0,1e-330"], {}, {})


def test_one_dask_worker_thread_is_singular(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(sweep, "MAX_SWEEP_SECONDS", 1e-6, raising=False)
    monkeypatch.setattr(dask_cluster, "dask_executor", lambda address: contextlib.nullcontext((None, 1)))
    line = refused(tmp_path, capsys, "pendulum", "--grid", "damping=0,1", "--scheduler", "tcp://x:1", *FIXED)
    assert "(1 worker thread))" in line, line  # it said "1 worker threads"


def test_a_robot_file_name_that_is_not_utf8_is_written_to_sweep_csv(tmp_path, capsys):
    """--grid robot=$'\\xff.toml',... ran every cell, then writing sweep.csv raised UnicodeEncodeError on the name's
    lone surrogate (an internal error, no sweep folder)."""
    robot = os.fsdecode(bytes(tmp_path) + b"/\xff.toml")
    shutil.copy(Path(sweep.__file__).parent / "kinematics" / "arms" / "elbow.toml", robot)
    assert sweep.cell_text(robot).endswith("/\\xff.toml")
    out = tmp_path / "sweep"
    argv = ["sweep", "arm-track", "--grid", f"robot={robot},elbow", "--set", "duration=0.01", "--out", str(out)]
    assert main(argv) == 0, capsys.readouterr().err
    assert "\\xff.toml" in (out / "sweep.csv").read_text(encoding="utf-8")
