"""Command line: `hexabot-sim list | run NAME | check`; the only place errors become exit codes."""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any, NoReturn

from hexabot_sim import params as params_mod
from hexabot_sim import scenarios
from hexabot_sim.errors import HexabotError, UsageError

PROG = "hexabot-sim"


class _Parser(argparse.ArgumentParser):
    """argparse that reports bad usage as one line and exit code 2, like every other input error."""

    def error(self, message: str) -> NoReturn:
        raise UsageError(message)


def _size(text: str) -> tuple[int, int]:
    width, sep, height = text.lower().partition("x")
    try:
        w, h = int(width), int(height)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT, e.g. 640x480; got {text!r}") from None
    if not sep or not (16 <= w <= 3840 and 16 <= h <= 2160):
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT between 16x16 and 3840x2160; got {text!r}")
    return w, h


def _fps(text: str) -> int:
    try:
        fps = int(text)
    except ValueError:
        fps = 0
    if not 1 <= fps <= 240:
        raise argparse.ArgumentTypeError(f"expected a whole number of frames per second from 1 to 240; got {text!r}")
    return fps


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog=PROG, description="Robotics-course simulations on MuJoCo: run named scenarios.")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser, metavar="{list,run,check,kin}")
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
    run.add_argument("--out", metavar="DIR", help="run folder (default: runs/<scenario>-<timestamp>)")
    run.add_argument("--force", action="store_true", help="replace --out if it already holds files")
    run.add_argument("--video", action="store_true", help="also render video.mp4 (headless)")
    run.add_argument(
        "--quality", choices=("preview", "high"), default="preview", help="video preset (default: preview)"
    )
    run.add_argument("--size", type=_size, default=(640, 480), metavar="WxH", help="video size (default: 640x480)")
    run.add_argument("--fps", type=_fps, default=30, help="video frame rate (default: 30)")
    run.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    sub.add_parser("check", help="MuJoCo version, working OpenGL backend, ffmpeg")
    kin = sub.add_parser("kin", help="kinematics of a robot: T0n, J, singularities, IK branches")
    kin.add_argument("robot", help="rrp, elbow, stanford, scara or leg")
    kin.add_argument("--q", metavar="Q1,Q2,...", help="joint values (rad for revolute, m for prismatic)")
    kin.add_argument("--target", metavar="X,Y,Z", help="tool position for IK (stanford: x,y,z,roll,pitch,yaw)")
    kin.add_argument("--set", dest="sets", action="append", default=[], metavar="NAME=VALUE", help="link length [m]")
    kin.add_argument("--json", action="store_true", help="machine-readable output")
    kin.add_argument("--symbolic", action="store_true", help="also derive T0n and J symbolically (needs sympy)")
    return parser


class ProgressBar:
    """A one-line progress bar on stderr when it is a terminal; silent otherwise."""

    def __init__(self, label: str, stream: Any = None) -> None:
        self.label = label
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = hasattr(self.stream, "isatty") and self.stream.isatty()
        self._last = -1

    def __call__(self, done: int, total: int) -> None:
        if not self.enabled:
            return
        percent = 100 * done // max(total, 1)
        if percent == self._last and done != total:
            return
        self._last = percent
        filled = percent * 30 // 100
        self.stream.write(f"\r{self.label} [{'#' * filled}{'.' * (30 - filled)}] {percent:3d}% ({done}/{total})")
        if done >= total:
            self.stream.write("\n")
        self.stream.flush()


def cmd_list() -> int:
    for scenario in scenarios.SCENARIOS.values():
        cls = scenario.params_type
        print(f"{scenario.name}\n  {scenario.summary}")
        for name, (info, default) in params_mod.infos(cls).items():
            value = scenario.defaults.get(name, default)
            if isinstance(value, tuple):
                value = ",".join(f"{v:.6g}" for v in value)
            unit = f" [{info.unit}]" if info.unit else ""
            allowed = f" (one of: {', '.join(info.choices)})" if info.choices else ""
            print(f"    {name:<12} = {value!s:<8}{unit:<12} {info.doc}{allowed}")
        print()
    return 0


def cmd_check() -> int:
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
    try:
        import imageio_ffmpeg

        print(f"ffmpeg        {imageio_ffmpeg.get_ffmpeg_exe()}")
        ffmpeg_ok = True
    except Exception as e:
        print(f"ffmpeg        NOT found: {e}")
        ffmpeg_ok = False
    video = "available" if working and ffmpeg_ok else "unavailable (CSV and plots still work)"
    print(f"video         {video}; MUJOCO_GL={os.environ.get('MUJOCO_GL', '')!r}")
    return 0


def cmd_kin(args: argparse.Namespace) -> int:
    import json

    from hexabot_sim import kinreport

    lengths = {}
    for name, raw in params_mod.parse_assignments(args.sets).items():
        lengths[name] = kinreport.parse_numbers(raw, f"length '{name}'")[0]
    report = kinreport.describe(args.robot, lengths)
    if args.q is not None:
        report |= kinreport.at_configuration(args.robot, kinreport.parse_numbers(args.q, "--q"), lengths)
    if args.target is not None:
        report |= kinreport.solve(args.robot, kinreport.parse_numbers(args.target, "--target"), lengths)
    if args.symbolic:
        try:
            from hexabot_sim.kinematics import symbolic
        except ImportError:
            raise UsageError("--symbolic needs sympy: pip install 'hexabot-sim[symbolic]'") from None
        chain = symbolic.symbolic_chain(args.robot)
        report["symbolic"] = {
            "T0n": symbolic.pretty(symbolic.transforms(chain)[-1]),
            "J": symbolic.pretty(symbolic.jacobian(chain)),
            "T0n_latex": symbolic.latex(symbolic.transforms(chain)[-1]),
            "J_latex": symbolic.latex(symbolic.jacobian(chain)),
        }
    if args.json:
        print(json.dumps(report, indent=2, allow_nan=False))
    else:
        print(kinreport.text(report))
        if args.symbolic:
            print(f"symbolic T0n:\n{report['symbolic']['T0n']}\nsymbolic J:\n{report['symbolic']['J']}")
    return 0


def _format(value: Any, unit: str) -> str:
    if value is None:
        return "n/a"
    if isinstance(value, float):
        return f"{value:.8g}{' ' + unit if unit and unit != '1' else ''}"
    return f"{value}{' ' + unit if unit and unit != '1' else ''}"


def cmd_run(args: argparse.Namespace) -> int:
    scenario = scenarios.get(args.scenario)
    sets = params_mod.parse_assignments(args.sets)
    config = params_mod.read_config(args.config) if args.config else {}

    # The OpenGL backend must be chosen before MuJoCo is imported (scenario modules import it).
    backend, no_video_reason = None, "not requested (add --video)"
    if args.video:
        from hexabot_sim import gl

        backend, no_video_reason = gl.choose()

    p: Any = params_mod.resolve(scenario.params_type, scenario.defaults, config, sets)
    out = Path(args.out) if args.out else None

    from hexabot_sim import output

    out = out if out is not None else output.default_out(scenario.name)
    with output.run_folder(out, force=args.force) as folder:
        started = time.perf_counter()
        result = scenario.runner(scenario.name, p, progress=ProgressBar(scenario.name))
        sim_seconds = time.perf_counter() - started

        output.write_csv(folder / result.csv_name, result.columns)
        output.write_text(folder / output.MODEL_NAME, result.model_xml)
        files = [result.csv_name, output.JSON_NAME, output.MODEL_NAME]
        if not args.no_plots:
            from hexabot_sim import plots

            files += output.write_figures(plots.figures(result), folder)

        if args.video and (result.camera is None or result.trajectory is None):
            backend, no_video_reason = None, f"{scenario.name} produces no trajectory to film"
        video: dict[str, Any] = {"written": False, "reason": no_video_reason}
        if args.video and backend is not None and result.trajectory is not None and result.camera is not None:
            from hexabot_sim import render

            width, height = args.size
            frames = render.render_video(
                result.model,
                result.trajectory.t,
                result.trajectory.qpos,
                folder / output.VIDEO_NAME,
                camera=result.camera,
                width=width,
                height=height,
                fps=args.fps,
                quality=args.quality,
                markers=result.markers,
                trail=result.trail,
                progress=ProgressBar("video"),
            )
            files.append(output.VIDEO_NAME)
            video = {
                "written": True,
                "file": output.VIDEO_NAME,
                "frames": frames,
                "fps": args.fps,
                "size": [width, height],
                "quality": args.quality,
                "gl_backend": backend,
            }

        output.write_json(
            folder / output.JSON_NAME,
            {
                "scenario": scenario.name,
                "description": scenario.summary,
                "params": params_mod.as_dict(p),
                "metrics": {name: m.value for name, m in result.metrics.items()},
                "units": {
                    "params": params_mod.units(type(p)),
                    "metrics": {name: m.unit for name, m in result.metrics.items()},
                    "columns": result.column_units,
                },
                "metric_docs": {name: m.doc for name, m in result.metrics.items()},
                "files": files,
                "video": video,
                "simulation": {
                    "steps": None if result.trajectory is None else len(result.trajectory.t) - 1,
                    "simulated_time": None if result.trajectory is None else float(result.trajectory.t[-1]),
                    "wall_time": sim_seconds,
                },
                "versions": output.versions(),
            },
        )

    simulated = (
        f"{result.trajectory.t[-1]:.6g} s simulated in {sim_seconds:.2f} s"
        if result.trajectory is not None
        else f"finished in {sim_seconds:.2f} s"
    )
    print(f"{scenario.name}: {simulated} -> {output.display_path(out)}")
    for name in result.summary:
        metric = result.metrics[name]
        print(f"  {name:<26} {_format(metric.value, metric.unit)}")
    print(f"  files: {', '.join(files)}")
    if args.video and backend is None:
        print(f"no video: {no_video_reason}", file=sys.stderr)
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Runs the CLI; returns the exit code (0 ok, 1 simulation failed, 2 bad input)."""
    try:
        args = build_parser().parse_args(argv)
        if args.command == "list":
            return cmd_list()
        if args.command == "check":
            return cmd_check()
        if args.command == "kin":
            return cmd_kin(args)
        return cmd_run(args)
    except HexabotError as e:
        print(f"{PROG}: error: {e}", file=sys.stderr)
        return e.exit_code
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted; nothing written", file=sys.stderr)
        return 130


def console() -> NoReturn:
    """Entry point of the `hexabot-sim` console script."""
    try:
        code = main()
        sys.stdout.flush()
    except BrokenPipeError:  # e.g. `hexabot-sim list | head`: the reader left; not an error of ours
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        code = 0
    sys.exit(code)


if __name__ == "__main__":
    console()
