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

A landing point on a step's edge is moved off it (legs' SHIFT column, body frame; kernels.targets moves the foot
there over the swing's second half and the stance keeps it): a foot whose centre lands within a foot radius of a
riser's foot stops against the riser's face at a height between the steps (the map's bilinear reading across the
riser's 1 cm cell), slides down into the corner when loaded, and at its next lift-off its swing drives it into the
face: on hexabot-stairs with waypoints turning onto the landing, two rear feet did so (x = 0.492 and 0.742, the
risers at 0.5 and 0.75), each pitching the body 10.8 deg nose up and raising it 7.6 cm (22-28 N on the face, at the
friction cone's limit); roll / pitch peak to peak 12.6 / 15.4 deg. A spot counts as level if the map's ground within
a foot radius and CLEAR of it, and AHEAD on along the way the next swing goes, varies by at most EDGE (more on a
map with an error: its noise is no edge); an edge found in the swing's first half is moved off to the nearest level
spot along the body's x or y.

The body's pose comes from the free joint: a perfect state estimate (a real robot's estimator and map errors are
the map's `error`, terrain/heightmap.py).
"""

from __future__ import annotations

import math

import numpy as np

from hexabot_sim.control import kernels as K

# Scalars `mpar`: the map grid's origin and spacing [m] (HeightMap.params), the foot's radius [m], the time
# constant [s] the swing's landing height follows the map's with, and the height range [m] that makes an edge
# (edge_range).
X0, Y0, CELL, FOOT_RADIUS, FILTER, EDGE_RANGE = range(6)
# A landing spot whose ground varies by more than EDGE [m] (plus EDGE_NOISE times the map's error) within CLEAR [m] of
# the foot's rim is on an edge (a step's riser): the landing point is moved along the body's x or y, SHIFT_STEP at a
# time, up to MAX_SHIFT, to the nearest spot clear of it (1 cm rough ground varies by at most 1.1 cm over such an area:
# never an edge; the noise of a map with an error spans ~4 errors over its 21 points, rarely 6).
EDGE: float = 0.015
EDGE_NOISE: float = 6.0
CLEAR: float = 0.004
SHIFT_STEP: float = 0.0025
MAX_SHIFT: float = 0.04
RIM = 16  # points on the disc's rim
AHEAD: float = 0.02  # [m] and along the way the foot will swing next: a foot at a riser's foot catches it at lift-off
LANE = 4  # points along it


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


def edge_range(error: float) -> float:
    """The height range [m] over a landing spot that makes it an edge, on a map with this error [m]."""
    return EDGE + EDGE_NOISE * error


@K.jit
def level_spot(mpar, hmap, x, y, ux, uy):
    """True if the map's ground within a foot radius and CLEAR of (x, y), and on to AHEAD further along the unit
    vector (ux, uy) (the way the foot will next swing: (0, 0) for none), varies by at most mpar[EDGE_RANGE] (or the
    map does not
    reach there: nothing to avoid)."""
    rho = mpar[FOOT_RADIUS] + CLEAR
    h = map_height(mpar, hmap, x, y)
    if math.isnan(h):
        return True
    low = high = h
    for k in range(RIM + LANE):
        if k < RIM:
            a = 2.0 * math.pi * k / RIM
            h = map_height(mpar, hmap, x + rho * math.cos(a), y + rho * math.sin(a))
        else:
            d = rho + AHEAD * (k - RIM + 1) / LANE
            h = map_height(mpar, hmap, x + d * ux, y + d * uy)
        if math.isnan(h):
            return True
        low, high = min(low, h), max(high, h)
    return high - low <= mpar[EDGE_RANGE]


@K.jit
def _landing_point(qpos, rot, plane, c, s, vx, vy, tau, lx, ly):
    """The landing point (lx, ly): its height bz in today's body frame and where it is in the world (px, py, pz).
    The frame is where the body will be at the touchdown (the command's twist held: turned by the angle whose cos and
    sin are c, s; moved by v tau), the point planned in it at the stance plane's height. rot: the body's rotation
    matrix, row by row."""
    bx = c * lx - s * ly + vx * tau
    by = s * lx + c * ly + vy * tau
    bz = plane[0] + plane[1] * lx + plane[2] * ly
    px = qpos[0] + rot[0] * bx + rot[1] * by + rot[2] * bz
    py = qpos[1] + rot[3] * bx + rot[4] * by + rot[5] * bz
    pz = qpos[2] + rot[6] * bx + rot[7] * by + rot[8] * bz
    return bz, px, py, pz


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
    rot = (r00, r01, r02, r10, r11, r12, r20, r21, r22)
    f = K.ramp(par, t)
    vx, vy, wz = f * cmd[0], f * cmd[1], f * cmd[2]
    share = min(1.0, par[K.DT] / mpar[FILTER]) if mpar[FILTER] > 0 else 1.0
    for i in range(legs.shape[0]):
        mode = flags[i, K.MODE]
        if mode != K.SWING and mode != K.NEAR:
            legs[i, K.MAP_Z] = np.nan
            legs[i, K.SHIFT] = legs[i, K.SHIFT + 1] = 0.0
            continue
        tau = max(legs[i, K.T_LIFT] + par[K.SWING_TIME] - t, 0.0)  # [s] to the planned touchdown
        lx, ly = legs[i, K.LANDING], legs[i, K.LANDING + 1]
        c, s = math.cos(wz * tau), math.sin(wz * tau)  # the body's turn until the touchdown
        bz, px, py, pz = _landing_point(qpos, rot, plane, c, s, vx, vy, tau, lx, ly)
        # Off an edge: the shift (body frame at the touchdown) kept while its spot stays level, else the nearest level
        # spot, chosen in the swing's first half (kernels.targets moves the foot to it in the second).
        if legs[i, K.T_LIFT] + 0.5 * par[K.SWING_TIME] > t:
            sx, sy = legs[i, K.SHIFT], legs[i, K.SHIFT + 1]
            ex, ey = r00 * c + r01 * s, r10 * c + r11 * s  # the landing frame's x and y in the world's plane
            fx, fy = -r00 * s + r01 * c, -r10 * s + r11 * c
            speed = math.hypot(vx, vy)
            ux = (ex * vx + fx * vy) / speed if speed > 1e-6 else 0.0  # the way the next swing goes
            uy = (ey * vx + fy * vy) / speed if speed > 1e-6 else 0.0
            if not level_spot(mpar, hmap, px + ex * sx + fx * sy, py + ey * sx + fy * sy, ux, uy):
                sx = sy = 0.0
                n_steps = int(MAX_SHIFT / SHIFT_STEP + 0.5)
                for k in range(n_steps + 1):
                    found = False
                    for d in range(4 if k > 0 else 1):
                        dx = k * SHIFT_STEP * (1.0 if d == 0 else -1.0 if d == 1 else 0.0)
                        dy = k * SHIFT_STEP * (1.0 if d == 2 else -1.0 if d == 3 else 0.0)
                        if level_spot(mpar, hmap, px + ex * dx + fx * dy, py + ey * dx + fy * dy, ux, uy):
                            sx, sy, found = dx, dy, True
                            break
                    if found:
                        break
            legs[i, K.SHIFT], legs[i, K.SHIFT + 1] = sx, sy
        sx, sy = legs[i, K.SHIFT], legs[i, K.SHIFT + 1]
        if sx != 0.0 or sy != 0.0:  # the shifted landing point
            bz, px, py, pz = _landing_point(qpos, rot, plane, c, s, vx, vy, tau, lx + sx, ly + sy)
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
    par, mpar = np.zeros(K.NPAR), np.array([0.0, 0.0, 0.01, 0.008, 0.02, EDGE])
    legs, flags = np.zeros((n, K.NLEG)), np.zeros((n, 3), dtype=np.int64)
    qpos = np.zeros(7 + 3 * n)
    qpos[3] = 1.0
    landing_heights(par, mpar, np.zeros((2, 2)), legs, flags, np.zeros(3), qpos, np.zeros(3), 0.0)


KERNELS = (map_height, level_spot, _landing_point, landing_heights)
