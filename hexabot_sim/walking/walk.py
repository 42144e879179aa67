"""A legged robot walking on contact physics: run, analyse and watch live (each robot's scenario module binds its
parameter class to these, e.g. robots/hexabot/walk.py)."""

from __future__ import annotations

import dataclasses
import math
import time

import mujoco
import numpy as np

from hexabot_sim.budget import step_count
from hexabot_sim.control.commands import Steering, steering_acceleration
from hexabot_sim.kinematics import legged
from hexabot_sim.result import Live, Metric, Progress, ScenarioResult, at_home
from hexabot_sim.simulate import simulate
from hexabot_sim.walking import commands, course
from hexabot_sim.walking.constants import SETTLE_TIME
from hexabot_sim.walking.figures import _moving_mean, figures
from hexabot_sim.walking.forces import force_metrics
from hexabot_sim.walking.ground import terrain
from hexabot_sim.walking.metrics import (
    in_plane,
    replay_contacts,
    rpy_from_quat,
    steady_window,
    terrain_metrics,
    velocity_in_plane,
    walk_warnings,
    walking_metrics,
    walking_up,
)
from hexabot_sim.walking.parameters import WalkParams, feasibility
from hexabot_sim.walking.scene import build_xml, make_controller
from hexabot_sim.walking.steering import KeySteering

__all__ = ["analyse", "figures", "live", "run"]


def run(name: str, p: WalkParams, progress: Progress | None = None) -> ScenarioResult:
    """Stands the robot on its neutral stance, then walks with the command and records everything."""
    xml = build_xml(p)
    model, data = at_home(xml)
    controller = make_controller(p, model, data)
    n_steps = step_count(p.duration, p.timestep)
    started = time.perf_counter()
    traj = simulate(model, data, n_steps, controller=controller, progress=progress, record_ctrl=True)
    wall = time.perf_counter() - started
    return analyse(name, p, model, xml, traj, controller, wall)


def analyse(name, p, model, xml, traj, controller, wall) -> ScenarioResult:
    """Columns, metrics and figure data of a walk."""
    t, qpos, qvel, ctrl = traj.t, traj.qpos, traj.qvel, traj.ctrl
    legs = p.ROBOT.layout.legs
    contacts = replay_contacts(model, t, qpos, qvel, ctrl, legs)
    total_mass = float(model.body_subtreemass[model.body("torso").id])
    ground = terrain(p)
    up = walking_up(p, ground)  # speeds, headings and distances along the slope walked with level_body=off
    plane = in_plane(qpos, up)
    metrics = walking_metrics(p, t, qpos, qvel, contacts, total_mass, ground, plane)
    gait = commands.start_gait(p)  # a schedule's first row's gait replaces the walk's
    changes = len({row.gait for row in commands.setpoints(p)}) > 1 if p.schedule else False
    duty = Metric(gait.duty, "1", "stance fraction of the gait cycle")
    if changes:
        duty = Metric(None, "1", f"{duty.doc}; null here: the schedule changes gait (each walked at its own duty)")
    metrics |= {
        "stride": Metric(math.hypot(p.vx, p.vy) * gait.duty * p.period, "m", "body travel per stance at the command"),
        "duty": duty,
        "real_time_factor": Metric(t[-1] / wall, "1", "simulated time / wall time of the simulation loop"),
    }
    loaded = contacts.loaded(total_mass)
    planned = controller.planned_stance(t)  # (n, n_legs)
    if not ground.flat or p.on_ground():  # flat runs with the planned controller keep their metrics as they were
        metrics |= terrain_metrics(p, ground, t, qpos, controller, plane)
    window = steady_window(p, t)
    weight = total_mass * 9.81
    metrics |= force_metrics(contacts.load[window], loaded[window], planned[window], p.timestep, weight, legs)
    extras = course_results(p, t, qpos, qvel, contacts, controller, total_mass, metrics)
    rpy = rpy_from_quat(qpos[:, 3:7])
    # Command in force at every row: the chunk's command (re-planned every chunk) times the ramp's factor.
    plan_t = np.array([c[0] for c in controller.commands])
    idx = np.clip(np.searchsorted(plan_t, t, side="right") - 1, 0, len(plan_t) - 1)
    plan = np.array([c[1:] for c in controller.commands])[idx] * np.asarray(controller.scale(t))[:, None]
    heading = rpy_from_quat(plane[:, 3:7])[:, 2]
    vel = velocity_in_plane(qvel, up)
    c, s = np.cos(heading), np.sin(heading)
    vx_b = c * vel[:, 0] + s * vel[:, 1]
    vy_b = -s * vel[:, 0] + c * vel[:, 1]
    columns: dict[str, np.ndarray] = {"t": t, "x": qpos[:, 0], "y": qpos[:, 1], "z": qpos[:, 2]}
    columns |= {"roll": rpy[:, 0], "pitch": rpy[:, 1], "yaw": np.unwrap(rpy[:, 2])}
    columns |= {"vx_body": vx_b, "vy_body": vy_b, "yaw_rate": qvel[:, 5]}
    columns |= {"cmd_vx": plan[:, 0], "cmd_vy": plan[:, 1], "cmd_yaw_rate": plan[:, 2]}
    for i, leg in enumerate(legs):
        columns[f"contact_{leg}"] = loaded[:, i].astype(float)
    for i, leg in enumerate(legs):
        columns[f"force_{leg}"] = contacts.load[:, i]
    for i, leg in enumerate(legs):
        columns[f"force_t_{leg}"] = contacts.tangential[:, i]
    for i, leg in enumerate(legs):
        for j, joint in enumerate(legged.JOINTS):
            columns[f"q_{leg}_{joint}"] = qpos[:, 7 + 3 * i + j]
    units = {"t": "s", "x": "m", "y": "m", "z": "m", "roll": "rad", "pitch": "rad", "yaw": "rad"}
    units |= {"vx_body": "m/s", "vy_body": "m/s", "yaw_rate": "rad/s", "cmd_vx": "m/s", "cmd_vy": "m/s"}
    units |= {"cmd_yaw_rate": "rad/s"}
    units |= {k: "N" for k in columns if k.startswith("force_")}
    units |= {k: ("1" if k.startswith("contact_") else "rad") for k in columns if k not in units}
    if p.schedule:  # each row's steady twist (needs the columns)
        more, table = course.schedule_metrics(p, t, columns, SETTLE_TIME)
        metrics |= more
        extras["schedule_table"] = table
    trail = qpos[:, :3].copy()
    trail[:, 2] = ground.height(trail[:, 0], trail[:, 1]) + 0.002  # the body's path drawn on the ground
    period_rows = max(1, round(p.period / p.timestep))
    speed = np.hypot(_moving_mean(vx_b, period_rows), _moving_mean(vy_b, period_rows))
    switches = [(-math.inf, gait.name), *controller.planner.switches]  # the gait in force at each row
    cmd_speed = np.hypot(plan[:, 0], plan[:, 1])
    walked = np.searchsorted([s for s, _ in switches], t, side="right") - 1
    names = [name for _, name in switches]
    overlay = [
        lambda k: f"{names[walked[k]]} gait, speed {speed[k] * 1000:.0f} mm/s (command {cmd_speed[k] * 1000:.0f})",
        lambda k: "feet down: " + " ".join(leg for i, leg in enumerate(legs) if loaded[k, i]),
    ]
    return ScenarioResult(
        scenario=name,
        params=p,
        model=model,
        model_xml=xml,
        trajectory=traj,
        columns=columns,
        column_units=units,
        metrics=metrics,
        summary=["mean_vx", "mean_vy", "mean_yaw_rate", "lateral_drift", "heading_drift", "slip_per_stance", "fell"],
        warnings=walk_warnings(metrics, p.ROBOT.torque_limit, math.hypot(p.vx, p.vy)),
        camera="slope" if p.slope_deg else "track",
        trail=trail,
        overlay=overlay,
        extras={
            "contacts": contacts,
            "planned_stance": planned,
            "window": window,
            "terrain": ground,
            "touchdowns": getattr(controller, "events", []),
        }
        | extras,
    )


def course_results(p, t, qpos, qvel, contacts, controller, total_mass, metrics) -> dict:
    """With a schedule or waypoints: the whole-walk errors against vx, vy, yaw_rate made null (the command
    changes), a course's metrics added; the extras the figures need."""
    if not (p.schedule or p.waypoints):
        return {}
    extras: dict = {"gait_switches": list(controller.planner.switches)}
    why = "the command changes during the walk (schedule or waypoints): see the schedule_ or course_ metrics"
    # With them the terrain's speed_made_good_error and the stride (the walk's own vx, vy, which they replace: a
    # schedule standing still read -100 %, a crab at 0.08 m/s that made 0.078 m/s -22 %).
    keys = ("vx_error", "vy_error", "yaw_rate_error", "speed_abs_error", "lateral_drift", "heading_drift")
    for key in (*keys, "speed_made_good_error", "stride"):
        m = metrics.get(key)
        if m is not None:
            doc = m.doc.split("; null here: ")[0]  # its own reason (e.g. vy commanded 0) is not this walk's
            metrics[key] = dataclasses.replace(m, value=None, doc=f"{doc}; null here: {why}")
    if not p.waypoints:
        return extras
    power = np.abs(contacts.torque * qvel[:, 6 : 6 + contacts.torque.shape[1]]).sum(axis=1)
    metrics |= course.course_metrics(p, t, qpos, controller.source, power, total_mass, SETTLE_TIME)
    return extras | {"follower": controller.source}


def live(p: WalkParams) -> Live:
    """The robot on its neutral stance with its walking controller, for the interactive viewer; without a schedule
    or waypoints, steered by keys (walking/steering.py)."""
    model, data = at_home(build_xml(p))
    keys = None
    if not (p.schedule or p.waypoints):
        steering = Steering(p.command(), p.gait, p.step_height, p.stand_height, start=SETTLE_TIME,
                            acceleration=steering_acceleration(p.period))  # fmt: skip
        keys = KeySteering(p, steering, feasibility)
    # The same controller a run uses (terrain, levelling), its command from the keys.
    controller = make_controller(p, model, data, source=None if keys is None else keys.steering)

    def step() -> None:
        controller(model, data)
        mujoco.mj_step(model, data)

    def speed_text(d: mujoco.MjData) -> str:
        gait = controller.planner.gait.name
        return f"{gait} gait, speed {math.hypot(d.qvel[0], d.qvel[1]) * 1000:4.0f} mm/s, x = {d.qpos[0]:6.3f} m"

    def summary(d: mujoco.MjData) -> str:
        yaw = rpy_from_quat(np.asarray(d.qpos[3:7])[None])[0, 2]
        state = f"body at x = {d.qpos[0]:.3f} m, y = {d.qpos[1]:.3f} m, yaw = {yaw:.3f} rad"
        return f"{state}, {controller.planner.gait.name} gait; {keys.text().splitlines()[0]}" if keys else state

    ground = terrain(p)

    def trail(d: mujoco.MjData) -> np.ndarray:
        return np.array([d.qpos[0], d.qpos[1], float(ground.height(d.qpos[0], d.qpos[1])) + 0.002])

    return Live(
        model, data, step, p.timestep, p.duration, camera="slope" if p.slope_deg else "track", track_body="torso",
        trail=trail, overlay=[speed_text, *([lambda d: keys.text()] if keys else [])],
        keys=None if keys is None else keys.key, key_help=keys.help if keys else (), summary=summary,
    )  # fmt: skip
