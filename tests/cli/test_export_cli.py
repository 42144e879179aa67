"""hexabot-sim export ROBOT|FILE --mjcf OUT.xml --urdf OUT.urdf: files written whole, never replaced without --force."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest
from helpers import cli

import hexabot_sim as hs
from hexabot_sim import api
from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics import robots

SLIDE = """\
name = "slide"
convention = "standard"
angles = "deg"
[[joints]]
name = "q1"
type = "revolute"
a = 0.3
alpha = 0.0
d = 0.0
theta = 0.0
[[joints]]
name = "s"
type = "prismatic"
a = 0.0
alpha = 0.0
d = 0.1
theta = 0.0
"""


def test_export_writes_both_models_and_they_compile(tmp_path, capsys):
    mjcf, urdf = tmp_path / "scara.xml", tmp_path / "scara.urdf"
    code, out, err = cli(capsys, "export", "scara", "--mjcf", str(mjcf), "--urdf", str(urdf), "--set", "a1=0.4")
    assert code == 0, err
    assert out.splitlines() == [f"wrote {mjcf}", f"wrote {urdf}"] and sorted(p.name for p in tmp_path.iterdir()) == [
        "scara.urdf", "scara.xml"]  # fmt: skip
    chain = robots.get("scara").chain({"a1": 0.4})
    q = np.array([0.3, -0.2, 0.1, 0.5])
    for path, frame in ((mjcf, "site"), (urdf, "body")):
        model = mujoco.MjModel.from_xml_path(str(path))
        data = mujoco.MjData(model)
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        position = data.site("tool").xpos if frame == "site" else data.body("tool").xpos
        np.testing.assert_allclose(position, chain.fk(q)[:3, 3], atol=1e-12)


def test_an_existing_file_is_replaced_only_with_force(tmp_path, capsys):
    mjcf = tmp_path / "arm.xml"
    mjcf.write_text("mine")
    code, out, err = cli(capsys, "export", "elbow", "--mjcf", str(mjcf))
    assert code == 2 and out == "" and err.count("\n") == 1 and "exists; add --force" in err
    assert mjcf.read_text() == "mine"
    code, out, err = cli(capsys, "export", "elbow", "--mjcf", str(mjcf), "--force")
    assert code == 0 and mjcf.read_text().startswith("<!--") and len(list(tmp_path.iterdir())) == 1


def test_nothing_is_written_when_one_model_is_refused(tmp_path, capsys):
    robot = tmp_path / "slide.toml"
    robot.write_text(SLIDE)
    mjcf, urdf = tmp_path / "out.xml", tmp_path / "out.urdf"
    code, _, err = cli(capsys, "export", str(robot), "--mjcf", str(mjcf), "--urdf", str(urdf))
    assert code == 2 and err.count("\n") == 1 and "joint 's' is prismatic without 'lower' and 'upper'" in err
    assert not mjcf.exists() and not urdf.exists() and sorted(p.name for p in tmp_path.iterdir()) == ["slide.toml"]
    code, _, _ = cli(capsys, "export", str(robot), "--mjcf", str(mjcf))  # the MJCF alone needs no stroke
    assert code == 0 and mjcf.exists()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["export", "elbow"], "export needs an output: --mjcf FILE and/or --urdf FILE"),
        (["export", "puma", "--mjcf", "x.xml"], "unknown robot 'puma'"),
        (
            ["export", "elbow", "--mjcf", "no/such/folder/x.xml"],
            "the folder 'no/such/folder' for the MJCF file does not",
        ),
        (["export", "elbow", "--mjcf", "same", "--urdf", "same"], "--mjcf and --urdf name the same file 'same'"),
        (["export", "elbow", "--urdf", ""], "URDF file needs a file name; got an empty one"),  # was: "'.' is a folder"
        (["export", "elbow", "--mjcf", "x.xml", "--set", "a2=0"], "length 'a2' of elbow must be 0.001 to 10 m"),
    ],
)
def test_bad_exports_are_one_line(tmp_path, capsys, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    code, out, err = cli(capsys, *argv)
    assert code == 2 and out == "" and err.count("\n") == 1 and message in err
    assert list(tmp_path.iterdir()) == []


def test_a_file_name_of_250_bytes_is_exported(tmp_path, capsys):
    """Found by fuzzing: its staging name ('.NAME.partial-PID-HEX') went over 255 bytes, an exit 1 'File name too
    long' for a name the file system takes."""
    mjcf = tmp_path / ("a" * 250 + ".xml")
    code, _, err = cli(capsys, "export", "leg", "--mjcf", str(mjcf))
    assert code == 0 and err == "" and [p.name for p in tmp_path.iterdir()] == [mjcf.name]


def test_a_folder_that_cannot_be_written_is_refused_up_front(tmp_path, capsys, monkeypatch):
    """Found by fuzzing: a read-only file system was an exit 1 'writing the MJCF file ... failed' after the models were
    made, not exit 2 before. (os.access stands in for the read-only mount: chmod does not stop root.)"""
    real = os.access
    monkeypatch.setattr(os, "access", lambda path, mode, **kw: path != tmp_path and real(path, mode, **kw))
    code, out, err = cli(capsys, "export", "leg", "--mjcf", str(tmp_path / "leg.xml"))
    assert code == 2 and out == "" and err.count("\n") == 1
    assert f"the folder '{tmp_path}' for the MJCF file cannot be written" in err and list(tmp_path.iterdir()) == []


def test_the_api_exports_a_spec_and_refuses_a_folder(tmp_path):
    (path,) = hs.export(robots.get("leg"), urdf=tmp_path / "leg.urdf", lengths={"l3": 0.12})
    assert path == tmp_path / "leg.urdf" and 'name="tool"' in path.read_text()
    with pytest.raises(UsageError, match="is a folder"):
        api.export("leg", mjcf=tmp_path)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [({"robot": 5}, "a robot is one of rrp, elbow, stanford, scara, leg, the path of a robot file (str or os"),
     ({"robot": None}, "or a RobotSpec; got NoneType"),
     ({"robot": b"leg.toml"}, "or a RobotSpec; got bytes"),
     ({"mjcf": "leg\0.xml"}, "MJCF file 'leg\\x00.xml' holds a NUL byte, which no file name can"),
     ({"lengths": "l3=0.2"}, "the lengths of leg are a mapping name -> [m]; got str"),
     ({"lengths": [0.2]}, "the lengths of leg are a mapping name -> [m]; got list")],
)  # fmt: skip
def test_the_api_refuses_a_wrong_type_in_one_line(tmp_path, monkeypatch, kwargs, message):
    """robot=5, None or bytes was pathlib's TypeError, a NUL in a path its ValueError, lengths="l3=0.2" an
    AttributeError: every wrong argument is one UsageError, as mjcf=3 already was."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(UsageError) as info:
        hs.export(**({"robot": "leg", "mjcf": "leg.xml"} | kwargs))
    assert message in str(info.value) and "\n" not in str(info.value)
    assert list(tmp_path.iterdir()) == []


def test_the_robot_file_itself_is_never_written_over_not_even_with_force(tmp_path, capsys):
    robot = tmp_path / "slide.toml"
    robot.write_text(SLIDE)
    (tmp_path / "link.toml").symlink_to(robot)
    (tmp_path / "hard.xml").hardlink_to(robot)
    for source, out in (("slide.toml", "slide.toml"), ("link.toml", "slide.toml"), ("slide.toml", "link.toml"),
                        ("slide.toml", "hard.xml")):  # fmt: skip
        code, stdout, err = cli(capsys, "export", str(tmp_path / source), "--mjcf", str(tmp_path / out), "--force")
        assert code == 2 and stdout == "" and err.count("\n") == 1, err
        assert "is the robot file being exported; it is never written over" in err
    assert robot.read_text() == SLIDE and sorted(p.name for p in tmp_path.iterdir()) == [
        "hard.xml", "link.toml", "slide.toml"]  # fmt: skip


@pytest.mark.parametrize("urdf", ["{d}/out.xml", "{d}/sub/../out.xml", "./out.xml"])
def test_one_file_spelled_two_ways_is_refused_before_anything_is_written(tmp_path, capsys, monkeypatch, urdf):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "sub").mkdir()
    for force in ([], ["--force"]):
        code, out, err = cli(capsys, "export", "elbow", "--mjcf", "out.xml", "--urdf", urdf.format(d=tmp_path), *force)
        assert code == 2 and out == "" and err.count("\n") == 1 and "--mjcf and --urdf name the same file" in err
        assert sorted(p.name for p in tmp_path.iterdir()) == ["sub"]


def test_a_path_ending_in_a_slash_names_a_folder_not_a_file(tmp_path, capsys):
    code, out, err = cli(capsys, "export", "elbow", "--mjcf", f"{tmp_path}/new/")
    assert code == 2 and out == "" and "ends with '/': that names a folder; give a file name" in err
    assert list(tmp_path.iterdir()) == []


def test_the_exported_files_are_well_formed_xml_whatever_the_summary_says(tmp_path, capsys):
    from xml.dom import minidom

    robot = tmp_path / "slide.toml"
    text = SLIDE.replace('name = "slide"', 'name = "slide"\nsummary = "x-->y <&> ends with-"')
    robot.write_text(text.replace('name = "q1"', 'name = "q---1"'))  # "--" went raw into the MJCF's DH table comment
    mjcf, urdf = tmp_path / "out.xml", tmp_path / "out.urdf"
    code, _, err = cli(capsys, "export", str(robot), "--mjcf", str(mjcf))
    assert code == 0, err
    minidom.parse(str(mjcf))
    mujoco.MjModel.from_xml_path(str(mjcf))
    robot.write_text(robot.read_text().replace("d = 0.1\n", "d = 0.1\nlower = 0.0\nupper = 0.2\n"))
    code, _, err = cli(capsys, "export", str(robot), "--urdf", str(urdf))
    assert code == 0, err
    minidom.parse(str(urdf))
    mujoco.MjModel.from_xml_path(str(urdf))


def test_three_dashes_in_the_summary_or_the_path_are_exported_and_tracked(tmp_path, capsys):
    """A "--" was replaced once: "a---b" left "a- --b" in the header comment, and export (and arm-track, whose comment
    was not escaped at all) refused a valid file with "comment must not contain '--'"; a legged file's path made a
    walk's MJCF "not well-formed", an internal error."""
    folder = tmp_path / "v1---v2"
    folder.mkdir()
    robot = folder / "arm---3.toml"
    robot.write_text(Path(robots.get("elbow").source).read_text().replace('summary = "', 'summary = "v1 --- v2: '))
    code, _, err = cli(capsys, "export", str(robot), "--mjcf", str(tmp_path / "out.xml"))
    assert code == 0, err
    mujoco.MjModel.from_xml_path(str(tmp_path / "out.xml"))
    assert hs.run("arm-track", robot=str(robot), duration=0.01).metrics["joints"].value == 3
    walker = folder / "hex---apod.toml"
    walker.write_text((Path(__file__).resolve().parents[2] / "examples" / "my_hexapod.toml").read_text())
    from hexabot_sim.kinematics import legged_file

    mujoco.MjModel.from_xml_string(legged_file.read(walker).robot_xml())


@pytest.mark.parametrize("stop_at", [1, 2])
def test_ctrl_c_while_writing_leaves_neither_file(tmp_path, monkeypatch, stop_at):
    """Ctrl-C (or SIGTERM, raised the same way by the CLI) while the second file was synced left the first
    published: both are now written under temporary names first and renamed only when both are whole."""
    from hexabot_sim import exporting

    calls = []
    real = os.fsync

    def fsync(fd):
        calls.append(fd)
        if len(calls) == stop_at:
            raise KeyboardInterrupt
        real(fd)

    monkeypatch.setattr(exporting.os, "fsync", fsync)
    with pytest.raises(KeyboardInterrupt):
        api.export("elbow", mjcf=tmp_path / "a.xml", urdf=tmp_path / "a.urdf")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("force", [False, True])
def test_a_second_file_that_fails_takes_the_first_back(tmp_path, monkeypatch, force):
    """The URDF failing after the MJCF was in place (an I/O error, or a file made there meanwhile) left the MJCF
    published, and with --force a new MJCF beside the old URDF (found by fuzzing, with strace's fault injection)."""
    from hexabot_sim import exporting, folders

    mjcf, urdf = tmp_path / "a.xml", tmp_path / "a.urdf"
    if force:
        mjcf.write_text("old mjcf")
        urdf.write_text("old urdf")
    real_replace, real_publish = os.replace, folders.publish_new

    def fail_second(publish):
        def wrapped(src, dst, *args, **kwargs):
            if Path(dst) == urdf and ".partial-" in Path(src).name:
                raise OSError(5, "Input/output error")
            return publish(src, dst, *args, **kwargs)

        return wrapped

    monkeypatch.setattr(exporting.os, "replace", fail_second(real_replace))
    monkeypatch.setattr(exporting.folders, "publish_new", fail_second(real_publish))
    with pytest.raises(hs.errors.OutputError, match=r"writing the URDF file .* failed: Input/output error"):
        api.export("elbow", mjcf=mjcf, urdf=urdf, force=force)
    assert sorted(p.name for p in tmp_path.iterdir()) == (["a.urdf", "a.xml"] if force else [])
    if force:
        assert mjcf.read_text() == "old mjcf" and urdf.read_text() == "old urdf"
    monkeypatch.undo()
    assert api.export("elbow", mjcf=mjcf, urdf=urdf, force=True) == [mjcf, urdf]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.urdf", "a.xml"]  # no kept copy left behind
    assert mjcf.read_text().startswith("<!--") and urdf.read_text().startswith("<?xml")


@pytest.mark.parametrize("force", [False, True])
def test_a_stop_right_after_the_first_file_is_published_takes_it_back(tmp_path, monkeypatch, force):
    """Found by fuzzing (strace delaying the rename, then SIGTERM): a stop that came after the first file's rename
    but before it was counted left that file published and, with --force, the file it replaced lost."""
    from hexabot_sim import exporting, folders

    mjcf, urdf = tmp_path / "a.xml", tmp_path / "a.urdf"
    if force:
        mjcf.write_text("old mjcf")
        urdf.write_text("old urdf")

    def stop_after(publish):
        def wrapped(src, dst, *args, **kwargs):
            publish(src, dst, *args, **kwargs)
            if Path(dst) == mjcf:
                raise KeyboardInterrupt

        return wrapped

    monkeypatch.setattr(exporting.os, "replace", stop_after(os.replace))
    monkeypatch.setattr(exporting.folders, "publish_new", stop_after(folders.publish_new))
    with pytest.raises(KeyboardInterrupt):
        api.export("elbow", mjcf=mjcf, urdf=urdf, force=force)
    assert sorted(p.name for p in tmp_path.iterdir()) == (["a.urdf", "a.xml"] if force else [])
    if force:
        assert mjcf.read_text() == "old mjcf" and urdf.read_text() == "old urdf"


SIGTERM_AFTER_FIRST_RENAME = """
import os, signal, sys
real = os.replace
def replace(src, dst, *a, **k):  # SIGTERM arrives just after the first file is renamed into place
    real(src, dst, *a, **k)
    if str(dst).endswith("a.xml"):
        os.kill(os.getpid(), signal.SIGTERM)
os.replace = replace
from hexabot_sim.cli import console
sys.argv = ["hexabot-sim", "export", "elbow", "--mjcf", sys.argv[1] + "/a.xml", "--urdf", sys.argv[1] + "/a.urdf",
            "--force"]
console()
"""


def test_the_command_line_holds_a_stop_until_both_files_are_in_place(tmp_path):
    (tmp_path / "a.xml").write_text("old mjcf")
    (tmp_path / "a.urdf").write_text("old urdf")
    proc = subprocess.run([sys.executable, "-c", SIGTERM_AFTER_FIRST_RENAME, str(tmp_path)], capture_output=True,
                          text=True, timeout=120)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert "SIGTERM came after the results were published; they are complete" in proc.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.urdf", "a.xml"]  # no kept copy or staging file left
    assert (tmp_path / "a.xml").read_text().startswith("<!--") and (tmp_path / "a.urdf").read_text().startswith("<?x")


def test_a_folder_without_write_bits_is_refused_even_for_root(tmp_path, capsys):
    """Found by fuzzing: as root, export wrote into a chmod 555 folder (os.access says yes to root), where run,
    sweep and compare refuse it."""
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        code, out, err = cli(capsys, "export", "leg", "--mjcf", str(folder / "leg.xml"))
        assert code == 2 and out == "" and "cannot be written" in err and list(folder.iterdir()) == []
    finally:
        folder.chmod(0o755)


def test_a_stop_as_a_staging_file_is_opened_leaves_no_hidden_file(tmp_path, monkeypatch):
    """Found by fuzzing: SIGTERM just as open() of the staging file returned left an empty .a.xml.partial-* file
    (it was recorded for removal only once open had returned)."""
    import builtins

    from hexabot_sim import exporting

    def open_then_stop(file, *args, **kwargs):
        builtins.open(file, *args, **kwargs).close()  # the file exists: the stop lands as open() returns
        raise KeyboardInterrupt

    monkeypatch.setattr(exporting, "open", open_then_stop, raising=False)
    with pytest.raises(KeyboardInterrupt):
        api.export("elbow", mjcf=tmp_path / "a.xml", urdf=tmp_path / "a.urdf")
    assert list(tmp_path.iterdir()) == []
