"""The walking hexabot's robot and parameters, apart from the walk itself: `hexabot-sim list` reads them
without MuJoCo (the scenario module is hexabot/walk.py)."""

from __future__ import annotations

import dataclasses
from typing import ClassVar

from hexabot_sim.robots.hexabot import model as hx
from hexabot_sim.walking.parameters import WalkingRobot, WalkParams
from hexabot_sim.walking.robot_choice import RobotChoice

HEXABOT = WalkingRobot(
    name="hexabot",
    layout=hx.DEFAULT_LAYOUT,
    scene="hexabot_scene",
    torque_limit=hx.ROBOT.torque_limit,  # [N m] the joints' actuatorfrcrange (hexabot.toml, models/hexabot.xml)
)
# The hexabot, or a legged-robot file with six legs (its gaits are for six).
ROBOTS = RobotChoice(HEXABOT, hx.MODEL, "the hexabot's scenarios")


@dataclasses.dataclass(frozen=True)
class HexabotParams(WalkParams):
    """Parameters of the walking-hexabot scenarios (body frame: x forward, y left, z up)."""

    ROBOTS: ClassVar[RobotChoice] = ROBOTS
    robot: str = ROBOTS.param("the hexabot, or your own six-legged robot (docs/robot-files.md)")
