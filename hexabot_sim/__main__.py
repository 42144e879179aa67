"""Command line: `hexabot-sim list | run NAME | check`; the only place errors become exit codes."""

from __future__ import annotations

import argparse
import contextlib
import errno
import math
import os
import shutil
import signal
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any, NoReturn

from hexabot_sim import params as params_mod
from hexabot_sim import scenarios
from hexabot_sim.errors import (
    HOLD,
    PENDING_SIGNALS,
    PUBLISHED,
    RECEIVED_SIGNALS,
    HexabotError,
    Interrupted,
    OutputError,
    UsageError,
    stop_request,
)

PROG = "hexabot-sim"


class _Parser(argparse.ArgumentParser):
    """argparse that reports bad usage as one line and exit code 2, like every other input error."""

    def error(self, message: str) -> NoReturn:
        raise UsageError(message)


# Video frames: H.264 in yuv420p needs even sides; beyond 4:1 a frame shows a sliver of the scene.
VIDEO_MIN_SIDE, VIDEO_MAX_SIZE, VIDEO_MAX_ASPECT = 64, (3840, 2160), 4.0


def _size(text: str) -> tuple[int, int]:
    width, sep, height = text.lower().partition("x")
    try:
        w, h = int(width), int(height)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT, e.g. 640x480; got {text!r}") from None
    lo, (w_max, h_max) = VIDEO_MIN_SIDE, VIDEO_MAX_SIZE
    if not sep or not (lo <= w <= w_max and lo <= h <= h_max):
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT between {lo}x{lo} and {w_max}x{h_max}; got {text!r}")
    if w % 2 or h % 2:
        raise argparse.ArgumentTypeError(
            f"width and height must be even (H.264 video), e.g. {w + w % 2}x{h + h % 2}; got {text!r}"
        )
    if max(w / h, h / w) > VIDEO_MAX_ASPECT:
        raise argparse.ArgumentTypeError(f"aspect ratio must be at most 4:1 either way; got {text!r}")
    return w, h


def _fps(text: str) -> int:
    try:
        fps = int(text)
    except ValueError:
        fps = 0
    if not 1 <= fps <= 240:
        raise argparse.ArgumentTypeError(f"expected a whole number of frames per second from 1 to 240; got {text!r}")
    return fps


def _add_folder_options(parser: argparse.ArgumentParser, what: str) -> None:
    """--out and --force, the same for every command that writes a folder (run, sweep, compare)."""
    parser.add_argument("--out", metavar="DIR", help=what)
    parser.add_argument("--force", action="store_true", help="replace --out if it already holds files")


def build_parser() -> argparse.ArgumentParser:
    from hexabot_sim import __version__

    parser = _Parser(prog=PROG, description="Robotics-course simulations on MuJoCo: run named scenarios.")
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    parser.add_argument(
        "--debug", action="store_true", help="show the Python traceback of an internal error (or HEXABOT_SIM_DEBUG=1)"
    )
    sub = parser.add_subparsers(
        dest="command", required=True, parser_class=_Parser, metavar="{list,run,view,sweep,compare,check,kin,clean}"
    )
    sub.add_parser("list", help="scenarios and their parameters with defaults and units")
    run = sub.add_parser("run", help="run a scenario and write a run folder")
    run.add_argument("scenario", help="scenario name (see 'hexabot-sim list')")
    run.add_argument(
        "--set",
        dest="sets",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="override a parameter (repeatable)",
    )
    run.add_argument("--config", metavar="FILE", help="TOML file of 'name = value' parameter lines")
    _add_folder_options(run, "run folder (default: runs/<scenario>-<timestamp>)")
    run.add_argument("--video", action="store_true", help="also render video.mp4 (headless)")
    run.add_argument(
        "--quality", choices=("preview", "high"), default="preview", help="video preset (default: preview)"
    )
    run.add_argument("--size", type=_size, default=(640, 480), metavar="WxH", help="video size (default: 640x480)")
    run.add_argument("--fps", type=_fps, default=30, help="video frame rate (default: 30)")
    run.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    sub.add_parser("check", help="MuJoCo version, working OpenGL backend, ffmpeg")
    clean = sub.add_parser("clean", help="remove staging folders left by runs that were killed (SIGKILL, power loss)")
    clean.add_argument("folder", nargs="?", default="runs", help="folder holding run folders (default: runs)")
    clean.add_argument("--dry-run", action="store_true", help="only list what would be removed")
    kin = sub.add_parser(
        "kin",
        help="kinematics of a robot: T0n, J, singularities, IK branches",
        description="DH table and singular sets; with --q also T0n, J, det and the singular conditions that hold; "
        "with --target every IK branch and its FK residual. Units: m; revolute joints and target angles in rad "
        "(or deg with --deg). Negative values are typed as they are: --q -1,0.5,0.2. Allowed: link lengths "
        "0.001 to 10 m (the offsets elbow d, stanford d2 and d6, scara d4 may be 0); |revolute q| and |angle| "
        "<= 1000 rad; |prismatic q| <= 100 m; |x|, |y|, |z| of a target <= 1000 m. Warnings (stderr, and "
        "'warnings' in --json): q outside a joint range, IK branches dropped by the joint ranges.",
    )
    import re  # kin only: `--q -1,0.5,0.2` is a value, not an option (argparse accepts only a lone -1 or -.5)

    kin._negative_number_matcher = re.compile(r"^-(?:\d|\.\d|inf|nan)", re.IGNORECASE)  # kinreport.NUMBER_LIST
    kin.add_argument("robot", help="rrp, elbow, stanford, scara or leg")
    kin.add_argument(
        "--q", metavar="Q1,Q2,...", help="joint values: rad (deg with --deg) for revolute joints, m for prismatic"
    )
    kin.add_argument(
        "--target",
        metavar="X,Y,Z",
        help="tool position [m] for IK (scara: x,y,z[,yaw]; stanford: x,y,z,roll,pitch,yaw with R = Rz Ry Rx)",
    )
    kin.add_argument("--set", dest="sets", action="append", default=[], metavar="NAME=VALUE", help="link length [m]")
    kin.add_argument(
        "--deg",
        action="store_true",
        help="revolute joint values and target angles in degrees, in --q/--target and in the output (DH angles, "
        "joint ranges, IK solutions); T0n stays in m and J per rad",
    )
    kin.add_argument("--json", action="store_true", help="machine-readable output (with a 'warnings' list)")
    kin.add_argument(
        "--symbolic",
        action="store_true",
        help="also derive T0n and J with sympy, printed with c1/s23 abbreviations and as LaTeX "
        "(needs sympy, the extra 'symbolic': pip install \".[symbolic]\" in the hexabot-sim folder)",
    )
    view = sub.add_parser(
        "view",
        help="MuJoCo's interactive viewer: a scenario driven live, or a run folder replayed",
        description="NAME: the scenario's model driven live by its controller at real time. RUN_DIR: the run "
        "folder's exact model.xml replaying its trajectory.npz. Keys: space play/pause, - and = half/double "
        "speed, Left/Right step 1/30 s, Down/Up jump 1 s, Home/End first/last state (live: Right one frame, "
        "Home restart); the mouse turns, moves and zooms the view. Needs a display and the 'viewer' extra "
        '(glfw): pip install "hexabot-sim[viewer]".',
    )
    view.add_argument("target", metavar="NAME|RUN_DIR", help="scenario name, or a run folder written by 'run'")
    view.add_argument("--set", dest="sets", action="append", default=[], metavar="NAME=VALUE", help="parameter")
    view.add_argument("--config", metavar="FILE", help="TOML file of 'name = value' parameter lines")
    view.add_argument("--speed", type=_view_speed, default=1.0, help="playback speed, times real time (default 1)")
    view.add_argument("--paused", action="store_true", help="start paused at t = 0 (space plays)")
    view.add_argument(
        "--quit-after", type=_view_seconds, metavar="SECONDS", help="close the window after this wall time (scripts)"
    )
    _add_study_parsers(sub)
    return parser


class ProgressBar:
    """Progress on stderr: a redrawn bar on a terminal, else a plain line every PLAIN_EVERY percent and at least
    every PLAIN_SECONDS while it is called (logs: a run allowed to take an hour was silent for 15 min between
    quarters)."""

    PLAIN_EVERY: int = 25  # [%]
    PLAIN_SECONDS: float = 60.0  # [s]

    def __init__(self, label: str, stream: Any = None) -> None:
        self.label = label
        self.stream = stream if stream is not None else sys.stderr
        self.tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self._last = -1
        self._last_line = time.monotonic()

    def __call__(self, done: int, total: int) -> None:
        percent = 100 * done // max(total, 1)
        if not self.tty:
            step = percent // self.PLAIN_EVERY * self.PLAIN_EVERY
            now = time.monotonic()
            if step > self._last or now - self._last_line >= self.PLAIN_SECONDS:
                self._last, self._last_line = max(step, self._last), now
                self._write(f"{self.label}: {percent}% ({done}/{total})\n")
            return
        if percent == self._last and done != total:
            return
        self._last = percent
        filled = percent * 30 // 100
        self._write(f"\r{self.label} [{'#' * filled}{'.' * (30 - filled)}] {percent:3d}% ({done}/{total})")
        if done >= total:
            self._write("\n")

    def _write(self, text: str) -> None:
        try:
            self.stream.write(text)
            self.stream.flush()
        except (OSError, ValueError):  # progress is a courtesy: a broken stderr must not stop the run
            pass


def cmd_list() -> int:
    for scenario in scenarios.SCENARIOS.values():
        print(f"{scenario.name}\n  {scenario.summary}")
        rows = []
        for name, (info, default) in params_mod.infos(scenario.params_type).items():
            value = scenario.defaults.get(name, default)
            text = ",".join(f"{v:.6g}" for v in value) if isinstance(value, tuple) else str(value)
            unit = f"[{info.unit}]" if info.unit else ""
            allowed = (
                params_mod.describe_range(info)
                if hasattr(params_mod, "describe_range")
                else (f"one of: {', '.join(info.choices)}" if info.choices else "")
            )
            rows.append((name, text, unit, f"{info.doc}{'; ' + allowed if allowed else ''}"))
        widths = [min(max(len(row[k]) for row in rows), cap) for k, cap in ((0, 30), (1, 24), (2, 14))]
        for name, text, unit, doc in rows:
            print(f"    {name:<{widths[0]}} = {text:<{widths[1]}} {unit:<{widths[2]}} {doc}")
        print()
    return 0


def cmd_check() -> int:
    import hexabot_sim
    from hexabot_sim import gl

    print(f"python        {sys.version.split()[0]}")
    try:
        import mujoco
    except ImportError as e:
        print(f"mujoco        NOT importable: {e}")
        return 1
    print(f"mujoco        {mujoco.__version__} ({mujoco.__file__})")
    working = []
    for backend in ("egl", "osmesa", "glfw"):
        reason = gl.probe(backend)
        working += [backend] if reason is None else []
        print(f"gl {backend:<10} {'works' if reason is None else 'fails: ' + reason.split(': ', 1)[-1]}")
    ffmpeg_problem = gl.ffmpeg_problem()
    if ffmpeg_problem is None:
        import imageio_ffmpeg

        print(f"ffmpeg        {imageio_ffmpeg.get_ffmpeg_exe()}")
    else:
        print(f"ffmpeg        NOT working: {ffmpeg_problem}")
    video = "available" if working and ffmpeg_problem is None else "unavailable (CSV and plots still work)"
    user_gl = hexabot_sim.USER_MUJOCO_GL
    print(f"video         {video}; MUJOCO_GL {'not set' if user_gl is None else '= ' + repr(user_gl)}")
    return 0


def cmd_kin(args: argparse.Namespace) -> int:
    import json

    from hexabot_sim import kinreport

    sets = params_mod.parse_assignments(args.sets)
    report = kinreport.report(args.robot, sets, args.q, args.target, degrees=args.deg, symbolic=args.symbolic)
    for warning in report["warnings"]:
        _eprint(f"{PROG}: warning: {warning}")
    print(json.dumps(report, indent=2, allow_nan=False) if args.json else kinreport.text(report))
    return 0


def _format(value: Any, unit: str) -> str:
    if value is None:
        return "n/a"
    if isinstance(value, float):
        return f"{value:.8g}{' ' + unit if unit and unit != '1' else ''}"
    return f"{value}{' ' + unit if unit and unit != '1' else ''}"


def _video_settings(args: argparse.Namespace) -> Any:
    """The --video options as output.VideoSettings."""
    from hexabot_sim import output

    width, height = args.size
    return output.VideoSettings(width=width, height=height, fps=args.fps, quality=args.quality)


# Seconds to render and encode one video frame here: a fixed part plus a part per megapixel (software
# OpenGL), per quality preset. Measured: preview 140 frames/s at 640x480 over 301 frames (scripts/bench.py),
# 27 at 1920x1080 and 7.9 at 3840x2160; high 20, 7.4 and 2.2.
VIDEO_FRAME_SECONDS: dict[str, tuple[float, float]] = {"preview": (0.005, 0.013), "high": (0.035, 0.050)}


def _check_video_cost(args: argparse.Namespace, p: Any) -> None:
    """Refuses, before anything runs, a --video that would take longer to render than a run may take."""
    duration = getattr(p, "duration", None)
    if not isinstance(duration, (int, float)) or not math.isfinite(duration):
        return
    width, height = args.size
    from hexabot_sim import render  # after gl.choose(): it imports MuJoCo

    frames = render.frame_count(duration, args.fps)
    fixed, per_megapixel = VIDEO_FRAME_SECONDS[args.quality]
    seconds = frames * (fixed + per_megapixel * width * height / 1e6)
    if seconds > params_mod.MAX_SECONDS:
        hours, limit = params_mod.over(seconds, params_mod.MAX_SECONDS, lambda s: f"{s / 3600:.2g} h", 3600, " h")
        raise UsageError(
            f"the video would take ~{hours} to render ({frames} frames of {width}x{height} at the "
            f"{args.quality} preset); the limit is {limit}: lower --fps, --size or "
            "'duration'" + ("" if args.quality == "preview" else ", or use --quality preview")
        )


def cmd_run(args: argparse.Namespace) -> int:
    scenario = scenarios.get(args.scenario)
    sets = params_mod.parse_assignments(args.sets)
    config = params_mod.read_config(args.config) if args.config is not None else {}

    from hexabot_sim import gl, output

    # The OpenGL backend must be chosen before MuJoCo is imported (scenario modules import it).
    backend, no_video_reason = None, "not requested (add --video)"
    if args.video:
        backend, no_video_reason, notice = gl.choose()
        if notice:
            _eprint(f"{PROG}: {notice}")
        if backend is not None:
            ffmpeg_problem = gl.ffmpeg_problem()
            if ffmpeg_problem is not None:
                backend, no_video_reason = None, ffmpeg_problem

    p: Any = params_mod.resolve(scenario.params_type, scenario.defaults, config, sets)
    if args.video:
        _check_video_cost(args, p)
    if args.out is not None:
        output.check_not_input(args.out, [args.config] if args.config is not None else [])
        output.check_out(args.out, force=args.force)  # before the simulation, not after it
    with _mujoco_warnings_to_stderr():
        return _execute(args, scenario, p, backend, no_video_reason)


def _mujoco_warnings_to_stderr() -> contextlib.AbstractContextManager[None]:
    """MuJoCo's warnings as one line each on stderr (never appended to MUJOCO_LOG.TXT in the user's folder)."""
    from hexabot_sim.simulate import mujoco_warnings

    return mujoco_warnings(lambda message: _eprint(f"{PROG}: MuJoCo warning: {message}"))


def _execute(args: argparse.Namespace, scenario: Any, p: Any, backend: str | None, no_video_reason: str) -> int:
    """Runs the scenario into its run folder, then prints the summary."""
    from hexabot_sim import output

    out = args.out
    started = time.perf_counter()
    with output.run_folder(out, scenario.name, force=args.force) as run:
        result = scenario.runner(scenario.name, p, progress=ProgressBar(scenario.name))
        sim_seconds = time.perf_counter() - started
        if not args.no_plots:
            from hexabot_sim import plots

            plots.use_agg()  # the CLI draws off-screen; importing the package never picks a backend
        written = output.write_run(
            run.path,
            scenario,
            p,
            result,
            sim_seconds=sim_seconds,
            plots=not args.no_plots,
            video=_video_settings(args) if args.video else None,
            backend=backend,
            no_video_reason=no_video_reason,
            video_progress=ProgressBar("video"),
        )
        files, video, video_seconds = written.files, written.video, written.video_seconds
        no_video_reason = video.get("reason", no_video_reason)
    assert run.final is not None
    total_seconds = time.perf_counter() - started

    timing = f"simulated in {sim_seconds:.2f} s" if result.trajectory is not None else f"ran in {sim_seconds:.2f} s"
    if result.trajectory is not None:
        timing = f"{result.trajectory.t[-1]:.6g} s {timing}"
    if video_seconds:
        timing += f", video in {video_seconds:.2f} s"
    timing += f", {total_seconds:.2f} s in all"
    if args.video and not video["written"]:
        _eprint(f"{PROG}: no video: {no_video_reason}")
    _COMPLETED[:] = [f"the run folder {output.display_path(run.final)} is complete"]
    print(f"{scenario.name}: {timing} -> {output.display_path(run.final)}")
    for name in result.summary:
        metric = result.metrics[name]
        print(f"  {name:<26} {_format(metric.value, metric.unit)}")
    print(f"  files: {', '.join(files)}")
    return 0


def cmd_clean(args: argparse.Namespace) -> int:
    from hexabot_sim import output

    if not args.folder:
        raise UsageError("clean needs a folder name (default: runs); got an empty one")
    root = Path(args.folder)
    if not root.is_dir():
        raise UsageError(f"{output.display_path(root)!r} is not a folder")
    stale = output.stale_staging(root) + output.stale_cells()
    removed = 0
    for path in stale:
        if args.dry_run:
            print(f"would remove {output.display_path(path)}")
            continue
        try:
            shutil.rmtree(path)
        except OSError as e:
            raise OutputError(f"could not remove {output.display_path(path)!r}: {e.strerror or e}") from None
        print(f"removed {output.display_path(path)}")
        removed += 1
        _DONE_SO_FAR[:] = [f"{removed} stale folder{'s' if removed > 1 else ''} removed before it, listed above"]
    if not stale:
        cells = tempfile.gettempdir()
        print(f"no staging folders left by interrupted runs in {args.folder} (nor sweep cells in {cells})")
    return 0


def _view_speed(text: str) -> float:
    from hexabot_sim.viewer import MAX_SPEED, MIN_SPEED

    try:
        speed = float(text)
    except ValueError:
        speed = float("nan")
    if not MIN_SPEED <= speed <= MAX_SPEED:
        raise argparse.ArgumentTypeError(f"expected a speed from {MIN_SPEED:g} to {MAX_SPEED:g}; got {text!r}")
    return speed


def _view_seconds(text: str) -> float:
    try:
        seconds = float(text)
    except ValueError:
        seconds = float("nan")
    if not 0 < seconds <= 86400:
        raise argparse.ArgumentTypeError(f"expected seconds, more than 0 and at most 86400; got {text!r}")
    return seconds


def cmd_view(args: argparse.Namespace) -> int:
    """`view NAME` (live) or `view RUN_DIR` (replay) in MuJoCo's viewer: a window, so GLFW and a display."""
    from hexabot_sim import gl, viewer

    folder = Path(args.target)
    replaying = folder.is_dir() or os.sep in args.target or args.target in (".", "..")
    if replaying and not folder.is_dir():
        shown = os.fsencode(args.target).decode("utf-8", "backslashreplace")  # bytes that are not UTF-8 as \xNN
        raise UsageError(f"run folder {shown!r} does not exist")
    if replaying and (args.sets or args.config):
        raise UsageError("--set and --config choose a scenario's parameters; a run folder replays its own")
    if gl.loaded_backend() is None:
        os.environ["MUJOCO_GL"] = "glfw"  # MuJoCo binds its OpenGL at import: the window's, not EGL's
    # Bad input (the folder, or every parameter as a run would check it) is reported before the display is looked at.
    recording = viewer.load_recording(folder) if replaying else None
    make = None
    if not replaying:
        scenario = scenarios.get(args.target)
        sets = params_mod.parse_assignments(args.sets)
        config = params_mod.read_config(args.config) if args.config is not None else {}
        p: Any = params_mod.resolve(scenario.params_type, scenario.defaults, config, sets)
        make = viewer.live_maker(scenario.name, p)  # a grid scenario is refused before the window opens
    problem = viewer.display_problem()
    if problem is not None:
        raise UsageError(f"cannot open the viewer: {problem}")
    options = {"speed": args.speed, "paused": args.paused, "quit_after": args.quit_after}

    def announce(text: str) -> None:
        _eprint(f"{PROG}: {text}")

    with _mujoco_warnings_to_stderr():
        if recording is not None:
            summary = viewer.replay(recording, announce=announce, **options)
        else:
            assert make is not None
            summary = viewer.live(make, scenario.name, announce=announce, **options)
    print(summary)
    return 0


def _workers(text: str) -> int:
    from hexabot_sim import sweep

    try:
        n = int(text)
    except ValueError:
        n = 0
    if not 1 <= n <= sweep.MAX_WORKERS:
        raise argparse.ArgumentTypeError(f"expected a whole number of worker processes from 1 to {sweep.MAX_WORKERS}")
    return n


def _add_study_parsers(sub: Any) -> None:
    """The `sweep` and `compare` sub-commands (studies over many runs)."""
    sweep = sub.add_parser(
        "sweep",
        help="run a scenario over a grid of parameter values (all cores, or a Dask cluster) into a sweep folder",
        description="Full-factorial grid: each --grid adds an axis (the first varies slowest). Writes sweep.csv "
        "(one row per cell: swept parameters, every scalar metric, 'error'), sweep.json (grid, fixed parameters, "
        "units, versions, timing) and a figure per metric (one axis: metric vs the parameter; two: a heatmap).",
    )
    sweep.add_argument("scenario", help="scenario name (see 'hexabot-sim list')")
    sweep.add_argument(
        "--grid",
        action="append",
        default=[],
        metavar="PARAM=VALUES",
        help="swept parameter: V1,V2,... or START:STOP:N (linear) or log:START:STOP:N (repeatable)",
    )
    sweep.add_argument("--set", dest="sets", action="append", default=[], metavar="NAME=VALUE", help="fixed value")
    sweep.add_argument("--config", metavar="FILE", help="TOML file of 'name = value' parameter lines (fixed)")
    _add_folder_options(sweep, "sweep folder (default: runs/sweep-<scenario>-<timestamp>)")
    sweep.add_argument("--workers", type=_workers, help="local worker processes (default: all cores)")
    sweep.add_argument(
        "--scheduler", metavar="ADDRESS", help="Dask scheduler, e.g. tcp://10.0.0.5:8786 (extra 'cluster')"
    )
    sweep.add_argument("--keep-runs", action="store_true", help="also write every cell's run folder under cells/")
    sweep.add_argument("--no-plots", action="store_true", help="skip the PNG figures (also in the kept runs)")
    compare = sub.add_parser(
        "compare",
        help="parameters and metrics of run folders side by side, their shared columns overlaid",
        description="Prints the parameters (differing first) and metrics of two or more run folders with the "
        "differences to the first, and writes them (compare.csv, compare.json) with overlay figures of the "
        "columns their CSVs share into a new compare folder.",
    )
    compare.add_argument("runs", nargs="+", metavar="RUN_DIR", help="run folders written by 'run' (two or more)")
    _add_folder_options(compare, "compare folder (default: runs/compare-<timestamp>)")
    compare.add_argument("--no-plots", action="store_true", help="skip the overlay figures")


def _duration(seconds: float) -> str:
    if seconds < 60:
        return f"{seconds:.0f} s"
    if seconds < 3600:
        return f"{seconds // 60:.0f} min {seconds % 60:02.0f} s"
    return f"{seconds // 3600:.0f} h {seconds % 3600 // 60:02.0f} min"


class SweepProgress(ProgressBar):
    """Cells done / total with the elapsed time and an ETA; in logs a plain line every 10 % or PLAIN_SECONDS."""

    PLAIN_EVERY: int = 10  # [%]

    def __init__(self, label: str, stream: Any = None) -> None:
        super().__init__(label, stream)
        self._start = self._last_line

    def __call__(self, done: int, total: int) -> None:
        now = time.monotonic()
        elapsed = now - self._start
        percent = 100 * done // max(total, 1)
        eta = f", ETA {_duration(elapsed / done * (total - done))}" if 0 < done < total else ""
        text = f"{done}/{total} cells, {_duration(elapsed)}{eta}"
        if not self.tty:
            step = percent // self.PLAIN_EVERY * self.PLAIN_EVERY
            if step > self._last or now - self._last_line >= self.PLAIN_SECONDS or done == total != 0 > self._last:
                self._last, self._last_line = max(step, self._last), now
                self._write(f"{self.label}: {percent}% ({text})\n")
            return
        filled = percent * 30 // 100
        self._write(f"\r{self.label} [{'#' * filled}{'.' * (30 - filled)}] {percent:3d}% ({text})\x1b[K")
        if done >= total:
            self._write("\n")


def cmd_sweep(args: argparse.Namespace) -> int:
    from hexabot_sim import output, sweep

    sets = params_mod.parse_assignments(args.sets)
    config = params_mod.read_config(args.config) if args.config is not None else {}
    if args.scheduler is not None and args.workers is not None:
        raise UsageError("--workers is for the local pool; with --scheduler the cluster's workers run the cells")
    name = f"sweep-{scenarios.get(args.scenario).name}"
    checking = SweepProgress(f"{name}: checking")  # speaks only if checking the cells takes seconds
    plan = sweep.plan(args.scenario, args.grid, config, sets, checking)  # every cell validated: nothing runs before
    if args.out is not None:
        output.check_not_input(args.out, [args.config] if args.config is not None else [])
        output.check_out(args.out, force=args.force)
    if args.scheduler is not None:
        pool: Any = sweep.dask_executor(args.scheduler)  # connects now: an unreachable scheduler writes nothing
    else:
        workers = min(args.workers or sweep.workers_default(), len(plan.cells))
        sweep.check_cost(plan, workers, f"{workers} local process{'es' if workers > 1 else ''}")
        pool = contextlib.nullcontext((sweep.local_executor(workers), workers))
    started = time.perf_counter()
    with pool as (executor, workers), output.run_folder(args.out, name, force=args.force) as run:
        threads = f"{workers} worker thread{'s' if workers != 1 else ''}"
        where = f"Dask scheduler {args.scheduler} ({threads})" if args.scheduler else None
        if where:  # the cluster's size is known once connected (the staging folder goes with the refusal)
            sweep.check_cost(plan, workers, where)
        where = where or f"{workers} local process{'es' if workers > 1 else ''}"
        kept = 0

        def keep(result: sweep.CellResult) -> None:
            nonlocal kept
            if result.files:
                folder = run.path / sweep.cell_folder(result.index, len(plan.cells))
                folder.mkdir(parents=True)
                for relative, content in result.files.items():
                    (folder / relative).parent.mkdir(parents=True, exist_ok=True)
                    (folder / relative).write_bytes(content)
                kept += 1

        jobs = sweep.jobs(plan, args.keep_runs, plots=not args.no_plots)
        results = sweep.run_cells(executor, jobs, SweepProgress(name), keep)
        wall = time.perf_counter() - started
        table = sweep.table(plan, results)
        sweep.write_csv(run.path / sweep.CSV_NAME, table)
        files = [sweep.CSV_NAME, sweep.JSON_NAME]
        if not args.no_plots:
            from hexabot_sim import plots

            plots.use_agg()
            with output.package_style():
                files += output.write_figures(sweep.figures(plan, table), run.path)
        executor_record = {"kind": "dask" if args.scheduler else "local processes", "workers": workers}
        executor_record |= {"scheduler": args.scheduler} if args.scheduler else {}
        record = sweep.record(plan, table, results, executor_record, wall)
        record |= {"files": files, "kept_runs": f"{sweep.CELLS_DIR}/ ({kept} folders)" if args.keep_runs else None}
        record["versions"] = output.versions()
        record["files"] = [*files, "report.html"]
        output.write_json(run.path / sweep.JSON_NAME, record)
        from hexabot_sim import params as params_info
        from hexabot_sim import report

        docs = {name: info.doc for name, (info, _) in params_info.infos(type(plan.base)).items()}
        (run.path / "report.html").write_text(report.sweep_page(record, docs, run.path))
    assert run.final is not None
    total = time.perf_counter() - started
    failed = [r for r in results if r.error]
    shape = " x ".join(f"{len(a.values)} {a.name}" for a in plan.axes)
    _COMPLETED[:] = [f"the sweep folder {output.display_path(run.final)} is complete"]
    if failed:
        first = failed[0]
        values = plan.cell_values(first.index)
        label = ", ".join(f"{n} = {sweep._text(v)}" for n, v in zip(table.swept, values, strict=True))
        print(
            f"{PROG}: warning: {len(failed)} of {len(results)} cells failed (rows with an 'error' in "
            f"{sweep.CSV_NAME}); the first, {label}: {first.error}",
            file=sys.stderr,
        )
    cell_time = sum(r.seconds for r in results)
    print(
        f"{name}: {len(results)} cells ({shape}) on {where} in {total:.2f} s "
        f"(cells {cell_time:.2f} s in all) -> {output.display_path(run.final)}"
    )
    print(f"  cells ok: {len(results) - len(failed)}, failed: {len(failed)}")
    figures = [f for f in files if f.endswith(".png")]
    print(f"  files: {sweep.CSV_NAME}, {sweep.JSON_NAME}, {len(figures)} figures" + (
        f", {sweep.CELLS_DIR}/ ({kept} run folders)" if args.keep_runs else ""))  # fmt: skip
    return 0


def cmd_compare(args: argparse.Namespace) -> int:
    from hexabot_sim import compare, output

    runs = compare.load_all(args.runs)  # refuses anything that is not a run folder, before writing
    if args.out is not None:
        output.check_not_input(args.out, args.runs)
        output.check_out(args.out, force=args.force)
    table = compare.rows(runs)
    shared = compare.shared_columns([compare.header(r) for r in runs])
    with output.run_folder(args.out, "compare", force=args.force) as run:
        compare.write_csv(run.path / compare.CSV_NAME, runs, table)
        files = [compare.CSV_NAME, compare.JSON_NAME]
        if not args.no_plots:
            from hexabot_sim import plots

            plots.use_agg()
            with output.package_style():
                files += output.write_figures(compare.figures(runs), run.path)
        output.write_json(run.path / compare.JSON_NAME, compare.record(runs, table, shared, files))
    assert run.final is not None
    _COMPLETED[:] = [f"the compare folder {output.display_path(run.final)} is complete"]
    print(compare.text(runs, table), end="")
    overlaid = f"{len(shared) - 1} shared columns overlaid" if len(shared) > 1 else "no shared columns to overlay"
    print(f"compare: {len(runs)} runs, {overlaid} -> {output.display_path(run.final)}")
    print(f"  files: {', '.join(files)}")
    return 0


# What was completed before standard output failed, for the error message (e.g. the run folder).
_COMPLETED: list[str] = []
# What a command that is no run had already done when it was stopped (clean: the folders it removed).
_DONE_SO_FAR: list[str] = []


class _StdoutError(Exception):
    """Standard output could not be written (closed, full, I/O error)."""

    def __init__(self, error: OSError) -> None:
        super().__init__(error)
        self.error = error


class _GuardedStdout:
    """Wraps sys.stdout so a failing write is told apart from every other OSError (a closed pipe stays quiet)."""

    def __init__(self, stream: Any) -> None:
        self._stream = stream

    def write(self, text: str) -> int:
        try:
            return self._stream.write(text)
        except BrokenPipeError:
            raise
        except OSError as e:
            raise _StdoutError(e) from None

    def flush(self) -> None:
        try:
            self._stream.flush()
        except BrokenPipeError:
            raise
        except OSError as e:
            raise _StdoutError(e) from None

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)


class _ClosedStdout:
    """Standard output when the process was started with it closed: every write fails with EBADF."""

    def write(self, text: str) -> int:
        raise OSError(errno.EBADF, "standard output is closed")

    def flush(self) -> None:
        pass

    def isatty(self) -> bool:
        return False


def _debug_requested(argv: Sequence[str]) -> bool:
    return "--debug" in argv or os.environ.get("HEXABOT_SIM_DEBUG", "") not in ("", "0")


def main(argv: Sequence[str] | None = None) -> int:
    """Runs the CLI; returns the exit code (0 ok, 1 simulation or output failed, 2 bad input, 128+N signal N)."""
    if argv is not None:  # called from Python (tests, scripts): no stop request carries over from before
        RECEIVED_SIGNALS.clear()
        PENDING_SIGNALS.clear()
        PUBLISHED[0] = False
    argv = list(sys.argv[1:] if argv is None else argv)
    stdout, sys.stdout = sys.stdout, _GuardedStdout(sys.stdout)
    _COMPLETED.clear()
    _DONE_SO_FAR.clear()
    try:
        code = _main(argv)
        sys.stdout.flush()
        return code
    except _StdoutError as e:
        done = f" ({_COMPLETED[0]})" if _COMPLETED else ""
        _eprint(f"{PROG}: error: cannot write to standard output: {e.error.strerror or e.error}{done}")
        return 1
    finally:
        sys.stdout = stdout


def _main(argv: list[str]) -> int:
    try:
        # --debug is honoured wherever it is typed (before or after the sub-command).
        args = build_parser().parse_args([a for a in argv if a != "--debug"])
        if args.command == "view":  # draws in a window: GLFW, chosen inside cmd_view
            return cmd_view(args)
        if not (args.command == "run" and args.video):
            from hexabot_sim import gl

            gl.disable_if_unused()  # nothing is drawn: a broken MUJOCO_GL must not matter
        if args.command == "list":
            return cmd_list()
        if args.command == "check":
            return cmd_check()
        if args.command == "kin":
            return cmd_kin(args)
        if args.command == "clean":
            return cmd_clean(args)
        if args.command in ("sweep", "compare"):
            return cmd_sweep(args) if args.command == "sweep" else cmd_compare(args)
        return cmd_run(args)
    except HexabotError as e:
        _eprint(f"{PROG}: error: {e}")
        return e.exit_code
    except (_StdoutError, BrokenPipeError):
        raise
    except KeyboardInterrupt as e:
        return _interrupted(e)
    except SystemExit as e:  # argparse's --help / --version
        return e.code if isinstance(e.code, int) else 0
    except (Exception, RecursionError) as e:
        cause = _interruption_in(e)
        if cause is None and RECEIVED_SIGNALS:  # a library swallowed the stop request and failed after it
            cause = stop_request(RECEIVED_SIGNALS[-1])
        if cause is not None:  # e.g. Ctrl-C while a C extension was being imported (ImportError from it)
            return _interrupted(cause)
        if _debug_requested(argv):
            raise
        text = " ".join(str(e).split())[:300]
        _eprint(
            f"{PROG}: internal error: {type(e).__name__}{': ' + text if text else ''} -- this is a bug in "
            f"{PROG}, please report it with the output of the same command plus --debug"
        )
        return 1


def _eprint(text: str) -> None:
    """One line on stderr; a closed or full stderr must not change the exit code (nothing else can be told)."""
    try:
        print(text, file=sys.stderr, flush=True)
    except UnicodeEncodeError:  # e.g. a path in a non-UTF-8 locale
        with contextlib.suppress(OSError, ValueError):
            print(text.encode("ascii", "backslashreplace").decode(), file=sys.stderr, flush=True)
    except (OSError, ValueError):
        pass


def _interruption_in(error: BaseException) -> KeyboardInterrupt | None:
    """The Ctrl-C or signal behind an exception (a C extension may wrap it in its own error), if any."""
    seen = set()
    while error is not None and id(error) not in seen:
        seen.add(id(error))
        if isinstance(error, KeyboardInterrupt):
            return error
        error = error.__cause__ or error.__context__
    return None


def _interrupted(error: KeyboardInterrupt) -> int:
    """The one line and exit code of a run stopped by Ctrl-C (130) or SIGTERM/SIGHUP (128 + N)."""
    what = _DONE_SO_FAR[0] if _DONE_SO_FAR else "nothing written"
    if isinstance(error, Interrupted):
        _eprint(f"{PROG}: stopped by {signal.Signals(error.signum).name}; {what}")
        return 128 + error.signum
    _eprint(f"{PROG}: interrupted; {what}")
    return 130


def _raise_interrupted(signum: int, frame: Any) -> None:
    """Ctrl-C, SIGTERM and SIGHUP stop the run; while a publish or clean-up is held, only after it."""
    RECEIVED_SIGNALS.append(signum)
    if HOLD[0] > 0 or PUBLISHED[0]:  # held, or too late: the results are published
        PENDING_SIGNALS.append(signum)
        return
    raise stop_request(signum)


def _ensure_std_streams() -> None:
    """Opens /dev/null on a closed stdin/stdout/stderr, so no file we create takes their numbers."""
    for fd in (0, 1, 2):
        try:
            os.fstat(fd)
        except OSError:
            os.open(os.devnull, os.O_RDWR)  # takes the lowest free number: this one
    if sys.stdout is None:  # started with stdout closed: say so at the first write
        sys.stdout = _ClosedStdout()
    if sys.stderr is None:
        sys.stderr = open(os.devnull, "w")


def console() -> NoReturn:
    """Entry point of the `hexabot-sim` console script."""
    _ensure_std_streams()
    os.environ["MPLBACKEND"] = "Agg"  # the command line draws off-screen, whatever the environment says
    from hexabot_sim._entry import quiet_interruptions

    quiet_interruptions()
    # SIGTERM and SIGHUP stop a run exactly like Ctrl-C: clean up, exit 128 + N.
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        if signal.getsignal(sig) is not signal.SIG_IGN:  # e.g. Ctrl-C stays ignored in a background job
            signal.signal(sig, _raise_interrupted)
    try:
        code = main()
        sys.stdout.flush()
    except BrokenPipeError:  # e.g. `hexabot-sim list | head`: the reader left; not an error of ours
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        code = 0
    except OSError as e:  # stdout full at the final flush
        _eprint(f"{PROG}: error: cannot write to standard output: {e.strerror or e}")
        code = 1
    # The outcome is decided: a stop request now must not kill the exit (Python's shutdown puts the default
    # handlers back, which would end a published run with 128 + N and no word).
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, signal.SIG_IGN)
    if PUBLISHED[0] and PENDING_SIGNALS:
        name = signal.Signals(PENDING_SIGNALS[-1]).name
        _eprint(f"{PROG}: {name} came after the results were published; they are complete")
    sys.exit(code)


if __name__ == "__main__":
    console()
