"""Any serial arm (a package robot or a robot file, docs/robot-files.md) tracking a task-space path in MuJoCo."""

from hexabot_sim.scenario import Scenario

SCENARIOS = (
    Scenario(
        "arm-track",
        "any arm (stanford, scara, elbow, ... or a robot file): resolved-rate tracking of a line, circle or figure-8",
        "hexabot_sim.robots.arm.track",
        "ArmTrackParams",
        defaults={},
        smoke={"robot": "scara", "duration": 1.0},
        params_module="hexabot_sim.robots.arm.parameters",
    ),
)
