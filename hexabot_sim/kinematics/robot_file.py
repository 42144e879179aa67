"""Robot files: a DH table in TOML (docs/robot-files.md), checked strictly, resolved into one RobotSpec."""

from __future__ import annotations

import copyreg
import dataclasses
import math
import os
import re
import stat
import sys
import tomllib
import unicodedata
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from hexabot_sim.errors import UsageError, printable
from hexabot_sim.kinematics.chain import Joint, SerialChain
from hexabot_sim.kinematics.robot_chain import build as _build
from hexabot_sim.kinematics.robot_chain import check_not_degenerate
from hexabot_sim.kinematics.robot_chain import cos_sin as _cos_sin
from hexabot_sim.kinematics.robot_chain import joint as _joint
from hexabot_sim.kinematics.robot_chain import rx as _rx
from hexabot_sim.kinematics.robot_chain import ry as _ry
from hexabot_sim.kinematics.robot_chain import rz as _rz
from hexabot_sim.kinematics.robot_chain import value as _value
from hexabot_sim.params import MAX_KEY_PARTS, deep_key_line

# Every link length and offset named in [lengths] lies in [LENGTH_MIN, LENGTH_MAX] in [m] (those with zero = true
# may also be 0): from a millimetre (below it an arm is a point and relative tolerances lose meaning) to ten metres
# (no course robot is larger; products of lengths stay far from overflow and underflow).
LENGTH_MIN: float = 1e-3
LENGTH_MAX: float = 10.0
MAX_FILE_BYTES: int = 1 << 20  # a robot file is a few hundred bytes; 1 MiB is far beyond any real table
MAX_JOINTS: int = 7  # the joints (revolute or prismatic) of a chain; fixed rows do not count
MAX_FIXED_ROWS: int = 8  # fixed rows after the last joint (a foot, a flange, a tool): 12,000 of them made kin hang
MAX_LENGTHS: int = 64  # named lengths: a 7-joint table with tool and base names at most 4 x 7 + 2 x 14 + 6 of them
DISTANCE_MAX: float = 100.0  # |a|, |d|, |prismatic limit|, |tool and base xyz| typed as numbers, in [m]
ANGLE_MAX_DEG: float = 360.0  # |theta|, |alpha|, |revolute limit|, |rpy| in [deg] (2π rad): beyond it, a unit slip
MASS_MAX: float = 1000.0  # [kg] a link's optional mass
# [kg] and at least this (as a legged-robot file's masses): 1e-12 kg scaled the link's inertia below what MuJoCo
# accepts ("inertia must have positive eigenvalues"): export wrote a model that does not load, arm-track crashed.
MASS_MIN: float = 1e-4
NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_.-]{0,63}")  # robot and joint names: XML-, URDF- and file-safe
LENGTH_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,63}")  # length names: symbols of --symbolic too
# Symbol names --symbolic prints as something else: c1, s23 are its cos/sin of joint angles, pi, E, I, oo, zoo, nan
# sympy's constants (a length "c1" printed "c1*c1" for c1·cos q1, one named "pi" as π in the LaTeX).
MISREAD_SYMBOL = re.compile(r"[cs][0-9]+|pi|E|I|oo|zoo|nan")

TOP_KEYS = ("name", "summary", "convention", "angles", "lengths", "joints", "tool", "base")
JOINT_KEYS = ("name", "type", "a", "alpha", "d", "theta", "lower", "upper", "mass")
DH_KEYS = ("a", "alpha", "d", "theta")
FRAME_KEYS = ("xyz", "rpy")
LENGTH_KEYS = ("value", "doc", "zero")
TYPES = ("revolute", "prismatic", "fixed")
CONVENTIONS = ("standard", "modified")
ANGLE_UNITS = ("deg", "rad")


@dataclasses.dataclass(frozen=True)
class Length:
    """A named link length of a robot: `kin --set NAME=VALUE` changes it."""

    default: float
    doc: str
    allow_zero: bool = False  # offsets may be 0; link lengths must be > 0

    def allowed(self) -> str:
        """The allowed values as text, e.g. '0 or 0.001 to 10 m'."""
        return f"{'0 or ' if self.allow_zero else ''}{LENGTH_MIN:g} to {LENGTH_MAX:g} m"

    def accepts(self, value: object) -> bool:
        """Whether `value` is an allowed length in [m]."""
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return False
        return (self.allow_zero and value == 0) or LENGTH_MIN <= value <= LENGTH_MAX


@dataclasses.dataclass(frozen=True)
class RobotSpec:
    """A robot, resolved once: its named lengths and the function that builds its chain from them.

    Attributes:
        name: Robot name.
        summary: One line about it.
        lengths: Named lengths (may be empty).
        build: Lengths by name -> the chain.
        joint_units: "rad" or "m" per joint.
        fixed: Lengths by name -> the table's fixed rows after the last joint (shown by `kin`; already folded
            into the chain's tool). None: no fixed rows.
        masses: Each joint's link mass in [kg], or None for the model's default (solid aluminium cylinders).
        source: The file it was read from, or None for a spec written in Python.
        builtin: One of the package's robots (their closed-form IK and singular sets apply).
        file_id: The file's (device, inode), or None: `export` refuses to write over it.
        text: The file's text as read, or None: what a pickled spec is made again from (`build` is a closure), so a
            run's parameters travel to a sweep's worker with the version of the file that was checked.
    """

    name: str
    summary: str
    lengths: Mapping[str, Length]
    build: Callable[[Mapping[str, float]], SerialChain]
    joint_units: tuple[str, ...]
    fixed: Callable[[Mapping[str, float]], tuple[Joint, ...]] | None = None
    masses: tuple[float | None, ...] = ()
    source: str | None = None
    builtin: bool = False
    file_id: tuple[int, int] | None = None  # (st_dev, st_ino) of the file read: exports never write over it
    text: str | None = dataclasses.field(default=None, repr=False)

    def __reduce__(self):
        if self.text is None:  # a spec written in Python: its own fields (a closure in `build` cannot be pickled)
            return copyreg.__newobj__, (type(self),), dict(self.__dict__)
        return _from_text, (self.text, self.source or "<robot file>", self.builtin, self.file_id)

    def values(self, overrides: Mapping[str, float] | None = None) -> dict[str, float]:
        """Every length by name in [m]: the defaults replaced by `overrides` (validated)."""
        values = {name: spec.default for name, spec in self.lengths.items()}
        if not (overrides is None or isinstance(overrides, Mapping)):  # lengths="a2=0.3": an AttributeError
            raise UsageError(f"the lengths of {self.name} are a mapping name -> [m]; got {type(overrides).__name__}")
        for name, value in (overrides or {}).items():
            if name not in self.lengths:
                known = ", ".join(self.lengths) or "none (the file has no [lengths])"
                raise UsageError(f"unknown length '{name}' for {self.name}; known: {known}")
            length = self.lengths[name]
            if not length.accepts(value):
                raise UsageError(f"length '{name}' of {self.name} must be {length.allowed()}; got {value!r}")
            values[name] = float(value)
        return values

    def chain(self, overrides: Mapping[str, float] | None = None) -> SerialChain:
        """The chain with default lengths replaced by `overrides` (validated)."""
        return self.build(self.values(overrides))

    def fixed_rows(self, overrides: Mapping[str, float] | None = None) -> tuple[Joint, ...]:
        """The fixed rows after the last joint (e.g. the leg's foot), () if none."""
        return () if self.fixed is None else self.fixed(self.values(overrides))


# ---------------------------------------------------------------------------------------------------- reading


def read(path: str | os.PathLike[str], *, builtin: bool = False) -> RobotSpec:
    """The robot in a TOML robot file, checked: any problem is one UsageError line naming the file and the field.

    Args:
        path: The file.
        builtin: True for the package's own robots (enables their closed forms).

    Raises:
        UsageError: Unreadable, larger than MAX_FILE_BYTES, not UTF-8 or not TOML, or any field wrong.
    """
    shown = printable(os.fspath(path))
    text, status = read_text(path, "a DH table")
    return _from_text(text, shown, builtin, (status.st_dev, status.st_ino))


def _from_text(text: str, source: str, builtin: bool, file_id: tuple[int, int] | None) -> RobotSpec:
    """The robot of a file's text as `read` made it (and a pickled spec is made again)."""
    return dataclasses.replace(parse(text, source, builtin=builtin), file_id=file_id, text=text)


def read_text(path: str | os.PathLike[str], what: str) -> tuple[str, os.stat_result]:
    """The text of a robot file (a DH table, a legged robot) and its status: any problem one UsageError line.

    Refused: a folder, a FIFO or a device (opened without blocking: a FIFO never hangs), over MAX_FILE_BYTES
    (`what` says what a robot file is instead), not UTF-8. A byte-order mark is dropped, as params.read_config.
    """
    shown = printable(os.fspath(path))
    try:
        # Non-blocking: a FIFO opens at once (and is refused below) instead of waiting for a writer forever.
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_BINARY", 0))
    except IsADirectoryError:
        raise UsageError(f"robot file {shown}: is a folder, not a file") from None
    except OSError as e:
        raise UsageError(f"robot file {shown}: cannot be read ({e.strerror or e})") from None
    status = os.fstat(fd)
    if not stat.S_ISREG(status.st_mode):  # a folder, a FIFO, a device (/dev/zero), a socket: not a DH table
        os.close(fd)
        if stat.S_ISDIR(status.st_mode):
            raise UsageError(f"robot file {shown}: is a folder, not a file")
        raise UsageError(f"robot file {shown}: not a regular file (a pipe or a device); give a .toml file")
    with open(fd, "rb") as f:
        try:
            data = f.read(MAX_FILE_BYTES + 1)
        except OSError as e:
            raise UsageError(f"robot file {shown}: cannot be read ({e.strerror or e})") from None
    if len(data) > MAX_FILE_BYTES:
        raise UsageError(f"robot file {shown}: larger than {MAX_FILE_BYTES // 1024} KiB; a robot file is {what}")
    try:
        return data.decode("utf-8").removeprefix("\ufeff"), status  # a BOM from a Windows editor
    except UnicodeDecodeError as e:
        raise UsageError(f"robot file {shown}: not UTF-8 text (byte {e.start})") from None


def load_toml(text: str, source: str) -> dict[str, Any]:
    """The TOML document of a robot file's text; not TOML (or nested too deeply for tomllib) is one UsageError."""
    line = deep_key_line(text)  # tomllib's time and memory grow with the square of a key's depth
    if line is not None:
        raise UsageError(
            f"robot file {source}: line {line}: a dotted key of more than {MAX_KEY_PARTS} parts; a robot file's keys "
            "have at most 3 (lengths.l2.value)"
        )
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise UsageError(f"robot file {source}: not valid TOML: {e}") from None
    except RecursionError:  # tomllib parses nested arrays and inline tables recursively: `x = [[[[...]]]]`
        raise UsageError(f"robot file {source}: not valid TOML: arrays or tables nested too deeply") from None
    except ValueError as e:  # an integer longer than Python converts ("Exceeds the limit (4300 digits) ..."):
        reason = f"an integer of more than {sys.get_int_max_str_digits()} digits" if "digits" in str(e) else e
        raise UsageError(f"robot file {source}: not valid TOML: {reason}") from None


def parse(text: str, source: str = "<robot file>", *, builtin: bool = False) -> RobotSpec:
    """The robot described by TOML `text`; `source` names it in messages (see `read`)."""
    return _Reader(source, load_toml(text, source)).spec(builtin)


class _Reader:
    """Checks one parsed document; every message starts "robot file FILE: ..."."""

    def __init__(self, source: str, doc: dict[str, Any]) -> None:
        self.source = source
        self.doc = doc

    def fail(self, where: str, message: str) -> UsageError:
        return UsageError(f"robot file {self.source}: {where}{': ' if where else ''}{message}")

    def keys(
        self, table: Any, allowed: tuple[str, ...], where: str, required: tuple[str, ...] = (), any_key: bool = False
    ) -> dict:
        if not isinstance(table, dict):
            raise self.fail(where, f"must be a table; got {type(table).__name__}")
        for key in table:
            if not any_key and key not in allowed:
                raise self.fail(where, f"unknown key '{printable(key)}'; allowed: {', '.join(allowed)}")
        for key in required:
            if key not in table:
                raise self.fail(where, f"missing '{key}' (required: {', '.join(required)})")
        return table

    def choice(self, table: dict, key: str, options: tuple[str, ...], where: str) -> str:
        value = table[key]
        if value not in options:
            raise self.fail(where, f"'{key}' must be one of {', '.join(options)}; got {brief(value)}")
        return value

    def name(self, value: Any, where: str, what: str) -> str:
        if not isinstance(value, str) or not NAME.fullmatch(value):
            raise self.fail(
                where,
                f"{what} must be 1 to 64 letters, digits, _ . - (starting with a letter or _); got {brief(value)}",
            )
        return value

    def number(self, value: Any, where: str, key: str, unit: str, limit: float) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.fail(where, f"'{key}' must be a number [{unit}]; got {brief(value)}")
        if not finite(value):
            raise self.fail(where, f"'{key}' must be a finite number [{unit}]; got {brief(value)}")
        if abs(value) > limit:
            hint = ""
            if unit == "rad":
                hint = ' (the file says angles = "rad"; for degrees write angles = "deg")'
            raise self.fail(where, f"'{key}' = {value:g} {unit} is outside the allowed ±{limit:g} {unit}{hint}")
        return float(value)

    def spec(self, builtin: bool) -> RobotSpec:
        if isinstance(self.doc, dict) and not {"leg", "legs"}.isdisjoint(self.doc) and "joints" not in self.doc:
            raise self.fail("", "is a legged-robot file, not a serial-arm (DH) robot file: walk it with --set "
                            "robot=FILE in hexabot-walk (six legs) or quadbot-walk (four legs) "
                            "(docs/robot-files.md#legged-robot-files)")  # fmt: skip
        doc = self.keys(self.doc, TOP_KEYS, "", ("name", "convention", "angles", "joints"))
        name = self.name(doc["name"], "", "'name'")
        summary = doc.get("summary", "")
        if not one_line(summary) or len(summary) > 200:
            raise self.fail("", f"'summary' must be one line of text (at most 200 characters); got {brief(summary)}")
        convention = self.choice(doc, "convention", CONVENTIONS, "")
        self.unit = self.choice(doc, "angles", ANGLE_UNITS, "")
        self.angle_max = ANGLE_MAX_DEG if self.unit == "deg" else math.radians(ANGLE_MAX_DEG)
        self.lengths = self.named_lengths(doc.get("lengths", {}))
        rows = doc["joints"]
        if not isinstance(rows, list) or not rows:
            raise self.fail("", "'joints' must be one or more [[joints]] tables")
        if len(rows) > MAX_JOINTS + MAX_FIXED_ROWS:
            raise self.fail(
                "",
                f"{len(rows)} [[joints]] rows; at most {MAX_JOINTS} joints and {MAX_FIXED_ROWS} fixed rows after them",
            )
        joints = [self.row(i, row) for i, row in enumerate(rows, start=1)]
        moving = [j for j in joints if j["type"] != "fixed"]
        if not moving:
            raise self.fail("", "no joint: a chain needs at least one revolute or prismatic joint")
        if len(moving) > MAX_JOINTS:
            raise self.fail("", f"{len(moving)} joints; at most {MAX_JOINTS} (fixed rows not counted)")
        if len(joints) - len(moving) > MAX_FIXED_ROWS:
            raise self.fail("", f"{len(joints) - len(moving)} fixed rows; at most {MAX_FIXED_ROWS}")
        last = max(i for i, j in enumerate(joints) if j["type"] != "fixed")
        for i, j in enumerate(joints[:last]):
            if j["type"] == "fixed":
                raise self.fail(self.where(i + 1, j["name"]), "a fixed row may only follow the last joint")
        names = [j["name"] for j in joints]
        for i, n in enumerate(names):
            if names.index(n) != i:
                raise self.fail(self.where(i + 1, n), f"the name '{n}' is used twice; joint names must be unique")
            if n in self.lengths:
                raise self.fail(self.where(i + 1, n), f"the name '{n}' is also a length; use distinct names")
        tool = self.frame(doc.get("tool"), "[tool]")
        base = self.frame(doc.get("base"), "[base]")
        rows_t = tuple(joints)

        def build(values: Mapping[str, float]) -> SerialChain:  # checked for every set of lengths (--set too)
            return check_not_degenerate(
                _build(name, convention, rows_t, tool, base, values, self.source), self.source, LENGTH_MIN
            )

        def fixed(values: Mapping[str, float]) -> tuple[Joint, ...]:
            return tuple(_joint(row, values) for row in rows_t if row["type"] == "fixed")

        spec = RobotSpec(
            name=name,
            summary=summary,
            lengths=dict(self.lengths),
            build=build,
            joint_units=tuple("m" if j["type"] == "prismatic" else "rad" for j in moving),
            fixed=fixed if len(moving) < len(joints) else None,
            masses=tuple(j.get("mass") for j in moving),
            source=self.source,
            builtin=builtin,
        )
        spec.chain()  # the default lengths must make a tool that moves
        return spec

    def where(self, index: int, name: Any = None) -> str:
        return f"joint {index}" + (f" ('{name}')" if isinstance(name, str) and NAME.fullmatch(name) else "")

    def named_lengths(self, table: Any) -> dict[str, Length]:
        if isinstance(table, dict) and len(table) > MAX_LENGTHS:  # before any loop over them (40,000 took 24 s)
            raise self.fail("[lengths]", f"{len(table)} lengths; at most {MAX_LENGTHS}")
        table = self.keys(table, (), "[lengths]", any_key=True)
        out = {}
        for key, entry in table.items():
            if not LENGTH_NAME.fullmatch(key):  # a symbol in --symbolic: "c1*l-1" would read as c1 l minus 1
                raise self.fail(
                    "[lengths]",
                    f"a length name must be 1 to 64 letters, digits, _ (starting with a letter or _; it is a symbol in "
                    f"--symbolic, where - and . would read as a minus and a decimal point); got {brief(key)}",
                )
            if MISREAD_SYMBOL.fullmatch(key):
                raise self.fail(
                    "[lengths]",
                    f"the length name {brief(key)} would be misread in --symbolic, where c1, s23 are cos and sin of "
                    "joint angles and pi, E, I, oo, zoo, nan are constants; choose another name",
                )
            where = f"[lengths] {key}"
            if isinstance(entry, dict):
                entry = self.keys(entry, LENGTH_KEYS, where, ("value",))
            else:
                entry = {"value": entry}
            doc = entry.get("doc", "")
            zero = entry.get("zero", False)
            if not one_line(doc):
                raise self.fail(where, f"'doc' must be one line of text; got {brief(doc)}")
            if not isinstance(zero, bool):
                raise self.fail(where, f"'zero' must be true or false; got {brief(zero)}")
            value = self.number(entry["value"], where, "value", "m", LENGTH_MAX)
            length = Length(value, doc, zero)
            if not length.accepts(value):
                raise self.fail(where, f"'value' must be {length.allowed()}; got {value:g}")
            out[key] = length
        return out

    def row(self, index: int, row: Any) -> dict[str, Any]:
        where = self.where(index, row.get("name") if isinstance(row, dict) else None)
        row = self.keys(row, JOINT_KEYS, where, ("name", "type", *DH_KEYS))
        name = self.name(row["name"], where, "'name'")
        kind = self.choice(row, "type", TYPES, where)
        out: dict[str, Any] = {"name": name, "type": kind, "where": where}
        for key in DH_KEYS:
            if key in ("a", "d"):
                out[key] = self.distance(row[key], where, key)
            else:
                out[key] = self.angle(row[key], where, key)
        has = [key in row for key in ("lower", "upper")]
        if kind == "fixed" and (any(has) or "mass" in row):
            raise self.fail(where, "a fixed row takes no 'lower', 'upper' or 'mass'")
        if has[0] != has[1]:
            raise self.fail(
                where, f"give both 'lower' and 'upper', or neither; got only '{'lower' if has[0] else 'upper'}'"
            )
        if all(has):
            for key in ("lower", "upper"):
                out[key] = (
                    self.distance(row[key], where, key) if kind == "prismatic" else self.angle(row[key], where, key)
                )
            lo, hi = _value(out["lower"], self.lengths), _value(out["upper"], self.lengths)
            if not lo < hi:
                unit = "m" if kind == "prismatic" else self.unit
                shown_lo, shown_hi = (lo, hi) if unit != "deg" else (math.degrees(lo), math.degrees(hi))
                raise self.fail(where, f"'lower' ({shown_lo:g} {unit}) must be less than 'upper' ({shown_hi:g} {unit})")
        if "mass" in row:
            mass = self.number(row["mass"], where, "mass", "kg", MASS_MAX)
            if not mass >= MASS_MIN:
                raise self.fail(where, f"'mass' must be {MASS_MIN:g} to {MASS_MAX:g} kg; got {mass:g}")
            out["mass"] = mass
        return out

    def distance(self, value: Any, where: str, key: str) -> float | tuple[float, str]:
        """A number in [m], or a reference "name" / "-name" to a length: (sign, name)."""
        if isinstance(value, str):
            sign, ref = (-1.0, value[1:]) if value.startswith("-") else (1.0, value)
            if ref not in self.lengths:
                known = ", ".join(self.lengths) or "none: the file has no [lengths]"
                raise self.fail(where, f"'{key}' names the length {brief(ref)}, which [lengths] lacks; known: {known}")
            return (sign, ref)
        return self.number(value, where, key, "m", DISTANCE_MAX)

    def angle(self, value: Any, where: str, key: str) -> float:
        """A number in the file's angle unit -> [rad]."""
        number = self.number(value, where, key, self.unit, self.angle_max)
        return math.radians(number) if self.unit == "deg" else number

    def frame(self, table: Any, where: str) -> tuple[tuple[Any, ...], np.ndarray]:
        """[tool] or [base]: (xyz as distances, the rotation (3, 3) of rpy, R = Rz(yaw) Ry(pitch) Rx(roll))."""
        if table is None:
            return (0.0, 0.0, 0.0), np.eye(3)
        table = self.keys(table, FRAME_KEYS, where)
        xyz = table.get("xyz", [0.0, 0.0, 0.0])
        rpy = table.get("rpy", [0.0, 0.0, 0.0])
        for key, value in (("xyz", xyz), ("rpy", rpy)):
            if not isinstance(value, list) or len(value) != 3:
                raise self.fail(where, f"'{key}' must be a list of 3 numbers; got {brief(value)}")
        position = tuple(self.distance(v, where, f"xyz[{i}]") for i, v in enumerate(xyz))
        angles = [self.number(v, where, f"rpy[{i}]", self.unit, self.angle_max) for i, v in enumerate(rpy)]
        cs = [_cos_sin(v, self.unit) for v in angles]
        return position, _rz(*cs[2]) @ _ry(*cs[1]) @ _rx(*cs[0]) + 0.0


def finite(value: int | float) -> bool:
    """Whether a TOML number is finite as a float: not nan or inf, nor an integer beyond a float's range (TOML
    integers have any number of digits: math.isfinite(10**400) raises OverflowError)."""
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


def one_line(text: Any) -> bool:
    """One line of printable text: it goes into the MJCF's and URDF's header comment (XML allows no control
    characters, U+FFFE or U+FFFF, even in a comment) and onto the terminal (ESC would recolour it, a bidi control
    U+202A-E or U+2066-9 reorder what follows)."""
    bad = "\u2028\u2029\ufffe\uffff\u202a\u202b\u202c\u202d\u202e\u2066\u2067\u2068\u2069"
    return isinstance(text, str) and not any((unicodedata.category(c) == "Cc" and c != "\t") or c in bad for c in text)


def brief(value: Any) -> str:
    """A TOML value for a message, short and on one line."""
    text = printable(repr(value))
    return text if len(text) <= 40 else text[:37] + "..."


# --------------------------------------------------------------------------------------------- the package's

ARMS_DIR = Path(__file__).resolve().parent / "arms"  # the package's robot files (they ship in the wheel)


def builtin_files() -> dict[str, Path]:
    """The package's robot files by name (file stem)."""
    return {p.stem: p for p in sorted(ARMS_DIR.glob("*.toml"))}
