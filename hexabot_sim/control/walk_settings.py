"""What the walking controllers (control/walker.py) are asked to do and how: the walk's settings, the ground-finding
controller's, and the record of a swing's touchdown."""

from __future__ import annotations

import dataclasses

from hexabot_sim.control.compliance import AdmittanceSettings
from hexabot_sim.control.force_control import ForceSettings
from hexabot_sim.control.gait import Command
from hexabot_sim.terrain.heightmap import HeightMap


@dataclasses.dataclass(frozen=True)
class WalkSettings:
    """What the walking controller is asked to do and how.

    Attributes:
        command: Body twist to walk at after the ramp.
        settle_time: Standing still on the neutral stance first [s] (the robot settles on its feet).
        ramp_time: The command grows linearly from 0 to `command` over this time [s].
        heading_hold: Correct the yaw rate from the IMU's yaw.
        heading_gain: Yaw-rate correction per radian of heading error [1/s].
        trims: Servo zero errors (3 n_legs,) [rad], leg by leg: each servo holds q_cmd + trim while its encoder
            reads q - trim; empty: none.
        admittance: The legs' admittance around the position servos, driven by the touch sensors
            (control/compliance.py); None: stiff position-controlled legs.
        force: The stance legs' force control (control/force_control.py); None: none.
    """

    command: Command
    settle_time: float = 0.5
    ramp_time: float = 1.0
    heading_hold: bool = False
    heading_gain: float = 2.0
    trims: tuple[float, ...] = ()
    admittance: AdmittanceSettings | None = None
    force: ForceSettings | None = None


@dataclasses.dataclass(frozen=True)
class GroundSettings:
    """How the walking controller meets uneven ground (GroundController).

    Attributes:
        sensed: A swing foot whose touch sensor fires in the second half of its swing goes to stance at
            once (early touchdown); one that has not touched at the planned touchdown keeps descending
            (late touchdown) until it touches or its target leaves `depth_range` (no ground found).
        level: Keep the body level relative to gravity from the IMU's roll and pitch; else the body
            follows the plane of the stance feet.
        stand_height: Depth of the stance feet below the body's origin over the local ground [m].
        depth_range: (smallest, largest) depth of a foot target below its hip [m] (the legs' workspace).
        attitude_gain: Rate at which tilt errors are removed [1/s].
        height_gain: Rate at which body-height errors are removed [1/s].
        touch_threshold: Touch-sensor force that counts as contact [N].
        update_every: Control steps between updates of the ground plane and the levelling.
        reflex_lift: The elevator reflex (sensed touchdown): a swing foot that touches something before
            `reflex_until` of its swing holds its horizontal target and lifts this much higher [m] over
            `reflex_rise` [s], then reaches on to its landing point; 0: no reflex (such a touch is ignored
            in the first half of the swing and is an early touchdown in the second).
        reflex_until: Swing fraction before which a touch triggers the reflex instead of a touchdown.
        reflex_rise: Time the reflex takes to lift [s].
        early_band: A touch with the swing's target less than this above its end height [m] is not an early
            touchdown: the swing goes on to its planned end, as with planned touchdown (a soft foot's pad meets the
            ground a little above the height it stands at); 0: every touch in the second half ends the swing.
        terrain_map: The ground's heights as the robot's map holds them (terrain/heightmap.py): each swing ends on
            the map's ground under its landing point (control/map_kernels.py); None: on the stance plane.
    """

    sensed: bool = True
    level: bool = False
    stand_height: float = 0.09
    depth_range: tuple[float, float] = (0.03, 0.17)
    attitude_gain: float = 10.0
    height_gain: float = 5.0
    touch_threshold: float = 0.3
    update_every: int = 5
    reflex_lift: float = 0.0
    reflex_until: float = 0.75
    reflex_rise: float = 0.1
    early_band: float = 0.0
    terrain_map: HeightMap | None = None


@dataclasses.dataclass(frozen=True)
class Touchdown:
    """A swing that ended: when the plan said and when the foot touched (NaN: no ground found)."""

    leg: int
    planned: float  # [s] planned touchdown time
    touched: float  # [s] touch-sensor time (sensed) or the planned time (planned); NaN: no ground
