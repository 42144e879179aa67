"""leg-sweep: the grid, its prediction from the workspace, and the CLI run folder."""

import json
import math

import numpy as np
import pytest

from hexabot_sim import params, registry
from hexabot_sim.__main__ import main
from hexabot_sim.errors import UsageError


def test_small_grid_matches_the_workspace_prediction():
    s = registry.get("leg-sweep")
    p = params.resolve(s.params_type, s.defaults, {"amplitudes": "0.05,0.1", "omegas": "1", "periods": "1"})
    result = s.runner("leg-sweep", p)
    c = result.columns
    assert list(c["amplitude"]) == [0.05, 0.1] and list(c["omega"]) == [1.0, 1.0]
    # Independent reach along x at z = -80 mm: (x - L1)^2 + z^2 = (L2 + L3)^2.
    reach = 0.05 + math.sqrt(0.2**2 - 0.08**2) - 0.05
    assert c["reach_forward"] == pytest.approx([reach, reach])
    assert c["excursion_forward"] == pytest.approx([0.1, 0.2])  # 2A/omega
    assert list(c["predicted_to_leave"]) == [0.0, 1.0]
    assert list(c["reached_singular"]) == [0.0, 1.0]
    assert c["max_deviation"][0] < 1e-6 < 1e-3 < c["max_deviation"][1]
    assert result.metrics["prediction_agreement"].value == 1.0


@pytest.mark.slow
def test_sweep_reports_cases_run_in_parallel_like_serially():
    s = registry.get("leg-sweep")
    grid = {"amplitudes": "0.08", "omegas": f"1,{math.pi / 6}", "periods": "1"}
    serial = s.runner("leg-sweep", params.resolve(s.params_type, s.defaults, grid | {"workers": "1"}))
    parallel = s.runner("leg-sweep", params.resolve(s.params_type, s.defaults, grid | {"workers": "2"}))
    for name in serial.columns:
        assert np.array_equal(serial.columns[name], parallel.columns[name]), name
    # 80 mm/s: inside at 1 rad/s (160 mm < 183 mm), out at pi/6 (306 mm): excursion, not frequency.
    assert list(serial.columns["predicted_to_leave"]) == [0.0, 1.0]


@pytest.mark.parametrize(
    ("value", "fragment"),
    [
        ("0.1,,0.2", "comma-separated list"),
        ("0.1,-1", "must be a number with 0.01 <= omegas"),
        ("a", "must be a number"),
        # A value twice made the same cell twice (found by fuzzing; sweep --grid refuses it too).
        ("1,2,1", "parameter 'omegas': the value 1 appears twice; give each value once"),
    ],
)
def test_bad_grid(value, fragment):
    s = registry.get("leg-sweep")
    with pytest.raises(UsageError) as info:
        params.resolve(s.params_type, s.defaults, {"omegas": value})
    assert fragment in str(info.value)


@pytest.mark.slow
def test_cli_writes_grid_and_figures(tmp_path, capsys):
    out = tmp_path / "sweep"
    argv = ["run", "leg-sweep", "--set", "amplitudes=0.02,0.1", "--set", "omegas=1,2", "--set", "periods=0.5"]
    assert main([*argv, "--out", str(out), "--video"]) == 0
    err = capsys.readouterr().err
    assert "no video: leg-sweep produces no trajectory to film" in err
    assert {p.name for p in out.iterdir()} == {
        "grid.csv",
        "run.json",
        "model.xml",
        "sweep.png",
        "workspace.png",
        "report.html",
    }
    header = (out / "grid.csv").read_text().splitlines()[0].split(",")
    assert header[:2] == ["amplitude", "omega"] and "max_deviation" in header
    record = json.loads((out / "run.json").read_text())
    assert record["params"]["omegas"] == [1.0, 2.0] and record["metrics"]["cells"] == 4


@pytest.mark.parametrize(("scenario", "change"), [("leg-sweep", {"substeps": 4}), ("leg-step", {"mode": "kinematic",
                         "integrator": "Euler"}), ("leg-sweep", {"gravity_compensation": "off"})])  # fmt: skip
def test_a_dynamic_setting_in_the_kinematic_mode_is_refused_not_ignored(scenario, change):
    """leg-sweep's default mode is kinematic (q imposed): substeps, integrator and gravity_compensation gave the same
    grid bit for bit whatever their value."""
    import hexabot_sim as hs

    name, value = list(change.items())[-1]
    with pytest.raises(UsageError, match=rf"^parameter '{name}' = '?{value}'? acts in mode=dynamic only .*; set "
                       r"mode=dynamic or leave it at "):  # fmt: skip
        hs.run(scenario, **change, amplitudes="0.05", omegas="1") if scenario == "leg-sweep" else hs.run(
            scenario, **change, duration=0.1
        )
