"""Stairs: steps up along the walking direction, then a landing that continues beyond the walk."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from hexabot_sim.terrain.kerb import KERB_LENGTH, KERB_WIDTH, box_highest_on_line
from hexabot_sim.terrain.limits import Limits


@dataclasses.dataclass(frozen=True)
class Stairs:
    """`count` steps, each `rise` [m] higher than the last and `run` [m] deep, the first one's edge `distance`
    [m] ahead of the start along `along` (a horizontal unit vector (2,), the walking direction); the top step
    is a landing that runs on `landing` [m] (beyond the walk). Each step is a box reaching `depth` below the
    ground's level (down to a rough patch's valleys), `width` [m] across the path, centred on the start."""

    rise: float
    run: float
    count: int
    distance: float = 0.5
    along: tuple[float, float] = (1.0, 0.0)
    landing: float = KERB_LENGTH
    width: float = KERB_WIDTH
    depth: float = 0.0

    def _steps(self) -> list[tuple[float, float, float]]:
        """Per step: (from, to) along the path [m] and its top [m]; the last step is the landing."""
        out = []
        for k in range(self.count):
            start = self.distance + k * self.run
            end = start + (self.run if k < self.count - 1 else self.landing)
            out.append((start, end, (k + 1) * self.rise))
        return out

    def surface(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Height [m] of the stairs' top over ground-frame points, -inf where they do not lie."""
        ahead = u * self.along[0] + v * self.along[1]
        across = -u * self.along[1] + v * self.along[0]
        z = np.full(np.shape(ahead), -np.inf)
        for start, end, top in self._steps():
            on = (ahead >= start) & (ahead <= end) & (np.abs(across) <= self.width / 2)
            z = np.where(on, np.maximum(z, top), z)
        return z

    def highest_on_line(self, origin: np.ndarray, direction: np.ndarray) -> np.ndarray:
        """The largest t [m] with origin + t * direction inside a step (ground frame), -inf where the line misses
        them all: `origin` (..., 3) points, `direction` (3,) the world's vertical in the ground frame."""
        t = np.full(origin.shape[:-1], -np.inf)
        for start, end, top in self._steps():
            hit = box_highest_on_line(origin, direction, self.along, (start, end), self.width, self.depth, top)
            t = np.maximum(t, hit)
        return t

    def mjcf(self) -> tuple[list[str], list[str]]:
        """(asset elements, ground elements) as MJCF text, in the ground frame: a box `stairs_<k>` per step."""
        ax, ay = self.along
        yaw = math.atan2(ay, ax)
        geoms = []
        for k, (start, end, top) in enumerate(self._steps()):
            centre, half = (start + end) / 2, (top + self.depth) / 2
            geoms.append(
                f'<geom name="stairs_{k}" type="box" size="{(end - start) / 2!r} {self.width / 2!r} {half!r}" '
                f'pos="{centre * ax!r} {centre * ay!r} {(top - self.depth) / 2!r}" '
                f'quat="{math.cos(yaw / 2)!r} 0 0 {math.sin(yaw / 2)!r}" material="terrain" '
                'contype="0" conaffinity="2" group="0"/>'
            )
        return [], geoms

    def problem(self, limits: Limits) -> str:
        """'' if the robot can climb every step, else why not (one line)."""
        if self.count < 1 or self.run <= 0:
            return f"stairs need at least one step and a positive run; got {self.count} steps of {self.run:g} m"
        return limits.rise_problem(self.rise, "stair rise", "a step", "the largest climbable step")

    def label(self) -> str:
        return f"{self.count} stairs of {self.rise * 1000:g} mm x {self.run * 1000:g} mm at {self.distance:g} m"
