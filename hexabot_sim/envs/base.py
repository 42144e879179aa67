"""What every legged environment shares: the sensed observation, the commanded twist, the reward, falls, frames."""

from __future__ import annotations

import dataclasses
import inspect
import math
from typing import TYPE_CHECKING, Any

import gymnasium
import mujoco
import numpy as np
from gymnasium import spaces

from hexabot_sim.envs.scene import (
    EPISODE_SECONDS,
    PLATE_SITE,
    EnvScene,
    Randomization,
    check_range,
    real_number,
    walk_reach,
)
from hexabot_sim.kinematics import legged
from hexabot_sim.walking.constants import FALL_TILT_DEG
from hexabot_sim.walking.parameters import WalkParams

if TYPE_CHECKING:
    from hexabot_sim.envs.window import Window
    from hexabot_sim.render import Frames

TOUCH_THRESHOLD: float = 0.3  # [N] a foot's touch reading above this counts as a foot down (as GroundSettings')
SIGMA_MIN: float = 1e-6  # [m/s or rad/s] the smallest tracking scale of a Reward (its square stays a normal number)
WEIGHT_MAX: float = 1e6  # the largest weight or scale of a Reward (the reward stays finite)
COMMAND_RANGE: tuple[tuple[float, float], ...] = ((0.0, 0.1), (-0.05, 0.05), (-0.2, 0.2))  # vx, vy [m/s], yaw rate


def unknown_keywords(cls: type, given: dict[str, Any]) -> None:
    """A ValueError naming the first of `given` (keywords the environment does not take) and the ones it takes."""
    if given:
        known = [name for name in inspect.signature(cls.__init__).parameters if name not in ("self", "kwargs")]
        raise ValueError(f"unknown keyword {next(iter(given))!r} of {cls.__name__}; known: {', '.join(known)}")


def real_array(value, what: str) -> np.ndarray:
    """`value` as a float64 array; a ValueError "<what>; got ..." for complex numbers (numpy would drop their
    imaginary part with a warning), strings, objects or ragged lists."""
    try:
        raw = np.asarray(value)
        if raw.dtype.kind not in "biuf":
            raise TypeError(raw.dtype)
        return raw.astype(np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{what}; got {' '.join(repr(value).split())[:80]}") from None  # one line


def check_options(options) -> None:
    """reset()'s options: None or an empty dict (Gymnasium's checker passes {}); anything else was ignored without a
    word (options={"terrain": "rough"} reset on the flat), now a ValueError."""
    if options is not None and not (isinstance(options, dict) and not options):
        got = " ".join(repr(options).split())[:80]  # one line
        raise ValueError(f"reset() takes no options (terrain, ranges and the rest are make()'s keywords); got {got}")


@dataclasses.dataclass(frozen=True)
class Reward:
    """The reward's weights and scales (all per control step).

    reward = velocity exp(-|v_xy - c_xy|^2 / velocity_sigma^2) + yaw exp(-(w_z - c_w)^2 / yaw_sigma^2)
             - energy P - attitude sin^2(tilt) - slip sum over the feet down of |v_foot,xy|^2

    v_xy: the body's horizontal velocity in its heading frame [m/s]; w_z: its yaw rate [rad/s]; c: the command;
    P: the servos' mechanical power sum |tau_i dq_i| [W]; tilt: the plate's angle from level; v_foot,xy: the
    horizontal speed of each foot whose touch sensor reads more than TOUCH_THRESHOLD [m/s].

    Attributes:
        velocity, yaw: Weights of the two tracking terms [1].
        velocity_sigma: Speed error that costs 1/e of the velocity term [m/s].
        yaw_sigma: Yaw-rate error that costs 1/e of the yaw term [rad/s].
        energy: Penalty per watt [1/W].
        attitude: Penalty per sin^2 of the tilt [1].
        slip: Penalty per (m/s)^2 of a foot's horizontal speed while down [s^2/m^2].
    """

    velocity: float = 1.0
    yaw: float = 0.5
    velocity_sigma: float = 0.05
    yaw_sigma: float = 0.2
    energy: float = 0.01
    attitude: float = 1.0
    slip: float = 20.0

    def __post_init__(self) -> None:
        for field in dataclasses.fields(self):
            value = getattr(self, field.name)
            # A sigma below SIGMA_MIN squares to 0 (a ZeroDivisionError at the first step); a weight above WEIGHT_MAX
            # times a power or a speed overflows the reward to -inf.
            low, high = (SIGMA_MIN, WEIGHT_MAX) if field.name.endswith("sigma") else (0.0, WEIGHT_MAX)
            if not (real_number(value) and math.isfinite(value) and low <= value <= high):
                raise ValueError(f"reward {field.name} must be a number from {low:g} to {high:g}; got {value!r}")

    @classmethod
    def of(cls, reward: Reward | dict | None) -> Reward:
        """A Reward, or the defaults with a dict's fields changed; a ValueError naming the fields otherwise."""
        if isinstance(reward, cls):
            return reward
        if reward is None:
            return cls()
        if not isinstance(reward, dict):
            raise ValueError(f"reward must be a Reward, a dict of its fields or None; got {type(reward).__name__}")
        names = [field.name for field in dataclasses.fields(cls)]
        unknown = [key for key in reward if key not in names]
        if unknown:
            raise ValueError(f"unknown reward field {unknown[0]!r}; known: {', '.join(names)}")
        return cls(**reward)


class LeggedEnv(gymnasium.Env):
    """A legged robot (a robot folder with a '<robot>-walk' scenario) on contact physics, told to walk at a body twist.

    The subclasses choose the action (joint targets, or the twist given to the verified gait controller); the
    rest is here: the observation, the commanded twist drawn per episode, the reward, a fall, the frames.
    """

    metadata: dict[str, Any] = {"render_modes": ["human", "rgb_array"], "render_fps": 50}  # noqa: RUF012 (fps: per instance)

    def __init__(
        self,
        p: WalkParams,
        frame_skip: int,
        terrain: str,
        slope_deg: float,
        roughness: float,
        stairs,
        command_range,
        reward: Reward | dict | None,
        randomize_friction,
        randomize_mass,
        randomize_servo_gain,
        render_mode: str | None,
        width: int,
        height: int,
        camera: str,
    ) -> None:
        # At most one episode per action: a larger one overflowed MuJoCo's nstep (a TypeError at the first step).
        most = round(EPISODE_SECONDS / p.timestep)
        if isinstance(frame_skip, bool) or not isinstance(frame_skip, int | np.integer) or not 1 <= frame_skip <= most:
            raise ValueError(
                f"frame_skip must be an integer >= 1 and <= {most} (a control period of at most "
                f"{EPISODE_SECONDS:g} s); got {frame_skip!r}"
            )
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(
                f"unknown render_mode {render_mode!r}; known: None, {', '.join(self.metadata['render_modes'])}"
            )
        for name, value in (("width", width), ("height", height)):
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or not 1 <= value <= 8192:
                raise ValueError(f"{name} must be an integer from 1 to 8192 pixels; got {value!r}")
        try:
            rows = [tuple(r) for r in command_range]
        except TypeError:
            rows = []
        if len(rows) != 3:
            raise ValueError(f"command_range must be three (low, high) pairs: vx, vy, yaw rate; got {command_range!r}")
        names = ("vx", "vy", "yaw rate")
        ranges = [check_range(f"command_range {n}", r, -3.0, 3.0) for n, r in zip(names, rows, strict=True)]
        self.command_range = np.array(ranges)  # (3, 2)
        self.reward_weights = Reward.of(reward)
        randomization = Randomization(randomize_friction, randomize_mass, randomize_servo_gain)
        self.frame_skip = int(frame_skip)
        self.dt = self.frame_skip * p.timestep  # [s] the control period
        reach = walk_reach(float(np.abs(self.command_range[:2]).max()))
        self.scene = EnvScene(p, terrain, slope_deg, roughness, reach, randomization, stairs)
        self.model, self.data = self.scene.model, self.scene.data
        # The control rate: round(1 / dt) was 0 for a control period over 2 s (Gymnasium's render check asserts > 0)
        # and paced the window off the period (17 fps at 60 ms); a whole number stays an int (50, 10).
        fps = 1.0 / self.dt
        self.metadata = {**self.metadata, "render_fps": round(fps) if math.isclose(fps, round(fps)) else fps}
        cameras = [self.model.camera(i).name for i in range(self.model.ncam)]
        if not isinstance(camera, str) or camera not in cameras:  # checked here, not at the first render()
            raise ValueError(f"unknown camera {camera!r}; known: {', '.join(cameras)}")
        self.render_mode, self.width, self.height, self.camera = render_mode, width, height, camera
        self._frames: Frames | None = None
        self._window: Window | None = None
        if render_mode == "human":  # a window on the display, drawn at each step: refused now if none can open
            from hexabot_sim.envs.window import Window

            self._window = Window(self.model, camera, "torso", self.metadata["render_fps"])
        self._addresses(p)
        n = self.n_joints
        # Observation: gravity in the body (3), gyro (3), accelerometer (3), joint angles (n), joint speeds (n),
        # foot touch (n_legs), the commanded twist (3).
        self.obs_slices = {
            "gravity": slice(0, 3), "gyro": slice(3, 6), "accelerometer": slice(6, 9), "joint_angles": slice(9, 9 + n),
            "joint_speeds": slice(9 + n, 9 + 2 * n), "foot_touch": slice(9 + 2 * n, 9 + 2 * n + self.n_legs),
            "command": slice(9 + 2 * n + self.n_legs, 12 + 2 * n + self.n_legs),
        }  # fmt: skip
        size = 12 + 2 * n + self.n_legs
        self.observation_space = spaces.Box(-np.inf, np.inf, (size,), np.float64)
        self._obs = np.zeros(size)
        self._velocity = np.zeros(6)
        self.command = np.zeros(3)
        self._views()

    def _addresses(self, p: WalkParams) -> None:
        """Sensor addresses and ids, looked up by name once."""
        m = self.model
        layout = p.ROBOT.layout
        self.n_legs, self.n_joints = layout.n_legs, 3 * layout.n_legs

        def adr(name: str) -> int:
            return int(m.sensor_adr[m.sensor(name).id])

        self._quat, self._gyro, self._acc, self._plate = (
            adr("imu_quat"),
            adr("imu_gyro"),
            adr("imu_acc"),
            adr(PLATE_SITE),
        )
        self._touch = np.array([adr(f"{leg}_touch") for leg in layout.legs])
        self._foot_sites = [m.site(f"{leg}_foot").id for leg in layout.legs]
        self._torso = m.body("torso").id
        joints = [f"{leg}_{j}" for leg in layout.legs for j in legged.JOINTS]
        qadr = [int(m.jnt_qposadr[m.joint(name).id]) for name in joints]
        if qadr != list(range(7, 7 + self.n_joints)):
            raise ValueError(f"the model must put the {self.n_joints} leg joints after the free joint")
        self._cos_fall = math.cos(math.radians(FALL_TILT_DEG))
        self._site_type = int(mujoco.mjtObj.mjOBJ_SITE)  # an int: pybind converts it ~2 us faster than the enum
        # MuJoCo's divergence warnings: a bad acceleration, or a bad position or velocity (after which it resets the
        # data to qpos0 and time 0 and steps on: a teleported robot, not a NaN).
        self._bad = tuple(int(w) for w in (mujoco.mjtWarning.mjWARN_BADQACC, mujoco.mjtWarning.mjWARN_BADQPOS,
                                           mujoco.mjtWarning.mjWARN_BADQVEL))  # fmt: skip

    # ------------------------------------------------------------------------------------------- episode

    def _start(self, seed: int | None, options: dict | None = None) -> None:
        """Seeds the RNG (Gymnasium's reset), draws the command, the ground and the randomisation, places the robot."""
        check_options(options)
        super().reset(seed=seed)
        rng = self.np_random
        self.command[:] = rng.uniform(self.command_range[:, 0], self.command_range[:, 1])
        if self.scene.reset(rng):  # a new heightfield: frames of the new model, the window's copy uploaded again
            if self._frames is not None:
                self._frames.close()
                self._frames = None
            if self._window is not None:
                self._window.update_hfield(self.scene.hfield[0])
        self._warning = tuple(self.data.warning[i] for i in self._bad)  # live views of MuJoCo's counters
        self._warnings = self._warned()
        self._command = tuple(self.command.tolist())
        self._obs[self.obs_slices["command"]] = self.command

    def _warned(self) -> int:
        """MuJoCo's divergence warnings so far."""
        acc, pos, vel = self._warning
        return acc.number + pos.number + vel.number

    def _views(self) -> None:
        """Views of MjData's arrays (its memory is allocated once) paired with the observation's slices they fill:
        a step copies them without making arrays."""
        d, obs, sl = self.data, self._obs, self.obs_slices
        s = d.sensordata
        touch = self._touch
        contiguous = bool((np.diff(touch) == 1).all())
        self._copies = [
            (obs[sl["gyro"]], s[self._gyro : self._gyro + 3]),
            (obs[sl["accelerometer"]], s[self._acc : self._acc + 3]),
            (obs[sl["joint_angles"]], d.qpos[7:]),
            (obs[sl["joint_speeds"]], d.qvel[6:]),
        ]
        if contiguous:
            self._copies.append((obs[sl["foot_touch"]], s[touch[0] : touch[-1] + 1]))
        self._touch_view = None if contiguous else (s, touch, obs[sl["foot_touch"]])
        self._quat_view = s[self._quat : self._quat + 4]
        self._xmat_view = d.xmat[self._torso]
        self._twist_view = d.qvel[:6]
        self._torque_view, self._speed_view = d.qfrc_actuator[6:], d.qvel[6:]
        self._torque_abs, self._speed_abs = np.zeros(self.n_joints), np.zeros(self.n_joints)
        self._gravity_view, self._touch_obs = obs[:3], obs[sl["foot_touch"]]

    # Views into MjData and the observation buffer (_views) and MuJoCo's warning counter (_start): a copy of them is
    # not a view of the copied MjData (a deepcopy read the original's state: its observations were stale), and the
    # counter does not pickle. Left out of a copy or pickle and made again from the copied data.
    _DERIVED: tuple[str, ...] = (
        "_copies", "_touch_view", "_quat_view", "_xmat_view", "_twist_view", "_torque_view", "_speed_view",
        "_torque_abs", "_speed_abs", "_gravity_view", "_touch_obs", "_warning",
    )  # fmt: skip

    def __getstate__(self) -> dict[str, Any]:
        if self._window is not None:
            raise TypeError("an environment with render_mode='human' cannot be copied or pickled (its window)")
        state = {k: v for k, v in self.__dict__.items() if k not in self._DERIVED}
        state["_frames"] = None  # the copy renders with its own context, made at its first render()
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._views()
        if "_warnings" in state:  # reset: the live views of the copied data's counters
            self._warning = tuple(self.data.warning[i] for i in self._bad)

    def _observe(self) -> np.ndarray:
        """The observation (a new array; the buffer behind it is reused)."""
        w, x, y, z = self._quat_view.tolist()
        # Gravity's direction in the body frame: R^T (0, 0, -1), minus R's third row.
        obs = self._obs
        obs[0], obs[1], obs[2] = 2 * (w * y - x * z), -2 * (y * z + w * x), 2 * (x * x + y * y) - 1
        for dest, src in self._copies:
            dest[:] = src
        if self._touch_view is not None:
            s, touch, dest = self._touch_view
            np.take(s, touch, out=dest)
        return obs.copy()

    def _reward(self, obs: np.ndarray) -> tuple[float, bool, dict[str, Any]]:
        """(reward, terminated, info) of the state reached (obs: its observation)."""
        m, d, rw = self.model, self.data, self.reward_weights
        r00, _, _, r10, _, _, r20, r21, r22 = self._xmat_view.tolist()  # body -> world, row-major
        vx_w, vy_w, _, wx, wy, wz = self._twist_view.tolist()  # world linear velocity, body angular velocity
        norm = math.hypot(r00, r10) or 1.0
        c, s = r00 / norm, r10 / norm  # the heading: the body's x axis in the world's xy plane
        vx, vy = c * vx_w + s * vy_w, -s * vx_w + c * vy_w  # in the heading frame
        yaw_rate = r20 * wx + r21 * wy + r22 * wz  # the angular velocity's world z component
        cx, cy, cw = self._command
        track_v = rw.velocity * math.exp(-((vx - cx) ** 2 + (vy - cy) ** 2) / rw.velocity_sigma**2)
        track_w = rw.yaw * math.exp(-((yaw_rate - cw) ** 2) / rw.yaw_sigma**2)
        np.abs(self._torque_view, out=self._torque_abs)
        np.abs(self._speed_view, out=self._speed_abs)
        power = float(self._torque_abs @ self._speed_abs)  # sum |tau_i dq_i| [W]
        gx, gy, gz = self._gravity_view.tolist()
        tilt2 = gx * gx + gy * gy  # sin^2 of the tilt
        slip = 0.0
        velocity = self._velocity
        for site, touch in zip(self._foot_sites, self._touch_obs.tolist(), strict=True):
            if touch > TOUCH_THRESHOLD:
                mujoco.mj_objectVelocity(m, d, self._site_type, site, velocity, 0)  # (angular, linear), world
                _, _, _, ux, uy, _ = velocity.tolist()
                slip += ux * ux + uy * uy
        slip = float(slip)
        reward = track_v + track_w - rw.energy * power - rw.attitude * tilt2 - rw.slip * slip
        fell = -gz < self._cos_fall or d.sensordata[self._plate] > 0.0
        diverged = self._warned() != self._warnings or not math.isfinite(d.qpos[2])
        info = {
            "x": float(d.qpos[0]), "y": float(d.qpos[1]), "vx": vx, "vy": vy, "yaw_rate": yaw_rate,
            "reward_velocity": track_v, "reward_yaw": track_w, "power": power, "tilt_sin2": tilt2, "foot_slip": slip,
            "fell": bool(fell), "diverged": bool(diverged),
        }  # fmt: skip
        return reward, bool(fell or diverged), info

    def _check_action(self, action, n: int) -> np.ndarray:
        """The action as a float array of n, or a ValueError saying what was wrong."""
        a = real_array(action, f"the action must be {n} real numbers in [-1, 1]")
        if a.shape != (n,):
            raise ValueError(f"the action must be {n} numbers (shape ({n},)); got shape {a.shape}")
        if not np.isfinite(a).all():
            raise ValueError(f"the action must be finite numbers in [-1, 1]; got {a.tolist()}")
        return a

    # ------------------------------------------------------------------------------------------- frames

    def render(self) -> np.ndarray | None:
        """The frame (height, width, 3) of the current state from `camera` (render_mode "rgb_array"), else None
        (render_mode "human": the state drawn in the window, as step() and reset() draw it)."""
        if self._window is not None:
            self._window.show(self.data)
        if self.render_mode != "rgb_array":
            return None
        if self._frames is None:
            from hexabot_sim.render import Frames

            self._frames = Frames(self.model, self.width, self.height, self.camera)
        return self._frames(self.data)

    def close(self) -> None:
        if self._window is not None:
            self._window.close()
        if self._frames is not None:
            self._frames.close()
            self._frames = None
