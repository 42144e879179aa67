"""Off-screen frames of a recorded trajectory, streamed one by one into an MP4 encoder."""

from __future__ import annotations

import copy
import dataclasses
import functools
import itertools
import math
import threading
from collections.abc import Callable, Sequence
from pathlib import Path

import mujoco
import numpy as np

from hexabot_sim.encoder_watchdog import EncoderWatchdog
from hexabot_sim.signals import RECEIVED_SIGNALS, stop_request
from hexabot_sim.video import frame_count


@dataclasses.dataclass(frozen=True)
class Marker:
    """A segment drawn into every video frame (e.g. a predicted rest angle), world frame [m]."""

    start: tuple[float, float, float]
    end: tuple[float, float, float]
    radius: float
    rgba: tuple[float, float, float, float]


# [s] A frame the encoder has not taken after this long: it is stuck (an encoder that never reads its
# input would otherwise hang the run for ever). The slowest frame measured here, 4K at the high preset,
# takes 0.45 s.
FRAME_TIMEOUT: float = 120.0


@dataclasses.dataclass(frozen=True)
class Quality:
    """Render settings of a preset."""

    offsamples: int  # multisample anti-aliasing samples (0 = off)
    shadowsize: int  # shadow map size in texels (0 = no shadows)
    crf_quality: int  # imageio-ffmpeg quality, 0 (worst) .. 10 (best)
    x264_preset: str  # encoder speed: ultrafast costs least CPU, leaving more for the software renderer


# On a CPU (Mesa llvmpipe), multisampling and shadows cost ~8x in frame rate.
QUALITY: dict[str, Quality] = {
    "preview": Quality(offsamples=0, shadowsize=0, crf_quality=6, x264_preset="ultrafast"),
    "high": Quality(offsamples=8, shadowsize=4096, crf_quality=8, x264_preset="medium"),
}

FPS: int = 30  # [frames/s] video frame rate
# Scene cameras are framed for this width / height (the default 640x480). A narrower frame gets a
# taller field of view, so it keeps at least the width the camera was framed for; a wider one shows more.
DESIGN_ASPECT: float = 4 / 3

Progress = Callable[[int, int], None]
# One line of the text overlay: recording row -> text (e.g. lambda i: f"theta = {deg[i]:6.1f} deg").
OverlayLine = Callable[[int], str]


def frame_indices(t: np.ndarray, fps: float) -> np.ndarray:
    """Row of the recording nearest to each frame time t0 + i / fps: video duration = simulated duration."""
    n_frames = frame_count(float(t[-1] - t[0]), fps)
    times = t[0] + np.arange(n_frames) / fps
    idx = np.clip(np.searchsorted(t, times), 1, len(t) - 1)
    nearer_left = (times - t[idx - 1]) <= (t[idx] - times)
    return np.where(nearer_left, idx - 1, idx)


TRAIL_SEGMENTS: int = 150  # at most this many line segments draw a trail (cost grows per segment)
TRAIL_WIDTH: float = 3.0  # [px]
TRAIL_RGBA = np.array([1.0, 0.85, 0.1, 1.0], dtype=np.float32)


def fit_camera(
    points: np.ndarray,
    xyaxes: Sequence[float],
    fovy: float,
    aspect: float = DESIGN_ASPECT,
    margin: float = 0.1,
    text_lines: int = 0,
) -> np.ndarray:
    """Camera position [m] that frames `points` (k, 3) tightly, keeping the camera's orientation.

    The camera looks along -z of its frame (x right, y up, as MJCF `xyaxes`); it is centred on the
    points' extent across the view and moved back until every point is inside the field of view.

    Args:
        points: World points [m] that must be in view, e.g. a trajectory's envelope.
        xyaxes: The camera's right and up axes (6 numbers, as in MJCF), world frame.
        fovy: Vertical field of view in [deg].
        aspect: Frame width / height the framing is made for.
        margin: Free border, as a fraction of the half field of view on each side.
        text_lines: Lines of overlay text the video draws at the top: that band is kept free.

    Returns:
        (3,) camera position, world frame [m].
    """
    axes = np.asarray(xyaxes, dtype=float).reshape(2, 3)  # (2, 3)
    right = axes[0] / np.linalg.norm(axes[0])
    up = axes[1] - (axes[1] @ right) * right  # orthogonalised like MuJoCo does
    up /= np.linalg.norm(up)
    forward = np.cross(up, right)  # the camera looks along -z = y x x
    pts = np.asarray(points, dtype=float).reshape(-1, 3)  # (k, 3)
    px, py, pz = pts @ right, pts @ up, pts @ forward  # (k,) each, camera-aligned coordinates
    cx, cy = 0.5 * (px.max() + px.min()), 0.5 * (py.max() + py.min())
    tan_v = math.tan(math.radians(fovy) / 2) / (1 + margin)
    tan_h = tan_v * aspect
    band = overlay_fraction(text_lines)  # the top `band` of the frame height is left to the text
    tan_below = tan_v * (1 - band)  # the points fit a window (1 - band) as tall, centred band lower
    # Each point needs depth >= its offset from the centre / tan(half field of view).
    depth = np.minimum(pz - np.abs(px - cx) / tan_h, pz - np.abs(py - cy) / tan_below)
    eye_z = float(depth.min())
    # Lift the camera so the window sits below the band (exact for points at one depth).
    cy += band * tan_v * float(np.mean(pz - eye_z))
    return cx * right + cy * up + eye_z * forward


def overlay_fraction(lines: int) -> float:
    """Fraction of the frame height the overlay text takes with `lines` lines (the time included)."""
    if lines <= 0:
        return 0.0
    return min(0.5, (1.35 * lines + 0.8) * OVERLAY_TEXT_HEIGHT)


def _fovy_for(fovy: float, aspect: float) -> float:
    """Vertical field of view [deg] that keeps the horizontal field the camera has at DESIGN_ASPECT."""
    if aspect >= DESIGN_ASPECT:
        return fovy
    return math.degrees(2 * math.atan(math.tan(math.radians(fovy) / 2) * DESIGN_ASPECT / aspect))


# ---------------------------------------------------------------------------------------------
# Text overlay: glyphs rasterised once by matplotlib's Agg (no backend is selected), then copied
# into each frame with numpy; a few hundred pixels per frame, so the preview frame rate keeps.

OVERLAY_FONT: str = "DejaVu Sans Mono"  # monospaced: numbers do not jitter from frame to frame
OVERLAY_TEXT_HEIGHT: float = 0.034  # glyph size as a fraction of the frame height
OVERLAY_MIN_PX: int = 8  # [px] smallest glyph size (small videos stay legible)
OVERLAY_BOX_SHADE: float = 0.35  # the box behind the text keeps this fraction of the scene's brightness


class GlyphAtlas:
    """Anti-aliased masks of monospaced characters, all one cell in size, rasterised on first use."""

    def __init__(self, px: int) -> None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
        from matplotlib.font_manager import FontProperties

        self._prop = FontProperties(family=OVERLAY_FONT, size=px)  # points at 72 dpi = pixels
        renderer = FigureCanvasAgg(Figure(figsize=(1, 1), dpi=72)).get_renderer()
        width, _, _ = renderer.get_text_width_height_descent("M" * 10, self._prop, ismath=False)
        self.cell_width = max(1, round(width / 10))  # [px] advance of every character
        self.descent = math.ceil(0.25 * px)  # [px] room below the baseline (g, y, parentheses)
        self.cell_height = math.ceil(1.05 * px) + self.descent  # [px]
        self._masks: dict[str, np.ndarray] = {}
        self._lines: dict[str, np.ndarray] = {}
        self._add(" 0123456789.,:;+-=()[]/%|<>abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ_θωσ°−·²³µ")

    def _add(self, chars: str) -> None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        chars = "".join(dict.fromkeys(c for c in chars if c not in self._masks))
        if not chars:
            return
        stride = 2 * self.cell_width + 4  # [px] spacing in the scratch image: no glyph touches its neighbour
        width, height = stride * len(chars), self.cell_height
        fig = Figure(figsize=(width / 72, height / 72), dpi=72, facecolor="black")
        for n, char in enumerate(chars):
            fig.text(
                (n * stride + 2) / width, self.descent / height, char, color="white", fontproperties=self._prop,
                ha="left", va="baseline",
            )  # fmt: skip
        canvas = FigureCanvasAgg(fig)
        canvas.draw()
        image = np.asarray(canvas.buffer_rgba())[:, :, 0].astype(np.float32) / 255  # (h, w) coverage 0..1
        for n, char in enumerate(chars):
            self._masks[char] = image[:, n * stride + 2 : n * stride + 2 + self.cell_width].copy()

    def mask(self, text: str) -> np.ndarray:
        """(cell_height, cell_width * len(text)) coverage of `text`, 0..1 (lines that repeat are cached)."""
        cached = self._lines.get(text)
        if cached is None:
            self._add(text)
            cached = np.concatenate([self._masks[c] for c in text], axis=1)
            if len(self._lines) >= 64:  # most lines change every frame: keep only a few
                self._lines.clear()
            self._lines[text] = cached
        return cached


@functools.lru_cache(maxsize=4)
def glyph_atlas(px: int) -> GlyphAtlas:
    """The atlas for one glyph size, built once per process."""
    return GlyphAtlas(px)


def overlay_px(height: int) -> int:
    """Glyph size [px] of the overlay in a frame `height` pixels tall."""
    return max(OVERLAY_MIN_PX, round(OVERLAY_TEXT_HEIGHT * height))


def draw_text(frame: np.ndarray, lines: Sequence[str], atlas: GlyphAtlas | None = None) -> None:
    """Writes `lines` in white on a darkened box into the top-left corner of `frame` (h, w, 3) uint8, in place."""
    lines = [line for line in lines if line]
    if not lines:
        return
    atlas = atlas or glyph_atlas(overlay_px(frame.shape[0]))
    pad = max(2, atlas.cell_width // 2)
    masks = [atlas.mask(line) for line in lines]
    box_w = min(frame.shape[1], max(m.shape[1] for m in masks) + 2 * pad)
    box_h = min(frame.shape[0], atlas.cell_height * len(masks) + 2 * pad)
    box = frame[:box_h, :box_w].astype(np.float32) * OVERLAY_BOX_SHADE  # (box_h, box_w, 3)
    for n, mask in enumerate(masks):
        top = pad + n * atlas.cell_height
        rows = box[top : top + mask.shape[0], pad : pad + mask.shape[1]]
        cover = mask[: rows.shape[0], : rows.shape[1], None]
        rows += (255 - rows) * cover  # white text, anti-aliased
    frame[:box_h, :box_w] = box.astype(np.uint8)


def add_segment(scene: mujoco.MjvScene, marker: Marker) -> None:
    """Appends a capsule from marker.start to marker.end to the scene (if there is room)."""
    _connector(scene, mujoco.mjtGeom.mjGEOM_CAPSULE, marker.radius, marker.start, marker.end, marker.rgba)


def add_polyline(scene: mujoco.MjvScene, points: np.ndarray, width: float, rgba: np.ndarray) -> None:
    """Appends thin lines through points (k, 3), subsampled to at most TRAIL_SEGMENTS segments."""
    if len(points) < 2:
        return
    step = -(-(len(points) - 1) // TRAIL_SEGMENTS)
    keep = np.r_[points[:-1:step], points[-1:]]  # always ends at the newest point
    for a, b in itertools.pairwise(keep):
        _connector(scene, mujoco.mjtGeom.mjGEOM_LINE, width, a, b, rgba)


def _connector(scene: mujoco.MjvScene, kind: int, width: float, start, end, rgba) -> None:
    if scene.ngeom >= scene.maxgeom:
        return
    geom = scene.geoms[scene.ngeom]
    mujoco.mjv_initGeom(geom, kind, np.zeros(3), np.zeros(3), np.eye(3).ravel(), np.asarray(rgba, np.float32))
    mujoco.mjv_connector(geom, kind, width, np.asarray(start, float), np.asarray(end, float))
    scene.ngeom += 1


def _offscreen(
    model: mujoco.MjModel, width: int, height: int, camera: str, preset: Quality
) -> tuple[mujoco.MjModel, int]:
    """A copy of the model set up for off-screen frames of this size with a quality preset (its visual options
    edited only on the copy), and the camera's id, its vertical field of view fitted to the aspect ratio."""
    model = copy.copy(model)
    model.vis.quality.offsamples = preset.offsamples
    model.vis.quality.shadowsize = preset.shadowsize
    model.vis.global_.offwidth = max(model.vis.global_.offwidth, width)
    model.vis.global_.offheight = max(model.vis.global_.offheight, height)
    camera_id = model.camera(camera).id
    model.cam_fovy[camera_id] = _fovy_for(float(model.cam_fovy[camera_id]), width / height)
    return model, camera_id


def render_video(
    model: mujoco.MjModel,
    t: np.ndarray,
    qpos: np.ndarray,
    path: Path,
    *,
    camera: str,
    width: int = 640,
    height: int = 480,
    fps: int = FPS,
    quality: str = "preview",
    markers: Sequence[Marker] = (),
    trail: np.ndarray | None = None,
    overlay: Sequence[OverlayLine] = (),
    progress: Progress | None = None,
) -> int:
    """Renders the recorded states (t: (n,), qpos: (n, nq)) from `camera` into an MP4 at `path`.

    Frames are encoded as they are rendered; only one frame is held in memory. `markers` are drawn
    in every frame; `trail` (n, 3) world points are drawn as the path travelled up to each frame.
    Every frame shows the simulated time, then one text line per `overlay` function (called with
    the recording row of the frame), in its top-left corner.

    Args:
        width, height: Frame size in [px]; the file has exactly this size, so both must be even
            (H.264 in yuv420p stores colour at half resolution).

    Returns:
        Number of frames written.

    Raises:
        ValueError: If width or height is odd or not positive.
    """
    import imageio.v2 as imageio

    for name, value in (("width", width), ("height", height)):
        if value < 2 or value % 2:
            raise ValueError(f"video {name} must be an even number of pixels >= 2 (H.264, yuv420p); got {value}")
    preset = QUALITY[quality]
    model, camera_id = _offscreen(model, width, height, camera, preset)
    data = mujoco.MjData(model)
    indices = frame_indices(t, fps)
    atlas = glyph_atlas(overlay_px(height))
    digits = len(f"{t[-1]:.2f}")  # the time keeps its width, so the text does not jitter

    writer = imageio.get_writer(
        str(path),
        fps=fps,
        codec="libx264",
        quality=preset.crf_quality,
        pixelformat="yuv420p",
        macro_block_size=2,  # never resized: the size was checked to be even above
        ffmpeg_log_level="quiet",  # one line of ours on failure, not the encoder's chatter
        output_params=["-preset", preset.x264_preset],
    )
    import imageio_ffmpeg

    watchdog = EncoderWatchdog(imageio_ffmpeg.get_ffmpeg_exe(), FRAME_TIMEOUT)
    try:
        with watchdog, mujoco.Renderer(model, height, width, max_geom=model.ngeom + TRAIL_SEGMENTS + 100) as renderer:
            if preset.shadowsize == 0:
                renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = False
            for n, row in enumerate(indices):
                # Pose the model at the recorded state, draw it, hand the frame to the encoder.
                data.qpos[:] = qpos[row]
                data.time = t[row]
                mujoco.mj_kinematics(model, data)
                mujoco.mj_comPos(model, data)  # subtree centres of mass: "trackcom" cameras follow them
                mujoco.mj_camlight(model, data)
                renderer.update_scene(data, camera=camera_id)
                for marker in markers:
                    add_segment(renderer.scene, marker)
                if trail is not None:  # the path travelled so far
                    add_polyline(renderer.scene, trail[indices[: n + 1]], TRAIL_WIDTH, TRAIL_RGBA)
                frame = renderer.render()  # (height, width, 3) uint8, a new array
                draw_text(frame, [f"t = {t[row]:{digits}.2f} s", *(line(int(row)) for line in overlay)], atlas)
                watchdog.arm()
                try:
                    writer.append_data(frame)
                except Exception as e:
                    if watchdog.fired:
                        stuck = f"the video encoder took no frame for {FRAME_TIMEOUT:g} s and was stopped"
                        raise RuntimeError(stuck) from e
                    # imageio-ffmpeg re-raises the pipe's error as a plain OSError: it read "rendering failed: OSError:
                    # [Errno 32] Broken pipe"
                    if any(isinstance(x, BrokenPipeError) for x in (e, e.__cause__, e.__context__)):
                        raise RuntimeError(f"the video encoder stopped after {n} of {len(indices)} frames") from e
                    raise
                watchdog.disarm()
                if RECEIVED_SIGNALS:  # a stop request whose exception some library swallowed
                    raise stop_request(RECEIVED_SIGNALS[-1])
                if progress is not None:
                    progress(n + 1, len(indices))
    finally:
        try:
            writer.close()
        except Exception:
            if not watchdog.fired:  # closing the pipe of the encoder we stopped fails too; that is reported above
                raise
    return len(indices)


class Frames:
    """Single frames of a live simulation (a Gymnasium environment's render()): render_video's preset and field of
    view on a copy of the model, no encoder.

    Args:
        model: The simulated model, copied as it is now (its heightfields: make another Frames after changing one).
        width, height: Frame size in [px].
        camera: The camera's name.
    """

    def __init__(self, model: mujoco.MjModel, width: int, height: int, camera: str, quality: str = "preview") -> None:
        preset = QUALITY[quality]
        model, self.camera = _offscreen(model, width, height, camera, preset)
        self.renderer = mujoco.Renderer(model, height, width)
        if preset.shadowsize == 0:
            self.renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = False

    def __call__(self, data: mujoco.MjData) -> np.ndarray:
        """The frame (height, width, 3) uint8 of the state in `data` (a new array)."""
        self.renderer.update_scene(data, camera=self.camera)
        return self.renderer.render()

    def close(self) -> None:
        self.renderer.close()


def view_camera(
    cam: mujoco.MjvCamera, model: mujoco.MjModel, data: mujoco.MjData, camera: str | None, track_body: str | None
) -> None:
    """Sets a window's free (or tracking) camera `cam` to look from the scene camera the videos use (a name in the
    model; else left alone); the mouse can move it. `track_body`: the view follows that body."""
    if camera is None or camera not in [model.camera(i).name for i in range(model.ncam)]:
        return
    cam_id = model.camera(camera).id
    pos, rot = data.cam_xpos[cam_id], data.cam_xmat[cam_id].reshape(3, 3)
    forward = -rot[:, 2]  # a camera looks along its -z axis
    centre = data.xpos[model.body(track_body).id] if track_body else model.stat.center
    distance = max(0.05, float((centre - pos) @ forward))
    cam.lookat[:] = pos + distance * forward
    cam.distance = distance
    cam.azimuth = math.degrees(math.atan2(forward[1], forward[0]))
    cam.elevation = math.degrees(math.asin(float(np.clip(forward[2], -1.0, 1.0))))
    if track_body:
        cam.type = mujoco.mjtCamera.mjCAMERA_TRACKING
        cam.trackbodyid = model.body(track_body).id
    else:
        cam.type = mujoco.mjtCamera.mjCAMERA_FREE


def launch_window(
    model: mujoco.MjModel, data: mujoco.MjData, key_callback: Callable[[int], None] | None = None
) -> tuple[object, list[threading.Thread]]:
    """MuJoCo's passive viewer on (model, data), side panels hidden: its handle and the threads it started (which
    must end before the interpreter exits: close_window)."""
    import mujoco.viewer

    before = set(threading.enumerate())
    handle = mujoco.viewer.launch_passive(
        model, data, key_callback=key_callback, show_left_ui=False, show_right_ui=False
    )
    return handle, [t for t in threading.enumerate() if t not in before]


def close_window(handle: object, threads: list[threading.Thread], timeout: float) -> None:
    """Closes a launch_window window and waits up to `timeout` [s] for each of its threads (not the calling one)."""
    handle.close()  # type: ignore[attr-defined]
    for thread in threads:
        if thread is not threading.current_thread():
            thread.join(timeout)
