"""What the test modules share (tests/ is on sys.path: pyproject's [tool.pytest.ini_options] pythonpath)."""

from __future__ import annotations

import math
import re
from typing import Any

import mujoco
import numpy as np

from hexabot_sim import params
from hexabot_sim.cli import main


def cli(capsys: Any, *argv: str) -> tuple[int, str, str]:
    """Runs the command line in this process: (exit code, stdout, stderr)."""
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def walk_params(**overrides: Any) -> Any:
    """hexabot-walk's parameters with these overrides, checked as a run checks them."""
    from hexabot_sim.robots.hexabot.walk import HexabotParams

    return params.resolve(HexabotParams, {}, overrides)


def walk(**overrides: Any) -> Any:
    """A hexabot-walk run (ScenarioResult) with these parameters."""
    from hexabot_sim.robots.hexabot import walk as scenario

    return scenario.run("hexabot-walk", walk_params(**overrides))


def quat_to_matrix(q: Any) -> np.ndarray:
    """MuJoCo's rotation matrix (3, 3) of a quaternion (w, x, y, z)."""
    m = np.zeros(9)
    mujoco.mju_quat2Mat(m, np.asarray(q, float))
    return m.reshape(3, 3)


def foot_and_jacobian_errors(scene: str, layout: Any, samples: int, xml: str | None = None) -> tuple[float, float]:
    """Worst |foot site - analytic FK| and |mj_jacSite - analytic Jacobian| of a legged model at random joint
    angles and body poses: the layout's body-frame maths (kinematics/legged.py), rotated by the body, and each
    leg's own DH FK in its hip site (the leg's frame 0). `xml`: the model's text instead of models/<scene>.xml."""
    from hexabot_sim import models
    from hexabot_sim.kinematics import leg as leg_kin
    from hexabot_sim.kinematics import legged

    if xml is None:
        model = mujoco.MjModel.from_xml_path(str(models.model_path(scene)))
    else:
        model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    rng = np.random.default_rng(7)
    lower, upper = np.array(legged.JOINT_LOWER), np.array(legged.JOINT_UPPER)
    worst_p = worst_j = 0.0
    jacp = np.zeros((3, model.nv))  # (3, nv)
    for _ in range(samples):
        q = rng.uniform(lower, upper, size=(layout.n_legs, 3))
        quat = rng.normal(size=4)
        quat /= np.linalg.norm(quat)
        pos = rng.uniform(-1, 1, 3)
        data.qpos[:] = np.r_[pos, quat, q.ravel()]
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        rot = quat_to_matrix(quat)
        feet = pos + legged.feet_body(layout, q) @ rot.T
        jac_body = legged.jacobians_body(layout, q)
        for i, leg in enumerate(layout.legs):
            worst_p = max(worst_p, np.abs(data.site(f"{leg}_foot").xpos - feet[i]).max())
            mujoco.mj_jacSite(model, data, jacp, None, model.site(f"{leg}_foot").id)
            dofs = [model.joint(f"{leg}_{j}").dofadr[0] for j in legged.JOINTS]
            worst_j = max(worst_j, np.abs(jacp[:, dofs] - rot @ jac_body[i]).max())
            hip = data.site(f"{leg}_hip")
            local = hip.xmat.reshape(3, 3).T @ (data.site(f"{leg}_foot").xpos - hip.xpos)
            worst_p = max(worst_p, np.abs(local - leg_kin.fk(q[i], layout.geometry)).max())
    return worst_p, worst_j


# Random DH tables as robot files (tests/kinematics: FK, J and IK of files; the MJCF and URDF exports).


def random_table(rng: np.random.Generator, n: int, convention: str, angles: str) -> dict:
    unit = 180 / math.pi if angles == "deg" else 1.0
    joints = []
    for i in range(n):
        kind = "prismatic" if rng.random() < 0.3 else "revolute"
        row = {"name": f"j{i + 1}", "type": kind, "a": float(rng.uniform(-0.5, 0.5)),
               "d": float(rng.uniform(-0.5, 0.5)), "theta": float(rng.uniform(-math.pi, math.pi) * unit),
               "alpha": float(rng.uniform(-math.pi, math.pi) * unit)}  # fmt: skip
        if kind == "prismatic":
            row["lower"], row["upper"] = -0.3, 0.4
        else:
            row["lower"], row["upper"] = -0.9 * math.pi * unit, 0.9 * math.pi * unit
        joints.append(row)

    def frame() -> dict:
        return {"xyz": rng.uniform(-0.3, 0.3, 3).tolist(), "rpy": (rng.uniform(-math.pi, math.pi, 3) * unit).tolist()}

    return {"name": "random", "convention": convention, "angles": angles, "joints": joints, "tool": frame(),
            "base": frame()}  # fmt: skip


def to_toml(table: dict) -> str:
    lines = [f'name = "{table["name"]}"', f'convention = "{table["convention"]}"', f'angles = "{table["angles"]}"']
    for row in table["joints"]:
        lines.append("[[joints]]")
        lines += [f"{k} = {v!r}" if not isinstance(v, str) else f'{k} = "{v}"' for k, v in row.items()]
    for key in ("tool", "base"):
        lines += [f"[{key}]", f"xyz = {table[key]['xyz']!r}", f"rpy = {table[key]['rpy']!r}"]
    return "\n".join(lines) + "\n"


def random_q(table: dict, rng: np.random.Generator) -> np.ndarray:
    scale = math.pi / 180 if table["angles"] == "deg" else 1.0
    return np.array([
        rng.uniform(r["lower"], r["upper"]) * (1.0 if r["type"] == "prismatic" else scale) for r in table["joints"]
    ])  # fmt: skip


def staging_left(folder: Any) -> list[Any]:
    """The staging folders a run left under `folder` (a run publishes atomically: none should be left)."""
    return [p for p in folder.rglob(".hexabot-sim-*")]


def metric(result: Any, name: str) -> Any:
    """A run's metric value by name."""
    return result.metrics[name].value


def compiled_scene(p: Any) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """A walk's scene (hexabot or quadbot parameters) compiled, its start state forwarded."""
    from hexabot_sim.walking import scene

    model = mujoco.MjModel.from_xml_string(scene.build_xml(p))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data


def one_line_error(err: str) -> str:
    """The single error line of stderr, progress lines ('pendulum: 50% (5/10)') aside."""
    lines = [line for line in err.strip().splitlines() if not re.match(r"^[\w-]+: \d+% \(\d+/\d+\)$", line)]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]
