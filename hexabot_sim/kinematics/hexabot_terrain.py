"""Ground for the hexabot: a tilted floor, a seeded heightfield or a kerb, as MJCF and as a height function.

The terrain is described in the world frame (z up; the robot starts at the origin facing +x). One
feature at a time:
- slope: the floor plane turned about a horizontal axis, so the ground rises by tan(slope) per
  metre along `uphill` (a unit vector in the ground plane's horizontal projection);
- roughness: a MuJoCo heightfield of smoothed white noise, peak amplitude `roughness`, over a
  rectangle that covers the walk, its bumps fading to zero at the border; around it four boxes whose
  tops are the level floor (z = 0) out to FLOOR_RING metres, so a robot that wanders off the patch
  walks on (the floor plane is lowered below the bumps' valleys, as scenery);
- kerb: a box across the path whose top, `kerb_height` above the floor, starts `kerb_distance`
  ahead of the start along `along` and continues beyond the walk (a step up onto a pavement).

Heightfield choices (HFIELD_CELL, HFIELD_SIGMA): MuJoCo draws and collides a heightfield as two
triangles per grid cell, so the surface is piecewise linear between the grid points (no steps at
any resolution). White noise smoothed with a Gaussian of sigma = 2.5 cm has an autocorrelation 1/e
length of 2 sigma = 5 cm: bumps about three foot diameters wide (the foot is a 16 mm sphere). A
2 cm grid samples that with facets smaller than the bumps; a 1 cm grid would be smoother but
MuJoCo tests every sphere against each prism under it: bare mj_step cost 41 us with 1 cm cells,
30 us with 2 cm, 27 us with 4 cm (median of 10 walks on the shared 2-core machine, 0.01 m roughness;
a touching foot has 2.2, 1.35 and 1.2 contacts).
MuJoCo stores the elevation normalised to [0, 1] times
the geom's size[2]: the field is written already normalised (min 0, max 1) with 6 decimals, so
the quantisation is 1e-6 x (2 x roughness) (20 nm at 1 cm): no steps there either. The noise is
tapered to zero over HFIELD_TAPER at the border so the heightfield meets the level of the floor.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

HFIELD_CELL: float = 0.02  # [m] grid spacing of the heightfield
HFIELD_SIGMA: float = 0.025  # [m] Gaussian smoothing of the white noise (bumps ~5 cm across)
HFIELD_TAPER: float = 0.1  # [m] the bumps fade to zero over this band at the border
HFIELD_MARGIN: float = 0.6  # [m] heightfield beyond the body's path on every side (legs reach ~0.35 m)
HFIELD_MAX_POINTS: int = 2_000_000  # larger fields make the model files and compile time unreasonable
HFIELD_DECIMALS: int = 6  # digits of the normalised elevation written into the MJCF
KERB_LENGTH: float = 20.0  # [m] the pavement after the kerb (beyond any walk)
FLOOR_RING: float = 20.0  # [m] the level floor around the heightfield, beyond any walk
FLOOR_THICKNESS: float = 0.05  # [m] of the boxes around the heightfield
KERB_WIDTH: float = 20.0  # [m] across the path
# Checker drawn on every terrain geom, so the video shows the ground's shape: the squares' edges bend
# over the bumps. MuJoCo maps a 2d texture onto a heightfield or box by the geom's x and y (object-linear
# texture coordinates, no explicit ones): with texuniform="true" the texture repeats texrepeat / 2 times per
# metre whatever the geom's size (with "false", texrepeat times across the whole geom: a field several
# metres long got 1 m squares), and the builtin checker is 2 x 2 squares, so a square is 1 / texrepeat.
TERRAIN_SQUARE: float = 0.05  # [m] checker square: about one bump (HFIELD_SIGMA), a third of the plate's width
TERRAIN_TEXTURE = (
    '<texture name="terrain_grid" type="2d" builtin="checker" rgb1="0.86 0.80 0.66" rgb2="0.70 0.63 0.50" '
    'width="256" height="256" mark="edge" markrgb="0.45 0.38 0.30"/>'
)
TERRAIN_MATERIAL = (
    f'<material name="terrain" texture="terrain_grid" texrepeat="{1 / TERRAIN_SQUARE:g} {1 / TERRAIN_SQUARE:g}" '
    'texuniform="true"/>'
)


@dataclasses.dataclass(frozen=True)
class Terrain:
    """The ground of a run (world frame).

    Attributes:
        slope_deg: Floor tilt [deg].
        uphill: Horizontal unit vector (2,) along which the sloped floor rises.
        roughness: Peak amplitude of the heightfield [m] (0: none).
        seed: Seed of the heightfield's noise.
        extent: (x_min, x_max, y_min, y_max) [m] the heightfield covers.
        kerb_height: Height of the kerb [m] (0: none).
        kerb_distance: Distance of the kerb's edge from the start along `along` [m].
        along: Horizontal unit vector (2,) of the walking direction (the kerb lies across it).
    """

    slope_deg: float = 0.0
    uphill: tuple[float, float] = (1.0, 0.0)
    roughness: float = 0.0
    seed: int = 0
    extent: tuple[float, float, float, float] = (-1.0, 1.0, -1.0, 1.0)
    kerb_height: float = 0.0
    kerb_distance: float = 0.5
    along: tuple[float, float] = (1.0, 0.0)

    @property
    def flat(self) -> bool:
        return self.slope_deg == 0 and self.roughness == 0 and self.kerb_height == 0

    def normal(self) -> np.ndarray:
        """Unit normal (3,) of the (sloped) floor."""
        a = math.radians(self.slope_deg)
        ux, uy = self.uphill
        return np.array([-math.sin(a) * ux, -math.sin(a) * uy, math.cos(a)])

    def grid(self) -> tuple[np.ndarray, np.ndarray]:
        """Heightfield grid coordinates: x (ncol,) and y (nrow,) [m]."""
        x0, x1, y0, y1 = self.extent
        ncol = round((x1 - x0) / HFIELD_CELL) + 1
        nrow = round((y1 - y0) / HFIELD_CELL) + 1
        return np.linspace(x0, x1, ncol), np.linspace(y0, y1, nrow)

    def heights(self) -> np.ndarray:
        """Heightfield elevations (nrow, ncol) [m], row r at y[r], column c at x[c]; deterministic per seed."""
        x, y = self.grid()
        rng = np.random.default_rng(self.seed)
        pad = math.ceil(4 * HFIELD_SIGMA / HFIELD_CELL)
        noise = rng.standard_normal((len(y) + 2 * pad, len(x) + 2 * pad))
        taps = np.arange(-pad, pad + 1) * HFIELD_CELL
        kernel = np.exp(-0.5 * (taps / HFIELD_SIGMA) ** 2)
        kernel /= kernel.sum()
        # Separable Gaussian smoothing, keeping only the fully smoothed interior.
        smooth = np.apply_along_axis(np.convolve, 1, noise, kernel, "valid")
        smooth = np.apply_along_axis(np.convolve, 0, smooth, kernel, "valid")  # (nrow, ncol)
        # Fade to zero at the border: a smoothstep of the distance to the nearest edge.
        edge_x = np.minimum(x - x[0], x[-1] - x) / HFIELD_TAPER
        edge_y = np.minimum(y - y[0], y[-1] - y) / HFIELD_TAPER
        fade = np.clip(np.minimum(edge_y[:, None], edge_x[None, :]), 0.0, 1.0)
        smooth *= fade * fade * (3 - 2 * fade)
        return smooth * (self.roughness / np.abs(smooth).max())

    def hfield_levels(self) -> tuple[np.ndarray, float, float]:
        """(normalised elevation (nrow, ncol) in [0, 1] as written, base z [m], vertical size [m])."""
        h = self.heights()
        low, high = float(h.min()), float(h.max())
        norm = np.round((h - low) / (high - low), HFIELD_DECIMALS)
        return norm, low, high - low

    def height(self, x: np.ndarray | float, y: np.ndarray | float) -> np.ndarray:
        """Ground height [m] under the points (x, y) (world frame), as MuJoCo collides it."""
        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        z = np.zeros(x.shape)
        if self.slope_deg:
            z = z + math.tan(math.radians(self.slope_deg)) * (x * self.uphill[0] + y * self.uphill[1])
        if self.kerb_height:
            z = z + np.where(x * self.along[0] + y * self.along[1] >= self.kerb_distance, self.kerb_height, 0.0)
        if self.roughness:
            z = z + self._hfield_height(x, y)
        return z

    def _hfield_height(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Heightfield surface: in each grid cell the two triangles split along the diagonal (c, r)-(c+1, r+1)."""
        norm, base, size = self._levels_cached()
        gx, gy = self.grid()
        u = (x - gx[0]) / HFIELD_CELL
        v = (y - gy[0]) / HFIELD_CELL
        inside = (u >= 0) & (u <= len(gx) - 1) & (v >= 0) & (v <= len(gy) - 1)
        c = np.clip(np.floor(u).astype(int), 0, len(gx) - 2)
        r = np.clip(np.floor(v).astype(int), 0, len(gy) - 2)
        fu, fv = np.clip(u - c, 0, 1), np.clip(v - r, 0, 1)
        h00, h01 = norm[r, c], norm[r, c + 1]
        h10, h11 = norm[r + 1, c], norm[r + 1, c + 1]
        lower = fu >= fv  # below the diagonal: triangle (r, c), (r, c+1), (r+1, c+1)
        z = np.where(
            lower,
            h00 + fu * (h01 - h00) + fv * (h11 - h01),
            h00 + fv * (h10 - h00) + fu * (h11 - h10),
        )
        return np.where(inside, base + size * z, 0.0)

    def _levels_cached(self) -> tuple[np.ndarray, float, float]:
        cache = self.__dict__.get("_levels")
        if cache is None:
            cache = self.hfield_levels()
            object.__setattr__(self, "_levels", cache)
        return cache

    def mjcf(self) -> tuple[list[str], list[str]]:
        """(asset elements, worldbody elements: geoms, and the floor ring's static bodies) as MJCF text."""
        assets = [TERRAIN_TEXTURE]
        geoms: list[str] = []
        assets.append(TERRAIN_MATERIAL)
        if self.roughness:
            norm, base, size = self._levels_cached()
            x0, x1, y0, y1 = self.extent
            nrow, ncol = norm.shape
            # MJCF lists the rows from the far edge (+y) down, as an image (MuJoCo stores row 0 at -y).
            elevation = " ".join(f"{v:.{HFIELD_DECIMALS}f}".rstrip("0").rstrip(".") for v in norm[::-1].ravel())
            # size: half extents in x and y, the elevation range, and a base box below it.
            assets.append(
                f'<hfield name="terrain" nrow="{nrow}" ncol="{ncol}" '
                f'size="{(x1 - x0) / 2!r} {(y1 - y0) / 2!r} {size!r} 0.01" elevation="{elevation}"/>'
            )
            geoms.append(
                f'<geom name="terrain" type="hfield" hfield="terrain" '
                f'pos="{(x0 + x1) / 2!r} {(y0 + y1) / 2!r} {base!r}" '
                'material="terrain" contype="0" conaffinity="2" group="0"/>'
            )
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
                geoms.append(
                    f'<body name="floor_{side}" pos="{(a0 + a1) / 2!r} {(b0 + b1) / 2!r} {-FLOOR_THICKNESS / 2!r}">'
                    f'<geom name="floor_{side}" type="box" size="{(a1 - a0) / 2!r} {(b1 - b0) / 2!r} '
                    f'{FLOOR_THICKNESS / 2!r}" material="terrain" contype="0" conaffinity="2" group="0"/></body>'
                )
        if self.kerb_height:
            ax, ay = self.along
            centre = self.kerb_distance + KERB_LENGTH / 2
            yaw = math.atan2(ay, ax)
            geoms.append(
                f'<geom name="kerb" type="box" size="{KERB_LENGTH / 2!r} {KERB_WIDTH / 2!r} {self.kerb_height / 2!r}" '
                f'pos="{centre * ax!r} {centre * ay!r} {self.kerb_height / 2!r}" '
                f'quat="{math.cos(yaw / 2)!r} 0 0 {math.sin(yaw / 2)!r}" material="terrain" '
                'contype="0" conaffinity="2" group="0"/>'
            )
        return assets, geoms

    def floor_quat(self) -> np.ndarray:
        """Quaternion (w, x, y, z) turning the floor plane's normal from z to `normal()`."""
        a = math.radians(self.slope_deg)
        ux, uy = self.uphill
        return np.array([math.cos(a / 2), math.sin(a / 2) * uy, -math.sin(a / 2) * ux, 0.0])


__all__ = ["HFIELD_CELL", "HFIELD_SIGMA", "TERRAIN_SQUARE", "Terrain"]
