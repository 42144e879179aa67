"""render_mode="human": the environment's state in a window on the display as it steps (MuJoCo's passive viewer, the
window `hexabot-sim view` opens), paced at the environment's control rate as Gymnasium's own MuJoCo environments are.

The window draws a copy of the state (MjData of its own, set from the environment's at each frame), so dragging a body
with the mouse never changes the environment's physics. Closing the window ends the showing, not the environment.
"""

from __future__ import annotations

import importlib.util
import threading
import time

import gymnasium
import mujoco

from hexabot_sim import gl, render

JOIN_TIMEOUT: float = 10.0  # [s] waiting for the window's thread to end at close()


class Window:
    """A window showing the state of (model, data-like) at each `show`, `fps` frames a second of wall time at most."""

    def __init__(self, model: mujoco.MjModel, camera: str, track_body: str, fps: float) -> None:
        if importlib.util.find_spec("glfw") is None:
            raise gymnasium.error.DependencyNotInstalled(f"render_mode='human' needs glfw: {gl.INSTALL_HINT}")
        why = gl.display_problem("python your_script.py")
        if why:
            raise RuntimeError(f"render_mode='human' cannot open a window: {why}")
        self.model, self.data = model, mujoco.MjData(model)
        self.camera, self.track_body, self.period = camera, track_body, 1.0 / fps
        self._handle = None
        self._threads: list[threading.Thread] = []
        self._last = -float("inf")  # [s] monotonic time of the last frame
        self.closed = False  # by close(), or by the user at the window

    def show(self, data: mujoco.MjData) -> None:
        """Draws the state in `data` (opening the window the first time), at most one frame per period."""
        if self.closed:
            return
        if self._handle is not None and not self._handle.is_running():  # the user closed it: the env goes on
            self.close()
            return
        wait = self._last + self.period - time.monotonic()
        if wait > 0:
            time.sleep(wait)
        if self._handle is None:
            self._copy(data)
            self._open()
        else:
            with self._handle.lock():
                self._copy(data)
        self._handle.sync()
        self._last = time.monotonic()

    def _copy(self, data: mujoco.MjData) -> None:
        d = self.data
        d.qpos[:], d.qvel[:], d.act[:], d.ctrl[:], d.time = data.qpos, data.qvel, data.act, data.ctrl, data.time
        mujoco.mj_forward(self.model, d)

    def _open(self) -> None:
        import mujoco.viewer

        before = set(threading.enumerate())
        self._handle = mujoco.viewer.launch_passive(self.model, self.data, show_left_ui=False, show_right_ui=False)
        self._threads = [t for t in threading.enumerate() if t not in before]
        with self._handle.lock():
            render.view_camera(self._handle.cam, self.model, self.data, self.camera, self.track_body)

    def close(self) -> None:
        """Closes the window and waits for its thread (idempotent)."""
        self.closed = True
        if self._handle is not None:
            self._handle.close()
            self._handle = None
        for thread in self._threads:
            thread.join(JOIN_TIMEOUT)
        self._threads = []
