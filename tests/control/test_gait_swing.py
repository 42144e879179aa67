"""The swing arc: a quintic Hermite whose ends join the stance path in position, velocity and acceleration."""

from __future__ import annotations

import numpy as np
import pytest

from hexabot_sim.control.gait import GAITS, Command, GaitPlanner
from hexabot_sim.control.plan_kernels import quintic
from hexabot_sim.robots.hexabot.model import DEFAULT_LAYOUT


def test_quintic_basis_end_conditions_and_derivatives():
    """The weights of (p1 - p0, T v0, T v1, T^2 a0) take their ends' values, and d, dd are the derivatives of h
    (finite differences)."""
    u = np.linspace(0.0, 1.0, 20001)
    h, d, dd = (np.array(x) for x in quintic(u))  # (4, n)
    np.testing.assert_allclose(h[:, 0], 0.0, atol=1e-15)
    np.testing.assert_allclose(h[:, -1], [1, 0, 0, 0], atol=1e-12)
    np.testing.assert_allclose(d[:, 0], [0, 1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(d[:, -1], [0, 0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(dd[:, 0], [0, 0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(dd[:, -1], 0.0, atol=1e-12)
    step = u[1] - u[0]
    np.testing.assert_allclose(np.gradient(h, step, axis=1)[:, 1:-1], d[:, 1:-1], atol=1e-7)
    np.testing.assert_allclose(np.gradient(d, step, axis=1)[:, 1:-1], dd[:, 1:-1], atol=1e-6)


def test_swing_leaves_and_meets_the_stance_path_without_acceleration():
    """Walking straight, a stance target moves at -v in the body frame (no acceleration); the swing's horizontal
    acceleration is zero at lift-off and touchdown (a cubic's is its largest there, 6 stride / T^2), so near the
    ground a foot stays on its stance path to second order."""
    dt = 0.002
    planner = GaitPlanner(
        GAITS["tripod"], 1.0, 0.03, DEFAULT_LAYOUT.neutral_feet_body(), dt, start_time=0.0, profile="quintic"
    )
    rows = np.concatenate([planner.plan(Command(0.1), 500)] + [planner.plan(Command(0.1), 500)[1:] for _ in range(3)])
    stance = planner.in_stance(dt * np.arange(len(rows)))
    acc = np.diff(rows[..., :2], 2, axis=0) / dt**2  # (n - 2, legs, 2), at rows 1 .. n - 2
    peak = np.abs(acc).max()
    assert peak > 1.0  # [m/s^2] the swings accelerate (6 x 0.1 m / 0.5 s^2 / 1.6 for the quintic's 5.77)
    checked = 0
    for leg in range(6):
        edges = np.flatnonzero(stance[1:, leg] != stance[:-1, leg]) + 1  # first row of each new phase
        for k in edges[(edges > 2) & (edges < len(rows) - 2)]:
            near = np.abs(acc[k - 2 : k, leg]).max()  # rows k - 1 and k, the last of a phase and the first
            assert near < 0.05 * peak, (leg, k, near, peak)
            checked += 1
    assert checked >= 30


def test_the_quintic_swing_is_checked_with_its_own_peak_speed():
    """The quintic's swing peaks at 1.875x its mean speed (the cubic's 1.5x): the feasibility check plans the cycle
    with the walk's own profile, whichever was checked first (its answers are cached)."""
    import pytest

    from hexabot_sim import params
    from hexabot_sim.errors import UsageError
    from hexabot_sim.robots.hexabot.walk import HexabotParams

    params.resolve(HexabotParams, {}, {"gait": "ripple", "vx": 0.23})
    with pytest.raises(UsageError, match=r"the largest feasible in this direction is vx = 0\.21"):
        params.resolve(HexabotParams, {}, {"gait": "ripple", "vx": 0.23, "swing": "quintic"})
    params.resolve(HexabotParams, {}, {"gait": "ripple", "vx": 0.23})


@pytest.mark.parametrize("robot, gaits", [("hexabot", ("tripod", "ripple", "wave")), ("quadbot", ("crawl", "trot"))])
def test_the_feasibility_check_plans_steady_cycles(robot, gaits):
    """plan_steady (what the reach and joint-speed checks plan) returns two cycles of the steady walk: the second
    repeats the first, in every gait. A cycle that still held a start-up swing (a leg's first, from wherever its
    first stance from neutral left it) understated the ripple gait's reach: 0.215 m/s where 0.247 walks."""
    import importlib

    from hexabot_sim.walking.ground import plan_steady

    params_class = {"hexabot": "HexabotParams", "quadbot": "QuadbotParams"}[robot]
    module = importlib.import_module(f"hexabot_sim.robots.{robot}.parameters")
    for gait in gaits:
        p = getattr(module, params_class)(gait=gait, vx=0.05)
        feet, down, _ = plan_steady(p, Command(0.1, 0.02, 0.1), samples=120)
        assert feet.shape[0] == down.shape[0] == 2 * 120 + 1, gait
        np.testing.assert_allclose(feet[120:], feet[:121], atol=1e-9, err_msg=gait)
        assert (down[120:240] == down[:120]).all(), gait  # (the last row lies on an event: its flag rounds)
