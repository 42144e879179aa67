"""The walking quadbot: four DH legs on a free body, crawl and trot gaits on contact physics.

Everything but the robot is the shared walking machinery (hexabot_sim/walking/): the same commands,
terrain, controllers and metrics as the hexabot's.
"""

from hexabot_sim.robots.quadbot.parameters import QUADBOT, QuadbotParams
from hexabot_sim.walking.figures import figures
from hexabot_sim.walking.walk import live, run

__all__ = ["QUADBOT", "QuadbotParams", "figures", "live", "run"]  # the scenario contract (hexabot_sim.scenario)
