"""The Python API: list the scenarios, run one, and look at, save or film its result (for notebooks and scripts)."""

from __future__ import annotations

import contextlib
import dataclasses
import os
import secrets
import time
import warnings
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from hexabot_sim import folders, registry, unused
from hexabot_sim import params as params_mod
from hexabot_sim import video as video_options
from hexabot_sim.errors import HexabotError, OutputError, RunWarning, UsageError, printable
from hexabot_sim.exporting import export
from hexabot_sim.scenario import Scenario

# numpy, MuJoCo (hexabot_sim.result, gl) and the writers (output) are imported where a run or a save needs them:
# listing the scenarios (`hexabot-sim list`, `scenarios()`) imports none of them.
if TYPE_CHECKING:
    import numpy as np

    from hexabot_sim import output
    from hexabot_sim.result import Metric

__all__ = ["Columns", "Metric", "Parameter", "Result", "ScenarioInfo", "export", "run", "scenarios"]


def __getattr__(name: str) -> Any:
    if name == "Metric":  # hexabot_sim.result imports MuJoCo: loaded on first use
        from hexabot_sim.result import Metric

        return Metric
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


@dataclasses.dataclass(frozen=True)
class Parameter:
    """One parameter of a scenario, as `hexabot-sim list` shows it.

    Attributes:
        name: What `run(..., name=value)` and `--set name=value` take.
        default: This scenario's default value.
        unit: Unit of the value, e.g. "m/s" ("" for text, "1" for a plain number).
        doc: One-line meaning.
        allowed: The allowed values in words, e.g. "-1 <= amplitude <= 1 m/s" or "one of dynamic, kinematic".
        bounds: (lowest, highest) allowed number (whether each end is included: see `allowed`); None for text.
        choices: The allowed strings of a text parameter (case-insensitive), else None (a number, or a parameter
            that takes a name or a file's path: see `allowed`).
    """

    name: str
    default: Any
    unit: str
    doc: str
    allowed: str
    bounds: tuple[float, float] | None
    choices: tuple[str, ...] | None


@dataclasses.dataclass(frozen=True)
class ScenarioInfo:
    """A scenario: its name, one-line summary and parameters (name -> Parameter, in declaration order)."""

    name: str
    summary: str
    parameters: dict[str, Parameter]

    @property
    def defaults(self) -> dict[str, Any]:
        """Parameter name -> default value."""
        return {name: p.default for name, p in self.parameters.items()}


def _info(scenario: Scenario) -> ScenarioInfo:
    parameters = {}
    for name, (info, default) in params_mod.infos(scenario.params_type).items():
        value = scenario.defaults.get(name, default)
        bounds = None
        if not info.text and info.table is None:
            low = info.ge if info.ge is not None else info.gt
            high = info.le if info.le is not None else info.lt
            bounds = (float(low), float(high))  # type: ignore[arg-type]
        parameters[name] = Parameter(
            name, value, info.unit, info.doc, params_mod.describe_range(info, name), bounds, info.choices
        )
    return ScenarioInfo(scenario.name, scenario.summary, parameters)


def scenarios() -> dict[str, ScenarioInfo]:
    """Every scenario by name, with its parameters (default, unit, meaning, allowed range)."""
    return {name: _info(scenario) for name, scenario in registry.SCENARIOS.items()}


class Columns(dict):
    """The recorded columns of a run: name -> numpy array (n,), in CSV order; `.units` maps name -> unit."""

    def __init__(self, columns: Mapping[str, np.ndarray], units: Mapping[str, str]) -> None:
        super().__init__(columns)
        self.units: dict[str, str] = dict(units)


def _plain(value: Any) -> Any:
    """A numpy scalar or array as the Python value the CLI's parser takes (a number or a list of numbers)."""
    import numpy as np

    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def _mujoco_warnings() -> contextlib.AbstractContextManager[None]:
    """MuJoCo's warnings become Python RuntimeWarnings (its default handler writes MUJOCO_LOG.TXT to the cwd)."""
    from hexabot_sim.simulate import mujoco_warnings

    return mujoco_warnings(lambda message: warnings.warn(f"MuJoCo warning: {message}", RuntimeWarning, stacklevel=4))


def run(
    scenario: str,
    *,
    config: str | os.PathLike[str] | None = None,
    progress: Callable[[int, int], None] | None = None,
    **params: Any,
) -> Result:
    """Runs a scenario and returns its result (nothing is written; see Result.save).

    Parameters are checked exactly as `hexabot-sim run` checks them, with the same messages;
    precedence is the same too: scenario defaults < `config` < keyword parameters.

    Args:
        scenario: Scenario name, e.g. "leg-step" (see `scenarios()`).
        config: Optional TOML file of `name = value` lines (like `--config`).
        progress: Called with (done, total) while the run goes, e.g. for a progress bar.
        **params: Parameter values, e.g. `amplitude=0.08, mode="kinematic"`; numbers, strings (as
            `--set` takes them), or lists of numbers for list parameters.

    Raises:
        hexabot_sim.errors.UsageError: (a ValueError) an unknown scenario or parameter, a value out of
            its range, a run too large; the message names what is allowed.
        hexabot_sim.errors.SimulationError: the simulation went unstable (names the time and likely cause).

    Warns:
        hexabot_sim.errors.RunWarning: for each of `Result.warnings` (a run that finished but whose figures say
            something is physically off: an undamped pendulum that lost its energy, a walk that fell).
    """
    registry.get(scenario)
    _check_path("config", config)
    _check_callable("progress", progress)
    layers = [params_mod.read_config(Path(config), registry.get(scenario).params_type)] if config is not None else []
    layers.append({name: _plain(value) for name, value in params.items()})
    prepared = prepare(scenario, *layers)
    # The files it reads, which Result.save may not write over (the resolved params hold a schedule's rows, no file).
    files = params_mod.input_files(config, prepared.entry.params_type, layers)
    prepared = dataclasses.replace(prepared, inputs=tuple(os.path.abspath(f) for f in files))  # a later chdir
    with _mujoco_warnings():
        result = prepared.run(progress)
    for text in result.warnings:
        warnings.warn(RunWarning(text, result), stacklevel=2)  # raised as an error, it still carries the result
    return result


@dataclasses.dataclass(frozen=True)
class Prepared:
    """A scenario with its parameters resolved and checked (nothing has run yet): `run()` simulates it.

    Attributes:
        entry: The registry's entry of the scenario.
        params: The scenario's frozen parameter dataclass, fully resolved.
    """

    entry: Scenario
    params: Any
    inputs: tuple[str, ...] = ()  # the files the run reads (params.input_files): Result.save writes over none

    def run(self, progress: Callable[[int, int], None] | None = None) -> Result:
        """Simulates the scenario (MuJoCo's warnings go to whatever handler the caller installed)."""
        started = time.perf_counter()
        raw = self.entry.runner(self.entry.name, self.params, progress=progress)
        return Result(self.entry, self.params, raw, time.perf_counter() - started, self.inputs)


def prepare(scenario: str, *layers: Mapping[str, Any]) -> Prepared:
    """Resolves a scenario's parameters: its defaults, then each layer in turn (a config file's, then --set's).

    Values are checked as `run` checks them (UsageError naming what is allowed); nothing is simulated. The
    command line uses it to refuse a run (its video cost, its --out) before the simulation starts.
    """
    entry = registry.get(scenario)
    p = params_mod.resolve(entry.params_type, entry.defaults, *layers)
    unused.check([p], entry.defaults, unused.given(entry.params_type, layers))
    return Prepared(entry, p)


def _check_path(name: str, value: Any, optional: bool = True) -> None:
    """A path argument is a str or os.PathLike (or None where optional), else a UsageError (not pathlib's TypeError)."""
    if not (isinstance(value, (str, os.PathLike)) or (optional and value is None)):
        allowed = "a path (str or os.PathLike)" + (" or None" if optional else "")
        raise UsageError(f"'{name}' must be {allowed}; got {type(value).__name__}")
    if value is None:
        return
    raw = os.fsencode(value)
    if b"\0" in raw:
        raise UsageError(f"'{name}' holds a NUL byte, which no file name can; got {value!r}")
    if len(raw) > 4095 or any(len(part) > 255 for part in raw.split(b"/")):
        raise UsageError(f"'{name}' is too long: a file or folder name is at most 255 bytes, a path 4095")


def _same_file(a: str | os.PathLike[str], b: str | os.PathLike[str]) -> bool:
    """Whether both name one existing file (any links, mounts or spellings); False where either is missing."""
    try:
        return os.path.samefile(a, b)
    except (OSError, ValueError):
        return False


def _check_flag(name: str, value: Any) -> None:
    """A yes/no argument is a bool: force="no" is true in Python, and would replace a folder."""
    import numpy as np

    if not isinstance(value, (bool, np.bool_)):
        raise UsageError(f"'{name}' must be True or False; got {value!r}")


def _check_callable(name: str, value: Any) -> None:
    """A callback argument is callable (or None), checked before the run rather than at its first call."""
    if value is not None and not callable(value):
        raise UsageError(f"'{name}' must be a callable (done, total) -> None or None; got {type(value).__name__}")


class Result:
    """What one run produced, in memory.

    Attributes:
        scenario: Scenario name.
        description: The scenario's one-line summary.
        params: Parameter name -> the value the run used (fully resolved); `run(name, **r.params)` repeats it.
        param_units: Parameter name -> unit.
        metrics: Metric name -> Metric(value, unit, doc).
        summary: Names of the metrics that sum the run up (what the CLI prints).
        columns: Column name -> numpy array (the CSV's columns), with `.columns.units`.
        raw: The scenario's ScenarioResult (the compiled MjModel, the trajectory, ...).
        wall_time: Wall time of the simulation [s].
        warnings: What the run's figures say against its physics, one line each (empty for most runs): an
            undamped pendulum that lost its energy to a coarse timestep, a walk that fell or whose servos
            saturated. `run()` also issues each as a RunWarning; the CLI prints them, run.json keeps them.
    """

    def __init__(
        self, scenario: Scenario, params: Any, raw: Any, wall_time: float, inputs: tuple[str, ...] = ()
    ) -> None:
        self._scenario = scenario
        self._params = params
        self._inputs = inputs
        self.raw = raw
        self.wall_time = wall_time
        self.scenario: str = scenario.name
        self.description: str = scenario.summary
        self.params: dict[str, Any] = params_mod.as_dict(params)
        self.param_units: dict[str, str] = params_mod.units(type(params))
        self.metrics: dict[str, Metric] = dict(raw.metrics)
        self.summary: list[str] = list(raw.summary)
        self.warnings: list[str] = list(raw.warnings)
        self.columns = Columns(raw.columns, raw.column_units)

    def __repr__(self) -> str:
        key = "; ".join(f"{name}={_short(self.metrics[name])}" for name in self.summary)
        return f"<hexabot_sim.Result {self.scenario}: {key}>"

    def _repr_html_(self) -> str:
        from hexabot_sim import report

        record = {
            "metrics": {name: m.value for name, m in self.metrics.items()},
            "units": {"metrics": {name: m.unit for name, m in self.metrics.items()}},
        }
        line = report.summary_line(record, self.summary)
        import html

        notes = "".join(f"<p><b>Warning:</b> {html.escape(text)}</p>" for text in self.warnings)
        return f"<p><b>{html.escape(self.scenario)}</b>: {html.escape(line)}</p>{notes}"

    def to_pandas(self) -> Any:
        """The columns as a pandas DataFrame (units in `df.attrs["units"]`).

        Raises:
            ImportError: when pandas is not installed (it is not a dependency of hexabot-sim).
        """
        try:
            import pandas as pd
        except ImportError as e:
            raise ImportError(
                "Result.to_pandas() needs pandas, which hexabot-sim does not install: pip install pandas "
                "(the columns are also in Result.columns as numpy arrays)"
            ) from e
        import numpy as np

        frame = pd.DataFrame({name: np.asarray(values) for name, values in self.columns.items()})
        frame.attrs["units"] = dict(self.columns.units)
        return frame

    def figures(self) -> dict[str, Any]:
        """The scenario's figures: file stem -> matplotlib Figure (new ones at every call).

        They are made without pyplot, in matplotlib's default style, whatever the global rcParams
        are; no backend is chosen and no rcParams are changed.
        """
        from hexabot_sim import output

        with output.package_style():
            return dict(self._scenario.figures(self.raw))

    def save(
        self,
        out: str | os.PathLike[str] | None = None,
        *,
        force: bool = False,
        plots: bool = True,
        video: bool = False,
        quality: str = "preview",
        size: tuple[int, int] | str = (640, 480),
        fps: int = 30,
        progress: Callable[[int, int], None] | None = None,
    ) -> Path:
        """Writes the run folder `hexabot-sim run` writes: the same files with the same bytes (timings aside).

        Args:
            out: The run folder (new or empty; default: runs/<scenario>-<timestamp>[-N]).
            force: Replace a non-empty `out` (as `--force`).
            plots: Write the PNG figures (as not `--no-plots`).
            video: Also render video.mp4; when no OpenGL or ffmpeg works, the folder is written
                without it and run.json's `video.reason` says why (as `--video`).
            quality, size, fps: The video's preset, (width, height) [px] or "WxH", frame rate.
            progress: Called with (frames done, frames in all) while the video renders.

        Returns:
            The run folder.

        Raises:
            hexabot_sim.errors.UsageError: a refused `out` (see the README's run folder contract; also one that is,
                holds or lies inside a file the run read, with or without `force`) or bad video options.
            hexabot_sim.errors.OutputError: the folder could not be written.
        """
        _check_path("out", out)
        for flag, value in (("force", force), ("plots", plots), ("video", video)):
            _check_flag(flag, value)
        _check_callable("progress", progress)
        from hexabot_sim import gl

        settings = video_options.settings(quality, size, fps)  # checked with or without a video, as the CLI does
        settings = settings if video else None
        backend, reason = None, video_options.NOT_REQUESTED
        if video:
            backend, reason = gl.video_backend()
        try:
            if out is not None:  # a config, schedule or robot file the run read is never written over
                folders.check_not_input(out, list(self._inputs))
            with folders.run_folder(out, self.scenario, force=force) as folder:
                self.write_folder(folder.path, plots=plots, video=settings, backend=backend, no_video_reason=reason,
                                  video_progress=progress)  # fmt: skip
        except HexabotError as e:  # the folder's refusals speak the command line's words: say them as arguments
            e.args = (_argument_words(str(e)),)
            raise
        assert folder.final is not None
        return folder.final

    def write_folder(
        self,
        path: str | os.PathLike[str],
        *,
        plots: bool = True,
        video: video_options.VideoSettings | None = None,
        backend: str | None = None,
        no_video_reason: str = video_options.NOT_REQUESTED,
        video_progress: Callable[[int, int], None] | None = None,
    ) -> output.Written:
        """Writes the run's files into `path`, an empty folder made for them (`save` and the command line give
        it their staging folder, which they publish); `backend` is the working OpenGL backend for `video`.

        Raises:
            hexabot_sim.errors.UsageError: `path` is a file or a folder that holds some (they would be written over;
                `save` makes, fills and publishes a run folder). A folder that is missing (moved or removed during
                the run) is the writing's OSError, as the command line reports it.
        """
        from hexabot_sim import output

        _check_path("path", path, optional=False)
        path = Path(path)
        try:
            taken = path.exists() and (not path.is_dir() or any(path.iterdir()))
        except OSError:  # unreadable
            taken = True
        if taken:
            where = printable(str(path))
            raise UsageError(f"'path' must be an empty folder; {where} is not (Result.save writes a new one)")
        return output.write_run(
            path,
            self._scenario,
            self._params,
            self.raw,
            sim_seconds=self.wall_time,
            plots=plots,
            video=video,
            backend=backend,
            no_video_reason=no_video_reason,
            video_progress=video_progress,
        )

    def video(
        self,
        path: str | os.PathLike[str] = "video.mp4",
        *,
        quality: str = "preview",
        size: tuple[int, int] | str = (640, 480),
        fps: int = 30,
        progress: Callable[[int, int], None] | None = None,
        force: bool = False,
    ) -> Path:
        """Renders the run as an MP4 (H.264) at `path`, in real time, as `hexabot-sim run --video` does.

        Args:
            path: The file to write: a new one, or with `force` an existing file to replace.
            quality: "preview" (fast) or "high" (multisampling, shadows).
            size: (width, height) [px] or "WxH": even sides, 64x64 to 3840x2160, at most 4:1.
            fps: Frames per second, 1 to 240.
            force: Replace `path` if it exists (a regular file; never a folder, FIFO or device).

        Returns:
            The path written.

        Raises:
            hexabot_sim.errors.UsageError: bad options, a scenario without a trajectory (leg-sweep), or `path` a
                file the run read (its config, schedule, waypoints or robot file).
            hexabot_sim.errors.OutputError: no working OpenGL or ffmpeg here, or rendering failed.
        """
        _check_path("path", path, optional=False)
        _check_flag("force", force)
        _check_callable("progress", progress)
        settings = video_options.settings(quality, size, fps)
        if self.raw.camera is None or self.raw.trajectory is None:
            raise UsageError(f"{self.scenario} produces no trajectory to film")
        from hexabot_sim import gl, output

        backend, reason = gl.video_backend()
        if backend is None:
            raise OutputError(f"no video: {reason}")
        path = Path(path)
        if path.is_dir():
            raise UsageError(f"video path {str(path)!r} is a folder; give a file name such as video.mp4")
        folder = path.parent
        if not folder.is_dir():
            raise UsageError(f"the folder {str(folder)!r} for the video does not exist")
        if not folders.writable(folder):  # (root passes os.access: the mode bits too)
            raise OutputError(f"the folder {str(folder)!r} for the video cannot be written")
        if any(_same_file(path, f) for f in self._inputs):
            raise UsageError(f"video path {str(path)!r} is a file the run read (its config, schedule, waypoints or "
                             "robot file); a run never writes over what it reads: choose another path")  # fmt: skip
        folders.check_replace(path, force)
        # The name cut short (a 250-byte name is legal; '.NAME.partial-PID.mp4' was not: a raw OSError), with a
        # random part so two renders to one path in one process do not share it.
        staging = path.with_name(f".{path.name[:48]}.partial-{os.getpid()}-{secrets.token_hex(4)}.mp4")
        try:
            record, _ = output.write_video(folder, self.raw, settings, backend, progress, name=staging.name)
            if not record["written"]:
                raise OutputError(f"no video: {record['reason']}")
            folders.check_replace(path, force)  # again: the file may have appeared while the video rendered
            if force:
                os.replace(staging, path)
            else:
                folders.publish_new(staging, path)
        except OSError as e:
            raise OutputError(f"writing the video {str(path)!r} failed: {e.strerror or e}") from None
        finally:
            staging.unlink(missing_ok=True)
        return path


def _argument_words(text: str) -> str:
    """An output refusal of the command line's ("choose another --out or add --force to replace it") in the
    words of `Result.save`'s arguments ("choose another out or pass force=True to replace it")."""
    for flag, argument in (("add --force", "pass force=True"), ("--force", "force=True"), ("--out", "out")):
        text = text.replace(flag, argument)
    return text


def _short(metric: Metric) -> str:
    from hexabot_sim import report

    unit = "" if metric.unit in ("", "1") or metric.value is None else f" {metric.unit}"
    return f"{report.format_value(metric.value)}{unit}"
