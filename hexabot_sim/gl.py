"""Chooses a headless OpenGL backend for MuJoCo (EGL, then OSMesa) by probing in a subprocess.

MuJoCo and PyOpenGL bind their backend when first imported, so a backend that fails cannot be
swapped in-process: each candidate is tried in a short-lived child interpreter first.
"""

from __future__ import annotations

import functools
import os
import subprocess
import sys
import tempfile
from collections.abc import Callable

BACKENDS: tuple[str, ...] = ("egl", "osmesa")
PROBE_TIMEOUT: float = 60.0  # [s] software GL can be slow to start on a loaded machine

_PROBE = """
import mujoco
model = mujoco.MjModel.from_xml_string("<mujoco><worldbody><geom size='1'/></worldbody></mujoco>")
with mujoco.Renderer(model, 16, 16) as renderer:
    renderer.update_scene(mujoco.MjData(model))
    assert renderer.render().shape == (16, 16, 3)
"""


@functools.cache
def probe(backend: str) -> str | None:
    """None if MuJoCo renders with MUJOCO_GL=backend here, else the reason it does not (one line)."""
    env = dict(os.environ, MUJOCO_GL=backend)
    env.pop("PYOPENGL_PLATFORM", None)
    try:
        # Run in a fresh temporary folder: a failing GL may make MuJoCo drop MUJOCO_LOG.TXT in its cwd.
        with tempfile.TemporaryDirectory(prefix="hexabot-sim-gl-") as cwd:
            proc = subprocess.run(
                [sys.executable, "-c", _PROBE], env=env, capture_output=True, text=True, timeout=PROBE_TIMEOUT, cwd=cwd
            )
    except subprocess.TimeoutExpired:
        return f"{backend}: no answer within {PROBE_TIMEOUT:.0f} s"
    if proc.returncode == 0:
        return None
    lines = [line.strip() for line in proc.stderr.splitlines() if line.strip()]
    return f"{backend}: {lines[-1] if lines else f'exit code {proc.returncode}'}"


def loaded_backend() -> str | None:
    """The backend MuJoCo was imported with in this process, or None if it is not imported yet."""
    if "mujoco" not in sys.modules:
        return None
    return os.environ.get("MUJOCO_GL", "").lower() or "glfw"


def choose() -> tuple[str | None, str, str]:
    """Picks a working backend and exports MUJOCO_GL before MuJoCo is imported.

    Returns:
        (backend, "", notice) when one works, else (None, reason, notice) with one line saying why
        there is no video; `notice` is non-empty when the MUJOCO_GL the user set did not work and
        another backend was chosen instead.
    """
    loaded = loaded_backend()
    if loaded is not None:  # too late to switch: the one already bound must work
        reason = probe(loaded)
        return (loaded, "", "") if reason is None else (None, f"no working OpenGL: {reason}", "")
    wanted = os.environ.get("MUJOCO_GL", "").strip().lower()
    candidates = [wanted] + [b for b in BACKENDS if b != wanted] if wanted else list(BACKENDS)
    reasons = []
    for backend in candidates:
        reason = probe(backend)
        if reason is None:
            os.environ["MUJOCO_GL"] = backend
            # As in the probe: MuJoCo sets PyOpenGL's platform to the backend itself, and one set to another made the
            # backend the probe found working fail in the run ("Cannot use EGL rendering platform").
            os.environ.pop("PYOPENGL_PLATFORM", None)
            notice = (
                f"MUJOCO_GL={wanted!r} does not work here ({reasons[0]}); rendering with {backend}" if reasons else ""
            )
            return backend, "", notice
        reasons.append(reason)
    os.environ["MUJOCO_GL"] = "disable"  # so that importing MuJoCo for the simulation still works
    return None, "no working OpenGL (" + "; ".join(reasons) + ")", ""


def disable_if_unused() -> None:
    """For work that draws nothing: MuJoCo is imported without OpenGL, so a MUJOCO_GL that names a
    backend that is not installed (or is not a backend at all) cannot stop it."""
    if "mujoco" not in sys.modules:
        os.environ["MUJOCO_GL"] = "disable"


FFMPEG_TIMEOUT: float = 10.0  # [s] `ffmpeg -version` answers in milliseconds; a stuck one costs at most this


def ffmpeg_problem() -> str | None:
    """None if the ffmpeg that imageio will use runs here, else one line saying why there is no video."""
    try:
        import imageio_ffmpeg

        exe = imageio_ffmpeg.get_ffmpeg_exe()
    except Exception as e:  # ImportError, or RuntimeError "No ffmpeg exe could be found"
        return f"ffmpeg not found ({' '.join(str(e).split())})"
    try:
        proc = subprocess.run([exe, "-version"], capture_output=True, timeout=FFMPEG_TIMEOUT)
    except (OSError, subprocess.TimeoutExpired) as e:
        return f"ffmpeg {exe!r} does not run ({getattr(e, 'strerror', None) or e})"
    if proc.returncode != 0 or not proc.stdout.startswith(b"ffmpeg"):
        return f"{exe!r} is not a working ffmpeg (exit code {proc.returncode})"
    return None


def video_backend(announce: Callable[[str], None] | None = None) -> tuple[str | None, str]:
    """(working OpenGL backend, "") or (None, why there is no video: no OpenGL, no ffmpeg); `announce` hears a
    fallback's notice. Call it before MuJoCo is imported: the backend it chooses is the one MuJoCo binds."""
    backend, reason, notice = choose()
    if notice and announce is not None:
        announce(notice)
    if backend is not None:
        problem = ffmpeg_problem()
        if problem is not None:
            return None, problem
    return backend, reason


INSTALL_HINT = 'pip install "hexabot-sim[viewer]"'  # glfw, for a window on a display


def display_problem(command: str = "hexabot-sim view ...") -> str | None:
    """None if a viewer window can be opened here, else one line saying why not and what to do (`command`: what to
    run under a virtual display)."""
    try:
        import glfw
    except ImportError:
        return f"the viewer needs the 'viewer' extra (glfw): {INSTALL_HINT}"
    if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
        return (
            "no display is available (DISPLAY is not set): run it in a desktop session, over 'ssh -X', "
            f"or under a virtual one: xvfb-run -a {command}"
        )
    where = os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
    errors: list[str] = []
    codes: list[int] = []
    previous = glfw.ERROR_REPORTING
    glfw.ERROR_REPORTING = "ignore"  # our callback below collects the message

    def collect(code: int, text) -> None:
        codes.append(code)
        errors.append(text.decode() if isinstance(text, bytes) else text)

    glfw.set_error_callback(collect)
    glfw.get_time()  # GLFW_NOT_INITIALIZED unless something in this process already initialised GLFW
    fresh = glfw.NOT_INITIALIZED in codes
    initialised = False
    try:
        if not glfw.init():
            return f"cannot open the display {where!r}: {errors[-1] if errors else 'GLFW failed to initialise'}"
        initialised = True
        glfw.window_hint(glfw.VISIBLE, glfw.FALSE)
        window = glfw.create_window(64, 64, "hexabot-sim probe", None, None)
        if not window:
            return f"no OpenGL window on the display {where!r}: {errors[-1] if errors else 'unknown GLFW error'}"
        glfw.destroy_window(window)
        glfw.default_window_hints()
        return None
    finally:
        if fresh and initialised:  # GLFW left as found: no X connection of ours that a fork (Gymnasium's async
            glfw.terminate()  # vector environment's workers) would share with its parent
        glfw.set_error_callback(None)  # type: ignore[arg-type]
        glfw.ERROR_REPORTING = previous
