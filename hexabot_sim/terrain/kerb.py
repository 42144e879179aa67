"""A kerb: a step up across the path, onto a pavement that continues beyond the walk."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from hexabot_sim.terrain.limits import Limits

KERB_LENGTH: float = 20.0  # [m] the pavement after the kerb (beyond any walk)
KERB_WIDTH: float = 20.0  # [m] across the path


@dataclasses.dataclass(frozen=True)
class Kerb:
    """A box across the path whose top, `height` above the ground (along its normal), starts `distance` ahead of
    the start along `along` (a horizontal unit vector (2,), the walking direction) and runs on beyond the walk."""

    height: float
    distance: float = 0.5
    along: tuple[float, float] = (1.0, 0.0)
    length: float = KERB_LENGTH  # [m] of the pavement beyond the edge: the walk's reach past it, at least KERB_LENGTH
    width: float = KERB_WIDTH  # [m] across the path, centred on the start
    depth: float = 0.0  # [m] the box reaches this far below the ground's level: down to a rough patch's valleys

    def surface(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Height [m] of the kerb's top over ground-frame points, -inf where it does not lie."""
        ahead = u * self.along[0] + v * self.along[1]
        across = -u * self.along[1] + v * self.along[0]
        on = (ahead >= self.distance) & (ahead <= self.distance + self.length) & (np.abs(across) <= self.width / 2)
        return np.where(on, self.height, -np.inf)

    def highest_on_line(self, origin: np.ndarray, direction: np.ndarray) -> np.ndarray:
        """The largest t [m] with origin + t * direction inside the kerb's box (ground frame), -inf where the line
        misses it: `origin` (..., 3) points, `direction` (3,) the world's vertical in the ground frame."""
        return box_highest_on_line(
            origin, direction, self.along, (self.distance, self.distance + self.length), self.width, self.depth,
            self.height,
        )  # fmt: skip

    def mjcf(self) -> tuple[list[str], list[str]]:
        """(asset elements, ground elements) as MJCF text, in the ground frame."""
        ax, ay = self.along
        centre = self.distance + self.length / 2
        yaw = math.atan2(ay, ax)
        half = (self.height + self.depth) / 2
        geom = (
            f'<geom name="kerb" type="box" size="{self.length / 2!r} {self.width / 2!r} {half!r}" '
            f'pos="{centre * ax!r} {centre * ay!r} {(self.height - self.depth) / 2!r}" '
            f'quat="{math.cos(yaw / 2)!r} 0 0 {math.sin(yaw / 2)!r}" material="terrain" '
            'contype="0" conaffinity="2" group="0"/>'
        )
        return [], [geom]

    def problem(self, limits: Limits) -> str:
        """'' if the robot can climb the kerb, else why not (one line)."""
        return limits.rise_problem(self.height, "kerb", "the kerb", "the largest climbable")

    def label(self) -> str:
        return f"{self.height * 1000:g} mm kerb at {self.distance:g} m"


def box_highest_on_line(
    origin: np.ndarray,
    direction: np.ndarray,
    along: tuple[float, float],
    ahead: tuple[float, float],
    width: float,
    depth: float,
    height: float,
) -> np.ndarray:
    """The largest t [m] with origin + t * direction inside a box of the ground frame, -inf where the line misses
    it: the box spans `ahead` (from, to) [m] along the horizontal unit vector `along`, `width` [m] across it
    (centred on the origin) and -depth to height [m] along the ground's normal; `origin` (..., 3) points,
    `direction` (3,) the world's vertical in the ground frame."""
    ax, ay = along
    rows = (  # (ground-frame coordinate as a linear function of t, its lower and upper bound)
        ((ax, ay, 0.0), ahead[0], ahead[1]),
        ((-ay, ax, 0.0), -width / 2, width / 2),
        ((0.0, 0.0, 1.0), -depth, height),
    )
    lo = np.full(origin.shape[:-1], -np.inf)
    hi = np.full(origin.shape[:-1], np.inf)
    for axis, low, high in rows:
        start, rate = origin @ np.array(axis), float(np.dot(direction, axis))
        if rate == 0:
            outside = (start < low) | (start > high)
            hi = np.where(outside, -np.inf, hi)
            continue
        a, b = (low - start) / rate, (high - start) / rate
        lo, hi = np.maximum(lo, np.minimum(a, b)), np.minimum(hi, np.maximum(a, b))
    return np.where(lo <= hi, hi, -np.inf)
