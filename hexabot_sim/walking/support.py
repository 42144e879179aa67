"""Where the body's centre lies against the feet a gait stands on: the neutral stance's sets of feet down, and the
least margin over a planned cycle (the checks of walking.parameters)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from hexabot_sim.control.gait import Command
from hexabot_sim.walking.constants import TWO_FEET_APART_DEG
from hexabot_sim.walking.ground import plan_steady

if TYPE_CHECKING:
    from hexabot_sim.walking.parameters import WalkParams


def support_problem(p: WalkParams) -> str:
    """'' if every set of feet the gait stands on surrounds the body's centre at the neutral stance (a trot's two:
    lie on opposite sides of it, constants.TWO_FEET_APART_DEG), else why not. The gaits take the legs in the layout's
    order (the left row front to rear, then the right row): a robot file whose 'names' list them otherwise (lf, rf,
    lm, ...) stood a tripod on its three left feet and shuffled at -0.013 m/s for 0.1; legs turned all one way stood
    nowhere and fell."""
    gait = p.the_gait()
    layout = p.ROBOT.layout
    feet = layout.neutral_feet_body()[:, :2]  # (n, 2)
    for down in gait.stance_sets():
        margin = _hull_margin(feet[list(down)]) if len(down) >= 3 else math.inf
        if len(down) == 2:  # a trot's pair: on opposite sides of the centre (the gait balances on their line)
            a, b = feet[list(down)]
            cos = a @ b / max(float(np.linalg.norm(a) * np.linalg.norm(b)), 1e-12)
            apart = math.degrees(math.acos(min(1.0, max(-1.0, cos))))
            if apart < TWO_FEET_APART_DEG:
                legs = " and ".join(layout.legs[i] for i in down)
                return (
                    f"the {gait.name} gait stands on {legs} at once, and their feet are not on opposite sides of the "
                    f"body's centre ({apart:.0f} deg apart seen from it at the neutral stance, at least "
                    f"{TWO_FEET_APART_DEG:g} needed): the gaits take the legs in the robot file's order, the left row "
                    "front to rear, then the right row; reorder 'names', or move the hips or turn the yaws"
                )
        if margin < -1e-9:
            legs = ", ".join(layout.legs[i] for i in down)
            where = (  # -inf: the feet in one line (it printed "at least inf mm outside them")
                f"it is at least {-margin * 1000:.0f} mm outside them"
                if math.isfinite(margin)
                else "they stand in a line"
            )
            return (
                f"the {gait.name} gait stands on {legs} at once, and their feet do not surround the body's centre "
                f"({where} at the neutral stance): the gaits take the "
                "legs in the robot file's order, the left row front to rear, then the right row; reorder 'names', or "
                "move the hips or turn the yaws"
            )
    return ""


def least_support_margin(p: WalkParams, cmd: Command, samples: int = 240) -> float:
    """The least distance [m] of the body's centre inside the feet down (three or more) over a steady cycle of the
    gait's plan at this command (negative: outside; inf: never three down)."""
    feet, down, _ = plan_steady(p, cmd, samples)
    margins = [_hull_margin(feet[k, down[k], :2]) for k in range(len(feet)) if down[k].sum() >= 3]
    return min(margins, default=math.inf)


def _hull_margin(points: np.ndarray) -> float:
    """Distance [m] of the origin inside the convex hull of `points` (k, 2), k >= 3, from its nearest edge; < 0
    outside (minus the distance to the farthest edge line it is beyond), -inf for points on one line."""

    def cross(o: tuple, a: tuple, b: tuple) -> float:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    pts = sorted(map(tuple, points.tolist()))
    lower: list[tuple] = []
    upper: list[tuple] = []
    for chain, order in ((lower, pts), (upper, pts[::-1])):  # Andrew's monotone chain, counter-clockwise
        for point in order:
            while len(chain) >= 2 and cross(chain[-2], chain[-1], point) <= 0:
                chain.pop()
            chain.append(point)
    hull = lower[:-1] + upper[:-1]
    if len(hull) < 3:
        return -math.inf
    return min(cross(a, b, (0.0, 0.0)) / math.dist(a, b) for a, b in zip(hull, hull[1:] + hull[:1], strict=True))
