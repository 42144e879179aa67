"""Matplotlib (Agg) figures from a scenario result; nothing here simulates or writes files."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from hexabot_sim.scenarios.base import ScenarioResult

TARGET_STYLE: dict[str, Any] = {"color": "tab:red", "linestyle": "--", "linewidth": 1.2}
REST_STYLE: dict[str, Any] = {"color": "tab:green", "linestyle": ":", "linewidth": 1.5}


def _title(result: ScenarioResult, text: str) -> str:
    p = result.params
    return (
        f"{result.scenario}: {text}\n"
        f"m = {p.mass:g} kg, L = {p.length:g} m, b = {p.damping:g} N·m·s/rad, k = {p.stiffness:g} N·m/rad, "
        f"θ0 = {p.theta0_deg:g}°"
    )


def _angle_lines(ax: plt.Axes, result: ScenarioResult, horizontal: bool = True) -> None:
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

    fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(9, 6), constrained_layout=True)
    ax1.plot(t, theta, color="tab:blue", label="θ")
    _angle_lines(ax1, result)
    ax1.set_ylabel("angle θ [rad]")
    deg = ax1.secondary_yaxis("right", functions=(np.degrees, np.radians))
    deg.set_ylabel("[deg]")
    ax1.legend(loc="upper right", fontsize=8)
    ax1.grid(alpha=0.3)
    ax2.plot(t, omega, color="tab:orange", label="ω")
    ax2.set_ylabel("angular velocity ω [rad/s]")
    ax2.set_xlabel("time t [s]")
    ax2.grid(alpha=0.3)
    ax1.set_title(_title(result, "angle and angular velocity"), fontsize=10)
    figures["angle_velocity"] = fig

    fig, ax = plt.subplots(figsize=(6.5, 5.5), constrained_layout=True)
    ax.plot(theta, omega, color="tab:purple", linewidth=0.9)
    ax.plot(theta[0], omega[0], "o", color="black", label="start")
    ax.plot(theta[-1], omega[-1], "s", color="tab:purple", label="end")
    _angle_lines(ax, result, horizontal=False)
    ax.set_xlabel("angle θ [rad]")
    ax.set_ylabel("angular velocity ω [rad/s]")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    ax.set_title(_title(result, "phase portrait"), fontsize=9)
    figures["phase"] = fig

    fig, (ax1, ax2) = plt.subplots(
        2, 1, sharex=True, figsize=(9, 6.5), gridspec_kw={"height_ratios": [3, 1.4]}, constrained_layout=True
    )
    ax1.plot(t, c["energy_kinetic"], label="kinetic ½Iω²")
    ax1.plot(t, c["energy_gravity"], label="gravity mgc(1 − cos θ)")
    if result.params.stiffness > 0:
        ax1.plot(t, c["energy_spring"], label="spring ½k(θ − θ_t)²")
    if result.params.damping > 0:
        ax1.plot(t, c["energy_dissipated"], label="dissipated ∫bω² dt")
    ax1.plot(t, c["energy_total"], color="black", linewidth=2, label="total (incl. dissipated)")
    ax1.set_ylabel("energy [J]")
    ax1.legend(fontsize=8, loc="center right")
    ax1.grid(alpha=0.3)
    ax1.set_title(_title(result, "energy"), fontsize=10)
    e0 = c["energy_total"][0]
    if e0 > 0:
        err = np.abs(c["energy_total"] - e0) / e0
        ax2.semilogy(t[1:], np.maximum(err[1:], 1e-17), color="black", linewidth=0.8)
        ax2.set_ylabel("|E(t) − E(0)| / E(0)")
    ax2.set_xlabel("time t [s]")
    ax2.grid(alpha=0.3, which="both")
    figures["energy"] = fig
    return figures


def _shade_singular(ax: plt.Axes, t: np.ndarray, near: np.ndarray, label: bool = False) -> None:
    """Shades the intervals where sigma_min(J) is below the damping threshold."""
    edges = np.flatnonzero(np.diff(np.r_[0, near.astype(int), 0]))
    for n, (start, stop) in enumerate(zip(edges[::2], edges[1::2], strict=True)):
        ax.axvspan(
            t[start], t[min(stop, len(t) - 1)], color="tab:red", alpha=0.12, lw=0,
            label="near-singular (σ_min < threshold)" if label and n == 0 else None,
        )  # fmt: skip


def _min_span(ax: plt.Axes, span: float) -> None:
    """Keeps a y axis at least `span` tall so round-off (1e-17) is not blown up to full height."""
    low, high = ax.get_ylim()
    if high - low < span:
        mid = 0.5 * (low + high)
        ax.set_ylim(mid - span / 2, mid + span / 2)


def _leg_title(result: ScenarioResult, text: str) -> str:
    p = result.params
    return (
        f"{result.scenario}: {text}\n"
        f"{p.mode}, v_x = {p.amplitude * 1000:g} mm/s · {'sin' if p.profile == 'sine' else 'cos'}({p.omega:g} t), "
        f"start ({p.start_x * 1000:g}, {p.start_y * 1000:g}, {p.start_z * 1000:g}) mm"
    )


def leg_figures(result: ScenarioResult) -> dict[str, Figure]:
    """Report Figs. 11-16 (foot position, velocity, joints, foot orientation) plus det J and tracking error."""
    c = result.columns
    t, near = c["t"], result.extras["near_singular"]
    figures: dict[str, Figure] = {}

    def triple(
        names: tuple[str, ...], labels: tuple[str, ...], unit: str, scale: float, title: str, des: bool
    ) -> Figure:
        fig, axes = plt.subplots(len(names), 1, sharex=True, figsize=(9, 7), constrained_layout=True)
        for n, (ax, name, label) in enumerate(zip(axes, names, labels, strict=True)):
            ax.plot(t, c[name] * scale, color="tab:blue", label="measured (MuJoCo)")
            if des:
                ax.plot(t, c[f"{name}_des"] * scale, "--", color="black", linewidth=1, label="desired")
            _shade_singular(ax, t, near, label=n == 0)
            _min_span(ax, 1e-3)
            ax.set_ylabel(f"{label} [{unit}]")
            ax.grid(alpha=0.3)
        axes[0].legend(fontsize=8, loc="upper right")
        axes[-1].set_xlabel("time t [s]")
        axes[0].set_title(_leg_title(result, title), fontsize=10)
        return fig

    figures["foot_position"] = triple(
        ("foot_x", "foot_y", "foot_z"), ("x", "y", "z"), "mm", 1000, "foot position, world frame (report Fig. 11)", True
    )
    figures["foot_velocity"] = triple(
        ("vx", "vy", "vz"), ("v_x", "v_y", "v_z"), "mm/s", 1000, "foot velocity (report Fig. 12)", True
    )
    figures["joints"] = triple(
        ("q1", "q2", "q3"), ("q1 coxa", "q2 femur", "q3 tibia"), "rad", 1, "joint angles (report Figs. 13-15)", False
    )
    figures["foot_orientation"] = triple(
        ("roll", "pitch", "yaw"),
        ("roll", "pitch", "yaw"),
        "rad",
        1,
        "foot orientation, ZYX angles (report Fig. 16)",
        False,
    )

    fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(9, 6), constrained_layout=True)
    ax1.semilogy(t, np.maximum(np.abs(c["det_j"]), 1e-12), label="|det J| [m³/rad³]")
    ax1.semilogy(t, np.maximum(c["sigma_min"], 1e-12), label="σ_min(J) [m/rad]")
    ax1.axhline(result.params.sigma_threshold, **TARGET_STYLE, label="damping threshold")
    _shade_singular(ax1, t, near, label=True)
    ax1.legend(fontsize=8, loc="lower left")
    ax1.grid(alpha=0.3, which="both")
    ax1.set_title(_leg_title(result, "distance to singularity and tracking error"), fontsize=10)
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

    fig, ax = plt.subplots(figsize=(8, 7), constrained_layout=True)
    mesh = ax.pcolormesh(edges_x * 1000, edges_z * 1000, image, cmap="viridis", shading="flat")
    fig.colorbar(mesh, ax=ax, label="|det J| [cm³/rad³] (0 = singular)")
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
    ax.legend(fontsize=8, loc="upper left")
    ax.set_title(
        "leg workspace in its vertical plane (q1 = 0), joint ranges respected\n"
        f"reach along the line from the start: {line_reach(start)[0] * 1000:.0f} mm",
        fontsize=10,
    )
    return fig


def leg_sweep_figures(result: ScenarioResult) -> dict[str, Figure]:
    """Heatmap of the deviation over amplitude x omega with the predicted boundary 2A/omega = reach."""
    c = result.columns
    amps, omegas = np.unique(c["amplitude"]), np.unique(c["omega"])
    grid = np.full((len(amps), len(omegas)), np.nan)
    for a, w, d in zip(c["amplitude"], c["omega"], c["max_deviation"], strict=True):
        grid[np.searchsorted(amps, a), np.searchsorted(omegas, w)] = d
    reach = float(c["reach_forward"][0])

    def edges(v: np.ndarray, log: bool) -> np.ndarray:
        x = np.log(v) if log else v
        mid = 0.5 * (x[1:] + x[:-1])
        first, last = (x[0] - (mid[0] - x[0]), x[-1] + (x[-1] - mid[-1])) if len(x) > 1 else (x[0] - 0.1, x[0] + 0.1)
        out = np.r_[first, mid, last]
        return np.exp(out) if log else out

    from matplotlib.colors import LogNorm

    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(14, 6), constrained_layout=True)
    dev_mm = np.maximum(grid * 1000, 1e-6)
    mesh = ax.pcolormesh(
        edges(omegas, True), edges(amps, False) * 1000, dev_mm, norm=LogNorm(vmin=1e-6, vmax=max(dev_mm.max(), 1e-3)),
        cmap="magma",
    )  # fmt: skip
    fig.colorbar(mesh, ax=ax, label="max deviation from the line, y and z [mm]")
    w_line = np.geomspace(edges(omegas, True)[0], edges(omegas, True)[-1], 200)
    ax.plot(w_line, reach * w_line / 2 * 1000, color="cyan", lw=2, label=f"2A/ω = reach ({reach * 1000:.0f} mm)")
    ax.set_xscale("log")
    ax.set_ylim(edges(amps, False)[0] * 1000, edges(amps, False)[-1] * 1000)
    cases = [(0.01, 1.0), (0.05, 1.0), (0.10, 1.0), (0.08, 1.0), (0.08, np.pi / 6)]
    for a, w in cases:
        ax.plot(w, a * 1000, "o", mfc="none", mec="white", ms=11, mew=1.5)
        ax.annotate(f"{a * 1000:.0f} mm/s, ω={w:.3g}", (w, a * 1000), (6, 6), textcoords="offset points",
                    color="white", fontsize=8)  # fmt: skip
    from matplotlib.ticker import NullFormatter, NullLocator

    ax.xaxis.set_minor_locator(NullLocator())
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xticks(omegas, [f"{w:.3g}" for w in omegas])
    ax.set_xlabel("ω [rad/s]")
    ax.set_ylabel("amplitude A [mm/s]")
    ax.legend(loc="lower right", fontsize=8)
    ax.set_title("deviation over the grid; circles: the reports' cases", fontsize=10)

    scatter = ax2.scatter(
        c["excursion_forward"] / reach, np.maximum(c["max_deviation"] * 1000, 1e-6), c=c["omega"], cmap="viridis",
        norm=LogNorm(),
    )  # fmt: skip
    fig.colorbar(scatter, ax=ax2, label="ω [rad/s]")
    ax2.axvline(1.0, color="tab:red", linestyle="--", label="excursion = reach")
    ax2.set_yscale("log")
    ax2.set_xlabel("excursion 2A/ω ÷ reach along the line")
    ax2.set_ylabel("max deviation [mm]")
    ax2.legend(fontsize=8)
    ax2.grid(alpha=0.3, which="both")
    ax2.set_title("all frequencies collapse onto the excursion: it is A/ω, not ω, that matters", fontsize=10)
    p = result.params
    fig.suptitle(
        f"{result.scenario}: {p.mode} mode, sine profile, {p.periods:g} periods per cell, start "
        f"({p.start_x * 1000:g}, {p.start_y * 1000:g}, {p.start_z * 1000:g}) mm"
    )
    return {"sweep": fig, "workspace": workspace_figure(result)}


def rrp_velocity_figures(result: ScenarioResult) -> dict[str, Figure]:
    """Report 001 part 5: the tool's linear and angular velocity in the base frame, and the joints."""
    c = result.columns
    t = c["t"]
    p = result.params
    title = f"{result.scenario}: q = (sin t, cos 2t, sin 3t), d1 = {p.d1:g} m, a2 = {p.a2:g} m"
    fig, (ax1, ax2, ax3) = plt.subplots(3, 1, sharex=True, figsize=(9, 8), constrained_layout=True)
    for axis in ("vx", "vy", "vz"):
        ax1.plot(t, c[axis], label=f"{axis} (J q̇)")
    ax1.plot(t, c["vx_mujoco"], ":", color="black", linewidth=1, label="MuJoCo site velocity")
    ax1.set_ylabel("linear velocity [m/s]")
    for axis in ("wx", "wy", "wz"):
        ax2.plot(t, c[axis], label=f"{axis} (J q̇)")
    ax2.plot(t, c["wx_mujoco"], ":", color="black", linewidth=1, label="MuJoCo site velocity")
    ax2.set_ylabel("angular velocity [rad/s]")
    ax3.plot(t, c["q1"], label="q1 [rad]")
    ax3.plot(t, c["q2"], label="q2 [rad]")
    ax3.plot(t, c["d3"], label="d3 [m]")
    ax3.plot(t, c["det_jv"], "--", color="gray", label="det Jv = (a2 + d3)² cos q2 [m²]")
    ax3.set_ylabel("joints")
    ax3.set_xlabel("time t [s]")
    for ax in (ax1, ax2, ax3):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper right", ncol=2)
    ax1.set_title(title, fontsize=10)
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
