"""The walking hexabot (report 000): six DH legs on a free body, tripod/ripple/wave gaits on contact physics."""

from __future__ import annotations

import dataclasses
from typing import ClassVar

from hexabot_sim.robots.hexabot import model as hx
from hexabot_sim.walking.figures import figures
from hexabot_sim.walking.parameters import WalkingRobot, WalkParams
from hexabot_sim.walking.walk import live, run

HEXABOT = WalkingRobot(
    name="hexabot",
    layout=hx.DEFAULT_LAYOUT,
    scene="hexabot_scene",
    torque_limit=1.5,  # [N m] the joints' actuatorfrcrange (models/hexabot.xml)
)


@dataclasses.dataclass(frozen=True)
class HexabotParams(WalkParams):
    """Parameters of the walking-hexabot scenarios (body frame: x forward, y left, z up)."""

    ROBOT: ClassVar[WalkingRobot] = HEXABOT


__all__ = ["HEXABOT", "HexabotParams", "figures", "live", "run"]  # the scenario contract (hexabot_sim.scenario)
