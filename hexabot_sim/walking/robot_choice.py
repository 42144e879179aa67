"""The `robot` parameter of a walking robot's scenarios: the built-in robot, or a legged-robot file with as many legs
(docs/robot-files.md), whose model is generated at run time and walked in the built-in robot's scene with the
same gaits and controllers (the gaits are those for its number of legs, control.gait.gaits_for)."""

from __future__ import annotations

import dataclasses
import functools
import os
from typing import Any

from hexabot_sim.control.gait import gaits_for
from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics import legged_file
from hexabot_sim.params import NameOrFile, param
from hexabot_sim.walking.parameters import WalkingRobot

COUNTS: dict[int, str] = {3: "three", 4: "four", 5: "five", 6: "six", 8: "eight"}  # in words, in messages


@dataclasses.dataclass(frozen=True)
class RobotChoice:
    """The robots a walking scenario takes: `builtin` (by its name) or a file with its number of legs.

    Attributes:
        builtin: The robot of the scenarios (its scene hosts a file's robot).
        model: The MJCF file (models/<model>.xml) its scene includes, replaced by a file's generated model.
        scenario: The scenarios named in a refusal, e.g. "the hexabot's scenarios" (a refusal of quadbot-trot named
            quadbot-walk).
    """

    builtin: WalkingRobot
    model: str
    scenario: str

    @property
    def legs(self) -> int:
        return self.builtin.layout.n_legs

    def robot(self, robot: str) -> WalkingRobot:
        """The built-in robot, or the robot of a legged-robot file (read once per file version).

        Raises:
            UsageError: Any problem with the file (one line), or another number of legs than the built-in robot's.
            OSError: The file cannot be read.
        """
        if robot == self.builtin.name:
            return self.builtin
        info = os.stat(robot)
        return _from_file(self, os.path.abspath(robot), info.st_size, info.st_mtime_ns, robot)

    def name_or_file(self) -> NameOrFile:
        """The parameter's names and check (params.param's `name_or_file`)."""
        legs = COUNTS.get(self.legs, str(self.legs))
        return NameOrFile((self.builtin.name,), f"legged-robot file (.toml) with {legs} legs", self.robot)

    def param(self, doc: str) -> Any:
        """The `robot` parameter's field (params.param): the built-in robot by default."""
        return param(self.builtin.name, "", doc, name_or_file=self.name_or_file())

    def resolve(self, robot: str) -> WalkingRobot:
        """`robot` for WalkParams.ROBOT: a file that changed or went away since the parameter was checked is a
        ValueError naming the parameter."""
        try:
            return self.robot(robot)
        except (UsageError, OSError) as e:
            raise ValueError(f"parameter 'robot': {str(e).splitlines()[0]}") from None


@functools.lru_cache(maxsize=16)
def _from_file(choice: RobotChoice, path: str, size: int, mtime: int, shown: str) -> WalkingRobot:
    spec = legged_file.read(shown)
    n = spec.layout.n_legs
    if n != choice.legs:
        raise UsageError(
            f"robot file {spec.source}: {n} legs; {choice.scenario} walk {choice.legs}-legged robots (their gaits "
            f"{', '.join(gaits_for(choice.legs))} are for {choice.legs} legs)"
        )
    replace = ((f"{choice.model}.xml", spec.robot_xml()),)
    return WalkingRobot(spec.name, spec.layout, choice.builtin.scene, spec.torque_limit, replace)
