"""A scenario is one module: its parameters, run() and figures(), found through one registry entry."""

import dataclasses
import importlib
import subprocess
import sys

import pytest
from matplotlib.figure import Figure

from hexabot_sim import params, registry
from hexabot_sim.result import ScenarioResult

# The figure stems the existing scenario modules draw (a regression check; a new module needs no entry here:
# every scenario's smoke run must draw figures all the same).
STEMS: dict[str, tuple[str, ...]] = {
    "pendulum": ("angle_velocity", "phase", "energy"),
    "step": ("foot_position", "foot_velocity", "joints", "foot_orientation", "singularity", "workspace"),
    "step_sweep": ("sweep", "workspace"),
    "velocity": ("velocity",),
    "walk": ("path", "gait_diagram", "foot_forces", "velocity", "body", "slip"),
}
# Scenarios with more figures than their module's smoke run: the terrain presets (any robot's) draw the ground too.
EXTRA_STEMS: dict[str, tuple[str, ...]] = {
    name: ("terrain",)
    for name, scenario in registry.SCENARIOS.items()
    if any(scenario.defaults.get(key) for key in ("slope_deg", "roughness", "kerb_height", "stairs_rise"))
}


@pytest.mark.parametrize("name", sorted(registry.SCENARIOS))
def test_scenario_module_defines_params_run_and_figures(name):
    scenario = registry.get(name)
    module = importlib.import_module(scenario.module)
    params_type = getattr(module, scenario.params_class)
    assert dataclasses.is_dataclass(params_type) and params_type.__dataclass_params__.frozen
    assert callable(module.run) and callable(module.figures)
    assert scenario.params_type is params_type and scenario.runner is module.run
    assert scenario.figures is module.figures
    assert set(scenario.defaults) <= {f.name for f in dataclasses.fields(params_type)}


def test_results_name_no_figure_set():
    """Figures come from the scenario's module, not from a name looked up elsewhere."""
    assert "figures" not in {f.name for f in dataclasses.fields(ScenarioResult)}


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(registry.SCENARIOS))
def test_figures_of_a_short_run(name):
    scenario = registry.get(name)
    assert scenario.smoke, f"scenario {name} declares no smoke run (Scenario.smoke)"
    p = params.resolve(scenario.params_type, scenario.defaults, {}, dict(scenario.smoke))
    result = scenario.runner(name, p)
    figures = scenario.figures(result)
    assert figures and all(stem.isidentifier() for stem in figures)
    stems = STEMS.get(scenario.module.rsplit(".", 1)[-1])
    if stems is not None:
        assert tuple(figures) == stems + EXTRA_STEMS.get(name, ())
    assert all(isinstance(fig, Figure) and fig.axes for fig in figures.values())


@pytest.mark.slow
def test_listing_scenarios_does_not_import_matplotlib():
    code = (
        "import sys; from hexabot_sim import registry; "
        "[s.params_type for s in registry.SCENARIOS.values()]; print('matplotlib' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"
