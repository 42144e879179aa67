"""Walking controller of a legged robot: gait targets per leg, the leg's resolved-rate step, heading hold.

Shared by every robot built of the 3-DOF leg (kinematics/legged.py): the number of legs comes from the
layout, and the model must name its joints, actuators and touch sensors after the layout's legs.

Per control period: read the 3 joint angles of every leg (the servos' encoders), take each foot's target at t
and t + dt from the gait planner (planned a chunk ahead, in the leg's hip frame), and advance each
leg's joint command with `resolved_rate.rate_steps` — the same step leg-step uses, compiled (the
per-step work runs in control/kernels.py; planning, once a chunk, stays here). The servos get
q_cmd (position) and dq (velocity feedforward).

Two corrections make the body go where it is told:
- Rolling feet: a sphere foot that rolls without slipping moves its centre by r dtheta over the
  ground, theta = q2 + q3 its pitch in the leg plane. During stance the foot-centre target is
  shifted by r (theta - theta_touchdown) along the leg's radial direction, so the contact point,
  not the centre, stays where the plan puts it (otherwise the body is a few percent slow or fast).
- Heading hold (optional): the body's yaw from the IMU quaternion (sensor "imu_quat", not the free
  joint) is compared with the integral of the commanded yaw rate, and the yaw rate of the next
  chunk is corrected by heading_gain times the error.

A command that changes (control/commands.py: a schedule, the viewer's steering, a path follower) is asked at
each planning: its twist holds until the source says it changes (the chunk ends there), its gait switches the
planner, its step and stand heights are added to the targets.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from hexabot_sim.control.commands import CommandSource, StanceLog, add_heights
from hexabot_sim.control.compliance import Admittance
from hexabot_sim.control.force_control import StanceForce
from hexabot_sim.control.gait import Command, GaitPlanner, gaits_for
from hexabot_sim.control.resolved_rate import ResolvedRateGains, step_constants
from hexabot_sim.control.walk_settings import GroundSettings, Touchdown, WalkSettings
from hexabot_sim.kinematics import legged


def kernels(*groups: str):
    """control/kernels.py, imported on first use and its kernels of these groups compiled (kernels.GROUPS; none
    given: a walk's own). Importing numba takes ~0.15 s, which `hexabot-sim list` should not pay: it imports this
    module for the parameter tables."""
    from hexabot_sim.control import kernels

    kernels.warm_up(*groups)  # not under the signal hold: a cold compile takes tens of seconds (see kernels.warm_up)
    return kernels


MAX_HEADING_CORRECTION: float = 0.3  # [rad/s] largest yaw-rate correction heading hold adds
# [s] A swing's landing height follows the terrain map's (map_kernels.landing_heights) with this time constant: read
# every step through the body's pose, it carries the body's bobbing into the swing feet. Measured (1 cm rough ground,
# load_sharing=force feet=pad swing=quintic terrain_map=on, seeds 0 and 1, 8 s; tripod / ripple / wave): the force
# ripple of W/6 unfiltered 7.0-7.8 / 8.5-8.7 / 9.4-9.9 %, the wave's impact ratio 2.51-2.96; 10 ms 6.7-7.0 / 7.1-7.2 /
# 8.6-8.8 %, 3.17-3.18; 20 ms 6.5-6.8 / 6.8-7.0 / 8.7-8.9 %, 3.34-3.42; 50 ms 6.4-6.6 / 6.7-6.9 / 9.2-9.5 %, 3.90-4.22
# with 1-11 foot bounces (0-1 at 10 and 20 ms). 20 ms kept: on the flat (sensed touchdown) the wave then has no
# bounce, 9 in 6 s at 10 ms.
MAP_FILTER: float = 0.02


def yaw_of(quat: np.ndarray) -> float:
    """Yaw [rad] of a unit quaternion (w, x, y, z) (z-y-x Euler angles)."""
    w, x, y, z = (float(v) for v in quat)
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


class WalkingController:
    """Drives the 3 n_legs servos of a legged robot's model (models/hexabot.xml for the hexabot) so the body
    follows a walking command.

    Call it before every mj_step (it is a simulate() controller). State lives here: the joint command
    q_cmd (3 n_legs,), the previous joint rate, the planned targets of the current chunk.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        layout: legged.Layout,
        planner: GaitPlanner,
        gains: ResolvedRateGains,
        settings: WalkSettings,
        q_start: np.ndarray,
        source: CommandSource | None = None,
    ) -> None:
        self.layout = layout
        self.source = source  # a command that changes (control/commands.py); None: settings.command throughout
        self.stance_log = StanceLog()  # with a source: the stance flags as planned
        # The heights the planner was built with (the source's at time 0): the source's changes are added to them.
        self._heights0 = None if source is None else [float(v[0]) for v in source.heights(np.zeros(1))]
        self.planner = planner
        self.settings = settings
        self.dt = planner.dt
        self.foot_radius = layout.foot_radius
        n = layout.n_legs
        if planner.n_legs != n:
            raise ValueError(f"the gait planner has {planner.n_legs} legs; the layout has {n}")
        nq = 3 * n
        self.qadr = [int(model.joint(f"{leg}_{j}").qposadr[0]) for leg in layout.legs for j in legged.JOINTS]
        if self.qadr != list(range(7, 7 + nq)):
            raise ValueError(f"the model must put the {nq} leg joints after the free joint, in the layout's order")
        pos_act = [model.actuator(f"{leg}_{j}").id for leg in layout.legs for j in legged.JOINTS]
        vel_act = [model.actuator(f"{leg}_{j}_velocity").id for leg in layout.legs for j in legged.JOINTS]
        if pos_act + vel_act != list(range(2 * nq)):
            raise ValueError(
                f"the model must list the {nq} position then the {nq} velocity actuators in the layout's order"
            )
        self.quat_adr = int(model.sensor_adr[model.sensor("imu_quat").id])
        lower, upper = legged.JOINT_LOWER, legged.JOINT_UPPER
        groups = [g for g, on in (("force", settings.force), ("admittance", settings.admittance)) if on is not None]
        self.kernels = kernels("walk", *groups)  # the force control's, the admittance's: for the walks that run them
        from hexabot_sim.control import plan_kernels  # compiled with the kernels (kernels.warm_up)

        self.plan_kernels = plan_kernels
        self.consts = np.array(step_constants(layout.geometry, gains, lower, upper))
        self.trims = np.array(settings.trims, dtype=float) if settings.trims else np.zeros(nq)
        if self.trims.shape != (nq,):
            raise ValueError(f"{n} legs need {nq} servo trims; got {len(settings.trims)}")
        self.q_cmd = np.array(q_start, dtype=float).ravel()  # the position servos' command [rad]
        if self.q_cmd.shape != (nq,):
            raise ValueError(f"{n} legs need {nq} start joint angles; got {self.q_cmd.size}")
        self.dq = np.zeros(nq)  # the rate it moved at over the last step [rad/s]
        self.rot = layout.hip_rotations()  # (n, 3, 3) hip -> body
        self.hips = layout.hip_positions()  # (n, 3)
        # Targets of the current chunk in each hip frame, one flat row of 3 n floats per step, and stance flags.
        self._feed = np.zeros((0, nq))  # per step: the rate_steps feed (v_des + K x_des)
        self._k = 0
        # Rolling state carried between chunks: last row's offset and offset at lift-off (n, 4), in stance (n,).
        self._rolling = (np.zeros((n, 4)), np.ones(n, dtype=bool))
        g = layout.geometry
        self._foot_geo = np.array([g.l1, g.l2, g.l3, self.foot_radius])  # plan_kernels.hip_targets' geo
        self._no_dz = np.zeros(n)
        self._chunk = 0  # steps in the current chunk (0: plan one first)
        # Heading: desired yaw (integral of the commanded yaw rate) and the unwrapped measured yaw.
        self._yaw_des = 0.0
        self._yaw_meas = yaw_of(data.sensordata[self.quat_adr : self.quat_adr + 4])
        self._yaw_des = self._yaw_meas
        self.commands: list[tuple[float, float, float, float]] = []  # (t, vx, vy, yaw rate) per chunk
        self._qpos = data.qpos
        self._ctrl = data.ctrl
        self._sensordata = data.sensordata
        self.admittance = None if settings.admittance is None else Admittance(
            model, layout.legs, self.hips, layout.yaws, gains.task_gain, self.dt, planner.stance_time,
            settings.admittance,
        )  # fmt: skip
        self.force = None if settings.force is None else self._stance_force(model, layout, gains, planner)
        self._no_extra = np.zeros(nq)  # the feed correction without an admittance
        self._feed_row = np.zeros(nq)

    def _stance_force(self, model, layout, gains, planner) -> StanceForce:
        """The stance legs' force control: its height is the plan's stand height, the body not levelled."""
        stand_height = -float(np.mean(planner.neutral[:, 2]))
        return StanceForce(model, layout, gains, self.dt, self.settings.force, stand_height, False)

    def scale(self, t: np.ndarray | float) -> np.ndarray | float:
        """Fraction of the command in force at t (vectorised): 0 while settling, then a linear ramp to 1."""
        s = self.settings
        if s.ramp_time <= 0:
            return np.where(np.asarray(t) <= s.settle_time, 0.0, 1.0)
        return np.clip((np.asarray(t) - s.settle_time) / s.ramp_time, 0.0, 1.0)

    def _ramping(self, t: float) -> bool:
        """scale(t) < 1 (in floats): the chunk starting at t starts inside the ramp or while settling."""
        s = self.settings
        return t <= s.settle_time if s.ramp_time <= 0 else (t - s.settle_time) / s.ramp_time < 1.0

    def _replan(self, t: float) -> None:
        """Plans the next chunk of targets with the command in force now (and the heading correction).

        The ramp is planned inside the chunk (the planner's scale), so the command grows smoothly
        without short chunks; `commands` records the command before the ramp's factor.
        """
        s = self.settings
        n = self.planner.max_chunk
        cmd = base = s.command
        if self.source is not None:  # the source's twist, held over as many steps as it holds (a chunk at most)
            segment = self.source.segment(t, self._pose())
            cmd = base = segment.command
            n = min(n, max(1, round((segment.until - t) / self.dt))) if math.isfinite(segment.until) else n
            if segment.gait != self.planner.gait.name:  # swings under way finish; the new clock takes over
                self.planner.switch(gaits_for(self.layout.n_legs)[segment.gait])
                if self.admittance is not None:  # its shares' ramps end with the new gait's stance
                    self.admittance.stance_time = self.planner.stance_time
        if s.heading_hold:
            ramp = self.scale(t + self.dt * np.arange(n + 1))
            # Unwrap the IMU yaw next to the last one, compare with the commanded heading.
            quat = self._sensordata[self.quat_adr : self.quat_adr + 4]
            yaw = yaw_of(quat)
            self._yaw_meas += math.remainder(yaw - self._yaw_meas, 2 * math.pi)
            error = self._yaw_des - self._yaw_meas
            correction = max(-MAX_HEADING_CORRECTION, min(MAX_HEADING_CORRECTION, s.heading_gain * error))
            cmd = Command(cmd.vx, cmd.vy, cmd.yaw_rate + correction)
            # The commanded heading advances by the yaw rate times the integral of the ramp over the chunk.
            self._yaw_des += base.yaw_rate * float(np.sum(0.5 * (ramp[1:] + ramp[:-1]))) * self.dt
        self.commands.append((t, cmd.vx, cmd.vy, cmd.yaw_rate))
        ramped = self._ramping(t)
        targets = self.planner.plan(cmd, n, self.scale if ramped else None)  # (n + 1, legs, 3) body frame
        times = self.planner.time - self.dt * np.arange(n, -1, -1)  # (n + 1,)
        stance, swing_s = self.planner.flags(times)  # (n + 1, legs) each
        if self.source is not None:
            self._heights(targets, times, stance, swing_s)
            self.stance_log.append(times, stance)
        # Body -> hip frame of each leg, R^T (p - hip), and the rolling feet's offsets.
        hip = np.empty_like(targets)  # (n + 1, legs, 3)
        offsets, was = self._rolling
        geo = self._foot_geo
        geo[3] = self.foot_radius  # the attribute rules (0: plan as for a point foot)
        self.plan_kernels.hip_targets(targets, self.rot, self.hips, self._pitch_dz(), stance, swing_s, geo, offsets,
                                      was, hip)  # fmt: skip
        self._publish(hip.reshape(n + 1, -1), stance)
        if self.force is not None:
            self.force.plan(self.planner, times, stance)
        self._chunk = n
        self._k = 0

    def planned_stance(self, t: np.ndarray) -> np.ndarray:
        """The plan's stance flags (n, legs) at the times t (n,): as planned chunk by chunk with a command source
        (its gait may have changed), else the planner's clock."""
        return self.stance_log.at(t) if self.stance_log else self.planner.in_stance(t)

    def _pose(self) -> tuple[float, float, float]:
        """The body's planar pose (x, y [m], yaw [rad]) for a command source (a path follower's localisation)."""
        quat = self._sensordata[self.quat_adr : self.quat_adr + 4]
        return float(self._qpos[0]), float(self._qpos[1]), yaw_of(quat)

    def _heights(self, targets: np.ndarray, times: np.ndarray, stance: np.ndarray, swing_s: np.ndarray) -> None:
        """Adds the source's step and stand heights (rows of `times`) to the planned targets (n + 1, legs, 3)."""
        stand = add_heights(targets, self.source, self._heights0, times, stance, swing_s)
        if self.force is not None:  # row by row (it kept its first: a schedule raising the body 30 mm walked back)
            self.force.stand_rows = stand

    def _publish(self, rows: np.ndarray, stance: np.ndarray) -> None:
        """Keeps what the steps of the chunk need from its target rows (n + 1, 3 legs) (hip frames) and stance flags."""
        rates = np.empty(rows[1:].size)
        self.kernels.feed(self.consts[3], rows[:-1].ravel(), rows[1:].ravel(), self.dt, rates)
        self._feed = rates.reshape(rows.shape[0] - 1, rows.shape[1])
        self._rows, self._stance = rows, stance

    def _pitch_dz(self) -> np.ndarray:
        """How far (n_legs,) [m] below the planned height each foot stands, for the rolling feet's pitch (none here).

        The rolling feet (plan_kernels.hip_targets): a sphere foot rolling without slip moves its centre over
        the ground by r dtheta along the leg's radial direction e_r, theta = q2 + q3 its pitch. So in stance the
        centre target is shifted by the sum of r dtheta e_r since touchdown (theta of the shifted target, iterated
        once since the shift changes theta a little; summed step by step because e_r turns with the coxa); in the
        swing, the shift reached at lift-off fades out over the first half. The state at the end of a chunk carries
        over to the next one, whose row 0 repeats the previous chunk's last row.
        """
        return self._no_dz

    def __call__(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Sets data.ctrl for the step from data.time to data.time + dt."""
        k = self._k
        if k >= self._chunk:
            self._replan(data.time)
            k = 0
        feed = self._feed[k]
        if self.admittance is not None:
            extra = self.admittance.update(self._sensordata, self._rows[k], self._stance[k])
            feed = np.add(feed, extra, out=self._feed_row)
        if self.force is not None:  # its kernel runs the servo step too
            self.force.step(self._qpos, self.trims, self._sensordata, self._rows[k], self._stance[k], k, feed,
                            self.consts, self.q_cmd, self.dq, self._ctrl)  # fmt: skip
        else:
            self.kernels.servo(self.consts, self._qpos, self.trims, self.q_cmd, self.dq, feed, self.dt, self._ctrl)
        self._k = k + 1


def fit_plane(xy: list[tuple[float, float]], z: list[float]) -> list[float] | None:
    """Least-squares plane z = a + b x + c y through the points, [a, b, c]; None if they do not span one."""
    x, y = np.array(xy, dtype=float).reshape(-1, 2).T
    out = np.zeros(3)
    ok = kernels().plane_fit(np.ascontiguousarray(x), np.ascontiguousarray(y), np.asarray(z, dtype=float), len(z), out)
    return out.tolist() if ok else None


class GroundController(WalkingController):
    """WalkingController with feet that find the ground and (optionally) a body kept level.

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
      descending at half the swing's peak vertical speed until it touches or leaves the workspace.
    The per-step part (this state machine, the plane, the servo step) is kernels.ground_step; the
    legs' state lives in the arrays `legs` and `flags` (layout in the kernels module).
    """

    def __init__(
        self, model, data, layout, planner, gains, settings, q_start, ground: GroundSettings, source=None
    ) -> None:
        self.ground = ground  # before the base's __init__: its _stance_force reads it
        self._stand_rows: np.ndarray | None = None  # a changing command's stand height at each row of the chunk
        super().__init__(model, data, layout, planner, gains, settings, q_start, source)
        K = self.kernels
        n = layout.n_legs
        touch_adr = [int(model.sensor_adr[model.sensor(f"{leg}_touch").id]) for leg in layout.legs]
        feet = legged.feet_body(layout, np.asarray(q_start).reshape(n, 3))  # (n, 3)
        neutral = np.asarray(planner.neutral, dtype=float)
        # The legs' state (kernels module docstring): every foot in stance where it stands now.
        self.legs = np.zeros((n, K.NLEG))
        self.legs[:, K.Z] = self.legs[:, K.Z_LIFT] = feet[:, 2]
        self.legs[:, K.LANDING : K.LANDING + 2] = self.legs[:, K.NEXT_LANDING : K.NEXT_LANDING + 2] = neutral[:, :2]
        self.flags = np.zeros((n, 3), dtype=np.int64)
        self.flags[:, K.MODE] = K.STANCE
        self.flags[:, K.WAS_STANCE] = self.flags[:, K.GROUNDED] = 1
        self.plane = np.array([-ground.stand_height, 0.0, 0.0])  # stance plane z = a + b x + c y (body frame)
        self.counts = np.zeros(3, dtype=np.int64)
        self.cmd = np.zeros(3)  # the chunk's command (vx, vy, yaw rate), heading correction included
        self.geo = np.zeros((n, K.NGEO))
        self.geo[:, K.COS], self.geo[:, K.SIN] = np.cos(layout.yaws), np.sin(layout.yaws)
        self.geo[:, K.HIP_X : K.HIP_Y + 1] = self.hips[:, :2]
        self.geo[:, K.NEUTRAL_Z] = neutral[:, 2]
        self.geo[:, K.TOUCH_ADR] = touch_adr
        self.par = np.zeros(K.NPAR)
        self.par[[K.SENSED, K.LEVEL]] = ground.sensed, ground.level
        self.par[K.STAND_HEIGHT] = ground.stand_height
        self.par[[K.DEPTH_MIN, K.DEPTH_MAX]] = ground.depth_range
        self.par[[K.ATTITUDE_GAIN, K.HEIGHT_GAIN]] = ground.attitude_gain, ground.height_gain
        self.par[[K.TOUCH_THRESHOLD, K.UPDATE_EVERY]] = ground.touch_threshold, ground.update_every
        self._swing_time(planner)
        self.par[[K.DT, K.SETTLE_TIME, K.RAMP_TIME]] = self.dt, settings.settle_time, settings.ramp_time
        self.par[K.QUAT_ADR] = self.quat_adr
        self.par[[K.REFLEX_LIFT, K.REFLEX_UNTIL]] = ground.reflex_lift, ground.reflex_until
        self.par[K.REFLEX_RISE] = ground.reflex_rise
        self.par[K.EARLY_BAND] = ground.early_band
        self.legs[:, K.T_REFLEX] = -math.inf
        self.legs[:, K.MAP_Z] = math.nan  # no map, or not swinging: swings end on the stance plane
        self.events: list[Touchdown] = []
        self._new_swing_time_at = math.inf  # [s] after a gait switch: when the kernel takes the new gait's swing time
        self._events = np.zeros((n, 3))  # swings that ended in one step (kernels.targets): one a leg at most
        self._row_prev = np.zeros(3 * n)  # the targets at the current time (hip frames)
        self._started = False
        self._down = np.zeros(n, dtype=bool)
        self._down_modes = np.array([K.STANCE, K.EARLY], dtype=np.int64)  # with GROUNDED: the leg is down
        self._map = None  # a terrain map: (its kernels, their scalars, the heights)
        if ground.terrain_map is not None:
            from hexabot_sim.control import map_kernels  # compiled by kernels("map")

            kernels("map")
            edge = map_kernels.edge_range(ground.terrain_map.error)
            mpar = np.array([*ground.terrain_map.params(), layout.foot_radius, MAP_FILTER, edge])
            self._map = (map_kernels, mpar, ground.terrain_map.heights)

    def _stance_force(self, model, layout, gains, planner) -> StanceForce:
        """The stance legs' force control with the ground's height and levelling; the ground's own touchdown
        modes say when a leg is down."""
        force = StanceForce(
            model, layout, gains, self.dt, self.settings.force, self.ground.stand_height, self.ground.level
        )
        force.par[force.fk.EARLY_AFTER] = math.inf
        return force

    def _swing_time(self, planner: GaitPlanner) -> None:
        """The kernel's swing time and late-touchdown seek speed (half the swing's peak) from the planner's gait."""
        K = self.kernels
        self.par[K.SWING_TIME] = planner.swing_time
        self.par[K.SEEK_SPEED] = math.pi * planner.step_height / (2 * planner.swing_time)

    @property
    def updates(self) -> int:
        """Stance-plane updates so far."""
        K = self.kernels
        return int(self.counts[K.UPDATES])

    @property
    def clipped_updates(self) -> int:
        """Stance-plane updates whose heights were clipped to the legs' workspace."""
        K = self.kernels
        return int(self.counts[K.CLIPPED])

    def _publish(self, rows: np.ndarray, stance: np.ndarray) -> None:
        """Keeps the rows and stance flags themselves (the heights are set step by step) and the next landings."""
        K = self.kernels
        self._rows = np.ascontiguousarray(rows)
        self._stance = np.ascontiguousarray(stance)
        chosen = self.planner.landing_set
        self.legs[chosen, K.NEXT_LANDING : K.NEXT_LANDING + 2] = self.planner.landing[chosen]

    def _heights(self, targets: np.ndarray, times: np.ndarray, stance: np.ndarray, swing_s: np.ndarray) -> None:
        """The source's step height on the swings' lift; its stand height drives the stance plane row by row (the
        chunk's last row drove it up to 1 s ahead), and the force control's height."""
        self._stand_rows = add_heights(targets, self.source, self._heights0, times, stance, swing_s, stand=False)
        if self.force is not None:
            self.force.stand_rows = self._stand_rows

    def _pitch_dz(self) -> np.ndarray:
        """The rolling feet's pitch at the heights the feet stand at now (not the planned flat-ground height)."""
        K = self.kernels
        return self.legs[:, K.Z] - self.geo[:, K.NEUTRAL_Z]

    def _record(self, n: int) -> None:
        """Keeps the n swings that ended in the last kernel call.

        The kernel dates a swing's planned touchdown as its lift-off plus the swing time in force; a swing of the
        gait before a switch that lands late, after the kernel took the new gait's swing time, is re-dated with
        its own (the planner's record of it).
        """
        for leg, planned, t in self._events[:n]:
            leg, planned = int(leg), float(planned)
            if self.planner.switches:
                lift, touchdown = self.planner.switch_swing(leg)
                swing_time = float(self.par[self.kernels.SWING_TIME])
                if abs(planned - swing_time - lift) <= 1.5 * self.dt:
                    planned += (touchdown - lift) - swing_time
            self.events.append(Touchdown(leg, planned, float(t)))

    def __call__(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Sets data.ctrl for the step from data.time to data.time + dt."""
        K = self.kernels
        k = self._k
        if k >= self._chunk:
            switches = len(self.planner.switches)
            self._replan(data.time)
            k = 0
            self.cmd[:] = self.commands[-1][1:]
            if len(self.planner.switches) > switches:  # a gait switch: the swings under way keep their timing
                self._new_swing_time_at = self.planner.clock_from
        rows, stance, t = self._rows, self._stance, data.time
        if t >= self._new_swing_time_at - 1.5 * self.dt:  # the last old swing's last step is done; a new one lifts
            self._swing_time(self.planner)
            self._new_swing_time_at = math.inf
        if not self._started:  # the targets at the start
            n = K.targets(self.par, self.geo, self.legs, self.flags, self.plane, self.cmd, rows[k], stance[k], t,
                          rows[k], self._sensordata, self._row_prev, self._events)  # fmt: skip
            self._record(n)
            self._started = True
        extra = self._no_extra
        if self._stand_rows is not None:
            self.par[K.STAND_HEIGHT] = self._stand_rows[k]
        if self.admittance is not None:
            extra = self.admittance.update(self._sensordata, self._row_prev, stance[k])
        force = self.force
        if force is not None:
            force.fk.ground_down(self.flags, self._down_modes, K.NEAR, force.state, self._down)
            extra = force.pre(self._qpos, self.trims, self._sensordata, self._row_prev, self._down, k)
        if self._map is not None:
            mk, mpar, hmap = self._map
            mk.landing_heights(self.par, mpar, hmap, self.legs, self.flags, self.plane, self._qpos, self.cmd, t)
        n = K.ground_step(self.par, self.geo, self.consts, self.legs, self.flags, self.plane, self.counts, self.cmd,
                          rows, stance, k, t, self._row_prev, self.q_cmd, self.dq, self.trims, self._qpos,
                          self._sensordata, self._ctrl, self._events, extra)  # fmt: skip
        if force is not None:
            force.post(self._qpos, self.trims, self.q_cmd, self.dq, self._ctrl)
        if n:
            self._record(n)
        self._k = k + 1
