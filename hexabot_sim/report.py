"""report.html of a run folder: one self-contained page (relative links, no script) showing everything the run wrote."""

from __future__ import annotations

import html
import math
import struct
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from hexabot_sim.errors import encodable

# What each data file holds, for the links section.
LONG_VALUE: int = 40  # [characters] a longer value wraps in its cell (unit and meaning stay beside it)
FILE_DOCS: dict[str, str] = {
    "timeseries.csv": "time series, one row per recorded step; first column t [s], SI units",
    "grid.csv": "one row per grid cell",
    "run.json": "parameters, metrics, units, versions (machine-readable)",
    "model.xml": "the exact MJCF that was simulated (loading it reproduces the run)",
    "trajectory.npz": "full recorded state: t, qpos, qvel, ctrl (numpy.load)",
    "video.mp4": "the video (H.264)",
    "sweep.csv": "one row per grid cell: the swept parameters, every scalar metric, its run warnings, the error of a "
    "failed cell",
    "sweep.json": "grid, fixed parameters, units, failed cells, executor, timing, versions",
}

STYLE = """
:root { color-scheme: light dark; --fg: #1d1d1f; --bg: #fff; --muted: #5f6368; --line: #d9dce0; --head: #f3f4f6;
        --accent: #0b57d0; --warn: #fff4e5; }
@media (prefers-color-scheme: dark) {
  :root { --fg: #e8eaed; --bg: #16181b; --muted: #a0a5ab; --line: #3a3f45; --head: #23272c; --accent: #8ab4f8;
          --warn: #3b2a12; }
  figure img { background: #fff; }
}
* { box-sizing: border-box; }
html { -webkit-text-size-adjust: 100%; text-size-adjust: 100%; }
body { margin: 0 auto; max-width: 1200px; padding: 1.5rem 1.25rem 3rem; color: var(--fg); background: var(--bg);
       font: 16px/1.5 system-ui, -apple-system, "Segoe UI", Roboto, "Helvetica Neue", Arial, sans-serif; }
h1 { font-size: 1.7rem; margin: 0 0 .25rem; word-break: break-word; }
h2 { font-size: 1.25rem; margin: 2rem 0 .6rem; padding-bottom: .25rem; border-bottom: 1px solid var(--line); }
a { color: var(--accent); }
code, .num { font-family: ui-monospace, SFMono-Regular, Menlo, Consolas, monospace; font-size: .92em; }
.lead { margin: 0 0 .5rem; color: var(--muted); }
.summary { margin: .5rem 0 0; padding: .6rem .8rem; background: var(--head); border-radius: 6px; }
.warning { margin: .5rem 0 0; padding: .6rem .8rem; background: var(--warn); border-left: 4px solid #d9822b;
  border-radius: 6px; overflow-wrap: anywhere; }
.files { display: flex; flex-wrap: wrap; gap: .5rem; padding: 0; margin: 0; list-style: none; }
.files li { border: 1px solid var(--line); border-radius: 6px; padding: .35rem .6rem; max-width: 100%; }
.files span { color: var(--muted); font-size: .85em; }
.figures { display: grid; grid-template-columns: repeat(auto-fit, minmax(min(100%, 520px), 1fr)); gap: 1rem; }
figure { margin: 0; }
figure img { display: block; width: 100%; height: auto; border: 1px solid var(--line); border-radius: 4px; }
figcaption { font-size: .85em; color: var(--muted); margin-top: .2rem; }
video { display: block; width: 100%; height: auto; background: #000; border-radius: 4px; }
.scroll { overflow-x: auto; -webkit-overflow-scrolling: touch; }
table { border-collapse: collapse; width: 100%; font-size: .95em; }
th, td { text-align: left; vertical-align: top; padding: .35rem .6rem; border-bottom: 1px solid var(--line); }
th { background: var(--head); white-space: nowrap; }
td.num { white-space: nowrap; }
td.num.long { white-space: normal; overflow-wrap: anywhere; min-width: 16rem; }
td.doc { min-width: 14rem; color: var(--muted); }
tr.key td:first-child { font-weight: 600; }
footer { margin-top: 2.5rem; font-size: .85em; color: var(--muted); }
@media (max-width: 600px) {
  body { padding: 1rem .75rem 2rem; font-size: 15px; }
  h1 { font-size: 1.35rem; }
  /* Tables become one card per row: name, value and unit on a line, the meaning below. */
  thead { display: none; }
  table, tbody { display: block; }
  tr { display: flex; flex-wrap: wrap; align-items: baseline; gap: 0 .5rem; padding: .4rem 0;
       border-bottom: 1px solid var(--line); }
  td { border: 0; padding: 0; }
  td:first-child { flex: 1 1 auto; }
  td.num { white-space: normal; word-break: break-all; }
  td.doc { flex: 1 0 100%; min-width: 0; font-size: .9em; }
}
"""


def _e(text: Any) -> str:
    # A file name that is not UTF-8 (robot=b\xff.toml) comes as lone surrogates: written as \xff, not a crash at the
    # end of the run (UnicodeEncodeError writing report.html).
    return html.escape(encodable(str(text)), quote=True)


def format_value(value: Any) -> str:
    """A parameter or metric value as text: numbers to 8 significant digits, lists comma-separated, a list of rows
    (a schedule, waypoints) one bracketed row after another, a row's empty cell "–" (a schedule's "as before")."""
    if value is None:
        return "n/a"
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float):
        return f"{value:.8g}" if math.isfinite(value) else "n/a"
    if isinstance(value, (list, tuple)):
        if any(isinstance(v, (list, tuple)) for v in value):  # rows: they were flattened into one list
            return "; ".join(f"[{_cells(v)}]" if isinstance(v, (list, tuple)) else format_value(v) for v in value)
        return ", ".join(format_value(v) for v in value)
    return str(value)


def _cells(row: Sequence[Any]) -> str:
    return ", ".join("–" if v is None else format_value(v) for v in row)


def _unit(unit: str) -> str:
    return "" if unit in ("", "1") else unit


def _png_size(path: Path) -> tuple[int, int] | None:
    """(width, height) [px] from a PNG's header, None if it is not a readable PNG."""
    try:
        with open(path, "rb") as f:
            head = f.read(24)
    except OSError:
        return None
    if len(head) < 24 or head[:8] != b"\x89PNG\r\n\x1a\n":
        return None
    width, height = struct.unpack(">II", head[16:24])
    return int(width), int(height)


def _table(rows: Mapping[str, Any], units: Mapping[str, str], docs: Mapping[str, str], key: Sequence[str] = ()) -> str:
    lines = [
        '<div class="scroll"><table>',
        "<thead><tr><th>name</th><th>value</th><th>unit</th><th>meaning</th></tr></thead><tbody>",
    ]
    for name, value in rows.items():
        cls = ' class="key"' if name in key else ""
        text = format_value(value)
        wrap = " long" if len(text) > LONG_VALUE else ""  # a long path or schedule pushed unit and meaning off the page
        lines.append(
            f'<tr{cls}><td><code>{_e(name)}</code></td><td class="num{wrap}">{_e(text)}</td>'
            f'<td>{_e(_unit(units.get(name, "")))}</td><td class="doc">{_e(docs.get(name, ""))}</td></tr>'
        )
    lines.append("</tbody></table></div>")
    return "\n".join(lines)


def summary_line(record: Mapping[str, Any], key: Sequence[str]) -> str:
    """The key metrics in one line: "name = value unit; ..." (plain text)."""
    units = record["units"]["metrics"]
    parts = []
    for name in key:
        if name in record["metrics"]:
            unit = _unit(units.get(name, "")) if record["metrics"][name] is not None else ""
            parts.append(f"{name} = {format_value(record['metrics'][name])}{' ' + unit if unit else ''}")
    return "; ".join(parts)


def html_page(
    record: Mapping[str, Any], param_docs: Mapping[str, str], key_metrics: Sequence[str], folder: Path
) -> str:
    """The report page of a run folder.

    Args:
        record: The run.json content.
        param_docs: Parameter name -> one-line meaning.
        key_metrics: Names of the metrics that sum the run up (shown first, in bold in the table).
        folder: The folder the page is written to (its PNGs give the images' sizes).

    Returns:
        The HTML text: every text escaped, every link relative, no script, no network.
    """
    scenario = record["scenario"]
    files: list[str] = list(record["files"])
    figures = [name for name in files if name.endswith(".png")]
    data_files = [name for name in files if not name.endswith(".png") and name != "report.html"]
    video = record.get("video") or {}
    simulation = record.get("simulation") or {}

    out = [
        "<!DOCTYPE html>",
        '<html lang="en">',
        "<head>",
        '<meta charset="utf-8">',
        '<meta name="viewport" content="width=device-width, initial-scale=1">',
        f"<title>{_e(scenario)} — hexabot-sim run</title>",
        f"<style>{STYLE}</style>",
        "</head>",
        "<body>",
        "<header>",
        f"<h1>{_e(scenario)}</h1>",
        f'<p class="lead">{_e(record.get("description", ""))}</p>',
    ]
    line = summary_line(record, key_metrics)
    if line:
        out.append(f'<p class="summary">{_e(line)}</p>')
    for warning in record.get("warnings") or []:  # what the figures say against the run's physics
        out.append(f'<p class="warning"><b>Warning:</b> {_e(warning)}</p>')
    out.append("</header>")

    out += ["<section>", "<h2>Files</h2>", '<ul class="files">']
    for name in data_files:
        doc = FILE_DOCS.get(name, "")
        out.append(f'<li><a href="{_e(name)}">{_e(name)}</a>{" <span>" + _e(doc) + "</span>" if doc else ""}</li>')
    out += ["</ul>", "</section>"]

    if video.get("written"):
        width, height = video.get("size") or (640, 480)
        out += [
            "<section>",
            "<h2>Video</h2>",
            f'<video controls muted playsinline preload="metadata" width="{int(width)}" height="{int(height)}" '
            f'style="max-width: {int(width)}px" src="{_e(video.get("file", "video.mp4"))}">'
            f'<a href="{_e(video.get("file", "video.mp4"))}">video.mp4</a></video>',
            "</section>",
        ]

    if figures:
        out += ["<section>", "<h2>Figures</h2>", '<div class="figures">']
        for name in figures:
            size = _png_size(folder / name)
            dims = f' width="{size[0]}" height="{size[1]}"' if size else ""
            stem = name.removesuffix(".png").replace("_", " ")
            out.append(
                f'<figure><a href="{_e(name)}"><img src="{_e(name)}" alt="{_e(stem)}"{dims}></a>'
                f"<figcaption>{_e(name)}</figcaption></figure>"
            )
        out += ["</div>", "</section>"]

    out += [
        "<section>",
        "<h2>Metrics</h2>",
        _table(record["metrics"], record["units"]["metrics"], record.get("metric_docs", {}), key_metrics),
        "</section>",
        "<section>",
        "<h2>Parameters</h2>",
        _table(record["params"], record["units"]["params"], param_docs),
        "</section>",
    ]

    facts = []
    if simulation.get("simulated_time") is not None:
        facts.append(f"{format_value(simulation['simulated_time'])} s simulated in {simulation['steps']} steps")
    if not video.get("written") and video.get("reason"):
        facts.append(f"no video: {video['reason']}")
    versions = record.get("versions") or {}
    if versions:
        facts.append(", ".join(f"{name} {version}" for name, version in versions.items() if name != "platform"))
    out += ["<footer>", *(f"<p>{_e(fact)}</p>" for fact in facts), "</footer>", "</body>", "</html>", ""]
    return "\n".join(out)


def sweep_page(record: Mapping[str, Any], param_docs: Mapping[str, str], folder: Path) -> str:
    """The report page of a sweep folder (sweep.json's record): the grid, the fixed parameters, the figures."""
    grid = record["grid"]
    shape = " x ".join(f"{len(axis['values'])} {axis['name']}" for axis in grid)
    timing = record.get("timing") or {}
    metrics = {
        "cells": record["cells"],
        "failed_cells": len(record.get("failed_cells") or []),
        "warned_cells": len(record.get("warned_cells") or []),
        "wall_time": timing.get("wall_time"),
        "parallel_speedup": timing.get("parallel_speedup"),
    }
    units = {"cells": "1", "failed_cells": "1", "warned_cells": "1", "wall_time": "s", "parallel_speedup": "1"}
    docs = {
        "cells": f"grid cells ({shape}); row i of sweep.csv is cell i",
        "failed_cells": "cells whose run failed (a row with its error in sweep.csv)",
        "warned_cells": "cells whose run warned (a row with its warnings in sweep.csv)",
        "wall_time": "wall time of the whole sweep",
        "parallel_speedup": "summed cell time / wall time",
    }
    param_units = dict(record["units"]["params"])
    params: dict[str, Any] = {}
    for axis in grid:
        values = ", ".join(format_value(v) for v in axis["values"])
        params[axis["name"]] = f"swept: {values}"
    params |= record.get("fixed", {})
    page_record = {
        "scenario": f"sweep of {record['scenario']}",
        "description": f"{record.get('description', '')} ({shape} grid)",
        "files": list(record.get("files", [])),
        "metrics": metrics,
        "params": params,
        "units": {"metrics": units, "params": param_units},
        "metric_docs": docs,
        "versions": record.get("versions") or {},
    }
    return html_page(page_record, param_docs, ["cells", "failed_cells", "warned_cells", "wall_time"], folder)
