"""Every scenario, found in the robot folders: each `hexabot_sim/robots/<robot>/__init__.py` declares its own."""

from __future__ import annotations

import importlib

from hexabot_sim.errors import lookup
from hexabot_sim.scenario import Scenario

# The robot folders, in the order `hexabot-sim list` shows them: adding a robot is one name here.
ROBOTS: tuple[str, ...] = ("pendulum", "leg", "hexabot", "quadbot", "rrp", "arm")


def _declared() -> dict[str, Scenario]:
    table: dict[str, Scenario] = {}
    for robot in ROBOTS:
        for scenario in importlib.import_module(f"hexabot_sim.robots.{robot}").SCENARIOS:
            if scenario.name in table:
                raise RuntimeError(f"scenario {scenario.name!r} is declared twice (robots/{robot})")
            table[scenario.name] = scenario
    return table


SCENARIOS: dict[str, Scenario] = _declared()


def get(name: str) -> Scenario:
    """The scenario called `name`."""
    return lookup(SCENARIOS, name, "scenario")
