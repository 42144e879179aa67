"""A walk's figures: path, gait diagram, velocity, body attitude, slip, terrain."""

from __future__ import annotations

import math
from typing import Any

import mujoco
import numpy as np

from hexabot_sim.result import ScenarioResult
from hexabot_sim.terrain import Ground
from hexabot_sim.walking import commands, course
from hexabot_sim.walking.constants import SETTLE_TIME
from hexabot_sim.walking.ground import walking_direction
from hexabot_sim.walking.metrics import Contacts, planned_stand_heights

LEG_COLOURS = {
    "lf": "tab:blue",
    "lm": "tab:orange",
    "lr": "tab:green",
    "rf": "tab:red",
    "rm": "tab:purple",
    "rr": "tab:brown",
}


def _title(result: ScenarioResult, text: str) -> str:
    p = result.params
    if p.schedule or p.waypoints:
        what = f"a schedule of {len(p.schedule)} rows" if p.schedule else f"{len(p.waypoints)} waypoints"
        first = commands.start_gait(p).name  # a schedule's first row's gait replaces the walk's
        return f"{result.scenario}: {text}\n{first} gait at the start, period {p.period:g} s, command: {what}"
    return (
        f"{result.scenario}: {text}\n{p.gait} gait, period {p.period:g} s, command vx {p.vx:g} m/s, "
        f"vy {p.vy:g} m/s, yaw rate {p.yaw_rate:g} rad/s"
    )


def _moving_mean(values: np.ndarray, n: int) -> np.ndarray:
    """Centred moving mean over n samples (edges: shorter windows)."""
    n = max(1, min(n, len(values)))
    kernel = np.ones(n)
    return np.convolve(values, kernel, "same") / np.convolve(np.ones_like(values), kernel, "same")


def figures(result: ScenarioResult) -> dict[str, Any]:
    """Path with footprints, gait diagram, commanded vs achieved velocity, body height and attitude, foot slip."""
    from hexabot_sim import plots

    p, c = result.params, result.columns
    legs = p.ROBOT.layout.legs
    contacts: Contacts = result.extras["contacts"]
    t = c["t"]
    out: dict[str, Any] = {}

    # Path seen from above, with the footprints (where each foot touched down) and the heading.
    points = np.concatenate([np.c_[c["x"], c["y"]], contacts.point[..., :2].reshape(-1, 2)])
    points = points[np.isfinite(points).all(axis=1)]
    span_x, span_y = np.ptp(points, axis=0) + 0.1
    height = float(np.clip(7.0 * span_y / span_x, 3.0, 8.0))  # equal axes, a frame that fits the walk
    fig, ax = plots.figure(figsize=(10, height + 1.2))
    ax.plot(c["x"], c["y"], color="k", lw=1.5, label="body (plate centre)")
    loaded = np.stack([c[f"contact_{leg}"] for leg in legs], axis=1) > 0.5  # also the gait diagram's and slip's
    for leg, pts in zip(legs, contacts.touchdowns(c, legs), strict=True):
        ax.plot(pts[:, 0], pts[:, 1], "o", ms=3.5, mfc="none", color=LEG_COLOURS[leg], label=f"{leg} touchdowns")
    every = max(1, round(p.period / p.timestep))
    heading = c["yaw"][::every]
    ax.quiver(
        c["x"][::every], c["y"][::every], np.cos(heading), np.sin(heading),
        angles="xy", scale_units="xy", scale=12, width=0.004, color="0.4", label="heading (every period)",
    )  # fmt: skip
    ax.plot(c["x"][0], c["y"][0], "g^", ms=9, label="start")
    ax.plot(c["x"][-1], c["y"][-1], "rs", ms=8, label="end")
    ax.set_aspect("equal", adjustable="datalim")
    ax.margins(0.03)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, alpha=0.3)
    plots.legend_right(ax)
    fig.suptitle(_title(result, "path seen from above"), fontsize=plots.TITLE_FONTSIZE)
    out["path"] = fig

    # Gait diagram: measured stance (loaded foot) as bars, the plan as thin lines, over four cycles.
    start = SETTLE_TIME + 2 * p.period
    out["gait_diagram"] = _gait_diagram(result, loaded, start, start + 4 * p.period, "gait diagram")
    for k, (when, gait) in enumerate(result.extras.get("gait_switches", ())[:3]):  # a schedule's gait changes
        text = f"gait diagram across the switch to the {gait} gait at {when:.3g} s (dashed)"
        fig = _gait_diagram(result, loaded, when - 2 * p.period, when + 3 * p.period, text)
        fig.axes[0].axvline(when, color="k", ls="--", lw=1.0)
        out[f"gait_switch_{k + 1}"] = fig
    show = (t >= start) & (t <= start + 4 * p.period)  # the foot forces over the gait diagram's cycles
    if not show.any():
        show = t >= 0
    out["foot_forces"] = _forces_figure(result, show)

    # Commanded vs achieved body velocity (body frame), raw and averaged over one gait period.
    fig, axes = plots.figure(3, 1, figsize=(9, 8), sharex=True)
    n = max(1, round(p.period / p.timestep))
    command_label = "command (with ramp and heading hold)" if p.heading_hold == "on" else "command (with ramp)"
    for ax, key, cmd, label, unit in (
        (axes[0], "vx_body", "cmd_vx", "forward speed", "m/s"),
        (axes[1], "vy_body", "cmd_vy", "sideways speed", "m/s"),
        (axes[2], "yaw_rate", "cmd_yaw_rate", "yaw rate", "rad/s"),
    ):
        ax.plot(t, c[key], color="0.75", lw=0.6, label="measured")
        ax.plot(t, _moving_mean(c[key], n), color="tab:blue", lw=1.5, label="measured, mean over one period")
        ax.plot(t, c[cmd], **plots.TARGET_STYLE, label=command_label)
        ax.set_ylabel(f"{label} [{unit}]")
        ax.grid(True, alpha=0.3)
    plots.legend_above(axes[0])
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(_title(result, "commanded vs achieved velocity (body frame)"), fontsize=plots.TITLE_FONTSIZE)
    out["velocity"] = fig

    # Body height and attitude.
    fig, axes = plots.figure(2, 1, figsize=(9, 6), sharex=True)
    planned_h = (planned_stand_heights(p, t) + p.ROBOT.layout.foot_radius) * 1000  # (n,) [mm]: a schedule's rows'
    ground: Ground = result.extras["terrain"]
    axes[0].plot(t, c["z"] * 1000, color="tab:blue", label="body height")
    if ground.flat:
        if np.ptp(planned_h) == 0:
            axes[0].axhline(planned_h[0], **plots.TARGET_STYLE, label="planned height")
        else:
            axes[0].plot(t, planned_h, **plots.TARGET_STYLE, label="planned height")
    else:  # the planned height is above the ground under the body, which rises on a slope, a kerb or stairs
        planned = ground.height(c["x"], c["y"]) * 1000 + planned_h  # (n,) [mm]
        above = f"{planned_h[0]:.3g} mm" if np.ptp(planned_h) == 0 else "the stand height"
        axes[0].plot(t, planned, **plots.TARGET_STYLE, label=f"planned: ground under\nthe body + {above}")
    axes[0].set_ylabel("height [mm]")
    plots.plain(axes[0])
    plots.min_span(axes[0], 2.0)
    axes[1].plot(t, np.degrees(c["roll"]), label="roll")
    axes[1].plot(t, np.degrees(c["pitch"]), label="pitch")
    axes[1].set_ylabel("attitude [deg]")
    plots.min_span(axes[1], 0.5)
    for ax in axes:
        ax.grid(True, alpha=0.3)
        plots.legend_right(ax)
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(_title(result, "body height and attitude"), fontsize=plots.TITLE_FONTSIZE)
    out["body"] = fig

    # Foot slip: contact-point speed of the loaded feet.
    fig, ax = plots.figure(figsize=(9, 4.5))
    for i, leg in enumerate(legs):
        slip = np.where(loaded[:, i], contacts.slip[:, i] * 1000, np.nan)
        ax.plot(t, slip, lw=0.8, color=LEG_COLOURS[leg], label=leg)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("contact-point speed while loaded [mm/s]")
    ax.grid(True, alpha=0.3)
    plots.legend_right(ax)
    m = result.metrics
    per_stance = m["slip_per_stance"].value
    per_stance = "no stance in the steady walk" if per_stance is None else f"{per_stance:.3g} mm per stance"
    fig.suptitle(
        _title(result, f"foot slip: mean {m['slip_mean'].value * 1000:.3g} mm/s, {per_stance}"),
        fontsize=plots.TITLE_FONTSIZE,
    )
    out["slip"] = fig
    follower = result.extras.get("follower")
    if follower is not None:
        out["course"] = course.course_figure(result, follower, LEG_COLOURS)
    if not ground.flat:
        out["terrain"] = _terrain_figure(result, ground)
    return out


def _gait_diagram(result: ScenarioResult, loaded: np.ndarray, start: float, end: float, text: str) -> Any:
    """Measured stance (loaded foot) as bars and the planned stance as thin black lines, from start to end [s]."""
    from hexabot_sim import plots

    t, legs = result.columns["t"], result.params.ROBOT.layout.legs
    planned = result.extras["planned_stance"]
    show = (t >= start) & (t <= end)
    if not show.any():
        show = t >= 0
    fig, ax = plots.figure(figsize=(9, 4.5))
    for i, leg in enumerate(legs):
        y = len(legs) - 1 - i
        ts = t[show]
        ax.fill_between(ts, y - 0.35, y + 0.35, where=loaded[show, i], step="post", color=LEG_COLOURS[leg], alpha=0.8,
                        label="stance (foot loaded)" if i == 0 else None)  # fmt: skip
        ax.fill_between(ts, y + 0.38, y + 0.45, where=planned[show, i], step="post", color="k",
                        label="planned stance" if i == 0 else None)  # fmt: skip
    ax.set_yticks(range(len(legs)), list(reversed(legs)))
    ax.set_xlabel("t [s]")
    ax.set_xlim(t[show][0], t[show][-1])
    plots.legend_above(ax, ncol=2)
    fig.suptitle(_title(result, f"{text} (bars: measured stance; black: plan)"), fontsize=plots.TITLE_FONTSIZE)
    return fig


def _forces_figure(result: ScenarioResult, show: np.ndarray) -> Any:
    """Each foot's normal and tangential contact force over the rows `show` (four cycles of the steady walk), over
    its planned stance (shaded) and its static share of the weight."""
    from hexabot_sim import plots

    p, c, m = result.params, result.columns, result.metrics
    legs = p.ROBOT.layout.legs
    planned = result.extras["planned_stance"]
    t = c["t"][show]
    share = float(result.model.body_subtreemass[result.model.body("torso").id]) * 9.81 / len(legs)
    top = max(float(max(c[f"force_{leg}"][show].max() for leg in legs)), 2 * share) * 1.05
    fig, axes = plots.figure(len(legs), 1, figsize=(9, 1.5 * len(legs) + 1.5), sharex=True)
    for i, leg in enumerate(legs):
        ax = axes[i]
        ax.fill_between(t, 0, top, where=planned[show, i], step="post", color="0.88",
                        label="planned stance" if i == 0 else None)  # fmt: skip
        ax.plot(t, c[f"force_{leg}"][show], color=LEG_COLOURS.get(leg, "k"), lw=1.0,
                label="normal force" if i == 0 else None)  # fmt: skip
        ax.plot(t, c[f"force_t_{leg}"][show], color="0.35", lw=0.7, ls="--",
                label="tangential force" if i == 0 else None)  # fmt: skip
        ax.axhline(share, color="k", lw=0.6, ls=":", label="weight / legs" if i == 0 else None)
        ax.set_ylim(0, top)
        # Only the ticks inside the axis: one beyond its top is not drawn but still pushes the y label left (by
        # its wider label: 'lf [N]' was cut off at the figure's edge).
        ax.set_yticks([v for v in ax.get_yticks() if v <= top])
        ax.set_ylabel(f"{leg} [N]")
    axes[-1].set_xlabel("t [s]")
    axes[-1].set_xlim(t[0], t[-1])
    plots.legend_above(axes[0], ncol=4)

    def fmt(name: str, spec: str) -> str:
        value = m[name].value
        return "n/a" if value is None else format(value, spec)

    text = (
        f"foot forces: {fmt('foot_bounces', 'd')} bounces, impact ratio {fmt('touchdown_impact_ratio', '.2f')}, "
        f"ripple {fmt('stance_force_ripple', '.1%')} of W/{len(legs)}, "
        f"loaded {fmt('stance_loaded_fraction', '.1%')} of the planned stance"
    )
    fig.suptitle(_title(result, text), fontsize=plots.TITLE_FONTSIZE)
    return fig


def _foot_centres(result: ScenarioResult, every: int) -> tuple[np.ndarray, np.ndarray]:
    """Rows (k,) of the recording, one in `every`, and the world position of each foot centre there (k, n_legs, 3)."""
    model, traj = result.model, result.trajectory
    legs = result.params.ROBOT.layout.legs
    data = mujoco.MjData(model)
    sites = [model.site(f"{leg}_foot").id for leg in legs]
    rows = np.arange(0, len(traj.t), every)
    feet = np.empty((len(rows), len(sites), 3))
    for k, row in enumerate(rows):
        data.qpos[:] = traj.qpos[row]
        mujoco.mj_kinematics(model, data)
        feet[k] = data.site_xpos[sites]
    return rows, feet


def _straight(p: Any, along: np.ndarray) -> bool:
    """Whether the walk goes straight on along `along` (its terrain figure's axis is then the distance along it): a
    schedule's or waypoints' course, not the walk's own vx, vy, yaw_rate they replace (an arc drawn against its
    start's direction folded back on itself)."""
    if not (p.schedule or p.waypoints):
        return math.hypot(p.vx, p.vy) > 0 and p.yaw_rate == 0
    plan = commands.path(p, SETTLE_TIME)
    ahead, aside = plan @ along, plan @ np.array([-along[1], along[0]])
    return bool(ahead[-1] > 0 and (np.diff(ahead) >= -1e-9).all() and np.abs(aside).max() <= 1e-3)


def _terrain_figure(result: ScenarioResult, ground: Ground) -> Any:
    """Side view: the ground under the body and the body's height; per leg, the ground along that foot's own track,
    the sole's path over it and the touchdowns (contact points), so every point is drawn over the ground under it."""
    from hexabot_sim import plots

    p, c = result.params, result.columns
    legs = p.ROBOT.layout.legs
    contacts: Contacts = result.extras["contacts"]
    t = c["t"]
    # Horizontal axis: distance along the commanded direction for a straight walk, else time.
    along = walking_direction(p)
    straight = _straight(p, along)

    def axis(xy: np.ndarray, times: np.ndarray) -> np.ndarray:
        return xy @ along if straight else times

    rows, feet = _foot_centres(result, max(1, round(0.01 / p.timestep)))  # every 10 ms
    r = p.ROBOT.layout.foot_radius
    fig, axes = plots.figure(
        1 + len(legs), 1, figsize=(10, 11), sharex=True, gridspec_kw={"height_ratios": [1.6] + [1.0] * len(legs)}
    )
    ax = axes[0]
    s_body = axis(np.c_[c["x"], c["y"]], t)
    under = ground.height(c["x"], c["y"]) * 1000
    floor = float(min(under.min(), (feet[..., 2].min() - r) * 1000)) - 15.0  # [mm] bottom of the ground fill
    ax.fill_between(s_body, under, floor, color="0.82", label="ground under the body")
    ax.plot(s_body, c["z"] * 1000, color="k", lw=1.2, label="body origin (plate centre)")
    ax.set_ylabel("height [mm]")
    plots.legend_above(ax, ncol=2)
    loaded = np.stack([c[f"contact_{leg}"] for leg in legs], axis=1) > 0.5
    low, high = np.inf, -np.inf
    for i, leg in enumerate(legs):
        ax = axes[1 + i]
        s_foot = axis(feet[:, i, :2], t[rows])
        g = ground.height(feet[:, i, 0], feet[:, i, 1]) * 1000
        sole = (feet[:, i, 2] - r) * 1000
        ax.plot(s_foot, g, color="0.35", lw=1.6, label="ground under the foot (along its own track)")
        ax.plot(s_foot, sole, color=LEG_COLOURS[leg], lw=0.8, label="sole (foot centre - radius)")
        down = np.flatnonzero(np.diff(loaded[:, i].astype(int)) == 1) + 1
        pts = contacts.point[down, i]
        ok = np.isfinite(pts).all(axis=1)
        ax.plot(axis(pts[ok, :2], t[down][ok]), pts[ok, 2] * 1000, "o", ms=4, mfc=LEG_COLOURS[leg], mec="k", mew=0.5,
                label="touchdown (contact point)")  # fmt: skip
        ax.set_ylabel(f"{leg} [mm]")
        low, high = min(low, g.min(), sole.min()), max(high, g.max(), sole.max())
        ax.grid(True, alpha=0.3)
    margin = 0.05 * (high - low) + 2.0
    for ax in axes[1:]:
        ax.set_ylim(low - margin, high + margin)
    axes[0].grid(True, alpha=0.3)
    plots.legend_above(axes[1], ncol=3)
    axes[-1].set_xlabel("distance along the commanded direction [m]" if straight else "t [s]")
    fig.suptitle(
        _title(result, f"terrain: {ground.label()}, touchdown {p.touchdown}, level_body {p.level_body}"),
        fontsize=plots.TITLE_FONTSIZE,
    )
    return fig
