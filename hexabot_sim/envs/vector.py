"""Many joint-level environments stepped at once by mujoco.rollout (MuJoCo's C thread pool), one process."""

from __future__ import annotations

import os
from typing import Any

import mujoco
import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space
from mujoco import rollout

from hexabot_sim.envs.base import TOUCH_THRESHOLD, check_options, real_array
from hexabot_sim.envs.joints import LeggedJointsEnv

STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS  # what mujoco.rollout takes and returns per step


class LeggedJointsVectorEnv(VectorEnv):
    """`num_envs` LeggedJointsEnv (their models, resets, randomisation and RNGs) whose physics runs in one call of
    mujoco.rollout per step, on `threads` C threads (default: the cores), and whose observations and rewards are
    computed for all of them at once from the rollout's states and sensor data.

    The same spaces, reward and termination as LeggedJointsEnv, with these differences: the physics solver starts
    each action's steps without the previous step's warm start (mujoco.rollout does not return it: a trajectory
    agrees with the single environment's to the solver's tolerance, not bit for bit); a diverging simulation is
    seen by MuJoCo's reset of its time inside the rollout; no rendering. Episodes are reset on the step after
    they end (Gymnasium's NEXT_STEP autoreset) and truncated after `max_episode_steps`.
    """

    metadata: dict[str, Any] = {"render_modes": [], "autoreset_mode": AutoresetMode.NEXT_STEP}  # noqa: RUF012

    def __init__(self, num_envs: int = 8, max_episode_steps: int = 1000, threads: int | None = None, **kwargs) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, int | np.integer) or num_envs < 1:
            raise ValueError(f"num_envs must be an integer >= 1; got {num_envs!r}")
        num_envs = int(num_envs)
        # threads=-1 was MuJoCo's "The list of data instances is empty" at construction, 1.5 or "2" a TypeError.
        whole = isinstance(threads, int | np.integer) and not isinstance(threads, bool)
        if threads is not None and not (whole and threads >= 1):
            raise ValueError(f"threads must be an integer >= 1 or None (one per core); got {threads!r}")
        steps_ok = isinstance(max_episode_steps, int | np.integer) and not isinstance(max_episode_steps, bool)
        if not steps_ok or max_episode_steps < 1:
            raise ValueError(f"max_episode_steps must be an integer >= 1; got {max_episode_steps!r}")
        if kwargs.get("render_mode") is not None:
            raise ValueError("the rollout vector environment does not render; use render_mode=None")
        self.envs = [LeggedJointsEnv(**kwargs) for _ in range(num_envs)]
        first = self.envs[0]
        self.num_envs, self.max_episode_steps = num_envs, int(max_episode_steps)
        self.single_observation_space, self.single_action_space = first.observation_space, first.action_space
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self.frame_skip, self.dt, self._n_joints = first.frame_skip, first.dt, first.n_joints
        self.models = [env.model for env in self.envs]
        threads = threads or os.cpu_count() or 1
        self._thread_data = [mujoco.MjData(first.model) for _ in range(min(threads, num_envs))]
        self._addresses(first)
        m = first.model
        nstate, n = mujoco.mj_stateSize(m, STATE), num_envs
        self._state = np.zeros((n, nstate))
        self._states_out = np.zeros((n, self.frame_skip, nstate))
        self._sensors_out = np.zeros((n, self.frame_skip, m.nsensordata))
        self._ctrl = np.zeros((n, 1, m.nu))
        self._warmstart = np.zeros((n, m.nv))  # the solver starts each action cold (rollout returns no warm start)
        self._low, self._half = first._low, first._half
        self._command = np.zeros((n, 3))
        self._steps = np.zeros(n, dtype=np.int64)
        self._time = np.zeros(n)
        self._autoreset = np.zeros(n, dtype=bool)
        self._started = False  # step() before the first reset() would run from an all-zero state

    def _addresses(self, env: LeggedJointsEnv) -> None:
        m = env.model
        legs = env.scene.p.ROBOT.layout.legs

        def adr(name: str) -> int:
            return int(m.sensor_adr[m.sensor(name).id])

        self._qpos = mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_TIME)
        self._qvel = self._qpos + m.nq
        self._quat, self._gyro, self._acc, self._plate = env._quat, env._gyro, env._acc, env._plate
        self._touch = env._touch
        self._torque = np.array([adr(f"env_{leg}_{j}_torque") for leg in legs for j in ("coxa", "femur", "tibia")])
        foot = np.array([adr(f"env_{leg}_foot_velocity") for leg in legs])
        self._foot_x, self._foot_y = foot, foot + 1
        self.obs_slices = env.obs_slices
        self._cos_fall = env._cos_fall

    def _reset_one(self, i: int, seed: int | None) -> np.ndarray:
        env = self.envs[i]
        obs, _ = env.reset(seed=seed)
        mujoco.mj_getState(env.model, env.data, self._state[i], STATE)
        self._command[i] = env.command
        self._steps[i] = 0
        self._time[i] = env.data.time
        return obs

    def reset(self, *, seed: int | list[int] | None = None, options: dict | None = None) -> tuple[np.ndarray, dict]:
        check_options(options)
        seeds: list[int | None]
        if isinstance(seed, list | tuple):
            seeds = list(seed)
        elif seed is None:
            seeds = [None] * self.num_envs
        elif isinstance(seed, bool) or not isinstance(seed, int | np.integer):  # "a" + 0 was a TypeError
            raise ValueError(f"seed must be an integer, a list of one per environment, or None; got {seed!r}")
        else:
            seeds = [int(seed) + i for i in range(self.num_envs)]
        if len(seeds) != self.num_envs:
            raise ValueError(f"reset needs one seed per environment ({self.num_envs}); got {len(seeds)}")
        obs = np.stack([self._reset_one(i, s) for i, s in enumerate(seeds)])
        self._autoreset[:] = False
        self._started = True
        return obs, {"command": self._command.copy()}

    def step(self, actions) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict]:
        if not self._started:
            raise RuntimeError("call reset() before step()")
        n, nj = self.num_envs, self._n_joints
        a = real_array(actions, f"the actions must be real numbers in [-1, 1], shape ({n}, {nj})")
        if a.shape != (n, nj):
            raise ValueError(f"the actions must be shape ({n}, {nj}); got {a.shape}")
        if not np.isfinite(a).all():
            raise ValueError("the actions must be finite numbers in [-1, 1]")
        # Joint targets over the servos' ranges (velocity servos at 0), then frame_skip steps of every model.
        self._ctrl[:, 0, :nj] = self._low + (np.clip(a, -1.0, 1.0) + 1.0) * self._half
        rollout.rollout(self.models, self._thread_data, self._state, self._ctrl, nstep=self.frame_skip,
                        initial_warmstart=self._warmstart, state=self._states_out, sensordata=self._sensors_out,
                        persistent_pool=True)  # fmt: skip
        self._state[:] = self._states_out[:, -1]
        obs, reward, fell, info = self._readout(self._state, self._sensors_out[:, -1])
        # MuJoCo's time, added as mj_step adds it (one timestep a step): frame_skip x timestep at once drifted from it
        # by 1e-9 s after 355 s (step 17752 at 10 x 2 ms), and a long episode ended there as "diverged".
        for _ in range(self.frame_skip):
            self._time += self.models[0].opt.timestep
        diverged = ~np.isclose(self._state[:, 0], self._time, rtol=0, atol=1e-9) | ~np.isfinite(self._state).all(1)
        terminated = fell | diverged
        self._steps += 1
        truncated = (self._steps >= self.max_episode_steps) & ~terminated
        # NEXT_STEP autoreset: the environments that ended at the last step start again now.
        for i in np.flatnonzero(self._autoreset):
            obs[i] = self._reset_one(int(i), None)
            reward[i], terminated[i], truncated[i] = 0.0, False, False
        self._autoreset = terminated | truncated
        info |= {"fell": fell, "diverged": diverged}
        return obs, reward, terminated, truncated, info

    def _readout(self, state: np.ndarray, sensors: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict]:
        """Observations, rewards and falls of every environment from the states and sensor data (vectorised)."""
        rw = self.envs[0].reward_weights
        q = sensors[:, self._quat : self._quat + 4]
        w, x, y, z = q.T
        gravity = np.stack([2 * (w * y - x * z), -2 * (y * z + w * x), 2 * (x * x + y * y) - 1], axis=1)
        nq = self.models[0].nq
        qpos, qvel = state[:, self._qpos : self._qpos + nq], state[:, self._qvel :]
        obs = np.concatenate([
            gravity, sensors[:, self._gyro : self._gyro + 3], sensors[:, self._acc : self._acc + 3], qpos[:, 7:],
            qvel[:, 6:], sensors[:, self._touch], self._command,
        ], axis=1)  # fmt: skip
        # The heading from the body's x axis (R's first column), the twist in its frame, the yaw rate in the world.
        r00, r10 = 1 - 2 * (y * y + z * z), 2 * (x * y + w * z)
        r20, r21, r22 = 2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)
        norm = np.hypot(r00, r10)
        c, s = r00 / norm, r10 / norm
        vx, vy = c * qvel[:, 0] + s * qvel[:, 1], -s * qvel[:, 0] + c * qvel[:, 1]
        yaw_rate = r20 * qvel[:, 3] + r21 * qvel[:, 4] + r22 * qvel[:, 5]
        cmd = self._command
        track_v = rw.velocity * np.exp(-((vx - cmd[:, 0]) ** 2 + (vy - cmd[:, 1]) ** 2) / rw.velocity_sigma**2)
        track_w = rw.yaw * np.exp(-((yaw_rate - cmd[:, 2]) ** 2) / rw.yaw_sigma**2)
        power = np.abs(sensors[:, self._torque] * qvel[:, 6:]).sum(axis=1)
        tilt2 = gravity[:, 0] ** 2 + gravity[:, 1] ** 2
        down = sensors[:, self._touch] > TOUCH_THRESHOLD
        slip = np.where(down, sensors[:, self._foot_x] ** 2 + sensors[:, self._foot_y] ** 2, 0.0).sum(axis=1)
        reward = track_v + track_w - rw.energy * power - rw.attitude * tilt2 - rw.slip * slip
        fell = (-gravity[:, 2] < self._cos_fall) | (sensors[:, self._plate] > 0.0)
        info = {"x": qpos[:, 0].copy(), "y": qpos[:, 1].copy(), "vx": vx, "vy": vy, "yaw_rate": yaw_rate,
                "reward_velocity": track_v, "reward_yaw": track_w, "power": power, "tilt_sin2": tilt2,
                "foot_slip": slip}  # fmt: skip
        return obs, reward, fell, info

    def close_extras(self, **kwargs) -> None:
        for env in self.envs:
            env.close()
