"""numeric_ik.pose_and_jacobian (arm-track's control loop) against the chain's FK and its FK-derivative Jacobian."""

import numpy as np
import pytest

from hexabot_sim.kinematics import robots
from hexabot_sim.kinematics.chain import Joint, SerialChain
from hexabot_sim.kinematics.numeric_ik import batch_pose_and_jacobian, pose_and_jacobian


def random_chain(rng, convention):
    joints = []
    for i in range(rng.integers(1, 8)):
        kind = "prismatic" if rng.random() < 0.3 else "revolute"
        theta, alpha = rng.uniform(-np.pi, np.pi, 2)
        d, a = rng.uniform(-0.5, 0.5, 2)
        joints.append(Joint(f"j{i}", kind, theta, d, a, alpha, -1.0, 1.0))
    base, tool = np.eye(4), np.eye(4)
    base[:3, 3], tool[:3, 3] = rng.uniform(-1, 1, 3), rng.uniform(-0.2, 0.2, 3)
    c, s = np.cos(0.7), np.sin(0.7)
    tool[:3, :3] = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
    return SerialChain("random", tuple(joints), convention, base=base, tool=tool)


@pytest.mark.parametrize("convention", ["standard", "modified"])
def test_random_chains(convention):
    rng = np.random.default_rng(3)
    for _ in range(40):
        chain = random_chain(rng, convention)
        evaluate = pose_and_jacobian(chain)
        for q in rng.uniform(-1, 1, (5, chain.n)):
            pose, jac = evaluate(q)
            assert np.allclose(pose, chain.fk(q), atol=1e-13, rtol=0)
            assert np.allclose(jac, chain.jacobian_fk_derivative(q), atol=1e-12, rtol=0)
        poses, jacs = batch_pose_and_jacobian(chain, rng.uniform(-1, 1, (3, chain.n)))
        assert poses.shape == (3, 4, 4) and jacs.shape == (3, 6, chain.n)


@pytest.mark.parametrize("name", list(robots.ROBOTS))
def test_the_package_robots(name):
    chain = robots.get(name).chain()
    q = np.linspace(0.1, 0.7, chain.n)
    pose, jac = pose_and_jacobian(chain)(q)
    assert np.allclose(pose, chain.fk(q), atol=1e-13, rtol=0)
    assert np.allclose(jac, chain.jacobian(q), atol=1e-13, rtol=0)
