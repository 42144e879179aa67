"""RRP arm tool velocity (report 001, part 5): q(t) = (sin t, cos 2t, sin 3t), v and w by J(q) dq, checked by MuJoCo."""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np

from hexabot_sim import models
from hexabot_sim.kinematics import robots
from hexabot_sim.kinematics.mjcf import to_mjcf
from hexabot_sim.params import check_duration, param
from hexabot_sim.scenarios.base import Metric, Progress, ScenarioResult
from hexabot_sim.simulate import Trajectory, step_count

SINGULAR_TOL: float = 1e-9  # |a2 + d3| or |cos q2| below this counts as singular


@dataclasses.dataclass(frozen=True)
class RrpVelocityParams:
    """Parameters of the rrp-velocity scenario (joint trajectory fixed by the report)."""

    d1: float = param(1.0, "m", "height of the q2 axis (report: 1 m)", "positive")
    a2: float = param(1.0, "m", "offset of the prismatic stage (report: 1 m)", "positive")
    duration: float = param(20.0, "s", "t from 0 to duration (report: 20 s)", "positive")
    timestep: float = param(0.001, "s", "sample period", "positive")

    def __post_init__(self) -> None:
        check_duration(self.duration, self.timestep, 2_000_000)


def joint_trajectory(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """q(t) = (sin t, cos 2t, sin 3t) and its exact derivative, each (n, 3)."""
    q = np.stack([np.sin(t), np.cos(2 * t), np.sin(3 * t)], axis=1)
    dq = np.stack([np.cos(t), -2 * np.sin(2 * t), 3 * np.cos(3 * t)], axis=1)
    return q, dq


def run(name: str, p: RrpVelocityParams, progress: Progress | None = None) -> ScenarioResult:
    """Tool twist from the analytic Jacobian, and MuJoCo's site velocity while it plays q(t)."""
    chain = robots.get("rrp").chain({"d1": p.d1, "a2": p.a2})
    # The robot regenerated from its DH table with this run's lengths, inside the committed scene.
    robot = to_mjcf(chain, comment="rrp-velocity: report 001 part 5")
    xml = models.to_xml(models.load_tree("rrp_scene", replace={"rrp.xml": robot}))
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    n = step_count(p.duration, p.timestep)
    t = np.arange(n + 1) * p.timestep  # (n,)
    q, dq = joint_trajectory(t)

    # Analytic: twist = J(q) dq with the geometric Jacobian of the DH chain, base frame.
    twist = np.einsum("nij,nj->ni", np.array([chain.jacobian(qi) for qi in q]), dq)  # (n, 6)

    # MuJoCo: play q(t), dq(t) into qpos/qvel and read the tool site's velocity (mj_objectVelocity).
    addr = [int(model.joint(j.name).qposadr[0]) for j in chain.joints]
    dadr = [int(model.joint(j.name).dofadr[0]) for j in chain.joints]
    site = model.site("tool").id
    res = np.zeros(6)  # (6,) [angular, linear]
    mj_twist = np.empty((len(t), 6))  # (n, 6) [linear, angular]
    for i in range(len(t)):
        data.qpos[addr] = q[i]
        data.qvel[dadr] = dq[i]
        data.time = t[i]
        mujoco.mj_forward(model, data)
        mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_SITE, site, res, 0)
        mj_twist[i, :3], mj_twist[i, 3:] = res[3:], res[:3]
        if progress is not None and i % 2000 == 0:
            progress(i, len(t) - 1)

    a2_d3 = p.a2 + q[:, 2]
    det_jv = a2_d3**2 * np.cos(q[:, 1])  # closed form, tested against numpy.linalg.det
    singular = np.abs(det_jv) < SINGULAR_TOL
    lin_diff = float(np.max(np.abs(twist[:, :3] - mj_twist[:, :3])))
    ang_diff = float(np.max(np.abs(twist[:, 3:] - mj_twist[:, 3:])))
    zero_reach = np.flatnonzero((a2_d3[1:-1] < a2_d3[:-2]) & (a2_d3[1:-1] <= a2_d3[2:])) + 1  # minima of a2 + d3
    metrics = {
        "max_linear_speed": Metric(float(np.max(np.linalg.norm(twist[:, :3], axis=1))), "m/s", "max |v|"),
        "max_angular_speed": Metric(float(np.max(np.linalg.norm(twist[:, 3:], axis=1))), "rad/s", "max |w|"),
        "max_linear_diff_mujoco": Metric(lin_diff, "m/s", "max |J dq - MuJoCo site velocity|, linear"),
        "max_angular_diff_mujoco": Metric(ang_diff, "rad/s", "max |J dq - MuJoCo site velocity|, angular"),
        "min_abs_det_jv": Metric(float(np.min(np.abs(det_jv))), "m^2", "smallest |det Jv| = (a2 + d3)^2 |cos q2|"),
        "zero_reach_times": Metric(
            [float(t[i]) for i in zero_reach if a2_d3[i] < 1e-4], "s", "samples nearest to a2 + d3 = 0 (singular)"
        ),
        "singular_samples": Metric(int(singular.sum()), "1", f"samples with |det Jv| < {SINGULAR_TOL:g}"),
    }
    columns = {"t": t, "q1": q[:, 0], "q2": q[:, 1], "d3": q[:, 2], "dq1": dq[:, 0], "dq2": dq[:, 1], "dd3": dq[:, 2]}
    for k, axis in enumerate(("vx", "vy", "vz", "wx", "wy", "wz")):
        columns[axis] = twist[:, k]
    for k, axis in enumerate(("vx", "vy", "vz", "wx", "wy", "wz")):
        columns[f"{axis}_mujoco"] = mj_twist[:, k]
    columns["det_jv"] = det_jv
    units = {"t": "s", "q1": "rad", "q2": "rad", "d3": "m", "dq1": "rad/s", "dq2": "rad/s", "dd3": "m/s"}
    units |= {k: ("m/s" if k.startswith("v") else "rad/s") for k in columns if k[0] in "vw"}
    units["det_jv"] = "m^2"
    qpos = np.zeros((len(t), model.nq))
    qpos[:, addr] = q
    qvel = np.zeros((len(t), model.nv))
    qvel[:, dadr] = dq
    return ScenarioResult(
        scenario=name,
        params=p,
        model=model,
        model_xml=xml,
        trajectory=Trajectory(t=t, qpos=qpos, qvel=qvel),
        columns=columns,
        column_units={k: units[k] for k in columns},
        metrics=metrics,
        summary=["max_linear_speed", "max_angular_speed", "max_linear_diff_mujoco", "max_angular_diff_mujoco"],
        camera="three_quarter",
        figures="rrp_velocity",
        extras={"singular": singular},
    )
