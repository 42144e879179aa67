"""The simple pendulum of report 000 §1: free, damped, and with a spring toward a target angle."""

from hexabot_sim.scenario import Scenario

SCENARIOS = (
    Scenario(
        "pendulum-undamped",
        "pendulum released from 90 deg, no damping, no spring: constant amplitude (report Fig. 5/7)",
        "hexabot_sim.robots.pendulum.pendulum",
        "PendulumParams",
        defaults={"damping": 0.0, "stiffness": 0.0},
        smoke={"duration": 0.5},
        params_module="hexabot_sim.robots.pendulum.parameters",
    ),
    Scenario(
        "pendulum-damped",
        "pendulum with joint damping 0.01 N*m*s/rad: comes to rest hanging down (report Fig. 6/8)",
        "hexabot_sim.robots.pendulum.pendulum",
        "PendulumParams",
        defaults={"damping": 0.01, "stiffness": 0.0},
        smoke={"duration": 0.5},
        params_module="hexabot_sim.robots.pendulum.parameters",
    ),
    Scenario(
        "pendulum",
        "damped pendulum with a joint spring toward 30 deg: rests where spring and gravity balance",
        "hexabot_sim.robots.pendulum.pendulum",
        "PendulumParams",
        defaults={},
        smoke={"duration": 0.5},
        params_module="hexabot_sim.robots.pendulum.parameters",
    ),
)
