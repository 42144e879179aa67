"""The quadbot's scenarios with robot=FILE: a user's four-legged robot file walks in the quadbot's scene with its
gaits (walking/robot_choice.py, shared with hexabot-walk's six-legged files); other files are refused in one line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from helpers import cli

import hexabot_sim as hs
from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics import legged_file
from hexabot_sim.robots import quadbot

QUADBOT_FILE = Path(quadbot.__file__).with_name("quadbot.toml")
HEXAPOD_FILE = Path(__file__).resolve().parents[3] / "examples" / "my_hexapod.toml"


def _variant(tmp_path: Path, name: str, *changes: tuple[str, str]) -> Path:
    text = QUADBOT_FILE.read_text().replace('name = "quadbot"', f'name = "{name}"', 1)
    for old, new in changes:
        assert old in text
        text = text.replace(old, new, 1)
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return path


@pytest.mark.slow
def test_a_copy_of_the_quadbots_file_trots_exactly_as_the_quadbot(tmp_path: Path) -> None:
    copy = _variant(tmp_path, "myquad")
    mine, builtin = hs.run("quadbot-trot", robot=str(copy), duration=1.6), hs.run("quadbot-trot", duration=1.6)
    assert mine.params["robot"] == str(copy) and mine.params["stand_height"] == 0.07
    assert mine.columns.keys() == builtin.columns.keys()
    for name, values in builtin.columns.items():
        np.testing.assert_array_equal(mine.columns[name], values, err_msg=name)


@pytest.mark.slow
@pytest.mark.parametrize(("scenario", "tolerance"), [("quadbot-walk", 0.01), ("quadbot-trot", 0.03)])
def test_a_longer_quadruped_of_its_own_walks_at_the_commanded_speed(
    tmp_path: Path, scenario: str, tolerance: float
) -> None:
    """Hips 0.26 m apart on a 0.30 m plate of 0.8 kg (the quadbot's: 0.20, 0.26, 1.0 kg), in its generated model.
    Measured: the crawl -0.12 % (the quadbot's -0.10 %), the trot -1.7 % (-1.3 %) over 4 s."""
    hips = ("[[0.10, 0.06], [-0.10, 0.06]]", "[[0.13, 0.06], [-0.13, 0.06]]")
    path = _variant(tmp_path, "longquad", hips, ("size = [0.26, 0.16, 0.03]", "size = [0.30, 0.16, 0.03]"),
                    ("mass = 1.0 ", "mass = 0.8 "))  # fmt: skip
    result = hs.run(scenario, robot=str(path), duration=4.0)
    model = result.raw.model
    layout = legged_file.read(path).layout
    assert model.body_subtreemass[model.body("torso").id] == pytest.approx(layout.total_mass, rel=1e-12)
    assert model.site("lf_hip").pos.tolist() == [0.13, 0.06, 0.0] and model.site("rr_hip").pos.tolist() == [
        -0.13, -0.06, 0.0
    ]  # fmt: skip
    assert result.metrics["fell"].value is False
    assert abs(result.metrics["vx_error"].value) < tolerance


def test_other_leg_counts_and_a_crawl_that_cannot_stand_are_refused_before_the_walk(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A six-legged file in a quadbot scenario and a four-legged one in a hexabot one: one line naming the counts.
    Rear hips narrower than the front ones (0.05 against 0.09 m): the crawl's three feet lr, rf, rr leave the
    body's centre outside them (the lr-rf diagonal crosses x = 0 at y = -20 mm: a crawl without a body shift would
    tip), refused; the trot of the same file walks. A file whose 'names' pair the trot's legs front and rear (lf, lr,
    rr, rf: a bound, -94 % of the speed, fell false) is refused naming the pair."""
    trapezoid = _variant(tmp_path, "trapezoid", ("[[0.10, 0.06], [-0.10, 0.06]]", "[[0.10, 0.09], [-0.10, 0.05]]"),
                         ("size = [0.26, 0.16, 0.03]", "size = [0.26, 0.20, 0.03]"))  # fmt: skip
    bound = _variant(tmp_path, "bound", ('rows = ["f", "r"]', 'names = ["lf", "lr", "rr", "rf"]'),
                     ("[[0.10, 0.06], [-0.10, 0.06]]", "[[0.10, 0.06], [-0.10, 0.06], [-0.10, -0.06], [0.10, -0.06]]"),
                     ("[45.0, 135.0]", "[45.0, 135.0, -135.0, -45.0]"))  # fmt: skip
    line = _variant(tmp_path, "line", ("[[0.10, 0.06], [-0.10, 0.06]]", "[[0.0, 0.06], [0.0, 0.06]]"),
                    ("[45.0, 135.0]", "[90.0, 90.0]"))  # fmt: skip
    cases = [
        ("quadbot-trot", HEXAPOD_FILE, "6 legs; the quadbot's scenarios walk 4-legged robots (their gaits crawl, "
         "trot are for 4"),  # it named quadbot-walk
        ("hexabot-turn", trapezoid, "4 legs; the hexabot's scenarios walk 6-legged robots (their gaits tripod, "
         "ripple, wave"),
        ("quadbot-walk", trapezoid, "the crawl gait stands on lr, rf, rr at once, and their feet do not surround the "
         "body's centre (it is at least 15 mm outside them at the neutral stance)"),
        # Feet in one line through the centre: it read "at least inf mm outside them" (found by fuzzing).
        ("quadbot-walk", line, "the crawl gait stands on lf, lr, rf at once, and their feet do not surround the "
         "body's centre (they stand in a line at the neutral stance)"),
        ("quadbot-trot", bound, "the trot gait stands on lf and rf at once, and their feet are not on opposite sides "
         "of the body's centre (77 deg apart seen from it at the neutral stance, at least 120 needed)"),
    ]  # fmt: skip
    for scenario, path, message in cases:
        out = tmp_path / "out"
        code, stdout, err = cli(capsys, "run", scenario, "--set", f"robot={path}", "--out", str(out))
        assert code == 2 and stdout == "" and err.count("\n") == 1 and not out.exists(), err
        assert message in err, err
    assert hs.run("quadbot-trot", robot=str(trapezoid), duration=1.6).metrics["fell"].value is False
    # With force control and a level body its crawl's centre, outside the feet down, is said to be outside them (it
    # read "comes within 0.0 mm of their edge").
    with pytest.raises(UsageError, match=r"the crawl gait of trapezoid leaves its centre 1\d\.\d mm outside them"):
        hs.run("quadbot-walk", robot=str(trapezoid), load_sharing="force", level_body="on")
