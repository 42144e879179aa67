"""Finds the MJCF models (source tree or installed wheel) and edits them before compiling."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Iterable, Mapping
from pathlib import Path

from hexabot_sim.errors import InstallError, UsageError

_PKG_DIR = Path(__file__).resolve().parent
# Installed wheel: models are packaged as hexabot_sim/_models; source tree: top-level models/.
_CANDIDATES = (_PKG_DIR / "_models", _PKG_DIR.parent / "models")


def models_dir() -> Path:
    """Directory that holds the MJCF files."""
    for candidate in _CANDIDATES:
        if candidate.is_dir() and any(candidate.glob("*.xml")):
            return candidate
    raise InstallError(
        f"the package's MJCF models are missing (looked in {', '.join(map(str, _CANDIDATES))}): the installation is "
        "incomplete; reinstall hexabot-sim"
    )


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


# A run folder's model.xml is untrusted input when it is replayed (`view RUN_DIR`): MuJoCo would follow its <include>s
# and file attributes anywhere on disk (or block on a FIFO, or read /dev/zero), and a few lines (<replicate count>,
# a 60000 px texture) would take it minutes or all memory to compile. The replay compiles only what a run writes:
# one self-contained MJCF file of the elements the committed models and the terrain use, of bounded size.
RUN_MODEL_LIMIT = 64 << 20  # [B] model.xml read at most (the largest a run writes, 2e6 heightfield points, ~16 MB)
RUN_MODEL_ELEMENTS = 20_000  # runs write ~200
RUN_MODEL_DEPTH = 32  # runs write 7
RUN_MODEL_TAGS = frozenset(
    "accelerometer actuator asset body camera compiler default framequat freejoint geom global gyro headlight hfield "
    "inertial joint key keyframe light material motor mujoco option position sensor site statistic texture touch "
    "velocity visual worldbody".split()
)
_FILE_ATTRIBUTES = frozenset(
    "file fileback filedown filefront fileleft fileright fileup meshdir texturedir assetdir content_type".split()
)
# (tag, the attributes whose product is bounded, the bound on its sum over the file): textures, heightfields or an
# offscreen buffer that big are a memory bomb (runs write ~0.4 Mpx of textures and one heightfield).
_PIXEL_LIMITS = (
    ("texture", ("width", "height"), 1 << 24),
    ("global", ("offwidth", "offheight"), 1 << 24),
    ("hfield", ("nrow", "ncol"), None),  # None: the terrain's own HFIELD_MAX_POINTS
)


def read_run_model(path: Path) -> str:
    """The MJCF text of a run folder's model.xml, checked to be what a run writes (UsageError in one line if not).

    Compile it with `mujoco.MjModel.from_xml_string`: it references no other file.
    """
    from hexabot_sim.params import read_bounded
    from hexabot_sim.terrain.heightfield import MAX_POINTS as HFIELD_MAX_POINTS

    data = read_bounded(path, "model file", RUN_MODEL_LIMIT, "a run's model.xml is at most a few MB")

    def bad(why: str) -> UsageError:
        return UsageError(f"cannot replay {path}: {why}; a run of hexabot-sim writes one self-contained MJCF model")

    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise bad("it is not UTF-8 text") from None
    if "<!DOCTYPE" in text or "<!ENTITY" in text:
        raise bad("it has a document type declaration (entities)")
    try:
        root = ET.fromstring(text)
    except ET.ParseError as e:
        raise bad(f"it is not well-formed XML ({e})") from None
    if root.tag != "mujoco":
        raise bad(f"its root element is <{root.tag}>, not <mujoco>")
    count, totals = 0, dict[str, int]()
    stack = [(root, 1)]
    while stack:
        element, depth = stack.pop()
        count += 1
        if count > RUN_MODEL_ELEMENTS or depth > RUN_MODEL_DEPTH:
            raise bad(f"it has more than {RUN_MODEL_ELEMENTS} elements or nests deeper than {RUN_MODEL_DEPTH}")
        if not isinstance(element.tag, str) or element.tag not in RUN_MODEL_TAGS:
            allowed = ", ".join(sorted(RUN_MODEL_TAGS))
            raise bad(f"it has an element <{element.tag}> (allowed: {allowed})")
        files = sorted(_FILE_ATTRIBUTES.intersection(element.attrib))
        if files:
            raise bad(f"<{element.tag}> names a file ({files[0]}=...)")
        for tag, names, limit in _PIXEL_LIMITS:
            if element.tag == tag and any(name in element.attrib for name in names):
                bound = HFIELD_MAX_POINTS if limit is None else limit
                try:  # one side given: count it as square
                    sides = [abs(int(element.attrib[n])) for n in names if n in element.attrib]
                except ValueError:
                    raise bad(f"<{tag}> {names[0]}/{names[1]} are not integers") from None
                totals[tag] = totals.get(tag, 0) + sides[0] * sides[-1]
                if totals[tag] > bound:
                    raise bad(
                        f"its <{tag}> elements have {names[0]} x {names[1]} = {totals[tag]} in all, more than {bound}"
                    )
        stack.extend((child, depth + 1) for child in element)
    return text
