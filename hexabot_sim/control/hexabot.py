"""Walking controller of the hexabot: gait targets per leg, the leg's resolved-rate step, heading hold.

Per control period: read the 18 joint angles (the servos' encoders), take each foot's target at t
and t + dt from the gait planner (planned a chunk ahead, in the leg's hip frame), and advance each
leg's joint command with `resolved_rate.rate_steps` — the same step leg-step uses. The servos get
q_cmd (position) and dq (velocity feedforward).

Two corrections make the body go where it is told:
- Rolling feet: a sphere foot that rolls without slipping moves its centre by r dtheta over the
  ground, theta = q2 + q3 its pitch in the leg plane. During stance the foot-centre target is
  shifted by r (theta - theta_touchdown) along the leg's radial direction, so the contact point,
  not the centre, stays where the plan puts it (otherwise the body is a few percent slow or fast).
- Heading hold (optional): the body's yaw from the IMU quaternion (sensor "imu_quat", not the free
  joint) is compared with the integral of the commanded yaw rate, and the yaw rate of the next
  chunk is corrected by heading_gain times the error.
"""

from __future__ import annotations

import dataclasses
import math

import mujoco
import numpy as np

from hexabot_sim.control.gait import Command, GaitPlanner
from hexabot_sim.control.resolved_rate import ResolvedRateGains, feed, rate_steps, step_constants
from hexabot_sim.kinematics import hexabot as hx

MAX_HEADING_CORRECTION: float = 0.3  # [rad/s] largest yaw-rate correction heading hold adds


@dataclasses.dataclass(frozen=True)
class WalkSettings:
    """What the walking controller is asked to do and how.

    Attributes:
        command: Body twist to walk at after the ramp.
        settle_time: Standing still on the neutral stance first [s] (the robot settles on its feet).
        ramp_time: The command grows linearly from 0 to `command` over this time [s].
        heading_hold: Correct the yaw rate from the IMU's yaw.
        heading_gain: Yaw-rate correction per radian of heading error [1/s].
        trims: Servo zero errors (6, 3) [rad]: each servo holds q_cmd + trim while its encoder reads q - trim.
    """

    command: Command
    settle_time: float = 0.5
    ramp_time: float = 1.0
    heading_hold: bool = False
    heading_gain: float = 2.0
    trims: tuple[float, ...] = (0.0,) * 18


def yaw_of(quat: np.ndarray) -> float:
    """Yaw [rad] of a unit quaternion (w, x, y, z) (z-y-x Euler angles)."""
    w, x, y, z = (float(v) for v in quat)
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


class HexabotController:
    """Drives the 18 servos of models/hexabot.xml so the body follows a walking command.

    Call it before every mj_step (it is a simulate() controller). State lives here: the joint command
    q_cmd (18,), the previous joint rate, the planned targets of the current chunk.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        layout: hx.Layout,
        planner: GaitPlanner,
        gains: ResolvedRateGains,
        settings: WalkSettings,
        q_start: np.ndarray,
    ) -> None:
        self.layout = layout
        self.planner = planner
        self.settings = settings
        self.dt = planner.dt
        self.foot_radius = layout.foot_radius
        self.qadr = [int(model.joint(f"{leg}_{j}").qposadr[0]) for leg in hx.LEGS for j in hx.JOINTS]
        if self.qadr != list(range(7, 25)):
            raise ValueError("hexabot.xml must put the 18 leg joints right after the free joint, in LEGS order")
        pos_act = [model.actuator(f"{leg}_{j}").id for leg in hx.LEGS for j in hx.JOINTS]
        vel_act = [model.actuator(f"{leg}_{j}_velocity").id for leg in hx.LEGS for j in hx.JOINTS]
        if pos_act + vel_act != list(range(36)):
            raise ValueError("hexabot.xml must list the 18 position then the 18 velocity actuators in LEGS order")
        self.quat_adr = int(model.sensor_adr[model.sensor("imu_quat").id])
        lower, upper = hx.JOINT_LOWER, hx.JOINT_UPPER
        self.consts = step_constants(layout.geometry, gains, lower, upper)
        self.trims = [float(v) for v in settings.trims]
        self._trimmed = any(self.trims)
        self.q_cmd = [float(v) for v in np.asarray(q_start).ravel()]
        self.dq = [0.0] * 18
        self.rot = layout.hip_rotations()  # (6, 3, 3) hip -> body
        self.hips = layout.hip_positions()  # (6, 3)
        # Targets of the current chunk in each hip frame, one flat row of 18 floats per step, and stance flags.
        self._feed: list[list[float]] = []  # per step: the rate_steps feed (v_des + K x_des), 18 floats
        self._k = 0
        # Rolling state carried between chunks: last row's offset (6, 2), offset at lift-off (6, 2), in stance.
        self._rolling = (np.zeros((6, 2)), np.zeros((6, 2)), np.ones(6, dtype=bool))
        self._chunk = 0  # steps in the current chunk (0: plan one first)
        # Heading: desired yaw (integral of the commanded yaw rate) and the unwrapped measured yaw.
        self._yaw_des = 0.0
        self._yaw_meas = yaw_of(data.sensordata[self.quat_adr : self.quat_adr + 4])
        self._yaw_des = self._yaw_meas
        self.commands: list[tuple[float, float, float, float]] = []  # (t, vx, vy, yaw rate) per chunk
        self._qpos = data.qpos
        self._ctrl = data.ctrl
        self._sensordata = data.sensordata

    def scale(self, t: np.ndarray | float) -> np.ndarray | float:
        """Fraction of the command in force at t (vectorised): 0 while settling, then a linear ramp to 1."""
        s = self.settings
        if s.ramp_time <= 0:
            return np.where(np.asarray(t) <= s.settle_time, 0.0, 1.0)
        return np.clip((np.asarray(t) - s.settle_time) / s.ramp_time, 0.0, 1.0)

    def _factor(self, t: float) -> float:
        """scale(t) for one time, in plain floats."""
        s = self.settings
        if t <= s.settle_time:
            return 0.0
        return 1.0 if s.ramp_time <= 0 else min(1.0, (t - s.settle_time) / s.ramp_time)

    def _replan(self, t: float) -> None:
        """Plans the next chunk of targets with the command in force now (and the heading correction).

        The ramp is planned inside the chunk (the planner's scale), so the command grows smoothly
        without short chunks; `commands` records the command before the ramp's factor.
        """
        s = self.settings
        n = self.planner.max_chunk
        cmd = s.command
        times = t + self.dt * np.arange(n + 1)
        ramp = self.scale(times)
        if s.heading_hold:
            # Unwrap the IMU yaw next to the last one, compare with the commanded heading.
            quat = self._sensordata[self.quat_adr : self.quat_adr + 4]
            yaw = yaw_of(quat)
            self._yaw_meas += math.remainder(yaw - self._yaw_meas, 2 * math.pi)
            error = self._yaw_des - self._yaw_meas
            correction = max(-MAX_HEADING_CORRECTION, min(MAX_HEADING_CORRECTION, s.heading_gain * error))
            cmd = Command(cmd.vx, cmd.vy, cmd.yaw_rate + correction)
            # The commanded heading advances by the yaw rate times the integral of the ramp over the chunk.
            self._yaw_des += s.command.yaw_rate * float(np.sum(0.5 * (ramp[1:] + ramp[:-1]))) * self.dt
        self.commands.append((t, cmd.vx, cmd.vy, cmd.yaw_rate))
        targets = self.planner.plan(cmd, n, None if ramp[0] >= 1.0 else self.scale)  # (n + 1, 6, 3) body frame
        times = self.planner.time - self.dt * np.arange(n, -1, -1)  # (n + 1,)
        stance = self.planner.in_stance(times)  # (n + 1, 6)
        duty = self.planner.gait.duty
        swing_s = np.where(stance, 0.0, (self.planner.phase(times) - duty) / (1.0 - duty))
        # Body -> hip frame of each leg: R^T (p - hip).
        hip = np.einsum("lji,klj->kli", self.rot, targets - self.hips)  # (n + 1, 6, 3)
        hip += self._rolling_offsets(hip, stance, swing_s)
        self._publish(hip.reshape(n + 1, 18), stance)
        self._chunk = n
        self._k = 0

    def _publish(self, rows: np.ndarray, stance: np.ndarray) -> None:
        """Keeps what the steps of the chunk need from its targets rows (n + 1, 18) (hip frames) and stance flags."""
        self._feed = ((rows[1:] - rows[:-1]) / self.dt + self.consts[3] * rows[:-1]).tolist()

    def _rolling_offsets(self, hip: np.ndarray, stance: np.ndarray, swing_s: np.ndarray) -> np.ndarray:
        """Offsets (n + 1, 6, 3) of the foot-centre targets for feet that roll without slipping.

        A sphere foot rolling without slip moves its centre over the ground by r dtheta along the leg's
        radial direction e_r, theta = q2 + q3 its pitch. So in stance the centre target is shifted by
        the sum of r dtheta e_r since touchdown (theta of the shifted target, iterated once since the
        shift changes theta a little; summed step by step because e_r turns with the coxa); in the
        swing, the shift reached at lift-off fades out over the first half. The state at the end of a
        chunk carries over to the next one, whose row 0 repeats the previous chunk's last row.
        """
        n = hip.shape[0] - 1
        offset0, lift0, was0 = self._rolling
        # Which rows roll, and the latest touchdown / lift-off row at every row (0: none in this chunk).
        st = stance[1:]  # (n, 6); row 0 is the previous chunk's last row
        before = np.vstack([was0[None], st[:-1]])
        rows = np.arange(1, n + 1)[:, None]  # (n, 1)
        last_td = np.maximum.accumulate(np.where(st & ~before, rows, 0), axis=0)  # (n, 6)
        last_lo = np.maximum.accumulate(np.where(~st & before, rows, 0), axis=0)
        legs = np.arange(6)
        td_row, lo_row = np.maximum(last_td - 1, 0) * 6 + legs, np.maximum(last_lo - 1, 0) * 6 + legs  # flat (row, leg)
        after_td, after_lo = (last_td > 0)[..., None], (last_lo > 0)[..., None]
        # r e_r at the middle of every rolling step (0 elsewhere), and the swing's fade (smoothstep 1 -> 0).
        radial = hip[..., :2] / np.hypot(hip[..., 0], hip[..., 1])[..., None]  # (n + 1, 6, 2)
        e_mid = radial[1:] + radial[:-1]
        e_mid *= (self.foot_radius / np.hypot(e_mid[..., 0], e_mid[..., 1]))[..., None]
        r_e = np.where((st & before)[..., None], e_mid, 0.0)  # (n, 6, 2)
        fade = 1.0 - np.clip(2.0 * swing_s[1:], 0.0, 1.0)
        fade = (fade * fade * (3.0 - 2.0 * fade))[..., None]  # (n, 6, 1)
        offset = np.repeat(lift0[None], n + 1, axis=0)  # (n + 1, 6, 2) [m] first guess
        stance3 = st[..., None]
        shifted = hip.copy()
        for _ in range(2):
            shifted[..., :2] = hip[..., :2] + offset
            theta = hx.foot_pitch(self.layout, shifted)  # (n + 1, 6)
            total = np.cumsum(r_e * np.diff(theta, axis=0)[..., None], axis=0)  # (n, 6, 2)
            at_td = total.reshape(-1, 2)[td_row]  # total at each leg's latest touchdown
            stance_offset = np.where(after_td, total - at_td, offset0 + total)
            full = np.concatenate([offset0[None], np.where(stance3, stance_offset, 0.0)])  # (n + 1, 6, 2)
            lift = np.where(after_lo, full.reshape(-1, 2)[lo_row], lift0)
            offset = np.concatenate([offset0[None], np.where(stance3, stance_offset, lift * fade)])
        self._rolling = (offset[-1], lift[-1], st[-1])
        out = np.zeros_like(hip)
        out[..., :2] = offset
        return out

    def __call__(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Sets data.ctrl for the step from data.time to data.time + dt."""
        k = self._k
        if k >= self._chunk:
            self._replan(data.time)
            k = 0
        self._servo(self._feed[k])
        self._k = k + 1

    def _servo(self, rate: list[float]) -> None:
        """One resolved-rate step of the six legs toward `rate` (see `feed`), written to the 36 servos."""
        q_cmd, dq = self.q_cmd, self.dq
        if self._trimmed:
            trims = self.trims
            q = [a - b for a, b in zip(self._qpos[7:25].tolist(), trims, strict=True)]  # what the encoders read
            rate_steps(self.consts, q, q_cmd, dq, rate, self.dt)
            self._ctrl[:] = [a + b for a, b in zip(q_cmd, trims, strict=True)] + dq
        else:
            rate_steps(self.consts, self._qpos[7:25].tolist(), q_cmd, dq, rate, self.dt)
            self._ctrl[:] = q_cmd + dq  # position servos: q_cmd; velocity servos: dq


def fit_plane(xy: list[tuple[float, float]], z: list[float]) -> list[float] | None:
    """Least-squares plane z = a + b x + c y through the points, [a, b, c]; None if they do not span one.

    The 3x3 normal equations solved by Cramer's rule in plain floats (a handful of feet, every few
    control steps: numpy's lstsq would cost more than the whole control step).
    """
    n = len(xy)
    if n < 3:
        return None
    sx = sy = sxx = sxy = syy = sz = sxz = syz = 0.0
    for (x, y), h in zip(xy, z, strict=True):
        sx += x
        sy += y
        sxx += x * x
        sxy += x * y
        syy += y * y
        sz += h
        sxz += x * h
        syz += y * h
    # Centred sums: the plane's slope from the covariance of the points, its height at their centroid.
    mx, my, mz = sx / n, sy / n, sz / n
    cxx, cxy, cyy = sxx - sx * mx, sxy - sx * my, syy - sy * my
    cxz, cyz = sxz - sx * mz, syz - sy * mz
    det = cxx * cyy - cxy * cxy
    if det <= 1e-12 * (cxx + cyy) ** 2 or det <= 0.0:  # collinear feet: no plane through them
        return None
    b = (cyy * cxz - cxy * cyz) / det
    c = (cxx * cyz - cxy * cxz) / det
    return [mz - b * mx - c * my, b, c]


# Swing state machine of GroundController, per leg.
STANCE, SWING, EARLY, SEEKING = 0, 1, 2, 3


@dataclasses.dataclass(frozen=True)
class GroundSettings:
    """How the walking controller meets uneven ground (GroundController).

    Attributes:
        sensed: A swing foot whose touch sensor fires in the second half of its swing goes to stance at
            once (early touchdown); one that has not touched at the planned touchdown keeps descending
            (late touchdown) until it touches or its target leaves `depth_range` (no ground found).
        level: Keep the body level relative to gravity from the IMU's roll and pitch; else the body
            follows the plane of the stance feet.
        stand_height: Depth of the stance feet below the body's origin over the local ground [m].
        depth_range: (smallest, largest) depth of a foot target below its hip [m] (the legs' workspace).
        attitude_gain: Rate at which tilt errors are removed [1/s].
        height_gain: Rate at which body-height errors are removed [1/s].
        touch_threshold: Touch-sensor force that counts as contact [N].
        update_every: Control steps between updates of the ground plane and the levelling.
    """

    sensed: bool = True
    level: bool = False
    stand_height: float = 0.09
    depth_range: tuple[float, float] = (0.03, 0.17)
    attitude_gain: float = 10.0
    height_gain: float = 5.0
    touch_threshold: float = 0.3
    update_every: int = 5


@dataclasses.dataclass(frozen=True)
class Touchdown:
    """A swing that ended: when the plan said and when the foot touched (NaN: no ground found)."""

    leg: int
    planned: float  # [s] planned touchdown time
    touched: float  # [s] touch-sensor time (sensed) or the planned time (planned); NaN: no ground


class GroundController(HexabotController):
    """HexabotController with feet that find the ground and (optionally) a body kept level.

    The gait planner's targets keep their horizontal motion; the height of each foot target (the z of
    the body/hip frame, which the hip frames share) is set here:
    - stance: z_i, the height where the foot touched down, moved with the whole stance by a plane
      a + b x + c y every `update_every` steps: a drives the stance plane's height at the body origin
      to -stand_height, (b, c) drive the body's roll and pitch from the IMU quaternion to zero (level)
      or the stance plane's slope to zero (follow the ground); clipped to the workspace depths;
    - swing: from the lift-off height to the stance plane under the landing point (smoothstep), plus
      the planner's lift h sin^2(pi s);
    - sensed touchdown: early, the leg is in stance from the touch on (its horizontal target becomes
      ground-fixed, the offset to the plan fading out over its next swing); late, the target keeps
      descending at SEEK_SPEED until it touches or leaves the workspace.
    """

    def __init__(self, model, data, layout, planner, gains, settings, q_start, ground: GroundSettings) -> None:
        super().__init__(model, data, layout, planner, gains, settings, q_start)
        self.ground = ground
        self.touch_adr = [int(model.sensor_adr[model.sensor(f"{leg}_touch").id]) for leg in hx.LEGS]
        feet = hx.feet_body(layout, np.asarray(q_start).reshape(6, 3))  # (6, 3)
        self.z = [float(v) for v in feet[:, 2]]  # stance height of each foot target (body frame) [m]
        self.mode = [STANCE] * 6
        self.grounded = [True] * 6  # in stance on something (False: no ground was found)
        self.offset = [[0.0, 0.0] for _ in range(6)]  # horizontal target offset (hip frame) [m]
        self.offset_lift = [[0.0, 0.0] for _ in range(6)]
        self.z_lift = list(self.z)
        self.t_lift = [0.0] * 6
        self.events: list[Touchdown] = []
        self.clipped_updates = 0
        self.updates = 0
        self._cos = [math.cos(y) for y in layout.yaws]
        self._sin = [math.sin(y) for y in layout.yaws]
        self._hips_xy = [(float(h[0]), float(h[1])) for h in self.hips]
        self._neutral = [(float(p[0]), float(p[1])) for p in planner.neutral]
        self._neutral_z = [float(p[2]) for p in planner.neutral]
        self._landing = list(self._neutral)
        self._plane = [-ground.stand_height, 0.0, 0.0]  # stance plane z = a + b x + c y (body frame)
        self._was_stance = [True] * 6
        self._row_prev: list[float] | None = None
        self._count = 0
        self._cmd = Command()
        swing_time = planner.swing_time
        self.seek_speed = math.pi * planner.step_height / (2 * swing_time)  # [m/s] half the swing's peak

    def _publish(self, rows: np.ndarray, stance: np.ndarray) -> None:
        """Keeps the rows and stance flags themselves: the heights are set step by step (`_targets`)."""
        self._rows: list[list[float]] = rows.tolist()
        self._stance: list[list[bool]] = stance.tolist()

    def _rolling_offsets(self, hip: np.ndarray, stance: np.ndarray, swing_s: np.ndarray) -> np.ndarray:
        """The rolling offsets of the feet at the heights they stand at now (not the planned flat-ground height)."""
        shifted = hip.copy()
        shifted[..., 2] += np.array(self.z) - np.array(self._neutral_z)
        return super()._rolling_offsets(shifted, stance, swing_s)

    def _body_xy(self, row: list[float], i: int) -> tuple[float, float]:
        """Body-frame horizontal position of leg i's target in a hip-frame row."""
        c, s = self._cos[i], self._sin[i]
        x, y = row[3 * i], row[3 * i + 1]
        return c * x - s * y + self._hips_xy[i][0], s * x + c * y + self._hips_xy[i][1]

    def _update_plane(self, row: list[float]) -> None:
        """Refits the stance plane and moves every grounded stance target by the levelling/height correction."""
        g = self.ground
        legs = [i for i in range(6) if self.mode[i] in (STANCE, EARLY) and self.grounded[i]]
        xy = [self._body_xy(row, i) for i in legs]
        plane = fit_plane(xy, [self.z[i] for i in legs]) or list(self._plane)
        step = g.update_every * self.dt
        da = -g.height_gain * (plane[0] + g.stand_height) * step
        if g.level:
            w, x, y, z = (float(v) for v in self._sensordata[self.quat_adr : self.quat_adr + 4])
            roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
            pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
            db, dc = -g.attitude_gain * math.tan(pitch) * step, g.attitude_gain * math.tan(roll) * step
        else:
            db, dc = -g.attitude_gain * plane[1] * step, -g.attitude_gain * plane[2] * step
        lo, hi = -g.depth_range[1], -g.depth_range[0]
        clipped = False
        for i, (x, y) in zip(legs, xy, strict=True):
            z = self.z[i] + da + db * x + dc * y
            if not lo <= z <= hi:
                z, clipped = min(hi, max(lo, z)), True
            self.z[i] = z
        self.updates += 1
        self.clipped_updates += clipped
        self._plane = [plane[0] + da, plane[1] + db, plane[2] + dc]

    def _targets(self, row: list[float], stance: list[bool], t: float, row_prev: list[float]) -> list[float]:
        """The planner's hip-frame row at time t with the heights and offsets of uneven ground."""
        g = self.ground
        out = list(row)
        sensed = g.sensed
        modes, was_stance, heights, offsets = self.mode, self._was_stance, self.z, self.offset
        t_lift, z_lifts, offset_lift, landings = self.t_lift, self.z_lift, self.offset_lift, self._landing
        swing_time = self.planner.swing_time
        for i in range(6):
            planned = stance[i]
            mode = modes[i]
            was = was_stance[i]
            was_stance[i] = planned
            if mode == STANCE and planned:  # most legs, most steps: a stance goes on unchanged
                offset, j = offsets[i], 3 * i
                out[j] += offset[0]
                out[j + 1] += offset[1]
                out[j + 2] = heights[i]
                continue
            if mode in (STANCE, SEEKING) and was and not planned:  # planned lift-off
                if mode == SEEKING:
                    self.events.append(Touchdown(i, self.t_lift[i] + self.planner.swing_time, math.nan))
                self.mode[i] = mode = SWING
                self.z_lift[i] = self.z[i]
                self.offset_lift[i] = list(self.offset[i])
                self.t_lift[i] = t - self.dt
                self.grounded[i] = True
                # Where the foot will land (body frame): the planner's touchdown point of this swing.
                landing = self.planner.swing_targets[i]
                self._landing[i] = self._neutral[i] if landing is None else (float(landing[0]), float(landing[1]))
            elif mode == EARLY and planned:
                self.mode[i] = mode = STANCE
            if mode == SWING:
                s = (t - t_lift[i]) / swing_time
                if s > 1.0:
                    s = 1.0
                u = s * s * (3 - 2 * s)
                x, y = landings[i]
                a, b, c = self._plane
                z_lift = z_lifts[i]
                base = z_lift + (a + b * x + c * y - z_lift) * u  # toward the stance plane under the landing point
                z = base + row[3 * i + 2] - self._neutral_z[i]  # + the planner's lift
                offset = offsets[i]
                if s < 0.5:
                    fade = 1.0 - 2.0 * s
                    fade = fade * fade * (3 - 2 * fade)
                    offset[0] = offset_lift[i][0] * fade
                    offset[1] = offset_lift[i][1] * fade
                else:
                    offset[0] = offset[1] = 0.0
                if sensed and s >= 0.5 and self._sensordata[self.touch_adr[i]] > g.touch_threshold:
                    self.events.append(Touchdown(i, self.t_lift[i] + swing_time, t))
                    self.z[i] = z
                    self.mode[i] = mode = EARLY if not planned else STANCE
                    if planned:  # touched right at the planned touchdown
                        out[3 * i + 2] = z
                        out[3 * i] += self.offset[i][0]
                        out[3 * i + 1] += self.offset[i][1]
                        continue
                elif planned:  # the planned touchdown came without a touch
                    self.z[i] = base
                    if sensed:
                        self.mode[i] = mode = SEEKING
                    else:
                        self.mode[i] = mode = STANCE
                        self.events.append(Touchdown(i, t, t))
                else:
                    j = 3 * i
                    out[j] += offset[0]
                    out[j + 1] += offset[1]
                    out[j + 2] = z
                    continue
            if mode == EARLY:
                # Ground-fixed from the touch on: the target moves at the stance velocity, not along the swing.
                cmd = self._cmd.scaled(self._factor(t))  # the command in force (ramp included)
                bx, by = self._body_xy(row_prev, i)
                bx += self.offset[i][0] * self._cos[i] - self.offset[i][1] * self._sin[i]
                by += self.offset[i][0] * self._sin[i] + self.offset[i][1] * self._cos[i]
                vx, vy = -cmd.vx + cmd.yaw_rate * by, -cmd.vy - cmd.yaw_rate * bx
                c, s_ = self._cos[i], self._sin[i]
                hx_, hy_ = c * vx + s_ * vy, -s_ * vx + c * vy  # body -> hip frame
                self.offset[i][0] += hx_ * self.dt - (row[3 * i] - row_prev[3 * i])
                self.offset[i][1] += hy_ * self.dt - (row[3 * i + 1] - row_prev[3 * i + 1])
            elif mode == SEEKING:
                if self._sensordata[self.touch_adr[i]] > g.touch_threshold:
                    self.events.append(Touchdown(i, self.t_lift[i] + self.planner.swing_time, t))
                    self.mode[i] = mode = STANCE
                elif self.z[i] - self.seek_speed * self.dt < -g.depth_range[1]:
                    self.events.append(Touchdown(i, self.t_lift[i] + self.planner.swing_time, math.nan))
                    self.mode[i] = mode = STANCE
                    self.grounded[i] = False
                else:
                    self.z[i] -= self.seek_speed * self.dt
            out[3 * i] += self.offset[i][0]
            out[3 * i + 1] += self.offset[i][1]
            out[3 * i + 2] = self.z[i]
        return out

    def __call__(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Sets data.ctrl for the step from data.time to data.time + dt."""
        k = self._k
        if k >= self._chunk:
            self._replan(data.time)
            k = 0
            self._cmd = Command(*self.commands[-1][1:])
        if self._row_prev is None:
            self._row_prev = self._targets(self._rows[k], self._stance[k], data.time, self._rows[k])
        row0 = self._row_prev
        if self._count % self.ground.update_every == 0:
            self._update_plane(row0)
        self._count += 1
        row1 = self._targets(self._rows[k + 1], self._stance[k + 1], data.time + self.dt, self._rows[k])
        self._servo(feed(self.consts[3], row0, row1, self.dt))
        self._row_prev = row1
        self._k = k + 1
