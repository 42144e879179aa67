"""RRP arm tool velocity (report 001, part 5): q(t) = (sin t, cos 2t, sin 3t), v and w by J(q) dq, checked by MuJoCo."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from hexabot_sim import models, render
from hexabot_sim.budget import step_count
from hexabot_sim.kinematics import robots
from hexabot_sim.kinematics.mjcf import to_mjcf
from hexabot_sim.result import Live, Metric, Progress, ScenarioResult
from hexabot_sim.robots.rrp.parameters import RrpVelocityParams
from hexabot_sim.simulate import Trajectory

if TYPE_CHECKING:
    from matplotlib.figure import Figure

SINGULAR_TOL: float = 1e-9  # |a2 + d3| or |cos q2| below this counts as singular
VIDEO_LINK_RADIUS: float = 0.04  # [m] link capsules of the generated arm (to_mjcf default: 0.02)


def joint_trajectory(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """q(t) = (sin t, cos 2t, sin 3t) and its exact derivative, each (n, 3)."""
    q = np.stack([np.sin(t), np.cos(2 * t), np.sin(3 * t)], axis=1)
    dq = np.stack([np.cos(t), -2 * np.sin(2 * t), 3 * np.cos(3 * t)], axis=1)
    return q, dq


def run(name: str, p: RrpVelocityParams, progress: Progress | None = None) -> ScenarioResult:
    """Tool twist from the analytic Jacobian, and MuJoCo's site velocity while it plays q(t)."""
    chain = robots.get("rrp").chain({"d1": p.d1, "a2": p.a2})
    # The robot regenerated from its DH table with this run's lengths, inside the committed scene.
    # Links twice the default radius: visible in a video of a 4 m wide motion (masses do not enter a
    # kinematic replay: the twist depends on q and dq only).
    robot = to_mjcf(chain, comment="rrp-velocity: report 001 part 5", link_radius=VIDEO_LINK_RADIUS)
    tree = models.load_tree("rrp_scene", replace={"rrp.xml": robot})
    xml = models.to_xml(tree)
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
    frame_sites = [model.site(name).id for name in ("base", "frame1", "frame2", "tool")]
    res = np.zeros(6)  # (6,) [angular, linear]
    mj_twist = np.empty((len(t), 6))  # (n, 6) [linear, angular]
    sites = np.empty((len(t), len(frame_sites), 3))  # (n, 4, 3) the arm's frame origins, for the camera
    for i in range(len(t)):
        data.qpos[addr] = q[i]
        data.qvel[dadr] = dq[i]
        data.time = t[i]
        mujoco.mj_forward(model, data)
        mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_SITE, site, res, 0)
        mj_twist[i, :3], mj_twist[i, 3:] = res[3:], res[:3]
        sites[i] = data.site_xpos[frame_sites]
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
    # Video: the camera framed on the volume the arm's frames and tool swept (visual only, so the
    # recompiled model is the same arm), the tool's path as a trail, q and the speeds as text.
    camera = models.find(tree, "camera", "three_quarter")
    overlay = [
        lambda i: f"q1 = {q[i, 0]:6.3f} rad  q2 = {q[i, 1]:6.3f} rad  d3 = {q[i, 2]:6.3f} m",
        lambda i: f"|v| = {np.linalg.norm(twist[i, :3]):5.2f} m/s  |ω| = {np.linalg.norm(twist[i, 3:]):5.2f} rad/s",
    ]
    xyaxes = [float(v) for v in camera.get("xyaxes", "").split()]
    eye = render.fit_camera(sites.reshape(-1, 3), xyaxes, float(camera.get("fovy", 45)), text_lines=1 + len(overlay))
    camera.set("pos", models.fmt(tuple(eye.tolist())))
    xml = models.to_xml(tree)
    model = mujoco.MjModel.from_xml_string(xml)
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
        trail=sites[:, -1].copy(),
        overlay=overlay,
        extras={"singular": singular, "zero_reach_times": metrics["zero_reach_times"].value},
    )


# ---------------------------------------------------------------------------------------------
# Figures (matplotlib is imported only when they are drawn: `hexabot-sim list` never loads it)


def figures(result: ScenarioResult) -> dict[str, Figure]:
    """Report 001 part 5: the tool's linear and angular velocity in the base frame, and the joints."""
    from hexabot_sim import plots

    c = result.columns
    t = c["t"]
    p = result.params
    fig, (ax1, ax2, ax3, ax4, ax5) = plots.figure(
        5, 1, figsize=(9, 11.5), sharex=True, gridspec_kw={"height_ratios": [2.2, 2.2, 1.2, 1.2, 1.2]}
    )
    mujoco_style: dict[str, Any] = {"linestyle": (0, (1, 2)), "color": "black", "linewidth": 1.2}
    for ax, axes in ((ax1, ("vx", "vy", "vz")), (ax2, ("wx", "wy", "wz"))):
        for axis in axes:
            ax.plot(t, c[axis], label=f"{axis} = (J q̇)_{axis[1]}")
        for n, axis in enumerate(axes):  # drawn over each curve
            ax.plot(t, c[f"{axis}_mujoco"], **mujoco_style, label="MuJoCo site velocity (each)" if n == 0 else None)
        ax.grid(alpha=0.3)
        plots.legend_above(ax, ncol=4)
    ax1.set_ylabel("tool linear velocity [m/s]")
    ax2.set_ylabel("tool angular velocity [rad/s]")
    ax3.plot(t, c["q1"], label="q1")
    ax3.plot(t, c["q2"], label="q2")
    ax3.set_ylabel("revolute joints [rad]")
    ax4.plot(t, c["d3"], color="tab:green", label="d3")
    ax4.plot(t, p.a2 + c["d3"], color="tab:olive", linestyle="--", label="a2 + d3 (0: singular)")
    ax4.set_ylabel("prismatic joint [m]")
    ax5.plot(t, c["det_jv"], color="tab:gray", label="det Jv = (a2 + d3)² cos q2")
    ax5.set_ylabel("det Jv [m²]")
    ax5.set_xlabel("time t [s]")
    singular_times = result.extras.get("zero_reach_times") or []
    for n, ts in enumerate(singular_times):
        for ax in (ax4, ax5):
            ax.axvline(ts, color="tab:red", linestyle=":", linewidth=1, label="a2 + d3 = 0" if n == 0 else None)
    for ax in (ax3, ax4, ax5):
        ax.axhline(0, color="black", linewidth=0.5)
        ax.grid(alpha=0.3)
        plots.plain(ax)
        plots.legend_above(ax, ncol=3)
    fig.suptitle(
        f"{result.scenario}: q = (sin t, cos 2t, sin 3t), d1 = {p.d1:g} m, a2 = {p.a2:g} m; tool velocity in the base "
        "frame",
        fontsize=plots.TITLE_FONTSIZE,
    )
    return {"velocity": fig}


def live(p: RrpVelocityParams) -> Live:
    """The RRP arm playing q(t) = (sin t, cos 2t, sin 3t), for the interactive viewer."""
    chain = robots.get("rrp").chain({"d1": p.d1, "a2": p.a2})
    robot = to_mjcf(chain, comment="rrp-velocity: report 001 part 5", link_radius=VIDEO_LINK_RADIUS)
    model = mujoco.MjModel.from_xml_string(models.to_xml(models.load_tree("rrp_scene", replace={"rrp.xml": robot})))
    data = mujoco.MjData(model)
    addr = [int(model.joint(j.name).qposadr[0]) for j in chain.joints]
    dadr = [int(model.joint(j.name).dofadr[0]) for j in chain.joints]
    tool = model.site("tool").id

    def step() -> None:
        # Kinematic playback: the prescribed q(t) and its derivative, one timestep on.
        q, dq = joint_trajectory(np.array([data.time + p.timestep]))
        data.time += p.timestep
        data.qpos[addr], data.qvel[dadr] = q[0], dq[0]
        mujoco.mj_kinematics(model, data)

    q0, _ = joint_trajectory(np.zeros(1))
    data.qpos[addr] = q0[0]
    mujoco.mj_forward(model, data)
    return Live(
        model, data, step, p.timestep, p.duration, camera="three_quarter",
        trail=lambda d: d.site_xpos[tool], overlay=[lambda d: f"q1 = {d.qpos[addr[0]]:6.3f} rad"],
    )  # fmt: skip
