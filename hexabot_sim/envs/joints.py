"""Joint-level control of a legged robot: the policy sets every servo's target (HexabotJoints-v0, QuadbotJoints-v0)."""

from __future__ import annotations

import mujoco
import numpy as np
from gymnasium import spaces

from hexabot_sim.envs.base import COMMAND_RANGE, LeggedEnv, Reward, unknown_keywords
from hexabot_sim.envs.scene import real_number, robot_params, terrain_keywords

SETTLE_TIME: float = 0.25  # [s] at a reset the robot stands on its servos' home targets this long (it lands)


class LeggedJointsEnv(LeggedEnv):
    """A legged robot whose policy sets the target angle of each of its 3 n_legs position servos.

    The robot is data: `robot` names a robot folder with a '<robot>-walk' scenario (hexabot, quadbot), whose model,
    stance and servos this environment uses; HexabotJoints-v0 and QuadbotJoints-v0 differ in that name only.

    Action: Box(-1, 1, (3 n_legs,)), float32: joint targets normalised over each servo's range, legs in the layout's
    order (hexabot: lf, lm, lr, rf, rm, rr), joints coxa, femur, tibia: target = low + (a + 1) / 2 (high - low)
    [rad] with (low, high) = (-pi/2, pi/2) for coxa and femur, (0, 2.79) for the tibia (the models' ctrlrange). The
    velocity servos get 0 (pure damping). Actions outside [-1, 1] are clipped; a wrong shape or a NaN is a ValueError.

    Observation: Box(-inf, inf, (12 + 7 n_legs,)), float64 (hexabot: 54), what the robot senses (`obs_slices`):
    gravity's direction in the body frame from the IMU's orientation (3, unit), the gyro (3) [rad/s], the
    accelerometer (3) [m/s^2] (specific force: +9.81 up when standing), joint angles (3 n_legs) [rad] and speeds
    (3 n_legs) [rad/s], each foot's touch sensor (n_legs) [N], and the episode's commanded twist (3): vx, vy [m/s]
    (body frame, x forward, y left), yaw rate [rad/s]. The sensors read as MuJoCo computed them in the action's last
    physics step (before its integration: 2 ms old, a real sensor's latency); joints are the state after it.

    Reward: `Reward`'s tracking of the commanded twist less its energy, attitude and foot-slip penalties.
    The command is drawn per episode from the environment's RNG, uniform in `command_range`.

    Episode: starts on the home stance (with joint noise of +-reset_noise_scale rad, then SETTLE_TIME standing);
    terminates when the robot falls (tilt beyond 45 deg, or its plate touches the ground) or the physics diverges
    (info["diverged"]); registered with 1000 steps of 20 ms (20 s).

    Args:
        robot: "hexabot" or "quadbot" (any robot with a '<robot>-walk' scenario), or the path of a legged-robot file
            (.toml, docs/robot-files.md): six legs walk as the hexabot's files do, four as the quadbot's.
        frame_skip: Physics steps (2 ms each) per action.
        terrain: "flat", "slope" (uphill along +x, `slope_deg`), "rough" (`roughness`: a fresh seeded patch of
            ~5 cm bumps at every reset, drawn from the environment's RNG, the level floor beyond it) or "stairs"
            (`stairs`: steps up along +x, the first edge 0.5 m ahead of the start, then a landing).
        slope_deg: The slope's angle [deg], 0 < slope_deg <= 30; default 10.
        roughness: The bumps' peak height [m], 0 < roughness <= 0.03; default 0.01.
        stairs: (rise [m], run [m], count) of the staircase: 0 < rise <= 0.1, 0.05 <= run <= 2, 1 <= count <= 50
            (as hexabot-walk's stairs_*); default (0.04, 0.25, 3).
            Each of these three only with its terrain: given with another, a ValueError (it would have no effect).
        command_range: (low, high) of vx [m/s], vy [m/s] and the yaw rate [rad/s].
        reward: A Reward, or a dict of its fields to change.
        randomize_friction, randomize_mass, randomize_servo_gain: (low, high) ranges of factors drawn at every
            reset (scene.Randomization): each foot's friction, the plate's mass and inertia, each servo's kp and kv.
        reset_noise_scale: Uniform noise on the start joint angles [rad].
        render_mode: None, "rgb_array" (frames of `camera`, width x height, render.py's preview preset) or "human" (a
            window on the display drawn at each step, paced at the control rate; needs glfw: the viewer extra).
    """

    def __init__(
        self,
        robot: str = "hexabot",
        frame_skip: int = 10,
        terrain: str = "flat",
        slope_deg: float | None = None,
        roughness: float | None = None,
        stairs: tuple[float, float, int] | None = None,
        command_range=COMMAND_RANGE,
        reward: Reward | dict | None = None,
        randomize_friction: tuple[float, float] | None = None,
        randomize_mass: tuple[float, float] | None = None,
        randomize_servo_gain: tuple[float, float] | None = None,
        reset_noise_scale: float = 0.02,
        render_mode: str | None = None,
        width: int = 640,
        height: int = 480,
        camera: str = "track",
        **kwargs,
    ) -> None:
        unknown_keywords(type(self), kwargs)  # a misspelt keyword: a ValueError naming the known ones, not a TypeError
        slope_deg, roughness, stairs = terrain_keywords(terrain, slope_deg, roughness, stairs)
        if not (real_number(reset_noise_scale) and 0.0 <= reset_noise_scale <= 0.5):  # numpy's numbers too
            raise ValueError(f"reset_noise_scale must be a number from 0 to 0.5 rad; got {reset_noise_scale!r}")
        p = robot_params(robot)
        super().__init__(
            p, frame_skip, terrain, slope_deg, roughness, stairs, command_range, reward, randomize_friction,
            randomize_mass, randomize_servo_gain, render_mode, width, height, camera,
        )  # fmt: skip
        self.robot = robot
        self.reset_noise_scale = float(reset_noise_scale) + 0.0  # -0.0: uniform(0, -0) raised at reset
        n = self.n_joints
        self.action_space = spaces.Box(-1.0, 1.0, (n,), np.float32)
        pos = self.scene.pos_act
        self._low = self.model.actuator_ctrlrange[pos, 0].copy()
        self._half = 0.5 * (self.model.actuator_ctrlrange[pos, 1] - self._low)
        self._target = np.zeros(n)
        self._settle_steps = round(SETTLE_TIME / p.timestep)
        self._started = False  # step() before the first reset() is an error, as in the command environment

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        self._start(seed, options)
        d = self.data
        d.qpos[7:] += self.np_random.uniform(-self.reset_noise_scale, self.reset_noise_scale, self.n_joints)
        mujoco.mj_forward(self.model, d)
        mujoco.mj_step(self.model, d, nstep=self._settle_steps)  # on the home targets: it lands on its feet
        d.time = 0.0
        self._warnings = self._warned()
        self._started = True
        if self.render_mode == "human":
            self.render()
        return self._observe(), {"command": self.command.copy()}

    def step(self, action) -> tuple[np.ndarray, float, bool, bool, dict]:
        if not self._started:
            raise RuntimeError("call reset() before step()")
        a = self._check_action(action, self.n_joints)
        # Targets over the servos' ranges; the velocity servos keep 0.
        np.clip(a, -1.0, 1.0, out=self._target)
        self._target += 1.0
        self._target *= self._half
        self._target += self._low
        n = self.n_joints
        self.data.ctrl[:n] = self._target
        mujoco.mj_step(self.model, self.data, nstep=self.frame_skip)
        obs = self._observe()
        reward, terminated, info = self._reward(obs)
        if self.render_mode == "human":
            self.render()
        return obs, reward, terminated, False, info
