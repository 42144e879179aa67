"""The ground of a run: a slope carrying a rough patch and obstacles (a kerb, stairs), composed, as MJCF and heights."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from hexabot_sim.terrain.heightfield import RoughPatch
from hexabot_sim.terrain.kerb import Kerb
from hexabot_sim.terrain.limits import Limits, apart
from hexabot_sim.terrain.slope import Slope
from hexabot_sim.terrain.stairs import Stairs

# Checker drawn on every terrain geom, so the video shows the ground's shape: the squares' edges bend
# over the bumps. MuJoCo maps a 2d texture onto a heightfield or box by the geom's x and y (object-linear
# texture coordinates, no explicit ones): with texuniform="true" the texture repeats texrepeat / 2 times per
# metre whatever the geom's size (with "false", texrepeat times across the whole geom: a field several
# metres long got 1 m squares), and the builtin checker is 2 x 2 squares, so a square is 1 / texrepeat.
SQUARE: float = 0.05  # [m] checker square: about one bump (heightfield.SIGMA), a third of the plate's width
TEXTURE = (
    '<texture name="terrain_grid" type="2d" builtin="checker" rgb1="0.86 0.80 0.66" rgb2="0.70 0.63 0.50" '
    'width="256" height="256" mark="edge" markrgb="0.45 0.38 0.30"/>'
)
MATERIAL = (
    f'<material name="terrain" texture="terrain_grid" texrepeat="{1 / SQUARE:g} {1 / SQUARE:g}" texuniform="true"/>'
)
FLOOR_BELOW: float = 0.002  # [m] the floor plane lies this far below a rough patch's deepest valley (scenery)
HEIGHT_TOLERANCE: float = 1e-12  # [m] the world height of a point on a tilted ground is solved to this


@dataclasses.dataclass(frozen=True)
class Ground:
    """The ground in the world frame (z up; the robot starts at the origin facing +x).

    The types compose: `slope` turns the ground frame; in it lies the surface (`rough`, or the level floor),
    and on the surface stand the `obstacles` (a kerb), each a solid whose top hides what is below it.
    """

    slope: Slope = dataclasses.field(default_factory=Slope)
    rough: RoughPatch | None = None
    obstacles: tuple[Kerb | Stairs, ...] = ()

    def __post_init__(self) -> None:
        # An obstacle on rough ground stands on its valleys: a kerb's box from z = 0 up left a gap under its
        # edge wherever the bumps dipped below it (a foot could slip under the kerb's lip).
        if self.rough is not None:
            depth = self.rough.roughness + FLOOR_BELOW
            object.__setattr__(self, "obstacles", tuple(dataclasses.replace(o, depth=depth) for o in self.obstacles))

    @property
    def flat(self) -> bool:
        return not self.slope.tilted and self.rough is None and not self.obstacles

    def normal(self) -> np.ndarray:
        """Unit normal (3,) of the ground plane (the slope's)."""
        return self.slope.normal()

    def surface(self, u: np.ndarray | float, v: np.ndarray | float) -> np.ndarray:
        """Height [m] of the ground over points of the ground frame (along its normal)."""
        u, v = np.broadcast_arrays(np.asarray(u, dtype=float), np.asarray(v, dtype=float))
        z = self.rough.surface(u, v) if self.rough is not None else np.zeros(u.shape)
        for obstacle in self.obstacles:
            z = np.maximum(z, obstacle.surface(u, v))
        return z

    def height(self, x: np.ndarray | float, y: np.ndarray | float) -> np.ndarray:
        """Ground height [m] under the world points (x, y), as MuJoCo collides it (a vertical ray from above)."""
        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        if not self.slope.tilted:
            return self.surface(x, y)
        # The highest z with R^T (x, y, z) on the surface (the rough patch or the plane): from above, step down
        # along the vertical by the distance to the surface over cos(slope) (a contraction: the surface's own
        # slopes are gentle). An obstacle is a step, where that iteration does not converge (a kerb's edge on a
        # 20 deg downhill slope was 42 mm off): the vertical meets its box along an interval, solved exactly.
        r = self.slope.rotation()
        top = 0.0 if self.rough is None else self.rough.roughness
        z = self.slope.height(x, y) + (top + 0.01) / r[2, 2]
        rough = self.rough.surface if self.rough is not None else (lambda u, v: np.zeros(np.shape(u)))
        for _ in range(200):
            u = r[0, 0] * x + r[1, 0] * y + r[2, 0] * z
            v = r[0, 1] * x + r[1, 1] * y + r[2, 1] * z
            w = r[0, 2] * x + r[1, 2] * y + r[2, 2] * z
            gap = w - rough(u, v)
            z = z - gap / r[2, 2]
            if np.all(np.abs(gap) < HEIGHT_TOLERANCE):
                break
        if self.obstacles:
            origin = np.stack([x, y, np.zeros(x.shape)], axis=-1) @ r  # R^T (x, y, 0), the line's point at z = 0
            for obstacle in self.obstacles:
                z = np.maximum(z, obstacle.highest_on_line(origin, r[2]))
        return z

    def floor(self) -> dict[str, np.ndarray | str]:
        """Attributes of the scene's floor plane under this ground: turned with the slope; under a rough patch
        lowered below its valleys and no longer collided (scenery: the patch and its ring are the ground)."""
        attributes: dict[str, np.ndarray | str] = {}
        if self.slope.tilted:
            attributes["quat"] = self.slope.floor_quat()
        if self.rough is not None:
            depth = self.rough.roughness + FLOOR_BELOW
            pos = np.array([0.0, 0.0, -depth]) if not self.slope.tilted else -depth * self.normal()
            attributes |= {"conaffinity": "0", "pos": pos}
        return attributes

    def mjcf(self) -> tuple[list[str], list[str]]:
        """(asset elements, worldbody elements) as MJCF text: the features, in a body turned with the slope."""
        assets, elements = [TEXTURE, MATERIAL], []
        for feature in ([self.rough] if self.rough is not None else []) + list(self.obstacles):
            more_assets, more_elements = feature.mjcf()
            assets += more_assets
            elements += more_elements
        if self.slope.tilted and elements:
            quat = " ".join(repr(float(v)) for v in self.slope.floor_quat())
            elements = [f'<body name="ground" quat="{quat}">{"".join(elements)}</body>']
        return assets, elements

    def problem(self, limits: Limits) -> str:
        """'' if the robot can walk this ground, else the first reason it cannot (one line)."""
        if self.slope.tilted:
            tan = math.tan(math.radians(self.slope.slope_deg))
            if tan > limits.friction:
                friction, least = apart(limits.friction, tan, "up")
                slope, steepest = apart(self.slope.slope_deg, math.degrees(math.atan(limits.friction)), "down")
                why = f" ({limits.friction_why})" if limits.friction_why else ""
                return (
                    f"a {slope} deg slope needs a friction coefficient of at least tan(slope) = "
                    f"{least} to hold the feet; friction is {friction}{why} (the steepest slope it holds is "
                    f"{steepest} deg)"
                )
        if self.rough is not None:
            problem = self.rough.problem(limits)
            if problem:
                return problem
            # An obstacle on rough ground is climbed from its lowest valley.
            bumps = self.rough.roughness
            limits = dataclasses.replace(
                limits,
                climbable=limits.climbable - bumps,
                climbable_why=f"{limits.climbable_why}, less {bumps * 1000:g} mm of rough ground",
            )
        for obstacle in self.obstacles:
            problem = obstacle.problem(limits)
            if problem:
                return problem
        return ""

    def label(self) -> str:
        """The ground in words, e.g. '8 deg slope (uphill), roughness 10 mm, seed 0'."""
        parts = [self.slope.label()] if self.slope.tilted else []
        parts += [self.rough.label()] if self.rough is not None else []
        parts += [o.label() for o in self.obstacles]
        return ", ".join(parts) if parts else "flat ground"
