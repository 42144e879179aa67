"""Compiled per-step work of the walking controllers (numba): the servo step and the ground-finding legs.

A walking controller runs before every 2 ms physics step. In pure Python its per-step work (a
resolved-rate step per leg, the touchdown state machine, the stance plane) cost as much as MuJoCo's
step itself; compiled it costs a few microseconds (scripts/bench.py). What happens once per chunk is
driven from Python (control/walker.py, which owns the state arrays these kernels update in place; heading
hold), its heavy parts compiled too (plan_kernels.py: the gait plan, the rolling feet's offsets).

No kernel knows how many legs there are: it comes from the shapes of the arrays (n legs: 3 n joint
angles and targets, n rows of `legs`, `flags` and `geo`). numba compiles a kernel per argument types,
not shapes, so one compiled (and cached) version serves the hexabot's six legs and any other count.

The resolved-rate step is `resolved_rate.rate_steps` itself, compiled here: the single leg of
leg-step runs the same source as plain Python (cheaper there than converting its lists to arrays).
The kernels are cached on disk (numba's cache beside the source, or its user-wide cache when the
package directory is read-only), so only the first run on a machine compiles them (tens of seconds: warm_up).
NUMBA_DISABLE_JIT=1 runs them as plain Python, for debugging.

State of the ground-finding legs (GroundController), one row per leg:
- `legs` float (n, NLEG): stance height z [m] (body/hip frame z of the foot target), its value at
  lift-off, the lift-off time [s], the horizontal target offset (x, y) [m] in the hip frame, the
  offset at lift-off, the landing point (x, y) of the swing under way in the body frame, the
  planner's landing point of the next swing (set with each chunk's plan), the elevator reflex's
  trigger time [s] and the horizontal target (x, y) [m] (hip frame) it holds while lifting, the
  stance height's change per step [m] until the next plane update, and the swing's landing height from a
  terrain map [m] (NaN without one: the stance plane's; map_kernels.py);
- `flags` int (n, 3): swing mode (STANCE, SWING, EARLY, SEEKING, NEAR), planned stance at the last step, grounded.
"""

from __future__ import annotations

import math
import sys

import numba
import numba.core.event
import numpy as np
from numba.core.caching import NullCache

from hexabot_sim.control import resolved_rate
from hexabot_sim.kinematics.leg import LegGeometry


def jit(function):
    """numba.njit, cached on disk; compiled in every process where numba finds no writable cache directory."""
    try:
        return numba.njit(cache=True, nogil=True)(function)
    except RuntimeError:  # numba's "cannot cache function ...: no locator available"
        return numba.njit(nogil=True)(function)


rate_steps = jit(resolved_rate.rate_steps)
feed = jit(resolved_rate.feed)

# Swing state machine, per leg. NEAR: touched within EARLY_BAND of the swing's end height, which it goes on to.
STANCE, SWING, EARLY, SEEKING, NEAR = 0, 1, 2, 3, 4
# Columns of `legs`.
Z, Z_LIFT, T_LIFT, OFFSET, OFFSET_LIFT, LANDING, NEXT_LANDING, T_REFLEX, HOLD, Z_STEP, MAP_Z, SHIFT = (
    0, 1, 2, 3, 5, 7, 9, 11, 12, 14, 15, 16)  # fmt: skip
NLEG = 18
# Columns of `flags`.
MODE, WAS_STANCE, GROUNDED = 0, 1, 2
# Per-leg constants `geo` (n, NGEO): cos and sin of the hip yaw, hip position (x, y) in the body frame, the
# neutral foot height [m], the touch sensor's address in sensordata.
COS, SIN, HIP_X, HIP_Y, NEUTRAL_Z, TOUCH_ADR = 0, 1, 2, 3, 4, 5
NGEO = 6
# Scalars `par`: GroundSettings, the gait's timing and the command's ramp.
(SENSED, LEVEL, STAND_HEIGHT, DEPTH_MIN, DEPTH_MAX, ATTITUDE_GAIN, HEIGHT_GAIN, TOUCH_THRESHOLD, UPDATE_EVERY,
 SWING_TIME, SEEK_SPEED, DT, SETTLE_TIME, RAMP_TIME, QUAT_ADR,
 REFLEX_LIFT, REFLEX_UNTIL, REFLEX_RISE, EARLY_BAND) = range(19)  # fmt: skip
NPAR = 19
REFLEX_FROM: float = 0.2  # a touch earlier in the swing is the foot leaving the ground, not an obstacle
# Counters `counts`: control steps so far, plane updates, updates whose heights were clipped to the workspace.
STEPS, UPDATES, CLIPPED = 0, 1, 2


@jit
def servo(k, qpos, trims, q_cmd, dq, feed, dt, ctrl):
    """One resolved-rate step of the n joints (3 a leg) toward `feed` (rate_steps), written to the 2 n servos.

    The encoders read qpos[7:7 + n] - trims (the joints right after the free joint); the position servos
    ctrl[:n] get q_cmd + trims, the velocity servos ctrl[n:2 n] dq.
    """
    n = q_cmd.shape[0]
    q = qpos[7 : 7 + n] - trims
    rate_steps(k, q, q_cmd, dq, feed, dt)
    for i in range(n):
        ctrl[i] = q_cmd[i] + trims[i]
        ctrl[n + i] = dq[i]


@jit
def plane_fit(x, y, z, n, out):
    """Least-squares plane z = a + b x + c y through the first n points into out[:3]; False if they span none.

    The 3x3 normal equations, centred, solved by Cramer's rule.
    """
    if n < 3:
        return False
    sx = sy = sxx = sxy = syy = sz = sxz = syz = 0.0
    for i in range(n):
        xi, yi, h = x[i], y[i], z[i]
        sx += xi
        sy += yi
        sxx += xi * xi
        sxy += xi * yi
        syy += yi * yi
        sz += h
        sxz += xi * h
        syz += yi * h
    # Centred sums: the plane's slope from the covariance of the points, its height at their centroid.
    mx, my, mz = sx / n, sy / n, sz / n
    cxx, cxy, cyy = sxx - sx * mx, sxy - sx * my, syy - sy * my
    cxz, cyz = sxz - sx * mz, syz - sy * mz
    det = cxx * cyy - cxy * cxy
    if det <= 1e-12 * (cxx + cyy) ** 2 or det <= 0.0:  # collinear points: no plane through them
        return False
    b = (cyy * cxz - cxy * cyz) / det
    c = (cxx * cyz - cxy * cxz) / det
    out[0], out[1], out[2] = mz - b * mx - c * my, b, c
    return True


@jit
def update_plane(par, geo, legs, flags, plane, counts, row, sensordata):
    """Refits the stance plane and sets how every grounded stance target moves by the levelling/height correction.

    The plane z = a + b x + c y (body frame) through the stance feet's targets; a is driven to
    -stand_height, (b, c) to zero: from the IMU's roll and pitch (level) or the plane's own slope.
    Heights are clipped to the legs' workspace depths. The correction is spread over the steps until
    the next update (Z_STEP, applied by ground_step): moved at once, every UPDATE_EVERY steps, the
    targets' steps rang through the stance feet (force spikes every 10 ms, 130 % of a foot's share).
    """
    n_legs = legs.shape[0]
    xs, ys, zs = np.empty(n_legs), np.empty(n_legs), np.empty(n_legs)
    idx = np.empty(n_legs, dtype=np.int64)
    n = 0
    for i in range(n_legs):
        mode = flags[i, MODE]
        if (mode == STANCE or mode == EARLY) and flags[i, GROUNDED]:
            c, s = geo[i, COS], geo[i, SIN]
            x, y = row[3 * i], row[3 * i + 1]
            xs[n] = c * x - s * y + geo[i, HIP_X]
            ys[n] = s * x + c * y + geo[i, HIP_Y]
            zs[n] = legs[i, Z]
            idx[n] = i
            n += 1
    fit = plane.copy()
    plane_fit(xs, ys, zs, n, fit)  # keeps the last plane where the feet span none
    step = par[UPDATE_EVERY] * par[DT]
    gain = par[ATTITUDE_GAIN]
    da = -par[HEIGHT_GAIN] * (fit[0] + par[STAND_HEIGHT]) * step
    if par[LEVEL]:
        a = int(par[QUAT_ADR])
        w, x, y, z = sensordata[a], sensordata[a + 1], sensordata[a + 2], sensordata[a + 3]
        roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
        pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
        db, dc = -gain * math.tan(pitch) * step, gain * math.tan(roll) * step
    else:
        db, dc = -gain * fit[1] * step, -gain * fit[2] * step
    lo, hi = -par[DEPTH_MAX], -par[DEPTH_MIN]
    clipped = False
    for i in range(n_legs):
        legs[i, Z_STEP] = 0.0  # a foot that lands before the next update keeps its height until then
    for m in range(n):
        i = idx[m]
        z = legs[i, Z] + da + db * xs[m] + dc * ys[m]
        if not lo <= z <= hi:
            z, clipped = min(hi, max(lo, z)), True
        legs[i, Z_STEP] = (z - legs[i, Z]) / par[UPDATE_EVERY]
    counts[UPDATES] += 1
    counts[CLIPPED] += clipped
    plane[0], plane[1], plane[2] = fit[0] + da, fit[1] + db, fit[2] + dc


@jit
def _event(events, n, leg, planned, touched):
    events[n, 0], events[n, 1], events[n, 2] = leg, planned, touched
    return n + 1


@jit
def _smoothstep(x):
    x = min(1.0, max(0.0, x))
    return x * x * (3 - 2 * x)


@jit
def reflex(par, legs, i, t, s, z):
    """The elevator reflex of leg i since its trigger: the swing's height z raised by REFLEX_LIFT over REFLEX_RISE
    [s], the raise fading over the last 30 % of the swing; the horizontal target (hip frame) held where it was at
    the touch while lifting, then let go to the plan's by 90 % of the swing. Returns (z, the hold's weight)."""
    since = t - legs[i, T_REFLEX]
    z += par[REFLEX_LIFT] * _smoothstep(since / par[REFLEX_RISE]) * (1.0 - _smoothstep((s - 0.7) / 0.3))
    release = legs[i, T_LIFT] + 0.9 * par[SWING_TIME] - legs[i, T_REFLEX] - par[REFLEX_RISE]  # [s] to let go in
    hold = 1.0 - _smoothstep((since - par[REFLEX_RISE]) / max(release, par[DT]))
    return z, hold


@jit
def targets(par, geo, legs, flags, plane, cmd, row, stance, t, row_prev, sensordata, out, events):
    """The planner's hip-frame row (3 n,) at time t with the heights and offsets of uneven ground, into out.

    Per leg: a planned stance goes on at its height z; a planned lift-off starts a swing from the
    lift-off height toward the stance plane under the landing point, or the terrain map's ground there (MAP_Z),
    (smoothstep) plus the planner's lift, the lift-off offset fading out over the first half and the map's shift
    of the landing point off an edge (SHIFT, map_kernels.landing_heights) moving in over the second, kept through
    the stance; a touch in the second half of a swing (sensed) ends it early, the target then ground-fixed at the
    command's stance velocity, unless the target is within EARLY_BAND of the swing's end height (NEAR: a soft
    foot's first contact, which the swing goes on through to its planned end, as with planned touchdown); a swing
    that reaches its planned touchdown untouched keeps descending (SEEKING) until it touches or
    leaves the workspace (no ground). Swings that ended are written to events as (leg, planned
    touchdown time, touch time or NaN); returns how many.
    """
    sensed = par[SENSED] != 0.0
    swing_time, dt, threshold = par[SWING_TIME], par[DT], par[TOUCH_THRESHOLD]
    n_events = 0
    for i in range(stance.shape[0]):
        j = 3 * i
        planned = stance[i]
        mode = flags[i, MODE]
        was = flags[i, WAS_STANCE] != 0
        flags[i, WAS_STANCE] = planned
        out[j], out[j + 1], out[j + 2] = row[j], row[j + 1], row[j + 2]
        touching = sensordata[int(geo[i, TOUCH_ADR])] > threshold
        if mode == STANCE and planned:  # most legs, most steps: a stance goes on unchanged
            out[j] += legs[i, OFFSET]
            out[j + 1] += legs[i, OFFSET + 1]
            out[j + 2] = legs[i, Z]
            continue
        if (mode == STANCE or mode == SEEKING) and was and not planned:  # planned lift-off
            if mode == SEEKING:
                n_events = _event(events, n_events, i, legs[i, T_LIFT] + swing_time, np.nan)
            mode = SWING
            legs[i, Z_LIFT] = legs[i, Z]
            legs[i, OFFSET_LIFT], legs[i, OFFSET_LIFT + 1] = legs[i, OFFSET], legs[i, OFFSET + 1]
            legs[i, T_LIFT] = t - dt
            legs[i, LANDING], legs[i, LANDING + 1] = legs[i, NEXT_LANDING], legs[i, NEXT_LANDING + 1]
            flags[i, GROUNDED] = 1
        elif mode == EARLY and planned:
            mode = STANCE
        if mode == SWING or mode == NEAR:
            s = min((t - legs[i, T_LIFT]) / swing_time, 1.0)
            u = s * s * (3 - 2 * s)
            z_lift = legs[i, Z_LIFT]
            under = legs[i, MAP_Z]  # the terrain map's ground under the landing point, else the stance plane's
            if math.isnan(under):
                under = plane[0] + plane[1] * legs[i, LANDING] + plane[2] * legs[i, LANDING + 1]
            base = z_lift + (under - z_lift) * u  # toward the landing height
            z = base + row[j + 2] - geo[i, NEUTRAL_Z]  # + the planner's lift
            if s < 0.5:
                fade = 1.0 - 2.0 * s
                fade = fade * fade * (3 - 2 * fade)
                legs[i, OFFSET] = legs[i, OFFSET_LIFT] * fade
                legs[i, OFFSET + 1] = legs[i, OFFSET_LIFT + 1] * fade
            else:  # the terrain map's shift of the landing point off an edge (body frame), moved in over the rest
                w = _smoothstep(2.0 * s - 1.0)
                c, s_ = geo[i, COS], geo[i, SIN]
                sx, sy = legs[i, SHIFT] * w, legs[i, SHIFT + 1] * w
                legs[i, OFFSET], legs[i, OFFSET + 1] = c * sx + s_ * sy, -s_ * sx + c * sy  # body -> hip frame
            # Elevator reflex: a touch before REFLEX_UNTIL of the swing is an obstacle in the way, not the ground.
            blocked = sensed and touching and mode == SWING and REFLEX_FROM < s < par[REFLEX_UNTIL]
            blocked = blocked and par[REFLEX_LIFT] > 0.0
            if blocked and legs[i, T_REFLEX] < legs[i, T_LIFT]:  # the first touch of this swing: hold and lift
                legs[i, T_REFLEX] = t
                legs[i, HOLD] = out[j] + legs[i, OFFSET]
                legs[i, HOLD + 1] = out[j + 1] + legs[i, OFFSET + 1]
            if legs[i, T_REFLEX] >= legs[i, T_LIFT]:
                z, hold = reflex(par, legs, i, t, s, z)
                legs[i, OFFSET] = (legs[i, HOLD] - out[j]) * hold
                legs[i, OFFSET + 1] = (legs[i, HOLD + 1] - out[j + 1]) * hold
            touched = mode == SWING and sensed and s >= 0.5 and touching and not blocked
            if touched:
                n_events = _event(events, n_events, i, legs[i, T_LIFT] + swing_time, t)
            near = par[EARLY_BAND] > 0.0 and z - under < par[EARLY_BAND]
            if touched and (planned or not near):
                legs[i, Z] = z
                mode = STANCE if planned else EARLY
            elif planned:  # the planned touchdown came without a touch (or after one NEAR its end)
                legs[i, Z] = base
                if mode == NEAR:
                    mode = STANCE
                elif sensed:
                    mode = SEEKING
                else:
                    mode = STANCE
                    n_events = _event(events, n_events, i, t, t)
            else:  # still swinging
                if touched:
                    mode = NEAR
                out[j] += legs[i, OFFSET]
                out[j + 1] += legs[i, OFFSET + 1]
                out[j + 2] = z
                flags[i, MODE] = mode
                continue
        if mode == EARLY:
            # Ground-fixed from the touch on: the target moves at the stance velocity, not along the swing.
            f = ramp(par, t)
            c, s_ = geo[i, COS], geo[i, SIN]
            ox, oy = legs[i, OFFSET], legs[i, OFFSET + 1]
            px, py = row_prev[j] + ox, row_prev[j + 1] + oy
            bx, by = c * px - s_ * py + geo[i, HIP_X], s_ * px + c * py + geo[i, HIP_Y]  # body frame
            vx, vy = f * (-cmd[0] + cmd[2] * by), f * (-cmd[1] - cmd[2] * bx)
            hx, hy = c * vx + s_ * vy, -s_ * vx + c * vy  # body -> hip frame
            legs[i, OFFSET] = ox + hx * dt - (row[j] - row_prev[j])
            legs[i, OFFSET + 1] = oy + hy * dt - (row[j + 1] - row_prev[j + 1])
        elif mode == SEEKING:
            if touching:
                n_events = _event(events, n_events, i, legs[i, T_LIFT] + swing_time, t)
                mode = STANCE
            elif legs[i, Z] - par[SEEK_SPEED] * dt < -par[DEPTH_MAX]:
                n_events = _event(events, n_events, i, legs[i, T_LIFT] + swing_time, np.nan)
                mode = STANCE
                flags[i, GROUNDED] = 0
            else:
                legs[i, Z] -= par[SEEK_SPEED] * dt
        flags[i, MODE] = mode
        out[j] += legs[i, OFFSET]
        out[j + 1] += legs[i, OFFSET + 1]
        out[j + 2] = legs[i, Z]
    return n_events


@jit
def ramp(par, t):
    """Fraction of the command in force at t: 0 while settling, then a linear ramp to 1."""
    if t <= par[SETTLE_TIME]:
        return 0.0
    if par[RAMP_TIME] <= 0:
        return 1.0
    return min(1.0, (t - par[SETTLE_TIME]) / par[RAMP_TIME])


@jit
def ground_step(par, geo, k, legs, flags, plane, counts, cmd, rows, stance, r, t, row_prev, q_cmd, dq, trims,
                qpos, sensordata, ctrl, events, extra):  # fmt: skip
    """One control step of GroundController from t to t + dt (row r of the chunk's rows is time t).

    Updates the stance plane every UPDATE_EVERY steps, sets the targets at t + dt, and advances the
    servos by one resolved-rate step from row_prev (the targets at t) to them, its feed plus `extra`
    (3 n,) (the legs' admittance, control/compliance.py; zeros without). Returns the number of
    swings that ended (written to events).
    """
    dt = par[DT]
    if counts[STEPS] % int(par[UPDATE_EVERY]) == 0:
        update_plane(par, geo, legs, flags, plane, counts, row_prev, sensordata)
    counts[STEPS] += 1
    for i in range(legs.shape[0]):  # the plane update's correction, a step's share of it
        mode = flags[i, MODE]
        if (mode == STANCE or mode == EARLY) and flags[i, GROUNDED]:
            legs[i, Z] += legs[i, Z_STEP]
    row1 = np.empty(row_prev.shape[0])
    n_events = targets(par, geo, legs, flags, plane, cmd, rows[r + 1], stance[r + 1], t + dt, rows[r], sensordata,
                       row1, events)  # fmt: skip
    rate = np.empty(row_prev.shape[0])
    feed(k[3], row_prev, row1, dt, rate)
    rate += extra
    row_prev[:] = row1
    servo(k, qpos, trims, q_cmd, dq, rate, dt, ctrl)
    return n_events


# What a walk compiles: "walk" (every walk: the servo step, the ground-finding legs, the gait plan), "force" (the
# stance force control, load_sharing=force: force_kernels.py), "admittance" (load_sharing=admittance:
# compliance_kernels.py) and "map" (terrain_map=on: map_kernels.py). A default walk compiles only the first: 62 % of
# the first three's cold compile, 27 of 44 s on a loaded 2-core machine (scripts/bench.py --only compile).
GROUPS: tuple[str, ...] = ("walk", "force", "admittance", "map")
_WARM: set[str] = set()


def warm_up(*groups: str) -> None:
    """Compiles the kernels of these groups (GROUPS; none given: "walk"), or loads them from the cache, for the
    argument types the controllers pass.

    Once per process and group, before a walk's first step. The compiling (tens of seconds on a loaded machine's
    first run) is not under the command line's signal hold: a stop request ends it at once. One that struck inside
    numba's compiler may come out of it as another error, or be swallowed and leave a kernel unusable ("no compiled
    object yet"): a stop request recorded by then is raised instead of retrying or going on (the run stops either
    way). A cache numba cannot use (a full disk, a truncated or foreign file) does not stop the walk: the
    kernels are compiled in memory instead, with a one-line note naming the cache folder.
    """
    unknown = set(groups) - set(GROUPS)
    if unknown:
        raise ValueError(f"kernel groups {sorted(unknown)}: known are {', '.join(GROUPS)}")
    wanted = tuple(g for g in (groups or ("walk",)) if g not in _WARM)
    if not wanted:
        return
    try:
        _compile_all(wanted)
    except Exception as error:  # retried without the cache; if that fails too, the first error stands
        _stop_if_requested()
        where = getattr(getattr(ground_step, "_cache", None), "cache_path", "?")
        for kernel in _all_kernels():
            kernel._cache = NullCache()  # numba's own "no caching" (the dispatcher attribute cache=True sets)
        try:
            _compile_all(wanted)
        except Exception:
            _stop_if_requested()
            raise error from None
        text = " ".join(f"{type(error).__name__}: {error}".split())[:200]
        print(
            f"hexabot-sim: note: numba's cache in {where} could not be used ({text}); the walking kernels were "
            "compiled in memory (removing that folder lets numba rebuild it)",
            file=sys.stderr,
        )
    _stop_if_requested()  # numba swallowed it: its kernels may be unusable, so they are not marked warm
    _WARM.update(wanted)


def _stop_if_requested() -> None:
    """Raises the stop request the command line recorded (Ctrl-C, SIGTERM, SIGHUP), if any (and not held)."""
    from hexabot_sim.signals import HOLD, PUBLISHED, RECEIVED_SIGNALS, stop_request

    if RECEIVED_SIGNALS and not HOLD[0] and not PUBLISHED[0]:
        raise stop_request(RECEIVED_SIGNALS[-1]) from None


class _StopBetweenPasses(numba.core.event.Listener):
    """Stops a compile at the start of numba's next compiler pass once a stop request was recorded.

    numba's compiler drops (and frees) thousands of LLVM objects, whose __del__ is Python: a stop signal whose handler
    runs in one raises where Python can only print and drop it ("Exception ignored", which the command line silences).
    The compile went on with every kernel, a minute under load (found by fuzzing with a cold cache).
    """

    def on_start(self, event: numba.core.event.Event) -> None:
        _stop_if_requested()

    def on_end(self, event: numba.core.event.Event) -> None:
        pass


def _all_kernels() -> tuple:
    """Every compiled kernel of the walking controllers: these, the legs' admittance (compliance_kernels.py), the
    force control's, the terrain map's and the gait plan's (plan_kernels.py)."""
    from hexabot_sim.control import compliance_kernels, force_kernels, map_kernels, plan_kernels

    kernels = compliance_kernels.KERNELS + force_kernels.KERNELS + map_kernels.KERNELS + plan_kernels.KERNELS
    return _KERNELS + kernels


def _compile_all(groups: tuple[str, ...]) -> None:
    """Calls each kernel of the groups that the controllers call from Python once, on arrays of the types they pass
    (for six legs; the types, hence the compiled code, are the same for any leg count); a stop request recorded
    meanwhile ends it at numba's next compiler pass (_StopBetweenPasses)."""
    with numba.core.event.install_listener("numba:run_pass", _StopBetweenPasses()):
        _compile_each(groups)


def _compile_each(groups: tuple[str, ...] = GROUPS) -> None:
    from hexabot_sim.control import compliance_kernels, force_kernels, map_kernels, plan_kernels

    if "map" in groups:
        map_kernels.compile_all()
    if "admittance" in groups:
        compliance_kernels.compile_all()
    if "force" in groups:
        force_kernels.compile_all()
    if "walk" not in groups:
        return
    plan_kernels.compile_all()
    par = np.zeros(NPAR)
    par[UPDATE_EVERY], par[DT], par[SWING_TIME] = 1.0, 0.002, 1.0
    gains = resolved_rate.ResolvedRateGains(max_joint_acceleration=200.0)
    k = np.array(resolved_rate.step_constants(LegGeometry(), gains, (-1.0, -1.0, 0.0), (1.0, 1.0, 2.0)))
    n, nq = 6, 18  # legs, joints: any count compiles the same code
    qpos, sensordata, ctrl = np.zeros(7 + nq), np.zeros(8), np.zeros(2 * nq)
    qpos[7:] = np.tile([0.0, 0.5, 1.0], n)  # a leg away from its singularities
    geo, legs, flags = np.zeros((n, NGEO)), np.zeros((n, NLEG)), np.zeros((n, 3), dtype=np.int64)
    plane, counts, cmd = np.zeros(3), np.zeros(3, dtype=np.int64), np.zeros(3)
    rows, stance = np.zeros((2, nq)), np.ones((2, n), dtype=bool)
    q_cmd, dq, trims, row, events = np.zeros(nq), np.zeros(nq), np.zeros(nq), np.zeros(nq), np.zeros((n, 3))
    feed(1.0, rows[:-1].ravel(), rows[1:].ravel(), 0.002, np.empty(nq))  # as WalkingController._publish
    servo(k, qpos, trims, q_cmd, dq, rows[0], 0.002, ctrl)
    targets(par, geo, legs, flags, plane, cmd, rows[0], stance[0], 0.0, rows[0], sensordata, row, events)
    ground_step(par, geo, k, legs, flags, plane, counts, cmd, rows, stance, 0, 0.0, row, q_cmd, dq, trims, qpos,
                sensordata, ctrl, events, np.zeros(nq))  # fmt: skip


_KERNELS = (rate_steps, feed, servo, plane_fit, update_plane, _event, _smoothstep, reflex, targets, ramp, ground_step)
