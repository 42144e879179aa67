"""Matplotlib figures from a scenario result; nothing here simulates, writes files or picks a backend."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.colors import LogNorm
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter, NullLocator

from hexabot_sim.scenarios.base import ScenarioResult

TARGET_STYLE: dict[str, Any] = {"color": "tab:red", "linestyle": "--", "linewidth": 1.2}
REST_STYLE: dict[str, Any] = {"color": "tab:green", "linestyle": ":", "linewidth": 1.5}
LEGEND_FONTSIZE: float = 8
TITLE_FONTSIZE: float = 10


def use_agg() -> None:
    """Selects matplotlib's non-interactive Agg backend. FOR THE CLI ONLY; never called on import.

    The figures below are made without pyplot (plain `Figure` objects), so they need no backend
    and a notebook keeps its own; the CLI may call this before anything imports pyplot.
    """
    import matplotlib

    matplotlib.use("Agg")


# ---------------------------------------------------------------------------------------------
# Shared style: constrained layout, titles on the figure, legends outside the data.


def _figure(nrows: int = 1, ncols: int = 1, figsize: tuple[float, float] = (9, 6), **kw: Any) -> tuple[Figure, Any]:
    """A figure with constrained layout (made without pyplot) and its axes."""
    fig = Figure(figsize=figsize, layout="constrained")
    return fig, fig.subplots(nrows, ncols, **kw)


def _legend_above(ax: Axes, ncol: int = 3, **kw: Any) -> None:
    """The axes' legend in a row above it: outside the data, whatever the data does."""
    ax.legend(
        loc="lower left", bbox_to_anchor=(0.0, 1.01), ncol=ncol, fontsize=LEGEND_FONTSIZE, frameon=False,
        borderaxespad=0.0, **kw,
    )  # fmt: skip


def _legend_right(ax: Axes, **kw: Any) -> None:
    """The axes' legend to its right, outside the data."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=LEGEND_FONTSIZE, borderaxespad=0.0, **kw)


def _plain(ax: Axes) -> None:
    """Tick labels as plain numbers: no '+2.2e2' offset, no '1e-3' multiplier above the axis."""
    ax.ticklabel_format(axis="y", useOffset=False, style="plain")


def _min_span(ax: Axes, span: float) -> None:
    """Keeps a y axis at least `span` tall so round-off (1e-17) is not blown up to full height."""
    low, high = ax.get_ylim()
    if high - low < span:
        mid = 0.5 * (low + high)
        ax.set_ylim(mid - span / 2, mid + span / 2)


def _length_mm(value: float, _pos: Any = None) -> str:
    """A length given in [mm] as a readable label: 10 mm, 1 mm, 100 µm, 1 µm, 10 nm."""
    if value >= 1:
        return f"{value:g} mm"
    if value >= 1e-3:
        return f"{value * 1e3:.3g} µm"
    return f"{value * 1e6:.3g} nm"


def _decades(ax: Axes, low: float, high: float) -> None:
    """A log y axis from whole decades around [low, high] (at least one), labelled as lengths in mm."""
    lo = 10 ** math.floor(math.log10(low))
    hi = 10 ** math.ceil(math.log10(high))
    ax.set_ylim(lo, hi if hi > lo else 10 * lo)
    ax.yaxis.set_major_locator(LogLocator(base=10, numticks=20))
    ax.yaxis.set_major_formatter(FuncFormatter(_length_mm))
    ax.yaxis.set_minor_formatter(NullFormatter())


# ---------------------------------------------------------------------------------------------
# Pendulum


def _title(result: ScenarioResult, text: str) -> str:
    p = result.params
    return (
        f"{result.scenario}: {text}\n"
        f"m = {p.mass:g} kg, L = {p.length:g} m, b = {p.damping:g} N·m·s/rad, k = {p.stiffness:g} N·m/rad, "
        f"θ0 = {p.theta0_deg:g}°"
    )


def _angle_lines(ax: Axes, result: ScenarioResult, horizontal: bool = True) -> None:
    """Draws the spring target and the predicted rest angle."""
    draw = ax.axhline if horizontal else ax.axvline
    target, rest = result.extras.get("target"), result.extras.get("rest_angle")
    if target is not None:
        draw(target, label=f"spring target {math.degrees(target):.1f}°", **TARGET_STYLE)
    if rest is not None and result.params.damping > 0:
        draw(rest, label=f"predicted rest angle {math.degrees(rest):.2f}°", **REST_STYLE)


def pendulum_figures(result: ScenarioResult) -> dict[str, Figure]:
    """Angle and angular velocity vs time (report Figs. 5-8), phase portrait, energy balance."""
    c = result.columns
    t, theta, omega = c["t"], c["theta"], c["omega"]
    figures: dict[str, Figure] = {}

    fig, (ax1, ax2) = _figure(2, 1, figsize=(9, 6.5), sharex=True)
    ax1.plot(t, theta, color="tab:blue", label="θ")
    _angle_lines(ax1, result)
    ax1.set_ylabel("angle θ [rad]")
    deg = ax1.secondary_yaxis("right", functions=(np.degrees, np.radians))
    deg.set_ylabel("θ [deg]")
    _legend_above(ax1)
    ax1.grid(alpha=0.3)
    ax2.plot(t, omega, color="tab:orange")
    ax2.set_ylabel("angular velocity ω [rad/s]")
    ax2.set_xlabel("time t [s]")
    ax2.grid(alpha=0.3)
    fig.suptitle(_title(result, "angle and angular velocity"), fontsize=TITLE_FONTSIZE)
    figures["angle_velocity"] = fig

    fig, ax = _figure(figsize=(6.5, 6))
    ax.plot(theta, omega, color="tab:purple", linewidth=0.9)
    ax.plot(theta[0], omega[0], "o", color="black", label="start")
    ax.plot(theta[-1], omega[-1], "s", color="tab:purple", label="end")
    _angle_lines(ax, result, horizontal=False)
    ax.set_xlabel("angle θ [rad]")
    ax.set_ylabel("angular velocity ω [rad/s]")
    _legend_above(ax, ncol=2)
    ax.grid(alpha=0.3)
    fig.suptitle(_title(result, "phase portrait"), fontsize=TITLE_FONTSIZE)
    figures["phase"] = fig

    fig, (ax1, ax2) = _figure(2, 1, figsize=(9, 7), sharex=True, gridspec_kw={"height_ratios": [3, 1.4]})
    ax1.plot(t, c["energy_kinetic"], label="kinetic ½Iω²")
    ax1.plot(t, c["energy_gravity"], label="gravity mgc(1 − cos θ)")
    if result.params.stiffness > 0:
        ax1.plot(t, c["energy_spring"], label="spring ½k(θ − θ_t)²")
    if result.params.damping > 0:
        ax1.plot(t, c["energy_dissipated"], label="dissipated by damping ∫bω² dt")
    ax1.plot(t, c["energy_total"], color="black", linewidth=2, label="sum E(t): kinetic + potential + dissipated")
    ax1.set_ylabel("energy [J]")
    _legend_above(ax1, ncol=2)
    ax1.grid(alpha=0.3)
    fig.suptitle(_title(result, "energy"), fontsize=TITLE_FONTSIZE)
    e0 = c["energy_total"][0]
    if e0 > 0:
        err = np.abs(c["energy_total"] - e0) / e0
        ax2.semilogy(t[1:], np.maximum(err[1:], 1e-17), color="black", linewidth=0.8)
        ax2.set_ylabel("|E(t) − E(0)| / E(0)\n(energy balance error)")
    else:
        ax2.text(0.5, 0.5, "E(0) = 0: no relative balance error", transform=ax2.transAxes, ha="center")
    ax2.set_xlabel("time t [s]")
    ax2.grid(alpha=0.3, which="both")
    figures["energy"] = fig
    return figures


# ---------------------------------------------------------------------------------------------
# Leg


def _shade_singular(ax: Axes, t: np.ndarray, near: np.ndarray, label: bool = False) -> None:
    """Shades the intervals where sigma_min(J) is below the damping threshold."""
    edges = np.flatnonzero(np.diff(np.r_[0, near.astype(int), 0]))
    for n, (start, stop) in enumerate(zip(edges[::2], edges[1::2], strict=True)):
        ax.axvspan(
            t[start], t[min(stop, len(t) - 1)], color="tab:red", alpha=0.12, lw=0,
            label="near-singular (σ_min < threshold)" if label and n == 0 else None,
        )  # fmt: skip


def _mm(values: Sequence[float]) -> str:
    return "(" + ", ".join(f"{v * 1000:.4g}" for v in values) + ") mm"


def _leg_title(result: ScenarioResult, text: str, world: bool = False) -> str:
    p = result.params
    start = (p.start_x, p.start_y, p.start_z)
    lines = [
        f"{result.scenario}: {text}",
        f"{p.mode}, v_x = {p.amplitude * 1000:g} mm/s · {'sin' if p.profile == 'sine' else 'cos'}({p.omega:g} t) "
        f"along the hip's x axis, start {_mm(start)} in the hip frame",
    ]
    if world:
        hip, start_world = result.extras["hip"], result.extras["start_world"]
        lines.append(f"world frame: hip at {_mm(hip)}, start at {_mm(start_world)}")
    return "\n".join(lines)


def _stack(
    result: ScenarioResult,
    series: Sequence[tuple[np.ndarray, np.ndarray | None, str]],
    title: str,
    legend: str = "measured (MuJoCo)",
) -> tuple[Figure, Any]:
    """Panels over time sharing x: (values, desired or None, y label) each, singular intervals shaded."""
    t, near = result.columns["t"], result.extras["near_singular"]
    fig, axes = _figure(len(series), 1, figsize=(9, 7.5), sharex=True)
    for n, (ax, (values, desired, label)) in enumerate(zip(axes, series, strict=True)):
        ax.plot(t, values, color="tab:blue", label=legend)
        if desired is not None:
            ax.plot(t, desired, "--", color="black", linewidth=1, label="desired")
        _shade_singular(ax, t, near, label=n == 0)
        _min_span(ax, 1e-3)
        _plain(ax)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    _legend_above(axes[0])
    axes[-1].set_xlabel("time t [s]")
    fig.suptitle(title, fontsize=TITLE_FONTSIZE)
    return fig, axes


def leg_figures(result: ScenarioResult) -> dict[str, Figure]:
    """Report Figs. 11-16 (foot position, velocity, joints, foot orientation) plus det J and tracking error."""
    c = result.columns
    t, near = c["t"], result.extras["near_singular"]
    figures: dict[str, Figure] = {}

    def triple(names: Sequence[str], labels: Sequence[str], unit: str, scale: float, des: bool) -> list:
        return [
            (c[name] * scale, c[f"{name}_des"] * scale if des else None, f"{label} [{unit}]")
            for name, label in zip(names, labels, strict=True)
        ]

    figures["foot_position"], _ = _stack(
        result,
        triple(("foot_x", "foot_y", "foot_z"), ("x", "y", "z"), "mm", 1000, True),
        _leg_title(result, "foot position, world frame (report Fig. 11)", world=True),
    )
    figures["foot_velocity"], _ = _stack(
        result,
        triple(("vx", "vy", "vz"), ("v_x", "v_y", "v_z"), "mm/s", 1000, True),
        _leg_title(result, "foot velocity, world frame (report Fig. 12)"),
    )
    figures["joints"], _ = _stack(
        result,
        triple(("q1", "q2", "q3"), ("q1 coxa", "q2 femur", "q3 tibia"), "rad", 1, False),
        _leg_title(result, "joint angles (report Figs. 13-15)"),
    )
    figures["foot_orientation"] = foot_orientation_figure(result)

    fig, (ax1, ax2) = _figure(2, 1, figsize=(9, 6.5), sharex=True)
    ax1.semilogy(t, np.maximum(np.abs(c["det_j"]), 1e-12), label="|det J| [m³/rad³]")
    ax1.semilogy(t, np.maximum(c["sigma_min"], 1e-12), label="σ_min(J) [m/rad]")
    ax1.axhline(result.params.sigma_threshold, **TARGET_STYLE, label="damping threshold (σ_min)")
    _shade_singular(ax1, t, near, label=True)
    ax1.set_ylabel("|det J| [m³/rad³], σ_min(J) [m/rad]\n(values below 1e-12 drawn at 1e-12)")
    _legend_above(ax1, ncol=2)
    ax1.grid(alpha=0.3, which="both")
    fig.suptitle(_leg_title(result, "distance to singularity and tracking error"), fontsize=TITLE_FONTSIZE)
    err = np.linalg.norm(
        np.c_[c["foot_x"] - c["foot_x_des"], c["foot_y"] - c["foot_y_des"], c["foot_z"] - c["foot_z_des"]], axis=1
    )
    ax2.semilogy(t, np.maximum(err * 1000, 1e-9), color="black", linewidth=0.9)
    _shade_singular(ax2, t, near)
    ax2.set_ylabel("|foot − foot_des| [mm]")
    ax2.set_xlabel("time t [s]")
    ax2.grid(alpha=0.3, which="both")
    figures["singularity"] = fig
    figures["workspace"] = workspace_figure(result)
    return figures


def foot_orientation_figure(result: ScenarioResult) -> Figure:
    """Foot orientation as ZYX angles on the branch continuous in time, with the gimbal-lock instants marked.

    The principal ZYX angles (CSV columns roll, pitch, yaw, pitch within +-90 deg) jump by 180 deg
    where q2 + q3 crosses 90 deg although the foot turns smoothly; here yaw = q1, pitch = q2 + q3
    and roll follows from the rotation matrix (scenarios.leg.continuous_zyx).
    """
    roll, pitch, yaw = result.extras["orientation_continuous"]
    t = result.columns["t"]
    title = _leg_title(result, "foot orientation in the hip frame, ZYX angles continuous in time (report Fig. 16)")
    title += "\nroll stays −90° (the knee axis stays horizontal); dotted: the CSV's principal ZYX angles jump by 180°"
    fig, axes = _stack(
        result,
        [(roll, None, "roll [rad]"), (pitch, None, "pitch = q2 + q3 [rad]"), (yaw, None, "yaw = q1 [rad]")],
        title,
        legend="measured (MuJoCo foot site)",
    )
    for ax in axes:
        ax.secondary_yaxis("right", functions=(np.degrees, np.radians)).set_ylabel("[deg]")
    # Where cos(pitch) changes sign the principal angles (CSV) change branch: mark it.
    lock = np.flatnonzero(np.diff(np.signbit(np.cos(pitch))))
    axes[1].axhline(np.pi / 2, color="gray", linestyle=":", linewidth=1, label="pitch = 90°: gimbal lock")
    for n, i in enumerate(lock):
        for ax in axes:
            ax.axvline(
                t[i], color="tab:purple", linestyle=":", linewidth=1,
                label="principal ZYX angles jump by 180°" if n == 0 and ax is axes[1] else None,
            )  # fmt: skip
    _legend_above(axes[1], ncol=2)
    return fig


def workspace_figure(result: ScenarioResult) -> Figure:
    """The leg's vertical plane (coxa at 0): reachable region within the joint ranges, coloured by |det J|."""
    from hexabot_sim.kinematics import leg as leg_kin
    from hexabot_sim.scenarios.leg import GEOMETRY, excursion, line_reach

    p, model = result.params, result.model
    lower = [model.jnt_range[model.joint(j).id][0] for j in ("femur", "tibia")]
    upper = [model.jnt_range[model.joint(j).id][1] for j in ("femur", "tibia")]
    q2, q3 = np.meshgrid(np.linspace(lower[0], upper[0], 700), np.linspace(lower[1], upper[1], 700))
    q = np.stack([np.zeros_like(q2), q2, q3], axis=-1).reshape(-1, 3)  # (N, 3)
    foot = leg_kin.fk(q, GEOMETRY)  # (N, 3)
    det = np.abs(leg_kin.det_jacobian(q, GEOMETRY)) * 1e6  # [cm^3/rad^3]
    # Rasterise: each pixel keeps the best |det J| of the configurations that reach it.
    extent = GEOMETRY.l1 + GEOMETRY.l2 + GEOMETRY.l3
    edges_x = np.linspace(-extent, extent, 301)
    edges_z = np.linspace(-extent, extent, 301)
    ix = np.clip(np.digitize(foot[:, 0], edges_x) - 1, 0, 299)
    iz = np.clip(np.digitize(foot[:, 2], edges_z) - 1, 0, 299)
    image = np.full((300, 300), np.nan)
    np.fmax.at(image, (iz, ix), det)

    fig, ax = _figure(figsize=(8, 8.5))
    mesh = ax.pcolormesh(edges_x * 1000, edges_z * 1000, image, cmap="viridis", shading="flat")
    fig.colorbar(mesh, ax=ax, label="|det J| [cm³/rad³] (0 = singular)", shrink=0.8)
    ax.axvline(0, color="tab:red", linestyle=":", label="coxa axis: ρ = 0, singular (missed by report 000)")
    circle = np.linspace(0, 2 * np.pi, 400)
    reach = GEOMETRY.l2 + GEOMETRY.l3
    ax.plot(
        (GEOMETRY.l1 + reach * np.cos(circle)) * 1000, reach * np.sin(circle) * 1000, "--", color="tab:red",
        label="leg stretched: q3 = 0, singular",
    )  # fmt: skip
    start = np.array([p.start_x, p.start_y, p.start_z])
    forward, backward = excursion(p) if hasattr(p, "amplitude") else (line_reach(start)[0], 0.0)
    ax.plot(
        [(start[0] - backward) * 1000, (start[0] + forward) * 1000], [start[2] * 1000] * 2, color="tab:orange", lw=2.5,
        label="commanded line x0 .. x0 + 2A/ω" if hasattr(p, "amplitude") else "reachable part of the line",
    )  # fmt: skip
    ax.plot(start[0] * 1000, start[2] * 1000, "o", color="tab:orange", markeredgecolor="black", label="start")
    ax.plot(0, 0, "s", color="black", label="hip (coxa axis)")
    ax.set_xlabel("x in the hip frame [mm]")
    ax.set_ylabel("z in the hip frame [mm]")
    ax.set_aspect("equal")
    ax.set_xlim(-extent * 1000 * 0.75, extent * 1000 * 1.05)
    ax.set_ylim(-extent * 1000, extent * 1000)
    ax.legend(fontsize=LEGEND_FONTSIZE, loc="upper center", bbox_to_anchor=(0.5, -0.08), ncol=2, frameon=False)
    ax.set_title(
        "leg workspace in its vertical plane (q1 = 0), joint ranges respected\n"
        f"reach along the line from the start: {line_reach(start)[0] * 1000:.0f} mm",
        fontsize=TITLE_FONTSIZE,
    )
    return fig


# ---------------------------------------------------------------------------------------------
# Leg sweep

# The reports' cases (A [m/s], omega [rad/s]), circled where the grid has them.
REPORT_CASES: tuple[tuple[float, float], ...] = ((0.01, 1.0), (0.05, 1.0), (0.10, 1.0), (0.08, 1.0), (0.08, np.pi / 6))
DEVIATION_FLOOR_MM: float = 1e-6  # deviations below this (1 nm, round-off) are drawn at it


def _cell_edges(values: np.ndarray, log: bool) -> np.ndarray:
    """Edges of cells centred on sorted grid values: midpoints (geometric on a log axis), never <= 0."""
    if len(values) == 1:
        return np.array([values[0] / 1.5, values[0] * 1.5])
    x = np.log(values) if log else values
    mid = 0.5 * (x[1:] + x[:-1])
    edges = np.r_[x[0] - (mid[0] - x[0]), mid, x[-1] + (x[-1] - mid[-1])]
    if log:
        return np.exp(edges)
    edges[0] = max(edges[0], 0.5 * values[0])  # amplitudes are positive: the first cell stops above 0
    return edges


def leg_sweep_figures(result: ScenarioResult) -> dict[str, Figure]:
    """Heatmap of the deviation over amplitude x omega with the predicted boundary 2A/omega = reach."""
    c = result.columns
    amps, omegas = np.unique(c["amplitude"]), np.unique(c["omega"])
    grid = np.full((len(amps), len(omegas)), np.nan)
    for a, w, d in zip(c["amplitude"], c["omega"], c["max_deviation"], strict=True):
        grid[np.searchsorted(amps, a), np.searchsorted(omegas, w)] = d
    reach = float(c["reach_forward"][0])
    w_edges, a_edges = _cell_edges(omegas, True), _cell_edges(amps, False) * 1000  # [rad/s], [mm/s]

    fig, (ax, ax2) = _figure(1, 2, figsize=(14, 6.5))
    dev_mm = np.maximum(grid * 1000, DEVIATION_FLOOR_MM)
    top = 10 ** math.ceil(math.log10(max(float(np.nanmax(dev_mm)), 1e-3)))
    mesh = ax.pcolormesh(w_edges, a_edges, dev_mm, norm=LogNorm(vmin=DEVIATION_FLOOR_MM, vmax=top), cmap="magma")
    bar = fig.colorbar(mesh, ax=ax, label="max deviation from the line (y and z)")
    bar.ax.yaxis.set_major_locator(LogLocator(base=10, numticks=20))
    bar.ax.yaxis.set_major_formatter(FuncFormatter(_length_mm))
    bar.ax.yaxis.set_minor_formatter(NullFormatter())
    w_line = np.geomspace(w_edges[0], w_edges[-1], 200)
    ax.plot(w_line, reach * w_line / 2 * 1000, color="cyan", lw=2)
    in_grid = [np.isclose(amps, a, rtol=1e-3).any() and np.isclose(omegas, w, rtol=1e-3).any() for a, w in REPORT_CASES]
    circled = [case for case, inside in zip(REPORT_CASES, in_grid, strict=True) if inside]
    for a, w in circled:
        ax.plot(w, a * 1000, "o", mfc="none", mec="white", ms=11, mew=1.5)
        ax.annotate(f"{a * 1000:.0f} mm/s, ω={w:.3g}", (w, a * 1000), (6, 6), textcoords="offset points",
                    color="white", fontsize=8)  # fmt: skip
    ax.set_xscale("log")
    ax.set_xlim(w_edges[0], w_edges[-1])
    ax.set_ylim(a_edges[0], a_edges[-1])
    ax.xaxis.set_minor_locator(NullLocator())
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xticks(omegas, [f"{w:.3g}" for w in omegas])
    if len(amps) <= 12:
        ax.set_yticks(amps * 1000, [f"{a * 1000:.4g}" for a in amps])
    ax.set_xlabel("ω [rad/s] (grid values)")
    ax.set_ylabel("amplitude A [mm/s] (grid values)")
    ax.set_title(
        f"deviation over the grid; cyan: predicted boundary 2A/ω = reach ({reach * 1000:.0f} mm)\n"
        + ("circles: the reports' cases" if circled else "none of the reports' cases is in this grid"),
        fontsize=TITLE_FONTSIZE,
    )

    dev = np.maximum(c["max_deviation"] * 1000, DEVIATION_FLOOR_MM)
    w_norm = LogNorm(vmin=omegas[0], vmax=omegas[-1]) if len(omegas) > 1 else LogNorm(omegas[0] / 1.5, omegas[0] * 1.5)
    scatter = ax2.scatter(c["excursion_forward"] / reach, dev, c=c["omega"], cmap="viridis", norm=w_norm)
    bar = fig.colorbar(scatter, ax=ax2, label="ω [rad/s]")
    bar.ax.yaxis.set_minor_locator(NullLocator())
    bar.set_ticks(list(omegas), labels=[f"{w:.3g}" for w in omegas])
    ax2.axvline(1.0, color="tab:red", linestyle="--")
    ax2.set_yscale("log")
    _decades(ax2, float(dev.min()), float(dev.max()))
    ax2.set_xlim(0, max(1.1, float(np.max(c["excursion_forward"] / reach)) * 1.05))
    ax2.set_xlabel("excursion 2A/ω ÷ reach along the line")
    ax2.set_ylabel("max deviation from the line (y and z)")
    ax2.grid(alpha=0.3, which="major")
    ax2.set_title(
        "all frequencies collapse onto the excursion: it is A/ω, not ω, that matters\nred dashed: excursion = reach",
        fontsize=TITLE_FONTSIZE,
    )
    p = result.params
    fig.suptitle(
        f"{result.scenario}: {p.mode} mode, {p.profile} profile, {p.periods:g} periods per cell, start "
        f"{_mm((p.start_x, p.start_y, p.start_z))} in the hip frame"
    )
    return {"sweep": fig, "workspace": workspace_figure(result)}


# ---------------------------------------------------------------------------------------------
# RRP arm


def rrp_velocity_figures(result: ScenarioResult) -> dict[str, Figure]:
    """Report 001 part 5: the tool's linear and angular velocity in the base frame, and the joints."""
    c = result.columns
    t = c["t"]
    p = result.params
    fig, (ax1, ax2, ax3, ax4, ax5) = _figure(
        5, 1, figsize=(9, 11.5), sharex=True, gridspec_kw={"height_ratios": [2.2, 2.2, 1.2, 1.2, 1.2]}
    )
    mujoco_style: dict[str, Any] = {"linestyle": (0, (1, 2)), "color": "black", "linewidth": 1.2}
    for ax, axes in ((ax1, ("vx", "vy", "vz")), (ax2, ("wx", "wy", "wz"))):
        for axis in axes:
            ax.plot(t, c[axis], label=f"{axis} = (J q̇)_{axis[1]}")
        for n, axis in enumerate(axes):  # drawn over each curve
            ax.plot(t, c[f"{axis}_mujoco"], **mujoco_style, label="MuJoCo site velocity (each)" if n == 0 else None)
        ax.grid(alpha=0.3)
        _legend_above(ax, ncol=4)
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
        _plain(ax)
        _legend_above(ax, ncol=3)
    fig.suptitle(
        f"{result.scenario}: q = (sin t, cos 2t, sin 3t), d1 = {p.d1:g} m, a2 = {p.a2:g} m; tool velocity in the base "
        "frame",
        fontsize=TITLE_FONTSIZE,
    )
    return {"velocity": fig}


FIGURES: dict[str, Callable[[ScenarioResult], dict[str, Figure]]] = {
    "pendulum": pendulum_figures,
    "leg": leg_figures,
    "leg_sweep": leg_sweep_figures,
    "rrp_velocity": rrp_velocity_figures,
}


def figures(result: ScenarioResult) -> dict[str, Figure]:
    """The figure set of a result, by file stem."""
    return FIGURES[result.figures](result)
