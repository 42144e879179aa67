"""The command line's arguments: one parser, every value checked where it is typed (one line, exit 2)."""

from __future__ import annotations

import argparse
from typing import Any, NoReturn

from hexabot_sim import video
from hexabot_sim.cli.common import PROG
from hexabot_sim.errors import UsageError


class _Once(argparse.Action):
    """A value option's action: given twice it is an error, as a repeated --set NAME is (argparse keeps the last
    without a word: `run --out a --out b` wrote to b, `kin --q 0,0,0 --q 1,1,1` showed the second)."""

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace, values: Any,
                 option_string: str | None = None) -> None:  # fmt: skip
        given = namespace.__dict__.setdefault("_given_once", set())
        if self.dest in given:
            parser.error(f"argument {option_string}: given more than once; give it once")
        given.add(self.dest)
        setattr(namespace, self.dest, values)


class _Parser(argparse.ArgumentParser):
    """argparse that reports bad usage as one line and exit code 2, like every other input error; a value option
    (one without an action of its own) may be given once."""

    def error(self, message: str) -> NoReturn:
        raise UsageError(message)

    def add_argument(self, *args: Any, **kwargs: Any) -> argparse.Action:
        if args and str(args[0]).startswith("-") and "action" not in kwargs:
            kwargs["action"] = _Once
        return super().add_argument(*args, **kwargs)


def _size(text: str) -> tuple[int, int]:
    try:
        return video.parse_size(text)
    except UsageError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def _fps(text: str) -> int:
    try:
        return video.parse_fps(text)
    except UsageError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def _add_folder_options(parser: argparse.ArgumentParser, what: str) -> None:
    """--out and --force, the same for every command that writes a folder (run, sweep, compare)."""
    parser.add_argument("--out", metavar="DIR", help=what)
    parser.add_argument("--force", action="store_true", help="replace --out if it already holds files")


def build_parser() -> argparse.ArgumentParser:
    from hexabot_sim._version import __version__

    parser = _Parser(prog=PROG, description="Robotics-course simulations on MuJoCo: run named scenarios.")
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    parser.add_argument(
        "--debug", action="store_true", help="show the Python traceback of an internal error (or HEXABOT_SIM_DEBUG=1)"
    )
    sub = parser.add_subparsers(
        dest="command",
        required=True,
        parser_class=_Parser,
        metavar="{list,run,view,sweep,compare,check,kin,export,clean}",
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
    run.add_argument("--quality", choices=("preview", "high"), default=None, help="video preset (default: preview)")
    # Their defaults are applied by cmd_run (None: not given; given without --video they are warned of).
    run.add_argument("--size", type=_size, default=None, metavar="WxH", help="video size (default: 640x480)")
    run.add_argument("--fps", type=_fps, default=None, help="video frame rate (default: 30)")
    run.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    sub.add_parser("check", help="MuJoCo version, working OpenGL backend, ffmpeg")
    clean = sub.add_parser("clean", help="remove staging folders left by runs that were killed (SIGKILL, power loss)")
    clean.add_argument("folder", nargs="?", default="runs", help="folder holding run folders (default: runs)")
    clean.add_argument("--dry-run", action="store_true", help="only list what would be removed")
    kin = sub.add_parser(
        "kin",
        help="kinematics of a robot or a robot file: T0n, J, singularities, IK",
        description="DH table and singular sets; with --q also T0n, J, det and the singular conditions that hold; "
        "with --target every IK branch and its FK residual (a robot file: numeric IK from many seeds, x,y,z for "
        "fewer than 6 joints, x,y,z,roll,pitch,yaw for 6 or more; sigma_min reported). Units: m; revolute joints "
        "and target angles in rad "
        "(or deg with --deg). Negative values are typed as they are: --q -1,0.5,0.2. Allowed: link lengths "
        "0.001 to 10 m (the offsets elbow d, stanford d2 and d6, scara d4 may be 0); |revolute q| and |angle| "
        "<= 1000 rad; |prismatic q| <= 100 m; |x|, |y|, |z| of a target <= 1000 m. Warnings (stderr, and "
        "'warnings' in --json): q outside a joint range, IK branches dropped by the joint ranges.",
    )
    import re  # kin only: `--q -1,0.5,0.2` is a value, not an option (argparse accepts only a lone -1 or -.5)

    kin._negative_number_matcher = re.compile(r"^-(?:\d|\.\d|inf|nan)", re.IGNORECASE)  # kinreport.NUMBER_LIST
    kin.add_argument("robot", metavar="ROBOT|FILE", help="rrp, elbow, stanford, scara, leg, or a robot file (.toml)")
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
    export = sub.add_parser(
        "export",
        help="a robot's MJCF (qpos = DH q) and URDF, from its name or robot file",
        description="Writes the MJCF whose body frames are the DH frames (MuJoCo's qpos is the DH q; sites base, "
        "frame1..frameN, tool) and/or a URDF with the same link frames and inertials. An existing file is replaced "
        "only with --force; each file is written under a temporary name and renamed into place.",
    )
    export.add_argument("robot", metavar="ROBOT|FILE", help="rrp, elbow, stanford, scara, leg, or a robot file (.toml)")
    export.add_argument("--mjcf", metavar="OUT.xml", help="the MJCF file to write")
    export.add_argument("--urdf", metavar="OUT.urdf", help="the URDF file to write")
    export.add_argument("--set", dest="sets", action="append", default=[], metavar="NAME=VALUE", help="link length [m]")
    export.add_argument("--force", action="store_true", help="replace the files if they exist")
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
        "--quit-after",
        type=_view_seconds,
        metavar="SECONDS",
        help="close the window this long after it opens (scripts)",
    )
    _add_study_parsers(sub)
    return parser


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
        "(one row per cell: swept parameters, every scalar metric, 'warnings', 'error'), sweep.json (grid, fixed "
        "parameters, units, versions, timing) and a figure per metric (one axis: metric vs the parameter; two: a "
        "heatmap).",
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
