"""A sweep's figures: each metric against one swept parameter, or as a heatmap over two."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from hexabot_sim.sweep import ERROR_COLUMN, Plan, Table, cell_text

if TYPE_CHECKING:
    from matplotlib.figure import Figure

HEATMAP_LABELS_MAX: int = 12  # an axis with more values labels every k-th only
ANNOTATE_MAX_CELLS: int = 100  # heatmaps up to this many cells print each value in its cell
DECADES_FOR_LOG: float = 2.0  # positive values spanning this many decades get a log scale
CONSTANT_RTOL: float = 1e-12  # a metric that varies less than this (round-off) is not plotted


def _numeric(values: Sequence[Any]) -> np.ndarray | None:
    """Floats of a metric column (None -> nan, bools -> 0/1), or None if it holds text."""
    out = []
    for v in values:
        if isinstance(v, str):
            return None
        out.append(np.nan if v is None else float(v))
    return np.array(out, dtype=float)


def _spans_decades(values: np.ndarray) -> bool:
    finite = values[np.isfinite(values)]
    return bool(len(finite) and (finite > 0).all() and math.log10(finite.max() / finite.min()) >= DECADES_FOR_LOG)


def plotted_metrics(t: Table) -> dict[str, np.ndarray]:
    """Metric column -> values, for the metrics that are numbers and not the same in every cell that ran.

    A metric that is null in some cells that ran (e.g. a settling time never reached) is drawn too.
    """
    ran = np.array([not e for e in t.column(ERROR_COLUMN)], dtype=bool)
    out = {}
    for name in t.metrics:
        values = _numeric(t.column(name))
        if values is None:
            continue
        finite = values[ran & np.isfinite(values)]
        if not len(finite):
            continue
        spread = np.ptp(finite) > CONSTANT_RTOL * np.abs(finite).max()
        if spread or len(finite) < ran.sum():
            out[name] = values
    return out


def _axis_label(name: str, unit: str) -> str:
    return f"{name} [{unit}]" if unit and unit != "1" else name


def figures(p: Plan, t: Table) -> dict[str, Figure]:
    """One figure per plotted metric (file stem = metric): a curve over one axis, a heatmap over two.

    Three or more swept parameters give no figures (plot sweep.csv as you need).
    """
    if len(p.axes) not in (1, 2):
        return {}
    metrics = plotted_metrics(t)
    failed = np.array([bool(e) for e in t.column(ERROR_COLUMN)])
    draw = _curve if len(p.axes) == 1 else _heatmap
    return {name: draw(p, t, name, values, failed) for name, values in metrics.items()}


def _title(p: Plan, t: Table, name: str) -> str:
    import textwrap

    doc = textwrap.shorten(t.docs.get(name, ""), 200, placeholder=" ...")
    return f"{p.scenario}: {name}" + (f"\n{textwrap.fill(doc, 100)}" if doc else "")


def _curve(p: Plan, t: Table, name: str, values: np.ndarray, failed: np.ndarray) -> Figure:
    from hexabot_sim import plots

    axis = p.axes[0]
    fig, ax = plots.figure(figsize=(8, 5))
    xs = _numeric(list(axis.values))
    categorical = xs is None
    x = np.arange(len(axis.values), dtype=float) if categorical else xs
    ax.plot(x, values, "o-", color="tab:blue", label=name)
    if failed.any():
        for xf in x[failed]:
            ax.axvline(xf, color="tab:red", alpha=0.3, lw=6)
        ax.plot([], [], color="tab:red", alpha=0.3, lw=6, label="cell failed (see the error column)")
    null = ~failed & ~np.isfinite(values)  # cells that ran without a value (e.g. a pendulum not yet settled)
    if null.any():  # marked as the heatmap's grey cells are, so the grid's ends are not silently cut off
        for xn in x[null]:
            ax.axvline(xn, color="0.5", alpha=0.3, lw=6)
        ax.plot([], [], color="0.5", alpha=0.3, lw=6, label="cell without a value (null)")
    if failed.any() or null.any():
        plots.legend_above(ax, ncol=2)
    if categorical:
        ax.set_xticks(x, [cell_text(v) for v in axis.values])
    elif axis.log or _spans_decades(x):
        ax.set_xscale("log")
    if _spans_decades(values):
        ax.set_yscale("log")
    else:
        ax.ticklabel_format(axis="y", useOffset=False)
    ax.set_xlabel(_axis_label(axis.name, t.units.get(axis.name, "")))
    ax.set_ylabel(_axis_label(name, t.units.get(name, "")))
    ax.grid(alpha=0.3, which="both")
    fig.suptitle(_title(p, t, name), fontsize=plots.TITLE_FONTSIZE)  # above the legend of marked cells
    return fig


def _ticks(values: Sequence[Any]) -> tuple[list[int], list[str]]:
    step = max(1, math.ceil(len(values) / HEATMAP_LABELS_MAX))
    index = list(range(0, len(values), step))
    return index, [f"{v:.4g}" if isinstance(v, float) else cell_text(v) for v in (values[i] for i in index)]


def _heatmap(p: Plan, t: Table, name: str, values: np.ndarray, failed: np.ndarray) -> Figure:
    """Rows: the first swept parameter; columns: the second; each cell drawn the same size (grid values labelled)."""
    from matplotlib.colors import LogNorm, Normalize

    from hexabot_sim import plots

    rows, cols = p.axes
    grid = values.reshape(p.shape)  # (len(rows), len(cols)), row-major like the cells
    bad = failed.reshape(p.shape)
    finite = grid[np.isfinite(grid)]
    log = _spans_decades(finite)
    low, high = (float(finite.min()), float(finite.max())) if len(finite) else (0.0, 1.0)
    norm = LogNorm(low, high) if log else Normalize(low, high if high > low else low + 1)
    fig, ax = plots.figure(figsize=(8.5, 6.5))
    masked = np.ma.masked_invalid(grid)
    mesh = ax.pcolormesh(np.arange(len(cols.values) + 1) - 0.5, np.arange(len(rows.values) + 1) - 0.5, masked,
                         cmap="viridis", norm=norm)  # fmt: skip
    ax.set_facecolor("0.85")  # cells without a value (failed or null) show grey
    bar = fig.colorbar(mesh, ax=ax, label=_axis_label(name, t.units.get(name, "")) + (" (log scale)" if log else ""))
    if not log:  # full values on the ticks: an offset ("1e-8 + ...") above the bar is easily missed
        bar.ax.ticklabel_format(axis="y", useOffset=False)
    if bad.any():
        r, c = np.nonzero(bad)
        ax.plot(c, r, "x", color="tab:red", ms=12, mew=2, label="cell failed (see the error column)")
        plots.legend_above(ax, ncol=1)
    if grid.size <= ANNOTATE_MAX_CELLS:
        for (i, j), v in np.ndenumerate(grid):
            if np.isfinite(v):
                shade = norm(v)
                ax.text(j, i, f"{v:.3g}", ha="center", va="center", fontsize=7,
                        color="black" if shade > 0.6 else "white")  # fmt: skip
            elif not bad[i, j]:
                ax.text(j, i, "null", ha="center", va="center", fontsize=7, color="0.3")
    for setter, axis in ((ax.set_xticks, cols), (ax.set_yticks, rows)):
        index, labels = _ticks(axis.values)
        setter(index, labels)
    ax.set_xlabel(_axis_label(cols.name, t.units.get(cols.name, "")) + (" (log-spaced)" if cols.log else ""))
    ax.set_ylabel(_axis_label(rows.name, t.units.get(rows.name, "")) + (" (log-spaced)" if rows.log else ""))
    ax.set_title(_title(p, t, name), fontsize=plots.TITLE_FONTSIZE)
    return fig
