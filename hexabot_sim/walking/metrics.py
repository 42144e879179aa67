"""What a walk measured: speed, drift, slip, attitude, contacts and terrain figures of merit."""

from __future__ import annotations

import dataclasses
import math

import mujoco
import numpy as np

from hexabot_sim.control.walker import WalkingController
from hexabot_sim.result import Metric
from hexabot_sim.terrain import Ground
from hexabot_sim.walking import commands, forces
from hexabot_sim.walking.constants import FALL_TILT_DEG, LOADED_FRACTION, SETTLE_TIME
from hexabot_sim.walking.ground import largest_climbable_kerb, walking_direction
from hexabot_sim.walking.parameters import WalkParams


def rpy_from_quat(quat: np.ndarray) -> np.ndarray:
    """Roll, pitch, yaw (..., 3) [rad] (z-y-x Euler angles) of unit quaternions (..., 4) (w, x, y, z)."""
    w, x, y, z = (quat[..., i] for i in range(4))
    roll = np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = np.arcsin(np.clip(2 * (w * y - z * x), -1.0, 1.0))
    yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return np.stack([roll, pitch, yaw], axis=-1)


def walking_up(p: WalkParams, ground: Ground | None) -> np.ndarray:
    """The normal of the plane the body walks in: the slope's where it follows the ground (level_body=off), else up."""
    return ground.normal() if ground is not None and p.level_body == "off" else _VERTICAL


def _plane_turn(up: np.ndarray) -> np.ndarray | None:
    """The least rotation (w, x, y, z) taking the vertical to `up` (mju_quatZ2Vec); None for the vertical itself."""
    if np.array_equal(up, _VERTICAL):
        return None
    turn = np.zeros(4)
    mujoco.mju_quatZ2Vec(turn, np.asarray(up, dtype=float))
    return turn


def _turn_matrix(turn: np.ndarray) -> np.ndarray:
    flat = np.zeros(9)
    mujoco.mju_quat2Mat(flat, turn)
    return flat.reshape(3, 3)  # plane -> world


def in_plane(qpos: np.ndarray, up: np.ndarray) -> np.ndarray:
    """The floating base's pose (qpos (n, >=7)) in the frame of the plane walked in: z along `up`, turned from the
    world by the least rotation. On a slope walked with level_body=off the body moves along the slope, and its speed,
    heading and distances are the slope's (horizontal ones read 1 - cos(slope) short: -14 % at 30 deg); on level
    ground, or with a level body, `qpos` itself."""
    turn = _plane_turn(up)
    if turn is None:
        return qpos
    out = qpos.copy()
    out[:, :3] = qpos[:, :3] @ _turn_matrix(turn)  # rows: R^T p
    w0, x0, y0, z0 = turn[0], -turn[1], -turn[2], -turn[3]  # the inverse turn, then the body's attitude
    w, x, y, z = (qpos[:, 3 + i] for i in range(4))
    out[:, 3] = w0 * w - x0 * x - y0 * y - z0 * z
    out[:, 4] = w0 * x + x0 * w + y0 * z - z0 * y
    out[:, 5] = w0 * y - x0 * z + y0 * w + z0 * x
    out[:, 6] = w0 * z + x0 * y - y0 * x + z0 * w
    return out


def velocity_in_plane(qvel: np.ndarray, up: np.ndarray) -> np.ndarray:
    """The floating base's linear velocity (qvel (n, >=3), its first three) in the frame of in_plane."""
    turn = _plane_turn(up)
    if turn is None:
        return qvel
    out = qvel.copy()
    out[:, :3] = qvel[:, :3] @ _turn_matrix(turn)
    return out


@dataclasses.dataclass(frozen=True)
class Contacts:
    """Per recorded row: foot loads, contact-point slip, joint torques, body-ground contact."""

    load: np.ndarray  # (n, n_legs) normal force of each foot [N]: mj_contactForce's normal, summed over its contacts
    tangential: np.ndarray  # (n, n_legs) tangential (friction) force of each foot [N]: |f_t| summed over its contacts
    slip: np.ndarray  # (n, n_legs) horizontal speed of the foot's material point at its contact [m/s]
    point: np.ndarray  # (n, n_legs, 3) contact point [m] (NaN where the foot is off the ground)
    torque: np.ndarray  # (n, 3 n_legs) joint actuator torque [N m]
    body_contact: np.ndarray  # (n,) the plate touches the ground

    def touchdowns(self, columns: dict[str, np.ndarray], legs: tuple[str, ...]) -> list[np.ndarray]:
        """Per leg, the contact points (k, 3) [m] at the rows where its foot became loaded (the CSV's contact_<leg>)."""
        loaded = np.stack([columns[f"contact_{leg}"] for leg in legs], axis=1) > 0.5
        return [self.point[np.flatnonzero(np.diff(loaded[:, i].astype(int)) == 1) + 1, i] for i in range(len(legs))]

    def loaded(self, total_mass: float) -> np.ndarray:
        """(n, n_legs) the feet that carry load: more than LOADED_FRACTION of their share of the robot's weight."""
        return self.load > LOADED_FRACTION * total_mass * 9.81 / self.load.shape[1]


def replay_contacts(
    model: mujoco.MjModel,
    t: np.ndarray,
    qpos: np.ndarray,
    qvel: np.ndarray,
    ctrl: np.ndarray,
    legs: tuple[str, ...],
) -> Contacts:
    """Recomputes contacts, slip and torques at every recorded row with mj_forward (the recorded state in);
    `legs`: the robot's leg names (its geoms `<leg>_foot`, bodies `<leg>_tibia`)."""
    data = mujoco.MjData(model)
    n = len(t)
    foot_geoms = {model.geom(f"{leg}_foot").id: i for i, leg in enumerate(legs)}
    tibia = [model.body(f"{leg}_tibia").id for leg in legs]
    torso_geom = model.geom("torso").id
    m = len(legs)
    load = np.zeros((n, m))
    tangential = np.zeros((n, m))
    slip = np.zeros((n, m))
    point = np.full((n, m, 3), np.nan)
    torque = np.empty((n, 3 * m))
    body_contact = np.zeros(n, dtype=bool)
    force = np.zeros(6)  # mj_contactForce's wrench
    jacp = np.zeros((3, model.nv))  # (3, nv)
    for k in range(n):
        data.qpos[:], data.qvel[:], data.ctrl[:] = qpos[k], qvel[k], ctrl[min(k + 1, n - 1)]
        data.time = t[k]
        mujoco.mj_forward(model, data)
        torque[k] = data.qfrc_actuator[6 : 6 + 3 * m]
        if not data.ncon:
            continue
        # The contact list's fields read once a row as arrays, not a wrapper made per contact (measured: a 20 s walk
        # on 1 cm rough ground, 10,001 rows, replayed in 1.06 s instead of 1.64 s, the same arrays bit for bit).
        contacts = data.contact
        geom1, geom2, pos = contacts.geom1.tolist(), contacts.geom2.tolist(), contacts.pos
        for c, (g1, g2) in enumerate(zip(geom1, geom2, strict=True)):
            leg = foot_geoms.get(g1, foot_geoms.get(g2))
            if g1 == torso_geom or g2 == torso_geom:
                body_contact[k] = True
            if leg is None:
                continue
            mujoco.mj_contactForce(model, data, c, force)
            load[k, leg] += force[0]
            tangential[k, leg] += math.hypot(force[1], force[2])
            # Velocity of the foot's material point at the contact: the tibia body's Jacobian at that point.
            mujoco.mj_jac(model, data, jacp, None, pos[c], tibia[leg])
            v = jacp @ data.qvel
            slip[k, leg] = math.hypot(v[0], v[1])
            point[k, leg] = pos[c]
    return Contacts(load=load, tangential=tangential, slip=slip, point=point, torque=torque, body_contact=body_contact)


def steady_window(p: WalkParams, t: np.ndarray) -> np.ndarray:
    """Rows of the steady walk: after settling, the ramp and one more period, whole cycles to the end."""
    start = SETTLE_TIME + 2 * p.period
    cycles = math.floor((t[-1] - start) / p.period + 1e-9)
    if cycles < 1:  # a short run: whatever follows the ramp
        start, end = SETTLE_TIME + p.period, t[-1]
    else:
        end = start + cycles * p.period
    return (t >= start - 1e-9) & (t <= end + 1e-9)


# A ratio is reported only where its denominator is well above what it is measured against (else null, with why).
# The standing robot creeps at ~0.05 mm/s and its body sways a few mm within every gait cycle, so a relative speed
# error needs a command of at least 1 mm/s (1 mrad/s for turning), and a per-metre figure 0.1 m of travel.
LEAST_SPEED: float = 1e-3  # [m/s] or [rad/s]

LEAST_TRAVEL: float = 0.1  # [m]


def _relative_error(measured: float, commanded: float) -> float | None:
    return None if abs(commanded) < LEAST_SPEED else (measured - commanded) / abs(commanded)


def _per_travel(amount: float, travelled: float) -> float | None:
    return amount / travelled if travelled >= LEAST_TRAVEL else None


def _null_why(metric: Metric, why: str) -> Metric:
    """`metric` with the reason appended to its doc when its value is null."""
    return metric if metric.value is not None else dataclasses.replace(metric, doc=f"{metric.doc}; null here: {why}")


def planned_stand_heights(p: WalkParams, t: np.ndarray) -> np.ndarray:
    """The stand height (n,) [m] planned at the times t: a schedule's rows' as the walker ramps them (the walk's own
    stand_height measured a schedule at 0.08 then 0.11 m against 0.09 m: a sag of -19 mm), else the walk's."""
    if p.schedule:
        return commands.source(p, SETTLE_TIME).heights(t)[1]
    return np.full(np.shape(t), p.stand_height)


_VERTICAL = np.array([0.0, 0.0, 1.0])
SATURATED: float = 1 - 1e-9  # a joint torque at this share of the limit (or more) is at the limit
SPEED_WARNING: float = 0.5  # a mean velocity further off the command than this share of its speed is warned of
STILL_DRIFT_WARNING: float = 0.01  # [m/s] a mean drift above this where no speed is commanded is warned of
SATURATION_WARNING: float = 0.25  # saturated in more of the steps is warned of (stairs 6 %, quadbot-trot-rough 10 %)
FELL_DOC = (
    f"the plate touched the ground or tilted beyond {FALL_TILT_DEG:g} deg from the attitude it walks in (the "
    "slope's, or level with level_body=on)"
)


def walking_metrics(
    p: WalkParams,
    t: np.ndarray,
    qpos: np.ndarray,
    qvel: np.ndarray,
    contacts: Contacts,
    total_mass: float,
    ground: Ground | None,
    plane: np.ndarray,
) -> dict[str, Metric]:
    """The walking metrics of a run, from its recorded state and contacts, on its ground (None: the flat floor);
    `plane`: qpos in the plane walked in (in_plane), for the speeds, headings and distances."""
    # The attitude the body walks in: its tilt is measured from it (the slope's normal where it follows the ground).
    up = walking_up(p, ground)
    window = steady_window(p, t)
    dt = p.timestep
    rpy = rpy_from_quat(qpos[:, 3:7])
    yaw = np.unwrap(rpy_from_quat(plane[:, 3:7])[:, 2])
    w = np.flatnonzero(window)
    i0, i1 = w[0], w[-1]
    duration = t[i1] - t[i0]
    # Body-frame velocity: world displacement over the window, rotated into the mean heading... per step.
    vel_world = np.diff(plane[:, :2], axis=0) / np.diff(t)[:, None]  # (n-1, 2)
    mid_yaw = 0.5 * (yaw[1:] + yaw[:-1])
    c, s = np.cos(mid_yaw), np.sin(mid_yaw)
    v_body = np.stack([c * vel_world[:, 0] + s * vel_world[:, 1], -s * vel_world[:, 0] + c * vel_world[:, 1]], -1)
    steps = slice(i0, i1)
    mean_vx, mean_vy = (float(v) for v in v_body[steps].mean(axis=0))
    mean_yaw_rate = float((yaw[i1] - yaw[i0]) / duration)
    # Drift: along / across the commanded direction in the world, over the window.
    disp = plane[i1, :2] - plane[i0, :2]
    distance = float(np.hypot(*disp))
    # Distance walked, for the cost of transport: the body's path sampled once a gait period (the sway within a cycle
    # left out). A straight walk's equals its displacement (to 1e-5); an arc's, a schedule's or a course's is what
    # was walked, where the displacement (0.19 m for the 6.3 m figure-eight) made the cost 30x too high.
    rows = np.r_[np.arange(i0, i1, max(1, round(p.period / dt))), i1]
    walked = float(np.hypot(*np.diff(plane[rows, :2], axis=0).T).sum())
    speed_cmd = math.hypot(p.vx, p.vy)
    if speed_cmd > 0 and p.yaw_rate == 0:
        heading0 = yaw[0]
        along = np.array([p.vx, p.vy]) / speed_cmd
        along = np.array([math.cos(heading0) * along[0] - math.sin(heading0) * along[1],
                          math.sin(heading0) * along[0] + math.cos(heading0) * along[1]])  # fmt: skip
        across = np.array([-along[1], along[0]])
        path = plane[i0 : i1 + 1, :2] - plane[i0, :2]
        travelled = float(path[-1] @ along)
        lateral = float(path[-1] @ across)
        lateral_drift = _per_travel(lateral, travelled)
        heading_drift = _per_travel(float(np.degrees(yaw[i1] - yaw[i0])), travelled)
        short = f"travelled {travelled:.3g} m along the command, under the {LEAST_TRAVEL:g} m a per-metre figure needs"
    else:
        lateral_drift = heading_drift = None
        short = "not a straight walk (no speed commanded, or turning)"
    slow = f"commanded under {LEAST_SPEED:g} (m/s or rad/s): the robot's own creep would dominate the ratio"
    # Height and attitude.
    height_cmd = planned_stand_heights(p, t[window]) + p.ROBOT.layout.foot_radius
    z = qpos[window, 2]
    # The body's height above the slope and the steps under it, along `up` (the planned height's direction; not
    # above the rough patch's bumps, which the feet's plane averages): a 20 deg slope walked down read a 64 mm sag.
    smooth = None if ground is None else dataclasses.replace(ground, rough=None)
    above = z if smooth is None or smooth.flat else (z - smooth.height(qpos[window, 0], qpos[window, 1])) * up[2]
    roll, pitch = np.degrees(rpy[window, 0]), np.degrees(rpy[window, 1])
    # Slip of loaded feet, per stance.
    loaded = contacts.loaded(total_mass)
    slip_loaded = contacts.slip[window][loaded[window]]
    slip_distance = float((contacts.slip[window] * loaded[window]).sum() * dt)
    # Touchdowns: the stances' starts with the bounces bridged (forces.stances); counted as loaded rising edges,
    # every bounce was a stance, and a walk whose feet bounced showed a fraction of its slip per stance.
    touchdowns = sum(start > 0 for leg in loaded[window].T for start, _ in forces.stances(leg, dt, whole=False))
    # Energy: positive and negative joint work both cost (hobby servos do not recover energy).
    power = np.abs(contacts.torque * qvel[:, 6 : 6 + contacts.torque.shape[1]]).sum(axis=1)
    work = float(power[window].sum() * dt)
    w_, x_, y_, z_ = qpos[:, 3:7].T  # the body's z axis in the world, against `up` (a 45 deg slope walked with
    # the body on it, 45.08 deg from the vertical, read as a fall)
    axis = np.stack([2 * (x_ * z_ + w_ * y_), 2 * (y_ * z_ - w_ * x_), 1 - 2 * (x_**2 + y_**2)], axis=1)
    tilt = np.degrees(np.arccos(np.clip(axis @ np.asarray(up, dtype=float), -1.0, 1.0)))
    falls = contacts.body_contact | (tilt > FALL_TILT_DEG)
    fell = bool(falls.any())
    peak_torque = float(np.abs(contacts.torque).max())
    # A joint of a loaded leg at its limit (actuatorfrcrange clamps the servo's torque there): the weight asks more
    # than the servos have. A swing foot pushing on a stair's riser also saturates, and is not counted.
    at_limit = np.abs(contacts.torque) >= SATURATED * p.ROBOT.torque_limit  # (n, 3 n_legs)
    leg_at_limit = at_limit.reshape(len(t), -1, 3).any(axis=2)  # (n, n_legs)
    saturated = (leg_at_limit & loaded).any(axis=1)
    return {
        "mean_vx": Metric(mean_vx, "m/s", "mean body-frame forward speed over the steady walk"),
        "mean_vy": Metric(mean_vy, "m/s", "mean body-frame sideways speed over the steady walk"),
        "mean_yaw_rate": Metric(mean_yaw_rate, "rad/s", "mean turning rate over the steady walk"),
        "vx_error": _null_why(Metric(_relative_error(mean_vx, p.vx), "1", "(mean_vx - vx) / |vx|"), slow),
        "vy_error": _null_why(Metric(_relative_error(mean_vy, p.vy), "1", "(mean_vy - vy) / |vy|"), slow),
        "yaw_rate_error": _null_why(
            Metric(_relative_error(mean_yaw_rate, p.yaw_rate), "1", "(mean_yaw_rate - yaw_rate) / |yaw_rate|"), slow
        ),
        "speed_abs_error": Metric(
            float(math.hypot(mean_vx - p.vx, mean_vy - p.vy)), "m/s", "|mean planar velocity - command|"
        ),
        "distance": Metric(distance, "m", "straight-line distance covered over the steady walk"),
        "lateral_drift": _null_why(
            Metric(
                None if lateral_drift is None else lateral_drift * 1000,
                "mm/m",
                "sideways deviation from the commanded direction per metre travelled (straight walks)",
            ),
            short,
        ),
        "heading_drift": _null_why(
            Metric(heading_drift, "deg/m", "heading change per metre travelled (straight walks)"), short
        ),
        "body_height_mean": Metric(float(z.mean()), "m", "mean body height over the steady walk"),
        "body_height_sag": Metric(
            float((height_cmd - above).mean()), "m", "planned body height minus the mean height (over a slope or steps)"
        ),
        "body_height_ptp": Metric(float(np.ptp(z)), "m", "peak-to-peak body height over the steady walk"),
        "roll_ptp": Metric(float(np.ptp(roll)), "deg", "peak-to-peak body roll over the steady walk"),
        "pitch_ptp": Metric(float(np.ptp(pitch)), "deg", "peak-to-peak body pitch over the steady walk"),
        "slip_mean": Metric(
            float(slip_loaded.mean()) if slip_loaded.size else 0.0,
            "m/s",
            "mean speed of the loaded feet's contact points (material point of the foot)",
        ),
        "slip_p95": Metric(
            float(np.percentile(slip_loaded, 95)) if slip_loaded.size else 0.0,
            "m/s",
            "95th percentile of the loaded feet's contact-point speed",
        ),
        "slip_per_stance": _null_why(
            Metric(
                slip_distance / touchdowns * 1000 if touchdowns else None,
                "mm",
                "contact-point sliding distance per stance (a bounce is not a stance)",
            ),
            "no stance began inside the steady walk's window (a period longer than the window); slip_mean has the "
            "feet's sliding",
        ),
        "cost_of_transport": _null_why(
            Metric(
                work / (total_mass * 9.81 * walked) if walked >= LEAST_TRAVEL else None,
                "1",
                "joint work |tau dq| / (m g distance walked) over the steady walk (the body's path, once a period)",
            ),
            f"walked {walked:.3g} m, under the {LEAST_TRAVEL:g} m a per-distance figure needs",
        ),
        "peak_joint_torque": Metric(peak_torque, "N*m", "largest joint torque of the run"),
        "torque_limit_fraction": Metric(
            peak_torque / p.ROBOT.torque_limit, "1", f"peak_joint_torque / the {p.ROBOT.torque_limit} N*m limit"
        ),
        "torque_saturated_fraction": Metric(
            float(saturated.mean()), "1", "share of the steps in which a joint of a loaded leg is at its torque limit"
        ),
        "fell": Metric(fell, "", FELL_DOC),
        "fell_at": _null_why(
            Metric(round(float(t[np.argmax(falls)]), 9) if fell else None, "s", "the time of the first row that fell"),
            "the robot did not fall",
        ),
    }


def _percent(share: float) -> str:
    return f"{100 * share:.3g} %" if share < 10 else f"{100 * share:.0f} %"  # 1530 %, not 1.53e+03 %


def walk_warnings(metrics: dict[str, Metric], torque_limit: float, speed: float) -> list[str]:
    """What the walk's figures say against it: a fall, a walk far off its command (the feet slid down a slope, say),
    swings that found no ground, servos held at their torque limit. `speed`: the command's planar speed [m/s]."""
    out = []
    if metrics["fell"].value:
        out.append(f"the robot fell at t = {metrics['fell_at'].value:.3g} s ({FELL_DOC}); the walk's figures from "
                   "then on are not a walk's")  # fmt: skip
    off = metrics["speed_abs_error"].value  # None where the command changes (a schedule, waypoints)
    still = metrics.get("schedule_still_drift_max", Metric(None, "m/s", "")).value
    if off is not None and speed < LEAST_SPEED:  # standing or turning on the spot: the drift itself
        still = off
    if still is not None and still > STILL_DRIFT_WARNING:
        out.append(f"the body drifted at {still:.3g} m/s where it was told to stand or turn on the spot: the feet "
                   "slid, or the walk went astray")  # fmt: skip
    if off is not None and speed >= LEAST_SPEED and off > SPEED_WARNING * speed:
        out.append(f"the body's mean velocity is {off:.3g} m/s off the commanded {speed:.3g} m/s "
                   f"({_percent(off / speed)}; mean_vx {metrics['mean_vx'].value:.3g}, mean_vy "
                   f"{metrics['mean_vy'].value:.3g} m/s): the feet slid, or the walk stalled")  # fmt: skip
    row = metrics.get("schedule_speed_error_max", Metric(None, "1", "")).value
    if row is not None and row > SPEED_WARNING:
        out.append(f"a schedule row's mean velocity is {_percent(row)} off its command (schedule_speed_error_max): "
                   "the feet slid, or the walk stalled")  # fmt: skip
    left, length = (metrics.get(k, Metric(None, "m", "")).value for k in ("course_distance_left", "course_length"))
    if left is not None and length is not None and not metrics["course_arrived"].value and left > length:
        out.append(f"the body ended {left:.3g} m from the last waypoint, further than the whole {length:.3g} m "
                   "course: the feet slid, or the walk went astray")  # fmt: skip
    lost = metrics.get("feet_without_ground", Metric(0, "1", "")).value
    if lost:
        loaded = metrics["stance_loaded_fraction"].value
        out.append(f"{lost} swing{'s' if lost > 1 else ''} found no ground within the legs' reach "
                   "(feet_without_ground): the ground fell away further than the legs reach down (a level body "
                   "walking downhill, say)" + ("" if loaded is None else
                   f"; the stance feet carried load {100 * loaded:.3g} % of their planned stance"))  # fmt: skip
    share = metrics["torque_saturated_fraction"].value
    if share > SATURATION_WARNING:
        out.append(f"the servos saturate: a joint of a loaded leg was at its {torque_limit:g} N m torque limit in "
                   f"{100 * share:.3g} % of the steps, so carrying the robot asks more than they have (a lighter "
                   "robot, a gentler command or stronger servos: torque_limit in a robot file)")  # fmt: skip
    return out


TOUCHDOWN_TOLERANCE: float = 0.02  # [s] a touchdown further than this from the plan counts as early or late


def terrain_metrics(
    p: WalkParams,
    ground: Ground,
    t: np.ndarray,
    qpos: np.ndarray,
    controller: WalkingController,
    plane: np.ndarray,
) -> dict[str, Metric]:
    """Attitude relative to gravity, height above the local ground, progress (along `plane`, qpos in the plane walked
    in), touchdowns and levelling limits (how often the stance feet carry load is a foot-force metric of every walk:
    walking/forces.py)."""
    window = steady_window(p, t)
    rpy = np.degrees(rpy_from_quat(qpos[window, 3:7]))  # z-y-x angles: roll and pitch are relative to gravity
    roll, pitch = rpy[:, 0], rpy[:, 1]
    above = qpos[window, 2] - ground.height(qpos[window, 0], qpos[window, 1])
    w = np.flatnonzero(window)
    i0, i1 = w[0], w[-1]
    along = walking_direction(p)
    made_good = float((plane[i1, :2] - plane[i0, :2]) @ along)
    speed = math.hypot(p.vx, p.vy)
    speed_made_good = made_good / (t[i1] - t[i0])
    events = [e for e in getattr(controller, "events", []) if e.planned > SETTLE_TIME]
    touched = np.array([e.touched - e.planned for e in events if math.isfinite(e.touched)])
    updates = getattr(controller, "updates", 0)
    return {
        "roll_peak": Metric(float(np.abs(roll).max()), "deg", "largest |body roll| relative to gravity (steady walk)"),
        "pitch_peak": Metric(float(np.abs(pitch).max()), "deg", "largest |body pitch| relative to gravity"),
        "roll_rms": Metric(float(np.sqrt(np.mean(roll**2))), "deg", "RMS body roll relative to gravity"),
        "pitch_rms": Metric(float(np.sqrt(np.mean(pitch**2))), "deg", "RMS body pitch relative to gravity"),
        "height_above_ground_mean": Metric(
            float(above.mean()), "m", "body origin above the ground straight under it (mean over the steady walk)"
        ),
        "height_above_ground_ptp": Metric(float(np.ptp(above)), "m", "peak-to-peak height above the local ground"),
        "distance_made_good": Metric(
            made_good,
            "m",
            "progress along the commanded direction over the steady walk (horizontal; along the "
            "slope's plane with level_body=off)",
        ),
        "speed_made_good": Metric(speed_made_good, "m/s", "distance_made_good / its time"),
        "speed_made_good_error": _null_why(
            Metric(_relative_error(speed_made_good, speed), "1", "(speed_made_good - |command|) / |command|"),
            f"commanded under {LEAST_SPEED:g} m/s: the robot's own creep would dominate the ratio",
        ),
        "touchdowns": Metric(len(events), "1", "swings that ended after the settling time"),
        "touchdown_error_mean": _null_why(
            Metric(float(touched.mean()) if touched.size else None, "s", "touch time - planned touchdown, mean"),
            "no swing ended on the ground after the settling time",
        ),
        "touchdown_error_max": _null_why(
            Metric(
                float(np.abs(touched).max()) if touched.size else None, "s", "largest |touch time - planned touchdown|"
            ),
            "no swing ended on the ground after the settling time",
        ),
        "early_touchdowns": Metric(
            int((touched < -TOUCHDOWN_TOLERANCE).sum()),
            "1",
            f"feet that touched more than {TOUCHDOWN_TOLERANCE * 1000:g} ms before the plan",
        ),
        "late_touchdowns": Metric(
            int((touched > TOUCHDOWN_TOLERANCE).sum()),
            "1",
            f"feet that touched more than {TOUCHDOWN_TOLERANCE * 1000:g} ms after the plan",
        ),
        "feet_without_ground": Metric(
            len(events) - int(touched.size), "1", "swings that found no ground by the end of the leg's reach"
        ),
        "level_clipped_fraction": Metric(
            controller.clipped_updates / updates if updates else 0.0,
            "1",
            "fraction of stance-height updates clipped to the legs' workspace",
        ),
        "largest_climbable_kerb": Metric(
            largest_climbable_kerb(p), "m", "highest kerb this gait can climb (step height and workspace)"
        ),
    }
