"""The RRP arm of report 001: tool linear and angular velocity, checked by MuJoCo."""

from hexabot_sim.scenario import Scenario

SCENARIOS = (
    Scenario(
        "rrp-velocity",
        "RRP arm (report 001): tool linear and angular velocity for q(t) = (sin t, cos 2t, sin 3t), t = 0..20 s",
        "hexabot_sim.robots.rrp.velocity",
        "RrpVelocityParams",
        defaults={},
        smoke={"duration": 1.0},
        params_module="hexabot_sim.robots.rrp.parameters",
    ),
)
