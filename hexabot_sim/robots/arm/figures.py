"""arm-track's figures: the tool path in 3-D and per axis, the joints, sigma_min and the Jacobian check."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from hexabot_sim import plots

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from hexabot_sim.result import ScenarioResult


def _title(result: ScenarioResult, what: str) -> str:
    p = result.params
    return f"{result.extras['robot']}: {p.path} {p.size * 1000:g} mm, {p.speed * 1000:g} mm/s, {p.plane} plane; {what}"


def path_figure(result: ScenarioResult) -> Figure:
    """The tool's path against the desired one in 3-D, per axis, and the tracking error."""
    c, m = result.columns, result.metrics
    t = c["t"]
    fig, axes = plots.figure(4, 2, figsize=(13, 9), gridspec_kw={"width_ratios": [1.1, 1]})
    grid = axes[0, 0].get_gridspec()
    for ax in axes[:, 0]:
        ax.remove()
    ax3 = fig.add_subplot(grid[:, 0], projection="3d")
    ax3.plot(c["x_des"], c["y_des"], c["z_des"], **plots.TARGET_STYLE, label="desired")
    ax3.plot(c["x"], c["y"], c["z"], color="tab:blue", linewidth=1.0, label="tool (MuJoCo site)")
    ax3.scatter(*(c[k][:1] for k in "xyz"), color="black", s=12, label="start")
    worst = result.extras["worst"]
    ax3.scatter(
        *(c[k][worst : worst + 1] for k in "xyz"),
        color="tab:red",
        marker="x",
        s=30,
        label=f"smallest σmin ({m['sigma_min'].value:.3g})",
    )
    span = max(float(np.ptp(c[f"{k}_des"])) for k in "xyz") / 2 or 0.05
    for k, setter in zip("xyz", (ax3.set_xlim, ax3.set_ylim, ax3.set_zlim), strict=True):
        mid = 0.5 * (c[k].max() + c[k].min())
        setter(mid - 1.2 * span, mid + 1.2 * span)
    ax3.set_xlabel("x [m]")
    ax3.set_ylabel("y [m]")
    ax3.set_zlabel("z [m]")
    ax3.legend(loc="upper left", fontsize=plots.LEGEND_FONTSIZE)
    for ax, k in zip(axes[:3, 1], "xyz", strict=True):
        ax.plot(t, c[f"{k}_des"], **plots.TARGET_STYLE, label=f"{k} desired")
        ax.plot(t, c[k], color="tab:blue", linewidth=1.0, label=f"{k} tool")
        ax.set_ylabel(f"{k} [m]")
        plots.min_span(ax, 1e-3)
        plots.legend_above(ax, ncol=2)
    ax = axes[3, 1]
    ax.plot(t, c["error"] * 1000, color="tab:purple", label="|tool - desired|")
    ax.axhline(m["tracking_error_rms"].value * 1000, color="black", linestyle=":", label="RMS")
    ax.set_ylabel("tracking error [mm]")
    ax.set_xlabel("time t [s]")
    plots.legend_above(ax, ncol=2)
    for ax in axes[:, 1]:
        ax.grid(alpha=0.3)
    fig.suptitle(
        _title(result, f"RMS error {m['tracking_error_rms'].value * 1000:.3g} mm"), fontsize=plots.TITLE_FONTSIZE
    )
    return fig


def joints_figure(result: ScenarioResult) -> Figure:
    """Joint values against their commands and ranges, joint speeds and the feedforward (gravity, Coriolis) torque."""
    c = result.columns
    t = c["t"]
    units = result.extras["units"]
    lower, upper = result.extras["ranges"]
    kinds = [u for u in ("rad", "m") if u in units]
    fig, axes = plots.figure(len(kinds) + 2, 1, figsize=(9, 3 + 2.4 * len(kinds)), sharex=True, squeeze=False)
    axes = axes[:, 0]
    for ax, unit in zip(axes, kinds, strict=False):
        for i, u in enumerate(units):
            if u != unit:
                continue
            (line,) = ax.plot(t, c[f"q{i + 1}"], label=f"q{i + 1}")
            ax.plot(t, c[f"q{i + 1}_cmd"], color=line.get_color(), linestyle="--", linewidth=0.8)
            for bound in (lower[i], upper[i]):
                if np.isfinite(bound) and abs(bound - c[f"q{i + 1}"]).min() < 0.2 * (upper[i] - lower[i]):
                    ax.axhline(bound, color=line.get_color(), linestyle=":", linewidth=0.8)
        ax.set_ylabel(f"{'revolute' if unit == 'rad' else 'prismatic'} joints [{unit}]")
        plots.legend_above(ax, ncol=7)
    for i, u in enumerate(units):
        axes[-2].plot(t, c[f"dq{i + 1}"], label=f"dq{i + 1} [{u}/s]")
        axes[-1].plot(t, c[f"tau{i + 1}_ff"], label=f"{i + 1} [{'N m' if u == 'rad' else 'N'}]")
    axes[-2].set_ylabel("joint speeds")
    axes[-1].set_ylabel("bias feedforward")
    axes[-1].set_xlabel("time t [s]")
    for ax in axes[-2:]:
        plots.legend_above(ax, ncol=7)
    for ax in axes:
        ax.grid(alpha=0.3)
        plots.plain(ax)
    fig.suptitle(_title(result, "joints (dashed: command; dotted: a range end near)"), fontsize=plots.TITLE_FONTSIZE)
    return fig


def singularity_figure(result: ScenarioResult) -> Figure:
    """sigma_min of the task Jacobian along the run, the joints at a range end and |analytic J - mj_jacSite|."""
    c, m, p = result.columns, result.metrics, result.params
    t = c["t"]
    fig, (ax1, ax2, ax3) = plots.figure(3, 1, figsize=(9, 8), sharex=True, gridspec_kw={"height_ratios": [2, 1, 1.2]})
    ax1.plot(t, c["sigma_min"], color="tab:gray", label="σmin of the task Jacobian")
    ax1.axhline(p.sigma_threshold, **plots.TARGET_STYLE, label=f"DLS threshold {p.sigma_threshold:g}")
    ax1.axvline(m["sigma_min_time"].value, color="tab:red", linestyle=":", label="smallest")
    plots.shade_singular(ax1, t, c["near_singular"] > 0, label=True)
    ax1.set_ylim(0, 1.1 * max(float(np.nanmax(c["sigma_min"])), p.sigma_threshold))
    ax1.set_ylabel("σmin")
    plots.legend_above(ax1, ncol=4)
    ax2.step(t, c["joints_at_limit"], where="post", color="tab:orange", label="joint commands at a range end")
    ax2.set_ylabel("joints")
    ax2.set_ylim(-0.1, max(1.0, float(c["joints_at_limit"].max())) + 0.1)
    plots.legend_above(ax2, ncol=2)
    diff = np.where(c["jacobian_diff"] > 0, c["jacobian_diff"], np.nan)
    ax3.semilogy(t, diff, color="tab:green", linewidth=0.8, label="max |analytic J - mj_jacSite| (0 not drawn)")
    ax3.set_ylabel("Jacobian difference")
    ax3.set_xlabel("time t [s]")
    plots.legend_above(ax3, ncol=2)
    for ax in (ax1, ax2, ax3):
        ax.grid(alpha=0.3)
    fig.suptitle(_title(result, "singularities, limits and the Jacobian check"), fontsize=plots.TITLE_FONTSIZE)
    return fig


def figures(result: ScenarioResult) -> dict[str, Figure]:
    """arm-track's figures by file stem."""
    return {"path": path_figure(result), "joints": joints_figure(result), "singularity": singularity_figure(result)}
