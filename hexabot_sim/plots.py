"""Shared figure style and helpers for the scenarios' own figures; never simulates, writes files or picks a backend."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

TARGET_STYLE: dict[str, Any] = {"color": "tab:red", "linestyle": "--", "linewidth": 1.2}  # a commanded value
REST_STYLE: dict[str, Any] = {"color": "tab:green", "linestyle": ":", "linewidth": 1.5}  # a predicted rest value
LEGEND_FONTSIZE: float = 8  # [pt]
TITLE_FONTSIZE: float = 10  # [pt] figure titles (suptitle) and axes titles


def use_agg() -> None:
    """Selects matplotlib's non-interactive Agg backend. FOR THE CLI ONLY; never called on import.

    The scenarios' figures are made without pyplot (plain `Figure` objects, see `figure`), so they
    need no backend and a notebook keeps its own; the CLI may call this before anything imports pyplot.
    """
    import matplotlib

    matplotlib.use("Agg")


# ---------------------------------------------------------------------------------------------
# Shared style: constrained layout, titles on the figure, legends outside the data.


def figure(nrows: int = 1, ncols: int = 1, figsize: tuple[float, float] = (9, 6), **kw: Any) -> tuple[Figure, Any]:
    """A figure with constrained layout (made without pyplot) and its axes."""
    fig = Figure(figsize=figsize, layout="constrained")
    return fig, fig.subplots(nrows, ncols, **kw)


def legend_above(ax: Axes, ncol: int = 3, **kw: Any) -> None:
    """The axes' legend in a row above it: outside the data, whatever the data does."""
    ax.legend(
        loc="lower left", bbox_to_anchor=(0.0, 1.01), ncol=ncol, fontsize=LEGEND_FONTSIZE, frameon=False,
        borderaxespad=0.0, **kw,
    )  # fmt: skip


def legend_right(ax: Axes, **kw: Any) -> None:
    """The axes' legend to its right, outside the data."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=LEGEND_FONTSIZE, borderaxespad=0.0, **kw)


def plain(ax: Axes) -> None:
    """Tick labels as plain numbers: no '+2.2e2' offset, no '1e-3' multiplier above the axis."""
    ax.ticklabel_format(axis="y", useOffset=False, style="plain")


def min_span(ax: Axes, span: float) -> None:
    """Keeps a y axis at least `span` tall so round-off (1e-17) is not blown up to full height."""
    low, high = ax.get_ylim()
    if high - low < span:
        mid = 0.5 * (low + high)
        ax.set_ylim(mid - span / 2, mid + span / 2)


def length_mm(value: float, _pos: Any = None) -> str:
    """A length given in [mm] as a readable label: 10 mm, 1 mm, 100 µm, 1 µm, 10 nm."""
    if value >= 1:
        return f"{value:g} mm"
    if value >= 1e-3:
        return f"{value * 1e3:.3g} µm"
    return f"{value * 1e6:.3g} nm"


def decades(ax: Axes, low: float, high: float) -> None:
    """A log y axis from whole decades around [low, high] (at least one), labelled as lengths in mm."""
    lo = 10 ** math.floor(math.log10(low))
    hi = 10 ** math.ceil(math.log10(high))
    ax.set_ylim(lo, hi if hi > lo else 10 * lo)
    ax.yaxis.set_major_locator(LogLocator(base=10, numticks=20))
    ax.yaxis.set_major_formatter(FuncFormatter(length_mm))
    ax.yaxis.set_minor_formatter(NullFormatter())


def point_mm(values: Sequence[float]) -> str:
    """A point given in [m] as a label in mm: "(50, 0, 220) mm"."""
    return "(" + ", ".join(f"{v * 1000:.4g}" for v in values) + ") mm"


def shade_singular(ax: Axes, t: np.ndarray, near: np.ndarray, label: bool = False) -> None:
    """Shades the intervals of `t` where `near` (e.g. sigma_min(J) below its damping threshold) is true."""
    edges = np.flatnonzero(np.diff(np.r_[0, near.astype(int), 0]))
    for n, (start, stop) in enumerate(zip(edges[::2], edges[1::2], strict=True)):
        ax.axvspan(
            t[start], t[min(stop, len(t) - 1)], color="tab:red", alpha=0.12, lw=0,
            label="near-singular (σ_min < threshold)" if label and n == 0 else None,
        )  # fmt: skip
