"""The leg-step scenario's figures: foot position and velocity, joints, orientation, singularity, workspace."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from hexabot_sim.kinematics import leg as leg_kin
from hexabot_sim.result import ScenarioResult

if TYPE_CHECKING:
    from matplotlib.figure import Figure

from hexabot_sim.robots.leg.step import excursion, line_reach


def _title(result: ScenarioResult, text: str, world: bool = False) -> str:
    from hexabot_sim import plots

    p = result.params
    start = (p.start_x, p.start_y, p.start_z)
    lines = [
        f"{result.scenario}: {text}",
        f"{p.mode}, v_x = {p.amplitude * 1000:g} mm/s · {'sin' if p.profile == 'sine' else 'cos'}({p.omega:g} t) "
        f"along the hip's x axis, start {plots.point_mm(start)} in the hip frame",
    ]
    if world:
        hip, start_world = result.extras["hip"], result.extras["start_world"]
        lines.append(f"world frame: hip at {plots.point_mm(hip)}, start at {plots.point_mm(start_world)}")
    return "\n".join(lines)


def _stack(
    result: ScenarioResult,
    series: Sequence[tuple[np.ndarray, np.ndarray | None, str]],
    title: str,
    legend: str = "measured (MuJoCo)",
) -> tuple[Figure, Any]:
    """Panels over time sharing x: (values, desired or None, y label) each, singular intervals shaded."""
    from hexabot_sim import plots

    t, near = result.columns["t"], result.extras["near_singular"]
    fig, axes = plots.figure(len(series), 1, figsize=(9, 7.5), sharex=True)
    for n, (ax, (values, desired, label)) in enumerate(zip(axes, series, strict=True)):
        ax.plot(t, values, color="tab:blue", label=legend)
        if desired is not None:
            ax.plot(t, desired, "--", color="black", linewidth=1, label="desired")
        plots.shade_singular(ax, t, near, label=n == 0)
        plots.min_span(ax, 1e-3)
        plots.plain(ax)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    plots.legend_above(axes[0])
    axes[-1].set_xlabel("time t [s]")
    fig.suptitle(title, fontsize=plots.TITLE_FONTSIZE)
    return fig, axes


def figures(result: ScenarioResult) -> dict[str, Figure]:
    """Report Figs. 11-16 (foot position, velocity, joints, foot orientation) plus det J and tracking error."""
    from hexabot_sim import plots

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
        _title(result, "foot position, world frame (report Fig. 11)", world=True),
    )
    figures["foot_velocity"], _ = _stack(
        result,
        triple(("vx", "vy", "vz"), ("v_x", "v_y", "v_z"), "mm/s", 1000, True),
        _title(result, "foot velocity, world frame (report Fig. 12)"),
    )
    figures["joints"], _ = _stack(
        result,
        triple(("q1", "q2", "q3"), ("q1 coxa", "q2 femur", "q3 tibia"), "rad", 1, False),
        _title(result, "joint angles (report Figs. 13-15)"),
    )
    figures["foot_orientation"] = foot_orientation_figure(result)

    fig, (ax1, ax2) = plots.figure(2, 1, figsize=(9, 6.5), sharex=True)
    ax1.semilogy(t, np.maximum(np.abs(c["det_j"]), 1e-12), label="|det J| [m³/rad³]")
    ax1.semilogy(t, np.maximum(c["sigma_min"], 1e-12), label="σ_min(J) [m/rad]")
    ax1.axhline(result.params.sigma_threshold, **plots.TARGET_STYLE, label="damping threshold (σ_min)")
    plots.shade_singular(ax1, t, near, label=True)
    ax1.set_ylabel("|det J| [m³/rad³], σ_min(J) [m/rad]\n(values below 1e-12 drawn at 1e-12)")
    plots.legend_above(ax1, ncol=2)
    ax1.grid(alpha=0.3, which="both")
    fig.suptitle(_title(result, "distance to singularity and tracking error"), fontsize=plots.TITLE_FONTSIZE)
    err = np.linalg.norm(
        np.c_[c["foot_x"] - c["foot_x_des"], c["foot_y"] - c["foot_y_des"], c["foot_z"] - c["foot_z_des"]], axis=1
    )
    ax2.semilogy(t, np.maximum(err * 1000, 1e-9), color="black", linewidth=0.9)
    plots.shade_singular(ax2, t, near)
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
    and roll follows from the rotation matrix (kinematics.leg.continuous_zyx).
    """
    from hexabot_sim import plots

    roll, pitch, yaw = result.extras["orientation_continuous"]
    t = result.columns["t"]
    title = _title(result, "foot orientation in the hip frame, ZYX angles continuous in time (report Fig. 16)")
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
    plots.legend_above(axes[1], ncol=2)
    return fig


def workspace_figure(result: ScenarioResult) -> Figure:
    """The leg's vertical plane (coxa at 0): reachable region within the joint ranges, coloured by |det J|.

    Shared with leg-sweep (its parameters have no amplitude: the line is drawn as far as it is reachable).
    """
    from hexabot_sim import plots

    p, model = result.params, result.model
    geom = p.geometry
    lower = [model.jnt_range[model.joint(j).id][0] for j in ("femur", "tibia")]
    upper = [model.jnt_range[model.joint(j).id][1] for j in ("femur", "tibia")]
    q2, q3 = np.meshgrid(np.linspace(lower[0], upper[0], 700), np.linspace(lower[1], upper[1], 700))
    q = np.stack([np.zeros_like(q2), q2, q3], axis=-1).reshape(-1, 3)  # (N, 3)
    foot = leg_kin.fk(q, geom)  # (N, 3)
    det = np.abs(leg_kin.det_jacobian(q, geom)) * 1e6  # [cm^3/rad^3]
    # Rasterise: each pixel keeps the best |det J| of the configurations that reach it.
    extent = geom.l1 + geom.l2 + geom.l3
    edges_x = np.linspace(-extent, extent, 301)
    edges_z = np.linspace(-extent, extent, 301)
    ix = np.clip(np.digitize(foot[:, 0], edges_x) - 1, 0, 299)
    iz = np.clip(np.digitize(foot[:, 2], edges_z) - 1, 0, 299)
    image = np.full((300, 300), np.nan)
    np.fmax.at(image, (iz, ix), det)

    fig, ax = plots.figure(figsize=(8, 8.5))
    mesh = ax.pcolormesh(edges_x * 1000, edges_z * 1000, image, cmap="viridis", shading="flat")
    fig.colorbar(mesh, ax=ax, label="|det J| [cm³/rad³] (0 = singular)", shrink=0.8)
    ax.axvline(0, color="tab:red", linestyle=":", label="coxa axis: ρ = 0, singular (missed by report 000)")
    circle = np.linspace(0, 2 * np.pi, 400)
    reach = geom.l2 + geom.l3
    ax.plot(
        (geom.l1 + reach * np.cos(circle)) * 1000, reach * np.sin(circle) * 1000, "--", color="tab:red",
        label="leg stretched: q3 = 0, singular",
    )  # fmt: skip
    start = np.array([p.start_x, p.start_y, p.start_z])
    forward, backward = excursion(p) if hasattr(p, "amplitude") else (line_reach(start, geom)[0], 0.0)
    ax.plot(
        [(start[0] - backward) * 1000, (start[0] + forward) * 1000], [start[2] * 1000] * 2, color="tab:orange", lw=2.5,
        label="the command's travel in the run (≤ 2A/ω)" if hasattr(p, "amplitude") else "reachable part of the line",
    )  # fmt: skip
    ax.plot(start[0] * 1000, start[2] * 1000, "o", color="tab:orange", markeredgecolor="black", label="start")
    ax.plot(0, 0, "s", color="black", label="hip (coxa axis)")
    ax.set_xlabel("x in the hip frame [mm]")
    ax.set_ylabel("z in the hip frame [mm]")
    ax.set_aspect("equal")
    ax.set_xlim(-extent * 1000 * 0.75, extent * 1000 * 1.05)
    ax.set_ylim(-extent * 1000, extent * 1000)
    ax.legend(fontsize=plots.LEGEND_FONTSIZE, loc="upper center", bbox_to_anchor=(0.5, -0.08), ncol=2, frameon=False)
    ax.set_title(
        "leg workspace in its vertical plane (q1 = 0), joint ranges respected\n"
        f"reach along the line from the start: {line_reach(start, geom)[0] * 1000:.0f} mm",
        fontsize=plots.TITLE_FONTSIZE,
    )
    return fig
