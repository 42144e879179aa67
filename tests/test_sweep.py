"""hexabot-sim sweep: grid specs, validation before anything runs, identical bytes on any executor, signals."""

import io
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from helpers import cli

from hexabot_sim import sweep, sweep_figures
from hexabot_sim.cli import main
from hexabot_sim.cli.progress import SweepProgress
from hexabot_sim.errors import UsageError

# 2 x 2 pendulum cells of 0.5 s; stiffness 1e6 at a 10 ms step diverges (docs/cli.md: sqrt(k/I) = 1.8e4 rad/s).
GRID = ["--grid", "damping=0,0.05", "--grid", "stiffness=0.5,1e6"]
FIXED = ["--set", "duration=0.5", "--set", "timestep=0.01"]


def sweep_ok(capsys, out, *extra):
    code = main(["sweep", "pendulum", *GRID, *FIXED, "--out", str(out), *extra])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    return captured


def test_grid_specs():
    assert sweep.parse_axis("damping=0, 0.1,0.2") == ("damping", ["0", "0.1", "0.2"], False)
    name, values, log = sweep.parse_axis("stiffness=0:1:5")
    assert (name, values, log) == ("stiffness", [0.0, 0.25, 0.5, 0.75, 1.0], False)
    name, values, log = sweep.parse_axis("mass=log:1e-3:1:4")
    assert log and values[0] == 1e-3 and values[-1] == 1.0 and values[1] == pytest.approx(1e-2)
    p = sweep.plan("pendulum", ["damping=0,0.1", "integrator=rk4,euler"], {}, {"mass": "0.2"})
    assert p.shape == (2, 2) and len(p.cells) == 4
    assert p.cell_values(1) == (0.0, "Euler") and p.cell_values(2) == (0.1, "RK4")  # the last axis varies fastest
    assert all(cell.mass == 0.2 for cell in p.cells)


@pytest.mark.parametrize(
    ("grid", "sets", "fragment"),
    [
        (["damping"], [], "malformed --grid 'damping'"),
        (["damping=0,,1"], [], "empty value"),
        (["dampin=0,1"], [], "unknown parameter 'dampin'; known: mass"),
        (["damping=0,-1"], [], "--grid 'damping=0,-1': parameter 'damping' must be a number with 0 <= damping"),
        (["length=0.3,300"], [], "did you mean 300 mm = 0.3 m?"),
        (["damping=log:0:1:3"], [], "a log range needs START > 0"),
        (["damping=0:1:1"], [], "N must be a whole number from 2"),
        (["damping=0:1:x"], [], "N must be a whole number from 2"),
        (["damping=0.1,0.10"], [], "the value 0.1 appears twice"),
        (["damping=0,1", "damping=2,3"], [], "given twice with --grid"),
        (["damping=0,1"], ["--set", "damping=1"], "both with --set and with --grid"),
        (["duration=0.01,1", "timestep=0.001,0.05"], [], "grid cell duration = 0.01, timestep = 0.05: parameter"),
        (["mass=0.01:1:400", "length=0.1:1:400"], [], "160000 cells; the limit is 100000"),
        ([], [], "give at least one --grid"),
    ],
)
def test_bad_grid_exits_2_with_one_line_and_writes_nothing(tmp_path, capsys, grid, sets, fragment):
    out = tmp_path / "sweep"
    argv = ["sweep", "pendulum", *[a for g in grid for a in ("--grid", g)], *sets, "--out", str(out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and fragment in err, err
    assert list(tmp_path.iterdir()) == []


def test_sweep_of_a_sweep_is_refused():
    with pytest.raises(UsageError, match="sweep leg-step instead"):
        sweep.plan("leg-sweep", ["periods=1,2"], {}, {})


@pytest.mark.slow
def test_same_bytes_on_one_or_two_workers_and_a_divergent_cell_is_a_row(tmp_path, capsys):
    one = sweep_ok(capsys, tmp_path / "one", "--workers", "1")
    sweep_ok(capsys, tmp_path / "two", "--workers", "2", "--no-plots")
    data = (tmp_path / "one" / "sweep.csv").read_bytes()
    assert data == (tmp_path / "two" / "sweep.csv").read_bytes()
    lines = data.decode().splitlines()
    header = lines[0].split(",")
    assert header[:2] == ["damping", "stiffness"] and header[-1] == "error" and "final_theta_deg" in header
    assert "real_time_factor" not in header
    rows = [line.split(",", 2) for line in lines[1:]]
    assert [r[:2] for r in rows] == [["0", "0.5"], ["0", "1000000"], ["0.05", "0.5"], ["0.05", "1000000"]]
    assert lines[1].endswith(",") and lines[3].endswith(",")  # converged cells: empty error
    for line in (lines[2], lines[4]):  # diverged cells: empty metrics, the reason in 'error'
        assert "simulation diverged" in line and "timestep" in line
    assert "2 of 4 cells failed" in one.err and "stiffness = 1000000" in one.err
    assert "4 cells (2 damping x 2 stiffness)" in one.out
    record = json.loads((tmp_path / "one" / "sweep.json").read_text())
    assert record["grid"][1] == {"name": "stiffness", "spec": "stiffness=0.5,1e6", "values": [0.5, 1e6], "log": False}
    assert record["failed_cells"] == [1, 3] and record["fixed"]["duration"] == 0.5 and "damping" not in record["fixed"]
    assert (
        record["units"]["columns"]["damping"] == "N*m*s/rad" and record["units"]["columns"]["final_theta_deg"] == "deg"
    )
    assert {"hexabot_sim", "mujoco"} <= set(record["versions"]) and record["timing"]["wall_time"] > 0
    pngs = {p.name for p in (tmp_path / "one").glob("*.png")}
    assert "final_theta_deg.png" in pngs and "target_deg.png" not in pngs  # constant metrics are not drawn
    assert set(record["files"]) == {"sweep.csv", "sweep.json", "report.html", *pngs}
    assert not list((tmp_path / "two").glob("*.png"))


def test_keep_runs_writes_each_cell_as_a_run_folder(tmp_path, capsys):
    out = tmp_path / "sweep"
    code = main(
        ["sweep", "pendulum", "--grid", "damping=0.01,0.02", *FIXED, "--out", str(out), "--keep-runs", "--no-plots"]
    )
    assert code == 0, capsys.readouterr().err
    lines = (out / "sweep.csv").read_text().splitlines()
    header = lines[0].split(",")
    for k in (0, 1):
        cell = out / "cells" / f"cell-000{k}"
        record = json.loads((cell / "run.json").read_text())
        assert record["params"]["damping"] == [0.01, 0.02][k] and (cell / "timeseries.csv").is_file()
        row = dict(zip(header, lines[1 + k].split(","), strict=True))
        assert float(row["final_theta_deg"]) == record["metrics"]["final_theta_deg"]
    # compare reads kept cells like any run folders.
    assert main(["compare", str(out / "cells" / "cell-0000"), str(out / "cells" / "cell-0001"), "--no-plots",
                 "--out", str(tmp_path / "cmp")]) == 0  # fmt: skip


def test_a_worker_whose_temporary_folder_is_full_fails_the_sweep_in_one_line(tmp_path, capsys, monkeypatch):
    """Issue 17 (TMPDIR on a full 2 MB tmpfs): every --keep-runs cell became a row 'internal error: OSError: No space
    left on device (a bug, please report it)' and the sweep exited 0; the worker's disk is no cell's failure."""
    from hexabot_sim import output

    def full(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(output, "write_run", full)  # the local pool forks: its workers see this too
    out = tmp_path / "sweep"
    code = main(["sweep", "pendulum", "--grid", "damping=0.01,0.02", *FIXED, "--out", str(out), "--keep-runs",
                 "--workers", "1"])  # fmt: skip
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1 and err[-1].startswith("hexabot-sim: error: a worker") and "No space left" in err[-1], err
    assert "bug" not in err[-1] and not out.exists() and list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_local_cluster_gives_the_same_bytes_as_the_local_pool(tmp_path, capsys):
    distributed = pytest.importorskip("distributed", reason="the 'cluster' extra (distributed) is not installed")
    sweep_ok(capsys, tmp_path / "pool", "--workers", "2", "--no-plots")
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=50
    ) as cluster:
        captured = sweep_ok(capsys, tmp_path / "dask", "--scheduler", cluster.scheduler_address, "--no-plots")
    assert "Dask scheduler" in captured.out
    assert (tmp_path / "pool" / "sweep.csv").read_bytes() == (tmp_path / "dask" / "sweep.csv").read_bytes()
    assert json.loads((tmp_path / "dask" / "sweep.json").read_text())["executor"]["kind"] == "dask"


def test_scheduler_and_workers_together_are_refused(tmp_path, capsys):
    argv = ["sweep", "pendulum", *GRID, "--scheduler", "tcp://127.0.0.1:1", "--workers", "2"]
    argv += ["--out", str(tmp_path / "s")]
    assert main(argv) == 2
    assert "--workers is for the local pool" in capsys.readouterr().err


def test_progress_gives_cells_and_an_eta_in_logs():
    stream = io.StringIO()
    progress = SweepProgress("sweep-pendulum", stream)
    for done in range(0, 21):
        progress(done, 20)
    lines = stream.getvalue().splitlines()
    assert lines[0] == "sweep-pendulum: 0% (0/20 cells, 0 s)"
    assert "ETA" in lines[1] and lines[-1].startswith("sweep-pendulum: 100% (20/20 cells")
    assert len(lines) == 11  # every 10 %


@pytest.mark.slow
def test_sigterm_stops_the_workers_and_leaves_nothing(tmp_path):
    argv = ["sweep", "pendulum", "--grid", "damping=0.1:0.4:4", "--set", "duration=2000", "--workers", "2"]
    proc = subprocess.Popen(
        [sys.executable, "-m", "hexabot_sim", *argv, "--out", "sweep"],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 60
    children: list[str] = []
    while len(children) < 2:  # the staging folder exists and both workers run
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline
        time.sleep(0.05)
        children = subprocess.run(["pgrep", "-P", str(proc.pid)], capture_output=True, text=True).stdout.split()
    assert list(tmp_path.glob(".hexabot-sim-staging-*"))
    time.sleep(0.3)
    started = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=30)
    assert time.monotonic() - started < 5.0
    assert proc.returncode == 128 + signal.SIGTERM, err
    assert "Traceback" not in err and "nothing written" in err
    time.sleep(0.2)
    for pid in children:
        assert not Path(f"/proc/{pid}").exists() or "zombie" in Path(f"/proc/{pid}/status").read_text()
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_sweep_folder_has_a_report_page(tmp_path, capsys):
    out = tmp_path / "sweep"
    code = main(["sweep", "pendulum", "--grid", "damping=0.01,0.02", "--set", "duration=0.5", "--out", str(out)])
    assert code == 0, capsys.readouterr().err
    page = (out / "report.html").read_text()
    record = json.loads((out / "sweep.json").read_text())
    assert "report.html" in record["files"]
    for name in record["files"]:
        if name != "report.html":
            assert f'href="{name}"' in page and (out / name).exists()
    assert "swept: 0.01, 0.02" in page and "<script" not in page


@pytest.mark.parametrize("grid", [["damping=0.01:0.02:4"], ["damping=0.01:0.02:2", "stiffness=0.5:1:2"]])
def test_sweep_figures_print_full_values_not_an_offset(grid):
    """Values that differ in the 8th digit (an energy drift of 1e-8, say): the ticks carry the values themselves,
    never matplotlib's offset text ("+1" or "1e-8" above the axis), which a reader misses."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    p = sweep.plan("pendulum", grid, {}, {})
    n = len(p.cells)
    swept = tuple(axis.name for axis in p.axes)
    rows = tuple((*[getattr(cell, a) for a in swept], 1.0 + 1e-8 * i, "", "") for i, cell in enumerate(p.cells))
    table = sweep.Table(swept, ("drift",), ("drift",), rows, {"drift": "1"}, {"drift": "a metric"})
    fig = sweep_figures.figures(p, table)["drift"]
    FigureCanvasAgg(fig).draw()
    value_axis = fig.axes[-1].yaxis if len(grid) == 2 else fig.axes[0].yaxis  # the colour bar, or the curve's y
    assert value_axis.get_offset_text().get_text() == ""
    labels = [t.get_text() for t in value_axis.get_ticklabels() if t.get_text()]
    values = [float(label.replace("\u2212", "-")) for label in labels]
    assert len(set(values)) >= 2 and all(abs(v - 1.0) < 1e-7 for v in values), labels
    assert n == 4


def test_a_curve_marks_its_null_cells_and_keeps_the_whole_grid_in_view():
    """A metric with no value in some cells (settling_time of a pendulum that has not settled) was drawn as a curve
    over the other cells only: the grid's low end vanished from the axis, unmarked (the heatmap greys them)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    p = sweep.plan("pendulum", ["damping=log:0.001:0.1:5"], {}, {})
    rows = tuple((cell.damping, None if i < 2 else 1.0 / (i + 1), "", "") for i, cell in enumerate(p.cells))
    table = sweep.Table(("damping",), ("settle",), ("settle",), rows, {"settle": "s"}, {"settle": "a metric"})
    fig = sweep_figures.figures(p, table)["settle"]
    FigureCanvasAgg(fig).draw()
    ax = fig.axes[0]
    low, high = ax.get_xlim()
    assert low < 0.001 and high > 0.1  # every grid value on the axis
    marks = [line.get_xdata()[0] for line in ax.get_lines() if line.get_color() == "0.5" and len(line.get_xdata())]
    assert sorted(marks) == pytest.approx([0.001, 10**-2.5])
    legend = ax.get_legend()
    assert any("null" in text.get_text() for text in legend.get_texts())
    renderer = FigureCanvasAgg(fig).get_renderer()  # the legend sits between the title and the axes, on neither
    assert legend.get_window_extent(renderer).y1 <= fig._suptitle.get_window_extent(renderer).y0 + 1


def test_a_stopped_worker_removes_the_cell_folder_it_was_writing(tmp_path):
    """The sweep stops workers with SIGTERM: a --keep-runs cell half-written in the temporary folder goes with the
    worker (10 of 12 interrupted sweeps left ~1 MB cell folders behind, found by fuzzing)."""
    code = (
        "import os, signal, tempfile, time\n"
        "from hexabot_sim import pool\n"
        "pool._worker_init()\n"
        f"tmp = tempfile.mkdtemp(prefix=f'hexabot-sim-cell-{{os.getpid()}}-', dir={str(tmp_path)!r})\n"
        "pool.CELL_FOLDERS.append(tmp)\n"
        "open(os.path.join(tmp, 'timeseries.csv'), 'w').write('t\\n0\\n')\n"
        "os.kill(os.getpid(), signal.SIGTERM)\n"
        "time.sleep(30)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 128 + signal.SIGTERM, done.stderr
    assert list(tmp_path.iterdir()) == []


def test_clean_removes_cell_folders_of_workers_that_are_gone(tmp_path, monkeypatch, capsys):
    import tempfile

    from hexabot_sim import folders

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    # a killed worker left it (tempfile: 8 of [a-z0-9_])
    gone = tmp_path / f"{folders.CELL_PREFIX}{int(dead.stdout)}-abc_1234"
    alive = tmp_path / f"{folders.CELL_PREFIX}{os.getpid()}-def_5678"  # a worker still writing it
    for folder in (gone, alive):
        folder.mkdir()
        (folder / "run.json").write_text("{}")
    runs = tmp_path / "runs"
    runs.mkdir()
    assert main(["clean", str(runs)]) == 0
    assert f"removed {gone}" in capsys.readouterr().out
    assert not gone.exists() and alive.exists()


def test_a_grid_over_a_config_files_value_says_so(tmp_path, capsys):
    """A parameter in --config and in --grid was swept without a word (the grid wins, as --set would win over the
    config; --set and --grid together are refused)."""
    config = tmp_path / "cfg.toml"
    config.write_text("damping = 0.05\nmass = 0.2\n")
    code, out, err = cli(capsys, "sweep", "pendulum", "--grid", "damping=0,0.01", "--config", str(config), "--set",
                         "duration=0.05", "--no-plots", "--out", str(tmp_path / "s"))  # fmt: skip
    assert code == 0 and "cells ok: 2" in out
    [line] = [x for x in err.splitlines() if "warning" in x]  # (a progress line may follow)
    assert line == f"hexabot-sim: warning: --grid sweeps 'damping', which --config {config} also sets: the grid's " + (
        "values are used"
    )


def test_a_cells_run_warnings_reach_the_sweep(tmp_path, capsys):
    """Found by fuzzing: a cell whose run warned (an undamped pendulum that lost its energy) showed only its
    energy_drift_rel in sweep.csv, and nothing on stderr or in sweep.json."""
    out = tmp_path / "s"
    code, stdout, err = cli(capsys, "sweep", "pendulum-undamped", "--grid", "stiffness=0,24000", "--set",
                            "duration=0.5", "--no-plots", "--out", str(out))  # fmt: skip
    assert code == 0 and "cells ok: 2, failed: 0" in stdout
    [line] = [x for x in err.splitlines() if "warning" in x]
    assert line.startswith("hexabot-sim: warning: 1 of 2 cells warned (the 'warnings' column of sweep.csv); the "
                           "first, stiffness = 24000: energy_drift_rel = 0.947")  # fmt: skip
    lines = (out / "sweep.csv").read_text().splitlines()
    header = lines[0].split(",")
    assert header[-2:] == ["warnings", "error"]
    assert lines[1].endswith(",,") and "the integration broke the energy balance" in lines[2]
    assert json.loads((out / "sweep.json").read_text())["warned_cells"] == [1]
