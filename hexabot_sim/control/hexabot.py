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
from hexabot_sim.control.resolved_rate import ResolvedRateGains, rate_steps, step_constants
from hexabot_sim.kinematics import hexabot as hx

MAX_HEADING_CORRECTION: float = 0.3  # [rad/s] largest yaw-rate correction heading hold adds
RAMP_CHUNK_TIME: float = 0.02  # [s] planning chunk while the command ramps up


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
        self._rows: list[list[float]] = []
        self._stance: list[list[bool]] = []
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

    def scale(self, t: float) -> float:
        """Fraction of the command in force at t: 0 while settling, then a linear ramp to 1."""
        s = self.settings
        if t <= s.settle_time:
            return 0.0
        return 1.0 if s.ramp_time <= 0 else min(1.0, (t - s.settle_time) / s.ramp_time)

    def _replan(self, t: float) -> None:
        """Plans the next chunk of targets with the command in force now (and the heading correction)."""
        s = self.settings
        n = self.planner.max_chunk
        if self.scale(t) < 1.0:
            # Ramping: short chunks, so the command grows in steps too small to jolt the servos.
            n = max(1, min(n, round(RAMP_CHUNK_TIME / self.dt)))
        scale = self.scale(t + 0.5 * n * self.dt)
        cmd = s.command.scaled(scale)
        if s.heading_hold:
            # Unwrap the IMU yaw next to the last one, compare with the commanded heading.
            quat = self._sensordata[self.quat_adr : self.quat_adr + 4]
            yaw = yaw_of(quat)
            self._yaw_meas += math.remainder(yaw - self._yaw_meas, 2 * math.pi)
            error = self._yaw_des - self._yaw_meas
            correction = max(-MAX_HEADING_CORRECTION, min(MAX_HEADING_CORRECTION, s.heading_gain * error))
            if scale > 0:
                cmd = Command(cmd.vx, cmd.vy, cmd.yaw_rate + correction)
            self._yaw_des += s.command.yaw_rate * scale * n * self.dt
        self.commands.append((t, cmd.vx, cmd.vy, cmd.yaw_rate))
        targets = self.planner.plan(cmd, n)  # (n + 1, 6, 3) body frame
        times = self.planner.time - self.dt * np.arange(n, -1, -1)  # (n + 1,)
        stance = self.planner.in_stance(times)  # (n + 1, 6)
        duty = self.planner.gait.duty
        swing_s = np.where(stance, 0.0, (self.planner.phase(times) - duty) / (1.0 - duty))
        # Body -> hip frame of each leg: R^T (p - hip).
        hip = np.einsum("lji,klj->kli", self.rot, targets - self.hips)  # (n + 1, 6, 3)
        hip += self._rolling_offsets(hip, stance, swing_s)
        self._rows = hip.reshape(n + 1, 18).tolist()
        self._stance = stance.tolist()
        self._chunk = n
        self._k = 0

    def _rolling_offsets(self, hip: np.ndarray, stance: np.ndarray, swing_s: np.ndarray) -> np.ndarray:
        """Offsets (n + 1, 6, 3) of the foot-centre targets for feet that roll without slipping.

        A sphere foot rolling without slip moves its centre over the ground by r dtheta along the leg's
        radial direction e_r, theta = q2 + q3 its pitch. So in stance the centre target is shifted by
        the sum of r dtheta e_r since touchdown (theta from the target's IK, iterated once since the
        shift changes theta a little; summed step by step because e_r turns with the coxa); in the
        swing, the shift reached at lift-off fades out over the first half. The state at the end of a
        chunk carries over to the next one, whose row 0 repeats the previous chunk's last row.
        """
        radial = hip[..., :2] / np.hypot(hip[..., 0], hip[..., 1])[..., None]  # (n + 1, 6, 2)
        fade = 1.0 - np.clip(2.0 * swing_s[1:], 0.0, 1.0)
        fade = fade * fade * (3.0 - 2.0 * fade)  # (n, 6) smoothstep from 1 to 0
        offset = np.repeat(self._rolling[1][None], hip.shape[0], axis=0)  # (n + 1, 6, 2) [m]
        for _ in range(2):
            shifted = hip.copy()
            shifted[..., :2] += offset
            q, _ = hx.ik_hip_batch(self.layout, shifted)
            offset, state = self._offsets(q[..., 1] + q[..., 2], stance, fade, radial)
        self._rolling = state
        out = np.zeros_like(hip)
        out[..., :2] = offset
        return out

    def _offsets(self, theta, stance, fade, radial):
        """Rolling offsets (n + 1, 6, 2) from the foot pitch theta (n + 1, 6), and the state to carry over."""
        n = theta.shape[0] - 1
        rows = np.arange(1, n + 1)[:, None]  # (n, 1)
        offset0, lift0, was0 = self._rolling
        st = stance[1:]  # (n, 6); row 0 is the previous chunk's last row
        before = np.vstack([was0[None], st[:-1]])
        touchdown, liftoff = st & ~before, ~st & before
        # Stance: r dtheta e_r step by step, summed since the latest touchdown (else from the carried offset).
        rolling = (st & before)[..., None]
        e_mid = radial[1:] + radial[:-1]
        e_mid /= np.linalg.norm(e_mid, axis=-1, keepdims=True)
        increment = np.where(rolling, self.foot_radius * np.diff(theta, axis=0)[..., None] * e_mid, 0.0)
        total = np.cumsum(increment, axis=0)  # (n, 6, 2)
        last_td = np.maximum.accumulate(np.where(touchdown, rows, 0), axis=0)  # (n, 6) row, 0 = none yet
        at_td = np.take_along_axis(total, np.maximum(last_td - 1, 0)[..., None], axis=0)
        stance_offset = np.where((last_td > 0)[..., None], total - at_td, offset0 + total)
        # Swing: the offset of the last stance row, faded out.
        full = np.concatenate([offset0[None], np.where(st[..., None], stance_offset, 0.0)])  # (n + 1, 6, 2)
        last_lo = np.maximum.accumulate(np.where(liftoff, rows, 0), axis=0)
        at_lo = np.take_along_axis(full, np.maximum(last_lo - 1, 0)[..., None], axis=0)
        lift = np.where((last_lo > 0)[..., None], at_lo, lift0)
        offset = np.concatenate([offset0[None], np.where(st[..., None], stance_offset, lift * fade[..., None])])
        return offset, (offset[-1], lift[-1], st[-1])

    def __call__(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Sets data.ctrl for the step from data.time to data.time + dt."""
        k = self._k
        if k >= self._chunk:
            self._replan(data.time)
            k = 0
        q_cmd, dq = self.q_cmd, self.dq
        if self._trimmed:
            trims = self.trims
            q = [a - b for a, b in zip(self._qpos[7:25].tolist(), trims, strict=True)]  # what the encoders read
            rate_steps(self.consts, q, q_cmd, dq, self._rows[k], self._rows[k + 1], self.dt)
            self._ctrl[:] = [a + b for a, b in zip(q_cmd, trims, strict=True)] + dq
        else:
            rate_steps(self.consts, self._qpos[7:25].tolist(), q_cmd, dq, self._rows[k], self._rows[k + 1], self.dt)
            self._ctrl[:] = q_cmd + dq  # position servos: q_cmd; velocity servos: dq
        self._k = k + 1
