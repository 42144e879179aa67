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
    return figures


FIGURES: dict[str, Callable[[ScenarioResult], dict[str, Figure]]] = {
    "pendulum": pendulum_figures,
    "leg": leg_figures,
}


def figures(result: ScenarioResult) -> dict[str, Figure]:
    """The figure set of a result, by file stem."""
    return FIGURES[result.figures](result)
