"""The MJCF files: they compile, step cleanly, and hold the numbers their comments derive."""

import math

import mujoco
import numpy as np
import pytest

from hexabot_sim import models, params
from hexabot_sim.robots.pendulum import pendulum

MODEL_FILES = sorted(p.stem for p in models.models_dir().glob("*.xml"))


@pytest.mark.parametrize("name", MODEL_FILES)
def test_model_compiles_and_steps_cleanly(name):
    model = mujoco.MjModel.from_xml_path(str(models.model_path(name)))
    data = mujoco.MjData(model)
    rng = np.random.default_rng(0)
    for _ in range(500):
        data.ctrl[:] = rng.uniform(-1, 1, model.nu)
        data.qfrc_applied[:] = rng.normal(0, 0.01, model.nv)
        mujoco.mj_step(model, data)
    assert all(w.number == 0 for w in data.warning), name
    assert np.isfinite(data.qpos).all()


def test_pendulum_file_inertia_follows_from_mass_and_length():
    model = mujoco.MjModel.from_xml_path(str(models.model_path("pendulum")))
    link = model.body("link").id
    m, L, r = 0.1, 0.3, 0.01  # stated in the file's header
    assert model.body_mass[link] == pytest.approx(m)
    assert model.body_ipos[link] == pytest.approx([0, 0, -L / 2])
    i_perp = m * (3 * r**2 + L**2) / 12
    assert sorted(model.body_inertia[link]) == pytest.approx(sorted([i_perp, i_perp, m * r**2 / 2]))
    hinge = model.joint("hinge")
    assert model.dof_damping[hinge.dofadr[0]] == pytest.approx(0.01)
    assert model.qpos_spring[hinge.qposadr[0]] == pytest.approx(math.radians(30))
    assert model.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4
    assert model.key("home").qpos[0] == pytest.approx(math.pi / 2)


def test_theta_zero_hangs_down_and_positive_swings_to_plus_x():
    model = mujoco.MjModel.from_xml_path(str(models.model_path("pendulum_scene")))
    data = mujoco.MjData(model)
    for theta in (0.0, 0.3):
        data.qpos[0] = theta
        mujoco.mj_kinematics(model, data)
        tip = data.site("tip").xpos - data.site("pivot").xpos
        assert tip == pytest.approx([0.3 * math.sin(theta), 0, -0.3 * math.cos(theta)], abs=1e-12)


def test_overrides_are_written_at_full_precision_and_reload_identically():
    p = params.resolve(pendulum.PendulumParams, {}, {"mass": 1 / 3, "length": 0.7, "target_deg": 100 / 7})
    xml = pendulum.build_xml(p)
    model = mujoco.MjModel.from_xml_string(xml)
    again = mujoco.MjModel.from_xml_string(xml)
    link = model.body("link").id
    assert model.body_mass[link] == 1 / 3
    assert model.qpos_spring[0] == math.radians(100 / 7)
    for field in ("body_mass", "body_inertia", "body_ipos", "qpos_spring", "jnt_stiffness", "dof_damping", "cam_pos"):
        assert np.array_equal(getattr(model, field), getattr(again, field)), field


def test_scene_includes_are_inlined():
    root = models.load_tree("pendulum_scene")
    assert root.find(".//include") is None
    assert models.find(root, "joint", "hinge").get("name") == "hinge"


def test_an_install_without_its_models_says_so_in_one_line(tmp_path, monkeypatch, capsys):
    """A copy of the package without models/ (a broken install) once read "writing the run folder failed"."""
    from hexabot_sim.__main__ import main

    monkeypatch.setattr(models, "_CANDIDATES", (tmp_path / "_models", tmp_path / "models"))
    code = main(["run", "pendulum", "--set", "duration=0.5", "--no-plots", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 1 and len(err.strip().splitlines()) == 1, err
    assert "MJCF models are missing" in err and "reinstall" in err and "run folder" not in err, err
    assert not (tmp_path / "out").exists()
