"""Hexabot leg forward step (reports 000, 002, 004): resolved-rate control of the foot along the ground X axis."""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from hexabot_sim.budget import step_count
from hexabot_sim.control.resolved_rate import ResolvedRateController, ResolvedRateGains
from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics import leg as leg_kin
from hexabot_sim.result import Live, Marker, Metric, Progress, ScenarioResult
from hexabot_sim.robots.leg.model import build_xml
from hexabot_sim.robots.leg.parameters import GEOMETRY, LegStepParams, reachable
from hexabot_sim.simulate import Controller, simulate, site_trajectory

if TYPE_CHECKING:
    from matplotlib.figure import Figure

JOINTS = ("coxa", "femur", "tibia")
# In dynamic mode the servos overshoot a commanded speed transient by ~2 % (measured with the
# defaults driven out of the workspace): the command keeps this margin below max_joint_speed.
SERVO_SPEED_MARGIN: float = 0.95


def reference(p: LegStepParams, start: np.ndarray):
    """x_des(t) in the hip frame: the integral of the velocity command from the start point."""
    x0, y0, z0 = (float(v) for v in start)
    a, w = p.amplitude, p.omega
    if p.profile == "sine":
        return lambda t: (x0 + a / w * (1.0 - math.cos(w * t)), y0, z0)
    return lambda t: (x0 + a / w * math.sin(w * t), y0, z0)


def reference_velocity(p: LegStepParams, t: np.ndarray) -> np.ndarray:
    """v_x,des(t) [m/s]."""
    return p.amplitude * (np.sin(p.omega * t) if p.profile == "sine" else np.cos(p.omega * t))


REACH_TOL: float = 1e-7  # [m] resolution of line_reach


def line_reach(start: np.ndarray, geom: leg_kin.LegGeometry = GEOMETRY) -> tuple[float, float]:
    """How far the foot can travel along +x and -x from `start` inside the workspace [m].

    Walks out in 1 mm steps while every point has an IK solution inside the joint ranges, then
    bisects the last step down to REACH_TOL.
    """
    out = []
    for direction in (1.0, -1.0):
        inside, step = 0.0, 1e-3
        while inside < 1.0 and reachable(start + np.array([direction * (inside + step), 0.0, 0.0]), geom):
            inside += step
        outside = inside + step
        while outside - inside > REACH_TOL:
            mid = 0.5 * (inside + outside)
            if reachable(start + np.array([direction * mid, 0.0, 0.0]), geom):
                inside = mid
            else:
                outside = mid
        out.append(inside)
    return out[0], out[1]


def excursion(p: LegStepParams) -> tuple[float, float]:
    """Largest travel (forward, backward) [m] the command asks for within the run's duration: up to 2A/w (sine) or
    A/w each way (cosine), less in a run shorter than the half or three quarters of a cycle that takes (a 1 s run at
    w = 0.52 rad/s was said to leave a workspace it stays well inside). The travel's extremes lie at multiples of
    pi / w (sine) or odd multiples of pi / 2w (cosine), or at the end."""
    w, first = p.omega, (0.0 if p.profile == "sine" else 0.5 * math.pi)
    turns = first / w + (math.pi / w) * np.arange(0, max(0, math.floor((p.duration * w - first) / math.pi)) + 1)
    t = np.concatenate([[0.0, p.duration], turns[turns <= p.duration]])
    offsets = reference(p, np.zeros(3))
    x = np.array([offsets(float(v))[0] for v in t])
    return max(0.0, float(x.max())), max(0.0, float(-x.min()))


def start_pose(p: LegStepParams, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """IK of the start point on the branch inside the joint ranges (front of the coxa, knee out)."""
    target = np.array([p.start_x, p.start_y, p.start_z])
    try:
        branches = leg_kin.ik(target, p.geometry, q1=0.0)  # q1 = 0 if the start is on the coxa axis
    except UsageError as e:
        raise UsageError(f"start pose {tuple(target.tolist())} m is outside the workspace: {e}") from None
    inside = [q for q in branches if np.all(q >= lower - 1e-12) and np.all(q <= upper + 1e-12)]
    if not inside:
        raise UsageError(
            f"start pose {tuple(target.tolist())} m is reachable only outside the joint ranges "
            f"(coxa, femur within +-90 deg, tibia 0..160 deg)"
        )
    return min(inside, key=lambda q: (-q[2] > 0, abs(q[0])))


@dataclasses.dataclass
class LegLoop:
    """A ready-to-run leg-step loop: model and state at the start pose, controller hook and step function."""

    xml: str
    model: mujoco.MjModel
    data: mujoco.MjData
    n_steps: int
    control: Controller
    step: Controller
    start: np.ndarray  # (3,) start foot position, hip frame [m]
    qadr: list[int]
    dadr: list[int]


def run(name: str, p: LegStepParams, progress: Progress | None = None) -> ScenarioResult:
    """Drives the foot along the hip-frame X axis with the resolved-rate controller."""
    loop = prepare(p)
    traj = simulate(
        loop.model,
        loop.data,
        loop.n_steps,
        controller=loop.control,
        step=loop.step,
        progress=progress,
        record_ctrl=True,
    )
    return _result(name, p, loop.model, loop.xml, traj, loop.start, loop.qadr, loop.dadr)


def prepare(p: LegStepParams) -> LegLoop:
    """Builds the model, puts the leg at the start pose and wires the controller to the servos."""
    xml = build_xml(p)
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    qadr = [int(model.joint(j).qposadr[0]) for j in JOINTS]
    dadr = [int(model.joint(j).dofadr[0]) for j in JOINTS]
    lower = np.array([model.jnt_range[model.joint(j).id][0] for j in JOINTS])
    upper = np.array([model.jnt_range[model.joint(j).id][1] for j in JOINTS])
    q0 = start_pose(p, lower, upper)
    start = np.array([p.start_x, p.start_y, p.start_z])

    controller = ResolvedRateController(
        p.geometry,
        ResolvedRateGains(
            p.task_gain,
            p.sigma_threshold,
            p.max_damping,
            p.max_joint_speed * (SERVO_SPEED_MARGIN if p.mode == "dynamic" else 1.0),
            p.max_joint_acceleration,
        ),
        reference(p, start),
        tuple(q0.tolist()),
        tuple(lower.tolist()),
        tuple(upper.tolist()),
    )
    pos_act = [model.actuator(j).id for j in JOINTS]
    vel_act = [model.actuator(f"{j}_velocity").id for j in JOINTS]
    if pos_act + vel_act != list(range(6)) or qadr != [0, 1, 2]:
        raise ValueError("leg.xml must list the position then the velocity actuators of coxa, femur, tibia first")
    data.qpos[qadr] = q0
    data.ctrl[pos_act] = q0
    mujoco.mj_forward(model, data)
    dt = p.timestep  # control period; MuJoCo steps p.substeps times per period

    qpos, ctrl = data.qpos, data.ctrl  # views into mjData, bound once

    def control(model: mujoco.MjModel, data: mujoco.MjData) -> None:
        # Measure q, advance the command, hand it to the servos (position + velocity feedforward).
        ctrl[:] = controller.update(qpos.tolist(), data.time, dt)

    def kinematic_step(model: mujoco.MjModel, data: mujoco.MjData) -> None:
        # The report's Simulink: the integrated q is imposed, no dynamics.
        data.qpos[qadr] = controller.q_cmd
        data.qvel[dadr] = controller.dq
        data.time += dt
        mujoco.mj_kinematics(model, data)

    substeps = range(p.substeps)

    def dynamic_step(model: mujoco.MjModel, data: mujoco.MjData) -> None:
        for _ in substeps:
            mujoco.mj_step(model, data)

    step = dynamic_step if p.mode == "dynamic" else kinematic_step
    return LegLoop(xml, model, data, step_count(p.duration, p.timestep), control, step, start, qadr, dadr)


def _result(name, p, model, xml, traj, start, qadr, dadr) -> ScenarioResult:
    t = traj.t
    q = traj.qpos[:, qadr]  # (n, 3)
    dq = traj.qvel[:, dadr]  # (n, 3)
    foot = site_trajectory(model, traj, "foot")
    data = mujoco.MjData(model)
    mujoco.mj_kinematics(model, data)
    hip_pos = data.site("hip").xpos.copy()
    hip_rot = data.site("hip").xmat.reshape(3, 3).copy()

    ref = reference(p, start)
    des_hip = np.array([ref(float(ti)) for ti in t])  # (n, 3) hip frame
    des = hip_pos + des_hip @ hip_rot.T  # (n, 3) world
    vdes = np.zeros((len(t), 3))
    vdes[:, 0] = reference_velocity(p, t)
    vdes = vdes @ hip_rot.T
    geom = p.geometry
    det_j = leg_kin.det_jacobian(q, geom)
    sig_min, _ = leg_kin.singular_values(q, geom)
    foot_rot = np.einsum("ij,njk->nik", hip_rot.T, foot.xmat)  # (n, 3, 3) foot orientation in the hip frame
    roll, pitch, yaw = leg_kin.rpy(foot_rot)
    near = sig_min < p.sigma_threshold

    err = foot.pos - des
    x_dir, y_dir, z_dir = hip_rot[:, 0], hip_rot[:, 1], hip_rot[:, 2]
    start_world = hip_pos + hip_rot @ start
    lateral = (foot.pos - start_world) @ y_dir
    vertical = (foot.pos - start_world) @ z_dir
    x_err = err @ x_dir
    reach_fwd, reach_back = line_reach(start, geom)
    exc_fwd, exc_back = excursion(p)

    first = float(t[np.argmax(near)]) if near.any() else None
    family = None
    if near.any():
        i = int(np.argmax(near))
        rho = float(np.hypot(*leg_kin.fk(q[i], geom)[:2]))
        family = (
            "foot on the coxa axis (rho = 0)" if rho < p.sigma_threshold else "knee stretched or folded (sin q3 = 0)"
        )
    dt = float(np.median(np.diff(t)))
    metrics = {
        "max_lateral_deviation": Metric(
            float(np.max(np.abs(lateral))), "m", "max |y - y0|: sideways drift off the line"
        ),
        "max_vertical_deviation": Metric(float(np.max(np.abs(vertical))), "m", "max |z - z0|: vertical drift"),
        "max_x_error": Metric(float(np.max(np.abs(x_err))), "m", "max |x - x_des| along the line"),
        "max_tracking_error": Metric(float(np.max(np.linalg.norm(err, axis=1))), "m", "max |foot - foot_des|"),
        "min_abs_det_j": Metric(float(np.min(np.abs(det_j))), "m^3/rad^3", "smallest |det J| along the run"),
        "min_sigma": Metric(float(np.min(sig_min)), "m/rad", "smallest singular value of J along the run"),
        "max_joint_speed_reached": Metric(float(np.max(np.abs(dq))), "rad/s", "largest |dq_i|"),
        "singular_first_time": Metric(first, "s", "first time sigma_min(J) < sigma_threshold (null: never)"),
        "singular_duration": Metric(float(near.sum() * dt), "s", "time spent with sigma_min(J) < sigma_threshold"),
        "singular_family": Metric(family, "", "which singular set was approached first"),
        "excursion_forward": Metric(
            exc_fwd, "m", "travel the command asks for along +x within the run: up to 2A/omega (sine)"
        ),
        "reach_forward": Metric(reach_fwd, "m", "travel along +x before leaving the reachable workspace"),
        "excursion_backward": Metric(exc_back, "m", "travel the command asks for along -x within the run"),
        "reach_backward": Metric(reach_back, "m", "travel along -x before leaving the workspace (coxa near 0)"),
        "predicted_to_leave_workspace": Metric(
            bool(exc_fwd > reach_fwd or exc_back > reach_back), "", "excursion exceeds reach (before running)"
        ),
    }
    columns = {
        "t": t,
        "q1": q[:, 0],
        "q2": q[:, 1],
        "q3": q[:, 2],
        "dq1": dq[:, 0],
        "dq2": dq[:, 1],
        "dq3": dq[:, 2],
        "foot_x": foot.pos[:, 0],
        "foot_y": foot.pos[:, 1],
        "foot_z": foot.pos[:, 2],
        "foot_x_des": des[:, 0],
        "foot_y_des": des[:, 1],
        "foot_z_des": des[:, 2],
        "vx": foot.vel[:, 0],
        "vy": foot.vel[:, 1],
        "vz": foot.vel[:, 2],
        "vx_des": vdes[:, 0],
        "vy_des": vdes[:, 1],
        "vz_des": vdes[:, 2],
        "det_j": det_j,
        "sigma_min": sig_min,
        "roll": roll,
        "pitch": pitch,
        "yaw": yaw,
        "near_singular": near.astype(float),
    }
    units = {k: "rad" for k in ("q1", "q2", "q3", "roll", "pitch", "yaw")}
    units |= {k: "rad/s" for k in ("dq1", "dq2", "dq3")}
    units |= {k: "m" for k in columns if k.startswith("foot_")}
    units |= {k: "m/s" for k in columns if k.startswith("v")}
    units |= {"t": "s", "det_j": "m^3/rad^3", "sigma_min": "m/rad", "near_singular": "1"}
    return ScenarioResult(
        scenario=name,
        params=p,
        model=model,
        model_xml=xml,
        trajectory=traj,
        columns=columns,
        column_units={k: units[k] for k in columns},
        metrics=metrics,
        summary=[
            "max_lateral_deviation",
            "max_vertical_deviation",
            "max_x_error",
            "min_abs_det_j",
            "singular_first_time",
            "singular_family",
        ],
        camera="three_quarter",
        markers=[
            Marker(
                tuple(des[0]),
                tuple(start_world + x_dir * (exc_fwd if exc_fwd else 0) - x_dir * exc_back),
                0.0015,
                (0.9, 0.2, 0.15, 0.6),
            )
        ],
        trail=foot.pos,
        overlay=[
            lambda i: f"foot x = {foot.pos[i, 0] * 1000:6.1f} mm  target {des[i, 0] * 1000:6.1f} mm",
            lambda i: f"σ_min = {sig_min[i] * 1000:8.3g} mm/rad" + ("  NEAR-SINGULAR" if near[i] else ""),
        ],
        extras={
            "foot_world": foot.pos,
            "near_singular": near,
            "start_world": start_world,
            "hip": hip_pos,
            "orientation_continuous": leg_kin.continuous_zyx(foot_rot),
        },
    )


# ---------------------------------------------------------------------------------------------
# Figures (matplotlib is imported only when they are drawn: `hexabot-sim list` never loads it)


def figures(result: ScenarioResult) -> dict[str, Figure]:
    """The scenario's figures (robots/leg/figures.py draws them; imported when asked for)."""
    from hexabot_sim.robots.leg.figures import figures as draw

    return draw(result)


def live(p: LegStepParams) -> Live:
    """The leg at its start pose with the resolved-rate controller wired in, for the interactive viewer."""
    loop = prepare(p)
    model, data, control, advance = loop.model, loop.data, loop.control, loop.step
    hip_pos = data.site("hip").xpos.copy()
    hip_rot = data.site("hip").xmat.reshape(3, 3).copy()
    start_world = hip_pos + hip_rot @ loop.start
    forward, backward = excursion(p)
    x_dir = hip_rot[:, 0]
    target_line = Marker(
        tuple(start_world - backward * x_dir), tuple(start_world + forward * x_dir), 0.0015, (0.9, 0.2, 0.15, 0.6)
    )
    ref = reference(p, loop.start)
    foot = model.site("foot").id

    def step() -> None:
        control(model, data)
        advance(model, data)

    def foot_text(d: mujoco.MjData) -> str:
        target = hip_pos + hip_rot @ np.array(ref(float(d.time)))
        return f"foot x = {d.site_xpos[foot][0] * 1000:6.1f} mm  target {target[0] * 1000:6.1f} mm"

    return Live(
        model, data, step, p.timestep, p.duration, camera="three_quarter", markers=[target_line],
        trail=lambda d: d.site_xpos[foot], overlay=[foot_text],
    )  # fmt: skip
