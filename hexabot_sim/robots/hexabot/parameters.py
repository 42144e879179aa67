"""The walking hexabot's robot and parameters, apart from the walk itself: `hexabot-sim list` reads them
without MuJoCo (the scenario module is hexabot/walk.py)."""

from __future__ import annotations

import dataclasses
import functools
import os

from hexabot_sim.control.gait import GAITS
from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics import legged_file
from hexabot_sim.params import NameOrFile, param
from hexabot_sim.robots.hexabot import model as hx
from hexabot_sim.walking.parameters import WalkingRobot, WalkParams

HEXABOT = WalkingRobot(
    name="hexabot",
    layout=hx.DEFAULT_LAYOUT,
    scene="hexabot_scene",
    torque_limit=hx.ROBOT.torque_limit,  # [N m] the joints' actuatorfrcrange (hexabot.toml, models/hexabot.xml)
)
LEGS: int = len(hx.LEGS)  # a robot file walked here needs the hexabot's number of legs (its gaits are for six)


def walking_robot(robot: str) -> WalkingRobot:
    """The hexabot, or the robot of a legged-robot file (read once per file version).

    Raises:
        UsageError: Any problem with the file (one line), or a leg count other than six.
    """
    if robot == HEXABOT.name:
        return HEXABOT
    info = os.stat(robot)
    return _from_file(os.path.abspath(robot), info.st_size, info.st_mtime_ns, robot)


@functools.lru_cache(maxsize=16)
def _from_file(path: str, size: int, mtime: int, shown: str) -> WalkingRobot:
    spec = legged_file.read(shown)
    n = spec.layout.n_legs
    if n != LEGS:
        raise UsageError(
            f"robot file {spec.source}: {n} legs; hexabot-walk walks {LEGS}-legged robots (its gaits "
            f"{', '.join(GAITS)} are for {LEGS} legs)"
        )
    replace = ((f"{hx.MODEL}.xml", spec.robot_xml()),)
    return WalkingRobot(spec.name, spec.layout, HEXABOT.scene, spec.torque_limit, replace)


ROBOT = NameOrFile((HEXABOT.name,), "legged-robot file (.toml) with six legs", walking_robot)


@dataclasses.dataclass(frozen=True)
class HexabotParams(WalkParams):
    """Parameters of the walking-hexabot scenarios (body frame: x forward, y left, z up)."""

    robot: str = param(
        HEXABOT.name, "", "the hexabot, or your own six-legged robot (docs/robot-files.md)", name_or_file=ROBOT
    )

    @property
    def ROBOT(self) -> WalkingRobot:  # WalkParams' name for the robot a walk uses
        try:
            return walking_robot(self.robot)
        except (UsageError, OSError) as e:  # the file changed or went away since the parameter was checked
            raise ValueError(f"parameter 'robot': {str(e).splitlines()[0]}") from None
