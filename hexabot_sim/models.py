"""Finds the MJCF models (source tree or installed wheel) and edits them before compiling."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Iterable, Mapping
from pathlib import Path

from hexabot_sim.errors import UsageError

_PKG_DIR = Path(__file__).resolve().parent
# Installed wheel: models are packaged as hexabot_sim/_models; source tree: top-level models/.
_CANDIDATES = (_PKG_DIR / "_models", _PKG_DIR.parent / "models")


def models_dir() -> Path:
    """Directory that holds the MJCF files."""
    for candidate in _CANDIDATES:
        if candidate.is_dir() and any(candidate.glob("*.xml")):
            return candidate
    raise FileNotFoundError(f"MJCF models not found in any of: {', '.join(map(str, _CANDIDATES))}")


def model_path(name: str) -> Path:
    """Path of `models/<name>.xml`."""
    path = models_dir() / f"{name}.xml"
    if not path.is_file():
        known = sorted(p.stem for p in models_dir().glob("*.xml"))
        raise UsageError(f"unknown model '{name}'; known: {', '.join(known)}")
    return path


def load_tree(name: str, replace: Mapping[str, str] | None = None) -> ET.Element:
    """Parses `models/<name>.xml` with every `<include file=...>` inlined: one self-contained MJCF.

    Args:
        name: Model file stem in models/.
        replace: Included file name -> MJCF text to inline instead of that file (e.g. a robot
            regenerated with other link lengths inside its committed scene).
    """
    return _load(model_path(name), replace or {})


def _load(path: Path, replace: Mapping[str, str]) -> ET.Element:
    root = ET.parse(path).getroot()
    _inline_includes(root, path.parent, replace)
    return root


def _inline_includes(element: ET.Element, base: Path, replace: Mapping[str, str]) -> None:
    for index, child in enumerate(list(element)):
        if child.tag == "include":
            name = child.attrib["file"]
            if name in replace:
                included = ET.fromstring(replace[name])
                _inline_includes(included, base, replace)
            else:
                included = _load(base / name, replace)
            element.remove(child)
            for offset, grandchild in enumerate(included):
                element.insert(index + offset, grandchild)
        else:
            _inline_includes(child, base, replace)


def fmt(value: float | Iterable[float]) -> str:
    """Formats numbers for MJCF with full double precision (repr round-trips exactly)."""
    if isinstance(value, (int, float)):
        return repr(float(value))
    return " ".join(repr(float(v)) for v in value)


def find(root: ET.Element, tag: str, name: str | None = None) -> ET.Element:
    """The unique element `<tag name=...>` (or the unique `<tag>` when name is None)."""
    matches = [e for e in root.iter(tag) if name is None or e.get("name") == name]
    if len(matches) != 1:
        raise KeyError(f"expected exactly one <{tag}{f' name={name!r}' if name else ''}>, found {len(matches)}")
    return matches[0]


def remove(root: ET.Element, tag: str, name: str) -> None:
    """Removes the element `<tag name=...>` from the tree."""
    for parent in root.iter():
        for child in list(parent):
            if child.tag == tag and child.get("name") == name:
                parent.remove(child)
                return
    raise KeyError(f"no <{tag} name={name!r}>")


def to_xml(root: ET.Element) -> str:
    """Serialises the (edited) tree: the exact text that is compiled and saved as model.xml."""
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="unicode") + "\n"
