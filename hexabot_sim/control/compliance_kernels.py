"""Compiled per-step work of the legs' admittance (numba; control/compliance.py owns the state and explains it)."""

from __future__ import annotations

import numpy as np

from hexabot_sim.control.kernels import jit

# Scalars `par` of the kernel.
STIFFNESS, MASS, DAMPING, ALPHA, DT, LIMIT, TASK_GAIN, PRELOAD = range(8)
NPAR = 8
# Per-leg constants `geo` (n, 5) and state `state` (n, 3).
COS, SIN, HIP_X, HIP_Y, TOUCH_ADR = range(5)
DZ, VZ, FORCE = range(3)


@jit
def reference(x, y, total, out):
    """Least-norm forces (n,) on the feet at (x, y) (n,) that carry `total` with no moment about the origin:
    F = A^T (A A^T)^-1 (total, 0, 0), A = (1; x; y). Equal shares where the feet span no plane."""
    n = x.shape[0]
    sx = sy = sxx = sxy = syy = 0.0
    for i in range(n):
        sx += x[i]
        sy += y[i]
        sxx += x[i] * x[i]
        sxy += x[i] * y[i]
        syy += y[i] * y[i]
    # A A^T = [[n, sx, sy], [sx, sxx, sxy], [sy, sxy, syy]]; (A A^T)^-1 (1, 0, 0) is its first column / det.
    c0 = sxx * syy - sxy * sxy
    c1 = sy * sxy - sx * syy
    c2 = sx * sxy - sy * sxx
    det = n * c0 + sx * c1 + sy * c2
    if n < 3 or det <= 1e-9 * max(1.0, n * (sxx + syy)) ** 2:
        for i in range(n):
            out[i] = total / max(n, 1)
        return
    for i in range(n):
        out[i] = total * (c0 + c1 * x[i] + c2 * y[i]) / det


@jit
def admittance(par, geo, state, sensordata, row, stance, extra):
    """One step of every leg's admittance: filters the touch sensors, sets the stance feet's reference forces from
    the foot targets `row` (3 n,) (hip frames) and the plan's `stance` (n,), advances each leg's dz and writes the
    resolved-rate feed correction into `extra` (3 n,) (only the z entries)."""
    n = state.shape[0]
    dt = par[DT]
    xs, ys, ref = np.empty(n), np.empty(n), np.empty(n)
    idx = np.empty(n, dtype=np.int64)
    total = 0.0
    m = 0
    for i in range(n):
        state[i, FORCE] += par[ALPHA] * (sensordata[int(geo[i, TOUCH_ADR])] - state[i, FORCE])
        total += state[i, FORCE]
        if stance[i]:
            c, s = geo[i, COS], geo[i, SIN]
            x, y = row[3 * i], row[3 * i + 1]
            xs[m] = c * x - s * y + geo[i, HIP_X]
            ys[m] = s * x + c * y + geo[i, HIP_Y]
            idx[m] = i
            m += 1
    error = np.zeros(n)
    if par[PRELOAD] > 0.0:  # a preloaded spring in stance and swing alike
        for i in range(n):
            error[i] = state[i, FORCE] - par[PRELOAD]
    else:  # the force distribution of the stance feet
        reference(xs[:m], ys[:m], total, ref)
        for j in range(m):
            error[idx[j]] = state[idx[j], FORCE] - ref[j]
    k, mass, d, limit = par[STIFFNESS], par[MASS], par[DAMPING], par[LIMIT]
    for i in range(n):
        # Semi-implicit Euler: velocity first, then the offset with the new velocity.
        state[i, VZ] += (error[i] - d * state[i, VZ] - k * state[i, DZ]) / mass * dt
        dz = state[i, DZ] + state[i, VZ] * dt
        if dz > limit or dz < -limit:
            dz = max(-limit, min(limit, dz))
            state[i, VZ] = (dz - state[i, DZ]) / dt
        state[i, DZ] = dz
        extra[3 * i + 2] = par[TASK_GAIN] * dz + state[i, VZ]


def warm_up() -> None:
    """Compiles the kernels (or loads them from numba's cache) for the argument types the controller passes."""
    n = 6
    geo, state, extra = np.zeros((n, 5)), np.zeros((n, 3)), np.zeros(3 * n)
    par = np.ones(NPAR)
    admittance(par, geo, state, np.zeros(8), np.ones(3 * n), np.ones(n, dtype=np.bool_), extra)
