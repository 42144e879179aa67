"""Listing the scenarios imports no MuJoCo, matplotlib or numba: each robot's parameter dataclasses live in a light
module (robots/<robot>/parameters.py) that the scenario module imports, and the API loads MuJoCo only to run."""

import importlib
import os
import subprocess
import sys

import pytest

from hexabot_sim import registry

HEAVY = ("mujoco", "matplotlib", "numba")

# What `hexabot-sim list` and `hexabot-sim run NAME --help` do, and what a notebook's `scenarios()` does.
LIST = f"""
import contextlib, io, sys
from hexabot_sim import api, registry
from hexabot_sim.cli import main
api.scenarios()
[scenario.params_type for scenario in registry.SCENARIOS.values()]
with contextlib.redirect_stdout(io.StringIO()):
    assert main(["list"]) == 0
    for name in registry.SCENARIOS:
        try:
            main(["run", name, "--help"])
        except SystemExit:
            pass
print(sorted(m for m in {HEAVY!r} if m in sys.modules))
"""


def test_listing_imports_no_mujoco_matplotlib_or_numba():
    out = subprocess.run(
        [sys.executable, "-c", LIST], capture_output=True, text=True, timeout=120, env={**os.environ}
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"


@pytest.mark.parametrize("name", sorted(registry.SCENARIOS))
def test_the_scenario_module_runs_the_listed_parameter_class(name):
    """One class, one way in: the scenario module imports its parameter class from the light module."""
    scenario = registry.SCENARIOS[name]
    assert scenario.params_module, f"{name}: its parameter class would be read from the module that runs it"
    assert scenario.params_type.__module__ == scenario.params_module
    assert getattr(importlib.import_module(scenario.module), scenario.params_class) is scenario.params_type
