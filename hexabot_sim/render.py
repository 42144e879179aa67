"""Off-screen frames of a recorded trajectory, streamed one by one into an MP4 encoder."""

from __future__ import annotations

import copy
import dataclasses
import itertools
from collections.abc import Callable, Sequence
from pathlib import Path

import mujoco
import numpy as np

from hexabot_sim.scenarios.base import Marker


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

Progress = Callable[[int, int], None]


def frame_indices(t: np.ndarray, fps: float) -> np.ndarray:
    """Row of the recording nearest to each frame time t0 + i / fps: video duration = simulated duration."""
    n_frames = int(np.floor((t[-1] - t[0]) * fps + 1e-9)) + 1
    times = t[0] + np.arange(n_frames) / fps
    idx = np.clip(np.searchsorted(t, times), 1, len(t) - 1)
    nearer_left = (times - t[idx - 1]) <= (t[idx] - times)
    return np.where(nearer_left, idx - 1, idx)


TRAIL_SEGMENTS: int = 150  # at most this many line segments draw a trail (cost grows per segment)
TRAIL_WIDTH: float = 3.0  # [px]
TRAIL_RGBA = np.array([1.0, 0.85, 0.1, 1.0], dtype=np.float32)


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
    progress: Progress | None = None,
) -> int:
    """Renders the recorded states (t: (n,), qpos: (n, nq)) from `camera` into an MP4 at `path`.

    Frames are encoded as they are rendered; only one frame is held in memory. `markers` are drawn
    in every frame; `trail` (n, 3) world points are drawn as the path travelled up to each frame.

    Returns:
        Number of frames written.
    """
    import imageio.v2 as imageio

    preset = QUALITY[quality]
    model = copy.copy(model)  # the presets edit visual options only on this copy
    model.vis.quality.offsamples = preset.offsamples
    model.vis.quality.shadowsize = preset.shadowsize
    model.vis.global_.offwidth = max(model.vis.global_.offwidth, width)
    model.vis.global_.offheight = max(model.vis.global_.offheight, height)
    data = mujoco.MjData(model)
    indices = frame_indices(t, fps)
    camera_id = model.camera(camera).id

    writer = imageio.get_writer(
        str(path),
        fps=fps,
        codec="libx264",
        quality=preset.crf_quality,
        pixelformat="yuv420p",
        macro_block_size=16,
        ffmpeg_log_level="error",
        output_params=["-preset", preset.x264_preset],
    )
    try:
        with mujoco.Renderer(model, height, width, max_geom=model.ngeom + TRAIL_SEGMENTS + 100) as renderer:
            if preset.shadowsize == 0:
                renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = False
            for n, row in enumerate(indices):
                # Pose the model at the recorded state, draw it, hand the frame to the encoder.
                data.qpos[:] = qpos[row]
                data.time = t[row]
                mujoco.mj_kinematics(model, data)
                mujoco.mj_camlight(model, data)
                renderer.update_scene(data, camera=camera_id)
                for marker in markers:
                    add_segment(renderer.scene, marker)
                if trail is not None:  # the path travelled so far
                    add_polyline(renderer.scene, trail[indices[: n + 1]], TRAIL_WIDTH, TRAIL_RGBA)
                writer.append_data(renderer.render())
                if progress is not None:
                    progress(n + 1, len(indices))
    finally:
        writer.close()
    return len(indices)
