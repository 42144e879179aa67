"""Video options (size, frame rate, quality preset), checked once for the CLI and the API, and their cost."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from hexabot_sim.budget import MAX_SECONDS, over
from hexabot_sim.errors import UsageError

# Video frames: H.264 in yuv420p needs even sides; beyond 4:1 a frame shows a sliver of the scene.
MIN_SIDE, MAX_SIZE, MAX_ASPECT = 64, (3840, 2160), 4.0
MAX_FPS: int = 240  # [1/s]
NOT_REQUESTED = "not requested (add --video)"  # run.json's video reason when no video was asked for
PRESETS: tuple[str, ...] = ("preview", "high")  # render.QUALITY holds what each one sets

# Seconds to render and encode one video frame here: a fixed part plus a part per megapixel (software
# OpenGL), per quality preset. Measured: preview 140 frames/s at 640x480 over 301 frames (scripts/bench.py),
# 27 at 1920x1080 and 7.9 at 3840x2160; high 20, 7.4 and 2.2.
FRAME_SECONDS: dict[str, tuple[float, float]] = {"preview": (0.005, 0.013), "high": (0.035, 0.050)}


@dataclasses.dataclass(frozen=True)
class VideoSettings:
    """How video.mp4 is rendered.

    Attributes:
        width, height: Frame size in [px] (even, checked by `settings`).
        fps: Frame rate in [1/s].
        quality: "preview" or "high" (render.QUALITY).
    """

    width: int = 640
    height: int = 480
    fps: int = 30
    quality: str = "preview"


def parse_size(text: str) -> tuple[int, int]:
    """'WIDTHxHEIGHT' as (width, height) [px]; UsageError naming what is allowed."""
    width, sep, height = text.lower().partition("x")
    try:
        w, h = int(width), int(height)
    except ValueError:
        raise UsageError(f"expected WIDTHxHEIGHT, e.g. 640x480; got {text!r}") from None
    lo, (w_max, h_max) = MIN_SIDE, MAX_SIZE
    if not sep or not (lo <= w <= w_max and lo <= h <= h_max):
        raise UsageError(f"expected WIDTHxHEIGHT between {lo}x{lo} and {w_max}x{h_max}; got {text!r}")
    if w % 2 or h % 2:
        raise UsageError(f"width and height must be even (H.264 video), e.g. {w + w % 2}x{h + h % 2}; got {text!r}")
    if max(w / h, h / w) > MAX_ASPECT:
        raise UsageError(f"aspect ratio must be at most 4:1 either way; got {text!r}")
    return w, h


def parse_fps(text: str) -> int:
    """A frame rate typed as text, 1 to MAX_FPS; UsageError otherwise."""
    try:
        fps = int(text)
    except ValueError:
        fps = 0
    if not 1 <= fps <= MAX_FPS:
        raise UsageError(f"expected a whole number of frames per second from 1 to {MAX_FPS}; got {text!r}")
    return fps


def _plain(value: Any) -> Any:
    """A numpy number as a Python one (its text is then what a user typed)."""
    return value.item() if hasattr(value, "item") and not isinstance(value, (str, bytes)) else value


def settings(quality: str, size: tuple[int, int] | str, fps: int | str) -> VideoSettings:
    """The API's video options checked with the CLI's rules and messages (--quality, --size, --fps)."""
    if quality not in PRESETS:
        raise UsageError(f"video quality must be one of {', '.join(PRESETS)}; got {quality!r}")
    text = size if isinstance(size, str) else "x".join(str(_plain(v)) for v in size)
    try:
        width, height = parse_size(text)
        rate = parse_fps(str(_plain(fps)))
    except UsageError as e:
        raise UsageError(f"video: {e}") from None
    return VideoSettings(width=width, height=height, fps=rate, quality=quality)


def frame_count(duration: float, fps: float) -> int:
    """Frames of a real-time video of `duration` seconds: one at t = 0, then one every 1 / fps."""
    return math.floor(duration * fps + 1e-9) + 1


def check_cost(video: VideoSettings, duration: Any) -> None:
    """Refuses, before anything runs, a video that would take longer to render than a run may take."""
    if not isinstance(duration, (int, float)) or not math.isfinite(duration):
        return
    frames = frame_count(duration, video.fps)
    fixed, per_megapixel = FRAME_SECONDS[video.quality]
    seconds = frames * (fixed + per_megapixel * video.width * video.height / 1e6)
    if seconds > MAX_SECONDS:
        hours, limit = over(seconds, MAX_SECONDS, lambda s: f"{s / 3600:.2g} h", 3600, " h")
        raise UsageError(
            f"the video would take ~{hours} to render ({frames} frames of {video.width}x{video.height} "
            f"at the {video.quality} preset); the limit is {limit}: lower --fps, --size or "
            "'duration'" + ("" if video.quality == "preview" else ", or use --quality preview")
        )
