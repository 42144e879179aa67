"""The README and the pages in docs/: every relative link and image resolves, every #anchor names a
heading of its target page (GitHub's slugs), the README stays short, and every page can be reached."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path
from urllib.parse import unquote

import pytest

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
README = ROOT / "README.md"
README_MAX_LINES = 260

FENCE = re.compile(r"^\s*(```|~~~)")
HEADING = re.compile(r"^ {0,3}(#{1,6})\s+(.*?)\s*#*\s*$")
INLINE_CODE = re.compile(r"(`+)(.+?)\1")
# [text](target) and ![alt](target); the text may hold one level of brackets (e.g. `[`x`](y)` or an image).
LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\[\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
HTML_SRC = re.compile(r"<(?:img|a)\s[^>]*?(?:src|href)=\"([^\"]+)\"", re.IGNORECASE)


def pages() -> list[Path]:
    return [README, *sorted(DOCS.glob("*.md"))]


def prose_lines(text: str) -> list[tuple[int, str]]:
    """(line number, line) outside fenced code blocks."""
    out, fence = [], False
    for number, line in enumerate(text.splitlines(), 1):
        if FENCE.match(line):
            fence = not fence
            continue
        if not fence:
            out.append((number, line))
    return out


def slug(heading: str) -> str:
    """GitHub's anchor for a heading: its text without markup, lower-case, punctuation other than '-'
    and '_' dropped, spaces to '-'."""
    text = INLINE_CODE.sub(lambda m: m.group(2), heading)
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", text)  # a link or image keeps its text
    text = re.sub(r"<[^>]+>", "", text)  # inline HTML
    text = text.lower()
    text = re.sub(r"[^\w\- ]", "", text)  # \w: letters, digits and '_' of any script
    return text.replace(" ", "-")


def anchors(path: Path) -> set[str]:
    """Every anchor of a page: heading slugs, the n-th repeat of a slug suffixed -1, -2, ..."""
    seen: dict[str, int] = {}
    out = set()
    for _, line in prose_lines(path.read_text(encoding="utf-8")):
        m = HEADING.match(line)
        if not m:
            continue
        base = slug(m.group(2))
        n = seen.get(base, 0)
        seen[base] = n + 1
        out.add(base if n == 0 else f"{base}-{n}")
    return out


def links(path: Path) -> list[tuple[int, str]]:
    """(line number, target) of every Markdown link and image and every HTML src/href, outside code."""
    out = []
    for number, line in prose_lines(path.read_text(encoding="utf-8")):
        line = INLINE_CODE.sub("", line)
        out += [(number, m.group(1)) for m in LINK.finditer(line)]
        out += [(number, m.group(1)) for m in HTML_SRC.finditer(line)]
    return out


def is_external(target: str) -> bool:
    return bool(re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", target)) or target.startswith("//")


def broken_links(path: Path, root: Path = ROOT) -> list[str]:
    """What is wrong with the page's relative links: a missing file, or an anchor no heading has."""
    problems = []
    for number, target in links(path):
        if is_external(target):
            continue
        file_part, _, anchor = target.partition("#")
        dest = (path.parent / unquote(file_part)).resolve() if file_part else path
        where = f"{path.relative_to(root)}:{number}: {target}"
        if not dest.exists():
            problems.append(f"{where}: no such file")
        elif anchor and (dest.suffix != ".md" or unquote(anchor) not in anchors(dest)):
            problems.append(f"{where}: no heading with anchor '#{anchor}' in {dest.relative_to(root)}")
    return problems


@pytest.mark.parametrize("page", pages(), ids=lambda p: str(p.relative_to(ROOT)))
def test_every_relative_link_image_and_anchor_resolves(page):
    assert broken_links(page) == []


def test_the_readme_is_short():
    lines = len(README.read_text(encoding="utf-8").splitlines())
    assert lines <= README_MAX_LINES, f"README.md has {lines} lines; the manual belongs in docs/"


def test_every_docs_page_is_linked_from_the_readme_or_the_index():
    linked = set()
    for page in (README, DOCS / "index.md"):
        for _, target in links(page):
            if not is_external(target) and target.partition("#")[0]:
                linked.add((page.parent / unquote(target.partition("#")[0])).resolve())
    missing = [p.name for p in sorted(DOCS.glob("*.md")) if p.name != "index.md" and p.resolve() not in linked]
    assert missing == []
    assert (DOCS / "index.md").resolve() in linked


def test_the_readme_keeps_the_two_command_blocks_ci_runs():
    """The two install-and-run lines are a contract (.ci/run runs the second one)."""
    text = README.read_text(encoding="utf-8")
    assert (
        "**Install and run the main job** (fresh machine, Python ≥ 3.11):\n\n```bash\n"
        "python3 -m venv .venv && . .venv/bin/activate && pip install . && hexabot-sim run pendulum --video\n```"
    ) in text
    assert (
        "**Install and run the tests:**\n\n```bash\n"
        'python3 -m venv .venv && . .venv/bin/activate && pip install ".[test]" && pytest\n```'
    ) in text
    assert 'pip install ".[test]" && pytest' in (ROOT / ".ci" / "run").read_text(encoding="utf-8")


def test_the_sdist_ships_the_docs():
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    include = pyproject["tool"]["hatch"]["build"]["targets"]["sdist"]["include"]
    assert {"docs", "README.md"} <= set(include)


@pytest.mark.parametrize(
    ("heading", "expected"),
    [
        ("Video and OpenGL", "video-and-opengl"),
        ("`hexabot-sim compare RUN_DIR RUN_DIR ...`", "hexabot-sim-compare-run_dir-run_dir-"),
        ("Benchmark (`python scripts/bench.py`, line `sweep`)", "benchmark-python-scriptsbenchpy-line-sweep"),
        ("Report 004's pinv note", "report-004s-pinv-note"),
        ("1 cm rough ground, every seed", "1-cm-rough-ground-every-seed"),
        (
            'The walking Hexabot (report 000: "a robot that walks using six legs")',
            "the-walking-hexabot-report-000-a-robot-that-walks-using-six-legs",
        ),
    ],
)
def test_slug_follows_github(heading, expected):
    assert slug(heading) == expected


def test_a_broken_link_or_anchor_is_caught(tmp_path):
    (tmp_path / "b.md").write_text("# Target page\n\n## A section\n")
    page = tmp_path / "a.md"
    page.write_text(
        "# A\n\n[ok](b.md#a-section) [ok](#a) ![img](missing.png) [gone](nope.md) [bad](b.md#no-such)\n"
        "```text\n[in code](ignored.md)\n```\n`[inline](ignored.md)` [web](https://example.org/x.md)\n"
    )
    problems = broken_links(page, root=tmp_path)
    assert len(problems) == 3, problems
    assert "missing.png: no such file" in problems[0]
    assert "nope.md: no such file" in problems[1]
    assert "'#no-such'" in problems[2]
