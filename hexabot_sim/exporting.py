"""`hexabot-sim export`: a robot's MJCF and URDF written as files, whole or not at all."""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from hexabot_sim import folders
from hexabot_sim.errors import OutputError, UsageError


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
        force: Replace existing files (regular files only); without it an existing file is an error.
        lengths: The robot's named lengths to change, in [m].

    Returns:
        The paths written. Both models are made before anything is written, and each file is written to a
        temporary name in its folder and renamed into place: an error leaves no file half-written.

    Raises:
        hexabot_sim.errors.UsageError: a bad robot, file or length; an existing path without force; no path.
        hexabot_sim.errors.OutputError: a file could not be written.
    """
    from hexabot_sim.kinematics import robots
    from hexabot_sim.kinematics import urdf as urdf_mod
    from hexabot_sim.kinematics.mjcf import to_mjcf

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
    comment = f"{where}: {spec.summary}".replace("--", "- -")
    texts: dict[Path, tuple[str, str]] = {}
    if mjcf is not None:
        texts[Path(mjcf)] = ("MJCF file", to_mjcf(chain, comment=comment, masses=spec.masses))
    if urdf is not None:
        if Path(urdf) in texts:
            raise UsageError(f"--mjcf and --urdf name the same file {str(urdf)!r}")
        try:
            texts[Path(urdf)] = ("URDF file", urdf_mod.to_urdf(chain, comment=comment, masses=spec.masses))
        except UsageError as e:
            raise UsageError(f"{where}: {e}") from None
    for path, (what, _) in texts.items():
        if path.is_dir():
            raise UsageError(f"{what} {str(path)!r} is a folder; give a file name")
        if not path.parent.is_dir():
            raise UsageError(f"the folder {str(path.parent)!r} for the {what} does not exist")
        folders.check_replace(path, force, what, "add --force (force=True)")
    written = []
    for path, (what, text) in texts.items():
        staging = path.with_name(f".{path.name}.partial-{os.getpid()}")
        try:
            with open(staging, "x", encoding="utf-8") as f:
                f.write(text)
                f.flush()
                os.fsync(f.fileno())
            folders.check_replace(path, force, what, "add --force (force=True)")
            if force:
                os.replace(staging, path)
            else:
                folders.publish_new(staging, path, what, "it was written")
        except OSError as e:
            raise OutputError(f"writing the {what} {str(path)!r} failed: {e.strerror or e}") from None
        finally:
            staging.unlink(missing_ok=True)
        written.append(path)
    return written
