"""Registry of named scenarios: parameters with their defaults, and the function that runs them."""

from __future__ import annotations

import dataclasses
import importlib
import sys
import types
from collections.abc import Callable, Mapping
from typing import Any

from hexabot_sim.errors import lookup


@dataclasses.dataclass(frozen=True)
class Scenario:
    """A named, runnable scenario.

    Attributes:
        name: What users type after `hexabot-sim run`.
        summary: One line for `hexabot-sim list`.
        module: Module under hexabot_sim.scenarios holding the parameter class, `run(name, params)`
            and `figures(result)`.
        params_class: Name of the frozen parameter dataclass in that module.
        defaults: Scenario-specific defaults applied over the dataclass defaults.
    """

    name: str
    summary: str
    module: str
    params_class: str
    defaults: Mapping[str, Any] = dataclasses.field(default_factory=dict)

    def _module(self) -> Any:
        return importlib.import_module(f"hexabot_sim.scenarios.{self.module}")

    @property
    def params_type(self) -> type:
        return getattr(self._module(), self.params_class)

    @property
    def runner(self) -> Callable[..., Any]:
        return self._module().run

    @property
    def figures(self) -> Callable[..., dict[str, Any]]:
        """The scenario's figure set: result -> {file stem: matplotlib Figure}."""
        return self._module().figures


SCENARIOS: dict[str, Scenario] = {
    s.name: s
    for s in (
        Scenario(
            "pendulum-undamped",
            "pendulum released from 90 deg, no damping, no spring: constant amplitude (report Fig. 5/7)",
            "pendulum",
            "PendulumParams",
            {"damping": 0.0, "stiffness": 0.0},
        ),
        Scenario(
            "pendulum-damped",
            "pendulum with joint damping 0.01 N*m*s/rad: comes to rest hanging down (report Fig. 6/8)",
            "pendulum",
            "PendulumParams",
            {"damping": 0.01, "stiffness": 0.0},
        ),
        Scenario(
            "pendulum",
            "damped pendulum with a joint spring toward 30 deg: rests where spring and gravity balance",
            "pendulum",
            "PendulumParams",
            {},
        ),
        Scenario(
            "leg-step",
            "hexabot leg: resolved-rate forward step of the foot along the ground X axis (reports 000/002/004)",
            "leg",
            "LegStepParams",
            {},
        ),
        Scenario(
            "leg-sweep",
            "hexabot leg: amplitude x frequency grid of forward steps; deviation vs the workspace excursion 2A/omega",
            "leg_sweep",
            "LegSweepParams",
            {},
        ),
        Scenario(
            "hexabot-walk",
            "the six-legged hexabot walks on flat ground: tripod/ripple/wave gait, any direction (report 000)",
            "hexabot",
            "HexabotParams",
            {},
        ),
        Scenario(
            "hexabot-turn",
            "the hexabot turns on the spot at 0.3 rad/s (tripod gait)",
            "hexabot",
            "HexabotParams",
            {"vx": 0.0, "yaw_rate": 0.3},
        ),
        Scenario(
            "hexabot-crab",
            "the hexabot walks sideways (crab walk) at 0.1 m/s to its left",
            "hexabot",
            "HexabotParams",
            {"vx": 0.0, "vy": 0.1},
        ),
        Scenario(
            "hexabot-slope",
            "the hexabot walks up a 10 deg slope at 0.1 m/s, its body kept level from the IMU (sensed touchdown)",
            "hexabot",
            "HexabotParams",
            {"slope_deg": 10.0, "touchdown": "sensed", "level_body": "on", "duration": 10.0},
        ),
        Scenario(
            "hexabot-rough",
            "the hexabot walks over 1 cm rough ground (seeded heightfield) at 0.1 m/s, its feet finding the ground",
            "hexabot",
            "HexabotParams",
            {"roughness": 0.01, "touchdown": "sensed"},
        ),
        Scenario(
            "hexabot-kerb",
            "the hexabot climbs a 3 cm kerb 0.5 m ahead (feet lifted 4 cm, sensed touchdown, level body)",
            "hexabot",
            "HexabotParams",
            {"kerb_height": 0.03, "step_height": 0.04, "touchdown": "sensed", "level_body": "on", "duration": 14.0},
        ),
        Scenario(
            "rrp-velocity",
            "RRP arm (report 001): tool linear and angular velocity for q(t) = (sin t, cos 2t, sin 3t), t = 0..20 s",
            "rrp_velocity",
            "RrpVelocityParams",
            {},
        ),
    )
}


def get(name: str) -> Scenario:
    """The scenario called `name`."""
    return lookup(SCENARIOS, name, "scenario")


class _CallableModule(types.ModuleType):
    """This module is also the API's `hexabot_sim.scenarios()`: importing a sub-package named
    `scenarios` replaces any attribute of that name on the package, so the module itself answers the call."""

    def __call__(self) -> Any:
        from hexabot_sim import api

        return api.scenarios()


sys.modules[__name__].__class__ = _CallableModule
