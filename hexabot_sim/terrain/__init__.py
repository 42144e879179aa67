"""Ground under a walking robot: terrain types that compose (a slope, a rough patch, a kerb, stairs), each one
small type with its MJCF, its height over the ground and its refusals; `Ground` puts them together."""

from hexabot_sim.terrain.ground import Ground
from hexabot_sim.terrain.heightfield import RoughPatch
from hexabot_sim.terrain.kerb import Kerb
from hexabot_sim.terrain.limits import Limits
from hexabot_sim.terrain.slope import Slope
from hexabot_sim.terrain.stairs import Stairs

__all__ = ["Ground", "Kerb", "Limits", "RoughPatch", "Slope", "Stairs"]
