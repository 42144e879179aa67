"""The only writer of run folders: timeseries.csv, run.json, model.xml, figures, video and report, all or nothing."""

from __future__ import annotations

import dataclasses
import errno
import json
import math
import platform
import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from hexabot_sim.errors import SimulationError
from hexabot_sim.folders import disk_full
from hexabot_sim.video import NOT_REQUESTED, VideoSettings

JSON_NAME = "run.json"
MODEL_NAME = "model.xml"
VIDEO_NAME = "video.mp4"
TRAJECTORY_NAME = "trajectory.npz"
REPORT_NAME = "report.html"


def write_csv(path: Path, columns: Mapping[str, np.ndarray]) -> None:
    """Writes columns (first "t") with a header row; %.17g makes the text exact and deterministic."""
    names = list(columns)
    table = np.column_stack([np.asarray(columns[n], dtype=float) for n in names])  # (n, ncol)
    if not np.isfinite(table).all():
        row, col = np.argwhere(~np.isfinite(table))[0]
        raise SimulationError(
            f"non-finite value in column '{names[col]}' at t = {table[row, 0]:.6g} s; nothing written"
        )
    np.savetxt(path, table, fmt="%.17g", delimiter=",", header=",".join(names), comments="")


def _json_value(value: Any) -> Any:
    if isinstance(value, (np.floating, np.integer)):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def versions() -> dict[str, str]:
    """Versions of what produced a run."""
    import mujoco

    from hexabot_sim._version import __version__

    return {
        "hexabot_sim": __version__,
        "mujoco": mujoco.__version__,
        "numpy": np.__version__,
        "scipy": _installed("scipy"),
        "matplotlib": _installed("matplotlib"),
        "python": platform.python_version(),
        "platform": platform.platform(),
    }


def _installed(name: str) -> str:
    """A package's version from its installed metadata: importing scipy and matplotlib only for it took ~0.3 s of a
    run that uses neither (a pendulum run without plots)."""
    import importlib
    import importlib.metadata

    try:
        return importlib.metadata.version(name)
    except importlib.metadata.PackageNotFoundError:  # importable without metadata (a source tree on the path)
        return str(importlib.import_module(name).__version__)


def write_json(path: Path, record: Mapping[str, Any]) -> None:
    """Writes run.json (strict JSON: non-finite numbers become null)."""

    def clean(obj: Any) -> Any:
        if isinstance(obj, Mapping):
            return {str(k): clean(v) for k, v in obj.items()}
        if isinstance(obj, (list, tuple)):
            return [clean(v) for v in obj]
        return _json_value(obj)

    path.write_text(json.dumps(clean(record), indent=2, allow_nan=False) + "\n")


def write_figures(figures: Mapping[str, Any], folder: Path, dpi: int = 120) -> list[str]:
    """Saves each matplotlib figure as <stem>.png in `folder` and returns the file names."""
    names = []
    for stem, fig in figures.items():
        name = f"{stem}.png"
        fig.savefig(folder / name, dpi=dpi)
        names.append(name)
    return names


def write_arrays(path: Path, arrays: Mapping[str, np.ndarray]) -> None:
    """Writes arrays as an .npz (np.load reads it) with fixed zip timestamps: the same run gives the same bytes."""
    import zipfile

    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        for name, array in arrays.items():
            info = zipfile.ZipInfo(f"{name}.npy", date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            with archive.open(info, "w", force_zip64=True) as stream:
                np.lib.format.write_array(stream, np.ascontiguousarray(array), allow_pickle=False)


def write_text(path: Path, text: str) -> None:
    """Writes a text file (model.xml)."""
    path.write_text(text)


@contextmanager
def package_style() -> Iterator[None]:
    """Matplotlib's default style for the block, whatever the caller's rcParams; all restored afterwards.

    The figures of a run folder look the same from the CLI, a notebook or a script with its own
    matplotlibrc; the backend is never touched.
    """
    import matplotlib.style

    with matplotlib.style.context("default"):
        yield


@dataclasses.dataclass(frozen=True)
class Written:
    """What write_run put into a run folder: file names, the run.json `video` entry, video time [s]."""

    files: list[str]
    video: dict[str, Any]
    video_seconds: float


def write_video(
    folder: Path,
    result: Any,
    settings: VideoSettings,
    backend: str,
    progress: Callable[[int, int], None] | None = None,
    name: str = VIDEO_NAME,
) -> tuple[dict[str, Any], float]:
    """Renders `name` (video.mp4) into `folder`; a failure of the GL or ffmpeg is no reason to lose the run.

    Returns:
        (run.json's `video` entry, seconds spent). The entry says why there is no video if it failed.

    Raises:
        OSError: when the disk is full (ENOSPC, EDQUOT): the run cannot be written at all.
    """
    from hexabot_sim import render

    started = time.perf_counter()
    try:
        frames = render.render_video(
            result.model,
            result.trajectory.t,
            result.trajectory.qpos,
            folder / name,
            camera=result.camera,
            width=settings.width,
            height=settings.height,
            fps=settings.fps,
            quality=settings.quality,
            markers=result.markers,
            trail=result.trail,
            overlay=result.overlay,
            progress=progress,
        )
    except (KeyboardInterrupt, MemoryError):
        raise
    except Exception as e:  # OpenGL context or encoder failure: keep CSV and plots, say why
        (folder / name).unlink(missing_ok=True)
        if isinstance(e, OSError) and e.errno in (errno.ENOSPC, errno.EDQUOT):
            raise
        if disk_full(folder):  # ffmpeg ran out of space: its error (a broken pipe) does not say so
            raise OSError(errno.ENOSPC, "No space left on device (while encoding the video)") from None
        lines = [line.strip() for line in str(e).splitlines() if line.strip()]
        reason = f"rendering failed: {type(e).__name__}: {lines[0] if lines else ''}"  # the first line says what
        return {"written": False, "reason": reason.rstrip(": ")}, time.perf_counter() - started
    problem = mp4_problem(folder / name)
    if problem is not None:  # the encoder said nothing but made no playable file: detected, not trusted
        (folder / name).unlink(missing_ok=True)
        if disk_full(folder):
            raise OSError(errno.ENOSPC, "No space left on device (while encoding the video)")
        return {"written": False, "reason": f"the video encoder failed: {problem}"}, time.perf_counter() - started
    video = {
        "written": True,
        "file": name,
        "frames": frames,
        "fps": settings.fps,
        "size": [settings.width, settings.height],
        "quality": settings.quality,
        "gl_backend": backend,
    }
    return video, time.perf_counter() - started


def mp4_problem(path: Path) -> str | None:
    """None if `path` is a complete MP4 (an 'ftyp' box first, a 'moov' box, top-level boxes that fill the file
    exactly), else what is wrong with it."""
    try:
        size = path.stat().st_size
        with open(path, "rb") as stream:
            at, kinds = 0, []
            while at < size:
                stream.seek(at)
                head = stream.read(16)
                if len(head) < 8:
                    return f"{path.name} ends inside a box header at byte {at}"
                length, kind = int.from_bytes(head[:4], "big"), head[4:8]
                if length == 1 and len(head) == 16:
                    length = int.from_bytes(head[8:16], "big")
                elif length == 0:
                    length = size - at
                if length < 8 or at + length > size:
                    return f"{path.name} is truncated or not an MP4 (a box at byte {at} does not fit)"
                kinds.append(kind)
                at += length
    except OSError as e:
        return f"{path.name} cannot be read: {e.strerror or e}"
    if not kinds or kinds[0] != b"ftyp":
        return f"{path.name} is empty or not an MP4 (no 'ftyp' box first)"
    if b"moov" not in kinds:
        return f"{path.name} is unfinished (no 'moov' box: the encoder did not close it)"
    return None


def write_run(
    folder: Path,
    scenario: Any,
    params: Any,
    result: Any,
    *,
    sim_seconds: float,
    plots: bool = True,
    video: VideoSettings | None = None,
    backend: str | None = None,
    no_video_reason: str = NOT_REQUESTED,
    video_progress: Callable[[int, int], None] | None = None,
) -> Written:
    """Writes everything of a finished run into `folder` (a staging folder from run_folder).

    The one writer of a run folder's content, for the CLI and the Python API alike: the CSV,
    model.xml, trajectory.npz, the figures, video.mp4, run.json and report.html.

    Args:
        scenario: The registry entry (scenario.Scenario): name, summary, figures().
        params: The resolved parameter object the run used.
        result: The scenario's ScenarioResult.
        sim_seconds: Wall time of the simulation [s], recorded in run.json.
        plots: Whether to write the PNG figures.
        video: Render video.mp4 with these settings (None: no video).
        backend: The working OpenGL backend (None: no video, for `no_video_reason`).
        no_video_reason: Why there is no video, when there is none.
        video_progress: Called with (frames done, frames in all) while the video renders.
    """
    from hexabot_sim import params as params_mod
    from hexabot_sim import report

    write_csv(folder / result.csv_name, result.columns)
    write_text(folder / MODEL_NAME, result.model_xml)
    files = [result.csv_name, JSON_NAME, MODEL_NAME]
    if result.trajectory is not None:  # the full recorded state: recompute anything from model.xml
        traj = result.trajectory
        arrays = {"t": traj.t, "qpos": traj.qpos, "qvel": traj.qvel}
        arrays["ctrl"] = traj.ctrl if traj.ctrl is not None else np.zeros((len(traj.t), result.model.nu))
        write_arrays(folder / TRAJECTORY_NAME, arrays)
        files.append(TRAJECTORY_NAME)
    if plots:
        with package_style():
            files += write_figures(scenario.figures(result), folder)

    if video is not None and (result.camera is None or result.trajectory is None):
        backend, no_video_reason = None, f"{scenario.name} produces no trajectory to film"
    video_record: dict[str, Any] = {"written": False, "reason": no_video_reason}
    video_seconds = 0.0
    if video is not None and backend is not None:
        video_record, video_seconds = write_video(folder, result, video, backend, video_progress)
        if video_record["written"]:
            files.append(VIDEO_NAME)
    files.append(REPORT_NAME)

    record = {
        "scenario": scenario.name,
        "description": scenario.summary,
        "params": params_mod.as_dict(params),
        "metrics": {name: m.value for name, m in result.metrics.items()},
        "units": {
            "params": params_mod.units(type(params)),
            "metrics": {name: m.unit for name, m in result.metrics.items()},
            "columns": result.column_units,
        },
        "metric_docs": {name: m.doc for name, m in result.metrics.items()},
        "files": files,
        "warnings": list(result.warnings),
        "video": video_record,
        "simulation": {
            "steps": None if result.trajectory is None else len(result.trajectory.t) - 1,
            "simulated_time": None if result.trajectory is None else float(result.trajectory.t[-1]),
            "wall_time": sim_seconds,
        },
        "versions": versions(),
    }
    write_json(folder / JSON_NAME, record)
    param_docs = {name: info.doc for name, (info, _) in params_mod.infos(type(params)).items()}
    write_text(folder / REPORT_NAME, report.html_page(record, param_docs, result.summary, folder))
    return Written(files, video_record, video_seconds)
