"""Stance legs under force control (issue 19, `load_sharing=force`): a force distribution fed to the servos as joint
torques.

A position-controlled leg in a stance of four or more feet holds a height, not a force: the loads are undetermined
by statics and set by micrometres of geometry, so a lightly loaded foot unloads and lands again. Here each stance
leg holds its foot *horizontally* with its position servos as before, but *vertically* it pushes with a commanded
force (a virtual model controller with a force distribution, as legged robots with force-controlled stances do):

- the body's wrench: the robot's weight m g plus a PI on the body's height over the stance feet and a P on its
  attitude, Fz and the moments about the body's x and y axes. The errors come from the joint encoders: the
  weighted plane z = a + b x + c y through the stance feet (body frame); height error a + stand_height, slope
  errors (b, c) (with `level_body=on` the IMU's pitch and roll instead). They move with the feet that are down
  (the plane through the same feet with the same weights now and a step ago), drawn to the plane's own values over
  `filter_time` (the height) and `slope_filter_time` (the slopes): a foot that lands or lifts changes the plane at
  once, which would be a step in the wrench;
- its distribution: the vertical forces on the stance feet with the least weighted norm sum f_i^2 / w_i that sum
  to Fz, the moments soft (force_kernels.distribute, a closed form); a foot's weight ramps up from `least_weight`
  over `ramp_in` after its touchdown and down over `ramp_out` before its planned lift-off (with a `duty` above the
  gait's own, `for_overlap`: smoothstep ramps over the whole overlap of a landing and a lifting foot, so their
  weights sum to 1, and each foot's force closed around its touch sensor);
- the torques: each stance leg's position command is offset by tau / kp, tau = J_z^T (-f_i - F_z,servo), which
  replaces the vertical foot force the position servo would exert (beyond holding the leg's own weight) by the
  commanded one (the foot pushes down with f_i); the position command's height follows the measured foot's and
  the velocity command loses its vertical part, so vertically the servos keep only their damping. A leg blends
  into force mode over `blend_in` from its touchdown (planned, sensed by the ground controller, or its touch
  sensor firing after it was off the ground for `early_after`), and back to position control over `blend_out` after
  lift-off; the swing starts from where the foot is (a height offset that returns to the plan over
  `return_time`).

The controller reads what a real robot has: joint encoders, the touch sensors, the IMU, and the plan; the robot's
mass and the legs' link masses are design knowledge. The torque reaches the joints through the servos (the
position actuator's command offset); nothing else acts on the model. Compiled per step: force_kernels.py.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np


@dataclasses.dataclass(frozen=True)
class ForceSettings:
    """The stance force control's gains and ramps.

    Attributes:
        ramp_in: A foot's weight in the distribution ramps up over this time after touchdown [s].
        ramp_out: ... and down over this time before its planned lift-off [s].
        least_weight: The smallest weight (at touchdown and lift-off).
        blend_in: A leg's vertical control goes from position to force over this time after touchdown [s].
        blend_out: ... and back over this time after lift-off [s].
        height_gain, height_integral: PI on the body's height [N/m, N/(m s)].
        attitude_gain, attitude_integral: PI on the slopes [N m, N m / s] per unit slope.
        filter_time: The height error is drawn to the stance plane's with this time constant [s].
        slope_filter_time: ... and the slope errors with this one [s] (without `level_body`): on uneven ground
            the plane through the stance feet tilts in steps as feet land and lift, which at 50 ms swung the
            moments asked for by tens of N m and left stance feet commanded no force (1 cm rough ground).
        integral_limit: The integrals' bound [m s or s].
        return_time: In swing the target's height offset returns to the plan with this time constant [s].
        soft: The moments' softness r in the distribution [m^2] (0: exact; see force_kernels.distribute).
        touch_threshold: A swing foot whose touch sensor reads more than this [N] ...
        early_after: ... after it was off the ground (neither down nor touching) this long [s] is down (the
            planned controller; the ground controller's sensed touchdown says so itself). A foot that has not
            left the ground yet (a slow lift-off still on the pad) is not landing.
        smooth: The weights' ramps are smoothstep 3 x^2 - 2 x^3 instead of linear (force_kernels.ramp).
        from_plan: A foot down before its planned (or, with the ground controller, sensed) touchdown keeps the
            least weight until then; its ramp starts there.
        force_gain: Each stance foot's commanded force is corrected by this gain times its error against the
            foot's touch sensor (0: open loop).
        landing_lift: In swing the target's height offset returns to this much above the plan [m], so a foot
            meets the pad near its planned touchdown, not before it (force mode then presses it down).
    """

    ramp_in: float = 0.01
    ramp_out: float = 0.01
    least_weight: float = 0.01
    blend_in: float = 0.01
    blend_out: float = 0.01
    height_gain: float = 20000.0
    height_integral: float = 200000.0
    attitude_gain: float = 1500.0
    attitude_integral: float = 0.0
    filter_time: float = 0.05
    integral_limit: float = 0.01
    return_time: float = 0.05
    soft: float = 0.01
    touch_threshold: float = 0.3
    early_after: float = 0.06
    smooth: bool = False
    from_plan: bool = False
    force_gain: float = 0.0
    landing_lift: float = 0.0
    slope_filter_time: float = 0.5


HEIGHT_FILTER_SHARE = 0.05  # the height error's filter time over the gait period
RAMP_SHARE = 0.01  # the weights' ramps at touchdown and lift-off over the gait period


def for_walk(period: float, overlap: float) -> ForceSettings:
    """The settings of a walk with gait period `period` [s] whose hand-overs overlap by `overlap` [s] (a `duty`
    above the gait's own). The times scale with the period, never below the defaults (tuned at the default 1 s,
    and unchanged there and at shorter periods):

    - the height error is drawn to the stance plane over 5 % of the period, at least 50 ms (below it a landing
      foot's pad compressing reads as the body rising, and the sag grows). On uneven ground the plane steps by a
      millimetre or more when a tripod hands over, and the body then moves to its new height within a few filter
      times; over a fixed 50 ms that move is as sudden at a 3 s period as at 1 s (the 3 s tripod's force ripple on
      1 cm rough ground 2.6-3.1 %, half of it in the 50-200 ms after a touchdown);
    - a foot's weight ramps over 1 % of the period, at least 10 ms, after its touchdown and before its lift-off;
      an overlap longer than that ramps over the whole overlap instead (`for_overlap`).

    Measured at `period=3` on 1 cm rough ground with the pad, the quintic swing and the terrain map, seeds 0-4: force
    ripple tripod / ripple / wave 2.4-2.7 / 2.2-2.4 / 2.6-2.9 % with the filter alone, 2.0-2.1 / 1.9-2.2 /
    2.5-2.8 % with the ramps too (docs/hexabot.md)."""
    ramp = max(ForceSettings.ramp_in, RAMP_SHARE * period)
    settings = for_overlap(overlap) if overlap > ramp + 1e-9 else ForceSettings(ramp_in=ramp, ramp_out=ramp)
    return dataclasses.replace(settings, filter_time=max(settings.filter_time, HEIGHT_FILTER_SHARE * period))


def for_overlap(overlap: float) -> ForceSettings:
    """The settings for hand-overs that overlap by `overlap` [s] (a `duty` above the gait's own: a foot lands
    that long before the one it relieves lifts): each foot's weight ramps up over the whole overlap from its
    planned touchdown and down over the whole overlap to its planned lift-off, smoothstep, so a landing foot's
    and a lifting foot's weights sum to 1 throughout; the commanded forces closed around the touch sensors (gain
    1: the servos' damping and the pad otherwise make the feet's forces lag the command by ~20-30 ms); the swing
    ends 0.4 mm above the plan (half the pad's compression under a foot's share), so the foot meets the pad at
    about its planned touchdown; the least weight 0.05 (a landing foot pressed lightly at once, not pulled off by
    the force loop). An overlap not above the default ramps' 10 ms: the defaults."""
    if overlap <= ForceSettings.ramp_in + 1e-9:
        return ForceSettings()
    return ForceSettings(ramp_in=overlap, ramp_out=overlap, least_weight=0.05, smooth=True, from_plan=True,
                         force_gain=1.0, landing_lift=0.0004)  # fmt: skip


class StanceForce:
    """The force control of every leg of a walking controller: `plan` once a chunk, `pre` and `post` every step."""

    def __init__(self, model: mujoco.MjModel, layout, gains, dt: float, settings: ForceSettings, stand_height: float,
                 level: bool) -> None:  # fmt: skip
        from hexabot_sim.control import force_kernels as fk

        self.fk = fk
        n = layout.n_legs
        self.settings = settings
        self.dt = dt
        hips = layout.hip_positions()
        self.geo = np.zeros((n, 5))
        self.geo[:, fk.TOUCH_ADR] = [model.sensor_adr[model.sensor(f"{leg}_touch").id] for leg in layout.legs]
        self.geo[:, fk.COS], self.geo[:, fk.SIN] = np.cos(layout.yaws), np.sin(layout.yaws)
        self.geo[:, fk.HIP_X], self.geo[:, fk.HIP_Y] = hips[:, 0], hips[:, 1]
        g = layout.geometry
        mass = float(model.body_subtreemass[model.body("torso").id])
        s = settings
        p = np.zeros(fk.NPAR)
        p[fk.DT], p[fk.WEIGHT] = dt, mass * float(-model.opt.gravity[2])
        p[[fk.T_IN, fk.T_OUT, fk.S_IN, fk.S_OUT, fk.W_MIN]] = (
            s.ramp_in,
            s.ramp_out,
            s.blend_in,
            s.blend_out,
            s.least_weight,
        )
        p[[fk.K_H, fk.I_H, fk.K_T, fk.I_T]] = s.height_gain, s.height_integral, s.attitude_gain, s.attitude_integral
        p[fk.STAND], p[fk.LEVEL] = stand_height, float(level)
        p[fk.QUAT_ADR] = model.sensor_adr[model.sensor("imu_quat").id]
        p[fk.RETURN_TIME], p[fk.TASK_GAIN] = s.return_time, gains.task_gain
        p[[fk.L1, fk.L2, fk.L3]] = g.l1, g.l2, g.l3
        p[fk.FILTER], p[fk.I_LIMIT], p[fk.SOFT] = s.filter_time, s.integral_limit, s.soft
        p[fk.TOUCH_THRESHOLD], p[fk.EARLY_AFTER] = s.touch_threshold, s.early_after
        p[fk.SMOOTH], p[fk.FROM_PLAN], p[fk.K_F] = float(s.smooth), float(s.from_plan), s.force_gain
        p[fk.LIFT] = s.landing_lift
        p[fk.SLOPE_FILTER] = s.slope_filter_time
        femur, tibia = model.body(f"{layout.legs[0]}_femur"), model.body(f"{layout.legs[0]}_tibia")
        gravity = float(-model.opt.gravity[2])
        p[fk.G_FEMUR] = float(femur.mass[0]) * gravity * float(femur.ipos[0])
        p[fk.G_TIBIA], p[fk.TIBIA_COM] = float(tibia.mass[0]) * gravity, float(tibia.ipos[0])
        self.par = p
        self.state = np.zeros((n, fk.NSTATE))
        self.body = np.zeros(fk.NBODY)
        self.kp = np.ascontiguousarray(model.actuator_gainprm[: 3 * n, 0], dtype=float)
        self.extra = np.zeros(3 * n)
        self._until = np.full((1, n), 1e9)  # per row of the chunk: time to each leg's next planned lift-off [s]
        self.stand_rows: np.ndarray | None = None  # per row of the chunk: a changing command's stand height [m]

    def plan(self, planner, times: np.ndarray, stance: np.ndarray) -> None:
        """The chunk's rows (times (m,), planned stance (m, n)): the time from each row to each leg's next planned
        lift-off (after its next touchdown if it is in swing; 1e9 beyond the plan's next ramp_out)."""
        dt = self.dt
        extra = max(1, int(np.ceil(self.settings.ramp_out / dt)) + 2)
        later = planner.in_stance(times[-1] + dt * np.arange(1, extra + 1))
        flags = np.concatenate([stance, later.reshape(extra, -1)])
        rows = flags.shape[0]
        idx = np.arange(rows)[:, None]
        nf = np.minimum.accumulate(np.where(~flags, idx, rows)[::-1], axis=0)[::-1]  # next swing row
        nt = np.minimum.accumulate(np.where(flags, idx, rows)[::-1], axis=0)[::-1]  # next stance row
        legs = np.arange(flags.shape[1])[None, :]
        lift = np.where(nt < rows, nf[np.minimum(nt, rows - 1), legs], rows)
        until = np.where(lift < rows, (lift - idx) * dt, 1e9)
        self._until = np.ascontiguousarray(until[: stance.shape[0]])

    def pre(self, qpos, trims, sensordata, row, down, k: int) -> np.ndarray:
        """Before the servo step of row k: returns the feed correction (3 n,)."""
        if self.stand_rows is not None:
            self.par[self.fk.STAND] = self.stand_rows[k]
        self.fk.force_pre(self.par, self.geo, self.state, self.body, qpos, trims, sensordata, row, down,
                          self._until[k], self.extra)  # fmt: skip
        return self.extra

    def post(self, qpos, trims, q_cmd, dq, ctrl) -> None:
        """After the servo step: the force-mode legs' servo commands."""
        self.fk.force_post(self.par, self.state, qpos, trims, q_cmd, dq, self.kp, ctrl)

    def step(self, qpos, trims, sensordata, row, down, k: int, feed, consts, q_cmd, dq, ctrl) -> None:
        """pre, the servo step toward `feed` and post in one compiled call (the planned controller)."""
        if self.stand_rows is not None:
            self.par[self.fk.STAND] = self.stand_rows[k]
        self.fk.force_step(self.par, self.geo, self.state, self.body, qpos, trims, sensordata, row, down,
                           self._until[k], feed, consts, q_cmd, dq, self.kp, ctrl)  # fmt: skip

    @property
    def forces(self) -> np.ndarray:
        """The commanded vertical ground force of each foot now [N] (n_legs,)."""
        return self.state[:, self.fk.FORCE].copy()
