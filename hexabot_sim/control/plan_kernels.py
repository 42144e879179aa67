"""Compiled once-a-chunk work of the walking controllers (numba): the gait plan's maths and the rolling feet's offsets.

control/gait.py (GaitPlanner) owns the planner's state and explains the plan; control/walker.py the rolling feet.
Planning a chunk was fixed per-call overhead of numpy on tiny arrays (a Python loop per leg and per stance or
swing segment): ~1.6 ms a chunk of 50 steps, as much as the 50 physics steps it drives. Here it is a loop over
rows in plain floats, so a kernel is the one source of the maths: GaitPlanner's public functions call these.

No kernel knows the leg count (it comes from the arrays' shapes), as in control/kernels.py, whose `jit` (numba,
cached on disk; NUMBA_DISABLE_JIT=1 runs this source as plain Python) compiles them.

The planner's state, in arrays:
- `clock` (NCLOCK,): the gait clock's start [s], period [s], duty, whether a gait switch happened (1.0) and the
  step height [m], stance time [s] and swing time [s];
- `timing` (n, NTIMING): per leg the gait's phase offset [cycles], the swing under way at the last switch
  [lift-off, touchdown) [s] (-inf: none), the time before which it does not lift under the new clock [s] and its
  latest touchdown [s];
- a chunk's segments `seg` (n, rows, NSEG), `count` (n,): per leg the runs of rows of one mode (stance or
  swing): first row, end row (exclusive), stance (1.0), the time its state starts from, the time of the event
  that ends it (the chunk's last time for the last), a swing's touchdown time and its length [s], and the two
  times at which the command's ramp factor is asked (QUERY: stance: its end; swing: the touchdown and a quarter
  stance after it).
"""

from __future__ import annotations

import math

import numpy as np

from hexabot_sim.control.gait import FINISH, FINISH_LIFT, NO_LIFT, NTIMING, OFFSET, TOUCHDOWN
from hexabot_sim.control.kernels import jit
from hexabot_sim.kinematics import legged

# Scalars of `clock`.
START, PERIOD, DUTY, SWITCHED, STEP_HEIGHT, STANCE_TIME, SWING_TIME = range(7)
NCLOCK = 7
LANDED: float = 1e-9  # [cycles] a phase this close below 1 is at its touchdown (rounding in phase(); 1 ns at 1 s)
# Columns of `seg`.
FIRST, END, STANCE, T_STATE, T_END, T_TOUCHDOWN, SWING_LENGTH, QUERY = 0, 1, 2, 3, 4, 5, 6, 7  # QUERY: two
NSEG = 9
# Columns of the rolling feet's `geo`: the leg's link lengths l1, l2, l3 [m] and the foot's radius [m].
L1, L2, L3, RADIUS = range(4)

pitch_of = jit(legged.pitch_of)


@jit
def phase(t, clock, timing, leg):
    """Gait phase in [0, 1) of the leg at t; stance while it is below the duty."""
    return ((t - clock[START]) / clock[PERIOD] + timing[leg, OFFSET]) % 1.0


@jit
def in_stance(t, clock, timing, leg):
    """True where the plan has the foot on the ground (GaitPlanner.in_stance explains the rules)."""
    return _stance(t, phase(t, clock, timing, leg), clock, timing, leg)


@jit
def _stance(t, frac, clock, timing, leg):
    """in_stance at t, the leg's phase there being frac."""
    lift_time = t - (frac - clock[DUTY]) * clock[PERIOD]
    # A phase within LANDED of 1 is a touchdown, as next_touchdown's: at a hand-over the lifting legs' phase (offset
    # added) can round up to the duty while the landing legs' rounds down below 1, and no foot was down (a tripod at
    # period 7.9135634 s, 1 fs before its first hand-over).
    swing = clock[DUTY] <= frac < 1.0 - LANDED and lift_time >= clock[START] - 1e-9
    if clock[SWITCHED] != 0.0:  # the previous gait's swings finish; the new gait's that would lift before are skipped
        swing = swing and lift_time >= timing[leg, NO_LIFT] - 1e-9
        swing = swing or timing[leg, FINISH_LIFT] <= t < timing[leg, FINISH]
    return not swing


@jit
def _swing_fraction(t, frac, stance, clock, timing, leg):
    """How far the leg's swing has come at t, in [0, 1) (its phase being frac); 0 in stance."""
    s = 0.0 if stance else (frac - clock[DUTY]) / (1.0 - clock[DUTY])
    lift, land = timing[leg, FINISH_LIFT], timing[leg, FINISH]
    if clock[SWITCHED] != 0.0 and lift <= t < land:  # a swing of the gait before a switch
        s = (t - lift) / (land - lift)
    return s


@jit
def next_touchdown(t, clock, timing, leg):
    """First time > t at which the leg's phase wraps to 0 (touchdown), or the touchdown of a swing of the gait before
    a switch."""
    if timing[leg, FINISH_LIFT] <= t < timing[leg, FINISH]:
        return timing[leg, FINISH]
    start, period, offset = clock[START], clock[PERIOD], timing[leg, OFFSET]
    cycles = (t - start) / period + offset
    return start + (math.floor(cycles + LANDED) + 1 - offset) * period


@jit
def event_time(t0, t1, clock, timing, leg):
    """Time of the leg's lift-off (phase = duty) or touchdown (phase = 0) in (t0, t1]."""
    if t0 < timing[leg, FINISH] <= t1 + 1e-12:  # a swing of the gait before a switch lands
        return timing[leg, FINISH]
    start, period, offset = clock[START], clock[PERIOD], timing[leg, OFFSET]
    base = (t0 - start) / period + offset
    for boundary in (clock[DUTY], 1.0):
        k = math.floor(base - boundary) + 1  # next crossing of phase == boundary (mod 1)
        t_cross = start + (k + boundary - offset) * period
        if t0 < t_cross <= t1 + 1e-12:
            return t_cross
    return max(t0, start)  # the gait clock starting inside the step


@jit
def stance_point(vx, vy, w, x0, y0, tau):
    """Body-frame position (x, y) of a ground-fixed point that is at (x0, y0) now, tau [s] later, under the twist.

    p(tau) = R(-w tau) p0 - [[S, C], [-C, S]] v with S = sin(w tau) / w and C = (1 - cos(w tau)) / w: the solution of
    dp/dtau = -v - w x p written without the centre of rotation (-vy / w, vx / w), which is ill-conditioned for the
    tiny yaw rates heading hold can ask for (w = 1e-19 put it 1e18 m away). S and C are evaluated as tau sinc(w tau)
    and (w tau^2 / 2) sinc^2(w tau / 2), with no division by w: where w tau underflows to 0 (w = 5e-324) they are the
    straight-line tau and 0, not 0 and 0.
    """
    if w == 0.0:
        return x0 - vx * tau, y0 - vy * tau
    angle = w * tau
    c, s = math.cos(angle), math.sin(angle)
    half = 0.5 * angle
    sinc_half = math.sin(half) / half if half != 0.0 else 1.0
    big_s = tau * (s / angle if angle != 0.0 else 1.0)
    big_c = 0.5 * w * tau * tau * sinc_half * sinc_half
    return c * x0 + s * y0 - (big_s * vx + big_c * vy), -s * x0 + c * y0 + (big_c * vx - big_s * vy)


@jit
def hermite(p0, v0, p1, v1, duration, s):
    """Cubic Hermite of one coordinate from (p0, v0) to (p1, v1) over `duration` [s], at fraction s; and its rate.

    h00 p0 + h10 T v0 + h01 p1 + h11 T v1 with h00 = 1 - h01, h01 = 3 s^2 - 2 s^3, h10 = s^3 - 2 s^2 + s,
    h11 = s^3 - s^2.
    """
    s2 = s * s
    h11 = s2 * (s - 1.0)
    h01 = s2 - 2.0 * h11  # 3 s^2 - 2 s^3
    h10 = h11 - s2 + s  # s^3 - 2 s^2 + s
    d01 = 6.0 * s - 6.0 * s2
    rate = (d01 * (p1 - p0)) / duration + (3.0 * s2 - 4.0 * s + 1.0) * v0 + (3.0 * s2 - 2.0 * s) * v1
    return p0 + h01 * (p1 - p0) + (duration * h10) * v0 + (duration * h11) * v1, rate


def quintic(u):
    """Quintic Hermite basis at fractions u (floats or numpy arrays): the weights of (p1 - p0, T v0, T v1, T^2 a0) in
    the position, and their first and second derivatives in u; zero acceleration at u = 1 (swing="quintic")."""
    u2 = u * u
    u3 = u2 * u
    h = (u3 * (10 - 15 * u + 6 * u2), u - u3 * (6 - 8 * u + 3 * u2), -u3 * (4 - 7 * u + 3 * u2),
         0.5 * u2 - u3 * (1.5 - 1.5 * u + 0.5 * u2))  # fmt: skip
    d = (30 * u2 * (1 - u) ** 2, 1 - u2 * (18 - 32 * u + 15 * u2), -u2 * (12 - 28 * u + 15 * u2),
         u - u2 * (4.5 - 6 * u + 2.5 * u2))  # fmt: skip
    dd = (60 * u - u2 * (180 - 120 * u), -36 * u + u2 * (96 - 60 * u), -24 * u + u2 * (84 - 60 * u),
          1 - 9 * u + u2 * (18 - 10 * u))  # fmt: skip
    return h, d, dd


_quintic = jit(quintic)


@jit
def hermite5(p0, v0, a0, p1, v1, duration, u):
    """Quintic Hermite of one coordinate from (p0, v0, a0) to (p1, v1, zero acceleration) over `duration` [s], at
    fraction u; and its rate and acceleration."""
    h, d, dd = _quintic(u)
    t0, t1, t2, t3 = p1 - p0, duration * v0, duration * v1, duration * duration * a0
    pos = p0 + h[0] * t0 + h[1] * t1 + h[2] * t2 + h[3] * t3
    rate = (d[0] * t0 + d[1] * t1 + d[2] * t2 + d[3] * t3) / duration
    return pos, rate, (dd[0] * t0 + dd[1] * t1 + dd[2] * t2 + dd[3] * t3) / (duration * duration)


@jit
def stance_points(vx, vy, w, start, tau, out):
    """stance_point of every start (m, 2) at every tau (k,) into out (m, k, 2)."""
    for i in range(start.shape[0]):
        for k in range(tau.shape[0]):
            out[i, k, 0], out[i, k, 1] = stance_point(vx, vy, w, start[i, 0], start[i, 1], tau[k])


@jit
def flags(times, clock, timing, stance, swing_s):
    """The stance flags (n_t, n) at times (n_t,) and, into swing_s (n_t, n) unless it is empty, the swings'
    fractions."""
    fractions = swing_s.shape[0] > 0
    for k in range(times.shape[0]):
        t = times[k]
        for leg in range(timing.shape[0]):
            frac = phase(t, clock, timing, leg)
            stance[k, leg] = down = _stance(t, frac, clock, timing, leg)
            if fractions:
                swing_s[k, leg] = _swing_fraction(t, frac, down, clock, timing, leg)


@jit
def fractions(times, stance, clock, timing, out):
    """The swings' fractions (n_t, n) at times (n_t,) with the given stance flags; and the phases (the same shape) into
    `out` where stance is empty."""
    phases = stance.shape[0] == 0
    for k in range(times.shape[0]):
        for leg in range(timing.shape[0]):
            frac = phase(times[k], clock, timing, leg)
            out[k, leg] = frac if phases else _swing_fraction(times[k], frac, stance[k, leg], clock, timing, leg)


@jit
def segments(times, clock, timing, seg, count):
    """Each leg's runs of one mode over the chunk's rows `times` (n + 1,) into seg and count; records touchdowns.

    Row 0 is the state the chunk starts from; the first run covers rows 1 to the first change of mode. A run ends
    at the lift-off or touchdown between its last row and the next; the state continues from that event.
    """
    n1 = times.shape[0]
    for leg in range(timing.shape[0]):
        mode = in_stance(times[0], clock, timing, leg)
        first, t_state, j = 1, times[0], 0
        for end in range(1, n1 + 1):
            if end < n1:
                t = times[end]
                if _stance(t, phase(t, clock, timing, leg), clock, timing, leg) == mode:  # in_stance, inlined
                    continue
            row = seg[leg, j]
            row[FIRST], row[END], row[STANCE], row[T_STATE] = first, end, mode, t_state
            if not mode:  # a swing: to its touchdown, over the swing time of its own gait
                touchdown = next_touchdown(t_state, clock, timing, leg)
                length = clock[SWING_TIME]
                if touchdown == timing[leg, FINISH]:  # a swing of the gait before a switch
                    length = timing[leg, FINISH] - timing[leg, FINISH_LIFT]
                row[T_TOUCHDOWN], row[SWING_LENGTH] = touchdown, length
            if end < n1:  # a phase event between rows end - 1 and end
                t_state = event_time(times[end - 1], times[end], clock, timing, leg)
                mode = not mode
                if mode:
                    timing[leg, TOUCHDOWN] = t_state
            row[T_END] = t_state if end < n1 else times[n1 - 1]
            row[QUERY], row[QUERY + 1] = row[T_END], row[T_END]
            if not row[STANCE]:
                row[QUERY], row[QUERY + 1] = row[T_TOUCHDOWN], row[T_TOUCHDOWN] + 0.25 * clock[STANCE_TIME]
            first, j = end, j + 1
        count[leg] = j


@jit
def _warp(t, times, s, tau_rows):
    """Warped time tau(t) (the integral of the ramp factor s over the chunk, trapezoids on its rows) at t in it."""
    dt = times[1] - times[0]
    k = min(max(int((t - times[0]) / dt), 0), times.shape[0] - 2)
    f = t - (times[0] + k * dt)
    s_t = s[k] + (s[k + 1] - s[k]) * f / dt
    return tau_rows[k] + 0.5 * f * (s[k] + s_t)


@jit
def targets(
    cmd, times, s, warped, clock, timing, neutral, seg, count, factors, pos, vel, acc, quintic, aim, aimed, out
):
    """The chunk's foot targets (n + 1, n_legs, 3) into out, from the segments; advances pos (n, 3), vel (n, 2) and
    acc (n, 2) (the planar acceleration a quintic swing starts from; a stance's is taken as zero).

    cmd: (vx, vy, yaw rate). With `warped`, s (n + 1,) is the command's ramp factor at the rows and factors
    (n, rows, 2) its values at each segment's QUERY times: the twist s(t) cmd moves ground-fixed points along cmd's
    paths in the warped time tau = integral of s dt. A stance target is ground-fixed; a swing follows a cubic
    Hermite (with `quintic`, a quintic one that also starts from the acceleration and ends with none) in the ground
    plane from the state at lift-off to the touchdown point (aim (n, 2), chosen at lift-off,
    where the next stance is centred on the neutral point: half a stance of warped time before it), lifted by
    h sin^2(pi s). Each run's end state (at the event, or the chunk's last time) starts the next.
    """
    vx, vy, w = cmd[0], cmd[1], cmd[2]
    n1 = times.shape[0]
    tau_rows = np.empty(n1)  # warped time of the rows from row 0
    tau_rows[0] = 0.0
    for k in range(1, n1):
        if warped:
            tau_rows[k] = tau_rows[k - 1] + 0.5 * (s[k] + s[k - 1]) * (times[1] - times[0])
        else:
            tau_rows[k] = times[k] - times[0]
    height, stance_time = clock[STEP_HEIGHT], clock[STANCE_TIME]
    for leg in range(neutral.shape[0]):
        px, py, ux, uy, ax, ay = pos[leg, 0], pos[leg, 1], vel[leg, 0], vel[leg, 1], acc[leg, 0], acc[leg, 1]
        out[0, leg, 0], out[0, leg, 1], out[0, leg, 2] = px, py, pos[leg, 2]
        z = neutral[leg, 2]
        for j in range(count[leg]):
            row = seg[leg, j]
            first, end, t_state, t_end = int(row[FIRST]), int(row[END]), row[T_STATE], row[T_END]
            f_end, f_aim = 1.0, 1.0
            if warped:
                f_end, f_aim = factors[leg, j, 0], factors[leg, j, 1]
            if row[STANCE]:  # a ground-fixed point, from the state at t_state
                tau0 = _warp(t_state, times, s, tau_rows) if warped else t_state - times[0]
                for k in range(first, end):
                    out[k, leg, 0], out[k, leg, 1] = stance_point(vx, vy, w, px, py, tau_rows[k] - tau0)
                    out[k, leg, 2] = z
                tau = (_warp(t_end, times, s, tau_rows) if warped else t_end - times[0]) - tau0
                x, y = stance_point(vx, vy, w, px, py, tau)
                px, py, ux, uy = x, y, f_end * (-vx + w * y), f_end * (-vy - w * x)
                ax = ay = 0.0
                continue
            # A swing: the landing point is chosen at lift-off (a swing continued from the last chunk keeps its own).
            touchdown, length = row[T_TOUCHDOWN], row[SWING_LENGTH]
            if t_state > times[0] or not aimed[leg]:
                tau = -0.5 * (f_aim * stance_time)
                aim[leg, 0], aim[leg, 1] = stance_point(vx, vy, w, neutral[leg, 0], neutral[leg, 1], tau)
                aimed[leg] = True
            tx, ty = aim[leg, 0], aim[leg, 1]
            tu, tv = f_end * (-vx + w * ty), f_end * (-vy - w * tx)  # the stance velocity at the touchdown
            duration = touchdown - t_state
            for k in range(first, end):
                u = (times[k] - t_state) / duration
                if quintic:
                    out[k, leg, 0] = hermite5(px, ux, ax, tx, tu, duration, u)[0]
                    out[k, leg, 1] = hermite5(py, uy, ay, ty, tv, duration, u)[0]
                else:
                    out[k, leg, 0] = hermite(px, ux, tx, tu, duration, u)[0]
                    out[k, leg, 1] = hermite(py, uy, ty, tv, duration, u)[0]
                lift = min(max((times[k] - (touchdown - length)) / length, 0.0), 1.0)
                out[k, leg, 2] = z + height * math.sin(math.pi * lift) ** 2
            u = (t_end - t_state) / duration
            if quintic:
                px, ux, ax = hermite5(px, ux, ax, tx, tu, duration, u)
                py, uy, ay = hermite5(py, uy, ay, ty, tv, duration, u)
            else:
                px, ux = hermite(px, ux, tx, tu, duration, u)
                py, uy = hermite(py, uy, ty, tv, duration, u)
        out[n1 - 1, leg, 0], out[n1 - 1, leg, 1] = px, py  # the state at the chunk's last time
        pos[leg, 0], pos[leg, 1], pos[leg, 2] = px, py, out[n1 - 1, leg, 2]
        vel[leg, 0], vel[leg, 1] = ux, uy
        acc[leg, 0], acc[leg, 1] = ax, ay


@jit
def hip_targets(targets, rot, hips, dz, stance, swing_s, geo, state, was, hip):
    """The chunk's foot-centre targets in each hip frame, R^T (p - hip), with the rolling feet's offsets, into hip.

    targets (n + 1, n_legs, 3) body frame; rot (n_legs, 3, 3) hip -> body; hips (n_legs, 3). WalkingController's
    _pitch_dz explains the offsets. Per leg, in stance: the sum of r dtheta e_r since touchdown (e_r the radial
    direction at the middle of each step, theta = q2 + q3 the foot's pitch at the shifted target, iterated once);
    in swing: the shift reached at lift-off, fading out over the first half (smoothstep). The pitch is taken at the
    targets' height plus dz (n_legs,). `state` (n_legs, 4): the offset of the last row and the offset at the last
    lift-off (x, y) [m], `was` (n_legs,) the last row's stance: read from the previous chunk (whose last row is
    this one's row 0) and updated.
    """
    n = targets.shape[0] - 1
    for k in range(n + 1):
        for leg in range(targets.shape[1]):
            for i in range(3):
                acc = 0.0
                for j in range(3):
                    acc += rot[leg, j, i] * (targets[k, leg, j] - hips[leg, j])
                hip[k, leg, i] = acc
    l1, l2, l3, radius = geo[L1], geo[L2], geo[L3], geo[RADIUS]
    theta = np.zeros(n + 1)
    off = np.empty((n + 1, 2))
    r_e = np.zeros((n, 2))  # r e_r at the middle of each rolling step
    for leg in range(hip.shape[1]):
        ox0, oy0, lx0, ly0 = state[leg, 0], state[leg, 1], state[leg, 2], state[leg, 3]
        lift_x, lift_y = lx0, ly0
        before = was[leg]
        for i in range(n):
            if stance[i + 1, leg] and before:
                x0, y0, x1, y1 = hip[i, leg, 0], hip[i, leg, 1], hip[i + 1, leg, 0], hip[i + 1, leg, 1]
                h0, h1 = math.hypot(x0, y0), math.hypot(x1, y1)
                ex, ey = x1 / h1 + x0 / h0, y1 / h1 + y0 / h0
                scale = radius / math.hypot(ex, ey)
                r_e[i, 0], r_e[i, 1] = ex * scale, ey * scale
            before = stance[i + 1, leg]
        off[:, 0], off[:, 1] = lx0, ly0  # first guess: the lift-off offset
        for _ in range(2):
            for k in range(n + 1):
                if stance[k, leg] if k > 0 else was[leg]:  # the pitch is needed where the foot is down
                    x, y, z = hip[k, leg, 0] + off[k, 0], hip[k, leg, 1] + off[k, 1], hip[k, leg, 2] + dz[leg]
                    theta[k] = pitch_of(x, y, z, l1, l2, l3)
            before = was[leg]
            total_x = total_y = at_x = at_y = 0.0
            touched = False  # a touchdown in this chunk: the stance sums from it, else from the last chunk's offset
            lift_x, lift_y, full_x, full_y = lx0, ly0, ox0, oy0  # full: the offset of the row before (0 in swing)
            for i in range(n):
                st = stance[i + 1, leg]
                if st and before:  # a rolling step: r e_r times the pitch's change
                    d = theta[i + 1] - theta[i]
                    total_x += r_e[i, 0] * d
                    total_y += r_e[i, 1] * d
                if st and not before:
                    touched, at_x, at_y = True, total_x, total_y
                if before and not st:
                    lift_x, lift_y = full_x, full_y
                if st:
                    sx, sy = (total_x - at_x, total_y - at_y) if touched else (ox0 + total_x, oy0 + total_y)
                    off[i + 1, 0], off[i + 1, 1] = sx, sy
                    full_x, full_y = sx, sy
                else:
                    fade = 1.0 - min(max(2.0 * swing_s[i + 1, leg], 0.0), 1.0)
                    fade = fade * fade * (3.0 - 2.0 * fade)
                    off[i + 1, 0], off[i + 1, 1] = lift_x * fade, lift_y * fade
                    full_x = full_y = 0.0
                before = st
            off[0, 0], off[0, 1] = ox0, oy0
        for k in range(n + 1):
            hip[k, leg, 0] += off[k, 0]
            hip[k, leg, 1] += off[k, 1]
        state[leg, 0], state[leg, 1], state[leg, 2], state[leg, 3] = off[n, 0], off[n, 1], lift_x, lift_y
        was[leg] = stance[n, leg]


@jit
def add_heights(targets, step, stand, stance, swing_s):
    """Adds a change of step height step (n + 1,) [m] to the swings' lift sin^2(pi s) and lowers every foot by a
    change of stand height stand (n + 1,) [m] (empty: none) in the targets (n + 1, n_legs, 3) (commands.add_heights)."""
    for k in range(targets.shape[0]):
        for leg in range(targets.shape[1]):
            if not stance[k, leg]:
                targets[k, leg, 2] += step[k] * math.sin(math.pi * swing_s[k, leg]) ** 2
            if stand.shape[0] > 0:
                targets[k, leg, 2] -= stand[k]


def compile_all() -> None:
    """Calls each kernel the planner and the controllers call in a walk once, on arrays of the types they pass
    (kernels.warm_up calls this, with its fallback to compiling in memory when numba's cache cannot be used).
    `fractions` and `stance_points` (GaitPlanner.phase and swing_fraction, gait.stance_path: for the API's users,
    not a walk) compile on first use: ~0.5 s less on a machine's first run."""
    n, rows = 6, 3
    clock = np.array([0.0, 1.0, 0.5, 0.0, 0.03, 0.5, 0.5])
    timing = np.zeros((n, NTIMING))
    times = np.array([0.5, 0.502, 0.504])
    stance, swing_s = np.ones((rows, n), dtype=np.bool_), np.zeros((rows, n))
    flags(times, clock, timing, stance, swing_s)
    seg, count = np.zeros((n, rows, NSEG)), np.zeros(n, dtype=np.int64)
    segments(times, clock, timing, seg, count)
    pos, vel, aim, aimed = np.zeros((n, 3)), np.zeros((n, 2)), np.zeros((n, 2)), np.zeros(n, dtype=np.bool_)
    out = np.zeros((rows, n, 3))
    for quintic_swing in (False, True):  # one compiled version serves both (a bool argument)
        targets(np.zeros(3), times, times, True, clock, timing, pos, seg, count, np.ones((n, rows, 2)), pos, vel,
                vel.copy(), quintic_swing, aim, aimed, out)  # fmt: skip
    hip, rot = np.full((rows, n, 3), 0.1), np.zeros((n, 3, 3))
    hip_targets(hip.copy(), rot, pos, np.zeros(n), stance, swing_s, np.array([0.05, 0.1, 0.1, 0.008]),
                np.zeros((n, 4)), np.ones(n, dtype=np.bool_), hip)  # fmt: skip
    add_heights(hip, times, times, stance, swing_s)


KERNELS = (pitch_of, phase, in_stance, _stance, _swing_fraction, next_touchdown, event_time, stance_point, hermite,
           _quintic, hermite5, stance_points, flags, fractions, segments, _warp, targets, hip_targets,
           add_heights)  # fmt: skip
