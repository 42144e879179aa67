"""The MJCF and URDF exports of random robot files against the DH chain, in MuJoCo: FK and mj_jacSite to 1e-12."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest
from helpers import random_q, random_table, to_toml

from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics import robot_file, robots
from hexabot_sim.kinematics.chain import Joint, SerialChain
from hexabot_sim.kinematics.mjcf import to_mjcf
from hexabot_sim.kinematics.urdf import to_urdf

TOL = 1e-12


def pose_of(rotation: np.ndarray, position: np.ndarray) -> np.ndarray:
    t = np.eye(4)
    t[:3, :3] = rotation.reshape(3, 3)
    t[:3, 3] = position
    return t


@pytest.mark.parametrize("convention", ["standard", "modified"])
def test_exported_models_compile_and_match_the_dh_chain(convention):
    rng = np.random.default_rng(21 if convention == "standard" else 22)
    worst = {"mjcf fk": 0.0, "mjcf jac": 0.0, "urdf fk": 0.0}
    for n in range(1, 8):
        table = random_table(rng, n, convention, ("rad", "deg")[n % 2])
        spec = robot_file.parse(to_toml(table))
        chain = spec.chain()
        xml = mujoco.MjModel.from_xml_string(to_mjcf(chain))
        urdf = mujoco.MjModel.from_xml_string(to_urdf(chain))
        assert urdf.njnt == xml.njnt == n and [urdf.joint(i).name for i in range(n)] == [j.name for j in chain.joints]
        data_x, data_u = mujoco.MjData(xml), mujoco.MjData(urdf)
        site, tool = xml.site("tool").id, urdf.body("tool").id
        jacp, jacr = np.zeros((3, n)), np.zeros((3, n))
        for _ in range(10):
            q = random_q(table, rng)
            data_x.qpos[:] = q
            data_u.qpos[:] = q
            mujoco.mj_kinematics(xml, data_x)
            mujoco.mj_comPos(xml, data_x)
            mujoco.mj_kinematics(urdf, data_u)
            expected = chain.fk(q)
            mujoco.mj_jacSite(xml, data_x, jacp, jacr, site)
            worst["mjcf fk"] = max(
                worst["mjcf fk"], np.abs(pose_of(data_x.site_xmat[site], data_x.site_xpos[site]) - expected).max()
            )
            worst["mjcf jac"] = max(worst["mjcf jac"], np.abs(np.vstack([jacp, jacr]) - chain.jacobian(q)).max())
            worst["urdf fk"] = max(
                worst["urdf fk"], np.abs(pose_of(data_u.xmat[tool], data_u.xpos[tool]) - expected).max()
            )
    assert max(worst.values()) <= TOL, worst


def test_masses_of_a_file_are_the_models_masses():
    text = to_toml(random_table(np.random.default_rng(4), 3, "standard", "rad"))
    text = text.replace('name = "j2"', 'name = "j2"\nmass = 2.5', 1)
    spec = robot_file.parse(text)
    for xml in (to_mjcf(spec.chain(), masses=spec.masses), to_urdf(spec.chain(), masses=spec.masses)):
        model = mujoco.MjModel.from_xml_string(xml)
        body = model.body("link2").id
        assert model.body_mass[body] == pytest.approx(2.5, rel=1e-12)
    default = mujoco.MjModel.from_xml_string(to_mjcf(spec.chain()))
    assert default.body_mass[default.body("link2").id] != pytest.approx(2.5)


def test_urdf_joint_types_and_the_refusal_of_a_free_slide():
    text = to_urdf(robots.get("stanford").chain())  # d3 limited; the revolute joints have no range
    assert text.count('type="prismatic"') == 1 and text.count('type="continuous"') == 5 and text.count("<limit") == 1
    assert 'type="revolute"' in to_urdf(robots.get("leg").chain())  # limited hinges
    free = SerialChain("free", (Joint("s", "prismatic", a=0.1),))
    with pytest.raises(UsageError, match="joint 's' is prismatic without 'lower' and 'upper': URDF requires"):
        to_urdf(free)
    with pytest.raises(UsageError, match="joint 'tool_fixed': the URDF names its own fixed joints so"):
        to_urdf(SerialChain("clash", (Joint("tool_fixed", a=0.1),)))
