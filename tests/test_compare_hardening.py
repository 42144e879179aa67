"""Issue 17: compare reads damaged run folders as untrusted input, names odd folders safely, and shows relative
differences only where they mean something."""

import json
import os
import shutil
import subprocess
import sys
import warnings

import pytest
from helpers import cli

from hexabot_sim import compare
from hexabot_sim.__main__ import main


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("cmp")
    for name, damping in (("a", "0"), ("b", "0.01")):
        argv = ["run", "pendulum", "--set", "duration=0.05", "--set", f"damping={damping}", "--no-plots"]
        assert main([*argv, "--out", str(root / name)]) == 0
    return root


DAMAGE = {
    "binary csv": lambda f: (f / "timeseries.csv").write_bytes(bytes(range(256)) * 40),
    "latin-1 csv": lambda f: (f / "timeseries.csv").write_bytes("t,\xe9\n0,1\n".encode("latin-1")),
    "header-only csv": lambda f: (f / "timeseries.csv").write_text(
        (f / "timeseries.csv").read_text().split("\n")[0] + "\n"
    ),
    "empty csv": lambda f: (f / "timeseries.csv").write_bytes(b""),
    "ragged csv": lambda f: (f / "timeseries.csv").write_text((f / "timeseries.csv").read_text() + "1,2\n"),
    "duplicate header": lambda f: (f / "timeseries.csv").write_text("t,t\n0,1\n"),
    "huge run.json": lambda f: (f / "run.json").write_text('{"x": "' + "y" * (17 << 20) + '"}'),
    "latin-1 run.json": lambda f: (f / "run.json").write_bytes(b'{"scenario": "\xe9"}'),
    "fifo run.json": lambda f: ((f / "run.json").unlink(), os.mkfifo(f / "run.json")),
    "truncated csv": lambda f: (f / "timeseries.csv").write_text((f / "timeseries.csv").read_text()[:3000]),
}


@pytest.mark.parametrize("kind", sorted(DAMAGE))
def test_a_damaged_run_folder_is_one_line(runs, tmp_path, capsys, kind):
    broken = tmp_path / "broken"
    shutil.copytree(runs / "a", broken)
    DAMAGE[kind](broken)
    code, _, err = cli(capsys, "compare", str(broken), str(runs / "b"), "--out", str(tmp_path / "c"))
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1 and "internal error" not in err and "Traceback" not in err
    assert "broken" in err and "usecols" not in err  # numpy's advice named an option compare does not have
    assert not (tmp_path / "c").exists()


def test_the_default_compare_folder_is_never_made_inside_an_input(runs, tmp_path, monkeypatch, capsys):
    """From inside a run folder, `compare . ../b` wrote runs/compare-<stamp> into the input '.'."""
    inside = tmp_path / "a"
    shutil.copytree(runs / "a", inside)
    before = sorted(p.name for p in inside.iterdir())
    monkeypatch.chdir(inside)
    code, _, err = cli(capsys, "compare", ".", str(runs / "b"), "--no-plots")
    assert code == 2 and "lies inside the input '.'" in err and len(err.strip().splitlines()) == 1
    assert sorted(p.name for p in inside.iterdir()) == before


def test_labels_stay_distinct_when_a_folder_is_named_like_a_made_label(runs, tmp_path, capsys):
    """X/run, Y/run and a folder 'run#2' gave two 'run#2' columns."""
    for where in ("X/run", "Y/run", "run#2"):
        shutil.copytree(runs / "a", tmp_path / where)
    folders = [str(tmp_path / w) for w in ("X/run", "Y/run", "run#2")]
    code, out, _ = cli(capsys, "compare", *folders, "--no-plots", "--out", str(tmp_path / "c"))
    assert code == 0
    header = (tmp_path / "c" / "compare.csv").read_text().splitlines()[0].split(",")
    labels = header[4:7]
    assert len(set(labels)) == 3 and labels[2] == "run#2", header
    assert "not plotted (--no-plots)" in out and "overlaid" not in out  # nothing read, nothing overlaid


def test_many_runs_are_overlaid_without_a_legend_and_without_warnings(runs, tmp_path, capsys):
    """A legend of 60 runs or more squeezed the panels to nothing: matplotlib's layout warning reached stderr."""
    many = []
    for k in range(60):
        shutil.copytree(runs / ("a" if k % 2 else "b"), tmp_path / f"r{k}")
        many.append(str(tmp_path / f"r{k}"))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        code, _, err = cli(capsys, "compare", *many, "--out", str(tmp_path / "c"))
    assert code == 0 and err.strip() == "", err
    assert [str(w.message) for w in caught] == []


def test_relative_differences_only_against_a_reference_that_is_not_near_zero():
    row = compare.Row("metric", "x", "1", (1e-9, 0.0461, 2e-9))
    (d1, rel1), (_, rel2) = row.differences()
    assert rel1 is None and d1 == pytest.approx(0.0461)
    assert rel2 == pytest.approx(1.0)
    assert "%" not in compare._difference((d1, rel1), False)


@pytest.mark.slow
def test_folder_names_that_are_not_utf8_are_compared(runs, tmp_path):
    for name in (b"r\xff", b"q\xfe"):
        shutil.copytree(runs / "a", tmp_path / os.fsdecode(name))
    exe = [os.fsencode(sys.executable), b"-m", b"hexabot_sim"]
    proc = subprocess.run([*exe, b"compare", b"r\xff", b"q\xfe", b"--out", b"c\xfd"], cwd=tmp_path,
                          capture_output=True, env={**os.environ, "MUJOCO_GL": "egl"}, timeout=120)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    record = json.loads((tmp_path / os.fsdecode(b"c\xfd") / "compare.json").read_text())
    assert [r["label"] for r in record["runs"]] == ["r\\xff", "q\\xfe"]


def test_a_parameter_that_is_a_file_name_not_utf8_is_compared(runs, tmp_path, capsys):
    """A run with robot=$'\\xff.toml' records the name in run.json as the lone surrogate "\\udcff": compare's table
    and compare.csv raised UnicodeEncodeError on it (an internal error)."""
    odd = tmp_path / "odd"
    shutil.copytree(runs / "a", odd)
    record = json.loads((odd / "run.json").read_text())
    record["params"]["integrator"] = os.fsdecode(b"\xff.toml")
    (odd / "run.json").write_text(json.dumps(record))
    code, out, err = cli(capsys, "compare", str(runs / "a"), str(odd), "--out", str(tmp_path / "c"), "--no-plots")
    assert code == 0 and "internal error" not in err, err
    assert "\\xff.toml" in out and "\\xff.toml" in (tmp_path / "c" / "compare.csv").read_text()


@pytest.mark.parametrize("kind", ["metrics", "params"])
def test_an_integer_no_float_can_hold_in_run_json_is_not_a_bug(runs, tmp_path, capsys, kind):
    odd = tmp_path / "odd"
    shutil.copytree(runs / "a", odd)
    record = json.loads((odd / "run.json").read_text())
    name = next(iter(record[kind]))
    record[kind][name] = 10**400  # valid JSON; float() of it overflows
    (odd / "run.json").write_text(json.dumps(record))
    code, out, err = cli(capsys, "compare", str(runs / "a"), str(odd), "--out", str(tmp_path / "c"), "--no-plots")
    assert code == 0 and "internal error" not in err, err
    assert "differs" in out or kind == "params"


def test_a_difference_that_overflows_is_not_written_as_inf():
    row = compare.Row("metric", "x", "1", (-1e308, 1e308))
    assert row.differences() == [None]
    assert compare._difference(row.differences()[0], False) == "differs"


def test_a_large_csv_is_read_in_chunks_with_a_line_at_every_quarter(runs, tmp_path, capsys, monkeypatch):
    # a 2 GB CSV (what a run may write) took ~80 s to read in silence, all of it in memory
    import numpy as np

    monkeypatch.setattr(compare, "CHUNK_ROWS", 7)
    monkeypatch.setattr(compare, "MAX_POINTS", 10)
    monkeypatch.setattr(compare, "ANNOUNCE_BYTES", 1)
    run = compare.load(str(runs / "a"))
    whole = np.loadtxt(run.csv, delimiter=",", skiprows=1, ndmin=2)
    heard = []
    names, data = compare._read(run, heard.append)
    step = -(-len(whole) // 10)
    assert names[0] == "t" and np.array_equal(data, whole[::step]) and len(data) <= 10
    assert heard[0].startswith("compare: reading a/timeseries.csv (") and heard[1:] == [
        f"compare: reading a/timeseries.csv: {p} %" for p in (25, 50, 75)
    ]
    broken = tmp_path / "broken"
    shutil.copytree(runs / "a", broken)
    lines = (broken / "timeseries.csv").read_text().splitlines()
    lines[20] = lines[20].replace(",", ",x", 1)  # data row 19 (0-based), in the third chunk
    (broken / "timeseries.csv").write_text("\n".join(lines) + "\n")
    with pytest.raises(compare.UsageError, match="at row 19,"):
        compare._read(compare.load(str(broken)))
    code, _, err = cli(capsys, "compare", str(runs / "a"), str(runs / "b"), "--out", str(tmp_path / "c"))
    assert code == 0 and "compare: reading a/timeseries.csv: 75 %" in err


def test_control_characters_in_names_never_reach_the_terminal(runs, tmp_path, capsys):
    # ESC and CR in a folder name or a run.json name recoloured or overwrote the terminal; a newline split the line
    odd = tmp_path / "esc\x1b[31mRED"
    shutil.copytree(runs / "b", odd)
    record = json.loads((odd / "run.json").read_text())
    record["metrics"]["clear\x1b[2J\rx"] = 1.0
    (odd / "run.json").write_text(json.dumps(record))
    out_dir = tmp_path / "o\ru\x9bt"
    code, out, err = cli(capsys, "compare", str(runs / "a"), str(odd), "--out", str(out_dir), "--no-plots")
    assert code == 0, err
    assert not any(c in out + err for c in "\x1b\r\x9b") and "esc\\x1b[31mRED" in out and "clear\\x1b[2J\\x0dx" in out
    code, _, err = cli(capsys, "compare", str(runs / "a"), str(tmp_path / "no\nsuch\x1b"))
    assert code == 2 and err.count("\n") == 1 and "\x1b" not in err, err
