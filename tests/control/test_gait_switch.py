"""Gait changes mid-walk (GaitPlanner.switch): every swing and stance continuous, feet down, the new gait's pattern."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from hexabot_sim.control.gait import FINISH, FINISH_LIFT, GAITS, SETTLE, Command, GaitPlanner
from hexabot_sim.robots.hexabot.model import DEFAULT_LAYOUT

DT = 0.002
PERIOD = 1.0


def _walk(gaits: list[tuple[float, str]], cmd: Command, until: float, settle: float = SETTLE):
    """Plans chunk by chunk, switching gait at the given times: (times, targets (n, legs, 3), stance (n, legs))."""
    planner = GaitPlanner(GAITS[gaits[0][1]], PERIOD, 0.03, DEFAULT_LAYOUT.neutral_feet_body(), DT, start_time=0.5)
    pending = list(gaits[1:])
    times, rows, flags = [], [], []
    while planner.time < until - 1e-9:
        if pending and planner.time >= pending[0][0] - 1e-9:
            planner.switch(GAITS[pending.pop(0)[1]], settle=settle)
        n = planner.max_chunk // 4
        if pending:
            n = min(n, max(1, round((pending[0][0] - planner.time) / DT)))
        out = planner.plan(cmd, n)
        t = planner.time - DT * np.arange(n, -1, -1)
        times.append(t[1:])
        rows.append(out[1:])
        flags.append(planner.in_stance(t[1:]))
    return np.concatenate(times), np.concatenate(rows), np.concatenate(flags), planner


def _runs(flags: np.ndarray, times: np.ndarray, value: bool) -> list[tuple[float, float]]:
    """(start, length) [s] of each complete run of `value` in a leg's flags."""
    edges = np.flatnonzero(np.diff(flags.astype(int))) + 1
    out = []
    for a, b in itertools.pairwise(edges):
        if flags[a] == value:
            out.append((times[a], times[b] - times[a]))
    return out


@pytest.mark.parametrize("sequence", [("tripod", "wave", "tripod"), ("tripod", "ripple", "wave"), ("wave", "ripple")])
def test_switches_keep_every_swing_whole_the_stances_ground_fixed_and_three_feet_down(sequence):
    switches = [(0.0, sequence[0])] + [(3.3 + 2.7 * k, g) for k, g in enumerate(sequence[1:])]
    cmd = Command(0.05, 0.0, 0.0)
    t, rows, stance, planner = _walk(switches, cmd, switches[-1][0] + 3.0)
    assert [g for _, g in planner.switches] == list(sequence[1:])
    walking = t > 0.5
    assert stance[walking].sum(axis=1).min() >= 3  # never fewer than three feet down
    swing_times = {(1 - GAITS[g].duty) * PERIOD for g in sequence}
    for leg in range(stance.shape[1]):
        # Every swing lasts one of the gaits' swing times: none is cut short or stretched.
        for _, length in _runs(stance[:, leg], t, False):
            assert min(abs(length - s) for s in swing_times) < 1.5 * DT, (leg, length)
        # A stance foot is ground-fixed: under a straight command it moves back at exactly the body speed.
        x = rows[:, leg, 0]
        moving = stance[1:, leg] & stance[:-1, leg] & (t[:-1] >= 0.5)
        assert np.diff(x)[moving] == pytest.approx(-cmd.vx * DT, abs=1e-12)
        # Continuous targets: no step moves a foot faster than 1 m/s.
        assert np.abs(np.diff(rows[:, leg], axis=0)).max() < 1.0 * DT


@pytest.mark.parametrize("new", ["wave", "ripple"])
def test_after_a_switch_the_feet_lift_in_the_new_gaits_order(new):
    t, _, stance, _ = _walk([(0.0, "tripod"), (3.0, new)], Command(0.05, 0.0, 0.0), 8.0)
    late = t > 5.0  # two periods after the switch
    lifts = []
    for leg in range(stance.shape[1]):
        s = stance[late, leg].astype(int)
        k = np.flatnonzero(np.diff(s) == -1)[0] + 1
        lifts.append(t[late][k])
    # Lift-off times differ by the gait's phase offsets: leg i lifts when (t - start) / period + offset_i = duty.
    offsets = np.array(GAITS[new].offsets)
    implied = np.mod(np.array(lifts) / PERIOD + offsets, 1.0)
    spread = np.abs(np.angle(np.exp(2j * math.pi * (implied - implied[0])))).max()
    assert spread < 2 * math.pi * 2 * DT / PERIOD


@pytest.mark.parametrize("at", [6.5, 7.0, 11.0])
def test_a_switch_at_the_instant_a_foot_lands_takes_it_as_landed(at):
    # A wave clock started at 14/3 s (a phase a switch chose in a walk) has a foot land at each of these times with
    # its phase a rounding error short of 1. That once read as a swing under way whose touchdown was a whole period
    # later: after the switch to the tripod the plan had the robot stand on a foot in the air (its speed fell 86 %).
    planner = GaitPlanner(GAITS["wave"], PERIOD, 0.03, DEFAULT_LAYOUT.neutral_feet_body(), DT, start_time=14 / 3)
    while planner.time < at - 1e-9:
        planner.plan(Command(0.05, 0.0, 0.0), min(planner.max_chunk, max(1, round((at - planner.time) / DT))))
    planner.switch(GAITS["tripod"])
    lift, land = planner.timing[:, FINISH_LIFT], planner.timing[:, FINISH]
    swinging = land > at
    assert (land[swinging] - at <= (1 - GAITS["wave"].duty) * PERIOD + 1e-9).all(), land
    assert land[swinging] - lift[swinging] == pytest.approx((1 - GAITS["wave"].duty) * PERIOD), (lift, land)


@pytest.mark.parametrize("settle", [SETTLE, 0.25])
@pytest.mark.parametrize("sequence", [("tripod", "wave"), ("wave", "tripod"), ("tripod", "ripple"), ("ripple", "wave")])
def test_after_a_switch_every_foot_is_down_for_the_settling_time_before_the_new_gait_lifts_one(sequence, settle):
    t, _, stance, planner = _walk([(0.0, sequence[0]), (3.3, sequence[1])], Command(0.05, 0.0, 0.0), 7.0, settle)
    switched = planner.switches[0][0]
    swings = [run for leg in range(stance.shape[1]) for run in _runs(stance[:, leg], t, False)]
    last_old = max([lift + n for lift, n in swings if switched - 1.0 < lift <= switched] + [switched])
    first_new = min(lift for lift, _ in swings if lift > switched)
    assert first_new >= last_old + settle - DT / 2
    assert stance[(t >= last_old) & (t < last_old + settle)].all()
    assert not stance[(t >= first_new) & (t < first_new + DT / 2)].all()


@pytest.mark.parametrize("before", [0.3, 0.05, DT])
@pytest.mark.parametrize("new", ["wave", "ripple"])
def test_a_switch_while_standing_before_the_gait_clock_starts_walks_the_new_gait_from_the_start(new, before):
    # The viewer's steering plans 0.05 s chunks from t = 0, so a gait key pressed in the first half second switches
    # before the clock's start. That once finished the old gait's swings "under way" at the start from a planner
    # still standing: a foot's target jumped 28 mm in one step (~14 m/s) when the next chunk found it mid-swing.
    start, cmd = 0.5, Command(0.03, 0.0, 0.0)
    neutral = DEFAULT_LAYOUT.neutral_feet_body()
    planner = GaitPlanner(GAITS["tripod"], PERIOD, 0.03, neutral, DT, start_time=start)
    fresh = GaitPlanner(GAITS[new], PERIOD, 0.03, neutral, DT, start_time=start)
    rows, expected = [], []
    switched = False
    while planner.time < 4.0 - 1e-9:
        n = 25
        if not switched and planner.time + n * DT > start - before:  # switch `before` ahead of the start
            n = max(1, round((start - before - planner.time) / DT))
            if planner.time >= start - before - DT / 2:
                planner.switch(GAITS[new])
                switched = True
                n = 25
        rows.append(planner.plan(cmd, n)[1:])
        expected.append(fresh.plan(cmd, n)[1:])
    assert [g for _, g in planner.switches] == [new]
    rows = np.concatenate(rows)
    assert np.abs(np.diff(rows, axis=0)).max() < 1.0 * DT  # continuous targets
    np.testing.assert_allclose(rows, np.concatenate(expected), atol=1e-12)  # as if it had begun in the new gait


@pytest.mark.parametrize("period", [1.0, 1.2])
@pytest.mark.parametrize("new", ["wave", "ripple"])
def test_a_switch_at_the_instant_a_swing_lifts_plans_that_swing_from_the_switch(new, period):
    # At the gait clock's start (a schedule's second row before it) half the tripod lifts. Its touchdown less the
    # swing time came out 1e-16 s after the switch at period 1.2 s (1.1 - 0.6): the swing was not under way at the
    # chunk's start, the foot stayed down to the chunk's end and then jumped 28 mm up in one step.
    dt, start = 0.001, 0.5
    planner = GaitPlanner(GAITS["tripod"], period, 0.03, DEFAULT_LAYOUT.neutral_feet_body(), dt, start_time=start)
    planner.plan(Command(), round(start / dt))
    assert planner.time == start
    planner.switch(GAITS[new])
    lift = planner.timing[:, FINISH_LIFT]
    assert (lift[np.isfinite(lift)] <= start).all(), lift
    rows = np.concatenate([planner.plan(Command(), 250)[1:] for _ in range(8)])
    assert np.abs(np.diff(rows, axis=0)).max() < 1.0 * dt
