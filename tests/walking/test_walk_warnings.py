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


def _metrics(fell: bool = False, share: float = 0.0, off: float | None = 0.0, lost: int = 0) -> dict[str, Metric]:
    return {
        "fell": Metric(fell, "", ""),
        "fell_at": Metric(2.5 if fell else None, "s", ""),
        "torque_saturated_fraction": Metric(share, "1", ""),
        "speed_abs_error": Metric(off, "m/s", ""),
        "mean_vx": Metric(0.1 - (off or 0.0), "m/s", ""),
        "mean_vy": Metric(0.0, "m/s", ""),
        "feet_without_ground": Metric(lost, "1", ""),
        "stance_loaded_fraction": Metric(0.73, "1", ""),
    }


def test_the_warnings_follow_their_thresholds() -> None:
    def warned(**kw) -> list[str]:
        return metrics.walk_warnings(_metrics(**kw), 1.5, 0.1)

    assert warned() == [] and warned(off=None) == []  # None: a schedule's or a course's changing command
    assert warned(share=metrics.SATURATION_WARNING) == [] and warned(off=0.05) == []  # at the bounds: not above
    [fall] = warned(fell=True)
    assert fall.startswith("the robot fell at t = 2.5 s (the plate touched the ground or tilted beyond 45 deg")
    [saturate] = warned(share=0.3)
    assert saturate.startswith("the servos saturate: a joint of a loaded leg was at its 1.5 N m torque limit in 30 %")
    [slid] = warned(off=0.364)
    assert slid.startswith("the body's mean velocity is 0.364 m/s off the commanded 0.1 m/s (364 %; mean_vx -0.264")
    [lost] = warned(lost=7)
    assert lost.startswith("7 swings found no ground within the legs' reach") and "carried load 73 %" in lost
    assert len(warned(fell=True, share=0.9, off=0.2, lost=1)) == 4
    # No speed commanded (standing, a turn on the spot): the drift itself, above 1 cm/s.
    assert metrics.walk_warnings(_metrics(off=metrics.STILL_DRIFT_WARNING), 1.5, 0.0) == []
    [drift] = metrics.walk_warnings(_metrics(off=0.2), 1.5, 0.0)
    assert drift.startswith("the body drifted at 0.2 m/s where it was told to stand or turn on the spot")


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


@pytest.mark.parametrize(
    ("overrides", "start"),
    [
        # Found by fuzzing: accepted (the steepest levelled slope is 21.5 deg), 7 swings found no ground and the feet
        # carried load 73 % of their stance, and the run said nothing.
        ({"slope_deg": 21.0, "slope_heading": "downhill", "level_body": "on", "touchdown": "sensed", "duration": 4.0},
         "7 swings found"),
        # 45 deg at friction 1 passes the friction check (tan 45 = 1, necessary, not sufficient) and slides down; as a
        # schedule or a course too (their changing commands null the walk's speed errors: no warning at first).
        ({"slope_deg": 45.0, "duration": 4.0}, "the body's mean velocity is"),
        ({"slope_deg": 45.0, "schedule": [[0, 0.1, 0, 0]], "duration": 6.0}, "a schedule row's mean velocity is 4"),
        ({"slope_deg": 45.0, "waypoints": [[0.5, 0]], "duration": 9.0}, "the body ended 2.8"),
        # ... and told to turn on the spot, or to stand and turn in a schedule (no speed commanded: no warning at first)
        ({"slope_deg": 45.0, "vx": 0.0, "yaw_rate": 0.3, "duration": 8.0}, "the body drifted at 0.4"),
        ({"slope_deg": 45.0, "schedule": [[0, 0, 0, 0.3], [4, 0, 0, 0]], "duration": 8.0}, "the body drifted at 0.5"),
    ],
)  # fmt: skip
def test_walks_far_off_their_command_say_so(overrides, start) -> None:
    with pytest.warns(RunWarning) as caught:
        result = hs.run("hexabot-walk", **overrides)
    [warning] = result.warnings
    assert warning.startswith(start) and [str(w.message) for w in caught] == [warning]


def test_metrics_without_a_stance_in_the_window_are_null_and_say_why() -> None:
    """A 10 s period in a 12.5 s walk: no stance starts and ends inside the steady window. slip_per_stance read 0.0
    (the feet did slide: slip_mean > 0) and touchdown_impact_ratio was null without a word (found by fuzzing)."""
    result = hs.run("hexabot-walk", period=10.0, duration=12.5, vx=0.02)
    m = result.metrics
    assert m["slip_mean"].value > 0 and m["slip_per_stance"].value is None
    assert "null here: no stance began inside the steady walk's window" in m["slip_per_stance"].doc
    for name in ("touchdown_impact_ratio", "touchdown_impact_ratio_mean", "touchdown_impact_ratio_lf"):
        assert m[name].value is None and "null here: no stance started and ended inside" in m[name].doc
    assert "no stance in the steady walk" in result.figures()["slip"]._suptitle.get_text()


def test_a_warning_raised_as_an_error_keeps_the_result_and_a_notebook_shows_it(tmp_path) -> None:
    """Under warnings.simplefilter("error") the RunWarning came after the run and took the result with it; the
    notebook's display of a Result did not show its warnings (found by fuzzing)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(RunWarning) as raised:
            hs.run("pendulum-undamped", stiffness=24000.0, duration=0.5)
    result = raised.value.result
    assert result.metrics["energy_drift_rel"].value > 0.9 and result.warnings == [str(raised.value)]
    assert "<b>Warning:</b> energy_drift_rel = " in result._repr_html_()


def test_a_changing_command_gives_its_own_reason_once() -> None:
    """A schedule's walk nulled vy_error with two reasons, the first wrong ("commanded under 0.001": its second row
    walks at vy 0.1); schedule_yaw_rate_error_max was null without one."""
    m = hs.run("hexabot-walk", schedule=[[0, 0.1, 0, 0], [3, 0, 0.1, 0]], duration=6.0).metrics
    for name in ("vy_error", "yaw_rate_error", "lateral_drift"):
        assert m[name].value is None and m[name].doc.count("null here") == 1 and "the command changes" in m[name].doc
    assert "null here: no row turning" in m["schedule_yaw_rate_error_max"].doc


def test_a_run_warning_crosses_processes() -> None:
    """RunWarning's .result (a Result holding a compiled model and lambdas) made it unpicklable: raised as an error in
    a process pool's worker, it arrived as "Can't pickle local object" (found by fuzzing). The text crosses."""
    import pickle

    with pytest.warns(RunWarning):
        result = hs.run("pendulum-undamped", stiffness=24000.0, duration=0.2)
    again = pickle.loads(pickle.dumps(RunWarning(result.warnings[0], result)))
    assert isinstance(again, RunWarning) and str(again) == result.warnings[0] and again.result is None
