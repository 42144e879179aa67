"""The stepping loop: recording, controller hook, divergence detection."""

import mujoco
import numpy as np
import pytest

from hexabot_sim import models
from hexabot_sim.budget import step_count
from hexabot_sim.errors import SimulationError
from hexabot_sim.simulate import simulate


@pytest.fixture
def pendulum():
    model = mujoco.MjModel.from_xml_path(str(models.model_path("pendulum")))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    return model, data


def test_records_initial_state_and_every_step(pendulum):
    model, data = pendulum
    traj = simulate(model, data, 250)
    assert traj.t.shape == (251,) and traj.qpos.shape == (251, 1) and traj.qvel.shape == (251, 1)
    assert traj.qpos[0, 0] == pytest.approx(np.pi / 2) and traj.t[0] == 0
    assert traj.t[-1] == pytest.approx(0.25) and traj.qpos[-1, 0] == data.qpos[0]


def test_controller_is_called_before_every_step(pendulum):
    model, data = pendulum
    calls = []
    simulate(model, data, 10, controller=lambda m, d: calls.append(d.time))
    assert calls == pytest.approx(np.arange(10) * model.opt.timestep)


def test_step_count_covers_the_duration():
    assert step_count(10.0, 0.001) == 10000
    assert step_count(1.0, 0.3) == 4
    assert step_count(1e-6, 1.0) == 1


def test_divergence_is_reported_with_time_not_recorded(pendulum):
    model, data = pendulum
    model.jnt_stiffness[0] = 1e7
    model.opt.timestep = 0.01
    with pytest.raises(SimulationError, match=r"diverged after t = 0\.01 s \(MuJoCo: Nan, Inf or huge value"):
        simulate(model, data, 1000)


def test_non_finite_control_is_caught(pendulum):
    model, data = pendulum

    def poison(m, d):
        if d.time > 0.05:
            d.qfrc_applied[0] = np.inf

    with pytest.raises(SimulationError, match=r"diverged after t = 0\.05"):
        simulate(model, data, 1000, controller=poison)
    # MuJoCo's own warning printer is restored afterwards.
    assert mujoco.get_mju_user_warning() is None
