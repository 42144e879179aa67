"""arm-track: any serial arm (a package robot or a robot file) tracks a task-space path in MuJoCo with gravity.

The robot is the MJCF `hexabot-sim export` writes (qpos = DH q), without gravity compensation; each joint has a
position servo and a velocity servo sized from the joint-space inertia (mj_fullM) and a feedforward motor carrying
MuJoCo's bias force (gravity and Coriolis, qfrc_bias). Resolved-rate control with damped least squares, joint speed
and range limits drives the tool along a line, circle or figure-8; the analytic Jacobian it uses is compared with
MuJoCo's mj_jacSite at every control period.
"""

from __future__ import annotations

import dataclasses
import itertools
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from hexabot_sim.budget import step_count
from hexabot_sim.control.arm_rate import ArmRateController, ArmRateGains, rotation_error
from hexabot_sim.kinematics.numeric_ik import batch_pose_and_jacobian, pose_and_jacobian
from hexabot_sim.result import Live, Marker, Metric, Progress, ScenarioResult
from hexabot_sim.robots.arm import scene
from hexabot_sim.robots.arm.parameters import ArmTrackParams
from hexabot_sim.robots.arm.path import RAMP_TIME, Plan
from hexabot_sim.simulate import Controller, simulate, site_trajectory

if TYPE_CHECKING:
    from matplotlib.figure import Figure

PATH_MARKERS: int = 96  # segments drawn for the desired path in the video


@dataclasses.dataclass
class ArmLoop:
    """A ready-to-run arm-track loop: model at the start pose, the control hook, and what it records."""

    xml: str
    model: mujoco.MjModel
    data: mujoco.MjData
    n_steps: int
    control: Controller
    step: Controller
    plan: Plan
    names: list[str]
    units: tuple[str, ...]
    qadr: list[int]
    dadr: list[int]
    desired: np.ndarray  # (n_steps + 2, 3) the desired tool position at k * timestep
    record: dict[str, np.ndarray]  # per control period: q_cmd, sigma, limits, jac_diff


def prepare(p: ArmTrackParams) -> ArmLoop:
    """Builds the scene, puts the arm at the start pose and wires the resolved-rate controller to its servos."""
    spec = p.SPEC
    chain = spec.chain()
    run_plan = p.PLAN
    frames = np.concatenate(
        [np.stack(chain.frames(run_plan.q), axis=1)[..., :3, 3].reshape(-1, 3), run_plan.path.at(run_plan.t)[0]]
    )
    comment = f"arm-track: {spec.name}" + (f" ({spec.source})" if spec.source and not spec.builtin else "")
    xml, model = scene.build(
        chain, spec.masses, comment, run_plan.q_start, frames, p.timestep, p.servo_bandwidth, p.servo_damping
    )
    data = mujoco.MjData(model)
    names = [j.name for j in chain.joints]
    qadr = [int(model.joint(n).qposadr[0]) for n in names]
    dadr = [int(model.joint(n).dofadr[0]) for n in names]
    pos = [model.actuator(n).id for n in names]
    vel = [model.actuator(f"{n}_velocity").id for n in names]
    bias = [model.actuator(f"{n}_bias").id for n in names]
    tool = model.site("tool").id
    n_steps = step_count(p.duration, p.timestep)
    dt = p.timestep
    desired, _ = run_plan.path.at(np.arange(n_steps + 2) * dt)  # (n_steps + 2, 3)
    feed = np.diff(desired, axis=0) / dt  # (n_steps + 1, 3) the reference's mean velocity over each period
    speed = np.array([p.max_slide_speed if j.prismatic else p.max_joint_speed for j in chain.joints])
    gains = ArmRateGains(
        p.task_gain,
        p.sigma_threshold,
        p.max_damping,
        speed,
        np.full(chain.n, p.max_joint_acceleration),
        p.nullspace_gain,
    )
    controller = ArmRateController(
        pose_and_jacobian(chain),
        gains,
        run_plan.q_start,
        run_plan.lower,
        run_plan.upper,
        run_plan.rows == 6,
        run_plan.q_ref,
    )
    record = {
        "q_cmd": np.zeros((n_steps + 1, chain.n)),
        "sigma": np.full(n_steps + 1, np.nan),
        "limits": np.zeros(n_steps + 1),
        "jac_diff": np.full(n_steps + 1, np.nan),
    }
    record["q_cmd"][0] = run_plan.q_start
    data.qpos[qadr] = run_plan.q_start
    data.ctrl[pos] = run_plan.q_start
    mujoco.mj_forward(model, data)
    data.ctrl[bias] = data.qfrc_bias[dadr]  # the recorded row 0 shows the feedforward holding the start pose
    jacp, jacr = np.zeros((3, model.nv)), np.zeros((3, model.nv))  # (3, nv) each
    counter = [0]
    qpos, ctrl, bias_force = data.qpos, data.ctrl, data.qfrc_bias  # views into mjData, bound once

    def control(model: mujoco.MjModel, data: mujoco.MjData) -> None:
        k = counter[0]
        # Positions, velocities and bias forces at the current state (mj_step2 completes the step).
        mujoco.mj_step1(model, data)
        # Resolved rate from the measured q toward the desired point at the end of the period.
        q_cmd, dq = controller.update(qpos[qadr], desired[k], feed[k], run_plan.rot_hold, dt)
        ctrl[pos], ctrl[vel], ctrl[bias] = q_cmd, dq, bias_force[dadr]
        # The analytic Jacobian against MuJoCo's at the same state.
        mujoco.mj_jacSite(model, data, jacp, jacr, tool)
        jac = controller.jacobian
        diff = max(np.abs(jac[:3] - jacp[:, dadr]).max(), np.abs(jac[3:] - jacr[:, dadr]).max())
        record["jac_diff"][k] = diff
        record["sigma"][k] = controller.sigma_min
        record["q_cmd"][k + 1] = q_cmd
        record["limits"][k + 1] = controller.clipped.sum()
        counter[0] = k + 1

    return ArmLoop(
        xml,
        model,
        data,
        n_steps,
        control,
        mujoco.mj_step2,
        run_plan,
        names,
        spec.joint_units,
        qadr,
        dadr,
        desired,
        record,
    )


def run(name: str, p: ArmTrackParams, progress: Progress | None = None) -> ScenarioResult:
    """Tracks the path with the arm in MuJoCo and measures the tracking error, sigma_min, limits and the J check."""
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
    return _result(name, p, loop, traj)


def _result(name: str, p: ArmTrackParams, loop: ArmLoop, traj) -> ScenarioResult:
    run_plan, n = loop.plan, len(loop.names)
    t = traj.t
    tool = site_trajectory(loop.model, traj, "tool")  # MuJoCo's own tool position, not our FK
    desired = loop.desired[: len(t)]
    err = np.linalg.norm(tool.pos - desired, axis=1)  # (k,)
    rec = loop.record
    # sigma_min and the Jacobian check at the last state (the loop measures before each step).
    sigma, jac_diff = rec["sigma"].copy(), rec["jac_diff"].copy()
    sigma[-1], jac_diff[-1] = _final_check(loop, traj.qpos[-1], p.SPEC.chain())
    near = sigma < p.sigma_threshold
    worst = int(np.argmin(sigma))
    hits = rec["limits"] > 0
    dt = p.timestep
    poses, _ = batch_pose_and_jacobian(p.SPEC.chain(), traj.qpos[:, loop.qadr])
    fk_diff = float(np.abs(poses[:, :3, 3] - tool.pos).max())  # our FK of MuJoCo's qpos against its site: qpos = q
    orient = None
    if run_plan.rot_hold is not None:
        orient = np.array([np.linalg.norm(rotation_error(r, run_plan.rot_hold)) for r in tool.xmat])
    metrics = {
        "tracking_error_rms": Metric(float(np.sqrt(np.mean(err**2))), "m", "RMS of |tool - desired| (MuJoCo's site)"),
        "tracking_error_max": Metric(float(err.max()), "m", "max |tool - desired|"),
        "orientation_error_max": Metric(
            None if orient is None else float(orient.max()),
            "rad",
            "max angle from the held tool orientation (6+ joints; null: position only)",
        ),
        "sigma_min": Metric(float(sigma[worst]), "", "smallest sigma_min of the task Jacobian along the run"),
        "sigma_min_time": Metric(float(t[worst]), "s", "when it was smallest"),
        "sigma_min_point": Metric([float(v) for v in tool.pos[worst]], "m", "where the tool was then"),
        "near_singular_time": Metric(float(near.sum() * dt), "s", "time with sigma_min < sigma_threshold (DLS damps)"),
        "planned_sigma_min": Metric(float(run_plan.sigma.min()), "", "smallest sigma_min of the exact IK on the path"),
        "joint_limit_hits": Metric(
            int(np.sum(np.diff(np.r_[0, hits.astype(int)]) > 0)), "1", "times a joint command reached a range end"
        ),
        "joint_limit_time": Metric(float(hits.sum() * dt), "s", "time some joint command sat at a range end"),
        "jacobian_max_diff": Metric(float(jac_diff.max()), "", "max |analytic J - mj_jacSite| over the run"),
        "fk_max_diff": Metric(fk_diff, "m", "max |analytic FK(qpos) - MuJoCo's tool site| over the run"),
        "centre": Metric([float(v) for v in run_plan.path.centre], "m", "the path's centre"),
        "reference_pose": Metric([float(v) for v in run_plan.q_ref], "", "the best-conditioned pose (rad or m)"),
        "joints": Metric(n, "1", "joints of the robot"),
    }
    q, dq, ctrl = traj.qpos[:, loop.qadr], traj.qvel[:, loop.dadr], traj.ctrl
    columns: dict[str, np.ndarray] = {"t": t}
    units: dict[str, str] = {"t": "s"}
    for i, unit in enumerate(loop.units):
        rate = f"{unit}/s"
        force = "N*m" if unit == "rad" else "N"
        joint = (
            (f"q{i + 1}", q[:, i], unit),
            (f"dq{i + 1}", dq[:, i], rate),
            (f"q{i + 1}_cmd", rec["q_cmd"][:, i], unit),
            (f"tau{i + 1}_ff", ctrl[:, 2 * n + i], force),
        )
        for key, values, u in joint:
            columns[key], units[key] = values, u
    for k, axis in enumerate("xyz"):
        columns[axis], units[axis] = tool.pos[:, k], "m"
        columns[f"{axis}_des"], units[f"{axis}_des"] = desired[:, k], "m"
    columns["error"], units["error"] = err, "m"
    if orient is not None:
        columns["orientation_error"], units["orientation_error"] = orient, "rad"
    columns["sigma_min"], units["sigma_min"] = sigma, ""
    columns["near_singular"], units["near_singular"] = near.astype(float), "1"
    columns["joints_at_limit"], units["joints_at_limit"] = rec["limits"], "1"
    columns["jacobian_diff"], units["jacobian_diff"] = jac_diff, ""
    near_text = ("", "  NEAR-SINGULAR")
    return ScenarioResult(
        scenario=name,
        params=p,
        model=loop.model,
        model_xml=loop.xml,
        trajectory=traj,
        columns=columns,
        column_units=units,
        metrics=metrics,
        summary=["tracking_error_rms", "tracking_error_max", "sigma_min", "joint_limit_hits", "jacobian_max_diff"],
        camera="three_quarter",
        markers=path_markers(run_plan),
        trail=tool.pos,
        overlay=[lambda i: f"error = {err[i] * 1000:7.3f} mm   σmin = {sigma[i]:.3g}{near_text[int(near[i])]}"],
        extras={
            "robot": p.SPEC.name,
            "ranges": (run_plan.lower, run_plan.upper),
            "units": loop.units,
            "worst": worst,
        },
    )


def _final_check(loop: ArmLoop, qpos: np.ndarray, chain) -> tuple[float, float]:
    """sigma_min of the task Jacobian and max |analytic J - mj_jacSite| at the recorded final state."""
    model = loop.model
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    mujoco.mj_kinematics(model, data)
    mujoco.mj_comPos(model, data)
    jacp, jacr = np.zeros((3, model.nv)), np.zeros((3, model.nv))  # (3, nv) each
    mujoco.mj_jacSite(model, data, jacp, jacr, model.site("tool").id)
    _, jac = pose_and_jacobian(chain)(qpos[loop.qadr])
    sigma = float(np.linalg.svd(jac[: loop.plan.rows], compute_uv=False)[-1])
    return sigma, float(max(np.abs(jac[:3] - jacp[:, loop.dadr]).max(), np.abs(jac[3:] - jacr[:, loop.dadr]).max()))


def path_markers(run_plan: Plan) -> list[Marker]:
    """The desired path as PATH_MARKERS segments, for the video and the viewer."""
    ring, _ = run_plan.path.at(np.linspace(RAMP_TIME, RAMP_TIME + run_plan.path.period, PATH_MARKERS + 1))
    return [Marker(tuple(a), tuple(b), 0.0015, (0.9, 0.2, 0.15, 0.6)) for a, b in itertools.pairwise(ring)]


def figures(result: ScenarioResult) -> dict[str, Figure]:
    """The path in 3-D and per axis, the joints, sigma_min (robots/arm/figures.py draws them)."""
    from hexabot_sim.robots.arm.figures import figures as draw

    return draw(result)


def live(p: ArmTrackParams) -> Live:
    """The arm at its start pose with the controller wired in, for the interactive viewer."""
    loop = prepare(p)
    model, data, control, advance = loop.model, loop.data, loop.control, loop.step
    tool = model.site("tool").id
    last = loop.n_steps

    def step() -> None:
        if round(data.time / p.timestep) >= last:  # the reference ends with the run: hold the last command
            mujoco.mj_step(model, data)
            return
        control(model, data)
        advance(model, data)

    def error_text(d: mujoco.MjData) -> str:
        k = min(round(d.time / p.timestep), last)
        return f"error = {np.linalg.norm(d.site_xpos[tool] - loop.desired[k]) * 1000:7.3f} mm"

    return Live(
        model,
        data,
        step,
        p.timestep,
        p.duration,
        camera="three_quarter",
        markers=path_markers(loop.plan),
        trail=lambda d: d.site_xpos[tool],
        overlay=[error_text],
    )
