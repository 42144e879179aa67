"""hexabot-sim compare: metrics side by side with differences, overlays, and refusal of non-run folders."""

import json

import pytest

from hexabot_sim import compare
from hexabot_sim.__main__ import main

SHORT = ["--set", "duration=0.5", "--no-plots"]


@pytest.fixture(scope="module")
def two_runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("runs")
    for name, damping in (("soft", "0.01"), ("hard", "0.05")):
        assert main(["run", "pendulum", *SHORT, "--set", f"damping={damping}", "--out", str(root / name)]) == 0
    return root


@pytest.mark.slow
def test_compare_two_pendulum_runs(two_runs, tmp_path, capsys):
    capsys.readouterr()
    out = tmp_path / "cmp"
    assert main(["compare", str(two_runs / "soft"), str(two_runs / "hard"), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    lines = printed.splitlines()
    assert lines[0].split()[:3] == ["parameters", "(differing", "first)"]
    assert lines[1].startswith("* damping [N*m*s/rad]") and lines[1].split()[-2:] == ["0.01", "0.05"]
    assert lines[2].startswith("  mass")  # the same in both: after the differing ones, unmarked
    metric = next(line for line in lines if line.startswith("* final_theta_deg"))
    assert "%" in metric  # difference to the first run, absolute and relative
    record = json.loads((out / "compare.json").read_text())
    assert record["differing_params"] == ["damping"] and "final_theta_deg" in record["differing_metrics"]
    assert record["shared_columns"][:3] == ["t", "theta", "omega"]
    table = (out / "compare.csv").read_text().splitlines()
    assert table[0] == "kind,name,unit,differs,soft,hard,hard - soft"
    assert table[1].startswith("param,damping,N*m*s/rad,true,0.01,0.050000000000000003,")
    assert (out / "overlay.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert set(record["files"]) == {p.name for p in out.iterdir()}


@pytest.mark.parametrize(
    ("make", "fragment"),
    [
        (lambda d: d.mkdir(), "is not a run folder: it has no run.json"),
        (lambda d: (d.mkdir(), (d / "run.json").write_text("{")), "its run.json cannot be read"),
        (lambda d: (d.mkdir(), (d / "sweep.json").write_text("{}")), "is a sweep folder, not a run folder"),
        (lambda d: d.write_text("x"), "is not a run folder: not a folder"),
        (lambda d: None, "no such folder"),
    ],
)
def test_refuses_what_is_not_a_run_folder(two_runs, tmp_path, capsys, make, fragment):
    bad = tmp_path / "bad"
    make(bad)
    capsys.readouterr()
    assert main(["compare", str(two_runs / "soft"), str(bad), "--out", str(tmp_path / "cmp")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and fragment in err, err
    assert not (tmp_path / "cmp").exists()


def test_needs_two_different_runs(two_runs, capsys):
    assert main(["compare", str(two_runs / "soft")]) == 2
    assert "at least two run folders" in capsys.readouterr().err
    assert main(["compare", str(two_runs / "soft"), str(two_runs / "soft")]) == 2
    assert "is the same run folder" in capsys.readouterr().err


def test_a_table_parameter_reads_as_rows():
    """A walk's schedule (a list of rows in run.json) was written to compare.csv as Python reprs
    ("[0.0, 0.05, 0.0, 0.0, 'tripod', None, None],[...]"): rows now read "t vx ... ; t vx ...", a missing cell "-"."""
    rows = ((0.0, 0.05, 0.0, 0.0, "tripod", None, None), [2.0, 0.05, 0.0, 0.0, "ripple", None, None])
    assert compare._show(rows) == "0 0.05 0 0 tripod - -; 2 0.05 0 0 ripple - -"
    assert compare._show((0.1, 0.2)) == "0.1,0.2" and compare._show(()) == ""
