"""A sloped ground: the frame of every other terrain type turned about a horizontal axis."""

from __future__ import annotations

import dataclasses
import math

import numpy as np


@dataclasses.dataclass(frozen=True)
class Slope:
    """The ground plane tilted by `slope_deg`, rising along `uphill` (a horizontal unit vector (2,)).

    Every other terrain type is built in the ground frame (its z along the plane's normal): on a slope
    it is carried by the tilt, as a real kerb or rough patch lies on a sloped street.
    """

    slope_deg: float = 0.0
    uphill: tuple[float, float] = (1.0, 0.0)
    heading: str = ""  # how the walk meets it, in words (e.g. "uphill", "across"): for labels only

    @property
    def tilted(self) -> bool:
        return self.slope_deg != 0

    def normal(self) -> np.ndarray:
        """Unit normal (3,) of the (sloped) floor."""
        a = math.radians(self.slope_deg)
        ux, uy = self.uphill
        return np.array([-math.sin(a) * ux, -math.sin(a) * uy, math.cos(a)])

    def floor_quat(self) -> np.ndarray:
        """Quaternion (w, x, y, z) turning the floor plane's normal from z to `normal()`."""
        a = math.radians(self.slope_deg)
        ux, uy = self.uphill
        return np.array([math.cos(a / 2), math.sin(a / 2) * uy, -math.sin(a / 2) * ux, 0.0])

    def rotation(self) -> np.ndarray:
        """Rotation matrix (3, 3) from the ground frame to the world frame."""
        w, x, y, z = self.floor_quat()
        return np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
            ]
        )

    def height(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Height [m] of the plane itself over the world points (x, y)."""
        return math.tan(math.radians(self.slope_deg)) * (x * self.uphill[0] + y * self.uphill[1])

    def label(self) -> str:
        return f"{self.slope_deg:g} deg slope" + (f" ({self.heading})" if self.heading else "")
