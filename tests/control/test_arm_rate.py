"""The arm's resolved-rate step: the pseudo-inverse far from singularities, DLS at one, speed and range limits."""

import math

import numpy as np
import pytest

from hexabot_sim.control.arm_rate import ArmRateController, ArmRateGains, rotation_error
from hexabot_sim.kinematics import robots
from hexabot_sim.kinematics.chain import Joint, SerialChain
from hexabot_sim.kinematics.numeric_ik import pose_and_jacobian

ELBOW = robots.get("elbow").chain()


def gains(**kw):
    base = dict(task_gain=10.0, sigma_threshold=0.01, max_damping=0.01, max_speed=np.full(3, 100.0),
                max_acceleration=np.full(3, 1e6))  # fmt: skip
    return ArmRateGains(**(base | kw))


def controller(q, g=None, lower=-np.inf, upper=np.inf):
    return ArmRateController(pose_and_jacobian(ELBOW), g or gains(), np.array(q), np.full(3, lower),
                             np.full(3, upper), orientation=False)  # fmt: skip


def test_far_from_singularities_the_step_is_the_pseudo_inverse():
    q = np.array([0.3, 0.4, 1.1])
    c = controller(q)
    p = ELBOW.fk(q)[:3, 3]
    target, v = p + np.array([0.01, -0.02, 0.005]), np.array([0.05, 0.0, -0.02])
    _, dq = c.update(q, target, v, None, 1e-3)
    expected = np.linalg.pinv(ELBOW.jacobian(q)[:3]) @ (v + 10.0 * (target - p))
    assert np.allclose(dq, expected, atol=1e-12)


def test_at_an_exact_singularity_the_step_is_finite_and_speed_limited():
    q = np.array([0.3, 0.4, 0.0])  # elbow stretched: sigma_min = 0
    c = controller(q, gains(max_speed=np.full(3, 2.0)))
    far = ELBOW.fk(q)[:3, 3] * 2  # out of reach, along the stretched arm
    for _ in range(50):
        _, dq = c.update(q, far, np.zeros(3), None, 1e-3)
        assert np.isfinite(dq).all() and np.abs(dq).max() <= 2.0 + 1e-12
    assert c.sigma_min < 1e-12


def test_a_range_end_brakes_and_holds_and_counts():
    q = np.array([0.3, 0.4, 1.0])
    c = controller(q, gains(max_acceleration=np.full(3, 20.0)), lower=-1.2, upper=1.2)
    target = ELBOW.fk(np.array([0.3, 0.4, 2.5]))[:3, 3]  # q3 = 2.5 rad: beyond the 1.2 rad end
    hits = []
    for _ in range(2000):
        q_cmd, _ = c.update(c.q_cmd, target, np.zeros(3), None, 1e-3)
        assert np.all(q_cmd <= 1.2) and np.all(q_cmd >= -1.2)
        hits.append(bool(c.clipped.any()))
    assert any(hits) and hits[-1] and np.max(c.q_cmd) == pytest.approx(1.2, abs=1e-6)


@pytest.mark.parametrize("angle", [1e-9, 0.3, 2.0, math.pi - 1e-6])
def test_rotation_error_is_axis_times_angle(angle):
    rng = np.random.default_rng(1)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    turn = np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k  # Rodrigues
    rot = ELBOW.fk(np.array([0.1, 0.2, 0.3]))[:3, :3]
    assert np.allclose(rotation_error(rot, turn @ rot), angle * axis, atol=1e-9)


def test_a_joint_at_its_range_end_is_held_and_the_others_track():
    """A redundant arm (7 joints, position task) with joint 4 at its upper end, asked to move the tool the way joint 4
    alone would: the step holds joint 4 and the other six follow the moving target (kinematically, q = q_cmd)."""
    rows = [(0.36, -90), (0.0, 90), (0.42, 90), (0.0, -90), (0.4, -90), (0.0, 90), (0.126, 0)]
    joints = tuple(Joint(f"q{i}", "revolute", 0.0, d, 0.0, math.radians(alpha), -2.0, 2.0)
                   for i, (d, alpha) in enumerate(rows))  # fmt: skip
    chain = SerialChain("seven", joints)
    q0 = np.array([0.3, 0.8, -0.4, 2.0, 0.5, 0.9, 0.1])  # q4 at its 2 rad end
    velocity = chain.jacobian(q0)[:3, 3]
    velocity *= 0.05 / np.linalg.norm(velocity)  # [m/s] the way joint 4 alone would move the tool
    g = ArmRateGains(10.0, 0.01, 0.01, np.full(7, 3.0), np.full(7, 50.0))
    c = ArmRateController(pose_and_jacobian(chain), g, q0, np.full(7, -2.0), np.full(7, 2.0), orientation=False)
    start, dt = chain.fk(q0)[:3, 3], 1e-3
    for k in range(500):
        c.update(c.q_cmd, start + velocity * k * dt, velocity, None, dt)
        assert c.q_cmd[3] == 2.0 and c.clipped[3]
    # Within 3.6 µm all along (measured; without the clamping the tool falls 24 mm behind: joint 4 takes the motion).
    assert np.linalg.norm(chain.fk(c.q_cmd)[:3, 3] - (start + velocity * 0.5)) < 1e-5
