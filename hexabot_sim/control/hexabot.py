"""The walking controller's old home, kept while robots/hexabot/walk.py imports it from here.

The controller is shared machinery now, control/walker.py (HexabotController is its WalkingController);
import from there (issue 18). This module goes once walk.py does.
"""

from __future__ import annotations

from hexabot_sim.control.walker import (
    MAX_HEADING_CORRECTION,
    GroundController,
    GroundSettings,
    Touchdown,
    WalkSettings,
    fit_plane,
    kernels,
    yaw_of,
)
from hexabot_sim.control.walker import WalkingController as HexabotController

__all__ = [
    "MAX_HEADING_CORRECTION",
    "GroundController",
    "GroundSettings",
    "HexabotController",
    "Touchdown",
    "WalkSettings",
    "fit_plane",
    "kernels",
    "yaw_of",
]
