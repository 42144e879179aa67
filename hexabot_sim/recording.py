"""A run folder read for a replay, as untrusted input: its exact model (model.xml), recorded state (trajectory.npz)
and, if readable, its scenario and parameters (run.json)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

import numpy as np

from hexabot_sim.errors import UsageError


@dataclasses.dataclass(frozen=True)
class Recording:
    """A run folder's exact model and recorded state."""

    folder: Path
    scenario: str | None  # from run.json, None if it cannot be read
    params: dict[str, Any]
    xml_path: Path
    xml: str  # model.xml's text, checked by models.read_run_model (it references no other file)
    t: np.ndarray  # (n,) [s]
    qpos: np.ndarray  # (n, nq)
    qvel: np.ndarray  # (n, nv)
    ctrl: np.ndarray  # (n, nu)


def load_recording(folder: Path) -> Recording:
    """Reads model.xml, trajectory.npz and run.json of a run folder (UsageError naming what is missing)."""
    from hexabot_sim import output

    traj_path, xml_path = folder / output.TRAJECTORY_NAME, folder / output.MODEL_NAME
    if not traj_path.is_file():
        if (folder / "grid.csv").is_file():
            raise UsageError(
                f"{folder} is a leg-sweep run folder: a grid of runs (grid.csv), not one motion to replay; "
                "view one point of it live: hexabot-sim view leg-step --set amplitude=A --set omega=W"
            )
        raise UsageError(f"{folder} has no {output.TRAJECTORY_NAME}: not a hexabot-sim run folder with a motion")
    if not xml_path.is_file():
        raise UsageError(f"{folder} has no {output.MODEL_NAME}: the replay needs the run's exact model")
    scenario, params = None, {}
    try:  # read bounded, a regular file only: a FIFO named run.json must not block the replay
        from hexabot_sim.params import read_bounded

        info = json.loads(read_bounded(folder / output.JSON_NAME, "run record", 16 << 20, "").decode("utf-8"))
        scenario, params = str(info["scenario"]), dict(info.get("params") or {})
    except (UsageError, ValueError, KeyError, TypeError, RecursionError):
        pass  # replay works without it (no scenario markers)
    arrays = _read_trajectory(traj_path)
    t = arrays["t"]
    if t.ndim != 1 or len(t) < 1 or not np.all(np.isfinite(t)) or np.any(np.diff(t) < 0):
        raise UsageError(f"{traj_path}: 't' must be a non-empty, finite, non-decreasing time series")
    for name in ("qpos", "qvel", "ctrl"):
        if arrays[name].ndim != 2 or len(arrays[name]) != len(t):
            raise UsageError(f"{traj_path}: '{name}' must have one row per time (shape ({len(t)}, k))")
        if not np.all(np.isfinite(arrays[name])):
            raise UsageError(f"{traj_path}: '{name}' holds values that are not finite numbers")
    from hexabot_sim.models import read_run_model

    xml = read_run_model(xml_path)
    return Recording(folder, scenario, params, xml_path, xml, t, arrays["qpos"], arrays["qvel"], arrays["ctrl"])


TRAJECTORY_LIMIT = 4 << 30  # [B] the most trajectory.npz may hold once unpacked (a zip bomb is refused unread)


def _read_trajectory(path: Path) -> dict[str, np.ndarray]:
    """t, qpos, qvel and ctrl of a run's trajectory.npz, as float arrays; UsageError in one line for a damaged file.

    Only plain numeric arrays are read: never pickled objects (no allow_pickle), never more than TRAJECTORY_LIMIT.
    """
    import zipfile

    def bad(why: str) -> UsageError:
        return UsageError(f"cannot read {path}: {why}; it is not a trajectory a run of hexabot-sim wrote")

    try:
        with zipfile.ZipFile(path) as archive:
            members = {info.filename: info for info in archive.infolist()}
            missing = [f"{name}.npy" for name in ("t", "qpos", "qvel") if f"{name}.npy" not in members]
            if missing:
                raise bad(f"the archive has no {', '.join(missing)}")
            unpacked = sum(info.file_size for info in members.values())
            if unpacked > TRAJECTORY_LIMIT:
                limit = f"{TRAJECTORY_LIMIT / 2**30:g} GiB = {TRAJECTORY_LIMIT} bytes"  # exact: 4.0 GiB vs 4 GiB
                raise bad(f"it would unpack to {unpacked} bytes, more than {limit}")
            arrays = {}
            for name in ("t", "qpos", "qvel", "ctrl"):
                if f"{name}.npy" not in members:
                    continue
                with archive.open(f"{name}.npy") as stream:
                    array = np.lib.format.read_array(stream, allow_pickle=False)
                if array.dtype.kind not in "biuf":
                    raise bad(f"'{name}' holds {array.dtype} values, not real numbers")
                arrays[name] = np.asarray(array, dtype=float)
    except UsageError:
        raise
    except zipfile.BadZipFile:
        raise bad("not a NumPy .npz archive (a zip of .npy arrays)") from None
    except MemoryError:  # an .npy header may declare any shape: numpy allocates it before reading the data
        raise bad("an array's header declares more values than memory holds") from None
    except (OSError, EOFError, ValueError, RuntimeError, zipfile.LargeZipFile) as e:
        why = " ".join(str(e).split()) or type(e).__name__
        if "pickle" in why.lower():  # numpy's text advises allow_pickle, which would run the file's code
            why = "it holds Python objects, not numbers (never loaded: unpickling runs the file's code)"
        raise bad(why) from None
    if "ctrl" not in arrays:
        arrays["ctrl"] = np.zeros((len(arrays["t"]), 0))
    return arrays
