"""Compiled per-step work of the stance force control (numba; control/force_control.py owns the state and explains
it)."""

from __future__ import annotations

import math

import numpy as np

from hexabot_sim.control.kernels import jit, servo

# Scalars `par`.
(DT, WEIGHT, T_IN, T_OUT, S_IN, S_OUT, W_MIN, K_H, I_H, K_T, I_T, STAND, LEVEL, QUAT_ADR, RETURN_TIME, TASK_GAIN,
 L1, L2, L3, FILTER, I_LIMIT, SOFT, G_FEMUR, G_TIBIA, TIBIA_COM, TOUCH_THRESHOLD, EARLY_AFTER, SMOOTH,
 FROM_PLAN, K_F, LIFT, SLOPE_FILTER) = range(32)  # fmt: skip
NPAR = 32
# Per-leg constants `geo` (n, 5).
COS, SIN, HIP_X, HIP_Y, TOUCH_ADR = range(5)
# Per-leg state `state` (n, NSTATE): force-mode blend s, time down, the target's vertical offset and its rate,
# the commanded ground force [N], the weight in the distribution, the foot's body-frame position (x, y, z).
# A foot that touches in its swing after its touch sensor was quiet for EARLY_AFTER is down before the plan says
# (EARLY latched until its stance; UP: time since the foot was last down or touching [s]: a slow lift-off whose
# foot stays on the pad for a while is not a landing).
S, SINCE, DZ, VZ, FORCE, W, X, Y, Z, EARLY, UP, TOUCH = range(12)
NSTATE = 12
# The body's state `body` (NBODY,): the errors (height, two slopes) and their integrals, whether the errors have
# been measured once, the wrench asked for (Fz, Px, Py).
E, IE, STARTED, WRENCH = 0, 3, 6, 7
NBODY = 10


@jit
def solve3(a, b, out):
    """out = a^-1 b for a 3x3 matrix a (Cramer's rule); False if a is singular."""
    c00 = a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1]
    c01 = a[1, 2] * a[2, 0] - a[1, 0] * a[2, 2]
    c02 = a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]
    det = a[0, 0] * c00 + a[0, 1] * c01 + a[0, 2] * c02
    scale = abs(a[0, 0]) + abs(a[1, 1]) + abs(a[2, 2])
    if abs(det) <= 1e-12 * scale * scale * scale or scale == 0.0:
        return False
    inv = np.empty((3, 3))
    inv[0, 0] = c00 / det
    inv[0, 1] = (a[0, 2] * a[2, 1] - a[0, 1] * a[2, 2]) / det
    inv[0, 2] = (a[0, 1] * a[1, 2] - a[0, 2] * a[1, 1]) / det
    inv[1, 0] = c01 / det
    inv[1, 1] = (a[0, 0] * a[2, 2] - a[0, 2] * a[2, 0]) / det
    inv[1, 2] = (a[0, 2] * a[1, 0] - a[0, 0] * a[1, 2]) / det
    inv[2, 0] = c02 / det
    inv[2, 1] = (a[0, 1] * a[2, 0] - a[0, 0] * a[2, 1]) / det
    inv[2, 2] = (a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]) / det
    for i in range(3):
        out[i] = inv[i, 0] * b[0] + inv[i, 1] * b[1] + inv[i, 2] * b[2]
    return True


@jit
def ramp(x, smooth):
    """A weight's ramp at x (0 at x <= 0, 1 at x >= 1): linear, or smoothstep 3 x^2 - 2 x^3 if `smooth` (C1, and
    ramp(1 - x) = 1 - ramp(x): a foot ramping up and one ramping down over the same interval sum to 1)."""
    x = min(1.0, max(0.0, x))
    return x * x * (3.0 - 2.0 * x) if smooth else x


@jit
def normal_matrix(x, y, w):
    """The (3, 3) matrix sum_i w_i a_i a_i^T with a_i = (1, x_i, y_i): A W A^T of the distribution and the plane."""
    a = np.zeros((3, 3))
    for i in range(x.shape[0]):
        a[0, 0] += w[i]
        a[0, 1] += w[i] * x[i]
        a[0, 2] += w[i] * y[i]
        a[1, 1] += w[i] * x[i] * x[i]
        a[1, 2] += w[i] * x[i] * y[i]
        a[2, 2] += w[i] * y[i] * y[i]
    a[1, 0], a[2, 0], a[2, 1] = a[0, 1], a[0, 2], a[1, 2]
    return a


@jit
def distribute(x, y, w, fz, px, py, soft, out):
    """Vertical forces (m,) on the feet at (x, y) that sum to fz with moments sum x f = px, sum y f = py and the
    least weighted norm sum f^2 / w: f = W A^T (A W A^T)^-1 (fz, px, py), A = (1; x; y). With soft > 0 the moments
    are soft: f minimises sum f^2 / w + |A f - b|^2 / r with r = (0, soft, soft), f = W A^T (A W A^T + diag r)^-1 b
    (a foot of small weight is not made to carry a moment the others cannot). Feet that span no plane (fewer than
    3, or in a line) share fz in proportion to w. Returns False in that case."""
    m = x.shape[0]
    a = normal_matrix(x, y, w)
    a[1, 1] += soft
    a[2, 2] += soft
    lam = np.empty(3)
    b = np.array([fz, px, py])
    if m >= 3 and solve3(a, b, lam):
        for i in range(m):
            out[i] = w[i] * (lam[0] + lam[1] * x[i] + lam[2] * y[i])
        return True
    for i in range(m):
        out[i] = fz * w[i] / a[0, 0] if a[0, 0] > 0.0 else fz / max(m, 1)
    return False


@jit
def plane(x, y, z, w, out):
    """Weighted least-squares plane z = a + b x + c y through the points into out[:3]; False if they span none."""
    m = x.shape[0]
    a = normal_matrix(x, y, w)
    r = np.zeros(3)
    for i in range(m):
        r[0] += w[i] * z[i]
        r[1] += w[i] * x[i] * z[i]
        r[2] += w[i] * y[i] * z[i]
    return m >= 3 and solve3(a, r, out)


@jit
def foot(par, q1, q2, q3):
    """The foot centre in the leg's hip frame (x, y, z) and the leg plane's Jacobian block (radial, vertical rows
    by femur, tibia columns): b11 b12 / b21 b22."""
    l1, l2, l3 = par[L1], par[L2], par[L3]
    c2, s2 = math.cos(q2), math.sin(q2)
    c23, s23 = math.cos(q2 + q3), math.sin(q2 + q3)
    rho = l1 + l2 * c2 + l3 * c23
    h = l2 * s2 + l3 * s23
    return math.cos(q1) * rho, math.sin(q1) * rho, -h, -h, -l3 * s23, -(l2 * c2 + l3 * c23), -l3 * c23


@jit
def force_pre(par, geo, state, body, qpos, trims, sensordata, row, down, until, extra):
    """Before the servo step: the feet's measured positions (encoders), each stance foot's weight and force-mode
    blend, the body's height and attitude errors and the wrench they ask for, its distribution over the stance feet
    (state FORCE), and the feed correction `extra` (3 n,) that keeps each foot target's height at the measured
    foot in force mode and returns it to the plan in swing."""
    n = state.shape[0]
    dt = par[DT]
    xs, ys, zs, zp, ws = np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    idx = np.empty(n, dtype=np.int64)
    m = 0
    for i in range(n):
        j = 7 + 3 * i
        hx, hy, hz, _, _, _, _ = foot(par, qpos[j] - trims[3 * i], qpos[j + 1] - trims[3 * i + 1],
                                      qpos[j + 2] - trims[3 * i + 2])  # fmt: skip
        c, s = geo[i, COS], geo[i, SIN]
        state[i, X] = c * hx - s * hy + geo[i, HIP_X]
        state[i, Y] = s * hx + c * hy + geo[i, HIP_Y]
        z_before = state[i, Z] if body[STARTED] != 0.0 else hz
        state[i, Z] = hz
        state[i, TOUCH] = sensordata[int(geo[i, TOUCH_ADR])]
        touching = state[i, TOUCH] > par[TOUCH_THRESHOLD]
        if down[i]:
            state[i, EARLY] = 0.0
        elif touching and state[i, UP] > par[EARLY_AFTER]:
            state[i, EARLY] = 1.0  # the foot met the ground before its planned touchdown: down from now on
        if down[i] or state[i, EARLY] != 0.0:
            state[i, UP] = 0.0
            if down[i] or par[FROM_PLAN] == 0.0:  # FROM_PLAN: an early touch waits at the least weight
                state[i, SINCE] += dt
            state[i, S] = min(1.0, state[i, S] + dt / par[S_IN])
            smooth = par[SMOOTH] != 0.0
            w = min(ramp(state[i, SINCE] / par[T_IN], smooth), ramp(until[i] / par[T_OUT], smooth))
            state[i, W] = max(par[W_MIN], w)
            xs[m], ys[m], zs[m], zp[m], ws[m] = state[i, X], state[i, Y], hz, z_before, state[i, W]
            idx[m] = i
            m += 1
        else:  # UP: time since the foot was last down or touching (a foot still on the ground lands nowhere)
            state[i, UP] = 0.0 if touching else state[i, UP] + dt
            state[i, SINCE] = 0.0
            state[i, S] = max(0.0, state[i, S] - dt / par[S_OUT])
            state[i, W] = 0.0
            state[i, FORCE] = 0.0
    # The errors move with the feet that are down (the same weights now and a step ago: a foot that lands or lifts
    # does not make them jump) and are drawn to the stance plane's over FILTER (the height) and SLOPE_FILTER (the
    # slopes: on uneven ground the plane's slope steps with the set of feet; the IMU's replace them when levelling).
    fit, before = np.empty(3), np.empty(3)
    if plane(xs[:m], ys[:m], zs[:m], ws[:m], fit) and plane(xs[:m], ys[:m], zp[:m], ws[:m], before):
        err = np.empty(3)
        err[0] = fit[0] + par[STAND]  # > 0: the body is low over its feet
        err[1], err[2] = fit[1], fit[2]  # > 0: the feet ahead (left) stand high: lift the body's front (left)
        for k in range(3):
            tau = par[FILTER] if k == 0 else par[SLOPE_FILTER]
            pull = dt / (tau + dt) if body[STARTED] != 0.0 else 1.0
            body[E + k] += (fit[k] - before[k]) + pull * (err[k] - body[E + k] - (fit[k] - before[k]))
        if par[LEVEL] != 0.0:
            a = int(par[QUAT_ADR])
            qw, qx, qy, qz = sensordata[a], sensordata[a + 1], sensordata[a + 2], sensordata[a + 3]
            roll = math.atan2(2 * (qw * qx + qy * qz), 1 - 2 * (qx * qx + qy * qy))
            pitch = math.asin(max(-1.0, min(1.0, 2 * (qw * qy - qz * qx))))
            body[E + 1], body[E + 2] = math.tan(pitch), -math.tan(roll)
        lim = par[I_LIMIT]
        for k in range(3):
            body[IE + k] = max(-lim, min(lim, body[IE + k] + body[E + k] * dt))
        body[STARTED] = 1.0
    body[WRENCH] = par[WEIGHT] + par[K_H] * body[E] + par[I_H] * body[IE]
    for k in range(1, 3):
        body[WRENCH + k] = par[K_T] * body[E + k] + par[I_T] * body[IE + k]
    f = np.empty(m)
    distribute(xs[:m], ys[:m], ws[:m], body[WRENCH], body[WRENCH + 1], body[WRENCH + 2], par[SOFT], f)
    for k in range(m):
        state[idx[k], FORCE] = max(0.0, f[k])
    for i in range(n):
        dz = state[i, DZ]
        if down[i]:  # the target's height follows the measured foot as force mode takes over
            new = dz + state[i, S] * (state[i, Z] - row[3 * i + 2] - dz)
        else:  # back to the plan, LIFT above it
            new = par[LIFT] + (dz - par[LIFT]) * max(0.0, 1.0 - dt / par[RETURN_TIME])
        state[i, VZ] = (new - dz) / dt
        state[i, DZ] = new
        extra[3 * i + 2] = par[TASK_GAIN] * new + state[i, VZ]


@jit
def force_post(par, state, qpos, trims, q_cmd, dq, kp, ctrl):
    """After the servo step: for each leg in force mode (blend s > 0) the position command's height snaps to the
    measured foot's (a share s of the gap), the servo's vertical foot force is replaced by the commanded one
    (a share s) through the position command's offset tau / kp, and the velocity command loses its vertical
    part (a share s): the servos then hold the foot horizontally and push it down with the commanded force."""
    n = state.shape[0]
    nq = 3 * n
    for i in range(n):
        s = state[i, S]
        if s <= 0.0:
            continue
        j = 3 * i
        q1, q2, q3 = qpos[7 + j] - trims[j], qpos[8 + j] - trims[j + 1], qpos[9 + j] - trims[j + 2]
        _, _, zq, b11, b12, b21, b22 = foot(par, q1, q2, q3)
        _, _, zc, c11, c12, c21, c22 = foot(par, q_cmd[j], q_cmd[j + 1], q_cmd[j + 2])
        detc = c11 * c22 - c12 * c21
        det = b11 * b22 - b12 * b21
        if abs(det) < 1e-6 or abs(detc) < 1e-6:
            continue
        gap = s * (zq - zc)  # snap: (d2, d3) = C^-1 (0, gap)
        q_cmd[j + 1] += -c12 * gap / detc
        q_cmd[j + 2] += c11 * gap / detc
        # The leg's own weight as generalised forces (femur, tibia): G_FEMUR = m_femur g a (its COM a along it),
        # G_TIBIA = m_tibia g; what the servos exert beyond holding it up reaches the ground.
        c2, c23 = math.cos(q2), math.cos(q2 + q3)
        g3 = par[G_TIBIA] * par[TIBIA_COM] * c23
        g2 = par[G_FEMUR] * c2 + par[G_TIBIA] * par[L2] * c2 + g3
        t2 = kp[j + 1] * (q_cmd[j + 1] - q2) + g2
        t3 = kp[j + 2] * (q_cmd[j + 2] - q3) + g3
        fz = (-b12 * t2 + b11 * t3) / det  # (F_r, F_z) = B^-T (t2, t3): the servo's foot force on the ground, z
        # The commanded force, corrected by K_F times its error against the touch sensor's (a force loop around the
        # servo's open-loop push, which its damping and the pad make lag).
        push = state[i, FORCE] + par[K_F] * (state[i, FORCE] - state[i, TOUCH])
        add = -s * (fz + push)
        ctrl[j] = q_cmd[j] + trims[j]
        ctrl[j + 1] = q_cmd[j + 1] + trims[j + 1] + b21 * add / kp[j + 1]
        ctrl[j + 2] = q_cmd[j + 2] + trims[j + 2] + b22 * add / kp[j + 2]
        vz = s * (b21 * dq[j + 1] + b22 * dq[j + 2])  # the commanded vertical foot speed, removed
        ctrl[nq + j + 1] = dq[j + 1] + b12 * vz / det
        ctrl[nq + j + 2] = dq[j + 2] - b11 * vz / det


@jit
def force_step(par, geo, state, body, qpos, trims, sensordata, row, down, until, feed, k, q_cmd, dq, kp, ctrl):
    """One control step of the planned walking controller with force control, in one call: force_pre, the servo
    step toward `feed` (3 n,) plus its correction (kernels.servo), force_post."""
    extra = np.zeros(feed.shape[0])  # force_pre sets the z entries only
    force_pre(par, geo, state, body, qpos, trims, sensordata, row, down, until, extra)
    for i in range(feed.shape[0]):
        extra[i] += feed[i]
    servo(k, qpos, trims, q_cmd, dq, extra, par[DT], ctrl)
    force_post(par, state, qpos, trims, q_cmd, dq, kp, ctrl)


@jit
def ground_down(flags, stance_modes, near, state, out):
    """out[i] = the ground controller's leg i is down: its mode (flags[i, 0]) STANCE or EARLY (`stance_modes`) and
    grounded (flags[i, 2]). A leg in mode `near` (NEAR: touched close to its swing's end, which it goes on to) is an
    early touch (state EARLY, as the planned controller's): in force mode, its swing's height the reference."""
    for i in range(flags.shape[0]):
        mode = flags[i, 0]
        grounded = flags[i, 2] != 0
        out[i] = (mode == stance_modes[0] or mode == stance_modes[1]) and grounded
        if mode == near and grounded:
            state[i, EARLY] = 1.0


def compile_all() -> None:
    """Calls each kernel once on arrays of the types the controller passes."""
    n = 6
    par = np.ones(NPAR)
    geo, state, body = np.zeros((n, 5)), np.zeros((n, NSTATE)), np.zeros(NBODY)
    qpos = np.zeros(7 + 3 * n)
    qpos[7:] = np.tile([0.0, 0.5, 1.0], n)
    trims, extra, row = np.zeros(3 * n), np.zeros(3 * n), np.zeros(3 * n)
    force_pre(par, geo, state, body, qpos, trims, np.zeros(8), row, np.ones(n, dtype=np.bool_), np.ones(n), extra)
    force_post(par, state, qpos, trims, np.zeros(3 * n), np.zeros(3 * n), np.ones(3 * n), np.zeros(6 * n))
    ground_down(np.zeros((n, 3), dtype=np.int64), np.zeros(2, dtype=np.int64), 4, state, np.zeros(n, dtype=np.bool_))
    from hexabot_sim.control import resolved_rate
    from hexabot_sim.kinematics.leg import LegGeometry

    gains = resolved_rate.ResolvedRateGains(max_joint_acceleration=200.0)
    k = np.array(resolved_rate.step_constants(LegGeometry(), gains, (-1.0, -1.0, 0.0), (1.0, 1.0, 2.0)))
    force_step(par, geo, state, body, qpos, trims, np.zeros(8), row, np.ones(n, dtype=np.bool_), np.ones(n), extra, k,
               np.zeros(3 * n), np.zeros(3 * n), np.ones(3 * n), np.zeros(6 * n))  # fmt: skip


KERNELS = (solve3, ramp, normal_matrix, distribute, plane, foot, force_pre, force_post, force_step, ground_down)
