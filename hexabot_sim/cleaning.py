"""What `hexabot-sim clean` finds and puts back: the folders of runs whose process is gone.

Only real folders (never a link) named exactly as a run names them count: a staging folder, a replaced folder of a
--force run (folders._replace), a sweep worker's kept-run folder in the temporary folder. A name that merely starts
like one is a user's.
"""

from __future__ import annotations

import contextlib
import os
import re
import tempfile
from pathlib import Path

from hexabot_sim.errors import UsageError
from hexabot_sim.folders import CELL_PREFIX, OLD_PREFIX, PREVIOUS, STAGING_PREFIX, STAGING_SUFFIX, TARGET
from hexabot_sim.params import read_bounded


def replaced_fate(path: Path) -> tuple[str, Path | None]:
    """What `clean` does with a stale replaced folder (stale_staging lists it) of a --force run that died.

    Returns ("restore", where): the run died after it moved the user's folder aside and before it published its
    own, so the name is free: put `previous` back there (rename_back). ("keep", where or None): `previous` is there
    but its name is unknown, or taken by something that is not a run folder: only a person can tell, so it stays.
    ("remove", None): nothing of the user's is in it; ("remove", where): the new run was published at `where`, and
    `previous` is what --force was asked to replace.
    """
    previous = path / PREVIOUS
    if not os.path.lexists(previous) or previous.is_symlink():  # a link is not the user's folder (removed, not
        return "remove", None  # followed); a run makes only a folder there
    if not previous.is_dir():  # a file where a run puts a folder: not ours to judge
        return "keep", None
    name = _read_target(path / TARGET)
    if not name or name in (".", "..") or "/" in name or "\0" in name:
        return "keep", None
    where = path.parent / name
    if not os.path.lexists(where):
        return "restore", where
    return ("remove" if (where / "run.json").is_file() and not where.is_symlink() else "keep"), where


def _read_target(path: Path) -> str:
    """The name a replaced folder's `target` file holds; "" for anything a run does not write there (a link, a
    FIFO that would block, a device, a file over 4 KiB): params.read_bounded, links not followed."""
    if path.is_symlink():
        return ""
    try:
        return os.fsdecode(read_bounded(path, "target", 4096))
    except UsageError:
        return ""


def rename_back(path: Path, where: Path) -> None:
    """Moves a replaced folder's `previous` back to `where`, free when replaced_fate looked (a folder made there
    since would be replaced if empty: rename() does that; a taken one raises)."""
    os.rename(path / PREVIOUS, where)
    with contextlib.suppress(OSError):
        os.unlink(path / TARGET)


def stale_cells() -> list[Path]:
    """Sweep workers' kept-run folders in the system's temporary folder whose process is gone."""
    return [path for path in sorted(Path(tempfile.gettempdir()).glob(f"{CELL_PREFIX}*")) if _stale(path, _CELL_NAME)]


CLEAN_DEPTH: int = 4  # clean DIR looks this many folder levels down (an --out of runs/a/b/x stages in runs/a/b)


def stale_staging(root: Path) -> list[Path]:
    """Staging and replaced folders in `root` and its sub-folders (CLEAN_DEPTH levels, links not followed) left by
    runs whose process no longer exists: the staging folders first, then the replaced ones."""
    named: list[Path] = []
    level = [root]
    for _ in range(CLEAN_DEPTH):  # (one level down was looked at only: runs/a/b/x's were never found)
        down = []
        for folder in level:
            for name, is_folder in _folders_in(folder):
                if name.startswith(_OURS):  # ours (or a look-alike): judged, never looked into
                    named.append(folder / name)
                elif is_folder:
                    down.append(folder / name)
        level = down
    found = []
    for prefix, pattern in ((STAGING_PREFIX, _STAGING_NAME), (OLD_PREFIX, _OLD_NAME)):
        found += sorted(path for path in named if path.name.startswith(prefix) and _stale(path, pattern))
    return found


def _folders_in(folder: Path) -> list[tuple[str, bool]]:
    """(name, is a real folder) of the entries of `folder`; none when it is gone or cannot be read (another clean
    removed it, a folder without x permission: Path.is_dir raised PermissionError and clean stopped)."""
    try:
        with os.scandir(folder) as entries:
            out = []
            for entry in entries:
                try:
                    out.append((entry.name, entry.is_dir(follow_symlinks=False)))
                except OSError:
                    out.append((entry.name, False))
            return out
    except OSError:
        return []


# The exact names our runs create (_mkdir_unique: <prefix><pid>-<8 hex digits><suffix>; a sweep cell's
# tempfile.TemporaryDirectory: <prefix><pid>-<8 of [a-z0-9_]>). A name that merely starts like one is a user's.
_STAGING_NAME = re.compile(re.escape(STAGING_PREFIX) + r"([1-9][0-9]{0,9})-[0-9a-f]{8}" + re.escape(STAGING_SUFFIX))

_OURS = (STAGING_PREFIX, OLD_PREFIX)  # folders of ours are not looked into: what they hold is a run's, or a user's

_OLD_NAME = re.compile(re.escape(OLD_PREFIX) + r"([1-9][0-9]{0,9})-[0-9a-f]{8}")

_CELL_NAME = re.compile(re.escape(CELL_PREFIX) + r"([1-9][0-9]{0,9})-[a-z0-9_]{8}")


def _stale(path: Path, name: re.Pattern[str]) -> bool:
    """True only for a real folder (not a link) named exactly as a run of ours names it, whose process is gone."""
    match = name.fullmatch(path.name)
    if match is None or int(match.group(1)) > _PID_MAX or not _is_folder(path):
        return False  # a process id no system gives out is not one of ours either
    return not _alive(int(match.group(1)))


_PID_MAX = 1 << 22  # Linux's largest pid_max


def _is_folder(path: Path) -> bool:
    try:
        return path.is_dir() and not path.is_symlink()
    except OSError:  # a folder we may list but not enter: its entries' types cannot be read
        return False


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True
