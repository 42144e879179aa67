"""Swings that land on a terrain map's ground (terrain_map=on), compiled per step (numba, as control/kernels.py).

Without a map a swing ends on the stance plane under its landing point (the plane through the feet down), and on
uneven ground the foot meets the ground above or below it: above, still descending fast (the landing's impact
throws the body and unloads the other feet); below, seeking it after the planned touchdown. With a map
(terrain/heightmap.py) the swing ends where the map says the ground is: each step, for every swinging leg, the
landing point (the planner's, body frame at touchdown) is carried to the world by the body's pose and the commanded
motion until the touchdown, the map's height is read there, and that ground's height in today's body frame goes to
the legs' MAP_Z column, where the swing ends instead of the stance plane (kernels.targets). It is followed with a
20 ms time constant: read every step through the body's pose, it would carry the body's bobbing into the swing feet.
The touch sensors still end a swing the map got wrong (sensed touchdown).

The body's pose comes from the free joint: a perfect state estimate (a real robot's estimator and map errors are
the map's `error`, terrain/heightmap.py).
"""

from __future__ import annotations

import math

import numpy as np

from hexabot_sim.control import kernels as K

# Scalars `mpar`: the map grid's origin and spacing [m] (HeightMap.params), the foot's radius [m] and the time
# constant [s] the swing's landing height follows the map's with.
X0, Y0, CELL, FOOT_RADIUS, FILTER = range(5)


@K.jit
def map_height(mpar, hmap, x, y):
    """The map's height [m] at the world point (x, y): bilinear between grid points; NaN outside the grid (the map
    knows nothing there)."""
    ny, nx = hmap.shape
    a = (x - mpar[X0]) / mpar[CELL]
    b = (y - mpar[Y0]) / mpar[CELL]
    if not (0.0 <= a <= nx - 1.0 and 0.0 <= b <= ny - 1.0):
        return np.nan
    i = min(int(a), nx - 2)  # a >= 0: truncation is the floor
    j = min(int(b), ny - 2)
    u, v = a - i, b - j
    low = (1 - u) * hmap[j, i] + u * hmap[j, i + 1]
    high = (1 - u) * hmap[j + 1, i] + u * hmap[j + 1, i + 1]
    return (1 - v) * low + v * high


@K.jit
def landing_heights(par, mpar, hmap, legs, flags, plane, qpos, cmd, t):
    """Sets legs[:, MAP_Z] of the swinging legs: the height [m] along the body's z, below its origin, of the map's
    ground under each landing point (the foot's centre a radius above it), followed with the time constant
    mpar[FILTER] from the swing's first step; NaN for the other legs, and where the landing point is off the map (the
    swing then ends on the stance plane, its touch sensor finding the ground)."""
    w, x, y, z = qpos[3], qpos[4], qpos[5], qpos[6]
    r00, r01, r02 = 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)
    r10, r11, r12 = 2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)
    r20, r21, r22 = 2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)
    f = K.ramp(par, t)
    vx, vy, wz = f * cmd[0], f * cmd[1], f * cmd[2]
    share = min(1.0, par[K.DT] / mpar[FILTER]) if mpar[FILTER] > 0 else 1.0
    for i in range(legs.shape[0]):
        mode = flags[i, K.MODE]
        if mode != K.SWING and mode != K.NEAR:
            legs[i, K.MAP_Z] = np.nan
            continue
        tau = max(legs[i, K.T_LIFT] + par[K.SWING_TIME] - t, 0.0)  # [s] to the planned touchdown
        lx, ly = legs[i, K.LANDING], legs[i, K.LANDING + 1]
        # The landing point in today's body frame: where the body will be at the touchdown (the command's twist
        # held: turned by wz tau, moved by v tau), the point planned in that frame, at the stance plane's height.
        c, s = math.cos(wz * tau), math.sin(wz * tau)
        bx = c * lx - s * ly + vx * tau
        by = s * lx + c * ly + vy * tau
        bz = plane[0] + plane[1] * lx + plane[2] * ly
        px = qpos[0] + r00 * bx + r01 * by + r02 * bz
        py = qpos[1] + r10 * bx + r11 * by + r12 * bz
        pz = qpos[2] + r20 * bx + r21 * by + r22 * bz
        # The foot's centre on the map's ground: the plane's point moved along the world's vertical by the gap, in
        # the body frame (its z component: r22 per metre of the vertical).
        landing = bz + (map_height(mpar, hmap, px, py) + mpar[FOOT_RADIUS] - pz) * r22
        old = legs[i, K.MAP_Z]
        if math.isnan(landing):  # off the map
            legs[i, K.MAP_Z] = np.nan
            continue
        legs[i, K.MAP_Z] = landing if math.isnan(old) else old + share * (landing - old)


def compile_all() -> None:
    """Calls each kernel once on arrays of the types the controller passes."""
    n = 6
    par, mpar = np.zeros(K.NPAR), np.array([0.0, 0.0, 0.01, 0.008, 0.02])
    legs, flags = np.zeros((n, K.NLEG)), np.zeros((n, 3), dtype=np.int64)
    qpos = np.zeros(7 + 3 * n)
    qpos[3] = 1.0
    landing_heights(par, mpar, np.zeros((2, 2)), legs, flags, np.zeros(3), qpos, np.zeros(3), 0.0)


KERNELS = (map_height, landing_heights)
