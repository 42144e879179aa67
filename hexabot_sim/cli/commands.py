"""The commands that run one thing: list, check, kin, export, run, clean, view (a shell over the Python API)."""

from __future__ import annotations

import argparse
import contextlib
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from hexabot_sim import folders, registry, video
from hexabot_sim import params as params_mod
from hexabot_sim.cli.common import COMPLETED, DONE_SO_FAR, PROG, eprint, inputs
from hexabot_sim.cli.progress import ProgressBar
from hexabot_sim.errors import OutputError, UsageError, printable

if TYPE_CHECKING:  # the API imports MuJoCo, whose OpenGL backend each command chooses first
    from hexabot_sim import api


def cmd_list() -> int:
    from hexabot_sim import api

    for scenario in api.scenarios().values():
        print(f"{scenario.name}\n  {scenario.summary}")
        rows = []
        for name, p in scenario.parameters.items():
            value = p.default
            text = ",".join(f"{v:.6g}" for v in value) if isinstance(value, tuple) else str(value)
            unit = f"[{p.unit}]" if p.unit else ""
            rows.append((name, text, unit, f"{p.doc}; {p.allowed}"))
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
        eprint(f"{PROG}: warning: {warning}")
    print(json.dumps(report, indent=2, allow_nan=False) if args.json else kinreport.text(report))
    return 0


def cmd_export(args: argparse.Namespace) -> int:
    from hexabot_sim import api, kinreport

    robot = kinreport.resolve(args.robot, params_mod.parse_assignments(args.sets))  # --set checked as kin does
    for path in api.export(robot.spec, mjcf=args.mjcf, urdf=args.urdf, force=args.force, lengths=robot.lengths):
        print(f"wrote {printable(str(path))}")
    return 0


def _format(value: Any, unit: str) -> str:
    if value is None:
        return "n/a"
    if isinstance(value, float):
        return f"{value:.8g}{' ' + unit if unit and unit != '1' else ''}"
    return f"{value}{' ' + unit if unit and unit != '1' else ''}"


def _layers(args: argparse.Namespace) -> list[dict[str, Any]]:
    """The parameter layers a command line gives over the scenario's defaults: --config's, then --set's."""
    sets = params_mod.parse_assignments(args.sets)
    return [params_mod.read_config(args.config) if args.config is not None else {}, sets]


def _beside_config(args: argparse.Namespace, layers: list[dict[str, Any]], scenario: str) -> list[dict[str, Any]]:
    """The layers with --config's file names resolved beside it (params.files_beside). Called once MuJoCo may be
    imported: the scenario's parameter class comes with its module."""
    if args.config is None:
        return layers
    cls = registry.get(scenario).params_type
    return [params_mod.files_beside(layers[0], cls, Path(args.config)), *layers[1:]]


def cmd_run(args: argparse.Namespace) -> int:
    registry.get(args.scenario)
    layers = _layers(args)

    from hexabot_sim import gl

    # The OpenGL backend must be chosen before MuJoCo is imported (the API and the scenarios import it).
    backend, no_video_reason = None, video.NOT_REQUESTED
    given = [name for name in ("quality", "size", "fps") if getattr(args, name) is not None]
    if given and not args.video:  # they were ignored without a word
        eprint(f"{PROG}: warning: --{', --'.join(given)} shape{'s' if len(given) == 1 else ''} a video; without "
               "--video none is written")  # fmt: skip
    size, fps, quality = args.size or (640, 480), args.fps or 30, args.quality or "preview"
    settings = video.VideoSettings(*size, fps=fps, quality=quality) if args.video else None
    if settings is not None:
        backend, no_video_reason = gl.video_backend(announce=lambda notice: eprint(f"{PROG}: {notice}"))
    from hexabot_sim import api

    layers = _beside_config(args, layers, args.scenario)
    prepared = api.prepare(args.scenario, *layers)
    if settings is not None:
        video.check_cost(settings, getattr(prepared.params, "duration", None))
    if args.out is not None:
        folders.check_not_input(args.out, inputs(args.config, type(prepared.params), layers))
        folders.check_out(args.out, force=args.force)  # before the simulation, not after it
    with _mujoco_warnings_to_stderr():
        return _execute(args, prepared, settings, backend, no_video_reason)


def _mujoco_warnings_to_stderr() -> contextlib.AbstractContextManager[None]:
    """MuJoCo's warnings as one line each on stderr (never appended to MUJOCO_LOG.TXT in the user's folder)."""
    from hexabot_sim.simulate import mujoco_warnings

    return mujoco_warnings(lambda message: eprint(f"{PROG}: MuJoCo warning: {message}"))


def _execute(
    args: argparse.Namespace,
    prepared: api.Prepared,
    settings: video.VideoSettings | None,
    backend: str | None,
    no_video_reason: str,
) -> int:
    """Runs the scenario into its run folder (the staging folder is made first), then prints the summary."""
    from hexabot_sim import folders

    name = prepared.entry.name
    started = time.perf_counter()
    with folders.run_folder(args.out, name, force=args.force) as run:
        r = prepared.run(progress=ProgressBar(name))
        result = r.raw
        sim_seconds = time.perf_counter() - started
        if not args.no_plots:
            from hexabot_sim import plots

            plots.use_agg()  # the CLI draws off-screen; importing the package never picks a backend
        written = r.write_folder(run.path, plots=not args.no_plots, video=settings, backend=backend,
                                 no_video_reason=no_video_reason, video_progress=ProgressBar("video"))  # fmt: skip
        files, made, video_seconds = written.files, written.video, written.video_seconds
        no_video_reason = made.get("reason", no_video_reason)
    assert run.final is not None
    total_seconds = time.perf_counter() - started

    timing = f"simulated in {sim_seconds:.2f} s" if result.trajectory is not None else f"ran in {sim_seconds:.2f} s"
    if result.trajectory is not None:
        timing = f"{result.trajectory.t[-1]:.6g} s {timing}"
    if video_seconds:
        timing += f", video in {video_seconds:.2f} s"
    timing += f", {total_seconds:.2f} s in all"
    if args.video and not made["written"]:
        eprint(f"{PROG}: no video: {no_video_reason}")
    COMPLETED[:] = [f"the run folder {folders.display_path(run.final)} is complete"]
    print(f"{name}: {timing} -> {folders.display_path(run.final)}")
    for key in result.summary:
        metric = result.metrics[key]
        print(f"  {key:<26} {_format(metric.value, metric.unit)}")
    print(f"  files: {', '.join(files)}")
    for warning in result.warnings:
        eprint(f"{PROG}: warning: {warning}")
    return 0


def cmd_clean(args: argparse.Namespace) -> int:
    from hexabot_sim import cleaning, folders

    if not args.folder:
        raise UsageError("clean needs a folder name (default: runs); got an empty one")
    root = Path(args.folder)
    if not root.is_dir():
        raise UsageError(f"{folders.display_path(root)!r} is not a folder")
    stale = cleaning.stale_staging(root) + cleaning.stale_cells()
    removed, failures = 0, []  # a folder that cannot be removed is said, and the clean goes on (restores included)
    for path in stale:
        if path.name.startswith(folders.OLD_PREFIX) and not _settle_replaced(path, args.dry_run):
            continue  # kept: it holds the user's folder
        if args.dry_run:
            print(f"would remove {folders.display_path(path)}")
            continue
        if not os.path.lexists(path):
            continue  # another clean (or its owner) removed it meanwhile
        try:
            if sys.version_info >= (3, 12):
                shutil.rmtree(path, onexc=_gone_is_fine)
            else:
                shutil.rmtree(path, onerror=_gone_is_fine)
        except OSError as e:
            failures.append(f"could not remove {folders.display_path(path)!r}: {e.strerror or e}")
            continue
        except RecursionError:  # rmtree recurses per level (Python 3.11): a look-alike nested 1,500 deep
            failures.append(f"could not remove {folders.display_path(path)!r}: its folders nest deeper than Python's "
                            "recursion limit; remove it by hand (rm -r)")  # fmt: skip
            continue
        removed += 1
        done = f"{removed} stale folder{'s' if removed > 1 else ''} removed before it"
        DONE_SO_FAR[:] = [f"{done}, listed above"]
        COMPLETED[:] = [f"{done}, the last {folders.display_path(path)}"]  # if stdout fails, stderr names it
        print(f"removed {folders.display_path(path)}")
    if not stale:
        cells = tempfile.gettempdir()
        print(f"no staging folders left by interrupted runs in {args.folder} (nor sweep cells in {cells})")
    for failure in failures[1:]:
        eprint(f"{PROG}: {failure}")
    if failures:  # the first as the error, the others above it
        more = f" (and {len(failures) - 1} more, above)" if len(failures) > 1 else ""
        raise OutputError(failures[0] + more)
    return 0


def _settle_replaced(path: Path, dry_run: bool) -> bool:
    """A stale replaced folder of a --force run that died (cleaning.replaced_fate): puts the user's folder back under
    its name when that is free. True: the folder may go; False: it is kept (it holds the user's folder), and said."""
    from hexabot_sim import cleaning, folders

    fate, where = cleaning.replaced_fate(path)
    aside = folders.display_path(path / folders.PREVIOUS)
    if fate == "remove":
        if where is not None:  # the new run stands there: `previous` is what --force was asked to replace
            print(f"{'would remove' if dry_run else 'removing'} {aside}: the folder a --force run replaced with "
                  f"{folders.display_path(where)}")  # fmt: skip
        return True
    if fate == "restore" and where is not None:  # the run died between moving the folder aside and publishing
        if dry_run:
            print(f"would put {aside} back as {folders.display_path(where)}")
            return True
        try:
            cleaning.rename_back(path, where)
        except FileNotFoundError:
            if not os.path.lexists(path / folders.PREVIOUS):
                return True  # another clean put it back meanwhile
            why = "its name became unusable"
        except OSError as e:
            why = e.strerror or str(e)
        else:
            print(f"restored {folders.display_path(where)} (a --force run died before replacing it)")
            return True
        print(f"kept {aside}: it could not be put back as {folders.display_path(where)} ({why}); move it by hand")
        return False
    taken = "" if where is None else f"; {folders.display_path(where)} exists, so it was not put back"
    print(f"kept {aside}: a folder a --force run moved aside before it died{taken}; move it where it belongs by hand")
    return False


def _gone_is_fine(function: Any, path: str, info: Any) -> None:
    """rmtree's error handler for clean: what another clean running at the same time removed first is no error."""
    error = info[1] if isinstance(info, tuple) else info  # onerror's exc_info (3.11), onexc's exception (3.12+)
    if not isinstance(error, FileNotFoundError):
        raise error


def cmd_view(args: argparse.Namespace) -> int:
    """`view NAME` (live) or `view RUN_DIR` (replay) in MuJoCo's viewer: a window, so GLFW and a display."""
    from hexabot_sim import api, gl, viewer

    if not args.target:  # Path("") is ".": it replayed the working folder
        raise UsageError("view needs a scenario name or a run folder; got an empty one")
    folder = Path(args.target)
    replaying = folder.is_dir() or os.sep in args.target or args.target in (".", "..")
    if replaying and not folder.is_dir():  # /etc/passwd or a run's run.json "did not exist"
        why = "is a file, not a run folder" if os.path.lexists(folder) else "does not exist"
        raise UsageError(f"run folder {printable(args.target)!r} {why}; give the folder a run wrote")
    if replaying and (args.sets or args.config):
        raise UsageError("--set and --config choose a scenario's parameters; a run folder replays its own")
    if gl.loaded_backend() is None:
        os.environ["MUJOCO_GL"] = "glfw"  # MuJoCo binds its OpenGL at import: the window's, not EGL's
    # Bad input (the folder, or every parameter as a run would check it) is reported before the display is looked at.
    recording = viewer.load_recording(folder) if replaying else None
    make = None
    if not replaying:
        prepared = api.prepare(args.target, *_beside_config(args, _layers(args), args.target))
        make = viewer.live_maker(
            prepared.entry.name, prepared.params
        )  # a grid scenario is refused before the window opens
    problem = viewer.display_problem()
    if problem is not None:
        raise UsageError(f"cannot open the viewer: {problem}")
    options = {"speed": args.speed, "paused": args.paused, "quit_after": args.quit_after}

    def announce(text: str) -> None:
        eprint(f"{PROG}: {text}")

    with _mujoco_warnings_to_stderr():
        if recording is not None:
            summary = viewer.replay(recording, announce=announce, **options)
        else:
            assert make is not None
            summary = viewer.live(make, prepared.entry.name, announce=announce, **options)
    print(summary)
    return 0
