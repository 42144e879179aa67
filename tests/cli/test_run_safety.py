"""Run folders never destroy or lose anything: --out checks, concurrency, full disk, stdout."""

import errno
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest
from helpers import cli, one_line_error, staging_left

from hexabot_sim import folders, output, registry
from hexabot_sim.__main__ import main
from hexabot_sim.errors import OutputError, UsageError

FAST = ["--set", "duration=0.05", "--no-plots"]


@pytest.mark.parametrize("target", [".", "..", "a/b/..", "a/.", "./", "sub/../.."])
def test_out_that_normalises_elsewhere_is_refused_even_with_force(tmp_path, monkeypatch, capsys, target):
    (tmp_path / "a" / "b").mkdir(parents=True)
    (tmp_path / "a" / "keep.txt").write_text("mine")
    (tmp_path / "thesis.tex").write_text("mine")
    monkeypatch.chdir(tmp_path)
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", target, "--force")
    assert code == 2
    assert "--out" in one_line_error(err) or "folder" in err
    assert (tmp_path / "a" / "keep.txt").read_text() == "mine"
    assert (tmp_path / "thesis.tex").read_text() == "mine"


def test_out_that_is_the_working_folder_or_its_parent_is_refused(tmp_path, monkeypatch, capsys):
    work = tmp_path / "project" / "here"
    work.mkdir(parents=True)
    (work / "notes.txt").write_text("mine")
    monkeypatch.chdir(work)
    for target in (str(work), str(tmp_path / "project"), "../here", "../../project"):
        code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", target, "--force")
        assert code == 2, target
        assert "working folder" in one_line_error(err)
    assert (work / "notes.txt").read_text() == "mine"


def test_symlinked_out_is_refused(tmp_path, capsys):
    real = tmp_path / "real"
    real.mkdir()
    (real / "data.txt").write_text("mine")
    (tmp_path / "link").symlink_to(real)
    (tmp_path / "dangling").symlink_to(tmp_path / "nowhere")
    for name in ("link", "dangling"):
        code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(tmp_path / name), "--force")
        assert code == 2
        assert "symbolic link" in one_line_error(err)
    assert (real / "data.txt").read_text() == "mine"
    assert not (tmp_path / "nowhere").exists()


def test_non_empty_out_needs_force_and_force_replaces_it(tmp_path, capsys):
    out = tmp_path / "run"
    out.mkdir()
    (out / "old.txt").write_text("old")
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(out))
    assert code == 2 and "not empty" in one_line_error(err)
    assert (out / "old.txt").exists()
    code, _, _ = cli(capsys, "run", "pendulum", *FAST, "--out", str(out), "--force")
    assert code == 0
    assert not (out / "old.txt").exists() and (out / "run.json").exists()
    assert staging_left(tmp_path) == []


def test_file_created_in_out_during_the_run_is_never_deleted(tmp_path, monkeypatch, capsys):
    """`run ... --out out &` then the user writes out/thesis.tex: the run must not delete it."""
    out = tmp_path / "out"
    scenario = registry.get("pendulum")
    real_runner = scenario.runner

    def runner_meanwhile_user_writes(*args, **kwargs):
        out.mkdir()
        (out / "thesis.tex").write_text("three years of work")
        return real_runner(*args, **kwargs)

    monkeypatch.setattr(type(scenario), "runner", property(lambda self: runner_meanwhile_user_writes))
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(out))
    assert code == 1
    assert "filled by someone else" in one_line_error(err)
    assert (out / "thesis.tex").read_text() == "three years of work"
    assert sorted(p.name for p in out.iterdir()) == ["thesis.tex"]
    assert staging_left(tmp_path) == []


def test_two_runs_publishing_to_the_same_out_never_replace_each_other(tmp_path):
    out = tmp_path / "same"
    with pytest.raises(OutputError, match="filled by someone else"):
        with folders.run_folder(out) as first:
            (first.path / "run.json").write_text("first")
            with folders.run_folder(out) as second:
                (second.path / "run.json").write_text("second")
    assert (out / "run.json").read_text() == "second"  # the one that finished first keeps its folder
    assert staging_left(tmp_path) == []


def test_runs_in_the_same_second_get_their_own_folders(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(folders, "default_out", lambda scenario, root=Path("runs"): root / f"{scenario}-STAMP")
    for _ in range(3):
        code, out, _ = cli(capsys, "run", "pendulum", *FAST)
        assert code == 0
    assert sorted(p.name for p in (tmp_path / "runs").iterdir()) == [
        "pendulum-STAMP",
        "pendulum-STAMP-2",
        "pendulum-STAMP-3",
    ]
    assert "pendulum-STAMP-3" in out  # the summary names the folder the run really went to


@pytest.mark.slow
def test_concurrent_default_runs_all_survive(tmp_path):
    """Four processes started together, no --out: four complete, distinct run folders."""
    procs = [
        subprocess.Popen(
            [sys.executable, "-m", "hexabot_sim", "run", "pendulum", *FAST],
            cwd=tmp_path,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
        )
        for _ in range(4)
    ]
    for proc in procs:
        _, err = proc.communicate(timeout=120)
        assert proc.returncode == 0, err
    folders = list((tmp_path / "runs").iterdir())
    assert len(folders) == 4
    assert all((folder / "run.json").exists() for folder in folders)
    assert staging_left(tmp_path) == []


def test_over_long_names(tmp_path, capsys):
    ok = tmp_path / ("r" * 255)  # the longest valid name: the staging name must not push it over
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(ok))
    assert code == 0, err
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(tmp_path / ("r" * 256)))
    assert code == 2 and "255" in one_line_error(err)


def test_unwritable_parent(capsys):
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", "/proc/hexabot-sim-test/run")
    assert code == 2
    assert "cannot be written" in one_line_error(err)


@pytest.mark.parametrize("force", [False, True])
def test_a_read_only_out_is_refused_before_the_run_and_kept(tmp_path, capsys, force):
    """A run replaces --out by a rename, which root may do over a read-only folder: an empty read-only folder
    became a writable one holding the run (found by fuzzing). Refused up front, the folder and its mode kept."""
    out = tmp_path / "kept"
    out.mkdir()
    if force:
        (out / "mine.txt").write_text("mine")
    out.chmod(0o555)
    try:
        code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(out), *["--force"] * force)
        assert code == 2 and one_line_error(err).endswith("is read-only; make it writable or choose another --out")
        assert out.stat().st_mode & 0o777 == 0o555
        assert [p.name for p in out.iterdir()] == (["mine.txt"] if force else [])
        assert sorted(p.name for p in tmp_path.iterdir()) == ["kept"]
    finally:
        out.chmod(0o755)


def test_a_read_only_parent_is_refused_before_the_run(tmp_path, capsys):
    """Root may create a folder in a read-only one: the mode says not to (a non-root user is refused by the OS)."""
    parent = tmp_path / "shelf"
    parent.mkdir()
    parent.chmod(0o555)
    try:
        code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(parent / "new" / "run"))
        assert code == 2 and "cannot be written: no write permission in" in one_line_error(err)
        assert list(parent.iterdir()) == []
    finally:
        parent.chmod(0o755)


def test_an_immutable_out_is_refused_before_the_run(tmp_path, capsys):
    """An immutable (chattr +i) empty --out was found unwritable only after the run had been computed."""
    out = tmp_path / "frozen"
    out.mkdir()
    if shutil.which("chattr") is None or subprocess.run(["chattr", "+i", str(out)], capture_output=True).returncode:
        pytest.skip("chattr +i is not available here (needs root and a file system with the flag)")
    try:
        code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(out))
        assert code == 2 and "is read-only" in one_line_error(err)
    finally:
        subprocess.run(["chattr", "-i", str(out)], check=True)
    assert list(out.iterdir()) == []


def test_full_disk_leaves_nothing_and_removes_created_parents(tmp_path, monkeypatch, capsys):
    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(output, "write_csv", full)
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(tmp_path / "deep" / "nested" / "run"))
    assert code == 1
    assert "No space left on device" in one_line_error(err)
    assert list(tmp_path.iterdir()) == []  # deep/ and deep/nested/ were ours: gone again
    # Removing them is no move by someone else (it said "the folder ... was moved or removed during the run")
    assert "moved" not in err and "writing the run folder failed" in err


def test_default_runs_folder_removed_when_the_run_fails(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    code, _, err = cli(capsys, "run", "pendulum", "--set", "stiffness=1e4", "--set", "timestep=0.05", "--no-plots")
    assert code == 1, err
    assert "diverged" in one_line_error(err)
    assert list(tmp_path.iterdir()) == []


def test_existing_parents_are_kept_on_failure(tmp_path, monkeypatch, capsys):
    (tmp_path / "runs").mkdir()
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(output, "write_csv", lambda *a: (_ for _ in ()).throw(OSError(errno.EIO, "I/O error")))
    code, _, _ = cli(capsys, "run", "pendulum", *FAST)
    assert code == 1
    assert (tmp_path / "runs").is_dir() and list((tmp_path / "runs").iterdir()) == []


def test_check_out_names_what_is_wrong(tmp_path):
    (tmp_path / "file").write_text("x")
    with pytest.raises(UsageError, match="not a folder"):
        folders.check_out(tmp_path / "file")
    with pytest.raises(UsageError, match="not a folder"):
        folders.check_out(tmp_path / "file" / "run")


def test_unexpected_exception_is_one_line_and_debug_shows_it(tmp_path, monkeypatch, capsys):
    scenario = registry.get("pendulum")

    def broken(*args, **kwargs):
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr(type(scenario), "runner", property(lambda self: broken))
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(tmp_path / "r"))
    assert code == 1
    line = one_line_error(err)
    assert "internal error" in line and "ZeroDivisionError" in line and "--debug" in line
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(ZeroDivisionError):
        main(["run", "pendulum", *FAST, "--out", str(tmp_path / "r"), "--debug"])
    monkeypatch.setenv("HEXABOT_SIM_DEBUG", "1")
    with pytest.raises(ZeroDivisionError):
        main(["run", "pendulum", *FAST, "--out", str(tmp_path / "r")])


def test_force_never_replaces_home_or_its_parents(tmp_path, monkeypatch, capsys):
    home = tmp_path / "home" / "user"
    (home / "docs").mkdir(parents=True)
    (home / "docs" / "thesis.tex").write_text("mine")
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    monkeypatch.setenv("HOME", str(home))
    for target in (home, home.parent):
        code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(target), "--force")
        assert code == 2 and "home folder" in one_line_error(err)
    assert (home / "docs" / "thesis.tex").read_text() == "mine"


def test_out_inside_another_runs_staging_folder_is_refused(tmp_path, capsys):
    staging = tmp_path / f"{folders.STAGING_PREFIX}123-abcd{folders.STAGING_SUFFIX}"
    staging.mkdir()
    for target in (staging, staging / "b"):
        code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(target), "--force")
        assert code == 2 and "staging folder" in one_line_error(err)


def test_force_leaves_a_folder_that_changed_during_the_run_alone(tmp_path, monkeypatch, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "old.txt").write_text("old")
    scenario = registry.get("pendulum")
    real_runner = scenario.runner

    def runner_meanwhile_user_writes(*args, **kwargs):
        (out / "thesis.tex").write_text("written during the run")
        return real_runner(*args, **kwargs)

    monkeypatch.setattr(type(scenario), "runner", property(lambda self: runner_meanwhile_user_writes))
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(out), "--force")
    assert code == 1 and "changed during the run" in one_line_error(err)
    assert sorted(p.name for p in out.iterdir()) == ["old.txt", "thesis.tex"]
    assert staging_left(tmp_path) == []


def test_parent_moved_during_the_run_leaves_nothing(tmp_path, monkeypatch, capsys):
    parent = tmp_path / "pp"
    parent.mkdir()
    scenario = registry.get("pendulum")
    real_runner = scenario.runner

    def runner_meanwhile_parent_moves(*args, **kwargs):
        parent.rename(tmp_path / "pp.moved")
        return real_runner(*args, **kwargs)

    monkeypatch.setattr(type(scenario), "runner", property(lambda self: runner_meanwhile_parent_moves))
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(parent / "o"))
    assert code == 1, err
    assert list((tmp_path / "pp.moved").iterdir()) == []


def test_run_folder_permissions_follow_the_umask(tmp_path, capsys):
    previous = os.umask(0o022)
    try:
        code, _, _ = cli(capsys, "run", "pendulum", *FAST, "--out", str(tmp_path / "r"))
    finally:
        os.umask(previous)
    assert code == 0 and (tmp_path / "r").stat().st_mode & 0o777 == 0o755


def test_config_edge_cases(tmp_path, capsys):
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--config", "", "--out", str(tmp_path / "r"))
    assert code == 2 and "empty" in one_line_error(err)
    bom = tmp_path / "bom.toml"
    bom.write_bytes(b"\xef\xbb\xbfmass = 0.2\n")
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--config", str(bom), "--out", str(tmp_path / "r"))
    assert code == 0, err


def test_a_mount_point_is_refused_before_the_run(tmp_path, monkeypatch):
    """A run is published by renaming onto --out, which a mount point refuses (EBUSY): say so before simulating."""
    mounted = tmp_path / "mnt"
    mounted.mkdir()
    real = os.path.ismount
    monkeypatch.setattr(os.path, "ismount", lambda p: Path(p) == mounted or real(p))
    with pytest.raises(UsageError, match="is a mount point; give a new folder inside it"):
        folders.check_out(mounted)
    folders.check_out(mounted / "run")  # inside it: fine


def test_publishers_in_one_folder_take_turns(tmp_path):
    """Two runs publishing into the same folder hold a lock while they compare --out with what it was and rename,
    so two --force runs cannot both find it unchanged and both replace it."""
    import threading

    first, second = (os.open(tmp_path, os.O_RDONLY | os.O_DIRECTORY) for _ in range(2))
    times = {}

    def publish(name, fd, hold):
        with folders._publishing(fd):
            times[name] = time.monotonic()
            time.sleep(hold)

    try:
        a = threading.Thread(target=publish, args=("a", first, 0.4))
        a.start()
        time.sleep(0.1)
        b = threading.Thread(target=publish, args=("b", second, 0.0))
        b.start()
        a.join()
        b.join()
    finally:
        os.close(first)
        os.close(second)
    assert times["b"] - times["a"] >= 0.35


@pytest.mark.parametrize("which", ["parent", "out"])
def test_a_folder_made_read_only_during_the_run_is_not_published_into(tmp_path, which):
    """The refusal of a read-only --out or parent held before the run only: made read-only mid-run (a sweep), the
    folder was published into it all the same (root's rename goes through; found by fuzzing)."""
    parent = tmp_path / "shelf"
    parent.mkdir()
    out = parent / "run"
    if which == "out":
        out.mkdir()
    frozen = parent if which == "parent" else out
    try:
        with pytest.raises(OutputError, match="was made read-only during the run"):
            with folders.run_folder(out, "pendulum") as run:
                (run.path / "run.json").write_text("{}")
                frozen.chmod(0o555)
    finally:
        frozen.chmod(0o755)
    assert [p.name for p in parent.iterdir()] == (["run"] if which == "out" else [])
    assert not out.exists() or list(out.iterdir()) == []
