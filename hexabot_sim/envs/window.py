"""render_mode="human": the environment's state in a window on the display as it steps (MuJoCo's passive viewer, the
window `hexabot-sim view` opens), paced at the environment's control rate as Gymnasium's own MuJoCo environments are.

The window draws a copy of the state (MjData of its own, set from the environment's at each frame), so dragging a body
with the mouse never changes the environment's physics. Closing the window ends the showing, not the environment.
"""

from __future__ import annotations

import atexit
import gc
import importlib.util
import threading
import time
import weakref

import gymnasium
import mujoco

from hexabot_sim import gl, render

JOIN_TIMEOUT: float = 10.0  # [s] waiting for the window's thread to end at close()

# MuJoCo's passive viewer runs GLFW in a thread of its own per window: two at once in one process crash (GLFW is not
# thread-safe), and one still drawing when the interpreter exits crashes at MuJoCo's atexit glfw.terminate(). So one
# window at a time, closed (and its thread joined) by close(), when its environment is collected, and at exit.
_LIVE: list[_Shown] = []


class _Shown:
    """A window's viewer handle and threads, apart from the Window so that a finalizer and atexit can close it."""

    def __init__(self) -> None:
        self.handle = None
        self.threads: list[threading.Thread] = []

    def close(self) -> None:
        if self.handle is not None:
            render.close_window(self.handle, self.threads, JOIN_TIMEOUT)
            self.handle = None
        self.threads = []
        if self in _LIVE:
            _LIVE.remove(self)


def _close_all() -> None:
    """At exit, before MuJoCo's glfw.terminate(): every window still open closed and its thread joined."""
    for shown in list(_LIVE):
        shown.close()


class Window:
    """A window showing the state of (model, data-like) at each `show`, `fps` frames a second of wall time at most."""

    def __init__(self, model: mujoco.MjModel, camera: str, track_body: str, fps: float) -> None:
        if importlib.util.find_spec("glfw") is None:
            raise gymnasium.error.DependencyNotInstalled(f"render_mode='human' needs glfw: {gl.INSTALL_HINT}")
        for shown in list(_LIVE):  # a window the user closed at the screen is over
            if shown.handle is not None and not shown.handle.is_running():
                shown.close()
        if _LIVE:  # an environment dropped without close() may be in a reference cycle: collected, its window closes
            gc.collect()
        if _LIVE:  # (before the display probe: its GLFW calls beside an open window's thread would be the crash)
            raise RuntimeError(
                "render_mode='human' shows one window at a time per process (MuJoCo's viewer is not thread-safe): "
                "close() the environment whose window is open first"
            )
        why = gl.display_problem("python your_script.py")
        if why:
            raise RuntimeError(f"render_mode='human' cannot open a window: {why}")
        self.model, self.data = model, mujoco.MjData(model)
        self.camera, self.track_body, self.period = camera, track_body, 1.0 / fps
        self._shown = _Shown()
        _LIVE.append(self._shown)
        weakref.finalize(self, self._shown.close)  # an environment collected without close(): its window closes
        self._last = -float("inf")  # [s] monotonic time of the last frame
        self.closed = False  # by close(), or by the user at the window

    def show(self, data: mujoco.MjData) -> None:
        """Draws the state in `data` (opening the window the first time), at most one frame per period."""
        if self.closed:
            return
        if self._shown.handle is not None and not self._shown.handle.is_running():  # closed by the user: env goes on
            self.close()
            return
        wait = self._last + self.period - time.monotonic()
        if wait > 0:
            time.sleep(wait)
        self._last = time.monotonic()  # the frame's start: drawing (waiting for the viewer's lock) is in the period
        if self._shown.handle is None:
            self._copy(data)
            self._open()
        else:
            with self._shown.handle.lock():
                self._copy(data)
        self._shown.handle.sync()

    def update_hfield(self, hfield_id: int) -> None:
        """The heightfield `hfield_id` of the model changed: the open window draws the new one (its GPU copy)."""
        if self._shown.handle is not None and self._shown.handle.is_running():
            self._shown.handle.update_hfield(hfield_id)

    def _copy(self, data: mujoco.MjData) -> None:
        d = self.data
        d.qpos[:], d.qvel[:], d.act[:], d.ctrl[:], d.time = data.qpos, data.qvel, data.act, data.ctrl, data.time
        mujoco.mj_forward(self.model, d)

    def _open(self) -> None:
        handle, self._shown.threads = render.launch_window(self.model, self.data)
        self._shown.handle = handle
        atexit.unregister(_close_all)  # registered after MuJoCo's glfw.terminate(), so run before it (LIFO)
        atexit.register(_close_all)
        with handle.lock():
            render.view_camera(handle.cam, self.model, self.data, self.camera, self.track_body)

    def close(self) -> None:
        """Closes the window and waits for its thread (idempotent)."""
        self.closed = True
        self._shown.close()
