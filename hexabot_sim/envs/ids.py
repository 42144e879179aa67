"""The environment ids and their registration with Gymnasium, importable without the package (standard library only).

Gymnasium 1.x finds no plugins by itself (0.26-0.29 read the `gymnasium.envs` entry point; 1.0 removed that), so
the wheel installs `hexabot_sim_gymnasium.pth` into site-packages. At interpreter start it runs this file, found
on sys.path as hexabot_sim/envs/ids.py (not by importing `hexabot_sim`, whose import has side effects such as
choosing MuJoCo's OpenGL backend; it imports nothing more than the interpreter already has), and calls
`install_import_hook`: when a program first imports gymnasium, the hook registers our ids right after gymnasium's
own, as strings (entry points Gymnasium imports on `make`). So after `pip install "hexabot-sim[rl]"`,
`gymnasium.make("hexabot_sim/HexabotJoints-v0")` works without importing hexabot_sim first, and a program that
never imports gymnasium pays nothing but this file's load. HEXABOT_SIM_NO_AUTOREGISTER=1 (any value but 0, false,
no, off or empty) turns the hook off (the "hexabot_sim.envs:" prefix and `import hexabot_sim.envs` register the
ids in any case).
"""

import os
import sys

NAMESPACE: str = "hexabot_sim"

JOINTS = "hexabot_sim.envs.joints:LeggedJointsEnv"
ROLLOUT = "hexabot_sim.envs.vector:LeggedJointsVectorEnv"  # make_vec's default for the joint-level ids
# id -> (entry point, vector entry point or None, kwargs, max_episode_steps): a robot is a keyword, not a class.
ENVS: dict[str, tuple[str, str | None, dict, int]] = {
    "HexabotJoints-v0": (JOINTS, ROLLOUT, {"robot": "hexabot"}, 1000),
    "QuadbotJoints-v0": (JOINTS, ROLLOUT, {"robot": "quadbot"}, 1000),
    "HexabotCommand-v0": ("hexabot_sim.envs.command:LeggedCommandEnv", None, {"robot": "hexabot"}, 200),
}
OPT_OUT: str = "HEXABOT_SIM_NO_AUTOREGISTER"
_OPT_OUT_OFF = ("", "0", "false", "no", "off")  # values that leave the hook on (any other turns it off)


def register(gymnasium) -> None:  # no annotations needing __future__: this file loads at interpreter start
    """Registers every environment as hexabot_sim/<id> with this gymnasium module (again: a no-op)."""
    for name, (entry_point, vector_entry_point, kwargs, steps) in ENVS.items():
        env_id = f"{NAMESPACE}/{name}"
        if env_id not in gymnasium.registry:
            gymnasium.register(
                id=env_id, entry_point=entry_point, vector_entry_point=vector_entry_point, kwargs=dict(kwargs),
                max_episode_steps=steps,
            )  # fmt: skip


class _Loader:
    """gymnasium's own loader, which registers our ids once it has executed gymnasium. A wrapper for the import
    only: exec_module gives the module and its spec back their own loader first, so nothing afterwards (resources,
    copy, pickle, isinstance) sees this one; until then every other attribute is the original loader's."""

    def __init__(self, loader) -> None:
        self._loader = loader

    def __getattr__(self, name: str):
        if name == "_loader":  # not set (an instance made without __init__): no endless recursion
            raise AttributeError(name)
        return getattr(self._loader, name)

    def create_module(self, spec):
        return self._loader.create_module(spec)

    def exec_module(self, module) -> None:
        if getattr(module, "__loader__", None) is self:
            module.__loader__ = self._loader
        spec = getattr(module, "__spec__", None)
        if spec is not None and spec.loader is self:
            spec.loader = self._loader
        self._loader.exec_module(module)
        try:
            register(module)
        except Exception:  # never break the import of gymnasium; the "hexabot_sim.envs:" prefix still works
            pass


class _Finder:
    """A one-shot meta-path finder: on the first import of gymnasium, its real spec with the registering loader."""

    hexabot_sim_autoregister = True  # the mark of every copy (site-packages seen twice, e.g. through lib64, runs
    # the .pth twice, and each run makes its own module and class)

    def find_spec(self, fullname: str, path=None, target=None):
        if fullname != "gymnasium":
            return None
        _remove()
        if _opted_out():  # set by the program since the interpreter started (a notebook's first cell)
            return None
        try:
            import importlib.util  # here, not at interpreter start (it costs a few ms)

            spec = importlib.util.find_spec("gymnasium")  # the other finders' answer
        except Exception:
            return None
        if spec is not None and spec.loader is not None and hasattr(spec.loader, "exec_module"):
            spec.loader = _Loader(spec.loader)  # type: ignore[assignment]  # duck-typed: exec_module and the rest
        return spec


def _remove() -> None:
    sys.meta_path[:] = [f for f in sys.meta_path if not getattr(f, "hexabot_sim_autoregister", False)]


def _opted_out() -> bool:
    return os.environ.get(OPT_OUT, "").strip().lower() not in _OPT_OUT_OFF


def install_import_hook() -> None:
    """Registers the ids with gymnasium now if it is imported, else when it first is (see the module's docstring)."""
    if _opted_out():
        return
    gymnasium = sys.modules.get("gymnasium")
    if gymnasium is not None:
        register(gymnasium)
        return
    _remove()
    sys.meta_path.insert(0, _Finder())
