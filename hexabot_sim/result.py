"""What every scenario hands back: the compiled model, the recorded trajectory, columns and metrics."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

import mujoco
import numpy as np

from hexabot_sim.render import Marker
from hexabot_sim.simulate import Trajectory

Progress = Callable[[int, int], None]  # (done, total): scenarios report long work through it


@dataclasses.dataclass(frozen=True)
class Metric:
    """One scalar result of a run, with its unit and meaning."""

    value: Any  # float, int, str, bool, None or a list of those
    unit: str
    doc: str


@dataclasses.dataclass
class ScenarioResult:
    """Everything a run produced in memory; output.py, the scenario's figures() and render.py read it."""

    scenario: str
    params: Any  # the scenario's frozen parameter dataclass
    model: mujoco.MjModel
    model_xml: str  # the exact MJCF that compiled to `model`
    trajectory: Trajectory | None  # None for results that are not one trajectory (a parameter sweep)
    columns: dict[str, np.ndarray]  # CSV columns in order; the first is "t" for a time series
    column_units: dict[str, str]
    metrics: dict[str, Metric]
    summary: list[str]  # metric names shown after the run
    camera: str | None  # camera the video is rendered from (None: this result has no video)
    csv_name: str = "timeseries.csv"
    markers: list[Marker] = dataclasses.field(default_factory=list)  # drawn into the video
    trail: np.ndarray | None = None  # (n, 3) world points whose path the video draws (e.g. the foot)
    # Text lines the video shows under the time: each maps a recording row to text (render.OverlayLine).
    overlay: list[Callable[[int], str]] = dataclasses.field(default_factory=list)
    extras: dict[str, Any] = dataclasses.field(default_factory=dict)  # scenario data for its figures
    # What the run's figures say against its physics, one line each (an undamped pendulum that lost its energy, a
    # robot that fell or whose servos hit their torque limit): printed after the run, in run.json and the report.
    warnings: list[str] = dataclasses.field(default_factory=list)


@dataclasses.dataclass
class Live:
    """A scenario ready to be stepped interactively (`hexabot-sim view NAME`): model and state at the start.

    Each scenario module with a motion has `live(params) -> Live`; the viewer steps it in real time
    and draws `markers`, the path of `trail` and the `overlay` text as the videos do.
    """

    model: mujoco.MjModel
    data: mujoco.MjData
    step: Callable[[], None]  # advances `data` by one control period: controller, then physics
    timestep: float  # [s] simulated time one step() advances
    duration: float  # [s] the scenario's simulated time
    camera: str  # the scene camera of the videos: the viewer starts from its viewpoint
    track_body: str | None = None  # the view follows this body (a walking robot)
    markers: list[Marker] = dataclasses.field(default_factory=list)
    trail: Callable[[mujoco.MjData], np.ndarray] | None = None  # (3,) world point whose path is drawn
    overlay: list[Callable[[mujoco.MjData], str]] = dataclasses.field(default_factory=list)  # ASCII text lines
    # Keys the scenario takes in the viewer (a walk's steering): (GLFW key code, shift held) -> taken; their help
    # rows (key, what); and a line for the viewer's last words (the command steered to).
    keys: Callable[[int, bool], bool] | None = None
    key_help: tuple[tuple[str, str], ...] = ()
    summary: Callable[[mujoco.MjData], str] | None = None


def at_home(xml: str) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """Compiles `xml` and returns the model with its state at the "home" keyframe, forward-computed."""
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    return model, data
