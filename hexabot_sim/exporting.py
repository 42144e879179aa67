"""`hexabot-sim export`: a robot's MJCF and URDF written as files, whole or not at all."""

from __future__ import annotations

import contextlib
import errno
import os
import secrets
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from hexabot_sim import folders
from hexabot_sim.errors import OutputError, UsageError, printable
from hexabot_sim.signals import PUBLISHED, RECEIVED_SIGNALS, signals_held, stop_request


def export(
    robot: str | os.PathLike[str] | Any,
    *,
    mjcf: str | os.PathLike[str] | None = None,
    urdf: str | os.PathLike[str] | None = None,
    force: bool = False,
    lengths: Mapping[str, float] | None = None,
) -> list[Path]:
    """Writes the MJCF (body frames = DH frames, qpos = q) and/or the URDF of a robot, as `hexabot-sim export` does.

    Args:
        robot: A package robot's name (rrp, elbow, stanford, scara, leg), the path of a robot file, or a RobotSpec.
        mjcf: The MJCF file to write, or None.
        urdf: The URDF file to write, or None.
        force: Replace existing files (regular files only); without it an existing file is an error. The robot
            file being exported is never replaced, not even with force (nor through a link to it).
        lengths: The robot's named lengths to change, in [m].

    Returns:
        The paths written. Both models are made before anything is written, and both files are written to
        temporary names in their folders, then renamed into place: an error, Ctrl-C or SIGTERM while writing leaves
        no file half-written and neither file written (a first file already in place when the second fails is taken
        back: removed, or the file it replaced put back).

    Raises:
        hexabot_sim.errors.UsageError: a bad robot, file or length; an existing path without force; no path; a
            path ending in '/', both paths naming one file, or a path that is the robot file itself.
        hexabot_sim.errors.OutputError: a file could not be written.
    """
    from hexabot_sim.kinematics import robots
    from hexabot_sim.kinematics import urdf as urdf_mod
    from hexabot_sim.kinematics.mjcf import to_mjcf
    from hexabot_sim.kinematics.xml_text import comment_line

    if not isinstance(force, bool):
        raise UsageError(f"'force' must be True or False; got {force!r}")
    for name, value in (("mjcf", mjcf), ("urdf", urdf)):
        if not (value is None or isinstance(value, (str, os.PathLike))):
            raise UsageError(f"'{name}' must be a path (str or os.PathLike) or None; got {type(value).__name__}")
    if mjcf is None and urdf is None:
        raise UsageError("export needs an output: --mjcf FILE and/or --urdf FILE (mjcf=..., urdf=... in Python)")
    spec = robots.resolve(robot)
    chain = spec.chain(lengths)
    where = f"{spec.name} ({spec.source})" if spec.source else spec.name
    comment = comment_line(f"{where}: {spec.summary}")  # "a---b" in a path or summary: no "--" left
    texts: dict[Path, tuple[str, str]] = {}
    for value, what in ((mjcf, "MJCF file"), (urdf, "URDF file")):
        if value is None:
            continue
        raw = os.fspath(value)
        shown = printable(os.fsdecode(raw))
        if not raw:  # Path("") is '.': it was refused as "MJCF file '.' is a folder"
            raise UsageError(f"{what} needs a file name; got an empty one")
        if b"\0" in os.fsencode(raw):  # pathlib's ValueError "embedded null byte", not one line
            raise UsageError(f"{what} '{shown}' holds a NUL byte, which no file name can")
        if raw.endswith((os.sep, os.altsep or os.sep) if isinstance(raw, str) else os.fsencode(os.sep)):
            raise UsageError(f"{what} {shown!r} ends with '{os.sep}': that names a folder; give a file name")
        path = Path(os.fsdecode(raw))
        if any(_same_place(path, other) for other in texts):
            raise UsageError(f"--mjcf and --urdf name the same file {shown!r}")
        texts[path] = (what, "")
    for path, (what, _) in texts.items():
        if what == "MJCF file":
            texts[path] = (what, to_mjcf(chain, comment=comment, masses=spec.masses))
        else:
            try:
                texts[path] = (what, urdf_mod.to_urdf(chain, comment=comment, masses=spec.masses))
            except UsageError as e:
                raise UsageError(f"{where}: {e}") from None
    for path, (what, _) in texts.items():
        shown = printable(str(path))
        if path.is_dir():
            raise UsageError(f"{what} {shown!r} is a folder; give a file name")
        if not path.parent.is_dir():
            raise UsageError(f"the folder {printable(str(path.parent))!r} for the {what} does not exist")
        if not folders.writable(path.parent):  # a read-only folder or file system (also for root): exit 2, not 1
            raise UsageError(f"the folder {printable(str(path.parent))!r} for the {what} cannot be written")
        if spec.file_id is not None and _is_file(path, spec.file_id):
            raise UsageError(f"{what} {shown!r} is the robot file being exported; it is never written over")
        folders.check_replace(path, force, what, "add --force (force=True)")
    # Both files are written and synced under temporary names first, then renamed into place one right after
    # the other: Ctrl-C or SIGTERM while a file is written leaves neither (and no temporary file).
    staged: dict[Path, Path] = {}
    written: list[Path] = []
    undo: list[tuple[Path, Path | None, int]] = []  # (path, a hard link to what it replaces, our file's inode)
    try:
        for path, (what, text) in texts.items():
            # The name cut short: a 250-byte file name is legal, its staging name must be too (it was ENAMETOOLONG).
            staging = path.with_name(f".{path.name[:48]}.partial-{os.getpid()}-{secrets.token_hex(4)}")
            staged[path] = staging  # before it exists: a stop as open() returns left an empty hidden file
            try:
                with open(staging, "x", encoding="utf-8") as f:
                    f.write(text)
                    f.flush()
                    os.fsync(f.fileno())
            except OSError as e:
                if isinstance(e, FileExistsError):  # not ours (a random name taken): never removed
                    del staged[path]
                raise OutputError(f"writing the {what} {printable(str(path))!r} failed: {e.strerror or e}") from None
        for path, (what, _) in texts.items():  # every file checked again before either is published
            folders.check_replace(path, force, what, "add --force (force=True)")
            if spec.file_id is not None and _is_file(path, spec.file_id):  # linked to it meanwhile
                raise UsageError(f"{what} {printable(str(path))!r} is the robot file being exported; left alone")
        # Both or neither: a stop request (Ctrl-C, SIGTERM) waits until the files and their kept copies are settled
        # (it came between a file's rename and its bookkeeping, and the file replaced was lost).
        PUBLISHED[0] = False
        with signals_held():
            if RECEIVED_SIGNALS:  # a stop request some library swallowed: honour it before anything is published
                raise stop_request(RECEIVED_SIGNALS[-1])
            try:
                for path, (what, _) in texts.items():
                    try:
                        inode = os.stat(staged[path]).st_ino
                        undo.append((path, _keep_previous(path) if force else None, inode))
                        if force:
                            os.replace(staged[path], path)
                        else:
                            folders.publish_new(staged[path], path, what, "it was written")
                    except OSError as e:
                        raise OutputError(
                            f"writing the {what} {printable(str(path))!r} failed: {e.strerror or e}"
                        ) from None
                    written.append(path)
            except BaseException:  # the second file failed (or a stop came): the first one is taken back
                _take_back(undo)
                raise
            for _, previous, _ in undo:
                if previous is not None:
                    previous.unlink(missing_ok=True)
            PUBLISHED[0] = True  # a stop request from now on is too late: both files are in place
    finally:
        for staging in staged.values():
            staging.unlink(missing_ok=True)
    return written


def _keep_previous(path: Path) -> Path | None:
    """A hard link to the file (or link) `path` replaces, so a failed export can put it back; None: nothing there,
    or a file system without hard links (then a failure after it leaves the new file)."""
    if not os.path.lexists(path):
        return None
    keep = path.with_name(f".{path.name[:48]}.previous-{os.getpid()}-{secrets.token_hex(4)}")
    try:
        os.link(path, keep, follow_symlinks=False)
    except OSError as e:
        if e.errno in (errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.EMLINK):
            return None
        raise
    return keep


def _take_back(undo: list[tuple[Path, Path | None, int]]) -> None:
    """Undoes the files published so far: each put back as it was (removed if it was new), if it is still ours (our
    staged file's inode is there: published, even if a stop came before it was counted)."""
    for path, previous, inode in reversed(undo):
        with contextlib.suppress(OSError):
            ours = os.lstat(path).st_ino == inode
            if previous is not None:
                if ours:
                    os.replace(previous, path)
                else:
                    previous.unlink()
            elif ours:
                path.unlink()


def _same_place(path: Path, other: Path) -> bool:
    """Whether two output paths name the same directory entry (`a.xml`, `./a.xml`, `/abs/a.xml`, `d/../a.xml`)."""
    return path.name == other.name and os.path.realpath(path.parent) == os.path.realpath(other.parent)


def _is_file(path: Path, file_id: tuple[int, int]) -> bool:
    """Whether `path` is (or links to) the file with this (device, inode)."""
    for look in (os.stat, os.lstat):
        try:
            status = look(path)
        except OSError:
            continue
        if (status.st_dev, status.st_ino) == file_id:
            return True
    return False
