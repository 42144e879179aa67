"""A terrain map: the ground's height on a regular grid of the world's (x, y), as a walking robot's elevation map
holds it.

A robot that sees the ground (a depth camera or a lidar, fused into an elevation map over its odometry) knows where
the next foothold lies before its foot gets there. `HeightMap.sample` builds that map from the run's own ground
(terrain.Ground.height: the surface MuJoCo collides), on cells of CELL, with an optional error: independent Gaussian
noise per grid point (seeded), standing for the sensor's and the map's errors. Between grid points the map is
bilinear (what the controller reads: control/map_kernels.py; `height` here is the same in numpy).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

CELL: float = 0.01  # [m] the map's grid spacing: half the rough patch's (heightfield.CELL), so its facets are resolved
MAX_POINTS: int = 4_000_000  # 32 MB of float64: a walk whose area needs more is refused (walking.ground)


def grid_size(extent: tuple[float, float, float, float]) -> tuple[int, int]:
    """(nx, ny): the map's grid points over extent = (x_min, x_max, y_min, y_max) [m] at CELL."""
    x_min, x_max, y_min, y_max = extent
    return max(2, math.ceil((x_max - x_min) / CELL) + 1), max(2, math.ceil((y_max - y_min) / CELL) + 1)


@dataclasses.dataclass(frozen=True, eq=False)  # eq=False: an array field (compared by identity)
class HeightMap:
    """Heights (ny, nx) [m] at x0 + i cell, y0 + j cell (world frame); outside the grid the map knows nothing (NaN)."""

    x0: float
    y0: float
    cell: float
    heights: np.ndarray
    error: float = 0.0  # [m] the standard deviation of the noise on its heights

    @classmethod
    def sample(cls, ground, extent: tuple[float, float, float, float], error: float = 0.0, seed: int = 0) -> HeightMap:
        """The map of `ground` (terrain.Ground) over extent = (x_min, x_max, y_min, y_max) [m], each height off by
        N(0, error) [m] (seeded by `seed`)."""
        x_min, y_min, cell = extent[0], extent[2], CELL
        nx, ny = grid_size(extent)
        if nx * ny > MAX_POINTS:
            raise ValueError(f"a terrain map of {nx} x {ny} points: more than {MAX_POINTS}")
        x = x_min + cell * np.arange(nx)
        y = y_min + cell * np.arange(ny)
        heights = np.asarray(ground.height(*np.meshgrid(x, y)), dtype=float)
        if error > 0:
            heights = heights + np.random.default_rng([seed, 0x6D6170]).normal(0.0, error, heights.shape)
        return cls(float(x_min), float(y_min), float(cell), np.ascontiguousarray(heights), float(error))

    def params(self) -> np.ndarray:
        """(x0, y0, cell) as the compiled controller reads them."""
        return np.array([self.x0, self.y0, self.cell])

    def height(self, x: np.ndarray | float, y: np.ndarray | float) -> np.ndarray:
        """The map's height [m] at world points (x, y): bilinear between grid points, NaN outside the grid."""
        ny, nx = self.heights.shape
        a = (np.asarray(x, dtype=float) - self.x0) / self.cell
        b = (np.asarray(y, dtype=float) - self.y0) / self.cell
        inside = (a >= 0) & (a <= nx - 1) & (b >= 0) & (b <= ny - 1)
        a, b = np.clip(a, 0.0, nx - 1.0), np.clip(b, 0.0, ny - 1.0)
        i = np.minimum(np.floor(a).astype(int), nx - 2)
        j = np.minimum(np.floor(b).astype(int), ny - 2)
        u, v = a - i, b - j
        h = self.heights
        z = (1 - v) * ((1 - u) * h[j, i] + u * h[j, i + 1]) + v * ((1 - u) * h[j + 1, i] + u * h[j + 1, i + 1])
        return np.where(inside, z, np.nan)
