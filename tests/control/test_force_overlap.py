"""The stance force control's overlapping hand-overs (`load_sharing=force` with a `duty` above the gait's own,
force_control.for_overlap), against closed forms: the smoothstep ramp, the weights of a landing and a lifting
foot through force_pre (they sum to 1 over the overlap, each continuous), the forces' sum equal to the commanded
total at every step, an early touch held at the least weight, and the force loop around the touch sensors."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from hexabot_sim.control import force_kernels as fk
from hexabot_sim.control.force_control import ForceSettings, for_overlap, for_walk

W = 1.78 * 9.81
DT = 0.002


def test_the_ramps_are_linear_or_smoothstep():
    """ramp(x) is clip(x, 0, 1), or 3 x^2 - 2 x^3 on [0, 1] (0 before, 1 after); the smooth one is symmetric,
    ramp(x) + ramp(1 - x) = 1, and its slope is at most 3/2 (6 x (1 - x) at x = 1/2)."""
    xs = np.linspace(-0.5, 1.5, 401)
    for x in xs:
        c = min(1.0, max(0.0, x))
        assert fk.ramp(x, False) == c
        assert abs(fk.ramp(x, True) - (3 * c * c - 2 * c**3)) < 1e-15
        assert abs(fk.ramp(x, True) + fk.ramp(1.0 - x, True) - 1.0) < 1e-15
    smooth = np.array([fk.ramp(x, True) for x in xs])
    assert np.max(np.diff(smooth) / np.diff(xs)) <= 1.5 + 1e-12
    assert smooth[0] == 0.0 and smooth[-1] == 1.0


def _par(t_ramp: float, smooth: bool = True, from_plan: bool = True) -> np.ndarray:
    """Scalars for force_pre with no feedback (the wrench is the weight, no moments) and the hexabot's legs."""
    from hexabot_sim.kinematics.leg import LegGeometry

    g = LegGeometry()
    par = np.zeros(fk.NPAR)
    par[fk.DT], par[fk.WEIGHT] = DT, W
    par[[fk.T_IN, fk.T_OUT, fk.S_IN, fk.S_OUT, fk.W_MIN]] = t_ramp, t_ramp, 0.01, 0.01, 0.01
    par[[fk.L1, fk.L2, fk.L3]] = g.l1, g.l2, g.l3
    par[fk.FILTER], par[fk.RETURN_TIME], par[fk.SOFT] = 0.05, 0.05, 0.01
    par[fk.TOUCH_THRESHOLD], par[fk.EARLY_AFTER] = 0.3, 0.06
    par[fk.SMOOTH], par[fk.FROM_PLAN] = float(smooth), float(from_plan)
    return par


def _geo() -> np.ndarray:
    from hexabot_sim.robots.hexabot.walk import HexabotParams

    layout = HexabotParams().ROBOT.layout
    geo = np.zeros((6, 5))
    geo[:, fk.COS], geo[:, fk.SIN] = np.cos(layout.yaws), np.sin(layout.yaws)
    hips = layout.hip_positions()
    geo[:, fk.HIP_X], geo[:, fk.HIP_Y] = hips[:, 0], hips[:, 1]
    geo[:, fk.TOUCH_ADR] = np.arange(6)  # sensordata[i]: leg i's touch sensor
    return geo


def test_an_overlapping_tripod_hand_over_shares_the_weight_smoothly():
    """Tripod A (lf, lr, rm) down and lifting at step k_lift, tripod B (lm, rf, rr) landing at k_td with the overlap
    T = (k_lift - k_td + 2) dt equal to both ramps: at every step each foot's weight is the closed form
    max(least, smoothstep(time down / T)) for B and max(least, smoothstep(time to lift-off / T)) for A, a pair's
    weights sum to 1 while both are above the least, the forces sum to the commanded total (the weight), and no
    foot's force moves by more than 2 % of W in a step, from its touchdown to its lift-off."""
    t_ramp = 0.1
    k_td, steps = 50, round(t_ramp / DT)
    k_lift = k_td + steps - 2  # A's last step down: since_B + until_A = T at every step of the overlap
    par, geo = _par(t_ramp), _geo()
    state, body = np.zeros((6, fk.NSTATE)), np.zeros(fk.NBODY)
    qpos = np.zeros(25)
    qpos[7:] = np.tile([0.0, 0.5, 1.2], 6)
    a, b = np.array([0, 2, 4]), np.array([1, 3, 5])
    state[a, fk.SINCE], state[a, fk.S] = 1.0, 1.0  # A has been down for a second
    extra, row, touch = np.zeros(18), np.zeros(18), np.zeros(6)
    before = np.zeros(6)
    for k in range(k_lift + 20):
        down = np.zeros(6, dtype=np.bool_)
        down[a] = k <= k_lift
        down[b] = k >= k_td
        until = np.full(6, 1e9)
        until[a] = (k_lift - k + 1) * DT  # the time from this step to A's planned lift-off
        fk.force_pre(par, geo, state, body, qpos, np.zeros(18), touch, row, down, until, extra)
        w = state[:, fk.W]
        for i in a:
            expect = max(0.01, fk.ramp((k_lift - k + 1) * DT / t_ramp, True)) if k <= k_lift else 0.0
            assert abs(w[i] - expect) < 1e-12
        for i in b:
            expect = max(0.01, fk.ramp((k - k_td + 1) * DT / t_ramp, True)) if k >= k_td else 0.0
            assert abs(w[i] - expect) < 1e-12
        if k_td <= k <= k_lift and min(w[a[0]], w[b[0]]) > 0.01:
            assert abs(w[a[0]] + w[b[0]] - 1.0) < 1e-12
        f = state[:, fk.FORCE]
        assert np.all(f >= 0.0)
        assert abs(f.sum() - body[fk.WRENCH]) < 1e-9 * W and abs(body[fk.WRENCH] - W) < 1e-12
        if k > 0:
            assert np.max(np.abs(f - before)) < 0.02 * W, k  # continuous, touchdown and lift-off included
        before = f.copy()
    assert math.isclose(float(state[b, fk.FORCE].sum()), W, rel_tol=1e-9)  # B carries all after the overlap


def test_an_early_touch_waits_at_the_least_weight_until_its_planned_touchdown():
    """A swing foot whose touch sensor fires 60 ms after it was last down is down (force mode), but with
    from_plan its weight stays at the least until the plan has it down; without, it ramps from the touch."""
    for from_plan in (True, False):
        par, geo = _par(0.05, from_plan=from_plan), _geo()
        state, body = np.zeros((6, fk.NSTATE)), np.zeros(fk.NBODY)
        qpos = np.zeros(25)
        qpos[7:] = np.tile([0.0, 0.5, 1.2], 6)
        touch = np.zeros(6)
        out = np.zeros(18)
        weights = []
        for k in range(100):
            down = np.ones(6, dtype=np.bool_)
            down[0] = k < 10 or k >= 80  # leg 0 swings from step 10, touches at 60, planned down at 80
            touch[0] = 0.0 if 10 <= k < 60 else 1.0
            fk.force_pre(par, geo, state, body, qpos, np.zeros(18), touch, out, down, np.full(6, 1e9), out)
            weights.append(state[0, fk.W])
        during = np.array(weights[60:80])
        if from_plan:
            np.testing.assert_allclose(during, 0.01)
            assert abs(weights[80] - max(0.01, fk.ramp(DT / 0.05, True))) < 1e-12
        else:
            assert during[-1] > 0.5


def test_a_foot_still_on_the_ground_after_its_lift_off_is_not_an_early_touch():
    """A slow lift-off (a 1.5 s swing) leaves the foot on the pad, its sensor firing, for longer than early_after:
    that is not a landing, so the leg stays in position mode (no force, not down) however long it lasts; once the
    sensor has been quiet for early_after, a touch is an early touchdown (down, force mode). Before this was so,
    a period-3 tripod walk with load_sharing=force kept two of its swing feet pushing on the floor."""
    par, geo = _par(0.05), _geo()
    state, body = np.zeros((6, fk.NSTATE)), np.zeros(fk.NBODY)
    qpos = np.zeros(25)
    qpos[7:] = np.tile([0.0, 0.5, 1.2], 6)
    touch, out = np.zeros(6), np.zeros(18)
    quiet = round(0.06 / DT)
    for k in range(300):
        down = np.ones(6, dtype=np.bool_)
        down[0] = k < 10  # leg 0 lifts at step 10 and is not planned down again
        touch[0] = 1.0 if k < 150 or k >= 150 + quiet + 1 else 0.0  # on the pad 280 ms after lift-off, then clear
        fk.force_pre(par, geo, state, body, qpos, np.zeros(18), touch, out, down, np.full(6, 1e9), out)
        if 10 <= k < 150 + quiet + 1:
            assert state[0, fk.EARLY] == 0.0 and state[0, fk.FORCE] == 0.0, k
    assert state[0, fk.EARLY] == 1.0 and state[0, fk.FORCE] > 0.0


def test_a_swing_targets_the_landing_lift_above_the_plan():
    """In swing the target's height offset goes from where the stance left it to `landing_lift` above the plan as
    h + (dz0 - h) (1 - dt / return_time)^k after k steps, and the feed correction is task_gain dz + its rate."""
    par, geo = _par(0.05), _geo()
    h, rt, dz0, gain = 0.0004, 0.05, -0.002, 30.0
    par[fk.LIFT], par[fk.RETURN_TIME], par[fk.TASK_GAIN] = h, rt, gain
    state, body = np.zeros((6, fk.NSTATE)), np.zeros(fk.NBODY)
    state[:, fk.DZ] = dz0
    qpos = np.zeros(25)
    qpos[7:] = np.tile([0.0, 0.5, 1.2], 6)
    extra, before = np.zeros(18), dz0
    down = np.ones(6, dtype=np.bool_)
    down[0] = False
    for k in range(1, 60):
        fk.force_pre(par, geo, state, body, qpos, np.zeros(18), np.zeros(6), np.zeros(18), down, np.full(6, 1e9), extra)
        expect = h + (dz0 - h) * (1.0 - DT / rt) ** k
        assert abs(state[0, fk.DZ] - expect) < 1e-15
        assert abs(extra[2] - (gain * expect + (expect - before) / DT)) < 1e-9
        before = expect


def test_the_force_loop_adds_its_error_to_the_command():
    """force_post with force_gain k and the touch sensor reading t pushes as the open loop (gain 0) would with the
    command f + k (f - t)."""
    par = _par(0.05)
    qpos = np.zeros(25)
    qpos[7:] = np.tile([0.1, 0.5, 1.2], 6)
    q_cmd, dq, kp = qpos[7:].copy() + 0.01, np.full(18, 0.2), np.full(18, 3.0)
    state = np.zeros((6, fk.NSTATE))
    state[:, fk.S], state[:, fk.FORCE], state[:, fk.TOUCH] = 1.0, 3.0, np.linspace(1.0, 4.0, 6)
    closed, opened = np.zeros(36), np.zeros(36)
    par[fk.K_F] = 1.5
    fk.force_post(par, state.copy(), qpos, np.zeros(18), q_cmd.copy(), dq.copy(), kp, closed)
    par[fk.K_F] = 0.0
    open_state = state.copy()
    open_state[:, fk.FORCE] = 3.0 + 1.5 * (3.0 - state[:, fk.TOUCH])
    fk.force_post(par, open_state, qpos, np.zeros(18), q_cmd.copy(), dq.copy(), kp, opened)
    np.testing.assert_allclose(closed, opened, rtol=1e-12, atol=1e-12)


def test_a_duty_above_the_gaits_own_selects_the_overlap_settings():
    """for_overlap: 10 ms or less of overlap is the defaults; more ramps over it, smooth, from the plan, with the
    force loop, the landing lift and a larger least weight; the walk's scene passes (duty - the gait's own) x
    period."""
    assert for_overlap(0.0) == ForceSettings() and for_overlap(0.01) == ForceSettings()
    s = for_overlap(0.1)
    assert (s.ramp_in, s.ramp_out, s.smooth, s.from_plan, s.force_gain) == (0.1, 0.1, True, True, 1.0)
    assert (s.least_weight, s.landing_lift) == (0.05, 0.0004)
    from hexabot_sim.result import at_home
    from hexabot_sim.robots.hexabot.walk import HexabotParams
    from hexabot_sim.walking.scene import build_xml, make_controller

    for gait, duty, overlap in (("tripod", 0.6, 0.1), ("ripple", 0.75, 0.75 - 2 / 3), ("tripod", 0.0, 0.0)):
        p = HexabotParams(load_sharing="force", feet="pad", swing="quintic", gait=gait, duty=duty, vx=0.05)
        model, data = at_home(build_xml(p))
        settings = make_controller(p, model, data).force.settings
        assert dataclasses.astuple(settings) == pytest.approx(dataclasses.astuple(for_overlap(overlap)), rel=1e-12)


def test_the_filter_and_ramps_scale_with_the_period():
    """for_walk: the height filter at 5 % of the period, at least 50 ms, and the weights' ramps at 1 % of it, at
    least 10 ms (the settings' defaults, also at the default 1 s and the quadbot trot's 0.3 s); an overlap longer
    than the ramp takes for_overlap's settings (ramps over the whole overlap) with the scaled filter; the walk's
    scene passes its period and overlap."""
    assert for_walk(1.0, 0.0) == ForceSettings() and for_walk(0.3, 0.0) == ForceSettings()
    three = for_walk(3.0, 0.0)
    assert three == dataclasses.replace(ForceSettings(), filter_time=three.filter_time, ramp_in=0.03, ramp_out=0.03)
    assert abs(three.filter_time - 0.15) < 1e-12
    assert for_walk(3.0, 0.02) == three  # an overlap within the ramp: the ramp
    assert for_walk(3.0, 0.3) == dataclasses.replace(for_overlap(0.3), filter_time=three.filter_time)
    assert for_walk(1.0, 0.1) == for_overlap(0.1)
    from hexabot_sim.result import at_home
    from hexabot_sim.robots.hexabot.walk import HexabotParams
    from hexabot_sim.walking.scene import build_xml, make_controller

    for period, duty in ((3.0, 0.0), (2.0, 0.6)):
        p = HexabotParams(load_sharing="force", feet="pad", swing="quintic", gait="tripod", duty=duty, period=period,
                          vx=0.05)  # fmt: skip
        model, data = at_home(build_xml(p))
        settings = make_controller(p, model, data).force.settings
        assert settings == for_walk(period, (max(duty, 0.5) - 0.5) * period)
        assert abs(settings.filter_time - 0.05 * period) < 1e-12
