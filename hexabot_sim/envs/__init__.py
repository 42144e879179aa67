"""Gymnasium environments of the walking robots (the `rl` extra: pip install "hexabot-sim[rl]").

    import gymnasium
    env = gymnasium.make("hexabot_sim/HexabotJoints-v0")

Installed from the wheel, the ids are registered whenever gymnasium is imported, without importing this package
(ids.py: the `hexabot_sim_gymnasium.pth` import hook; Gymnasium 1.x itself loads no plugins). Without the hook
(the package on PYTHONPATH only, or HEXABOT_SIM_NO_AUTOREGISTER=1), `import hexabot_sim.envs` registers them, or
the id with the module prefix, "hexabot_sim.envs:hexabot_sim/HexabotJoints-v0", makes Gymnasium import it.
`gymnasium.make_vec` of a joint-level id defaults to the batched environment (vector.py: mujoco.rollout);
vectorization_mode="async" or "sync" give Gymnasium's own.
"""

from __future__ import annotations

try:
    import gymnasium
except ImportError as e:  # pragma: no cover - the message is the point
    raise ImportError('hexabot_sim.envs needs gymnasium: pip install "hexabot-sim[rl]"') from e

from hexabot_sim.envs.ids import ENVS, NAMESPACE, register


def register_envs() -> None:
    """Registers every environment as hexabot_sim/<id> (again: a no-op)."""
    register(gymnasium)


register_envs()

__all__ = ["ENVS", "NAMESPACE", "register_envs"]
