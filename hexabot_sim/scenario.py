"""The scenario contract: what a scenario module provides, and the registry line that declares a scenario."""

from __future__ import annotations

import dataclasses
import importlib
from collections.abc import Callable, Mapping
from typing import Any, Protocol, runtime_checkable


@runtime_checkable
class ScenarioModule(Protocol):
    """What a scenario module holds (dm_control's domain file, Playground's task file).

    A module may serve several scenarios (hexabot-walk, -turn, -crab differ in defaults only). It has:

    - a frozen parameter dataclass (named by `Scenario.params_class`) whose fields carry `params.param(...)`
      metadata (unit, meaning, range) and whose `__post_init__` refuses what cannot run, in one line (defined in
      the light `Scenario.params_module` and imported from it, so that listing needs no MuJoCo);
    - `run(name, params, progress=None) -> result.ScenarioResult`: the simulation, writing nothing;
    - `figures(result) -> {file stem: matplotlib Figure}`: its figures, made without pyplot;
    - optionally `live(params) -> result.Live`: the model ready to be stepped in the viewer.
    """

    def run(self, name: str, p: Any, progress: Callable[[int, int], None] | None = None) -> Any: ...

    def figures(self, result: Any) -> dict[str, Any]: ...


@dataclasses.dataclass(frozen=True)
class Scenario:
    """A named, runnable scenario: one line in its robot folder's `SCENARIOS`.

    The module is imported only when the scenario is used (it imports MuJoCo, whose OpenGL backend the
    command line chooses first): listing names and summaries imports nothing heavy.

    Attributes:
        name: What users type after `hexabot-sim run`.
        summary: One line for `hexabot-sim list`.
        module: Dotted path of the scenario module (see ScenarioModule).
        params_class: Name of the frozen parameter dataclass in that module.
        defaults: Scenario-specific defaults applied over the dataclass defaults.
        smoke: Parameters of a short run that still exercises the scenario (the tests run every
            scenario with them; a new scenario needs no edit to any test).
        params_module: Dotted path of a light module (no MuJoCo, no matplotlib) that holds the parameter
            dataclass, which `module` imports from it; "" when it is `module` itself. Listing the scenarios
            and their parameters imports only these.
    """

    name: str
    summary: str
    module: str
    params_class: str
    defaults: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    smoke: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    params_module: str = ""

    def _module(self) -> Any:
        return importlib.import_module(self.module)

    @property
    def params_type(self) -> type:
        return getattr(importlib.import_module(self.params_module or self.module), self.params_class)

    @property
    def runner(self) -> Callable[..., Any]:
        return self._module().run

    @property
    def figures(self) -> Callable[..., dict[str, Any]]:
        """The scenario's figure set: result -> {file stem: matplotlib Figure}."""
        return self._module().figures

    @property
    def live(self) -> Callable[..., Any] | None:
        """The module's `live(params)`, or None where the scenario has no motion to watch live."""
        return getattr(self._module(), "live", None)
