"""A parameter the user set that the run makes no use of is refused in one line (hexabot_sim.unused): a kerb's
distance with no kerb, a speed under a schedule. Not when the scenario set it, nor when it equals its default, nor
a run repeated from its run.json's parameters, nor a sweep some of whose cells use it."""

from __future__ import annotations

import re

import pytest
from helpers import cli

from hexabot_sim import api, params, sweep
from hexabot_sim.errors import UsageError

SCHEDULE = ((0.0, 0.05, 0.0, 0.0),)  # t, vx, vy, yaw_rate
SHORT = {"duration": 1.6}


@pytest.mark.parametrize(
    ("given", "fragment"),
    [
        ({"stairs_run": 0.3}, "'stairs_run' = 0.3 has no effect without stairs: set stairs_rise"),
        ({"stairs_count": 4}, "'stairs_count' = 4 has no effect without stairs"),
        ({"stairs_distance": 0.8}, "'stairs_distance' = 0.8 has no effect without stairs"),
        ({"kerb_distance": 0.4}, "'kerb_distance' = 0.4 has no effect without a kerb: set kerb_height"),
        ({"slope_heading": "across"}, "'slope_heading' = across has no effect on level ground: set slope_deg"),
        ({"reflex": "off"}, "'reflex' = off has no effect with planned touchdown"),
        ({"schedule_scale": 2.0}, "'schedule_scale' = 2 has no effect without a schedule"),
        ({"path_speed": 0.05}, "'path_speed' = 0.05 has no effect without waypoints"),
        ({"path_yaw_rate": 0.2}, "'path_yaw_rate' = 0.2 has no effect without waypoints"),
        ({"schedule": SCHEDULE, "vx": 0.05}, "'vx' = 0.05 has no effect with a schedule"),
        ({"waypoints": ((0.3, 0.0),), "yaw_rate": 0.1, "duration": 7.0}, "'yaw_rate' = 0.1 has no effect with way"),
    ],
)
def test_an_ignored_parameter_is_refused(given, fragment):
    with pytest.raises(UsageError, match=re.escape(fragment)) as e:
        api.prepare("hexabot-walk", SHORT, given)
    assert str(e.value).endswith("or leave it out") and "\n" not in str(e.value)


@pytest.mark.parametrize(
    ("scenario", "given"),
    [
        ("hexabot-walk", {"stairs_rise": 0.02, "stairs_count": 2, "stairs_run": 0.3, "touchdown": "sensed"}),
        ("hexabot-walk", {"kerb_height": 0.02, "kerb_distance": 0.4, "touchdown": "sensed"}),
        ("hexabot-walk", {"slope_deg": 5.0, "slope_heading": "across"}),
        ("hexabot-walk", {"touchdown": "sensed", "reflex": "off"}),
        ("hexabot-walk", {"schedule": SCHEDULE, "schedule_scale": 2.0}),
        ("hexabot-walk", {"stairs_count": 3, "vx": 0.1}),  # each its default: harmless
        ("hexabot-turn", {"schedule": SCHEDULE}),  # the scenario's own yaw_rate is not the user's
        ("hexabot-turn", {"schedule": SCHEDULE, "yaw_rate": 0.3}),  # set to the scenario's value
        ("hexabot-stairs", {"stairs_count": 2}),
    ],
)
def test_a_used_or_default_parameter_is_taken(scenario, given):
    api.prepare(scenario, SHORT, given)


def test_a_run_repeats_from_its_full_parameters():
    """A run.json's parameters hold every value, the ignored ones at their defaults: repeating them is not refused."""
    first = api.prepare("hexabot-turn", {"duration": 3.0, "schedule": SCHEDULE})
    again = api.prepare("hexabot-turn", params.as_dict(first.params))
    assert again.params == first.params


def test_the_command_line_refuses_in_one_line_and_writes_nothing(capsys, tmp_path):
    out = tmp_path / "run"
    code, stdout, err = cli(capsys, "run", "hexabot-walk", "--set", "kerb_distance=0.4", "--out", str(out))
    assert code == 2 and not stdout and not out.exists()
    assert err.strip().count("\n") == 0 and "'kerb_distance' = 0.4 has no effect without a kerb" in err


def test_a_sweep_refuses_a_parameter_no_cell_uses():
    with pytest.raises(UsageError, match=re.escape("'stairs_count' = 2 has no effect without stairs")):
        sweep.plan("hexabot-walk", ["seed=0,1"], {}, {**SHORT, "stairs_count": 2})
    # Cells with stairs use it (the flat one does not): a study of the rise from flat is taken.
    plan = sweep.plan("hexabot-walk", ["stairs_rise=0,0.02"], {}, {**SHORT, "stairs_count": 2, "touchdown": "sensed"})
    assert [c.stairs_count for c in plan.cells] == [2, 2]
    # A swept parameter is given by the user too.
    with pytest.raises(UsageError, match=re.escape("'kerb_distance' = 0.4 has no effect without a kerb")):
        sweep.plan("hexabot-walk", ["kerb_distance=0.4,0.6"], {}, SHORT)


def test_a_sweep_cell_repeats_from_its_recorded_parameters(tmp_path):
    """A cell without stairs of a sweep over stairs_rise records the sweep's stairs_count: its run.json's parameters
    (every one, in one layer) repeat it, through the API and a config file; a --set over them is still checked."""
    plan = sweep.plan("hexabot-walk", ["stairs_rise=0,0.02"], {}, {**SHORT, "stairs_count": 2, "touchdown": "sensed"})
    flat = params.as_dict(plan.cells[0])
    assert flat["stairs_rise"] == 0 and flat["stairs_count"] == 2
    assert api.prepare("hexabot-walk", flat).params == plan.cells[0]
    config = tmp_path / "cell.toml"
    config.write_text("".join(f"{k} = {v!r}\n".replace("'", '"').replace("()", "[]") for k, v in flat.items()))
    assert api.prepare("hexabot-walk", params.read_config(config), {}).params == plan.cells[0]
    with pytest.raises(UsageError, match=re.escape("'kerb_distance' = 0.7 has no effect without a kerb")):
        api.prepare("hexabot-walk", flat, {"kerb_distance": 0.7})
    # A sweep from the same parameters as its config file: the cells at stairs_rise = 0 use nothing new.
    sweep.plan("hexabot-walk", ["seed=0,1"], flat, {})


def test_a_refused_value_is_shown_exactly():
    """Not rounded to the default it is not: vx = 0.3 / 3 under a schedule was refused as "'vx' = 0.1"."""
    with pytest.raises(UsageError, match=re.escape("'kerb_distance' = 0.5000001 has no effect")):
        api.prepare("hexabot-walk", SHORT, {"kerb_distance": 0.5000001})
    with pytest.raises(UsageError, match=re.escape("'vx' = 0.09999999999999999 has no effect with a schedule")):
        api.prepare("hexabot-walk", SHORT, {"schedule": SCHEDULE, "vx": 0.3 / 3})
