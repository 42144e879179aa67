"""Interactive viewer: a scenario driven live, or a run folder replayed, in MuJoCo's passive viewer."""

from __future__ import annotations

import dataclasses
import math
import time
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any

import numpy as np

from hexabot_sim.errors import SimulationError, UsageError
from hexabot_sim.gl import INSTALL_HINT, display_problem
from hexabot_sim.recording import Recording, load_recording

__all__ = ["INSTALL_HINT", "Recording", "display_problem", "live", "live_maker", "load_recording", "replay"]

FRAME_PERIOD: float = 1 / 60  # [s] wall time between two pushes of the state to the viewer
SCRUB_FRAME: float = 1 / 30  # [s] simulated time Left/Right step by (one video frame)
SCRUB_JUMP: float = 1.0  # [s] simulated time Up/Down jump by
MIN_SPEED, MAX_SPEED = 1 / 64, 16.0  # playback speed range (times real time); '-' halves, '=' doubles
STEP_BUDGET: float = 0.05  # [s] wall time a live frame may spend stepping before the view falls behind
MAX_LAG: float = 0.1  # [s] simulated time the live view may fall behind before it drops the backlog
TRAIL_SAMPLES: int = 600  # recorded rows sampled for a replay's trail
TRAIL_KEEP: int = 2000  # live trail points kept (halved when exceeded)
JOIN_TIMEOUT: float = 10.0  # [s] waiting for the viewer's thread to close its window

# GLFW key codes (glfw.KEY_*), the keys the viewer's own key handling leaves alone in passive mode.
KEY_SPACE, KEY_MINUS, KEY_EQUAL = 32, 45, 61
KEY_RIGHT, KEY_LEFT, KEY_DOWN, KEY_UP, KEY_HOME, KEY_END = 262, 263, 264, 265, 268, 269
KEY_KP_SUBTRACT, KEY_KP_ADD = 333, 334
KEY_LEFT_SHIFT, KEY_RIGHT_SHIFT = 340, 344
SHIFT = 1 << 16  # added to a key code in the queue when shift was held

HELP_REPLAY = (
    ("space", "play / pause"),
    ("- =", "half / double speed"),
    ("Left Right", f"step {SCRUB_FRAME:.3g} s"),
    ("Down Up", f"jump {SCRUB_JUMP:g} s"),
    ("Home End", "first / last state"),
)
HELP_LIVE = (
    ("space", "play / pause"),
    ("- =", "half / double speed"),
    ("Right", "one frame (paused)"),
    ("Home", "restart"),
)


# ---------------------------------------------------------------------------------------------
# Playback clock and keys: pure Python, so they are tested without a display.


@dataclasses.dataclass
class Clock:
    """Where playback is in simulated time, how fast it runs, and what the keys do to it.

    Attributes:
        start, end: Simulated time of the first and last state [s].
        position: Simulated time shown (replay) or to be reached (live) [s].
        speed: Simulated seconds per wall second.
        paused: Time stands still.
        live: A live simulation: it cannot go back in time (Left/Down/End do nothing, Home restarts).
    """

    start: float
    end: float
    position: float
    speed: float = 1.0
    paused: bool = False
    live: bool = False
    restart: bool = False  # live: Home was pressed

    def advance(self, wall_dt: float) -> None:
        """Moves `position` on by wall_dt * speed unless paused; stops (paused) at the end."""
        if not self.paused:
            self.position = min(self.end, self.position + wall_dt * self.speed)
        if self.position >= self.end:
            self.position, self.paused = self.end, True

    def key(self, code: int) -> None:
        """Applies one key press (GLFW key code)."""
        if code == KEY_SPACE:
            if self.position >= self.end and not self.live:  # at the end: play again from the start
                self.position = self.start
            self.paused = not self.paused
        elif code in (KEY_MINUS, KEY_KP_SUBTRACT):
            self.speed = max(MIN_SPEED, self.speed / 2)
        elif code in (KEY_EQUAL, KEY_KP_ADD):
            self.speed = min(MAX_SPEED, self.speed * 2)
        elif code == KEY_HOME:
            if self.live:
                self.restart = True
            else:
                self.position, self.paused = self.start, True
        elif code == KEY_RIGHT:
            self.paused = True
            self.position = min(self.end, self.position + SCRUB_FRAME)
        elif self.live:
            return
        elif code == KEY_LEFT:
            self.position, self.paused = max(self.start, self.position - SCRUB_FRAME), True
        elif code == KEY_UP:
            self.position = min(self.end, self.position + SCRUB_JUMP)
        elif code == KEY_DOWN:
            self.position = max(self.start, self.position - SCRUB_JUMP)
        elif code == KEY_END:
            self.position, self.paused = self.end, True

    def status(self) -> str:
        state = "ended" if self.position >= self.end else ("paused" if self.paused else "playing")
        return f"{state}, speed {self.speed:g}x"


def nearest_row(t: np.ndarray, time_: float) -> int:
    """Index of the recorded time nearest to `time_` (t sorted ascending)."""
    i = int(np.clip(np.searchsorted(t, time_), 1, len(t) - 1)) if len(t) > 1 else 0
    if i > 0 and time_ - t[i - 1] <= t[i] - time_:
        i -= 1
    return i


# ---------------------------------------------------------------------------------------------
# Run folders (read by hexabot_sim.recording)


def _scenario_live(name: str | None, values: dict[str, Any]) -> Any:
    """The scenario's Live hook built with these parameters, or None (its markers are optional in a replay)."""
    from hexabot_sim import params as params_mod
    from hexabot_sim import registry

    if name not in registry.SCENARIOS:
        return None
    scenario = registry.SCENARIOS[name]
    hook = scenario.live
    if hook is None:
        return None
    try:
        values = {k: tuple(v) if isinstance(v, list) else v for k, v in values.items()}
        return hook(params_mod.resolve(scenario.params_type, {}, values))
    except Exception:  # parameters from another version: replay without the scenario's drawings
        return None


def live_maker(name: str, p: Any) -> Callable[[], Any]:
    """Builds the scenario's Live with parameters p on each call (UsageError for a scenario that is no motion)."""
    from hexabot_sim import registry

    hook = registry.get(name).live
    if hook is None:
        raise UsageError(
            f"{name} is a grid of runs, not one motion to watch; view one point of it live, e.g. "
            "hexabot-sim view leg-step --set amplitude=0.05 --set omega=1"
        )
    return lambda: hook(p)


# ---------------------------------------------------------------------------------------------
# The window


@dataclasses.dataclass
class Scene:
    """What the window shows besides the model: markers, a trail, text lines."""

    markers: Sequence[Any] = ()
    trail: list[np.ndarray] = dataclasses.field(default_factory=list)  # world points, oldest first
    lines: list[str] = dataclasses.field(default_factory=list)


def _with_shift(code: int) -> int:
    """The key code, plus SHIFT if a shift key is held (read from the window's thread, where the callback runs)."""
    import glfw

    window = glfw.get_current_context()
    held = bool(window) and any(glfw.get_key(window, k) == glfw.PRESS for k in (KEY_LEFT_SHIFT, KEY_RIGHT_SHIFT))
    return code | SHIFT if held and code not in (KEY_LEFT_SHIFT, KEY_RIGHT_SHIFT) else code


@contextmanager
def _window(model: Any, data: Any, keys: deque[int], title: str) -> Iterator[Any]:
    """MuJoCo's passive viewer on (model, data), side panels hidden; closed and its thread joined on exit."""
    from hexabot_sim import render

    handle, threads = render.launch_window(model, data, lambda code: keys.append(_with_shift(code)))
    try:
        yield handle
    finally:
        render.close_window(handle, threads, JOIN_TIMEOUT)  # the thread must end before the interpreter exits


def _draw(handle: Any, scene: Scene, help_rows: Sequence[tuple[str, str]]) -> None:
    """Markers and trail into the viewer's user scene, text into its overlay."""
    import mujoco

    from hexabot_sim import render

    with handle.lock():
        user = handle.user_scn
        user.ngeom = 0
        for marker in scene.markers:
            render.add_segment(user, marker)
        if len(scene.trail) >= 2:
            render.add_polyline(user, np.asarray(scene.trail), render.TRAIL_WIDTH, render.TRAIL_RGBA)
    font = mujoco.mjtFontScale.mjFONTSCALE_150
    handle.set_texts(
        [
            (font, mujoco.mjtGridPos.mjGRID_TOPLEFT, "\n".join(scene.lines), ""),
            (
                font,
                mujoco.mjtGridPos.mjGRID_BOTTOMLEFT,
                "\n".join(k for k, _ in help_rows),
                "\n".join(v for _, v in help_rows),
            ),
        ]
    )


def _deadline(quit_after: float | None) -> float:
    return math.inf if quit_after is None else time.monotonic() + quit_after


def replay(
    rec: Recording,
    *,
    speed: float = 1.0,
    paused: bool = False,
    quit_after: float | None = None,
    announce: Callable[[str], None] = print,
) -> str:
    """Replays a run folder (load_recording) in the viewer until its window is closed (or quit_after wall seconds
    after it opens).

    Returns:
        One line naming the last state shown (time, row, and whether it is the final state).
    """
    import mujoco

    from hexabot_sim import render

    folder = rec.folder
    try:
        model = mujoco.MjModel.from_xml_string(rec.xml)
    except Exception as e:
        raise UsageError(f"cannot load {rec.xml_path}: {' '.join(str(e).split())}") from None
    if rec.qpos.shape[1] != model.nq or rec.qvel.shape[1] != model.nv:
        raise UsageError(
            f"{folder}: trajectory.npz has {rec.qpos.shape[1]} qpos / {rec.qvel.shape[1]} qvel columns, "
            f"the model {model.nq} / {model.nv}: they are not from the same run"
        )
    data = mujoco.MjData(model)
    hook = _scenario_live(rec.scenario, rec.params)
    t, n = rec.t, len(rec.t)
    has_ctrl = rec.ctrl.shape[1] == model.nu

    def pose(row: int) -> None:
        data.qpos[:], data.qvel[:], data.time = rec.qpos[row], rec.qvel[row], t[row]
        if has_ctrl:
            data.ctrl[:] = rec.ctrl[row]
        mujoco.mj_forward(model, data)

    # The trail over the whole run, sampled once (the window draws the part up to the row shown).
    samples = np.unique(np.linspace(0, n - 1, min(n, TRAIL_SAMPLES)).astype(int))
    trail = np.empty((0, 3))
    if hook is not None and hook.trail is not None:
        points = []
        for row in samples:
            data.qpos[:] = rec.qpos[row]
            mujoco.mj_kinematics(model, data)
            points.append(np.array(hook.trail(data), dtype=float))
        trail = np.array(points)
    clock = Clock(float(t[0]), float(t[-1]), float(t[0]), speed=speed, paused=paused)
    keys: deque[int] = deque()
    row = 0
    pose(row)
    overlay = hook.overlay if hook is not None else []
    scene = Scene(markers=hook.markers if hook is not None else ())
    with _window(model, data, keys, str(folder)) as handle:
        if hook is not None:
            render.view_camera(handle.cam, model, data, hook.camera, hook.track_body)
        announce(f"replaying {folder} ({rec.scenario or 'unknown scenario'}, {t[-1] - t[0]:.6g} s, {n} states)")
        deadline = _deadline(quit_after)  # from the window's opening (seconds on a loaded machine with software GL)
        last = time.monotonic()
        while handle.is_running() and time.monotonic() < deadline:
            now = time.monotonic()
            while keys:
                clock.key(keys.popleft() & ~SHIFT)
            clock.advance(now - last)
            last = now
            row = nearest_row(t, clock.position)
            with handle.lock():
                pose(row)
            if len(trail):
                scene.trail = [*trail[samples <= row], np.array(hook.trail(data), dtype=float)]
            scene.lines = [
                f"t = {t[row]:.3f} s / {t[-1]:.3f} s   ({clock.status()})",
                *(line(data) for line in overlay),
            ]
            _draw(handle, scene, HELP_REPLAY)
            handle.sync()
            time.sleep(max(0.0, FRAME_PERIOD - (time.monotonic() - now)))
    final = ", the final state" if row == n - 1 else ""
    return f"last state shown: t = {t[row]:.6g} s (row {row} of {n - 1}{final})"


def live(
    make: Callable[[], Any],
    name: str,
    *,
    speed: float = 1.0,
    paused: bool = False,
    quit_after: float | None = None,
    announce: Callable[[str], None] = print,
) -> str:
    """Steps a scenario in real time in the viewer until its window is closed (or quit_after wall seconds after it
    opens).

    Args:
        make: Builds the scenario's Live (called again when Home restarts it).

    Returns:
        One line naming the simulated time reached.

    Raises:
        SimulationError: if the simulation diverged (it is shown paused until the window closes).
    """
    import mujoco

    from hexabot_sim import render

    sim = make()
    model = sim.model
    data = mujoco.MjData(model)  # the window's copy: a restart builds a new simulation, the window stays

    def show() -> None:
        data.qpos[:], data.qvel[:], data.ctrl[:], data.time = sim.data.qpos, sim.data.qvel, sim.data.ctrl, sim.data.time
        mujoco.mj_forward(model, data)

    clock = Clock(0.0, sim.duration, 0.0, speed=speed, paused=paused, live=True)
    keys: deque[int] = deque()
    scene = Scene(markers=sim.markers)
    diverged = ""
    behind = False
    show()
    with _window(model, data, keys, name) as handle:
        render.view_camera(handle.cam, model, data, sim.camera, sim.track_body)
        announce(f"viewing {name} live ({sim.duration:.6g} s simulated, timestep {sim.timestep:g} s)")
        deadline = _deadline(quit_after)  # from the window's opening
        last = time.monotonic()
        while handle.is_running() and time.monotonic() < deadline:
            now = time.monotonic()
            while keys:
                code = keys.popleft()
                if sim.keys is None or not sim.keys(code & ~SHIFT, bool(code & SHIFT)):  # the scenario's first
                    clock.key(code & ~SHIFT)
            if clock.restart:
                sim, diverged = make(), ""
                clock = Clock(0.0, sim.duration, 0.0, speed=clock.speed, live=True)
                scene.trail.clear()
            if not diverged:
                clock.advance(now - last)
                # Step until the simulation reaches the clock (within this frame's budget).
                budget_end = time.monotonic() + STEP_BUDGET
                while sim.data.time + 0.5 * sim.timestep < clock.position and time.monotonic() < budget_end:
                    sim.step()
                if not (np.isfinite(sim.data.qpos).all() and np.isfinite(sim.data.qvel).all()):
                    diverged = f"the simulation diverged at t = {sim.data.time:.4g} s"
                    clock.paused = True
                behind = clock.position - sim.data.time > MAX_LAG
                if behind:  # slower than the clock: drop the backlog rather than spiral
                    clock.position = sim.data.time
            last = now
            if not diverged:
                with handle.lock():
                    show()
            if sim.trail is not None and not diverged:
                point = np.array(sim.trail(sim.data), dtype=float)
                if not scene.trail or np.any(point != scene.trail[-1]):
                    scene.trail.append(point)
                if len(scene.trail) > TRAIL_KEEP:  # a long run: keep every other point (the path's shape stays)
                    scene.trail[:] = scene.trail[::2]
            scene.lines = [
                f"t = {sim.data.time:.3f} s / {sim.duration:.3f} s   ({clock.status()})"
                + ("  [slower than real time]" if behind else ""),
                *(line(sim.data) for line in sim.overlay),
                *([diverged.upper()] if diverged else []),
            ]
            _draw(handle, scene, help_rows(sim))
            handle.sync()
            time.sleep(max(0.0, FRAME_PERIOD - (time.monotonic() - now)))
    if diverged:
        raise SimulationError(f"{diverged} (try a smaller timestep: hexabot-sim run {name} names the cause)")
    summary = f"; {sim.summary(sim.data)}" if sim.summary is not None else ""
    return f"last state shown: t = {sim.data.time:.6g} s of {sim.duration:.6g} s{summary}"


def help_rows(sim: Any) -> tuple[tuple[str, str], ...]:
    """The live view's key help: the scenario's keys first; Right steps a frame only where the scenario leaves it."""
    if not sim.key_help:
        return HELP_LIVE
    return (*sim.key_help, *(row for row in HELP_LIVE if row[0] != "Right"))
