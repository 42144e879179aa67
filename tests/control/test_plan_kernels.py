"""The compiled gait plan (hexabot_sim/control/plan_kernels.py) against closed-form kinematics and finite differences.

A stance foot's target is ground-fixed: composed with the body's pose, which the commanded twist moves in closed
form, its world position stays put while the body walks, turns and ramps up, chunk after chunk and across changes
of command. A target's position and velocity are continuous across chunk boundaries and gait switches. The kernels
are one source: with numba's JIT disabled the same source, run as plain Python, plans the same targets.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys

import numpy as np
import pytest

from hexabot_sim.control.gait import GAITS_BY_LEGS, Command, GaitPlanner
from hexabot_sim.robots.hexabot.model import DEFAULT_LAYOUT
from hexabot_sim.robots.quadbot.model import LAYOUT as QUAD_LAYOUT

DT = 0.002
SETTLE, RAMP = 0.5, 1.0  # [s] the gait clock's start; the ramp's length from it


def ramp(t):
    """Fraction of the command in force: 0 up to SETTLE, then linear to 1 over RAMP (as the walking controller's)."""
    return np.clip((np.asarray(t, dtype=float) - SETTLE) / RAMP, 0.0, 1.0)


def ramp_integral(t: float) -> float:
    """The integral of ramp from 0 to t [s], in closed form."""
    if t <= SETTLE:
        return 0.0
    if t <= SETTLE + RAMP:
        return (t - SETTLE) ** 2 / (2 * RAMP)
    return RAMP / 2 + (t - SETTLE - RAMP)


def body_motion(cmd: Command, tau: float) -> tuple[float, float, float]:
    """(dx, dy, dyaw) of a body moving at the body-frame twist cmd for tau [s], in its starting frame (closed form)."""
    w = cmd.yaw_rate
    if w == 0.0:
        return cmd.vx * tau, cmd.vy * tau, 0.0
    s, c = math.sin(w * tau) / w, (1.0 - math.cos(w * tau)) / w
    return s * cmd.vx - c * cmd.vy, c * cmd.vx + s * cmd.vy, w * tau


def _walk(layout, gait, commands, seed, switch_to=None, scale=ramp):
    """Plans 5 s in chunks of random length, each with the next command of `commands` (cycled), switching gait at
    2.5 s; returns the row times (n,), targets (n, legs, 3), stance flags (n, legs), each chunk's row 0, the body's
    world pose (x, y, yaw) (n, 3) under the commanded twists scaled by `scale`, and the planner."""
    rng = np.random.default_rng(seed)
    planner = GaitPlanner(gait, 1.0, 0.03, layout.neutral_feet_body(), DT, start_time=SETTLE)
    times, rows, flags, starts, poses = [np.zeros(1)], [planner.pos[None].copy()], [], [], [np.zeros((1, 3))]
    pose = np.zeros(3)
    k = 0
    while planner.time < 5.0 - 1e-9:
        if switch_to is not None and planner.time >= 2.5 and not planner.switches:
            planner.switch(switch_to)
        cmd = commands[k % len(commands)]
        n = int(rng.integers(1, 120))
        t0 = planner.time
        out = planner.plan(cmd, n, scale)
        t = t0 + DT * np.arange(1, n + 1)
        starts.append(sum(len(r) for r in times) - 1)  # the row at t0: the last of the chunk before
        # The body's pose at each row: the chunk's twist from its start, in warped time (integral of the ramp).
        chunk = np.empty((n, 3))
        for i, ti in enumerate(t):
            tau = ramp_integral(ti) - ramp_integral(t0) if scale is not None else ti - t0
            dx, dy, dyaw = body_motion(cmd, tau)
            c, s = math.cos(pose[2]), math.sin(pose[2])
            chunk[i] = pose[0] + c * dx - s * dy, pose[1] + s * dx + c * dy, pose[2] + dyaw
        pose = chunk[-1].copy()
        times.append(t)
        rows.append(out[1:])
        poses.append(chunk)
        k += 1
    t = np.concatenate(times)
    flags = planner.in_stance(t)
    return t, np.concatenate(rows), flags, starts, np.concatenate(poses), planner


CASES = [
    (DEFAULT_LAYOUT, "tripod", [Command(0.1, 0.0, 0.0)]),
    (DEFAULT_LAYOUT, "ripple", [Command(0.05, -0.04, 0.3), Command(0.06, -0.03, 0.25)]),
    (DEFAULT_LAYOUT, "wave", [Command(-0.03, 0.02, -0.4), Command(0.0, 0.0, 1e-19)]),
    (QUAD_LAYOUT, "crawl", [Command(0.05, 0.01, 0.2), Command(0.04, 0.0, -0.1)]),
    (QUAD_LAYOUT, "trot", [Command(0.08, 0.0, -0.3)]),
]


@pytest.mark.parametrize(("layout", "gait", "commands"), CASES)
def test_a_stance_foot_stays_fixed_in_the_world_while_the_body_moves_by_the_twist(layout, gait, commands):
    gait = GAITS_BY_LEGS[layout.n_legs][gait]
    t, rows, stance, _, pose, _ = _walk(layout, gait, commands, seed=len(commands))
    c, s = np.cos(pose[:, 2])[:, None], np.sin(pose[:, 2])[:, None]  # (n, 1)
    world_x = pose[:, :1] + c * rows[..., 0] - s * rows[..., 1]  # (n, legs)
    world_y = pose[:, 1:2] + s * rows[..., 0] + c * rows[..., 1]
    checked = 0
    for leg in range(layout.n_legs):
        edges = np.flatnonzero(np.diff(stance[:, leg].astype(int))) + 1
        for a, b in zip(np.r_[0, edges], np.r_[edges, len(t)], strict=True):
            if not stance[a, leg] or t[a] < SETTLE:
                continue
            # From its touchdown row on, the foot's world position is the one it landed at.
            spread = max(np.ptp(world_x[a:b, leg]), np.ptp(world_y[a:b, leg]))
            assert spread < 1e-12, (leg, t[a], t[b - 1], spread)
            checked += b - a
    assert checked > 0.3 * layout.n_legs * np.count_nonzero(t > SETTLE + RAMP)
    assert abs(pose[-1, 0]) + abs(pose[-1, 2]) > 0.05  # the body did move


@pytest.mark.parametrize(
    ("layout", "gait", "new"), [(DEFAULT_LAYOUT, "tripod", "wave"), (QUAD_LAYOUT, "trot", "crawl")]
)
def test_targets_are_continuous_in_position_and_velocity_across_chunks_and_a_gait_switch(layout, gait, new):
    gaits = GAITS_BY_LEGS[layout.n_legs]
    cmd = Command(0.06, 0.02, 0.2)
    t, rows, stance, starts, _, planner = _walk(layout, gaits[gait], [cmd], seed=3, switch_to=gaits[new])
    assert [g for _, g in planner.switches] == [new]
    velocity = np.diff(rows, axis=0) / DT  # (n - 1, legs, 3) by finite differences: v[k] over rows k, k + 1
    assert np.abs(velocity).max() < 2.0  # [m/s]: no jump in position (the wave's first swings catch up, ~1.3 m/s)
    # A jump J in velocity at row b shows in the second differences of v next to it as ~J; a smooth target's are
    # its jerk times dt^2, at most that of the shortest swing's lift h sin^2(pi s) (4 pi^3 h / T^3) and Hermite arc
    # (~12 stride / T^3): 3e-3 m/s for the wave's 1/6 s swings, 4e-4 for the crawl's 1/4 s. Lift-offs and
    # touchdowns change the acceleration (a dt ~ 0.04 m/s): boundaries within 3 rows of one are left out.
    shortest = min((1 - g.duty) * planner.period for g in (gaits[gait], gaits[new]))
    smooth = (4 * math.pi**3 * planner.step_height + 12 * 0.1) / shortest**3 * DT**2
    curvature = np.abs(np.diff(velocity, 2, axis=0))  # (n - 3, legs, 3): row k is v[k + 2] - 2 v[k + 1] + v[k]
    boundaries = np.array(starts[1:])  # each chunk's row 0 (the last row of the one before) but the first's
    switch_row = int(np.argmin(np.abs(t - planner.switches[0][0])))
    assert switch_row in boundaries
    checked = 0
    for leg in range(layout.n_legs):
        events = np.flatnonzero(np.diff(stance[:, leg].astype(int))) + 1
        for b in boundaries[(boundaries > 3) & (boundaries < len(t) - 4)]:
            if events.size and np.abs(events - b).min() <= 3:
                continue
            assert curvature[b - 2 : b, leg].max() < smooth, (leg, t[b])  # [m/s]
            checked += 1
    assert checked > 0.5 * layout.n_legs * len(boundaries)
    assert smooth < 5e-3  # a jump of 0.01 m/s at a boundary would fail
    # A swing's fraction grows at 1 / its swing time from 0 (finite differences), stance at 0.
    _, swing_s = planner.flags(t)
    swinging = ~stance[1:] & ~stance[:-1]
    rate = np.diff(swing_s, axis=0)[swinging] / DT
    swing_times = {(1 - g.duty) * planner.period for g in (gaits[gait], gaits[new])}
    assert np.all(np.min([np.abs(rate - 1 / s) for s in swing_times], axis=0) < 1e-9)
    assert np.all(swing_s[stance] == 0.0)


def test_the_plan_source_runs_as_plain_python_with_the_same_targets(tmp_path):
    """NUMBA_DISABLE_JIT=1 runs the kernels' source as Python: one source, compiled or not, plans the same chunk."""
    code = (
        "import numpy as np\n"
        "from hexabot_sim.control.gait import GAITS, Command, GaitPlanner\n"
        "from hexabot_sim.robots.hexabot.model import DEFAULT_LAYOUT\n"
        "p = GaitPlanner(GAITS['ripple'], 1.0, 0.03, DEFAULT_LAYOUT.neutral_feet_body(), 0.002, start_time=0.5)\n"
        "scale = lambda t: np.clip((np.asarray(t) - 0.5), 0.0, 1.0)\n"
        "rows = [p.plan(Command(0.05, -0.02, 0.3), 200, scale) for _ in range(5)]\n"
        "np.save(__import__('sys').argv[1], np.concatenate(rows))\n"
    )
    out = {}
    for jit in ("0", "1"):
        path = tmp_path / f"plan_{jit}.npy"
        env = {**os.environ, "NUMBA_DISABLE_JIT": jit}
        command = [sys.executable, "-c", code, str(path)]
        done = subprocess.run(command, capture_output=True, text=True, timeout=300, env=env)
        assert done.returncode == 0, done.stderr
        out[jit] = np.load(path)
    np.testing.assert_allclose(out["1"], out["0"], rtol=0, atol=1e-15)
    assert np.ptp(out["0"][:, :, 0]) > 0.02  # it walked


@pytest.mark.parametrize("n_legs", sorted(GAITS_BY_LEGS))
def test_a_hand_over_never_has_fewer_feet_down_than_the_gait_stands_on(n_legs):
    """At a hand-over the lifting legs' phase (their offset added to the clock's) could round up to the duty while
    the landing legs' rounded down below 1: the tripod at period 7.9135634 s had no foot down 1 fs before its first
    hand-over, the trot the same at 29 of 60 random periods. Every gait, at its lift-off and touchdown times and a
    few ulps either side, at random periods: at least the feet the gait stands on between its events."""
    rng = np.random.default_rng(7)
    for name, gait in GAITS_BY_LEGS[n_legs].items():
        events = sorted({o % 1.0 for o in gait.offsets} | {(o + gait.duty) % 1.0 for o in gait.offsets})
        least = n_legs - max(sum(((p - o) % 1.0) >= gait.duty for o in gait.offsets) for p in np.linspace(0, 1, 997))
        for period in rng.uniform(0.2, 10.0, 40):
            planner = GaitPlanner(gait, period, 0.03, np.zeros((n_legs, 3)), 0.002, start_time=0.5)
            t = (0.5 + np.add.outer(np.arange(1, 200), events) * period).ravel()
            t = np.concatenate([t * (1.0 + e) for e in (-1e-13, -1e-15, -2.2e-16, 0.0, 2.2e-16, 1e-15, 1e-13)])
            down = planner.in_stance(t).sum(axis=1)
            assert down.min() >= least, (name, period, t[down.argmin()])
