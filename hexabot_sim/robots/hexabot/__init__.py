"""Report 000"s Hexabot: six DH legs on a free body, walking on flat ground, slopes, rough ground, a kerb, stairs."""

from hexabot_sim.scenario import Scenario

SCENARIOS = (
    Scenario(
        "hexabot-walk",
        "the six-legged hexabot walks on flat ground: tripod/ripple/wave gait, any direction (report 000)",
        "hexabot_sim.robots.hexabot.walk",
        "HexabotParams",
        defaults={},
        smoke={"duration": 1.6},
        params_module="hexabot_sim.robots.hexabot.parameters",
    ),
    Scenario(
        "hexabot-turn",
        "the hexabot turns on the spot at 0.3 rad/s (tripod gait)",
        "hexabot_sim.robots.hexabot.walk",
        "HexabotParams",
        defaults={"vx": 0.0, "yaw_rate": 0.3},
        smoke={"duration": 1.6},
        params_module="hexabot_sim.robots.hexabot.parameters",
    ),
    Scenario(
        "hexabot-crab",
        "the hexabot walks sideways (crab walk) at 0.1 m/s to its left",
        "hexabot_sim.robots.hexabot.walk",
        "HexabotParams",
        defaults={"vx": 0.0, "vy": 0.1},
        smoke={"duration": 1.6},
        params_module="hexabot_sim.robots.hexabot.parameters",
    ),
    Scenario(
        "hexabot-force",
        "the hexabot's feet share the load (issue 19): force-controlled stance legs, padded feet, quintic swings, a "
        "3 s cycle, swings landing on a terrain map (sensed touchdown); --set roughness=0.01 for rough ground",
        "hexabot_sim.robots.hexabot.walk",
        "HexabotParams",
        defaults={
            "load_sharing": "force",
            "feet": "pad",
            "swing": "quintic",
            "period": 3.0,
            "touchdown": "sensed",
            "terrain_map": "on",
            "duration": 20.0,
        },
        smoke={"duration": 3.6},
        params_module="hexabot_sim.robots.hexabot.parameters",
    ),
    Scenario(
        "hexabot-slope",
        "the hexabot walks up a 10 deg slope at 0.1 m/s, its body kept level from the IMU (sensed touchdown)",
        "hexabot_sim.robots.hexabot.walk",
        "HexabotParams",
        defaults={"slope_deg": 10.0, "touchdown": "sensed", "level_body": "on", "duration": 10.0},
        smoke={"duration": 1.6},
        params_module="hexabot_sim.robots.hexabot.parameters",
    ),
    Scenario(
        "hexabot-rough",
        "the hexabot walks over 1 cm rough ground (seeded heightfield) at 0.1 m/s, its feet finding the ground",
        "hexabot_sim.robots.hexabot.walk",
        "HexabotParams",
        defaults={"roughness": 0.01, "touchdown": "sensed"},
        smoke={"duration": 1.6},
        params_module="hexabot_sim.robots.hexabot.parameters",
    ),
    Scenario(
        "hexabot-kerb",
        "the hexabot climbs a 3 cm kerb 0.5 m ahead (feet lifted 4 cm, sensed touchdown, level body)",
        "hexabot_sim.robots.hexabot.walk",
        "HexabotParams",
        defaults={
            "kerb_height": 0.03,
            "step_height": 0.04,
            "touchdown": "sensed",
            "level_body": "on",
            "duration": 14.0,
        },
        smoke={"duration": 1.6},
        params_module="hexabot_sim.robots.hexabot.parameters",
    ),
    Scenario(
        "hexabot-stairs",
        "the hexabot climbs 3 stairs of 4 cm x 25 cm at 0.1 m/s with its default 3 cm step height: a foot that meets "
        "a step's face lifts higher (elevator reflex; sensed touchdown, level body)",
        "hexabot_sim.robots.hexabot.walk",
        "HexabotParams",
        defaults={"stairs_rise": 0.04, "touchdown": "sensed", "level_body": "on", "duration": 18.0},
        smoke={"duration": 1.6},
        params_module="hexabot_sim.robots.hexabot.parameters",
    ),
)
