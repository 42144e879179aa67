"""The only writer of run folders: timeseries.csv, run.json, model.xml, figures and video, all or nothing."""

from __future__ import annotations

import datetime as _dt
import json
import math
import os
import platform
import shutil
import tempfile
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from hexabot_sim.errors import SimulationError, UsageError

JSON_NAME = "run.json"
MODEL_NAME = "model.xml"
VIDEO_NAME = "video.mp4"


def default_out(scenario: str, root: Path = Path("runs")) -> Path:
    """A new timestamped folder name under `root`: runs/<scenario>-YYYYmmdd-HHMMSS[-N]."""
    stamp = _dt.datetime.now().strftime("%Y%m%d-%H%M%S")
    path = root / f"{scenario}-{stamp}"
    n = 2
    while path.exists():
        path = root / f"{scenario}-{stamp}-{n}"
        n += 1
    return path


@contextmanager
def run_folder(out: Path, force: bool = False) -> Iterator[Path]:
    """Yields a private staging folder that becomes `out` only if the block completes.

    On any error the staging folder is removed: no half-written run is ever left behind.

    Raises:
        UsageError: if `out` exists and is not an empty folder (unless force), or cannot be written.
    """
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise UsageError(f"output path {str(out)!r} exists and is not a folder")
    if out.is_dir() and any(out.iterdir()) and not force:
        raise UsageError(f"output folder {str(out)!r} is not empty; choose another --out or add --force to replace it")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        staging = Path(tempfile.mkdtemp(prefix=f".{out.name}.", suffix=".partial", dir=out.parent))
    except OSError as e:
        raise UsageError(f"output folder {str(out)!r} cannot be written: {e.strerror or e}") from None
    try:
        yield staging
        if out.exists():
            shutil.rmtree(out)
        staging.rename(out)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise


def write_csv(path: Path, columns: Mapping[str, np.ndarray]) -> None:
    """Writes columns (first "t") with a header row; %.17g makes the text exact and deterministic."""
    names = list(columns)
    table = np.column_stack([np.asarray(columns[n], dtype=float) for n in names])  # (n, ncol)
    if not np.isfinite(table).all():
        row, col = np.argwhere(~np.isfinite(table))[0]
        raise SimulationError(
            f"non-finite value in column '{names[col]}' at t = {table[row, 0]:.6g} s; nothing written"
        )
    np.savetxt(path, table, fmt="%.17g", delimiter=",", header=",".join(names), comments="")


def _json_value(value: Any) -> Any:
    if isinstance(value, (np.floating, np.integer)):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def versions() -> dict[str, str]:
    """Versions of what produced a run."""
    import matplotlib
    import mujoco
    import scipy

    import hexabot_sim

    return {
        "hexabot_sim": hexabot_sim.__version__,
        "mujoco": mujoco.__version__,
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "matplotlib": matplotlib.__version__,
        "python": platform.python_version(),
        "platform": platform.platform(),
    }


def write_json(path: Path, record: Mapping[str, Any]) -> None:
    """Writes run.json (strict JSON: non-finite numbers become null)."""

    def clean(obj: Any) -> Any:
        if isinstance(obj, Mapping):
            return {str(k): clean(v) for k, v in obj.items()}
        if isinstance(obj, (list, tuple)):
            return [clean(v) for v in obj]
        return _json_value(obj)

    path.write_text(json.dumps(clean(record), indent=2, allow_nan=False) + "\n")


def write_figures(figures: Mapping[str, Any], folder: Path, dpi: int = 120) -> list[str]:
    """Saves each matplotlib figure as <stem>.png in `folder`, closes it, and returns the file names."""
    import matplotlib.pyplot as plt

    names = []
    for stem, fig in figures.items():
        name = f"{stem}.png"
        fig.savefig(folder / name, dpi=dpi)
        plt.close(fig)
        names.append(name)
    return names


def write_text(path: Path, text: str) -> None:
    """Writes a text file (model.xml)."""
    path.write_text(text)


def display_path(path: Path) -> str:
    """`path` relative to the working directory when it is below it."""
    try:
        return os.path.relpath(path) if Path(path).resolve().is_relative_to(Path.cwd()) else str(path)
    except ValueError:
        return str(path)
