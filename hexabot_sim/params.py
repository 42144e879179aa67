"""Typed, validated scenario parameters: defaults, TOML files and `--set name=value` overrides."""

from __future__ import annotations

import dataclasses
import math
import tomllib
from collections.abc import Mapping
from pathlib import Path
from typing import Any, TypeVar

from hexabot_sim.errors import UsageError

# Allowed range of a numeric parameter, with the phrase used in error messages.
CHECKS: dict[str, tuple[str, Any]] = {
    "finite": ("a finite number", lambda v: True),
    "positive": ("a finite number > 0", lambda v: v > 0),
    "nonnegative": ("a finite number >= 0", lambda v: v >= 0),
}


@dataclasses.dataclass(frozen=True)
class ParamInfo:
    """What `hexabot-sim list` shows of a parameter and how its values are checked."""

    unit: str
    doc: str
    check: str = "finite"
    choices: tuple[str, ...] | None = None


def param(default: Any, unit: str, doc: str, check: str = "finite", choices: tuple[str, ...] | None = None) -> Any:
    """Declares a field of a scenario's parameter dataclass.

    Args:
        default: Value used when neither a config file nor `--set` gives one.
        unit: Unit in brackets as shown to users, e.g. "kg" or "rad/s"; "" for none.
        doc: One-line description.
        check: "finite", "positive" or "nonnegative" for numbers.
        choices: Allowed strings for a text parameter.
    """
    if check not in CHECKS:
        raise ValueError(f"unknown check {check!r}")
    return dataclasses.field(default=default, metadata={"param": ParamInfo(unit, doc, check, choices)})


def infos(cls: type) -> dict[str, tuple[ParamInfo, Any]]:
    """Name -> (ParamInfo, class default) for every parameter of a dataclass, in declaration order."""
    return {f.name: (f.metadata["param"], f.default) for f in dataclasses.fields(cls) if "param" in f.metadata}


def _convert(name: str, raw: Any, info: ParamInfo, kind: type) -> Any:
    """Converts one raw value (a string from --set or a TOML value) and checks its range."""
    if kind is tuple:  # a list of numbers: "0.01,0.05" on the command line, [0.01, 0.05] in TOML
        items = raw.split(",") if isinstance(raw, str) else raw
        if not isinstance(items, (list, tuple)) or not items or any(str(v).strip() == "" for v in items):
            raise UsageError(f"parameter '{name}' must be a comma-separated list of numbers; got {raw!r}")
        return tuple(_convert(name, v, info, float) for v in items)
    if info.choices is not None:
        text = str(raw)
        if text not in info.choices:
            raise UsageError(f"parameter '{name}' must be one of {', '.join(info.choices)}; got {raw!r}")
        return text
    phrase = CHECKS[info.check][0]
    if isinstance(raw, bool):
        raise UsageError(f"parameter '{name}' must be {phrase}; got {raw!r}")
    if isinstance(raw, str):
        try:
            value = float(raw.strip())
        except ValueError:
            raise UsageError(f"parameter '{name}' must be {phrase}; got {raw!r}") from None
    elif isinstance(raw, (int, float)):
        value = float(raw)
    else:
        raise UsageError(f"parameter '{name}' must be {phrase}; got {raw!r}")
    if not math.isfinite(value) or not CHECKS[info.check][1](value):
        raise UsageError(f"parameter '{name}' must be {phrase}; got {raw!r}")
    if kind is int:
        if value != int(value):
            raise UsageError(f"parameter '{name}' must be a whole number; got {raw!r}")
        return int(value)
    return value


def parse_assignments(items: list[str]) -> dict[str, str]:
    """Parses repeated `name=value` strings from the command line."""
    out: dict[str, str] = {}
    for item in items:
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or not name or not value.strip():
            raise UsageError(f"malformed --set {item!r}: expected name=value, e.g. --set mass=0.2")
        out[name] = value
    return out


def read_config(path: str | Path) -> dict[str, Any]:
    """Reads a TOML file of `name = value` lines (a `[params]` table is accepted too)."""
    path = Path(path)
    try:
        with path.open("rb") as f:
            data = tomllib.load(f)
    except FileNotFoundError:
        raise UsageError(f"config file {str(path)!r} not found") from None
    except IsADirectoryError:
        raise UsageError(f"config file {str(path)!r} is a directory, expected a TOML file") from None
    except OSError as e:
        raise UsageError(f"config file {str(path)!r} cannot be read: {e.strerror}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise UsageError(f"config file {str(path)!r} is not valid TOML: {e}") from None
    if set(data) == {"params"} and isinstance(data["params"], dict):
        data = data["params"]
    for key, value in data.items():
        if isinstance(value, dict):
            raise UsageError(
                f"config file {str(path)!r}: unexpected table [{key}]; write parameters as 'name = value' lines"
            )
    return data


T = TypeVar("T")


def resolve(cls: type[T], defaults: Mapping[str, Any], *layers: Mapping[str, Any]) -> T:
    """Builds a parameter object: class defaults < scenario defaults < each layer in order.

    Raises:
        UsageError: naming the unknown parameter or the bad value and what is allowed.
    """
    known = infos(cls)
    kinds = {f.name: type(f.default) for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
    values: dict[str, Any] = {}
    for layer in (defaults, *layers):
        for name, raw in layer.items():
            if name not in known:
                raise UsageError(f"unknown parameter '{name}'; known: {', '.join(known)}")
            values[name] = _convert(name, raw, known[name][0], kinds[name])
    try:
        return cls(**values)
    except ValueError as e:  # cross-field checks in __post_init__
        raise UsageError(str(e)) from None


def check_duration(duration: float, timestep: float, max_steps: int) -> None:
    """Cross-field check shared by time-stepped scenarios (raises ValueError, reported as a usage error)."""
    if timestep > duration:
        raise ValueError(f"parameter 'timestep' must not exceed 'duration' ({duration} s); got {timestep}")
    if duration / timestep > max_steps:
        raise ValueError(
            f"duration / timestep must be at most {max_steps:.0e} steps; raise 'timestep' or lower 'duration'"
        )


def as_dict(obj: Any) -> dict[str, Any]:
    """Parameter values of a resolved object, in declaration order."""
    return {name: getattr(obj, name) for name in infos(type(obj))}


def units(cls: type) -> dict[str, str]:
    """Parameter name -> unit."""
    return {name: info.unit for name, (info, _) in infos(cls).items()}
