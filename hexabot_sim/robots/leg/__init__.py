"""One 3-DOF hexabot leg (report 000 §2, reports 002/004): resolved-rate steps of the foot and their grid."""

from hexabot_sim.scenario import Scenario

SCENARIOS = (
    Scenario(
        "leg-step",
        "hexabot leg: resolved-rate forward step of the foot along the ground X axis (reports 000/002/004)",
        "hexabot_sim.robots.leg.step",
        "LegStepParams",
        defaults={},
        smoke={"duration": 0.5, "mode": "kinematic"},
        params_module="hexabot_sim.robots.leg.parameters",
    ),
    Scenario(
        "leg-sweep",
        "hexabot leg: amplitude x frequency grid of forward steps; deviation vs the workspace excursion 2A/omega",
        "hexabot_sim.robots.leg.step_sweep",
        "LegSweepParams",
        defaults={},
        smoke={"amplitudes": [0.02, 0.05], "omegas": [1, 2], "periods": 0.5, "workers": 1},
        params_module="hexabot_sim.robots.leg.parameters",
    ),
)
