"""The viewer's live steering (walking/steering.py, control/commands.Steering): at a long gait period the keys' twist
changes slowly enough that the stance feet stay in their workspace, and each key is checked at the walk's duty."""

from __future__ import annotations

import numpy as np
import pytest

from hexabot_sim import api
from hexabot_sim.control.commands import STEERING_ACCELERATION, steering_acceleration
from hexabot_sim.errors import UsageError
from hexabot_sim.walking import steering, walk


def test_the_steering_rate_falls_with_the_square_of_a_long_period():
    assert steering_acceleration(0.5) == steering_acceleration(1.0) == STEERING_ACCELERATION
    assert steering_acceleration(3.0) == pytest.approx(STEERING_ACCELERATION / 9, rel=1e-12)
    live = walk.live(api.prepare("hexabot-force", {}).params)
    keys = live.keys.__self__  # the viewer's key handler: steering.KeySteering
    assert isinstance(keys, steering.KeySteering) and keys.steering.acceleration == steering_acceleration(3.0)


def test_keys_that_reverse_a_3_s_walk_neither_throw_nor_sink_its_body():
    """hexabot-force steered live (3 s period): from its 0.1 m/s forward start, ten presses of Down at t = 8 s ask
    for -0.1 m/s. The twist changed at 0.2 m/s^2 whatever the period: a rear stance foot ran out of its workspace
    at the first hand-over after the start (the body thrown 34 mm up), and by the end the robot had been off the
    ground for 418 ms in all and its height had swung over 157 mm."""
    live = walk.live(api.prepare("hexabot-force", {"duration": 20.0}).params)
    data = live.data
    z, airborne = [], 0
    while data.time < 20.0 - 1e-9:
        live.step()
        if abs(data.time - 8.0) < 1e-9:
            for _ in range(10):
                assert live.keys(steering.KEY_DOWN, False)
        if data.time > 1.0:
            z.append(data.qpos[2])
            airborne += data.ncon == 0
    z = np.array(z)
    assert airborne == 0
    assert z.max() - z.min() < 0.002, (z.min(), z.max())  # 0.4 mm measured
    assert data.qvel[0] < -0.05  # walking backward by the end


def test_the_keys_are_checked_at_the_duty_the_walk_walks():
    """The keys were checked at the gait's own duty: with `duty=0.8` the tripod took Up to 0.13 m/s, which a run at
    that duty refuses (the largest 0.0958), and the live walk was thrown 69 mm up (found by fuzzing). After a key
    changes the gait, the controller walks the new gait's own duty, and the keys are checked at it."""
    p = api.prepare("hexabot-force", {"duty": 0.8, "vx": 0.05}).params
    live = walk.live(p)
    keys = live.keys.__self__
    for _ in range(6):
        assert live.keys(steering.KEY_UP, False)
    assert keys.steering.target.vx == pytest.approx(0.09) and keys.note.startswith("refused: the legs cannot")
    with pytest.raises(UsageError, match="the legs cannot deliver"):
        api.prepare("hexabot-force", {"duty": 0.8, "vx": 0.11})
    assert live.keys(steering.KEY_KP_2, False) and keys.steering.gait == "ripple" and keys.duty == 0.0
