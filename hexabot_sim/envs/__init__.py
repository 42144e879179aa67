"""Gymnasium environments of the walking robots (the `rl` extra: pip install "hexabot-sim[rl]").

    import gymnasium
    env = gymnasium.make("hexabot_sim.envs:hexabot_sim/HexabotJoints-v0")  # imports and registers on the way

or `import hexabot_sim.envs` (registers them), then `gymnasium.make("hexabot_sim/HexabotJoints-v0")`.
`gymnasium.make_vec` of a joint-level id defaults to the batched environment (vector.py: mujoco.rollout);
vectorization_mode="async" or "sync" give Gymnasium's own.
Gymnasium 1.x has no plugin entry points (removed in 1.0): the "module:" prefix is its way to find them.
"""

from __future__ import annotations

try:
    import gymnasium
except ImportError as e:  # pragma: no cover - the message is the point
    raise ImportError('hexabot_sim.envs needs gymnasium: pip install "hexabot-sim[rl]"') from e

NAMESPACE: str = "hexabot_sim"

JOINTS = "hexabot_sim.envs.joints:LeggedJointsEnv"
ROLLOUT = "hexabot_sim.envs.vector:LeggedJointsVectorEnv"  # make_vec's default for the joint-level ids
# id -> (entry point, vector entry point or None, kwargs, max_episode_steps): a robot is a keyword, not a class.
ENVS: dict[str, tuple[str, str | None, dict, int]] = {
    "HexabotJoints-v0": (JOINTS, ROLLOUT, {"robot": "hexabot"}, 1000),
    "QuadbotJoints-v0": (JOINTS, ROLLOUT, {"robot": "quadbot"}, 1000),
    "HexabotCommand-v0": ("hexabot_sim.envs.command:LeggedCommandEnv", None, {"robot": "hexabot"}, 200),
}


def register_envs() -> None:
    """Registers every environment as hexabot_sim/<id> (again: a no-op)."""
    for name, (entry_point, vector_entry_point, kwargs, steps) in ENVS.items():
        env_id = f"{NAMESPACE}/{name}"
        if env_id not in gymnasium.registry:
            gymnasium.register(
                id=env_id, entry_point=entry_point, vector_entry_point=vector_entry_point, kwargs=kwargs,
                max_episode_steps=steps,
            )  # fmt: skip


register_envs()

__all__ = ["ENVS", "NAMESPACE", "register_envs"]
