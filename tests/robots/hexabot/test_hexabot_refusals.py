"""The walking hexabot's refusals: commands, durations and duties it cannot walk, each said in one line, and the
values a refusal suggests accepted when typed back in."""

import re

import pytest

from hexabot_sim import params
from hexabot_sim.errors import UsageError
from hexabot_sim.robots.hexabot.walk import HexabotParams


@pytest.mark.parametrize(
    ("overrides", "fragment"),
    [
        ({"vx": 0.6}, "the largest feasible in this direction is vx = "),
        ({"vx": 0.6}, "workspace or joint ranges; the largest feasible in this direction is vx = 0.399 m/s; a shorter"),
        ({"gait": "wave", "vx": 0.25}, "the largest feasible in this direction is vx = "),
        # The swing's speed limit does not depend on the period: the advice is another gait, not a shorter period.
        ({"gait": "ripple", "vx": 0.25}, "swing moves the foot over the ground 2x as fast as the body whatever the"),
        # A duty of one's own is named as the fix (a tripod at duty 0.8 was told only of gaits with less stance).
        ({"vx": 0.2, "duty": 0.8}, "whatever the period: a lower 'duty' (the gait's own: 0.5)"),
        # The tripod has no gait with less stance (it was told to take one).
        ({"vx": 0.1, "step_height": 0.1}, "than the tripod: lower the command or 'step_height', or raise"),
        # A duty equal to the gait's own is not told to be lowered (the range starts there).
        (
            {"gait": "wave", "duty": 5 / 6, "period": 0.5, "vx": 0},
            "s): joints would turn at 12.2 rad/s, above 0.9 x "
            "max_joint_speed; lengthen 'period' or lower 'step_height'",
        ),
        ({"duty": 0.5, "vx": 0.1, "step_height": 0.1}, "no gait has less stance than the tripod"),
        # A pure turn's stride is its feet's arc (it printed "stride 0 m").
        ({"vx": 0, "yaw_rate": 3}, "(stride 0.391 m): foot rr would leave"),
        ({"vx": 0, "yaw_rate": 3}, "a shorter 'period' shortens the stride (the turn's arc)"),
        ({"vx": 100}, "did you mean 100 mm/s = 0.1 m/s"),
        ({"seed": "abc"}, "must be a number with 0 <= seed <= 4294967295; got 'abc'"),  # not 4.29497e+09
        ({"gait": "wave", "period": 0.5}, "even stepping in place is infeasible"),
        ({"max_joint_speed": 0.5}, "lengthen 'period' or lower 'step_height' (or raise 'max_joint_speed')"),
        ({"timestep": 0.005}, "timestep"),
        # A single row after the ramp gave NaN mean speeds and numpy warnings (found by fuzzing).
        ({"duration": 1.5001, "timestep": 0.0017}, "0.1 s to measure the walk: 1.6 s; got 1.5001"),
    ],
)
def test_infeasible_commands_are_refused_up_front(overrides, fragment):
    with pytest.raises(UsageError, match=None) as info:
        params.resolve(HexabotParams, {}, overrides)
    assert fragment in str(info.value)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("overrides", "pattern", "fix"),
    [
        *[
            ({"gait": g, d: v}, "largest feasible in this direction is (.+?); ", "command")
            for g in ("tripod", "ripple", "wave")
            for d, v in (("vx", 0.6), ("vx", -0.6), ("vy", 0.6), ("vy", -0.6), ("yaw_rate", 2.9), ("yaw_rate", -2.9))
        ],
        ({"gait": "wave", "vx": 0.05, "duty": 0.8}, r"must be (\S+) to < 1", "duty"),
        ({"gait": "ripple", "duty": 0.6}, r"must be (\S+) to < 1", "duty"),
        ({"slope_deg": 10.0, "friction": 0.1}, r"at least tan\(slope\) = (\S+)", "friction"),
        ({"slope_deg": 10.0, "friction": 0.1}, r"the steepest slope it holds is (\S+) deg", "slope_deg"),
        ({"slope_deg": 30.0, "level_body": "on"}, r"steepest levelled slope is (\S+) deg", "slope_deg"),
        ({"kerb_height": 0.05}, r"largest climbable, (\S+) mm", "kerb_height"),
        ({"kerb_height": 0.02, "stand_height": 0.03}, r"\(at most (\S+) mm\)", "kerb_height"),
        # 'needs about 17.3 s' (17.308) was refused when typed back (found by fuzzing).
        ({"waypoints": [[1.234, 0]], "duration": 10.0}, r"the walk needs about (\S+) s", "duration"),
    ],
)
def test_the_values_a_refusal_suggests_are_accepted(overrides, pattern, fix):
    """The advice in a refusal, typed back in, is accepted: bounds are rounded to the allowed side (found by fuzzing:
    'duty must be 0.833 to < 1' refused 0.833 for the wave, whose smallest duty is 5/6)."""
    with pytest.raises(UsageError) as refused:
        params.resolve(HexabotParams, {}, overrides)
    found = re.search(pattern, str(refused.value))
    assert found, str(refused.value)
    if fix == "command":  # "vx = 0.0561 m/s, vy = 0.336 m/s": the components not named are 0
        suggested = {"vx": 0.0, "vy": 0.0, "yaw_rate": 0.0}
        suggested |= {name: float(v) for name, v in re.findall(r"(\w+) = (\S+) ", found.group(1))}
    else:
        suggested = {fix: float(found.group(1)) / (1000 if fix == "kerb_height" else 1)}
    params.resolve(HexabotParams, {}, {**overrides, **suggested})  # no UsageError


def test_a_walk_too_long_for_the_run_budget_is_told_a_duration_it_takes():
    """Found by fuzzing: duration=2400 (allowed: <= 3600) was refused with "lower 'duration' or raise 'timestep'" at
    the largest timestep, and a long waypoint course advised "raise 'duration' to at least 2.4e+03 s", which the
    budget then refused: advice that could not be followed."""
    with pytest.raises(UsageError) as refused:
        params.resolve(HexabotParams, {}, {"duration": 2400})
    message = str(refused.value)
    assert "raise 'timestep'" not in message  # 0.002 s is its largest
    longest = re.search(r"lower 'duration' to at most (\S+) s at timestep 0\.002 s$", message)
    assert longest, message
    params.resolve(HexabotParams, {}, {"duration": float(longest.group(1))})  # the advice is taken
    assert "or raise 'timestep'" in str(_refusal({"duration": 1500, "timestep": 0.001}))
    course = _refusal({"waypoints": [[100, 0], [0, 0.5]], "duration": 100})
    assert f"longer than the longest walk ({longest.group(1)} s at timestep 0.002 s)" in str(course)


def _refusal(overrides: dict) -> UsageError:
    with pytest.raises(UsageError) as refused:
        params.resolve(HexabotParams, {}, overrides)
    return refused.value


def test_a_duty_too_long_to_step_in_place_is_named():
    """duty=0.99 was refused as 'even stepping in place is infeasible ... lengthen 'period' or lower 'step_height''
    without a word about the duty that left a 10 ms swing (found by fuzzing)."""
    words = r"duty 0\.99: a swing of 0\.01 s\): joints would turn .*; lengthen 'period', lower 'duty'"
    with pytest.raises(UsageError, match=words):
        params.resolve(HexabotParams, {}, {"duty": 0.99})


def test_refused_largest_feasible_command_is_feasible():
    with pytest.raises(UsageError) as info:
        params.resolve(HexabotParams, {}, {"vx": 0.6})
    largest = float(str(info.value).split("vx = ")[1].split(" m/s")[0])
    params.resolve(HexabotParams, {}, {"vx": largest * 0.999})


def test_an_hour_long_walk_is_refused_with_the_estimate():
    with pytest.raises(UsageError, match="GB in memory"):
        params.resolve(HexabotParams, {}, {"duration": 3600})


def _refusal_of(cls: type, overrides: dict) -> UsageError:
    with pytest.raises(UsageError) as refused:
        params.resolve(cls, {}, overrides)
    return refused.value


def test_the_quadbots_crawl_too_fast_is_told_of_the_trot():
    """The gaits with less stance were named for the hexabot's only: the crawl was told of none (found by fuzzing)."""
    from hexabot_sim.robots.quadbot.parameters import QuadbotParams

    assert str(_refusal_of(QuadbotParams, {"vx": 0.2})).endswith("a gait with less stance is faster (trot)")
