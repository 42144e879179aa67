"""Issue 17: `view` checks its input (a run folder's trajectory, a scenario's parameters) before the display."""

import io

import numpy as np
import pytest
from helpers import cli

from hexabot_sim.__main__ import main


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory):
    folder = tmp_path_factory.mktemp("view") / "run"
    assert main(["run", "pendulum", "--set", "duration=0.05", "--no-plots", "--out", str(folder)]) == 0
    return folder


def _npz(arrays: dict) -> bytes:
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    return buffer.getvalue()


def _damage(folder, kind):
    path = folder / "trajectory.npz"
    good = np.load(path)
    t, qpos, qvel = good["t"], good["qpos"], good["qvel"]
    if kind == "empty":
        path.write_bytes(b"")
    elif kind == "garbage":
        path.write_bytes(b"\x80\x04garbage" * 50)
    elif kind == "truncated":
        path.write_bytes(path.read_bytes()[:200])
    elif kind == "missing-member":
        path.write_bytes(_npz({"t": t, "qpos": qpos}))
    elif kind == "object":
        path.write_bytes(_npz({"t": t, "qpos": np.array([object()] * len(t), dtype=object), "qvel": qvel}))
    elif kind == "text":
        path.write_bytes(_npz({"t": t, "qpos": np.array(["a"] * len(t)), "qvel": qvel}))
    elif kind == "nan":
        q = qpos.copy()
        q[0, 0] = np.nan
        path.write_bytes(_npz({"t": t, "qpos": q, "qvel": qvel}))
    elif kind == "huge-header":  # an .npy header declaring 10**12 rows over a few bytes of data
        header = io.BytesIO()
        np.lib.format.write_array_header_1_0(header, {"descr": "<f8", "fortran_order": False, "shape": (10**12,)})
        path.write_bytes(_npz({"qpos": qpos, "qvel": qvel}))
        import zipfile

        with zipfile.ZipFile(path, "a") as archive:
            archive.writestr("t.npy", header.getvalue() + bytes(64))
    elif kind == "bomb":
        pass  # the archive is fine; the limit on what it may unpack to is lowered below


@pytest.mark.parametrize(
    "kind", ["empty", "garbage", "truncated", "missing-member", "object", "text", "nan", "huge-header", "bomb"]
)
def test_a_damaged_trajectory_is_one_line_before_any_display(run_folder, tmp_path, monkeypatch, capsys, kind):
    import shutil

    folder = tmp_path / "copy"
    shutil.copytree(run_folder, folder)
    _damage(folder, kind)
    if kind == "bomb":
        from hexabot_sim import recording

        monkeypatch.setattr(recording, "TRAJECTORY_LIMIT", 1000)
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    code, _, err = cli(capsys, "view", str(folder))
    assert code == 2, err
    line = err.strip()
    assert len(line.splitlines()) == 1 and "Traceback" not in err and "internal error" not in err
    assert "trajectory.npz" in line and "display" not in line
    assert "allow_pickle" not in line


def test_view_names_a_bad_parameter_before_the_display(monkeypatch, capsys):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    code, _, err = cli(capsys, "view", "pendulum", "--set", "mass=-1")
    assert code == 2 and "mass" in err and "display" not in err and "glfw" not in err


def test_view_refuses_an_infeasible_walk_before_the_display(monkeypatch, capsys):
    monkeypatch.delenv("DISPLAY", raising=False)
    code, _, err = cli(capsys, "view", "hexabot-walk", "--set", "vx=0.9")
    assert code == 2 and "vx" in err and "display" not in err


def test_a_fifo_named_run_json_does_not_block_the_replay_check(run_folder, tmp_path, monkeypatch, capsys):
    import os
    import shutil

    folder = tmp_path / "copy"
    shutil.copytree(run_folder, folder)
    (folder / "run.json").unlink()
    os.mkfifo(folder / "run.json")
    monkeypatch.delenv("DISPLAY", raising=False)
    code, _, err = cli(capsys, "view", str(folder))  # blocked for ever before
    assert code == 2 and "display" in err


def test_a_missing_folder_that_is_not_utf8_is_named_readably(capsys):
    import os

    code, _, err = cli(capsys, "view", os.fsdecode(b"no/such\xff"))
    assert code == 2 and "no/such\\\\xff" in err and "udc" not in err, err


# A replayed model.xml is untrusted: MuJoCo would follow its <include>s and file attributes anywhere (a FIFO blocks,
# /dev/zero or a big file fills memory) and a few lines (<replicate>, a huge texture) take minutes or all memory.
_HOSTILE_MODELS = {
    "include": '<mujoco><include file="/etc/passwd"/></mujoco>',
    "include-fifo": '<mujoco><include file="FIFO"/></mujoco>',
    "mesh-file": '<mujoco><asset><mesh name="m" file="/etc/hostname"/></asset><worldbody/></mujoco>',
    "meshdir": '<mujoco><compiler meshdir="/etc"/><worldbody/></mujoco>',
    "texture-file": '<mujoco><asset><texture name="t" type="2d" file="/etc/passwd"/></asset></mujoco>',
    "replicate": '<mujoco><worldbody><replicate count="1000" offset="0 0 1"><replicate count="1000" '
    'offset="1 0 0"><body><geom size="0.1"/></body></replicate></replicate></worldbody></mujoco>',
    "huge-texture": '<mujoco><asset><texture name="t" type="2d" builtin="checker" width="60000" height="60000" '
    'rgb1="1 1 1" rgb2="0 0 0"/></asset></mujoco>',
    "huge-hfield": '<mujoco><asset><hfield name="h" nrow="100000" ncol="100000" size="1 1 1 1"/></asset></mujoco>',
    "many-textures": "<mujoco><asset>"
    + "".join(f'<texture name="t{i}" type="2d" builtin="flat" width="2048" height="2048"/>' for i in range(8))
    + "</asset></mujoco>",
    "one-side-texture": '<mujoco><asset><texture name="t" type="cube" builtin="flat" width="100000"/></asset></mujoco>',
    "deep": "<mujoco><worldbody>" + "<body>" * 5000 + "</body>" * 5000 + "</worldbody></mujoco>",
    "entities": '<!DOCTYPE mujoco [<!ENTITY a "aaaaaaaaaa">]><mujoco model="&a;"/>',
    "not-xml": "<mujoco><worldbody>",
    "not-utf8": b"<mujoco model='\xff'/>",
    "other-root": "<html/>",
    "oversized": None,  # a good model, the limit lowered below it
}


@pytest.mark.parametrize("kind", sorted(_HOSTILE_MODELS))
def test_a_hostile_model_xml_is_one_line_and_never_followed(run_folder, tmp_path, monkeypatch, capsys, kind):
    import os
    import shutil

    from hexabot_sim import models

    folder = tmp_path / "copy"
    shutil.copytree(run_folder, folder)
    text = _HOSTILE_MODELS[kind]
    if kind == "oversized":
        monkeypatch.setattr(models, "RUN_MODEL_LIMIT", 1000)
    else:
        if "FIFO" in str(text):
            os.mkfifo(tmp_path / "fifo")
            text = text.replace("FIFO", str(tmp_path / "fifo"))
        (folder / "model.xml").write_bytes(text if isinstance(text, bytes) else text.encode())
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    code, _, err = cli(capsys, "view", str(folder))
    assert code == 2, err
    line = err.strip()
    assert len(line.splitlines()) == 1 and "Traceback" not in err and "internal error" not in err
    assert "model" in line and "display" not in line and "root:" not in line


def test_the_models_runs_write_pass_the_replay_check(run_folder):
    from hexabot_sim import models, params, registry
    from hexabot_sim.walking import scene

    assert models.read_run_model(run_folder / "model.xml")
    for name in ("leg-step", "hexabot-walk", "hexabot-rough", "hexabot-slope", "hexabot-kerb"):
        scenario = registry.get(name)
        build_xml = getattr(scenario._module(), "build_xml", scene.build_xml)  # the walks' is shared
        xml = build_xml(params.resolve(scenario.params_type, scenario.defaults))
        path = run_folder.parent / f"{name}.xml"
        path.write_text(xml)
        assert models.read_run_model(path) == xml


def test_a_trajectory_just_over_the_limit_is_told_in_numbers_that_differ(run_folder, tmp_path, monkeypatch, capsys):
    import shutil
    import zipfile

    from hexabot_sim import recording

    folder = tmp_path / "copy"
    shutil.copytree(run_folder, folder)
    with zipfile.ZipFile(folder / "trajectory.npz") as archive:
        unpacked = sum(info.file_size for info in archive.infolist())
    monkeypatch.setattr(recording, "TRAJECTORY_LIMIT", unpacked - 1)  # over by one byte: '4.0 GiB (the limit is 4 GiB)'
    monkeypatch.delenv("DISPLAY", raising=False)
    code, _, err = cli(capsys, "view", str(folder))
    assert code == 2 and f"{unpacked} bytes" in err and f"{unpacked - 1} bytes" in err, err


def test_an_empty_target_is_refused_not_read_as_the_working_folder(run_folder, monkeypatch, capsys):
    monkeypatch.chdir(run_folder)  # a run folder: "" replayed it as "."
    monkeypatch.delenv("DISPLAY", raising=False)
    code, _, err = cli(capsys, "view", "")
    assert code == 2 and "empty" in err, err
