"""Issue 17, data loss: `clean` removes only what a run of ours created; no command writes over its inputs."""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import cli

from hexabot_sim import folders

FAST = ["--set", "duration=0.05", "--no-plots"]


def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_clean_removes_only_folders_named_exactly_as_a_run_names_them(tmp_path, capsys):
    dead = _dead_pid()
    ours = [
        tmp_path / f"{folders.STAGING_PREFIX}{dead}-0a1b2c3d{folders.STAGING_SUFFIX}",
        tmp_path / "sub" / f"{folders.STAGING_PREFIX}{dead}-deadbeef{folders.STAGING_SUFFIX}",
        tmp_path / f"{folders.OLD_PREFIX}{dead}-00ff00ff",
    ]
    users = [
        tmp_path / f"{folders.STAGING_PREFIX}backup",  # merely starts like ours: a user's folder
        tmp_path / "sub" / f"{folders.STAGING_PREFIX}old",
        tmp_path / f"{folders.STAGING_PREFIX}{dead}-0a1b2c3d",  # no suffix
        tmp_path / f"{folders.STAGING_PREFIX}{dead}-0a1b2c3d{folders.STAGING_SUFFIX}.keep",
        tmp_path / f"{folders.OLD_PREFIX}{dead}-notes",
        tmp_path / f"{folders.OLD_PREFIX}99999999999-00ff00ff",  # no system gives out such a pid
        tmp_path / f"{folders.STAGING_PREFIX}{os.getpid()}-11223344{folders.STAGING_SUFFIX}",  # alive
    ]
    for folder in ours + users:
        folder.mkdir(parents=True)
        (folder / "thesis.tex").write_text("mine")
    code, out, err = cli(capsys, "clean", str(tmp_path))
    assert code == 0, err
    assert [p for p in ours if p.exists()] == []
    assert all((p / "thesis.tex").read_text() == "mine" for p in users)
    assert out.count("removed") == len(ours)


def test_clean_never_follows_a_link_named_like_ours(tmp_path, capsys):
    dead = _dead_pid()
    target = tmp_path / "precious"
    target.mkdir()
    (target / "data.csv").write_text("1,2")
    link = tmp_path / f"{folders.STAGING_PREFIX}{dead}-0a1b2c3d{folders.STAGING_SUFFIX}"
    link.symlink_to(target)
    code, _, _ = cli(capsys, "clean", str(tmp_path))
    assert code == 0 and link.is_symlink() and (target / "data.csv").exists()


def test_clean_of_an_empty_name_is_refused(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / f"{folders.STAGING_PREFIX}{_dead_pid()}-0a1b2c3d{folders.STAGING_SUFFIX}").mkdir()
    code, _, err = cli(capsys, "clean", "")
    assert code == 2 and "empty" in err and len(err.strip().splitlines()) == 1
    assert len(list(tmp_path.iterdir())) == 1


def test_clean_that_cannot_remove_says_which_folder(tmp_path, monkeypatch, capsys):
    stale = tmp_path / f"{folders.STAGING_PREFIX}{_dead_pid()}-0a1b2c3d{folders.STAGING_SUFFIX}"
    stale.mkdir()

    def denied(path, *args, **kwargs):
        raise PermissionError(13, "Permission denied", str(path))

    monkeypatch.setattr(shutil, "rmtree", denied)
    code, _, err = cli(capsys, "clean", str(tmp_path))
    assert code != 0 and "internal error" not in err and "Traceback" not in err
    assert "could not remove" in err and "Permission denied" in err and len(err.strip().splitlines()) == 1


def test_clean_of_a_folder_nested_too_deep_is_one_line(tmp_path, monkeypatch, capsys):
    """A look-alike nested 1,500 deep was an internal error (rmtree's RecursionError on Python 3.11)."""
    stale = tmp_path / f"{folders.STAGING_PREFIX}{_dead_pid()}-0a1b2c3d{folders.STAGING_SUFFIX}"
    stale.mkdir()

    def too_deep(path, *args, **kwargs):  # what rmtree raises there, without making 1,500 folders
        raise RecursionError("maximum recursion depth exceeded")

    monkeypatch.setattr(shutil, "rmtree", too_deep)
    code, _, err = cli(capsys, "clean", str(tmp_path))
    assert code == 1 and "internal error" not in err and len(err.strip().splitlines()) == 1
    assert "could not remove" in err and "remove it by hand" in err and stale.is_dir()


@pytest.fixture
def two_runs(tmp_path, capsys):
    for name in ("a", "b"):
        code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(tmp_path / name))
        assert code == 0, err
    return tmp_path / "a", tmp_path / "b"


@pytest.mark.parametrize("where", ["a", "a/", "a/inside", "a/../a", "."])
def test_compare_never_writes_over_an_input(two_runs, capsys, monkeypatch, where):
    a, _ = two_runs
    monkeypatch.chdir(a.parent)
    before = {p: p.read_bytes() for p in a.rglob("*") if p.is_file()}
    target = where if where != "." else str(a.parent)
    code, _, err = cli(capsys, "compare", "a", "b", "--out", target, "--force")
    assert code == 2 and "never writes over what it reads" in err, err
    assert {p: p.read_bytes() for p in a.rglob("*") if p.is_file()} == before


def test_compare_refuses_a_link_to_an_input(two_runs, capsys):
    a, b = two_runs
    link = a.parent / "link"
    link.symlink_to(a)
    code, _, err = cli(capsys, "compare", str(a), str(b), "--out", str(link / "cmp"), "--force")
    assert code == 2 and "never writes over" in err


def test_run_and_sweep_never_write_over_their_config(tmp_path, capsys):
    folder = tmp_path / "study"
    folder.mkdir()
    config = folder / "cfg.toml"
    config.write_text("damping = 0.01\n")
    for argv in (
        ["run", "pendulum", "--config", str(config), *FAST, "--out", str(folder), "--force"],
        [
            "sweep",
            "pendulum",
            "--grid",
            "damping=0,0.01",
            "--config",
            str(config),
            "--set",
            "duration=0.05",
            "--no-plots",
            "--out",
            str(folder),
            "--force",
        ],
    ):
        code, _, err = cli(capsys, *argv)
        assert code == 2 and "never writes over" in err, err
        assert config.read_text() == "damping = 0.01\n"


@pytest.mark.parametrize("command", ["run", "sweep"])
def test_an_empty_out_is_named_as_such_even_beside_an_input(tmp_path, capsys, monkeypatch, command):
    """Found by fuzzing: with a config file in the working folder, --out '' was refused as "output folder '.' is,
    contains or lies inside the input 'cfg.toml'", naming neither the empty --out nor what is allowed."""
    monkeypatch.chdir(tmp_path)
    Path("cfg.toml").write_text("damping = 0.01\n")
    grid = ["--grid", "mass=0.1,0.2"] if command == "sweep" else []
    code, out, err = cli(capsys, command, "pendulum", *grid, "--config", "cfg.toml", *FAST, "--out", "")
    assert (
        code == 2
        and out == ""
        and err == "hexabot-sim: error: output folder '' must end in a folder name (not '.' or '..')\n"
    )
    assert sorted(os.listdir(tmp_path)) == ["cfg.toml"]


@pytest.mark.slow
def test_a_folder_name_that_is_not_utf8_is_a_legal_out(tmp_path):
    """b'r\\xff' is a legal Linux name: the run and the sweep are written there, and say so on stdout."""
    env = {**os.environ, "MUJOCO_GL": "egl"}
    exe = [os.fsencode(sys.executable), b"-m", b"hexabot_sim"]
    for argv in (
        [b"run", b"pendulum", b"--set", b"duration=0.05", b"--out", b"r\xff"],
        [
            b"sweep",
            b"pendulum",
            b"--grid",
            b"damping=0,0.01",
            b"--set",
            b"duration=0.05",
            b"--no-plots",
            b"--out",
            b"s\xfe",
        ],
    ):
        proc = subprocess.run(exe + argv, cwd=tmp_path, capture_output=True, env=env, timeout=120)
        assert proc.returncode == 0, proc.stderr
        assert b"internal error" not in proc.stderr
    assert (tmp_path / os.fsdecode(b"r\xff") / "run.json").is_file()
    assert (tmp_path / os.fsdecode(b"s\xfe") / "sweep.json").is_file()


def test_a_parent_folder_renamed_mid_run_is_named(tmp_path, monkeypatch, capsys):
    """The run's parent folder renamed while it runs: the message says so (not only 'No such file or directory'),
    and no staging folder is left in the renamed folder."""
    from hexabot_sim import registry

    parent = tmp_path / "study"
    scenario = registry.get("pendulum")
    runner = scenario.runner

    def rename_then_run(*args, **kwargs):
        parent.rename(tmp_path / "moved")
        return runner(*args, **kwargs)

    monkeypatch.setattr(type(scenario), "runner", property(lambda self: rename_then_run))
    code, _, err = cli(capsys, "run", "pendulum", *FAST, "--out", str(parent / "r"))
    assert code != 0 and "moved or removed during the run" in err and "study" in err, err
    assert list((tmp_path / "moved").iterdir()) == []


def test_clean_stopped_after_removing_says_what_it_removed(tmp_path, monkeypatch, capsys):
    dead = _dead_pid()
    for suffix in ("0a1b2c3d", "0a1b2c3e"):
        (tmp_path / f"{folders.STAGING_PREFIX}{dead}-{suffix}{folders.STAGING_SUFFIX}").mkdir()
    real_rmtree, calls = shutil.rmtree, []

    def rmtree_then_ctrl_c(path, *args, **kwargs):
        calls.append(path)
        if len(calls) == 2:
            raise KeyboardInterrupt
        real_rmtree(path, *args, **kwargs)

    monkeypatch.setattr(shutil, "rmtree", rmtree_then_ctrl_c)
    code, _, err = cli(capsys, "clean", str(tmp_path))
    assert code == 130 and "1 stale folder removed" in err and "nothing written" not in err, err


@pytest.mark.parametrize("command", ["clean", "view", "compare-first", "compare-second"])
@pytest.mark.parametrize("name", ["a" * 300, "/".join(["b" * 200] * 30)], ids=["long-name", "long-path"])
def test_a_path_too_long_is_one_line_exit_2(two_runs, capsys, command, name):
    # Path.is_dir() raises ENAMETOOLONG (it returns False only for a missing file): it was an internal error.
    argv = {
        "clean": ["clean", name],
        "view": ["view", name],
        "compare-first": ["compare", name, str(two_runs[0])],
        "compare-second": ["compare", str(two_runs[0]), name],
    }[command]
    code, _, err = cli(capsys, *argv)
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1 and "internal error" not in err and "name too long" in err


def test_clean_names_a_folder_that_is_not_utf8_readably(tmp_path, capsys):
    code, _, err = cli(capsys, "clean", os.fsdecode(bytes(tmp_path) + b"/no\xff"))
    assert code == 2 and "no\\\\xff" in err and "udc" not in err, err


def test_clean_with_stdout_closed_says_on_stderr_what_it_removed(tmp_path):
    dead = _dead_pid()
    for suffix in ("0a1b2c3d", "0a1b2c3e"):
        (tmp_path / f"{folders.STAGING_PREFIX}{dead}-{suffix}{folders.STAGING_SUFFIX}").mkdir()
    proc = subprocess.run(f"{sys.executable} -m hexabot_sim clean . >&-", shell=True, cwd=tmp_path,
                          capture_output=True, text=True, timeout=120)  # fmt: skip
    assert proc.returncode == 1 and len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert "(1 stale folder removed before it, the last .hexabot-sim-staging-" in proc.stderr, proc.stderr


def test_two_cleans_at_once_are_no_error(tmp_path):
    # the second clean found the first's folders gone: "could not remove ...: No such file or directory", exit 1
    dead = _dead_pid()
    for k in range(30):
        folder = tmp_path / f"{folders.STAGING_PREFIX}{dead}-{k:08x}{folders.STAGING_SUFFIX}"
        for j in range(100):
            (folder / f"s{j}").mkdir(parents=True)
            (folder / f"s{j}" / "f").touch()
    exe = [sys.executable, "-m", "hexabot_sim", "clean", str(tmp_path)]
    procs = [subprocess.Popen(exe, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for _ in range(3)]
    results = [(p.wait(timeout=120), p.stderr.read()) for p in procs]
    assert all(code == 0 and err == "" for code, err in results), results
    assert list(tmp_path.iterdir()) == []


def test_run_and_sweep_never_write_over_the_files_their_parameters_name(tmp_path, capsys):
    """--force replaced a folder holding the walk's own schedule, waypoints or robot file (found by fuzzing): each
    file a parameter names is an input, as --config is."""
    folder = tmp_path / "study"
    folder.mkdir()
    schedule = folder / "schedule.csv"
    schedule.write_text("t, vx, vy, yaw_rate\n0, 0.1, 0, 0\n")
    robot = folder / "robot.toml"
    robot.write_text((Path(__file__).resolve().parents[2] / "examples" / "my_hexapod.toml").read_text())
    walk = ["--set", "duration=2", "--no-plots", "--out", str(folder), "--force"]
    for argv in (
        ["run", "hexabot-walk", "--set", f"schedule={schedule}", *walk],
        ["run", "hexabot-walk", "--set", f"robot={robot}", *walk],
        ["sweep", "hexabot-walk", "--grid", f"robot=hexabot,{robot}", *walk],
    ):
        code, _, err = cli(capsys, *argv)
        assert code == 2 and "a command never writes over what it reads" in err, (argv, err)
    assert sorted(p.name for p in folder.iterdir()) == ["robot.toml", "schedule.csv"]


@pytest.mark.parametrize("how", ["set", "config"])
@pytest.mark.parametrize("command", ["run", "sweep"])
def test_an_input_named_from_home_is_not_deleted_by_force(tmp_path, capsys, monkeypatch, how, command):
    """Found by fuzzing: `--set schedule=~/proj/s.csv --out ~/proj --force` deleted s.csv. The input check took the
    raw '~/proj/s.csv' (no such file), while the reader expanded ~ as a shell would."""
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    proj = tmp_path / "home" / "proj"
    proj.mkdir(parents=True)
    schedule = proj / "s.csv"
    schedule.write_text("t, vx, vy, yaw_rate\n0, 0.1, 0, 0\n")
    args = ["--set", "schedule=~/proj/s.csv"]
    if how == "config":
        config = tmp_path / "walk.toml"
        config.write_text('schedule = "~/proj/s.csv"\n')
        args = ["--config", str(config)]
    grid = ["--grid", "duration=1.6,1.7"] if command == "sweep" else ["--set", "duration=1.6"]
    code, out, err = cli(capsys, command, "hexabot-walk", *args, *grid, "--no-plots", "--out", str(proj), "--force")
    assert code == 2 and out == "" and "never writes over what it reads" in err and "s.csv" in err, err
    assert sorted(os.listdir(proj)) == ["s.csv"] and schedule.read_text().startswith("t, vx")


def test_the_api_never_saves_or_films_over_a_file_the_run_read(tmp_path, monkeypatch):
    """Result.save(out, force=True) into the folder of the run's schedule replaced the folder, schedule and all;
    Result.video(path, force=True) wrote over the schedule itself."""
    import hexabot_sim as hs
    from hexabot_sim.errors import UsageError

    monkeypatch.setenv("HOME", str(tmp_path))
    (tmp_path / "proj").mkdir()
    schedule = tmp_path / "proj" / "s.csv"
    schedule.write_text("t, vx, vy, yaw_rate\n0, 0.1, 0, 0\n")
    for name in (str(schedule), "~/proj/s.csv"):
        result = hs.run("hexabot-walk", schedule=name, duration=1.6)
        with pytest.raises(UsageError, match="never writes over what it reads"):
            result.save(tmp_path / "proj", force=True, plots=False)
        with pytest.raises(UsageError, match="never writes over what it reads"):
            result.video(schedule, force=True)
        assert sorted(os.listdir(tmp_path / "proj")) == ["s.csv"] and schedule.read_text().startswith("t, vx")
    assert result.save(tmp_path / "elsewhere", plots=False).is_dir()  # another folder is fine


KILLED_AFTER_MOVING_ASIDE = """
import os, sys
real = os.rename
def rename(src, dst, **kw):  # the process dies (SIGKILL-like) once --force has moved the old folder aside
    real(src, dst, **kw)
    if str(dst).endswith("/previous"):
        os._exit(9)
os.rename = rename
from hexabot_sim.cli import main
sys.exit(main(["run", "pendulum", "--set", "duration=0.05", "--no-plots", "--out", sys.argv[1], "--force"]))
"""


def test_clean_puts_back_a_folder_that_a_killed_force_run_moved_aside(tmp_path, capsys):
    """Found by fuzzing: a --force run killed between moving the old folder aside and publishing its own left the
    user's only copy in .hexabot-sim-replaced-*/previous, and `clean` then removed it with the unpublished run."""
    runs = tmp_path / "runs"
    (runs / "keep").mkdir(parents=True)
    (runs / "keep" / "precious.txt").write_text("my old result")
    proc = subprocess.run([sys.executable, "-c", KILLED_AFTER_MOVING_ASIDE, str(runs / "keep")], capture_output=True)
    assert proc.returncode == 9, proc.stderr
    assert not (runs / "keep").exists()  # the state the kill leaves: the old folder aside, the new one unpublished
    [aside] = runs.glob(f"{folders.OLD_PREFIX}*")
    assert (aside / "previous" / "precious.txt").exists() and len(list(runs.glob(f"{folders.STAGING_PREFIX}*"))) == 1
    code, out, err = cli(capsys, "clean", str(runs), "--dry-run")
    assert code == 0 and "would put" in out and not (runs / "keep").exists()
    code, out, err = cli(capsys, "clean", str(runs))
    assert code == 0 and "restored" in out and err == "", err
    assert sorted(os.listdir(runs)) == ["keep"] and (runs / "keep" / "precious.txt").read_text() == "my old result"


@pytest.mark.parametrize("case", ["published", "no target", "name taken by a user's folder"])
def test_clean_removes_a_replaced_folder_only_when_the_run_was_published(tmp_path, capsys, case):
    aside = tmp_path / f"{folders.OLD_PREFIX}{_dead_pid()}-00ff00ff"
    (aside / "previous").mkdir(parents=True)
    (aside / "previous" / "old.txt").write_text("old")
    if case != "no target":
        (aside / "target").write_text("keep")
        (tmp_path / "keep").mkdir()
        (tmp_path / "keep" / ("run.json" if case == "published" else "notes.txt")).write_text("{}")
    code, out, err = cli(capsys, "clean", str(tmp_path))
    assert code == 0, err
    if case == "published":  # the new run is in place: the old one is what --force was asked to replace
        assert not aside.exists() and "removed" in out
    else:
        assert (aside / "previous" / "old.txt").read_text() == "old" and "kept" in out and "by hand" in out
    assert (tmp_path / "keep").exists() or case == "no target"


def test_the_api_keeps_its_inputs_whatever_the_working_folder(tmp_path, monkeypatch):
    """Found by fuzzing: hs.run(schedule="schedule.csv") kept the relative name, so after a chdir Result.save(folder
    of the schedule, force=True) passed the check and replaced the folder, schedule and all."""
    import hexabot_sim as hs
    from hexabot_sim.errors import UsageError

    proj = tmp_path / "proj"
    proj.mkdir()
    (proj / "schedule.csv").write_text("t, vx, vy, yaw_rate\n0, 0.1, 0, 0\n")
    monkeypatch.chdir(proj)
    result = hs.run("hexabot-walk", schedule="schedule.csv", duration=1.6)
    monkeypatch.chdir(tmp_path)
    with pytest.raises(UsageError, match="never writes over what it reads"):
        result.save(proj, force=True, plots=False)
    with pytest.raises(UsageError, match=r"video path .* is a file the run read"):
        result.video(proj / "schedule.csv", force=True)
    assert sorted(os.listdir(proj)) == ["schedule.csv"]


@pytest.mark.skipif(os.geteuid() != 0 or shutil.which("mount") is None, reason="a bind mount needs root and mount(8)")
def test_an_input_named_through_a_bind_mount_of_out_is_still_an_input(tmp_path, capsys):
    """Found by fuzzing: --out P --force with schedule=M/schedule.csv, M a bind mount of P, deleted P's files: the
    check compared names; it now also compares the input's folders with --out by identity."""
    proj, mount = tmp_path / "proj", tmp_path / "mnt"
    proj.mkdir()
    mount.mkdir()
    (proj / "schedule.csv").write_text("t, vx, vy, yaw_rate\n0, 0.1, 0, 0\n")
    if subprocess.run(["mount", "--bind", str(proj), str(mount)], capture_output=True).returncode:
        pytest.skip("mount --bind is not permitted here")
    try:
        code, _, err = cli(capsys, "run", "hexabot-walk", "--set", f"schedule={mount / 'schedule.csv'}", *FAST[2:],
                           "--set", "duration=1.6", "--out", str(proj), "--force")  # fmt: skip
        assert code == 2 and "never writes over what it reads" in err
        assert sorted(os.listdir(proj)) == ["schedule.csv"]
    finally:
        subprocess.run(["umount", str(mount)], capture_output=True)


def test_clean_survives_hostile_replaced_folders_and_restores_the_rest(tmp_path, capsys):
    """Found by fuzzing: a `target` that is a FIFO hung clean (even --dry-run), one linked to /dev/zero was a
    MemoryError, and one name that could not be restored (300 bytes) ended the clean with exit 1 before the
    folders after it, a restorable one among them, on every later clean too."""
    dead = _dead_pid()

    def replaced(hexa: str) -> Path:
        folder = tmp_path / f"{folders.OLD_PREFIX}{dead}-{hexa}"
        (folder / "previous").mkdir(parents=True)
        (folder / "previous" / "data.txt").write_text(hexa)
        return folder

    os.mkfifo(replaced("00000001") / "target")
    (replaced("00000002") / "target").symlink_to("/dev/zero")
    (replaced("00000003") / "target").write_text("a" * 300)
    (replaced("00000004") / "target").write_text("ok")
    odd = tmp_path / f"{folders.OLD_PREFIX}{dead}-00000005"
    odd.mkdir()
    (odd / "previous").write_text("a file where a run puts a folder")
    (odd / "target").write_text("other")
    for argv in (["--dry-run"], []):
        code, out, err = cli(capsys, "clean", str(tmp_path), *argv)
        assert code == 0 and err == "", err
    assert (tmp_path / "ok" / "data.txt").read_text() == "00000004"  # the restorable one was put back
    assert "could not be put back" in out and "File name too long" in out
    for hexa in ("00000001", "00000002", "00000003"):
        assert (tmp_path / f"{folders.OLD_PREFIX}{dead}-{hexa}" / "previous" / "data.txt").read_text() == hexa
    assert (odd / "previous").read_text() == "a file where a run puts a folder"


def test_clean_looks_four_folder_levels_down(tmp_path, capsys):
    """Found by fuzzing: clean DIR looked one level down, so a run killed while writing --out runs/a/b/x left its
    staging folder (or a --force run the user's folder moved aside) in runs/a/b, where clean runs never looked."""
    dead = _dead_pid()
    name = f"{folders.STAGING_PREFIX}{dead}-0a1b2c3d{folders.STAGING_SUFFIX}"
    found = [tmp_path / "a" / "b" / name, tmp_path / "a" / "b" / "c" / name]
    beyond = tmp_path / "1" / "2" / "3" / "4" / name  # five levels down: not looked at
    inside = tmp_path / f"{folders.STAGING_PREFIX}{dead}-00ff00ff{folders.STAGING_SUFFIX}" / name  # within ours
    for folder in (*found, beyond, inside):
        folder.mkdir(parents=True)
    code, out, _ = cli(capsys, "clean", str(tmp_path))
    assert code == 0 and not any(p.exists() for p in found) and beyond.exists()
    assert out.count("removed") == 3  # the two found and the outer staging folder (with what it held)


def test_clean_goes_on_past_what_it_cannot_read_or_remove(tmp_path, capsys, monkeypatch):
    """Found by fuzzing: a folder that may be listed but not entered made clean's deeper look an internal error
    (PermissionError from Path.is_dir), and a staging folder that could not be removed ended the clean before it
    put a user's folder back."""
    dead = _dead_pid()
    locked = tmp_path / "locked"
    (locked / "inner").mkdir(parents=True)
    staging = tmp_path / "b" / f"{folders.STAGING_PREFIX}{dead}-deadbeef{folders.STAGING_SUFFIX}"
    staging.mkdir(parents=True)
    stuck = tmp_path / f"{folders.STAGING_PREFIX}{dead}-0badf00d{folders.STAGING_SUFFIX}"
    stuck.mkdir()
    aside = tmp_path / f"{folders.OLD_PREFIX}{dead}-cafebabe"
    (aside / "previous").mkdir(parents=True)
    (aside / "previous" / "data.txt").write_text("precious")
    (aside / "target").write_text("mydata")
    real_is_dir = Path.is_dir

    def is_dir(self):  # a folder listed but not entered: its entries' types cannot be read (as for a non-root user)
        if self.parent == locked:
            raise PermissionError(13, "Permission denied", str(self))
        return real_is_dir(self)

    real_rmtree = shutil.rmtree

    def rmtree(path, *args, **kwargs):
        if Path(path) == stuck:
            raise PermissionError(13, "Permission denied", str(path))
        return real_rmtree(path, *args, **kwargs)

    monkeypatch.setattr(Path, "is_dir", is_dir)
    monkeypatch.setattr(shutil, "rmtree", rmtree)
    code, _, err = cli(capsys, "clean", str(tmp_path))
    assert code == 1 and err.count("\n") == 1 and "could not remove" in err and "0badf00d" in err
    assert (tmp_path / "mydata" / "data.txt").read_text() == "precious" and not staging.exists() and stuck.exists()
