"""The quadbot: four of the hexabot's DH legs on a free body, crawling or trotting on the shared walking machinery."""

from hexabot_sim.scenario import Scenario

SCENARIOS = (
    Scenario(
        "quadbot-walk",
        "the four-legged quadbot crawls (one leg at a time, duty 3/4, period 1.5 s) forward at 0.05 m/s",
        "hexabot_sim.robots.quadbot.walk",
        "QuadbotParams",
        defaults={},
        smoke={"duration": 2.1},
        params_module="hexabot_sim.robots.quadbot.parameters",
    ),
    Scenario(
        "quadbot-trot",
        "the quadbot trots (diagonal pairs, duty 1/2, period 0.3 s) at 0.1 m/s, any direction",
        "hexabot_sim.robots.quadbot.walk",
        "QuadbotParams",
        defaults={"gait": "trot", "vx": 0.1, "period": 0.3},
        smoke={"duration": 1.6},
        params_module="hexabot_sim.robots.quadbot.parameters",
    ),
    Scenario(
        "quadbot-rough",
        "the quadbot crawls over 1 cm rough ground at 0.05 m/s (sensed touchdown, level body)",
        "hexabot_sim.robots.quadbot.walk",
        "QuadbotParams",
        defaults={"roughness": 0.01, "touchdown": "sensed", "level_body": "on"},
        smoke={"duration": 2.1},
        params_module="hexabot_sim.robots.quadbot.parameters",
    ),
    Scenario(
        "quadbot-trot-rough",
        "the quadbot trots over 1 cm rough ground at 0.1 m/s (sensed touchdown, level body)",
        "hexabot_sim.robots.quadbot.walk",
        "QuadbotParams",
        defaults={
            "gait": "trot",
            "vx": 0.1,
            "period": 0.3,
            "roughness": 0.01,
            "touchdown": "sensed",
            "level_body": "on",
        },
        smoke={"duration": 1.6},
        params_module="hexabot_sim.robots.quadbot.parameters",
    ),
)
