"""The walking hexabot (report 000): six DH legs on a free body, tripod/ripple/wave gaits on contact physics.

`robot` is the hexabot, or a legged-robot file with six legs (docs/robot-files.md): its model is generated at
run time and walked in the hexabot's scene with the same gaits and controllers.
"""

from hexabot_sim.robots.hexabot.parameters import HEXABOT, HexabotParams
from hexabot_sim.walking.figures import figures
from hexabot_sim.walking.walk import live, run

__all__ = ["HEXABOT", "HexabotParams", "figures", "live", "run"]  # the scenario contract (hexabot_sim.scenario)
