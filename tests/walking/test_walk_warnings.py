"""A walk whose figures say it is physically off says so: a fall, servos held at their torque limit (a warning line
after the run, in run.json, on the report page, and a RunWarning from the API); a sound walk warns of nothing."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import pytest
from helpers import cli

import hexabot_sim as hs
from hexabot_sim.errors import RunWarning
from hexabot_sim.result import Metric
from hexabot_sim.walking import metrics

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "my_hexapod.toml"


def _metrics(fell: bool, share: float) -> dict[str, Metric]:
    return {
        "fell": Metric(fell, "", ""),
        "fell_at": Metric(2.5 if fell else None, "s", ""),
        "torque_saturated_fraction": Metric(share, "1", ""),
    }


def test_the_warnings_follow_their_thresholds() -> None:
    assert metrics.walk_warnings(_metrics(False, 0.0), 1.5) == []
    assert metrics.walk_warnings(_metrics(False, metrics.SATURATION_WARNING), 1.5) == []  # at the bound: not above
    [fall] = metrics.walk_warnings(_metrics(True, 0.0), 1.5)
    assert fall.startswith("the robot fell at t = 2.5 s (the plate touched the ground or tilted beyond 45 deg")
    [saturate] = metrics.walk_warnings(_metrics(False, 0.3), 1.5)
    assert saturate.startswith("the servos saturate: a joint of a loaded leg was at its 1.5 N m torque limit in 30 %")
    assert len(metrics.walk_warnings(_metrics(True, 0.9), 1.5)) == 2


def test_a_sound_walk_warns_of_nothing_and_its_saturation_agrees_with_its_peak_torque() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error", RunWarning)
        result = hs.run("hexabot-walk", robot=str(EXAMPLE), duration=1.6)
    assert result.warnings == []
    assert result.metrics["torque_limit_fraction"].value < 1  # the peak under the limit: never at it
    assert result.metrics["torque_saturated_fraction"].value == 0.0
    assert result.metrics["fell"].value is False and result.metrics["fell_at"].value is None


def test_a_robot_too_heavy_for_its_servos_walks_with_a_warning(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """The example hexapod's plate at 3.8 kg instead of 1.2 passes the stand check (on three feet at the neutral
    stance) but its loaded legs sit at the 1.5 N m limit through most of the walk: it used to say nothing."""
    heavy = tmp_path / "heavy.toml"
    text = EXAMPLE.read_text()
    assert "mass = 1.2 " in text
    heavy.write_text(text.replace("mass = 1.2 ", "mass = 3.8 ", 1))
    out = tmp_path / "run"
    code, stdout, err = cli(capsys, "run", "hexabot-walk", "--set", f"robot={heavy}", "--set", "duration=1.6",
                            "--no-plots", "--out", str(out))  # fmt: skip
    assert code == 0 and "files:" in stdout
    [line] = [x for x in err.splitlines() if "warning" in x]
    assert line.startswith("hexabot-sim: warning: the servos saturate: a joint of a loaded leg was at its 1.5 N m")
    record = json.loads((out / "run.json").read_text())
    assert record["metrics"]["torque_saturated_fraction"] > metrics.SATURATION_WARNING
    assert record["metrics"]["torque_limit_fraction"] == pytest.approx(1.0)
    assert record["warnings"] == [line.removeprefix("hexabot-sim: warning: ")]
    assert "<b>Warning:</b> the servos saturate" in (out / "report.html").read_text()
    with pytest.warns(RunWarning, match="the servos saturate"):
        hs.run("hexabot-walk", robot=str(heavy), duration=1.6)
