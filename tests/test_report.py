"""report.html: in every run folder, escaped, self-contained; opened in headless Chromium with nothing broken."""

import json
import os
import shutil
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

import hexabot_sim as hs
from hexabot_sim import registry, report

# The shortest runs that each scenario accepts.
SHORT: dict[str, dict] = {name: dict(s.smoke) for name, s in registry.SCENARIOS.items()}  # each scenario's short run


class _Page(HTMLParser):
    """Tags, links and text of a page."""

    def __init__(self) -> None:
        super().__init__()
        self.tags: list[str] = []
        self.links: list[str] = []
        self.text: list[str] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append(tag)
        self.links += [value for name, value in attrs if name in ("src", "href") and value is not None]

    def handle_data(self, data):
        self.text.append(data)


def parse(path: Path) -> _Page:
    page = _Page()
    page.feed(path.read_text())
    return page


def check_page(folder: Path) -> _Page:
    """What every report must be: self-contained, no script, every run file linked or shown, every value listed."""
    record = json.loads((folder / "run.json").read_text())
    page = parse(folder / "report.html")
    text = " ".join(page.text)
    assert "script" not in page.tags and "iframe" not in page.tags
    for link in page.links:
        assert "://" not in link and not link.startswith(("/", "//", "data:")), link
        assert (folder / link).is_file(), link
    assert set(record["files"]) - {"report.html"} <= set(page.links)
    assert sorted(p.name for p in folder.iterdir()) == sorted(record["files"])
    assert record["scenario"] in text and record["description"] in text
    for name, value in [*record["params"].items(), *record["metrics"].items()]:
        assert name in text and report.format_value(value) in text, name
    for name, unit in record["units"]["params"].items():
        assert unit in ("", "1") or unit in text, name
    assert (page.tags.count("img"), page.tags.count("video")) == (
        sum(name.endswith(".png") for name in record["files"]),
        int(record["video"]["written"]),
    )
    return page


@pytest.mark.slow
@pytest.mark.parametrize("scenario", list(registry.SCENARIOS))
def test_every_scenario_has_a_report(tmp_path, scenario):
    assert set(SHORT) == set(registry.SCENARIOS)
    folder = hs.run(scenario, **SHORT[scenario]).save(tmp_path / "run", plots=False)
    page = check_page(folder)
    names = set(page.links)
    assert ("grid.csv" if scenario == "leg-sweep" else "timeseries.csv") in names
    assert ("trajectory.npz" in names) == (scenario != "leg-sweep")


def test_all_text_is_escaped(tmp_path):
    evil = '<script>alert("x")</script> & <b>'
    record = {
        "scenario": evil,
        "description": evil,
        "params": {"p<1>": evil, "n": 1.5},
        "metrics": {"m&m": 2.0, "none": None, "nan": float("nan"), "list": [1.0, 2.5]},
        "units": {"params": {"p<1>": "<u>", "n": "m"}, "metrics": {"m&m": "<v>", "none": "s", "nan": "", "list": "m"}},
        "metric_docs": {"m&m": evil},
        "files": ["timeseries.csv", "run.json", 'a"b.png', "report.html"],
        "video": {"written": False, "reason": evil},
        "simulation": {"steps": 3, "simulated_time": 0.3},
        "versions": {"hexabot_sim": evil},
    }
    page = report.html_page(record, {"p<1>": evil}, ["m&m", "none"], tmp_path)
    assert "<script" not in page and "<b>" not in page and "<u>" not in page and "<v>" not in page
    assert "&lt;script&gt;" in page and "m&amp;m = 2 &lt;v&gt;; none = n/a" in page
    assert 'src="a&quot;b.png"' in page and "1, 2.5" in page


def test_a_robot_file_name_that_is_not_utf8_is_shown_not_a_crash(tmp_path):
    """robot=b'\\xff.toml' (a Linux file name that is not UTF-8) reaches the parameters as a lone surrogate: the run
    simulated, then writing report.html raised UnicodeEncodeError (an internal error, no run folder)."""
    robot = os.fsdecode(bytes(tmp_path) + b"/\xff.toml")
    shutil.copy(Path(hs.__file__).parent / "kinematics" / "arms" / "elbow.toml", robot)
    result = hs.run("arm-track", robot=robot, duration=0.01)
    folder = tmp_path / "run"
    result.save(folder, plots=False)
    assert "\\xff.toml" in (folder / "report.html").read_text(encoding="utf-8")


# --- in a real browser ---------------------------------------------------------------------------

# Injected by the TEST into a copy of the page (the report itself has no script): after the load
# event it lists every image and video and whether the browser could decode it.
CHECK_SCRIPT = """
window.addEventListener("load", () => {
  const images = Array.from(document.images).map((i) => ({src: i.getAttribute("src"),
    ok: i.complete && i.naturalWidth > 0, width: i.naturalWidth}));
  const videos = Array.from(document.querySelectorAll("video")).map((v) => new Promise((done) => {
    const report = (ok, why) => done({src: v.getAttribute("src"), ok: ok, why: why, width: v.videoWidth,
      height: v.videoHeight, duration: v.duration});
    if (v.readyState >= 2) { report(true, "ready"); return; }
    v.addEventListener("loadeddata", () => report(true, "loadeddata"));
    v.addEventListener("error", () => report(false, "error " + (v.error ? v.error.code : "?")));
    setTimeout(() => report(false, "timeout, readyState " + v.readyState), 10000);
  }));
  Promise.all(videos).then((vs) => {
    const pre = document.createElement("pre");
    pre.id = "hexabot-check";
    pre.textContent = JSON.stringify({images: images, videos: vs});
    document.body.appendChild(pre);
  });
});
"""


@pytest.fixture(scope="module")
def chromium() -> str:
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        path = shutil.which(name)
        if path:
            return path
    pytest.skip("headless Chromium not found (Debian: apt-get install chromium); the report's browser test needs it")


@pytest.fixture(scope="module")
def browser(chromium):
    """One headless Chromium for the module's pages, each opened in a new tab (tests/browser.py)."""
    from browser import Browser

    running = Browser(chromium)
    yield running
    running.close()


def browser_check(browser, folder: Path) -> dict:
    """Opens the page (with the check script injected into a copy next to it) and returns what loaded."""
    page = (folder / "report.html").read_text()
    probe = folder / "_browser_check.html"
    probe.write_text(page.replace("</body>", f"<script>{CHECK_SCRIPT}</script></body>"))
    try:
        with browser.tab(probe.as_uri()) as tab:
            body = tab.wait_for('document.getElementById("hexabot-check")?.textContent ?? null', timeout=30)
    finally:
        probe.unlink()
    return json.loads(body)


def screenshot(browser, folder: Path, width: int, height: int, out: Path) -> np.ndarray:
    with browser.tab((folder / "report.html").as_uri(), width, height) as tab:
        tab.screenshot(out)
    assert out.is_file()
    from PIL import Image

    image = np.asarray(Image.open(out).convert("RGB"))
    assert image.shape[:2] == (height, width)
    keep = os.environ.get("HEXABOT_SIM_SCREENSHOTS")  # a folder to keep the screenshots in, to look at them
    if keep:
        Path(keep).mkdir(parents=True, exist_ok=True)
        shutil.copy(out, Path(keep) / f"{folder.name}-{width}.png")
    return image


@pytest.fixture(scope="module")
def browser_runs(tmp_path_factory, gl_backend):
    root = tmp_path_factory.mktemp("reports")
    return {
        "pendulum": hs.run("pendulum", duration=2.0).save(root / "pendulum", video=True, size=(320, 240)),
        "hexabot-walk": hs.run("hexabot-walk", duration=1.6).save(root / "hexabot-walk", video=True, size=(320, 240)),
        "leg-sweep": hs.run("leg-sweep", **SHORT["leg-sweep"]).save(root / "leg-sweep"),
    }


@pytest.mark.slow
@pytest.mark.parametrize("name", ["pendulum", "hexabot-walk", "leg-sweep"])
def test_report_in_headless_chromium(browser_runs, browser, name, tmp_path):
    folder = browser_runs[name]
    check_page(folder)
    record = json.loads((folder / "run.json").read_text())
    loaded = browser_check(browser, folder)
    pngs = [f for f in record["files"] if f.endswith(".png")]
    assert [image["src"] for image in loaded["images"]] == pngs and len(pngs) >= 2
    assert all(image["ok"] for image in loaded["images"]), loaded["images"]
    if name == "leg-sweep":
        assert loaded["videos"] == []
    else:
        assert record["video"]["written"], record["video"]
        (video,) = loaded["videos"]
        assert video["ok"] and (video["width"], video["height"]) == (320, 240), video
        assert abs(video["duration"] - record["simulation"]["simulated_time"]) < 0.2

    # Laptop and phone: the page fills the width without sideways scrolling and the figures are drawn.
    for width, height in ((1200, 2400), (400, 2400)):
        image = screenshot(browser, folder, width, height, tmp_path / f"{width}.png")
        assert image.std() > 20, "blank page"
        right_edge = image[:, -8:].reshape(-1, 3)
        assert (right_edge.min(axis=1) > 200).mean() > 0.95, "something sticks out on the right"


def test_browser_check_sees_a_broken_image(browser_runs, browser, tmp_path):
    folder = tmp_path / "broken"
    shutil.copytree(browser_runs["leg-sweep"], folder)
    (folder / "sweep.png").write_bytes(b"not a png")
    loaded = browser_check(browser, folder)
    assert {image["src"]: image["ok"] for image in loaded["images"]} == {"sweep.png": False, "workspace.png": True}


def test_a_schedule_keeps_its_rows_and_a_long_value_wraps():
    """A schedule was flattened ("0, 0.05, 0, 0, tripod, n/a, n/a, 1, 0.1, ..."), and a long value (a schedule, an
    absolute robot path) kept on one line pushed the unit and meaning columns off a 1280 px page (found in Chromium)."""
    rows = [[0.0, 0.05, 0.0, 0.0, "tripod", None, None], [1.0, 0.1, 0.0, 0.0, "ripple", None, None]]
    assert report.format_value(rows) == "[0, 0.05, 0, 0, tripod, –, –]; [1, 0.1, 0, 0, ripple, –, –]"
    assert report.format_value([0.1, None]) == "0.1, n/a"  # a flat list as before
    html = report._table({"schedule": rows, "vx": 0.1}, {"vx": "m/s"}, {})
    assert '<td class="num long">[0, 0.05' in html and '<td class="num">0.1</td>' in html
