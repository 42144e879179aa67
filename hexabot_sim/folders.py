"""Run folders: --out checks, a staging folder published atomically (--force, turns, interruption), stale folders."""

from __future__ import annotations

import contextlib
import datetime as _dt
import errno
import functools
import os
import secrets
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from hexabot_sim.errors import OutputError, UsageError, printable
from hexabot_sim.signals import PUBLISHED, RECEIVED_SIGNALS, signals_held, stop_request

# Every run is written into a hidden staging folder next to its destination and renamed into
# place only when complete. A run killed with SIGKILL leaves one behind: later runs ignore them,
# and `hexabot-sim clean` (or `rm -rf runs/.hexabot-sim-staging-*`) removes them.
STAGING_PREFIX = ".hexabot-sim-staging-"

STAGING_SUFFIX = ".partial"

OLD_PREFIX = ".hexabot-sim-replaced-"
PREVIOUS = "previous"  # in a replaced folder: what --force moved aside
TARGET = "target"  # ... and the name it had, written first: `clean` puts it back if the run died before publishing


def default_out(scenario: str, root: Path = Path("runs")) -> Path:
    """The default run folder name, runs/<scenario>-YYYYmmdd-HHMMSS (a -N suffix is added at publish if taken)."""
    return root / f"{scenario}-{_dt.datetime.now().strftime('%Y%m%d-%H%M%S')}"


def check_out(out: str | os.PathLike[str], force: bool = False) -> None:
    """Refuses, before anything runs, an --out that could destroy or hide something.

    Raises:
        UsageError: for a symbolic link, '.', '..' or a path ending in them, the working folder or one
            of its parents, a file, a non-empty folder without `force`, a read-only (or immutable) folder, or a
            parent that cannot be written.
    """
    text = os.fspath(out)
    out = Path(out)
    _check_name(out, text)
    try:
        _check_existing(out, text, force)
    except OSError as e:
        raise UsageError(f"output folder {text!r} cannot be used: {e.strerror or e}") from None


def _check_name(out: Path, text: str) -> None:
    """Refuses an --out that names no folder ('', '.', '..', 'a/..') or a name over 255 bytes."""
    last = text.rstrip("/").rsplit("/", 1)[-1]
    if out.name in ("", ".", "..") or last in ("", ".", ".."):
        raise UsageError(f"output folder {text!r} must end in a folder name (not '.' or '..')")
    if len(os.fsencode(out.name)) > 255:
        raise UsageError(f"output folder name is {len(os.fsencode(out.name))} bytes long; the limit is 255")


def check_not_input(out: str | os.PathLike[str], inputs: list[str]) -> None:
    """Refuses an --out that is, contains or lies inside one of a command's inputs (with or without --force).

    Raises:
        UsageError: naming the input; a command never writes over what it reads; first, an --out that names no
            folder (check_out's first refusal: --out '' was 'output folder '.' is, contains ... the input').
    """
    _check_name(Path(out), os.fspath(out))
    targets = {Path(os.path.abspath(out)), Path(os.path.realpath(out))}
    for item in inputs:
        sources = {Path(os.path.abspath(item)), Path(os.path.realpath(item))}
        overlaps = any(a == b or a.is_relative_to(b) or b.is_relative_to(a) for a in targets for b in sources)
        with contextlib.suppress(OSError):
            overlaps = overlaps or os.path.samefile(out, item) or _holds(out, item)
        if overlaps:
            raise UsageError(
                f"output folder {display_path(Path(out))!r} is, contains or lies inside the input "
                f"{display_path(Path(item))!r}; a command never writes over what it reads: choose another --out"
            )


def _holds(out: str | os.PathLike[str], item: str) -> bool:
    """Whether the existing folder `out` is one of the folders `item` lies in, by identity (device, inode): a bind
    mount or a second name of a folder is no other folder (found by fuzzing: the schedule named through a bind
    mount of --out was deleted with it)."""
    if not os.path.isdir(out):
        return False
    folder = Path(os.path.abspath(item)).parent
    for above in (folder, *folder.parents):
        with contextlib.suppress(OSError):
            if os.path.samefile(out, above):
                return True
    return False


def _check_existing(out: Path, text: str, force: bool) -> None:
    if out.is_symlink():
        raise UsageError(f"output folder {text!r} is a symbolic link; give the real folder instead")
    try:
        resolved = out.resolve()
        cwd = Path.cwd().resolve()
    except (OSError, RuntimeError) as e:
        raise UsageError(f"output folder {text!r} cannot be used: {e}") from None
    if cwd.is_relative_to(resolved):
        raise UsageError(f"output folder {text!r} is the working folder or one of its parents; choose a new folder")
    if Path.home().resolve().is_relative_to(resolved):
        raise UsageError(f"output folder {text!r} is the home folder or one of its parents; choose a new folder")
    for part in (*Path(os.path.abspath(out)).parts, *resolved.parts):
        if part.startswith((STAGING_PREFIX, OLD_PREFIX)):
            raise UsageError(
                f"output folder {text!r} is inside another run's staging folder {part!r}; choose a new folder"
            )
    if out.is_dir() and os.path.ismount(out):  # a run is published by renaming onto --out: not onto a mount point
        raise UsageError(f"output folder {text!r} is a mount point; give a new folder inside it")
    if out.exists() and not out.is_dir():
        raise UsageError(f"output path {text!r} exists and is not a folder")
    try:
        nonempty = out.is_dir() and any(out.iterdir())
    except OSError as e:
        raise UsageError(f"output folder {text!r} cannot be read: {e.strerror or e}") from None
    if nonempty and not force:
        raise UsageError(f"output folder {text!r} is not empty; choose another --out or add --force to replace it")
    if out.is_dir() and not writable(out):
        # A run replaces --out by a rename, which needs no write permission on it (and root needs none at all):
        # a folder made read-only (or immutable) was replaced by a writable one, or found unwritable after the run.
        raise UsageError(f"output folder {text!r} is read-only; make it writable or choose another --out")
    ancestor = out.parent
    while not ancestor.exists():
        if ancestor.is_symlink():  # a dangling link in the parents
            raise UsageError(f"output folder {text!r}: {str(ancestor)!r} is a broken symbolic link")
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise UsageError(f"output folder {text!r}: {str(ancestor)!r} is not a folder")
    if not writable(ancestor):
        raise UsageError(f"output folder {text!r} cannot be written: no write permission in {str(ancestor)!r}")


def writable(folder: Path) -> bool:
    """Whether files may be made in `folder`: a write bit set (root passes os.access anyway, and would write into a
    folder a user made read-only) and os.access (permissions, a read-only file system, an immutable folder)."""
    try:
        return bool(folder.stat().st_mode & 0o222) and os.access(folder, os.W_OK | os.X_OK)
    except OSError:
        return False


def _make_parents(folder: Path) -> list[Path]:
    """Creates the missing folders down to `folder`; returns those it created, deepest first."""
    missing = []
    while not folder.exists():
        missing.append(folder)
        folder = folder.parent
    created = []
    for path in reversed(missing):
        try:
            path.mkdir()
        except FileExistsError:  # created meanwhile by someone else: not ours to remove
            continue
        created.append(path)
    return created[::-1]


def _remove_created(created: list[Path]) -> None:
    """Removes folders this run created, deepest first, as long as they are still empty."""
    for path in created:
        try:
            path.rmdir()
        except OSError:
            break


class RunFolder:
    """Where one run is written: `.path` while it runs (staging), `.final` once published."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.final: Path | None = None


def _snapshot(folder: Path) -> tuple | None:
    """What a folder holds (every entry's path, kind, size and modification time), None if it does not exist."""
    try:
        top = os.stat(folder, follow_symlinks=False)
    except FileNotFoundError:
        return None
    entries = []
    for root, dirs, files in os.walk(folder):
        for name in sorted(dirs) + sorted(files):
            path = os.path.join(root, name)
            try:
                st = os.stat(path, follow_symlinks=False)
            except FileNotFoundError:  # removed while we looked: the folder is changing
                entries.append((os.path.relpath(path, folder), -1, -1, -1, -1))
                continue
            entries.append((os.path.relpath(path, folder), st.st_mode, st.st_size, st.st_mtime_ns, st.st_ino))
    return (top.st_ino, top.st_dev, tuple(sorted(entries)))


_TAKEN = (errno.EEXIST, errno.ENOTEMPTY, errno.ENOTDIR, errno.EISDIR)


def _mkdir_unique(parent_fd: int, prefix: str, suffix: str = "") -> str:
    """Creates a new folder named prefix<random>suffix in the folder `parent_fd`; mode from the umask."""
    for _ in range(100):
        name = f"{prefix}{secrets.token_hex(4)}{suffix}"
        try:
            os.mkdir(name, 0o777, dir_fd=parent_fd)
            return name
        except FileExistsError:
            continue
    raise OSError(errno.EEXIST, "no free staging folder name")


def _publish(parent_fd: int, staging: str, out: Path, auto_name: bool, force: bool, before: tuple | None) -> Path:
    """Renames the finished staging folder (in `parent_fd`) to `out` (or the next free `out-N`); returns where."""
    rename = functools.partial(os.rename, src_dir_fd=parent_fd, dst_dir_fd=parent_fd)
    if auto_name:
        for n in range(1, 10_000):
            name = out.name if n == 1 else f"{out.name}-{n}"
            try:
                # rename() only ever replaces an empty folder: a taken name raises and we try the next.
                rename(staging, name)
                return out.with_name(name)
            except OSError as e:
                if e.errno not in _TAKEN:
                    raise
        raise OutputError(f"no free run folder name next to {str(out)!r}")
    if out.is_symlink():
        raise OutputError(f"{str(out)!r} became a symbolic link during the run; result not written")
    with _publishing(parent_fd):
        old = _replace(parent_fd, staging, out, force, before, rename)
    if old is not None:  # what --force replaced, deleted once the new run is in place (and the lock is free)
        shutil.rmtree(old, ignore_errors=True, dir_fd=parent_fd)
    return out


@contextmanager
def _publishing(parent_fd: int) -> Iterator[None]:
    """One publisher at a time in a folder (an advisory lock on it): two --force runs to the same `out` cannot
    both find it as it was at their start and both replace it."""
    try:
        import fcntl
    except ImportError:  # not on Linux or macOS: no lock
        yield
        return
    fcntl.flock(parent_fd, fcntl.LOCK_EX)
    try:
        yield
    finally:
        fcntl.flock(parent_fd, fcntl.LOCK_UN)


def _replace(parent_fd: int, staging: str, out: Path, force: bool, before: tuple | None, rename) -> str | None:
    """_publish's rename into an explicit `out`: only over nothing, an empty folder, or (force) what was there.

    Returns the folder (in `parent_fd`) holding what --force moved aside, or None.
    """
    now = _snapshot(out)
    if force and now != before and not (before is None and now is not None and not now[2]):
        raise OutputError(
            f"output folder {str(out)!r} changed during the run; nothing replaced, the result is not written "
            "(--force replaces only what was there when the run started)"
        )
    old = None
    try:
        if force and now is not None and now[2]:
            old = _mkdir_unique(parent_fd, f"{OLD_PREFIX}{os.getpid()}-")
            _write_target(parent_fd, old, out.name)
            rename(out.name, f"{old}/{PREVIOUS}")  # moved aside first, deleted only once the new run is in place
        rename(staging, out.name)
    except OSError as e:
        if old is not None:
            try:
                rename(f"{old}/{PREVIOUS}", out.name)
            except OSError:
                pass
            with contextlib.suppress(OSError):
                os.unlink(f"{old}/{TARGET}", dir_fd=parent_fd)
                os.rmdir(old, dir_fd=parent_fd)
        if e.errno in _TAKEN:
            raise OutputError(
                f"output folder {str(out)!r} was filled by someone else during the run; nothing replaced "
                "(run again with another --out, or --force to replace it)"
            ) from None
        raise
    return old


@contextmanager
def run_folder(out: str | os.PathLike[str] | None, scenario: str = "run", force: bool = False) -> Iterator[RunFolder]:
    """Yields a private staging folder that becomes `out` only if the block completes.

    With `out` None the run goes to a new runs/<scenario>-<timestamp>[-N] folder that no other run
    can take. On any error, Ctrl-C or termination the staging folder and the parent folders this
    run created are removed: no half-written run is ever left behind. Nothing is replaced that was
    not there (empty) when the run was published; with `force`, what was in `out` when the run
    started is replaced, and a folder that changed during the run is left alone.

    Raises:
        UsageError: if `out` is refused by check_out.
        OutputError: if the folder cannot be written or `out` was filled or changed during the run.
    """
    auto_name = out is None
    target = default_out(scenario) if out is None else Path(out)
    # A default name that is taken is not an error: the publish moves on to the next free -N.
    check_out(target if out is None else out, force=force or auto_name)
    target = Path(os.path.abspath(target))  # a later chdir or a renamed working folder cannot redirect it
    before = _snapshot(target) if force and not auto_name else None
    PUBLISHED[0] = False
    created: list[Path] = []
    folder = None
    parent_fd = -1
    staging = ""
    try:
        with signals_held():
            created = _make_parents(target.parent)
            # The staging folder is created, published and removed through a handle on its parent,
            # so it is found again even if the parent is renamed meanwhile.
            parent_fd = os.open(target.parent, os.O_RDONLY | os.O_DIRECTORY)
            staging = _mkdir_unique(parent_fd, f"{STAGING_PREFIX}{os.getpid()}-", STAGING_SUFFIX)
            folder = RunFolder(target.parent / staging)
        yield folder
        with signals_held():
            if RECEIVED_SIGNALS:  # a stop request some library swallowed on its way: honour it now
                raise stop_request(RECEIVED_SIGNALS[-1])
            if _moved(target.parent, parent_fd):
                raise OutputError(f"the folder {str(target.parent)!r} was moved or replaced during the run")
            # Made read-only meanwhile (root's rename would go through); a default name taken moves on to -N.
            for where in (target.parent,) if auto_name else (target.parent, target):
                if where.is_dir() and not where.stat().st_mode & 0o222:
                    raise OutputError(f"the folder {display_path(where)!r} was made read-only during the run")
            folder.final = _publish(parent_fd, staging, target, auto_name, force and not auto_name, before)
            PUBLISHED[0] = True  # a stop request from now on (even one held above) is too late: the run is complete
    except BaseException as e:
        # Ctrl-C, a signal, a failed simulation or write: remove everything this run made, then say why.
        with signals_held():
            # Looked at before the clean-up: removing the parents this run created is no move by someone else (a
            # failed first run in a new runs/ said "the folder 'runs' ... was moved or removed during the run").
            moved = isinstance(e, OSError) and parent_fd >= 0 and _moved(target.parent, parent_fd)
            if staging and parent_fd >= 0:
                shutil.rmtree(staging, ignore_errors=True, dir_fd=parent_fd)
            _remove_created(created)
        if isinstance(e, OSError) and folder is None:
            raise UsageError(f"output folder {str(target)!r} cannot be written: {e.strerror or e}") from None
        if moved:
            raise OutputError(
                f"the folder {display_path(target.parent)!r} that was to receive the run folder was moved or "
                f"removed during the run ({e.strerror or e}); nothing written"
            ) from None
        if isinstance(e, OSError):
            raise OutputError(f"writing the run folder failed: {e.strerror or e}; nothing written") from None
        raise
    finally:
        if parent_fd >= 0:
            os.close(parent_fd)


def _moved(folder: Path, fd: int) -> bool:
    """True if `folder` is no longer the folder open as `fd` (renamed, removed or replaced)."""
    try:
        here, there = os.stat(folder), os.fstat(fd)
    except OSError:
        return True
    return (here.st_ino, here.st_dev) != (there.st_ino, there.st_dev)


CELL_PREFIX = "hexabot-sim-cell-"  # a sweep worker's kept-run folder in the temporary folder: <prefix><pid>-...

DISK_FULL_BYTES = 1 << 20  # [B] a folder with less free space than this is out of disk


def disk_full(folder: Path) -> bool:
    """True if the file system of `folder` has less than DISK_FULL_BYTES free (for this user)."""
    try:
        st = os.statvfs(folder)
    except (OSError, AttributeError):
        return False
    return st.f_bavail * st.f_frsize < DISK_FULL_BYTES


def _write_target(parent_fd: int, old: str, name: str) -> None:
    """Writes the name of the folder --force is about to move aside into its replaced folder `old` (fsynced)."""
    fd = os.open(f"{old}/{TARGET}", os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644, dir_fd=parent_fd)
    try:
        os.write(fd, os.fsencode(name))
        os.fsync(fd)
    finally:
        os.close(fd)


def display_path(path: Path) -> str:
    """`path` relative to the working directory when it is below it; bytes that are not UTF-8 shown as \\xNN."""
    try:
        return printable(os.path.relpath(path) if Path(path).resolve().is_relative_to(Path.cwd()) else str(path))
    except (OSError, ValueError):  # OSError: a name too long to resolve
        return printable(str(path))


def check_replace(path: Path, force: bool, what: str = "video path", how: str = "pass force=True") -> None:
    """An existing `path` is replaced only with force, and only if it is a file (or a link, itself replaced)."""
    if not os.path.lexists(path):
        return
    if not force:
        raise UsageError(f"{what} {str(path)!r} exists; {how} to replace it, or choose another name")
    if not (path.is_symlink() or path.is_file()):
        raise UsageError(f"{what} {str(path)!r} exists and is not a regular file; it is never replaced")


def publish_new(staging: Path, path: Path, what: str = "video path", meanwhile: str = "the video rendered") -> None:
    """Renames `staging` to `path` only if `path` does not exist (a hard link never replaces; rename would)."""
    try:
        os.link(staging, path)
    except FileExistsError:
        raise UsageError(f"{what} {str(path)!r} appeared while {meanwhile}; it was left alone") from None
    except OSError as e:
        if e.errno not in (errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.EMLINK):
            raise
        os.replace(staging, path)  # a file system without hard links: checked just before
