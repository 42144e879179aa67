"""Walking controller of the hexabot: gait targets per leg, the leg's resolved-rate step, heading hold.

Per control period: read the 18 joint angles (the servos' encoders), take each foot's target at t
and t + dt from the gait planner (planned a chunk ahead, in the leg's hip frame), and advance each
leg's joint command with `resolved_rate.rate_step` — the same step leg-step uses. The servos get
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
from hexabot_sim.control.resolved_rate import ResolvedRateGains, rate_step, step_constants
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
        self.q_cmd = [float(v) for v in np.asarray(q_start).ravel()]
        self.dq = [0.0] * 18
        self.rot = layout.hip_rotations()  # (6, 3, 3) hip -> body
        self.hips = layout.hip_positions()  # (6, 3)
        # Targets of the current chunk in each hip frame, one flat row of 18 floats per step, and stance flags.
        self._rows: list[list[float]] = []
        self._stance: list[list[bool]] = []
        self._k = 0
        self._theta_td = [self.q_cmd[3 * i + 1] + self.q_cmd[3 * i + 2] for i in range(6)]  # foot pitch at touchdown
        self._was_stance = [True] * 6
        self._roll_lo = [(0.0, 0.0)] * 6  # rolling offset (x, y) [m] in the hip frame at lift-off
        self._fade: list[list[float]] = []
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
        # Weight of the stance's rolling offset, fading out smoothly over the first half of the swing.
        fade = 1.0 - np.clip(2.0 * swing_s, 0.0, 1.0)
        self._fade = (fade * fade * (3.0 - 2.0 * fade)).tolist()
        # Body -> hip frame of each leg: R^T (p - hip).
        hip = np.einsum("lji,klj->kli", self.rot, targets - self.hips)  # (n + 1, 6, 3)
        self._rows = hip.reshape(n + 1, 18).tolist()
        self._stance = stance.tolist()
        self._k = 0

    def __call__(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Sets data.ctrl for the step from data.time to data.time + dt."""
        if self._k >= len(self._rows) - 1:
            self._replan(data.time)
        k = self._k
        row0, row1, stance = self._rows[k], self._rows[k + 1], self._stance[k]
        fade0, fade1 = self._fade[k], self._fade[k + 1]
        qpos, trims, q_cmd, dq, consts, dt, r = (
            self._qpos,
            self.trims,
            self.q_cmd,
            self.dq,
            self.consts,
            self.dt,
            self.foot_radius,
        )
        q = qpos[7:25].tolist()
        ctrl = [0.0] * 36
        for leg in range(6):
            j = 3 * leg
            c1, c2, c3 = q_cmd[j], q_cmd[j + 1], q_cmd[j + 2]
            x0, y0, z0, x1, y1, z1 = row0[j], row0[j + 1], row0[j + 2], row1[j], row1[j + 1], row1[j + 2]
            if stance[leg]:
                # Rolling foot: shift the centre target by r (theta - theta_td) along the leg's radial direction.
                if not self._was_stance[leg]:
                    self._theta_td[leg] = c2 + c3
                    self._was_stance[leg] = True
                roll0 = r * (c2 + c3 - self._theta_td[leg])
                roll1 = roll0 + r * (dq[j + 1] + dq[j + 2]) * dt
                e1, e2 = math.cos(c1), math.sin(c1)
                x0, y0, x1, y1 = x0 + roll0 * e1, y0 + roll0 * e2, x1 + roll1 * e1, y1 + roll1 * e2
            else:
                if self._was_stance[leg]:  # lift-off: remember the rolling offset, fade it out in the swing
                    self._was_stance[leg] = False
                    roll = r * (c2 + c3 - self._theta_td[leg])
                    self._roll_lo[leg] = (roll * math.cos(c1), roll * math.sin(c1))
                ox, oy = self._roll_lo[leg]
                f0, f1 = fade0[leg], fade1[leg]
                x0, y0, x1, y1 = x0 + f0 * ox, y0 + f0 * oy, x1 + f1 * ox, y1 + f1 * oy
            n1, n2, n3, v1, v2, v3 = rate_step(
                consts,
                q[j] - trims[j], q[j + 1] - trims[j + 1], q[j + 2] - trims[j + 2],
                c1, c2, c3, dq[j], dq[j + 1], dq[j + 2],
                x0, y0, z0, x1, y1, z1, dt,
            )  # fmt: skip
            q_cmd[j], q_cmd[j + 1], q_cmd[j + 2] = n1, n2, n3
            dq[j], dq[j + 1], dq[j + 2] = v1, v2, v3
            ctrl[j], ctrl[j + 1], ctrl[j + 2] = n1 + trims[j], n2 + trims[j + 1], n3 + trims[j + 2]
            ctrl[18 + j], ctrl[19 + j], ctrl[20 + j] = v1, v2, v3
        self._ctrl[:] = ctrl
        self._k = k + 1
