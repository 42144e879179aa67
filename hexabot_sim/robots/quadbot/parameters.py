"""The walking quadbot's robot and parameters, apart from the walk itself: `hexabot-sim list` reads them
without MuJoCo (the scenario module is quadbot/walk.py)."""

from __future__ import annotations

import dataclasses
from typing import ClassVar

from hexabot_sim.control.gait import gaits_for
from hexabot_sim.params import param
from hexabot_sim.robots.quadbot.model import LAYOUT, MODEL, ROBOT
from hexabot_sim.walking.constants import STAND_HEIGHT_MAX
from hexabot_sim.walking.parameters import WalkingRobot, WalkParams
from hexabot_sim.walking.robot_choice import RobotChoice

QUADBOT = WalkingRobot(
    name=MODEL,
    layout=LAYOUT,
    scene=f"{MODEL}_scene",
    torque_limit=ROBOT.torque_limit,  # [N m] the joints' actuatorfrcrange (quadbot.toml, models/quadbot.xml)
)
# The quadbot, or a legged-robot file with four legs (its gaits are for four).
ROBOTS = RobotChoice(QUADBOT, MODEL, "the quadbot's scenarios")


@dataclasses.dataclass(frozen=True)
class QuadbotParams(WalkParams):
    """Parameters of the walking-quadbot scenarios (body frame: x forward, y left, z up)."""

    gait: str = param("crawl", "", "which legs swing when", choices=tuple(gaits_for(LAYOUT.n_legs)))
    vx: float = param(0.05, "m/s", "commanded forward speed", ge=-1.0, le=1.0, typo=("mm/s", 1e-3))
    period: float = param(1.5, "s", "gait cycle: every leg swings once per period", ge=0.2, le=10.0)
    duty: float = param(0.0, "1", "stance fraction of the cycle; 0 = the gait's own (crawl 3/4, trot 1/2)", ge=0.0,
                        lt=1.0)  # fmt: skip
    step_height: float = param(0.025, "m", "foot lift at mid-swing", ge=0.002, le=0.1, typo=("mm", 1e-3))
    stand_height: float = param(
        0.0, "m", "foot depth below the hips while standing (body height - foot radius); 0 = the robot's own "
        "(the quadbot's 0.07, a robot file's [stance] height)", ge=0.0, le=STAND_HEIGHT_MAX, typo=("mm", 1e-3),
    )  # fmt: skip
    ROBOTS: ClassVar[RobotChoice] = ROBOTS
    robot: str = ROBOTS.param("the quadbot, or your own four-legged robot (docs/robot-files.md)")
