"""Typed, validated scenario parameters: defaults, TOML files and `--set name=value` overrides."""

from __future__ import annotations

import contextlib
import dataclasses
import datetime
import decimal
import math
import numbers
import os
import re
import stat
import sys
import tomllib
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, TypeVar

from hexabot_sim.errors import UsageError

MAX_LIST_ITEMS: int = 400  # longest comma-separated list a parameter takes (a grid axis)
MAX_CONFIG_BYTES: int = 1 << 20  # a parameter file is a few lines; more than 1 MiB is not one
MAX_SHOWN: int = 40  # characters of a bad value quoted back in an error message
MAX_PATH_CHARS: int = 4096  # longest file path a name-or-file parameter takes (PATH_MAX on Linux)


@dataclasses.dataclass(frozen=True)
class NameOrFile:
    """A text parameter that names one of `names` or gives the path of a file (a robot: a name or a TOML file);
    `check` reads the file when the parameter is resolved, so a bad one is refused (UsageError) before the run."""

    names: tuple[str, ...]  # matched case-insensitively; a name wins over a file of the same name
    what: str  # the file's kind in messages, e.g. "robot file (.toml)"
    check: Callable[[str], object]  # path -> anything; raises UsageError (one line) for any problem

    def allowed(self) -> str:
        return f"one of {', '.join(self.names)}, or the path of a {self.what}"


@dataclasses.dataclass(frozen=True)
class ParamInfo:
    """What `hexabot-sim list` shows of a parameter and how its values are checked.

    Attributes:
        unit: Unit as shown to users, e.g. "kg" or "rad/s"; "" for none.
        doc: One-line description.
        ge, gt: Lower bound, inclusive or exclusive (exactly one is set for a number).
        le, lt: Upper bound, inclusive or exclusive (exactly one is set for a number).
        choices: Allowed strings of a text parameter (matched case-insensitively).
        typo: (unit, size in this unit) of a unit users often type by mistake, e.g. ("mm/s", 1e-3):
            a value out of range, at least 10 in size and in range in that unit gets a "did you mean" hint.
        table: (what it takes in words, reader) of a table parameter: a CSV file name (--set, TOML) or rows
            (the Python API), which reader(name, raw) turns into a tuple of rows or refuses (UsageError).
        name_or_file: A text parameter that is a built-in name or the path of a file (NameOrFile), else None.
    """

    unit: str
    doc: str
    ge: float | None = None
    gt: float | None = None
    le: float | None = None
    lt: float | None = None
    choices: tuple[str, ...] | None = None
    typo: tuple[str, float] | None = None
    table: tuple[str, Callable[[str, Any], tuple]] | None = None
    name_or_file: NameOrFile | None = None

    @property
    def text(self) -> bool:  # a text parameter (choices, or a name or file), not a number
        return self.choices is not None or self.name_or_file is not None

    def contains(self, value: float) -> bool:
        """True if the number is inside the allowed range."""
        return (
            (self.ge is None or value >= self.ge)
            and (self.gt is None or value > self.gt)
            and (self.le is None or value <= self.le)
            and (self.lt is None or value < self.lt)
        )


def param(
    default: Any,
    unit: str,
    doc: str,
    *,
    ge: float | None = None,
    gt: float | None = None,
    le: float | None = None,
    lt: float | None = None,
    choices: tuple[str, ...] | None = None,
    typo: tuple[str, float] | None = None,
    table: tuple[str, Callable[[str, Any], tuple]] | None = None,
    name_or_file: NameOrFile | None = None,
) -> Any:
    """Declares a field of a scenario's parameter dataclass.

    A number needs a range with both ends (ge or gt, le or lt): every value that passes is one the
    scenario can run. A text parameter needs its choices, or is a name or a file (name_or_file); a table
    parameter needs its reader (ParamInfo.table).
    """
    bounded = choices is not None or name_or_file is not None or table is not None
    if not bounded and ((ge is None) == (gt is None) or (le is None) == (lt is None)):
        raise ValueError(f"parameter {doc!r}: give exactly one lower (ge, gt) and one upper (le, lt) bound")
    info = ParamInfo(unit, doc, ge, gt, le, lt, choices, typo, table, name_or_file)
    return dataclasses.field(default=default, metadata={"param": info})


def _number(value: float) -> str:
    """A bound in words: 6 significant digits, or in full an integer they would round (a seed's 4294967295)."""
    text = f"{value:.6g}"
    if math.isfinite(value) and float(value).is_integer() and float(text) != value:
        return str(int(value))
    return text


def apart(value: float, bound: float, toward: str, least: int = 3) -> tuple[str, str]:
    """`value` and `allowed(bound, toward)` with as many digits as it takes for the two texts to differ
    ("a 32.004 mm kerb is above the largest climbable, 32.003 mm", not "32 mm ... 32 mm"). Every refusal that
    prints a value against its bound formats the pair with this; a value equal to its (excluded) bound is shown
    as it is, twice ("smaller than 'length' (0.3 m); got 0.3", not "(0.29999999999999999 m)")."""
    if value == bound:
        text = f"{value:.{least}g}" if float(f"{value:.{least}g}") == value else repr(float(value))
        return text, text
    for digits in range(least, 18):
        shown, limit = f"{value:.{digits}g}", allowed(bound, toward, digits)
        if float(shown) != float(limit):
            return shown, limit
    return f"{value!r}", allowed(bound, toward, 17)


def allowed(value: float, toward: str, digits: int = 3) -> str:
    """`value` to 3 significant digits, rounded so the printed number is itself allowed: "up" for a lower
    bound, "down" for an upper bound, "zero" for the largest magnitude in a direction (0.8333 printed as
    0.833 was refused as below the wave's smallest duty, 5/6); "nearest" where the bound is shown as it is
    (a joint range in a warning). Rounding noise past 15 digits is ignored (a bound
    computed as 0.7500000000000001 is 0.75), and the rounding is decimal, not binary (1000 is not 999.99999)."""
    if value == 0 or not math.isfinite(value) or toward == "nearest":
        return f"{value:.{digits}g}"
    exact = decimal.Decimal(f"{value:.{max(15, digits)}g}")
    rounding = {"up": decimal.ROUND_CEILING, "down": decimal.ROUND_FLOOR, "zero": decimal.ROUND_DOWN}[toward]
    step = decimal.Decimal(1).scaleb(exact.adjusted() - (digits - 1))
    return f"{float(exact.quantize(step, rounding=rounding)):.{digits}g}"


def describe_range(info: ParamInfo, name: str = "value") -> str:
    """The allowed values in words, e.g. "0 < mass <= 1000 kg" or "one of RK4, Euler, implicit"."""
    if info.choices is not None:
        return f"one of {', '.join(info.choices)}"
    if info.table is not None:
        return f"{name} = {info.table[0]}"
    if info.name_or_file is not None:
        return info.name_or_file.allowed()
    low = f"{_number(info.ge)} <= " if info.ge is not None else f"{_number(info.gt)} < "  # type: ignore[arg-type]
    high = f" <= {_number(info.le)}" if info.le is not None else f" < {_number(info.lt)}"  # type: ignore[arg-type]
    unit = f" {info.unit}" if info.unit and info.unit != "1" else ""
    return f"{low}{name}{high}{unit}"


def infos(cls: type) -> dict[str, tuple[ParamInfo, Any]]:
    """Name -> (ParamInfo, class default) for every parameter of a dataclass, in declaration order."""
    return {f.name: (f.metadata["param"], f.default) for f in dataclasses.fields(cls) if "param" in f.metadata}


def _show(raw: Any) -> str:
    """A bad value as quoted back to the user: short, on one line."""
    if isinstance(raw, float):
        text = repr(raw)
    elif isinstance(raw, int) and not isinstance(raw, bool):
        digits = int(raw.bit_length() * math.log10(2)) + 1  # the count, or one less
        if raw.bit_length() < 128:
            text = str(raw)
        elif digits < sys.get_int_max_str_digits():  # str() of a longer int raises
            text = f"an integer of {len(str(abs(raw)))} digits"
        else:
            text = f"an integer of about {digits} digits"
    elif isinstance(raw, (datetime.date, datetime.time)):  # TOML dates and times
        text = f"the {type(raw).__name__} {raw.isoformat()}"
    else:
        text = repr(raw)
    return text if len(text) <= MAX_SHOWN else text[: MAX_SHOWN - 3] + "..."


def _to_float(raw: Any) -> float | None:
    """A number from a --set string or a TOML value (None if it is not one); huge integers become inf."""
    if isinstance(raw, bool):
        return None
    if isinstance(raw, str):
        text = raw.strip()
        if len(text) > 100 or "_" in text or not text.isascii():
            return None  # float() reads "1_0" as 10 and "５" as 5: a slip for "1,0" or "1.0", or not our digits
        try:
            return float(text)
        except ValueError:
            return None
    if isinstance(raw, int):
        try:
            return float(raw)
        except OverflowError:
            return math.inf if raw > 0 else -math.inf
    if isinstance(raw, float):
        return raw
    if isinstance(raw, (numbers.Real, decimal.Decimal)):  # numpy scalars, Fraction, Decimal from the Python API
        try:
            return float(raw)
        except (OverflowError, ValueError):
            return None
    return None


def _convert(name: str, raw: Any, info: ParamInfo, kind: type) -> Any:
    """Converts one raw value (a string from --set or a TOML value) and checks its range."""
    if (info.table is not None or info.name_or_file is not None) and isinstance(raw, str):
        raw = home(raw)
    if info.table is not None:  # a file name or rows: the parameter's own reader
        return info.table[1](name, raw)
    if kind is tuple:  # a list of numbers: "0.01,0.05" on the command line, [0.01, 0.05] in TOML
        items = raw.split(",", MAX_LIST_ITEMS) if isinstance(raw, str) else raw
        if not isinstance(items, (list, tuple)) or not items or any(str(v).strip() == "" for v in items[:3]):
            raise UsageError(
                f"parameter '{name}' must be a comma-separated list of numbers, each {describe_range(info, 'x')}; "
                f"got {_show(raw)}"
            )
        if len(items) > MAX_LIST_ITEMS:
            raise UsageError(f"parameter '{name}' takes at most {MAX_LIST_ITEMS} numbers; got more")
        return tuple(_convert(name, v, info, float) for v in items)
    if info.name_or_file is not None:
        return _name_or_file(name, raw, info.name_or_file)
    if info.choices is not None:
        text = raw.strip() if isinstance(raw, str) else None
        canonical = {c.casefold(): c for c in info.choices}
        if text is None or text.casefold() not in canonical:
            raise UsageError(f"parameter '{name}' must be one of {', '.join(info.choices)}; got {_show(raw)}")
        return canonical[text.casefold()]
    value = _to_float(raw)
    allowed = describe_range(info, name)
    if value is None or math.isnan(value):
        raise UsageError(f"parameter '{name}' must be a number with {allowed}; got {_show(raw)}")
    value += 0.0  # -0.0 -> 0.0
    if not info.contains(value):
        hint = ""
        if info.typo is not None and math.isfinite(value) and abs(value) >= 10:  # mm, mm/s, deg/s come as big numbers
            typo_unit, size = info.typo
            if info.contains(value * size):
                hint = f"; did you mean {_number(value)} {typo_unit} = {_number(value * size)} {info.unit}?"
        what = "a whole number" if kind is int else "a number"
        raise UsageError(f"parameter '{name}' must be {what} with {allowed}; got {_show(raw)}{hint}")
    if kind is int:
        if value != int(value):
            raise UsageError(f"parameter '{name}' must be a whole number with {allowed}; got {_show(raw)}")
        return int(value)
    return value


def input_files(config: str | os.PathLike | None, cls: type, layers: Sequence[Mapping[str, Any]],
                grid_values: Sequence[Any] = ()) -> list[str]:  # fmt: skip
    """The files a run or sweep reads: its config file and every existing file a file-naming parameter names (a
    walk's schedule or waypoints, a robot file) in the layers or a grid's values, as the readers take them (~ is
    the user's home). Its output folder may not be, hold or lie inside any of them (folders.check_not_input)."""
    files = [os.fspath(config)] if config is not None else []
    takes_file = {n for n, (info, _) in infos(cls).items() if info.table or info.name_or_file}
    values = [v for layer in layers for n, v in layer.items() if n in takes_file] + list(grid_values)
    named = [home(os.fspath(v)) for v in values if isinstance(v, (str, os.PathLike))]
    return files + [v for v in named if isinstance(v, str) and os.path.isfile(v)]


def home(text: str) -> str:
    """A file name with its leading ~ or ~user expanded, as a shell would (no shell expands it after `--set name=` or
    in a config file); any other text as it is."""
    return os.path.expanduser(text) if text.startswith("~") else text


def _name_or_file(name: str, raw: Any, kind: NameOrFile) -> str:
    """A built-in name (canonical spelling) or the path of a file that kind.check accepts, as given."""
    text = os.fspath(raw) if isinstance(raw, (str, os.PathLike)) else None
    if not isinstance(text, str) or not text.strip():
        raise UsageError(f"parameter '{name}' must be {kind.allowed()}; got {_show(raw)}")
    canonical = {n.casefold(): n for n in kind.names}
    if text.strip().casefold() in canonical:
        return canonical[text.strip().casefold()]
    if not (len(text) <= MAX_PATH_CHARS and "\0" not in text and os.path.exists(text)):  # exists() raises no OSError
        raise UsageError(f"parameter '{name}' must be {kind.allowed()}; got {_show(raw)} (no such name or file)")
    try:
        kind.check(text)
    except UsageError as e:
        raise UsageError(f"parameter '{name}': {e}") from None
    return text


def parse_assignments(items: list[str]) -> dict[str, str]:
    """Parses repeated `name=value` strings from the command line. An empty value goes to the parameter's own check
    (a table such as a walk's schedule reads it as none, clearing a config file's; a number refuses it), and a
    parameter given twice with different values is refused (the last one silently won)."""
    out: dict[str, str] = {}
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise UsageError(f"malformed --set {_show(item)}: expected name=value, e.g. --set mass=0.2")
        if name in out and out[name] != value:
            raise UsageError(
                f"parameter {_show(name)} is given twice with --set ({_show(out[name])} and {_show(value)}): "
                "give it once"
            )
        out[name] = value
    return out


# A dotted key (or table header) of this many parts is refused before tomllib reads it: its time and memory grow with
# the square of a key's depth (a 600 KB key "a.a.a..." of 300,000 parts ran 7 minutes and took 24 GB before it was
# killed). Found without backtracking: a part starts after no key character, dot or quote.
MAX_KEY_PARTS: int = 32
_DEEP_KEY = re.compile(
    r"""(?<![A-Za-z0-9_"'.-])(?:(?:[A-Za-z0-9_-]++|"[^"\\\n]*+"|'[^'\n]*+')[ \t]*+\.[ \t]*+)""" + f"{{{MAX_KEY_PARTS}}}"
)


def deep_key_line(text: str) -> int | None:
    """The line (from 1) of the first dotted key of more than MAX_KEY_PARTS parts in TOML `text`, or None."""
    deep = _DEEP_KEY.search(text)
    return None if deep is None else text.count("\n", 0, deep.start()) + 1


def read_bounded(
    path: Path, what: str = "config file", limit: int = MAX_CONFIG_BYTES, why: str = "a parameter file is a few lines"
) -> bytes:
    """At most `limit` bytes of a regular file; never blocks on a FIFO or reads a device (UsageError naming `what`)."""
    shown = repr(str(path))  # a path is shown whole: cut short, it would not name the file
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except FileNotFoundError:
        raise UsageError(f"{what} {shown} not found") from None
    except IsADirectoryError:
        raise UsageError(f"{what} {shown} is a directory, expected a file") from None
    except (OSError, ValueError) as e:  # ValueError: a NUL byte in the name
        raise UsageError(f"{what} {shown} cannot be read: {getattr(e, 'strerror', None) or e}") from None
    try:
        mode = os.fstat(fd).st_mode
        if stat.S_ISDIR(mode):
            raise UsageError(f"{what} {shown} is a directory, expected a file")
        if not stat.S_ISREG(mode):
            raise UsageError(f"{what} {shown} is not a regular file (a device, FIFO or socket)")
        chunks, size = [], 0
        while size <= limit:
            chunk = os.read(fd, limit + 1 - size)
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
    except OSError as e:
        raise UsageError(f"{what} {shown} cannot be read: {e.strerror or e}") from None
    finally:
        os.close(fd)
    if size > limit:
        shown_limit = f"{limit // 1024} KiB" if limit <= 1 << 20 else f"{limit / (1 << 20):g} MiB"
        raise UsageError(f"{what} {shown} is larger than {shown_limit}; {why}")
    return b"".join(chunks)


def read_config(path: str | Path, cls: type | None = None) -> dict[str, Any]:
    """Reads a TOML file of `name = value` lines, at the top level or in a `[params]` table (or both).

    With `cls` (the scenario's parameters), a parameter of it that names a file (a schedule, waypoints, a robot
    file) by a relative path is read from the config file's folder when the file is there, as tools that take
    config files do (a config and its files travel together); otherwise the path stays as written (relative to
    the working directory).

    Raises:
        UsageError: for a missing, unreadable, oversized or non-regular file, invalid TOML, another
            table than [params], or a name given both at the top level and in [params].
    """
    if str(path) == "":
        raise UsageError("--config needs a file name; got an empty one")
    path = Path(path)
    shown = repr(str(path))  # a path is shown whole: cut short, it would not name the file
    raw = read_bounded(path)
    try:
        text = raw.decode("utf-8").removeprefix("\ufeff")  # a BOM from a Windows editor
    except UnicodeDecodeError:
        raise UsageError(f"config file {shown} is not valid TOML: not UTF-8 text") from None
    line = deep_key_line(text)
    if line is not None:
        raise UsageError(
            f"config file {shown} is not a parameter file: line {line}: a dotted key of more than {MAX_KEY_PARTS} parts"
        )
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise UsageError(f"config file {shown} is not valid TOML: {_first_line(e)}") from None
    except (RecursionError, MemoryError):
        raise UsageError(f"config file {shown} is not a parameter file: nested too deeply") from None
    except ValueError as e:  # an integer longer than Python converts ("Exceeds the limit (4300 digits) ...")
        limit = sys.get_int_max_str_digits()
        reason = f"an integer of more than {limit} digits" if "digits" in str(e) else _first_line(e)
        raise UsageError(f"config file {shown} is not a parameter file: {reason}") from None
    table = data.pop("params", None)
    if table is not None:
        if not isinstance(table, dict):
            raise UsageError(f"config file {shown}: 'params' must be a table ([params]); got {_show(table)}")
        both = sorted(set(table) & set(data))
        if both:
            raise UsageError(
                f"config file {shown}: parameter '{both[0]}' is given both at the top level and in [params]"
            )
        data = {**data, **table}
    for key, value in data.items():
        if isinstance(value, dict):
            raise UsageError(
                f"config file {shown}: unexpected table [{_show(key)[1:-1]}]; write parameters as 'name = value' lines"
            )
    return data if cls is None else files_beside(data, cls, path)


def files_beside(data: dict[str, Any], cls: type, config: Path) -> dict[str, Any]:
    """The values of the config file `config` with each relative file name of a file-naming parameter resolved
    beside it when the file is there: in its folder, else (a config reached through a symbolic link) in the folder
    of the file it links to. A built-in name, e.g. robot = "hexabot", is not a file name."""
    folders = [config.parent]
    with contextlib.suppress(OSError, RuntimeError):  # a link loop: the config is refused when read
        if (real := config.resolve().parent) != config.parent.resolve():
            folders.append(real)
    out = dict(data)
    for name, (info, _) in infos(cls).items():
        value = data.get(name)
        if not isinstance(value, str) or value == "" or (info.table is None and info.name_or_file is None):
            continue
        if info.name_or_file is not None and value.lower() in (n.lower() for n in info.name_or_file.names):
            continue
        if Path(home(value)).is_absolute():  # ~/file: the user's home, not the config's folder
            continue
        missing = False
        with contextlib.suppress(OSError, ValueError):  # a NUL byte or an over-long name: checked later
            out[name] = found = next((str(f / value) for f in folders if (f / value).exists()), value)
            missing = info.table is not None and found == value and not Path(value).exists()
        if missing:  # say where it was looked for (the reader would say only "not found")
            places = " or ".join(repr(str(f)) for f in folders)
            raise UsageError(
                f"{name} file {value!r} (named in config file {str(config)!r}) is in neither {places} nor the "
                "working folder"
            )
    return out


def _first_line(e: Exception) -> str:
    text = str(e).splitlines()[0] if str(e) else type(e).__name__
    return text if len(text) <= 120 else text[:117] + "..."


T = TypeVar("T")


def converted(cls: type, defaults: Mapping[str, Any], *layers: Mapping[str, Any]) -> dict[str, Any]:
    """The given values of `cls`'s parameters, each checked on its own (name, type, range), merged in order.

    Raises:
        UsageError: naming the unknown parameter or the bad value and what is allowed.
    """
    known = infos(cls)
    kinds = {f.name: type(f.default) for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
    values: dict[str, Any] = {}
    for layer in (defaults, *layers):
        for name, raw in layer.items():
            if name not in known:
                raise UsageError(f"unknown parameter {_show(name)}; known: {', '.join(known)}")
            values[name] = _convert(name, raw, known[name][0], kinds[name])
    return values


def build(cls: type[T], values: Mapping[str, Any]) -> T:
    """A parameter object from converted values: the cross-parameter checks (__post_init__) run here.

    Raises:
        UsageError: with the check's message.
    """
    try:
        return cls(**values)
    except ValueError as e:  # cross-field checks in __post_init__
        raise UsageError(str(e)) from None


def resolve(cls: type[T], defaults: Mapping[str, Any], *layers: Mapping[str, Any]) -> T:
    """Builds a parameter object: class defaults < scenario defaults < each layer in order.

    Raises:
        UsageError: naming the unknown parameter or the bad value and what is allowed.
    """
    return build(cls, converted(cls, defaults, *layers))


def as_dict(obj: Any) -> dict[str, Any]:
    """Parameter values of a resolved object, in declaration order."""
    return {name: getattr(obj, name) for name in infos(type(obj))}


def units(cls: type) -> dict[str, str]:
    """Parameter name -> unit."""
    return {name: info.unit for name, (info, _) in infos(cls).items()}
