"""The hexabot and the quadbot are legged-robot files in the package (robots/<r>/<r>.toml): read by
kinematics/legged_file.py into exactly the layouts they had as Python (values written down from the Python
of before), shipped in the package, and a copy of the hexabot's file walks exactly as the built-in hexabot."""

from __future__ import annotations

import dataclasses
import shutil
from pathlib import Path

import numpy as np

import hexabot_sim as hs
from hexabot_sim.kinematics import leg as leg_kin
from hexabot_sim.kinematics import legged
from hexabot_sim.robots.hexabot import model as hx
from hexabot_sim.robots.quadbot import model as qb

# Every field of the layouts as hexabot_sim/robots/{hexabot,quadbot}/model.py defined them in Python (main at
# 3c859bf), before they became files.
HEXABOT = {
    "legs": ("lf", "lm", "lr", "rf", "rm", "rr"),
    "hips": ((0.12, 0.06), (0.0, 0.08), (-0.12, 0.06), (0.12, -0.06), (0.0, -0.08), (-0.12, -0.06)),
    "yaws_deg": (45.0, 90.0, 135.0, -45.0, -90.0, -135.0),
    "geometry": leg_kin.LegGeometry(l1=0.05, l2=0.1, l3=0.1),
    "plate": (0.15, 0.08, 0.015),
    "body_mass": 1.0,
    "link_masses": (0.03, 0.06, 0.04),
    "foot_radius": 0.008,
    "neutral_reach": 0.13,
    "stand_height": 0.09,
}
QUADBOT = {
    **HEXABOT,
    "legs": ("lf", "lr", "rf", "rr"),
    "hips": ((0.1, 0.06), (-0.1, 0.06), (0.1, -0.06), (-0.1, -0.06)),
    "yaws_deg": (45.0, 135.0, -45.0, -135.0),
    "plate": (0.13, 0.08, 0.015),
    "stand_height": 0.07,
}


def _fields(layout: legged.Layout) -> dict:
    return {f.name: getattr(layout, f.name) for f in dataclasses.fields(layout)}


def test_the_files_give_exactly_the_layouts_of_before() -> None:
    for module, expected, stance_legs in ((hx, HEXABOT, 3), (qb, QUADBOT, 2)):
        robot = module.ROBOT
        assert Path(robot.source).name == f"{module.MODEL}.toml"
        assert Path(robot.source).parent == Path(module.__file__).parent  # a robot is one folder
        assert type(robot.layout) is legged.Layout
        assert _fields(robot.layout) == expected  # == on floats: bit for bit
        assert robot.layout == legged.Layout(**expected)
        assert robot.name == module.MODEL and robot.torque_limit == 1.5 and robot.stance_legs == stance_legs
        assert module.STANCE_LEGS == stance_legs
    assert hx.DEFAULT_LAYOUT is hx.ROBOT.layout and qb.LAYOUT is qb.ROBOT.layout
    assert hx.LEGS == HEXABOT["legs"]


def test_a_copy_of_the_hexabots_file_walks_exactly_as_the_hexabot(tmp_path: Path) -> None:
    copy = tmp_path / "my_hexabot.toml"
    shutil.copyfile(hx.ROBOT.source, copy)
    default = hs.run("hexabot-walk", duration=1.6)
    mine = hs.run("hexabot-walk", robot=str(copy), duration=1.6)
    assert mine.raw.model.nq == default.raw.model.nq
    assert list(mine.raw.columns) == list(default.raw.columns)
    for name, values in default.raw.columns.items():
        np.testing.assert_array_equal(mine.raw.columns[name], values, err_msg=name)  # bit for bit
