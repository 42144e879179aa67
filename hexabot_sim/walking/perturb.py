"""A walk's seeded imperfections of the robot: servo trims, a body CoM offset, per-foot friction (walking/parameters:
trim_error_deg, com_offset, friction_spread), drawn once per seed for the scene, the controller and the checks."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from hexabot_sim.walking.parameters import WalkParams


def perturbations(p: WalkParams) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Seeded servo trims (3 n_legs,) [rad], body CoM offset (3,) [m] and per-foot friction factors (n_legs,)."""
    n = p.ROBOT.layout.n_legs
    rng = np.random.default_rng(p.seed)
    trims = rng.uniform(-1.0, 1.0, 3 * n) * math.radians(p.trim_error_deg)
    angle = rng.uniform(0.0, 2 * math.pi)
    com = np.array([math.cos(angle), math.sin(angle), 0.0]) * p.com_offset
    friction = 1.0 + rng.uniform(-1.0, 1.0, n) * p.friction_spread
    return trims, com, friction
