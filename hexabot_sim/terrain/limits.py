"""What a robot on the ground can take: each terrain type refuses, in one line, what exceeds it."""

from __future__ import annotations

import dataclasses

from hexabot_sim.params import apart

__all__ = ["Limits", "apart"]


@dataclasses.dataclass(frozen=True)
class Limits:
    """The robot's side of a terrain check, filled in by the robot (its legs, body and gait).

    Attributes:
        friction: Friction coefficient of the feet on the ground (with feet that differ: the least mean over the
            feet that stand at once).
        friction_why: How `friction` follows from the feet when they differ ("" when they do not).
        climbable: Highest step up [m] the walk can climb (swing clearance and leg reach).
        climbable_why: How `climbable` follows from the robot, e.g. "the foot lifts ..., the legs reach ...".
        climbable_hint: What to change to climb higher, e.g. "raise 'step_height'".
        underside: Height [m] of the body's underside above the ground it stands on.
        underside_why: Where `underside` comes from, e.g. "at stand_height 0.05 m".
        underside_hint: What to change to raise it, e.g. "raise 'stand_height'".
        clearance: [m] an obstacle stays this far below the underside.
        max_points: Largest heightfield (grid points) a run may build.
        points_hint: What to change to build a smaller one (the field covers where the walk may go).
    """

    friction: float
    climbable: float
    climbable_why: str
    climbable_hint: str
    underside: float
    underside_why: str
    underside_hint: str
    clearance: float
    max_points: int
    friction_why: str = ""
    points_hint: str = "shorten 'duration' or lower the speed"

    def rise_problem(self, height: float, what: str, each: str, largest: str) -> str:
        """'' if a step up of `height` [m] clears the body and can be climbed, else why not (one line), e.g. what
        "kerb", each "the kerb", largest "the largest climbable"."""
        if height > self.underside - self.clearance:
            rise_mm, highest_mm = apart(height * 1000, (self.underside - self.clearance) * 1000, "down")
            return (
                f"a {rise_mm} mm {what} would hit the plate: {self.underside_why} its underside is "
                f"{self.underside * 1000:.0f} mm above the ground, and {each} must stay "
                f"{self.clearance * 1000:g} mm below it (at most {highest_mm} mm); {self.underside_hint}"
            )
        if height > self.climbable:
            # Rough ground may take all the walk can climb: then none is (it said "the largest climbable, -28 mm").
            rise_mm, largest_mm = apart(height * 1000, max(self.climbable, 0.0) * 1000, "down")
            return (
                f"a {rise_mm} mm {what} is above {largest}, {largest_mm} mm ({self.climbable_why}); "
                f"{self.climbable_hint}"
            )
        return ""
