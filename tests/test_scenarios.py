"""A scenario is one module: its parameters, run() and figures(), found through one registry entry."""

import dataclasses
import importlib
import subprocess
import sys

import pytest
from matplotlib.figure import Figure

from hexabot_sim import params, scenarios
from hexabot_sim.scenarios.base import ScenarioResult

# Per scenario module: settings for a run of well under a second, and the figure stems it draws.
SHORT: dict[str, tuple[dict[str, str], tuple[str, ...]]] = {
    "pendulum": ({"duration": "0.2"}, ("angle_velocity", "phase", "energy")),
    "leg": (
        {"duration": "0.2"},
        ("foot_position", "foot_velocity", "joints", "foot_orientation", "singularity", "workspace"),
    ),
    "leg_sweep": (
        {"amplitudes": "0.03", "omegas": "3", "periods": "0.2", "workers": "1"},
        ("sweep", "workspace"),
    ),
    "rrp_velocity": ({"duration": "0.2"}, ("velocity",)),
    "hexabot": ({"duration": "1.6"}, ("path", "gait_diagram", "velocity", "body", "slip")),
}
# Scenarios with more figures than their module's short run above: the terrain presets draw the ground too.
EXTRA_STEMS: dict[str, tuple[str, ...]] = {
    name: ("terrain",) for name in ("hexabot-slope", "hexabot-rough", "hexabot-kerb")
}


@pytest.mark.parametrize("name", sorted(scenarios.SCENARIOS))
def test_scenario_module_defines_params_run_and_figures(name):
    scenario = scenarios.get(name)
    module = importlib.import_module(f"hexabot_sim.scenarios.{scenario.module}")
    params_type = getattr(module, scenario.params_class)
    assert dataclasses.is_dataclass(params_type) and params_type.__dataclass_params__.frozen
    assert callable(module.run) and callable(module.figures)
    assert scenario.params_type is params_type and scenario.runner is module.run
    assert scenario.figures is module.figures
    assert set(scenario.defaults) <= {f.name for f in dataclasses.fields(params_type)}


def test_results_name_no_figure_set():
    """Figures come from the scenario's module, not from a name looked up elsewhere."""
    assert "figures" not in {f.name for f in dataclasses.fields(ScenarioResult)}


@pytest.mark.parametrize("name", sorted(scenarios.SCENARIOS))
def test_figures_of_a_short_run(name):
    scenario = scenarios.get(name)
    assert scenario.module in SHORT, f"add a short run of module '{scenario.module}' to SHORT"
    sets, stems = SHORT[scenario.module]
    p = params.resolve(scenario.params_type, scenario.defaults, {}, sets)
    result = scenario.runner(name, p)
    figures = scenario.figures(result)
    assert tuple(figures) == stems + EXTRA_STEMS.get(name, ())
    assert all(isinstance(fig, Figure) and fig.axes for fig in figures.values())


def test_listing_scenarios_does_not_import_matplotlib():
    code = (
        "import sys; from hexabot_sim import scenarios; "
        "[s.params_type for s in scenarios.SCENARIOS.values()]; print('matplotlib' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"
