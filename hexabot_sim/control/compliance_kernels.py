"""Compiled per-step work of the legs' admittance (numba; control/compliance.py owns the state and explains it)."""

from __future__ import annotations

import numpy as np

from hexabot_sim.control.kernels import jit

# Scalars `par` of the kernel.
DAMPING, STIFFNESS, ALPHA, DT, LIMIT, TASK_GAIN, RETURN_TIME, RAMP_TIME, STANCE_TIME, LEAST_WEIGHT = range(10)
NPAR = 10
# Per-leg constants `geo` (n, 5) and state `state` (n, 4).
COS, SIN, HIP_X, HIP_Y, TOUCH_ADR = range(5)
DZ, VZ, FORCE, TIMER = range(4)


@jit
def reference(x, y, w, total, out):
    """Forces (n,) on the feet at (x, y) (n,) that carry `total` with no moment about the origin and the least
    weighted norm sum F_i^2 / w_i: F = W A^T (A W A^T)^-1 (total, 0, 0), A = (1; x; y), W = diag(w) (w = 1:
    the least-norm distribution). Shares in proportion to w where the feet span no plane."""
    n = x.shape[0]
    s0 = sx = sy = sxx = sxy = syy = 0.0
    for i in range(n):
        s0 += w[i]
        sx += w[i] * x[i]
        sy += w[i] * y[i]
        sxx += w[i] * x[i] * x[i]
        sxy += w[i] * x[i] * y[i]
        syy += w[i] * y[i] * y[i]
    # A W A^T = [[s0, sx, sy], [sx, sxx, sxy], [sy, sxy, syy]]; its inverse's first column is (c0, c1, c2) / det.
    c0 = sxx * syy - sxy * sxy
    c1 = sy * sxy - sx * syy
    c2 = sx * sxy - sy * sxx
    det = s0 * c0 + sx * c1 + sy * c2
    if n < 3 or det <= 1e-9 * max(1e-12, s0 * (sxx + syy)) ** 2:
        for i in range(n):
            out[i] = total * w[i] / s0 if s0 > 0.0 else total / max(n, 1)
        return
    for i in range(n):
        out[i] = total * w[i] * (c0 + c1 * x[i] + c2 * y[i]) / det


@jit
def admittance(par, geo, state, sensordata, row, stance, extra):
    """One step of every leg's admittance: filters the touch sensors, sets the stance feet's reference forces from
    the foot targets `row` (3 n,) (hip frames) and the plan's `stance` (n,), advances each leg's dz and writes the
    resolved-rate feed correction into `extra` (3 n,) (only the z entries)."""
    n = state.shape[0]
    dt = par[DT]
    xs, ys, ws, ref = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    idx = np.empty(n, dtype=np.int64)
    total = 0.0
    m = 0
    for i in range(n):
        state[i, FORCE] += par[ALPHA] * (sensordata[int(geo[i, TOUCH_ADR])] - state[i, FORCE])
        total += state[i, FORCE]
        if stance[i]:
            state[i, TIMER] += dt
            c, s = geo[i, COS], geo[i, SIN]
            x, y = row[3 * i], row[3 * i + 1]
            xs[m] = c * x - s * y + geo[i, HIP_X]
            ys[m] = s * x + c * y + geo[i, HIP_Y]
            # Load transfer: a foot's weight ramps up after touchdown and down before lift-off.
            into = state[i, TIMER] / par[RAMP_TIME]
            left = (par[STANCE_TIME] - state[i, TIMER]) / par[RAMP_TIME]
            ws[m] = max(par[LEAST_WEIGHT], min(1.0, into, left))
            idx[m] = i
            m += 1
        else:
            state[i, TIMER] = 0.0
    reference(xs[:m], ys[:m], ws[:m], total, ref)
    limit = par[LIMIT]
    for i in range(n):
        state[i, VZ] = -state[i, DZ] / par[RETURN_TIME]  # swing: back to the plan
    for j in range(m):
        i = idx[j]
        # D dz/dt + K dz = F - F_ref: an overloaded foot yields (dz > 0 lifts it), an underloaded one presses.
        state[i, VZ] = (state[i, FORCE] - ref[j] - par[STIFFNESS] * state[i, DZ]) / par[DAMPING]
    for i in range(n):
        dz = state[i, DZ] + state[i, VZ] * dt
        if dz > limit or dz < -limit:
            dz = max(-limit, min(limit, dz))
            state[i, VZ] = (dz - state[i, DZ]) / dt
        state[i, DZ] = dz
        extra[3 * i + 2] = par[TASK_GAIN] * dz + state[i, VZ]


def compile_all() -> None:
    """Calls each kernel once on arrays of the types the controller passes (kernels.warm_up calls this, with its
    fallback to compiling in memory when numba's cache cannot be used)."""
    n = 6
    geo, state, extra = np.zeros((n, 5)), np.zeros((n, 4)), np.zeros(3 * n)
    par = np.ones(NPAR)
    admittance(par, geo, state, np.zeros(8), np.ones(3 * n), np.ones(n, dtype=np.bool_), extra)


KERNELS = (reference, admittance)
