"""Metrics and figure of a walk whose command changes: each schedule row's steady twist; a waypoint course's errors."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from hexabot_sim.result import Metric
from hexabot_sim.walking import commands, forces

LEAST_STEADY_CYCLES: int = 1  # a schedule row is measured over at least this many whole cycles of steady walk


def segment_windows(p: Any, t: np.ndarray, settle: float) -> list[tuple[int, float, float]]:
    """(row index, start, end) [s] of each schedule row's steady walk: from one period after its ramp ends to the
    next row's ramp, whole gait cycles; rows too short for LEAST_STEADY_CYCLES are left out."""
    rows = commands.setpoints(p)
    starts = [max(r.t, settle) for r in rows]
    out = []
    for i, begin in enumerate(starts):
        end = min(starts[i + 1], float(t[-1])) if i + 1 < len(starts) else float(t[-1])
        first = begin + 2 * p.period  # the ramp, then one period for the gait to settle into the new twist
        cycles = math.floor((end - first) / p.period + 1e-9)
        if cycles >= LEAST_STEADY_CYCLES:
            out.append((i, first, first + cycles * p.period))
    return out


def schedule_metrics(p: Any, t: np.ndarray, columns: dict[str, np.ndarray], settle: float) -> tuple[dict, list]:
    """The largest relative error of a row's steady planar speed and yaw rate, and the per-row table.

    Planar speed error: |mean body-frame velocity - command| / |command| (rows with a speed command of at least
    1 mm/s); yaw-rate error: |mean yaw rate - command| / |command| (rows turning at 1 mrad/s or more); the mean
    yaw rate is the heading change over the window divided by its length.
    """
    table: list[dict[str, Any]] = []
    for i, a, b in segment_windows(p, t, settle):
        w = (t >= a - 1e-9) & (t <= b + 1e-9)
        row = commands.setpoints(p)[i]
        v = np.array([columns["vx_body"][w].mean(), columns["vy_body"][w].mean()])
        yaw = columns["yaw"][w]
        rate = float((yaw[-1] - yaw[0]) / (t[w][-1] - t[w][0]))
        cmd_v, cmd_w = np.array([row.command.vx, row.command.vy]), row.command.yaw_rate
        speed = float(np.hypot(*cmd_v))
        table.append({
            "row": i + 1, "t": row.t, "window": (a, b), "vx": float(v[0]), "vy": float(v[1]), "yaw_rate": rate,
            "speed_error": float(np.hypot(*(v - cmd_v)) / speed) if speed >= 1e-3 else None,
            "yaw_rate_error": abs(rate - cmd_w) / abs(cmd_w) if abs(cmd_w) >= 1e-3 else None,
        })  # fmt: skip
    speed_errors = [float(r["speed_error"]) for r in table if r["speed_error"] is not None]
    # Rows told to stand or turn on the spot have no relative speed error: their mean drift [m/s] instead.
    drifts = [float(np.hypot(r["vx"], r["vy"])) for r in table if r["speed_error"] is None]
    yaw_errors = [float(r["yaw_rate_error"]) for r in table if r["yaw_rate_error"] is not None]
    metrics = {
        "schedule_rows_measured": Metric(len(table), "1", "schedule rows long enough to measure a steady walk"),
        "schedule_speed_error_max": Metric(
            max(speed_errors) if speed_errors else None, "1",
            "largest |mean body velocity - row's command| / |command| over the rows' steady walks"
            + ("" if speed_errors else "; null here: no row moving at 1 mm/s or more has a steady walk measured"),
        ),
        "schedule_still_drift_max": Metric(
            max(drifts) if drifts else None, "m/s",
            "largest mean body speed over the steady walks of rows that command no speed (standing, turning on the "
            "spot)" + ("" if drifts else "; null here: every measured row commands a speed"),
        ),
        "schedule_yaw_rate_error_max": Metric(
            max(yaw_errors) if yaw_errors else None, "1",
            "largest |mean yaw rate - row's yaw_rate| / |yaw_rate| over the turning rows' steady walks"
            + ("" if yaw_errors else "; null here: no row turning at 1 mrad/s or more has a steady walk measured"),
        ),
    }  # fmt: skip
    return metrics, table


def course_metrics(
    p: Any, t: np.ndarray, qpos: np.ndarray, follower: Any, work: np.ndarray, total_mass: float, settle: float
) -> dict[str, Metric]:
    """Cross-track error, time and cost of transport of a waypoint course (from the start of walking to arrival).

    Args:
        work: Joint power |tau dq| summed over the joints at every row [W].
    """
    end = follower.arrived_at if follower.arrived_at is not None else float(t[-1])
    w = (t >= settle) & (t <= end + 1e-9)
    xy = qpos[w, :2]
    error = follower.cross_track(xy)
    travelled = float(np.hypot(*np.diff(xy, axis=0).T).sum())
    energy = float(work[w].sum() * p.timestep)
    arrived = follower.arrived_at is not None
    return {
        "cross_track_rms": Metric(float(np.sqrt(np.mean(error**2))), "m", "RMS distance of the body from the path"),
        "cross_track_max": Metric(float(error.max()), "m", "largest distance of the body from the path"),
        "course_length": Metric(follower.total, "m", "length of the path through the waypoints"),
        "course_time": Metric(
            end - settle if arrived else None, "s", "from the start of walking to arriving at the last waypoint"
            + ("" if arrived else "; null here: the walk ended before it arrived"),
        ),
        "course_arrived": Metric(
            arrived, "", f"the body came within {1000 * 0.01:g} mm of the last waypoint (facing its heading, if any)"
        ),
        "course_distance_left": Metric(
            float(np.hypot(*(qpos[-1, :2] - follower.points[-1, :2]))), "m",
            "distance from the body's last position to the last waypoint",
        ),
        "course_cost_of_transport": Metric(
            energy / (total_mass * 9.81 * travelled) if travelled > 0 else None, "1",
            "joint work |tau dq| / (m g distance walked) over the course",
        ),
    }  # fmt: skip


def course_figure(result: Any, follower: Any, colours: dict[str, str]) -> Any:
    """Path seen from above with the waypoints, the planned path and the footprints (`colours`: by leg)."""
    from hexabot_sim import plots

    p, c = result.params, result.columns
    legs = p.ROBOT.layout.legs
    contacts = result.extras["contacts"]
    fig, ax = plots.figure(figsize=(9, 8))
    ax.plot(follower.points[:, 0], follower.points[:, 1], color="0.6", lw=3, alpha=0.6, label="path (waypoints)")
    ax.plot(follower.points[1:, 0], follower.points[1:, 1], "kx", ms=6, label="waypoints")
    ax.plot(c["x"], c["y"], color="k", lw=1.2, label="body (plate centre)")
    for leg, pts in zip(legs, contacts.touchdowns(c, legs), strict=True):
        ax.plot(pts[:, 0], pts[:, 1], "o", ms=3, mfc="none", color=colours[leg], label=f"{leg} touchdowns")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(True, alpha=0.3)
    plots.legend_right(ax)
    m = result.metrics
    fig.suptitle(
        f"{result.scenario}: waypoint course, {p.gait} gait at {p.path_speed:g} m/s\ncross-track error RMS "
        f"{m['cross_track_rms'].value * 1000:.3g} mm, max {m['cross_track_max'].value * 1000:.3g} mm",
        fontsize=plots.TITLE_FONTSIZE,
    )
    return fig


def count_bounces(loaded: np.ndarray, t: np.ndarray, start: float, end: float) -> int:
    """Bounces of the feet between start and end [s], as the walk's `foot_bounces` counts them over the steady walk
    (walking.forces.bounces: a loaded foot that unloads for under 60 ms and lands again); loaded: (n, legs)."""
    w = (t >= start) & (t <= end)
    dt = float(t[1] - t[0])
    return sum(forces.bounces(loaded[w, leg], dt) for leg in range(loaded.shape[1]))


def speed_dip(t: np.ndarray, v: np.ndarray, command: float, period: float, start: float, end: float) -> float:
    """1 - the lowest mean of v over one period (moving) between start and end, over the command."""
    dt = float(t[1] - t[0])
    n = max(1, round(period / dt))
    mean = np.convolve(v, np.ones(n) / n, "valid")  # mean over [t_k, t_k + period]
    w = (t[: len(mean)] >= start) & (t[: len(mean)] + period <= end)
    return float(1.0 - mean[w].min() / command)
