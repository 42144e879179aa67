"""The Python API: scenarios(), run() with the CLI's checks, Result, the CLI's run folder, matplotlib untouched."""

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from matplotlib.figure import Figure

import hexabot_sim as hs
from hexabot_sim import registry
from hexabot_sim.__main__ import main
from hexabot_sim.errors import UsageError
from hexabot_sim.result import Metric

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def leg():
    return hs.run("leg-step", amplitude=0.08, mode="kinematic", duration=1.0)


def test_scenarios_lists_every_scenario_with_its_parameters():
    infos = hs.scenarios()
    assert list(infos) == list(registry.SCENARIOS)
    for info in infos.values():
        assert info.summary and info.parameters
        for p in info.parameters.values():
            assert p.doc and (p.choices or p.name in p.allowed)
            if p.choices is not None:
                assert p.default in p.choices
            elif p.bounds is not None:
                low, high = p.bounds
                values = p.default if isinstance(p.default, tuple) else (p.default,)
                assert all(low <= v <= high for v in values), (info.name, p)
            elif "CSV file" in p.allowed:  # a table parameter (a CSV file, or rows from the API): empty by default
                assert p.default == ()
            else:  # a name or a file: the default is a name, and the names are listed
                assert p.default in p.allowed and "path of a" in p.allowed
    amplitude = infos["leg-step"].parameters["amplitude"]
    assert (amplitude.default, amplitude.unit, amplitude.allowed) == (0.05, "m/s", "-1 <= amplitude <= 1 m/s")
    assert infos["pendulum"].defaults["stiffness"] == 0.5 and infos["pendulum-undamped"].defaults["stiffness"] == 0


@pytest.mark.parametrize(
    "scenario, values",
    [
        ("leg-step", {"amplitude": "100"}),
        ("leg-step", {"mode": "fast"}),
        ("pendulum", {"dampin": "0.1"}),
        ("pendulum", {"duration": "0.05", "timestep": "0.1"}),
        ("pendulum", {"mass": "nan"}),
        ("no-such-scenario", {}),
    ],
)
def test_bad_input_gives_the_cli_message_as_a_value_error(tmp_path, capsys, scenario, values):
    argv = ["run", scenario, "--out", str(tmp_path / "out")]
    for name, value in values.items():
        argv += ["--set", f"{name}={value}"]
    assert main(argv) == 2
    cli = capsys.readouterr().err.strip()
    with pytest.raises(ValueError) as info:
        hs.run(scenario, **values)
    assert isinstance(info.value, UsageError)
    assert cli == f"hexabot-sim: error: {info.value}"
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_python_values_are_checked_too():
    with pytest.raises(UsageError, match=r"did you mean 100 mm/s = 0.1 m/s"):
        hs.run("leg-step", amplitude=100)
    with pytest.raises(UsageError, match="must be a number"):
        hs.run("pendulum", mass=True)
    result = hs.run("leg-sweep", amplitudes=np.array([0.02, 0.05]), omegas=[1, np.int64(2)], workers=1)
    assert result.params["amplitudes"] == (0.02, 0.05) and result.params["omegas"] == (1.0, 2.0)


def test_result_params_metrics_columns(leg):
    assert leg.scenario == "leg-step" and leg.params["amplitude"] == 0.08 and leg.params["mode"] == "kinematic"
    assert leg.param_units["amplitude"] == "m/s"
    metric = leg.metrics["max_x_error"]
    assert isinstance(metric, Metric) and metric.unit == "m" and metric.doc and metric.value < 1e-5
    assert set(leg.summary) <= set(leg.metrics)
    t = leg.columns["t"]
    assert isinstance(t, np.ndarray) and t[-1] >= 1.0 and leg.columns.units["t"] == "s"
    assert list(leg.columns.units) == list(leg.columns) and all(len(v) == len(t) for v in leg.columns.values())
    assert "leg-step" in repr(leg) and "max_x_error" in leg._repr_html_()
    again = hs.run("leg-step", **leg.params)  # the resolved parameters repeat the run exactly
    np.testing.assert_array_equal(again.columns["q2"], leg.columns["q2"])


def test_to_pandas(leg, monkeypatch):
    pd = pytest.importorskip("pandas")
    frame = leg.to_pandas()
    assert isinstance(frame, pd.DataFrame) and list(frame.columns) == list(leg.columns)
    np.testing.assert_array_equal(frame["t"].to_numpy(), leg.columns["t"])
    assert frame.attrs["units"]["t"] == "s"
    monkeypatch.setitem(sys.modules, "pandas", None)  # as if pandas were not installed
    with pytest.raises(ImportError, match="pip install pandas"):
        leg.to_pandas()


def test_figures_are_figures(leg):
    figures = leg.figures()
    assert figures and all(isinstance(fig, Figure) for fig in figures.values())
    assert "foot_position" in figures


@pytest.mark.slow
def test_save_writes_the_same_run_folder_as_the_cli(tmp_path, capsys):
    assert main(["run", "pendulum", "--set", "duration=1", "--out", str(tmp_path / "cli")]) == 0
    capsys.readouterr()
    folder = hs.run("pendulum", duration=1).save(tmp_path / "api")
    assert folder == tmp_path / "api"
    names = sorted(p.name for p in folder.iterdir())
    assert names == sorted(p.name for p in (tmp_path / "cli").iterdir()) and "report.html" in names
    for name in names:
        cli, api = (tmp_path / "cli" / name).read_bytes(), (folder / name).read_bytes()
        if name == "run.json":  # identical but for the wall time
            cli_record, api_record = json.loads(cli), json.loads(api)
            for record in (cli_record, api_record):
                assert record["simulation"].pop("wall_time") > 0
            assert cli_record == api_record
        else:
            assert cli == api, name
    with pytest.raises(UsageError, match="not empty"):
        hs.run("pendulum", duration=0.1).save(folder)
    assert hs.run("pendulum", duration=0.1).save(folder, force=True, plots=False) == folder


@pytest.mark.slow
def test_video(tmp_path, gl_backend):
    import imageio.v2 as imageio

    result = hs.run("pendulum", duration=0.5)
    path = result.video(tmp_path / "pendulum.mp4", size=(160, 120), fps=10)
    assert path == tmp_path / "pendulum.mp4" and not [p for p in tmp_path.iterdir() if p.name.startswith(".")]
    with imageio.get_reader(str(path)) as reader:
        frames = [frame for frame in reader]
    assert len(frames) == 6 and frames[0].shape == (120, 160, 3) and frames[0].std() > 5
    with pytest.raises(UsageError, match="must be even"):
        result.video(tmp_path / "odd.mp4", size=(161, 120))
    with pytest.raises(UsageError, match="produces no trajectory"):
        hs.run("leg-sweep", amplitudes=[0.02], omegas=[1], workers=1).video(tmp_path / "sweep.mp4")


@pytest.mark.slow
def test_import_and_use_never_touch_the_callers_matplotlib(tmp_path):
    script = textwrap.dedent(
        """
        import sys
        import matplotlib
        matplotlib.use("svg")
        matplotlib.rcParams["lines.linewidth"] = 7.0
        matplotlib.rcParams["font.size"] = 21.0
        before = dict(matplotlib.rcParams)
        import hexabot_sim as hs
        assert "mujoco" not in sys.modules and "matplotlib.pyplot" not in sys.modules
        result = hs.run("pendulum", duration=0.2)
        figures = result.figures()
        result.save(sys.argv[1])
        assert matplotlib.get_backend() == "svg", matplotlib.get_backend()
        after = dict(matplotlib.rcParams)
        changed = sorted(k for k in before if before[k] != after[k])
        assert not changed, changed
        assert "matplotlib.pyplot" not in sys.modules
        # The package's figures keep matplotlib's default style, not the caller's rcParams.
        line = figures["angle_velocity"].axes[0].lines[0]
        assert line.get_linewidth() != 7.0, line.get_linewidth()
        print("ok")
        """
    )
    proc = subprocess.run(
        [sys.executable, "-c", script, str(tmp_path / "run")], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 0 and proc.stdout.strip() == "ok", proc.stderr


@pytest.mark.slow
def test_quickstart_notebook_runs_top_to_bottom(tmp_path, gl_backend):
    nbformat = pytest.importorskip("nbformat", reason="the notebook test needs the 'test' extra (nbformat)")
    nbclient = pytest.importorskip("nbclient", reason="the notebook test needs the 'test' extra (nbclient)")
    pytest.importorskip("ipykernel", reason="the notebook test needs the 'test' extra (ipykernel)")
    notebook = nbformat.read(ROOT / "examples" / "quickstart.ipynb", as_version=4)
    client = nbclient.NotebookClient(
        notebook, timeout=120, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}
    )
    client.execute()  # raises CellExecutionError on the first cell that fails
    outputs = [out for cell in notebook.cells if cell.cell_type == "code" for out in cell.get("outputs", [])]
    assert not [out for out in outputs if out.output_type == "error"]
    images = [out for out in outputs if "image/png" in out.get("data", {})]
    assert len(images) >= 3, "expected inline figures and video frames"
    html = " ".join(out["data"].get("text/html", "") for out in outputs if "data" in out)
    assert "<video" in html


def test_config_file_then_keywords(tmp_path):
    config = tmp_path / "p.toml"
    config.write_text("damping = 0.02\nstiffness = 0.7\n")
    result = hs.run("pendulum", config=config, stiffness=0.9, duration=0.1)
    assert (result.params["damping"], result.params["stiffness"]) == (0.02, 0.9)
    with pytest.raises(UsageError, match="not found"):
        hs.run("pendulum", config=tmp_path / "missing.toml")


@pytest.mark.parametrize(
    ("call", "fragment"),
    [
        (lambda: hs.run("pendulum", config=5), "'config' must be a path"),
        (lambda: hs.run("pendulum", config={"mass": 1}), "'config' must be a path"),
        (lambda: hs.run("pendulum", progress=5), "'progress' must be a callable"),
    ],
)
def test_wrong_argument_types_are_usage_errors(call, fragment):
    with pytest.raises(UsageError, match=fragment):
        call()


def test_wrong_save_and_video_arguments_are_usage_errors(tmp_path, leg):
    with pytest.raises(UsageError, match="'out' must be a path"):
        leg.save(5)
    with pytest.raises(UsageError, match="'progress' must be a callable"):
        leg.save(tmp_path / "run", progress="yes")
    with pytest.raises(UsageError, match="'path' must be a path"):
        leg.video(b"video.mp4")
    # Found by fuzzing: without video=True the video options went unchecked (the CLI refuses them either way).
    for bad in ({"quality": "ultra"}, {"size": (1, 1)}, {"fps": -5}):
        with pytest.raises(UsageError, match="video"):
            leg.save(tmp_path / "run", **bad)
    # ... and a scenario that is not a name was a TypeError (a list) or "unknown scenario 'pendulum'" (a Path).
    for name in (["pendulum"], Path("pendulum")):
        with pytest.raises(UsageError, match="scenario must be a name \\(a string\\); got "):
            hs.run(name)
    assert list(tmp_path.iterdir()) == []


def test_write_folder_writes_only_into_an_existing_empty_folder(tmp_path, leg):
    """Result.write_folder (the building block save and the command line fill their staging folder with) took a
    Path only (a str was a TypeError traceback), and it wrote over the files of a folder that held some. (A missing
    folder stays the writing's OSError: the command line says its staging folder was moved during the run.)"""
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "run.json").write_text("keep")
    for path in (tmp_path / "mine", str(tmp_path / "mine" / "run.json")):
        with pytest.raises(UsageError, match="'path' must be an empty folder"):
            leg.write_folder(path, plots=False)
    with pytest.raises(UsageError, match="'path' must be a path"):
        leg.write_folder(5)
    assert (tmp_path / "mine" / "run.json").read_text() == "keep"
    (tmp_path / "empty").mkdir()
    written = leg.write_folder(str(tmp_path / "empty"), plots=False)
    assert (tmp_path / "empty" / "run.json").is_file() and written is not None


def test_save_refusals_name_its_arguments_not_the_command_lines_options(tmp_path, leg):
    """Result.save into a non-empty folder said "choose another --out or add --force to replace it"."""
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "mine.txt").write_text("keep")
    with pytest.raises(UsageError) as refused:
        leg.save(tmp_path / "run")
    assert str(refused.value).endswith("is not empty; choose another out or pass force=True to replace it")
    assert (tmp_path / "run" / "mine.txt").read_text() == "keep"
