"""Rough ground: a seeded MuJoCo heightfield of smoothed white noise over the walk, level floor around it.

Heightfield choices (CELL, SIGMA): MuJoCo draws and collides a heightfield as two triangles per grid cell,
so the surface is piecewise linear between the grid points (no steps at any resolution). White noise
smoothed with a Gaussian of sigma = 2.5 cm has an autocorrelation 1/e length of 2 sigma = 5 cm: bumps
about three foot diameters wide (the foot is a 16 mm sphere). A 2 cm grid samples that with facets
smaller than the bumps; a 1 cm grid would be smoother but MuJoCo tests every sphere against each prism
under it: bare mj_step cost 41 us with 1 cm cells, 30 us with 2 cm, 27 us with 4 cm (median of 10 walks
on the shared 2-core machine, 0.01 m roughness; a touching foot has 2.2, 1.35 and 1.2 contacts).
MuJoCo stores the elevation normalised to [0, 1] times the geom's size[2]: the field is written already
normalised (min 0, max 1) with 6 decimals, so the quantisation is 1e-6 x (2 x roughness) (20 nm at 1 cm):
no steps there either. The noise is tapered to zero over TAPER at the border so the heightfield meets
the level of the floor around it: four boxes whose tops are the floor (z = 0 of the ground frame) out to
FLOOR_RING metres, so a robot that wanders off the patch walks on.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from hexabot_sim.terrain.limits import Limits, apart

CELL: float = 0.02  # [m] grid spacing of the heightfield
SIGMA: float = 0.025  # [m] Gaussian smoothing of the white noise (bumps ~5 cm across)
TAPER: float = 0.1  # [m] the bumps fade to zero over this band at the border
MARGIN: float = 0.6  # [m] heightfield beyond the body's path on every side (legs reach ~0.35 m)
MAX_POINTS: int = 2_000_000  # larger fields make the model files and compile time unreasonable
DECIMALS: int = 6  # digits of the normalised elevation written into the MJCF
FLOOR_RING: float = 20.0  # [m] the level floor around the heightfield, beyond any walk
FLOOR_THICKNESS: float = 0.05  # [m] of the boxes around the heightfield


@dataclasses.dataclass(frozen=True)
class RoughPatch:
    """Bumps of peak amplitude `roughness` [m], seeded, over `extent` = (x_min, x_max, y_min, y_max) [m] of the
    ground frame (grid points on multiples of CELL)."""

    roughness: float
    seed: int = 0
    extent: tuple[float, float, float, float] = (-1.0, 1.0, -1.0, 1.0)

    def grid(self) -> tuple[np.ndarray, np.ndarray]:
        """Heightfield grid coordinates: x (ncol,) and y (nrow,) [m]."""
        x0, x1, y0, y1 = self.extent
        ncol = round((x1 - x0) / CELL) + 1
        nrow = round((y1 - y0) / CELL) + 1
        return np.linspace(x0, x1, ncol), np.linspace(y0, y1, nrow)

    def points(self) -> float:
        x0, x1, y0, y1 = self.extent
        return ((x1 - x0) / CELL + 1) * ((y1 - y0) / CELL + 1)

    def heights(self) -> np.ndarray:
        """Heightfield elevations (nrow, ncol) [m], row r at y[r], column c at x[c]; deterministic per seed."""
        x, y = self.grid()
        rng = np.random.default_rng(self.seed)
        pad = math.ceil(4 * SIGMA / CELL)
        noise = rng.standard_normal((len(y) + 2 * pad, len(x) + 2 * pad))
        taps = np.arange(-pad, pad + 1) * CELL
        kernel = np.exp(-0.5 * (taps / SIGMA) ** 2)
        kernel /= kernel.sum()
        # Separable Gaussian smoothing, keeping only the fully smoothed interior.
        smooth = np.apply_along_axis(np.convolve, 1, noise, kernel, "valid")
        smooth = np.apply_along_axis(np.convolve, 0, smooth, kernel, "valid")  # (nrow, ncol)
        # Fade to zero at the border: a smoothstep of the distance to the nearest edge.
        edge_x = np.minimum(x - x[0], x[-1] - x) / TAPER
        edge_y = np.minimum(y - y[0], y[-1] - y) / TAPER
        fade = np.clip(np.minimum(edge_y[:, None], edge_x[None, :]), 0.0, 1.0)
        smooth *= fade * fade * (3 - 2 * fade)
        return smooth * (self.roughness / np.abs(smooth).max())

    def hfield_levels(self) -> tuple[np.ndarray, float, float]:
        """(normalised elevation (nrow, ncol) in [0, 1] as written, base z [m], vertical size [m])."""
        cache = self.__dict__.get("_levels")
        if cache is None:
            h = self.heights()
            low, high = float(h.min()), float(h.max())
            cache = np.round((h - low) / (high - low), DECIMALS), low, high - low
            object.__setattr__(self, "_levels", cache)
        return cache

    def surface(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Height [m] over ground-frame points as MuJoCo collides it: in each grid cell the two triangles split
        along the diagonal (c, r)-(c+1, r+1); 0 (the floor around the patch) outside it."""
        norm, base, size = self.hfield_levels()
        gx, gy = self.grid()
        a = (u - gx[0]) / CELL
        b = (v - gy[0]) / CELL
        inside = (a >= 0) & (a <= len(gx) - 1) & (b >= 0) & (b <= len(gy) - 1)
        c = np.clip(np.floor(a).astype(int), 0, len(gx) - 2)
        r = np.clip(np.floor(b).astype(int), 0, len(gy) - 2)
        fu, fv = np.clip(a - c, 0, 1), np.clip(b - r, 0, 1)
        h00, h01 = norm[r, c], norm[r, c + 1]
        h10, h11 = norm[r + 1, c], norm[r + 1, c + 1]
        lower = fu >= fv  # below the diagonal: triangle (r, c), (r, c+1), (r+1, c+1)
        z = np.where(lower, h00 + fu * (h01 - h00) + fv * (h11 - h01), h00 + fv * (h10 - h00) + fu * (h11 - h10))
        return np.where(inside, base + size * z, 0.0)

    def mjcf(self) -> tuple[list[str], list[str]]:
        """(asset elements, ground elements: the heightfield and the floor ring's static bodies) as MJCF text."""
        norm, base, size = self.hfield_levels()
        x0, x1, y0, y1 = self.extent
        nrow, ncol = norm.shape
        # MJCF lists the rows from the far edge (+y) down, as an image (MuJoCo stores row 0 at -y).
        elevation = " ".join(f"{v:.{DECIMALS}f}".rstrip("0").rstrip(".") for v in norm[::-1].ravel())
        # size: half extents in x and y, the elevation range, and a base box below it.
        assets = [
            f'<hfield name="terrain" nrow="{nrow}" ncol="{ncol}" '
            f'size="{(x1 - x0) / 2!r} {(y1 - y0) / 2!r} {size!r} 0.01" elevation="{elevation}"/>'
        ]
        elements = [
            f'<geom name="terrain" type="hfield" hfield="terrain" pos="{(x0 + x1) / 2!r} {(y0 + y1) / 2!r} {base!r}" '
            'material="terrain" contype="0" conaffinity="2" group="0"/>'
        ]
        # The level floor around the patch: west and east full width, south and north between them. Each box
        # in a static body of its own: MuJoCo's broadphase then prunes it by its own bounding box (as geoms of
        # the world body the four cost 2 us a step against 0.8 us, bare mj_step on rough ground, measured).
        far = FLOOR_RING
        for side, (a0, a1, b0, b1) in (
            ("west", (x0 - far, x0, y0 - far, y1 + far)),
            ("east", (x1, x1 + far, y0 - far, y1 + far)),
            ("south", (x0, x1, y0 - far, y0)),
            ("north", (x0, x1, y1, y1 + far)),
        ):
            elements.append(
                f'<body name="floor_{side}" pos="{(a0 + a1) / 2!r} {(b0 + b1) / 2!r} {-FLOOR_THICKNESS / 2!r}">'
                f'<geom name="floor_{side}" type="box" size="{(a1 - a0) / 2!r} {(b1 - b0) / 2!r} '
                f'{FLOOR_THICKNESS / 2!r}" material="terrain" contype="0" conaffinity="2" group="0"/></body>'
            )
        return assets, elements

    def problem(self, limits: Limits) -> str:
        """'' if the heightfield is of a size a run may build, else why not (one line)."""
        points = self.points()
        if points > limits.max_points:
            x0, x1, y0, y1 = self.extent
            shown, most = apart(points, limits.max_points, "down")
            return (
                f"the rough ground under this walk would be a {x1 - x0:.3g} x {y1 - y0:.3g} m heightfield of "
                f"{shown} points (at most {most}); {limits.points_hint}"
            )
        return ""

    def label(self) -> str:
        return f"roughness {self.roughness * 1000:g} mm, seed {self.seed}"
