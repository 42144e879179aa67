"""The reports' amplitude and frequency studies: a grid of leg-step runs on the cell pool, with their figures."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from hexabot_sim import pool
from hexabot_sim.errors import SimulationError
from hexabot_sim.result import Metric, Progress, ScenarioResult
from hexabot_sim.robots.leg import figures as leg_figures
from hexabot_sim.robots.leg import step as leg
from hexabot_sim.robots.leg.parameters import CELL_METRICS, LegSweepParams

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def run(name: str, p: LegSweepParams, progress: Progress | None = None) -> ScenarioResult:
    """Runs every (amplitude, omega) cell as a leg-step run on the cell pool and tabulates the deviations."""
    cells = [(a, w) for a in p.amplitudes for w in p.omegas]
    workers = min(p.workers or pool.workers_default(), len(cells))
    jobs = [pool.CellJob(i, "leg-step", p.cell(a, w), leg.run) for i, (a, w) in enumerate(cells)]
    # Ctrl-C or SIGTERM in the parent stops all workers (pool.run_cells); nothing partial is returned.
    done = pool.run_cells(pool.local_executor(workers), jobs, progress)
    for cell in done:
        if cell.error:  # this study's table needs every cell: a failed one fails the run, naming the cell
            a, w = cells[cell.index]
            raise SimulationError(f"grid cell amplitude = {a:g} m/s, omega = {w:g} rad/s: {cell.error}")
    results: dict[int, dict[str, Any]] = {cell.index: cell.metrics for cell in done}

    amplitude = np.array([a for a, _ in cells])
    omega = np.array([w for _, w in cells])
    columns: dict[str, np.ndarray] = {"amplitude": amplitude, "omega": omega}
    for metric in CELL_METRICS:
        columns[metric] = np.array([float(results[i][metric]) for i in range(len(cells))])
    columns["max_deviation"] = np.maximum(columns["max_lateral_deviation"], columns["max_vertical_deviation"])
    columns["reached_singular"] = np.array(
        [float(results[i]["singular_first_time"] is not None) for i in range(len(cells))]
    )
    columns["predicted_to_leave"] = (columns["excursion_forward"] > columns["reach_forward"]).astype(float)
    units = {"amplitude": "m/s", "omega": "rad/s", "min_abs_det_j": "m^3/rad^3", "min_sigma": "m/rad"}
    units |= {"max_joint_speed_reached": "rad/s", "singular_duration": "s", "reached_singular": "1"}
    units |= {"predicted_to_leave": "1"}
    units = {k: units.get(k, "m") for k in columns}

    agree = columns["reached_singular"] == columns["predicted_to_leave"]
    reach = float(columns["reach_forward"][0])
    metrics = {
        "cells": Metric(len(cells), "1", "runs in the grid"),
        "reach_forward": Metric(reach, "m", "travel along +x from the start before leaving the workspace"),
        "cells_leaving": Metric(
            int(columns["predicted_to_leave"].sum()), "1", "cells whose 2A/omega exceeds the reach"
        ),
        "cells_singular": Metric(int(columns["reached_singular"].sum()), "1", "cells that came near a singularity"),
        "prediction_agreement": Metric(
            float(agree.mean()), "1", "fraction of cells where 'reached a singularity' == '2A/omega > reach'"
        ),
        "max_deviation_inside": Metric(
            float(columns["max_deviation"][columns["predicted_to_leave"] == 0].max(initial=0.0)),
            "m",
            "largest deviation from the line among cells predicted to stay inside",
        ),
    }
    model = mujoco.MjModel.from_xml_string(xml := leg.build_xml(p))
    return ScenarioResult(
        scenario=name,
        params=p,
        model=model,
        model_xml=xml,
        trajectory=None,
        columns=columns,
        column_units=units,
        metrics=metrics,
        summary=["cells", "reach_forward", "cells_leaving", "cells_singular", "prediction_agreement"],
        camera=None,
        csv_name="grid.csv",
    )


# ---------------------------------------------------------------------------------------------
# Figures (matplotlib is imported only when they are drawn: `hexabot-sim list` never loads it)

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


def figures(result: ScenarioResult) -> dict[str, Figure]:
    """Heatmap of the deviation over amplitude x omega with the predicted boundary 2A/omega = reach."""
    from matplotlib.colors import LogNorm
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter, NullLocator

    from hexabot_sim import plots

    c = result.columns
    amps, omegas = np.unique(c["amplitude"]), np.unique(c["omega"])
    grid = np.full((len(amps), len(omegas)), np.nan)
    for a, w, d in zip(c["amplitude"], c["omega"], c["max_deviation"], strict=True):
        grid[np.searchsorted(amps, a), np.searchsorted(omegas, w)] = d
    reach = float(c["reach_forward"][0])
    w_edges, a_edges = _cell_edges(omegas, True), _cell_edges(amps, False) * 1000  # [rad/s], [mm/s]

    fig, (ax, ax2) = plots.figure(1, 2, figsize=(14, 6.5))
    dev_mm = np.maximum(grid * 1000, DEVIATION_FLOOR_MM)
    top = 10 ** math.ceil(math.log10(max(float(np.nanmax(dev_mm)), 1e-3)))
    mesh = ax.pcolormesh(w_edges, a_edges, dev_mm, norm=LogNorm(vmin=DEVIATION_FLOOR_MM, vmax=top), cmap="magma")
    bar = fig.colorbar(mesh, ax=ax, label="max deviation from the line (y and z)")
    bar.ax.yaxis.set_major_locator(LogLocator(base=10, numticks=20))
    bar.ax.yaxis.set_major_formatter(FuncFormatter(plots.length_mm))
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
        fontsize=plots.TITLE_FONTSIZE,
    )

    dev = np.maximum(c["max_deviation"] * 1000, DEVIATION_FLOOR_MM)
    w_norm = LogNorm(vmin=omegas[0], vmax=omegas[-1]) if len(omegas) > 1 else LogNorm(omegas[0] / 1.5, omegas[0] * 1.5)
    scatter = ax2.scatter(c["excursion_forward"] / reach, dev, c=c["omega"], cmap="viridis", norm=w_norm)
    bar = fig.colorbar(scatter, ax=ax2, label="ω [rad/s]")
    bar.ax.yaxis.set_minor_locator(NullLocator())
    bar.set_ticks(list(omegas), labels=[f"{w:.3g}" for w in omegas])
    ax2.axvline(1.0, color="tab:red", linestyle="--")
    ax2.set_yscale("log")
    plots.decades(ax2, float(dev.min()), float(dev.max()))
    ax2.set_xlim(0, max(1.1, float(np.max(c["excursion_forward"] / reach)) * 1.05))
    ax2.set_xlabel("excursion 2A/ω ÷ reach along the line")
    ax2.set_ylabel("max deviation from the line (y and z)")
    ax2.grid(alpha=0.3, which="major")
    ax2.set_title(
        "all frequencies collapse onto the excursion: it is A/ω, not ω, that matters\nred dashed: excursion = reach",
        fontsize=plots.TITLE_FONTSIZE,
    )
    p = result.params
    fig.suptitle(
        f"{result.scenario}: {p.mode} mode, {p.profile} profile, {p.periods:g} periods per cell, start "
        f"{plots.point_mm((p.start_x, p.start_y, p.start_z))} in the hip frame"
    )
    return {"sweep": fig, "workspace": leg_figures.workspace_figure(result)}
