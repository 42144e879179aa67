"""Side by side: the parameters and metrics of two or more run folders, and their shared columns overlaid."""

from __future__ import annotations

import csv
import dataclasses
import io
import itertools
import json
import math
import re
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from hexabot_sim.errors import UsageError, printable
from hexabot_sim.params import read_bounded

if TYPE_CHECKING:
    from matplotlib.figure import Figure

CSV_NAME = "compare.csv"
JSON_NAME = "compare.json"
RUN_JSON = "run.json"
PANELS_PER_FIGURE: int = 6  # shared columns per overlay figure (overlay.png, overlay_2.png, ...)
LEGEND_RUNS: int = 20  # runs named in an overlay's legend; more are drawn without one
MAX_POINTS: int = 20_000  # points drawn per line; longer columns are thinned evenly (the CSV keeps them all)
CHUNK_ROWS: int = 1 << 18  # CSV rows parsed at a time (memory stays bounded whatever the CSV's size)
ANNOUNCE_BYTES: int = 200 << 20  # a CSV this large (~8 s to read) is read with a line at every quarter
MAX_JSON_BYTES: int = 16 << 20  # a run.json is a few kB; one larger than this is not read
MAX_HEADER_BYTES: int = 1 << 16  # a CSV header line is at most this long
RELATIVE_FLOOR: float = 0.01  # a relative difference needs a reference at least this fraction of the other value
MAX_CSV_BYTES: float = 2e9  # a run folder's CSV is at most this large (budget.MAX_OUTPUT_BYTES)


@dataclasses.dataclass
class Run:
    """One run folder as compare reads it."""

    path: Path
    label: str
    scenario: str
    params: dict[str, Any]
    metrics: dict[str, Any]
    units: dict[str, dict[str, str]]  # "params", "metrics", "columns" -> name -> unit
    csv: Path


def load(folder: str) -> Run:
    """Reads a run folder's run.json and finds its CSV.

    Raises:
        UsageError: with the reason, for anything that is not a complete run folder.
    """
    path = Path(folder)
    shown = repr(printable(folder))
    if not path.is_dir():
        raise UsageError(f"{shown} is not a run folder: {'no such folder' if not path.exists() else 'not a folder'}")
    if path.name.startswith(".hexabot-sim-"):
        raise UsageError(f"{shown} is not a run folder: it is the staging folder of an unfinished or killed run")
    record_path = path / RUN_JSON
    if not record_path.is_file():
        if (path / "sweep.json").is_file():
            raise UsageError(
                f"{shown} is a sweep folder, not a run folder: compare its cells (sweep with --keep-runs, then "
                "compare cells/cell-0000 cells/cell-0001 ...) or read its sweep.csv"
            )
        raise UsageError(f"{shown} is not a run folder: it has no {RUN_JSON}")
    raw = read_bounded(record_path, "run record", MAX_JSON_BYTES, "a run's record is far smaller")
    try:
        record = json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError) as e:
        raise UsageError(f"{shown} is not a run folder: its {RUN_JSON} cannot be read ({type(e).__name__})") from None
    if not isinstance(record, dict):
        raise UsageError(f"{shown} is not a run folder: its {RUN_JSON} is not an object")
    for key, kind in (("scenario", str), ("params", dict), ("metrics", dict), ("files", list)):
        if not isinstance(record.get(key), kind):
            raise UsageError(f"{shown} is not a run folder: its {RUN_JSON} has no '{key}'")
    names = [f for f in record["files"] if isinstance(f, str) and f.endswith(".csv") and "/" not in f]
    if not names:
        raise UsageError(f"{shown} is not a run folder: its {RUN_JSON} names no CSV file")
    table = path / names[0]
    if not table.is_file():
        raise UsageError(f"{shown} is not a complete run folder: {names[0]} is missing")
    if table.stat().st_size > MAX_CSV_BYTES:
        raise UsageError(f"{shown}: {names[0]} is larger than a run folder's CSV can be")
    units = record.get("units") if isinstance(record.get("units"), dict) else {}
    units = {
        k: v if isinstance(v, dict) else {} for k, v in ((k, units.get(k)) for k in ("params", "metrics", "columns"))
    }
    scenario = printable(record["scenario"])
    run = Run(path, printable(path.name), scenario, record["params"], record["metrics"], units, table)
    names = header(run)
    if len(names) < 1 or len(set(names)) != len(names) or not all(names):
        raise UsageError(f"{shown}: the first line of {table.name} is not a header of distinct column names")
    return run


def load_all(folders: Sequence[str]) -> list[Run]:
    """Loads two or more distinct run folders; labels are their folder names (made unique)."""
    if len(folders) < 2:
        raise UsageError("compare needs at least two run folders")
    runs = [load(f) for f in folders]
    seen: dict[Path, str] = {}
    for run, text in zip(runs, folders, strict=True):
        key = run.path.resolve()
        if key in seen:
            raise UsageError(f"{text!r} is the same run folder as {seen[key]!r}; give different runs")
        seen[key] = text
    labels = [r.label for r in runs]
    for k, run in enumerate(runs):
        if labels.count(run.label) > 1:
            run.label = f"{run.label}#{k + 1}"
    labels = [r.label for r in runs]
    for k, run in enumerate(runs):  # a folder named like a made label (run, run and run#2: two "run#2" columns)
        while labels.count(run.label) > 1:
            run.label = labels[k] = f"{run.label}#{k + 1}"
    return runs


# ---------------------------------------------------------------------------------------------
# The table: parameters (differing first), then metrics with differences to the first run


@dataclasses.dataclass(frozen=True)
class Row:
    """One compared quantity: its values in every run and whether they differ."""

    kind: str  # "param" or "metric"
    name: str
    unit: str
    values: tuple[Any, ...]  # one per run; None where a run does not have it

    @property
    def differs(self) -> bool:
        return any(v != self.values[0] for v in self.values[1:])

    def differences(self) -> list[tuple[float, float | None] | None]:
        """(value - first, relative) for each run after the first; None where not numbers or it overflows."""
        first = self.values[0]
        out: list[tuple[float, float | None] | None] = []
        for v in self.values[1:]:
            d = float(v) - float(first) if _is_number(first) and _is_number(v) else math.nan
            if math.isfinite(d):  # not when the difference of two finite values overflows (-1e308 to 1e308)
                # Relative only against a reference that is not small beside the other value (at most +-9900 %):
                # a difference from a value near zero (1e-9 vs 0.05) is shown absolute only.
                meaningful = abs(float(first)) >= RELATIVE_FLOOR * max(abs(float(first)), abs(float(v))) > 0
                out.append((d, d / abs(float(first)) if meaningful else None))
            else:
                out.append(None)
        return out


def _is_number(v: Any) -> bool:
    """A finite int or float that a float can hold (a run.json may hold a 400-digit integer)."""
    if not isinstance(v, (int, float)) or isinstance(v, bool):
        return False
    try:
        return math.isfinite(float(v))
    except OverflowError:
        return False


def rows(runs: Sequence[Run]) -> list[Row]:
    """Parameters (those that differ first, then the same), then metrics in the first run's order."""
    out = []
    for kind, attr in (("param", "params"), ("metric", "metrics")):
        names: dict[str, None] = {}
        for run in runs:
            names |= dict.fromkeys(getattr(run, attr))
        found = []
        for name in names:
            unit = next((r.units[attr].get(name) for r in runs if r.units[attr].get(name) is not None), "")
            values = tuple(getattr(r, attr).get(name) for r in runs)
            if all(not isinstance(v, (dict, list)) for v in values) or kind == "param":
                found.append(Row(kind, name, unit, tuple(_plain(v) for v in values)))
        if kind == "param":
            found.sort(key=lambda r: not r.differs)  # stable: declaration order within each group
        out += found
    return out


def _plain(v: Any) -> Any:
    return tuple(v) if isinstance(v, list) else v


def _show(v: Any) -> str:
    if v is None:
        return "-"
    if isinstance(v, bool):
        return str(v).lower()
    if isinstance(v, float):
        return f"{v:.6g}"
    if isinstance(v, (tuple, list)):
        if any(isinstance(x, (tuple, list)) for x in v):  # a table (a schedule, a course): rows by "; "
            return "; ".join(" ".join(_show(x) for x in row) if isinstance(row, (tuple, list)) else _show(row)
                             for row in v)  # fmt: skip
        return ",".join(_show(x) for x in v)
    return printable(str(v))  # a file name that is not UTF-8 (robot=\xff.toml): lone surrogates crashed the CSV


def _difference(d: tuple[float, float | None] | None, same: bool) -> str:
    if d is None:
        return "" if same else "differs"
    diff, rel = d
    if diff == 0:
        return "0"
    return f"{diff:+.4g}" + (f" ({rel * 100:+.3g} %)" if rel is not None else "")


def text(runs: Sequence[Run], table: Sequence[Row]) -> str:
    """The table as aligned text: a '*' marks a quantity that differs between the runs."""
    labels = [r.label for r in runs]
    header = ["", *labels, *[f"{lab} - {labels[0]}" for lab in labels[1:]]]
    lines = []
    for kind, title in (("param", "parameters (differing first)"), ("metric", "metrics")):
        lines.append([title, *header[1:]])
        for row in (r for r in table if r.kind == kind):
            unit = f" [{row.unit}]" if row.unit and row.unit != "1" else ""
            diffs = [] if kind == "param" else [_difference(d, not row.differs) for d in row.differences()]
            diffs += [""] * (len(labels) - 1 - len(diffs))
            cells = [f"{'*' if row.differs else ' '} {row.name}{unit}", *map(_show, row.values), *diffs]
            lines.append([printable(cell) for cell in cells])  # names and values from run.json: no ESC, no CR
        lines.append(None)  # type: ignore[arg-type]
    widths = [max(len(line[k]) for line in lines if line is not None) for k in range(len(header))]
    widths = [min(w, 40) for w in widths]
    out = []
    for line in lines:
        if line is None:
            out.append("")
            continue
        out.append("  ".join(cell.ljust(w) if k == 0 else cell.rjust(w) for k, (cell, w) in
                             enumerate(zip(line, widths, strict=True))).rstrip())  # fmt: skip
    return "\n".join(out).rstrip() + "\n"


def write_csv(path: Path, runs: Sequence[Run], table: Sequence[Row]) -> None:
    """compare.csv: kind, name, unit, differs, one value column per run, one difference column per later run."""
    labels = [r.label for r in runs]
    with open(path, "w", newline="") as stream:
        writer = csv.writer(stream, lineterminator="\n")
        writer.writerow(["kind", "name", "unit", "differs", *labels, *[f"{lab} - {labels[0]}" for lab in labels[1:]]])
        for row in table:
            values = [
                "" if v is None else (format(v, ".17g") if isinstance(v, float) else _show(v)) for v in row.values
            ]
            diffs = ["" if d is None else format(d[0], ".17g") for d in row.differences()]
            writer.writerow([row.kind, row.name, row.unit, str(row.differs).lower(), *values, *diffs])


def record(runs: Sequence[Run], table: Sequence[Row], shared: Sequence[str], files: Sequence[str]) -> dict:
    """compare.json: the runs, which parameters differ, the shared columns overlaid, the files."""
    return {
        "runs": [{"label": r.label, "folder": printable(str(r.path)), "scenario": r.scenario} for r in runs],
        "differing_params": [r.name for r in table if r.kind == "param" and r.differs],
        "differing_metrics": [r.name for r in table if r.kind == "metric" and r.differs],
        "shared_columns": list(shared),
        "files": list(files),
    }


# ---------------------------------------------------------------------------------------------
# Overlays of the shared columns


def _read(run: Run, announce: Callable[[str], None] | None = None) -> tuple[list[str], np.ndarray]:
    """The CSV's columns, every row checked, at most MAX_POINTS rows kept (evenly: what the overlay draws).

    Read in chunks of CHUNK_ROWS, so a 2 GB CSV neither fills memory nor reads in silence: a CSV of at least
    ANNOUNCE_BYTES is announced to `announce` at the start and at every quarter.
    """
    shown = repr(printable(str(run.path)))
    names = header(run)
    kept, done, at = [], 0, 1  # row blocks kept, rows read, next quarter to announce
    try:
        size = run.csv.stat().st_size
        with open(run.csv, "rb") as stream:
            lines = sum(1 for _ in stream) - 1  # data rows (at most: blank lines are skipped)
            step = max(1, math.ceil(lines / MAX_POINTS))
            stream.seek(0)
            stream.readline()
            talk = announce if size >= ANNOUNCE_BYTES else None
            if talk:
                talk(f"compare: reading {run.label}/{run.csv.name} ({size / 1e6:.0f} MB)")
            while chunk := list(itertools.islice(stream, CHUNK_ROWS)):
                text = b"".join(chunk).decode("utf-8")
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", UserWarning)  # a chunk of blank lines: no rows (checked below)
                    try:
                        data = np.loadtxt(io.StringIO(text), delimiter=",", ndmin=2)  # (n, len(header))
                    except ValueError as e:  # numpy counts rows from the chunk's start
                        why = _shift_rows(str(e).split("; use `usecols`")[0], done)  # (numpy's advice, not ours)
                        raise UsageError(
                            f"{shown}: {run.csv.name} is not a numeric table ({' '.join(why.split())[:120]})"
                        ) from None
                if len(data) and data.shape[1] != len(names):
                    raise UsageError(f"{shown}: {run.csv.name} has rows of another width than its header")
                kept.append(data[(done + np.arange(len(data))) % step == 0])
                done += len(data)
                while talk and at < 4 and stream.tell() >= size * at / 4:
                    talk(f"compare: reading {run.label}/{run.csv.name}: {25 * at} %")
                    at += 1
    except UnicodeDecodeError:
        raise UsageError(f"{shown}: {run.csv.name} is not a numeric table (not UTF-8 text)") from None
    except OSError as e:
        raise UsageError(f"{shown}: {run.csv.name} cannot be read: {e.strerror or e}") from None
    if done == 0:
        raise UsageError(f"{shown}: {run.csv.name} is not a numeric table (it has no rows)")
    return names, np.concatenate(kept)


def _shift_rows(message: str, offset: int) -> str:
    """numpy's 'at row N' in a chunk's error, counted from the file's first data row instead."""
    return re.sub(r"at row (\d+)", lambda m: f"at row {int(m[1]) + offset}", message)


def shared_columns(headers: Sequence[Sequence[str]]) -> list[str]:
    """Columns every run has, in the first run's order; the first one (e.g. t) is the common x axis."""
    if len({h[0] for h in headers}) != 1:
        return []
    return [c for c in headers[0] if all(c in h for h in headers)]


def header(run: Run) -> list[str]:
    """The column names of a run's CSV (its first line)."""
    shown = repr(printable(str(run.path)))
    try:
        with open(run.csv, "rb") as stream:
            line = stream.readline(MAX_HEADER_BYTES + 1)
    except OSError as e:
        raise UsageError(f"{shown}: {run.csv.name} cannot be read: {e.strerror or e}") from None
    try:
        text = line.decode("utf-8")
    except UnicodeDecodeError:
        raise UsageError(f"{shown}: {run.csv.name} is not UTF-8 text (a binary or damaged file)") from None
    if len(line) > MAX_HEADER_BYTES or not text.endswith("\n") or "\0" in text:
        raise UsageError(f"{shown}: {run.csv.name} has no header line (a binary, empty or damaged file)")
    return text.strip().split(",")


def figures(runs: Sequence[Run], announce: Callable[[str], None] | None = None) -> dict[str, Figure]:
    """{file stem: figure}: each shared column against the first shared one (e.g. t), every run overlaid."""
    from hexabot_sim import plots

    shared = shared_columns([header(r) for r in runs])
    if len(shared) < 2:
        return {}
    tables = [_read(r, announce) for r in runs]
    x_name, ys = shared[0], shared[1:]
    units = {**runs[0].units["columns"]}
    out: dict[str, Figure] = {}
    for start in range(0, len(ys), PANELS_PER_FIGURE):
        chunk = ys[start : start + PANELS_PER_FIGURE]
        fig, axes = plots.figure(len(chunk), 1, figsize=(10, 2.2 * len(chunk) + 1.2), sharex=True, squeeze=False)
        for ax, name in zip(axes[:, 0], chunk, strict=True):
            for k, (run, (names, data)) in enumerate(zip(runs, tables, strict=True)):
                x, y = data[:, names.index(x_name)], data[:, names.index(name)]  # thinned by _read
                style = "-" if len(data) > 50 else "o-"
                ax.plot(x, y, style, color=f"C{k}", lw=1.2, ms=3, label=run.label, alpha=0.85)
            unit = units.get(name, "")
            ax.set_ylabel(f"{name}\n[{unit}]" if unit and unit != "1" else name, fontsize=8)
            ax.grid(alpha=0.3)
        if len(runs) <= LEGEND_RUNS:  # more entries squeezed the panels to nothing (a layout warning at 300 runs)
            plots.legend_above(axes[0, 0], ncol=min(4, len(runs)))
        x_unit = units.get(x_name, "")
        axes[-1, 0].set_xlabel(f"{x_name} [{x_unit}]" if x_unit and x_unit != "1" else x_name)
        scenarios = sorted({r.scenario for r in runs})
        legend = "" if len(runs) <= LEGEND_RUNS else f"; no legend above {LEGEND_RUNS}: colours C0-C9 in turn"
        fig.suptitle(f"compare: {', '.join(scenarios)} ({len(runs)} runs{legend})", fontsize=plots.TITLE_FONTSIZE)
        out["overlay" if start == 0 else f"overlay_{start // PANELS_PER_FIGURE + 1}"] = fig
    return out
