"""The six-legged hexabot of report 000: where each DH leg sits on its body.

The body-frame kinematics of all feet (FK, IK, Jacobians) is any legged robot's, kinematics/legged.py;
it is re-exported here, so `hexabot.ik_body(hexabot.DEFAULT_LAYOUT, feet)` reads as before.
"""

from __future__ import annotations

import dataclasses

from hexabot_sim.kinematics import legged
from hexabot_sim.kinematics.legged import (  # noqa: F401 (re-exported: the hexabot's kinematics is the generic one)
    JOINT_LOWER,
    JOINT_UPPER,
    JOINTS,
    body_to_hip,
    feet_body,
    foot_pitch,
    hip_to_body,
    ik_body,
    ik_hip_batch,
    jacobians_body,
)

LEGS: tuple[str, ...] = ("lf", "lm", "lr", "rf", "rm", "rr")  # left/right x front/middle/rear


@dataclasses.dataclass(frozen=True)
class Layout(legged.Layout):
    """The hexabot's layout (legged.Layout with the hexabot's legs as defaults).

    Six legs, front and rear legs splayed by 45 deg, middle legs sideways, as on most hobby hexapods
    (the left row mirrored: legged.mirrored(("f", "m", "r"), left hips, (45, 90, 135)) gives the same).
    """

    legs: tuple[str, ...] = LEGS
    hips: tuple[tuple[float, float], ...] = (
        (0.12, 0.06), (0.0, 0.08), (-0.12, 0.06), (0.12, -0.06), (0.0, -0.08), (-0.12, -0.06),
    )  # fmt: skip
    yaws_deg: tuple[float, ...] = (45.0, 90.0, 135.0, -45.0, -90.0, -135.0)


DEFAULT_LAYOUT = Layout()
