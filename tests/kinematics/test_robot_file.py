"""Robot files: the format's checks (one line naming file, joint and field) and the package's robots as files."""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest
from helpers import cli

from hexabot_sim import params
from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics import robot_file, robots
from hexabot_sim.kinematics.chain import SerialChain

ARM = """\
name = "textbook-arm"
convention = "standard"
angles = "deg"
[[joints]]
name = "q1"
type = "revolute"
a = 0.0
alpha = 90.0
d = 0.4
theta = 0.0
lower = -170.0
upper = 170.0
[[joints]]
name = "q2"
type = "revolute"
a = 0.3
alpha = 0.0
d = 0.0
theta = 0.0
[[joints]]
name = "q3"
type = "prismatic"
a = 0.0
alpha = 0.0
d = 0.1
theta = 0.0
lower = 0.0
upper = 0.2
[tool]
xyz = [0.0, 0.0, 0.1]
rpy = [0.0, 90.0, 0.0]
"""


def write(tmp_path: Path, text: str, name: str = "arm.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_the_example_reads_into_the_chain_it_describes(tmp_path):
    spec = robot_file.read(write(tmp_path, ARM))
    chain = spec.chain()
    assert spec.name == "textbook-arm" and spec.joint_units == ("rad", "rad", "m") and not spec.builtin
    assert chain.convention == "standard" and [j.kind for j in chain.joints] == ["revolute", "revolute", "prismatic"]
    assert chain.joints[0].alpha == math.pi / 2 and chain.joints[0].lower == math.radians(-170.0)
    assert chain.joints[2].upper == 0.2 and chain.joints[1].lower is None
    # Tool: Ry(90 deg) exactly (quarter turns are exact), 0.1 m along z.
    np.testing.assert_array_equal(chain.tool, [[0, 0, 1, 0], [0, 1, 0, 0], [-1, 0, 0, 0.1], [0, 0, 0, 1]])


def test_radians_modified_base_masses_and_fixed_rows(tmp_path):
    text = """\
name = "m"
convention = "modified"
angles = "rad"
[lengths]
L = { value = 0.2, doc = "link" }
[[joints]]
name = "a"
type = "revolute"
a = 0.0
alpha = 0.0
d = 0.0
theta = 0.5
mass = 1.5
[[joints]]
name = "foot"
type = "fixed"
a = "L"
alpha = 0.0
d = "-L"
theta = 0.0
[base]
xyz = [1.0, 2.0, 3.0]
rpy = [0.0, 0.0, 1.5707963267948966]
"""
    spec = robot_file.read(write(tmp_path, text))
    chain = spec.chain({"L": 0.3})
    assert spec.masses == (1.5,) and [j.name for j in spec.fixed_rows()] == ["foot"]
    np.testing.assert_array_equal(chain.base, [[0, -1, 0, 1], [1, 0, 0, 2], [0, 0, 1, 3], [0, 0, 0, 1]])
    np.testing.assert_array_equal(chain.tool[:3, 3], [0.3, 0.0, -0.3])  # Tx(L) Tz(-L), from --set L=0.3
    assert chain.joints[0].theta == 0.5


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ('name = "q2"\ntype = "revolute"\na = 0.3', 'name = "q2"\ntype = "revolute"\nlenght = 1\na = 0.3',
         "joint 2 ('q2'): unknown key 'lenght'; allowed: name, type, a, alpha, d, theta, lower, upper, mass"),
        ('a = 0.3\nalpha = 0.0\nd = 0.0\n', "a = 0.3\nalpha = 0.0\n", "joint 2 ('q2'): missing 'd'"),
        ("a = 0.3", 'a = "0.3"', "joint 2 ('q2'): 'a' names the length '0.3', which [lengths] lacks"),
        ("a = 0.3", "a = true", "joint 2 ('q2'): 'a' must be a number [m]; got True"),
        ("a = 0.3", "a = nan", "joint 2 ('q2'): 'a' must be a finite number [m]; got nan"),
        ("a = 0.3", "a = -inf", "joint 2 ('q2'): 'a' must be a finite number [m]; got -inf"),
        ("a = 0.3", "a = 1e9", "joint 2 ('q2'): 'a' = 1e+09 m is outside the allowed ±100 m"),
        ('angles = "deg"', 'angles = "rad"', "joint 1 ('q1'): 'alpha' = 90 rad is outside the allowed ±6.28319 rad"),
        ('angles = "deg"', 'angles = "grad"', "'angles' must be one of deg, rad; got 'grad'"),
        ('convention = "standard"', 'convention = "craig"', "'convention' must be one of standard, modified"),
        ('convention = "standard"\n', "", "missing 'convention'"),
        ('type = "prismatic"', 'type = "slider"', "joint 3 ('q3'): 'type' must be one of revolute, prismatic, fixed"),
        ("lower = 0.0\nupper = 0.2", "upper = 0.2", "joint 3 ('q3'): give both 'lower' and 'upper', or neither"),
        ("lower = 0.0\nupper = 0.2", "lower = 0.3\nupper = 0.2", "joint 3 ('q3'): 'lower' (0.3 m) must be less"),
        ('name = "q3"', 'name = "q1"', "joint 3 ('q1'): the name 'q1' is used twice"),
        ('name = "q3"', 'name = "q 3"', "joint 3: 'name' must be 1 to 64 letters"),
        ("xyz = [0.0, 0.0, 0.1]", "xyz = [0.0, 0.1]", "[tool]: 'xyz' must be a list of 3 numbers"),
        ("rpy = [0.0, 90.0, 0.0]", "ypr = [0.0, 90.0, 0.0]", "[tool]: unknown key 'ypr'; allowed: xyz, rpy"),
        ('name = "textbook-arm"', 'name = "textbook-arm"\ncolour = "red"', "unknown key 'colour'; allowed: name,"),
        ("mass", "mass", ""),  # placeholder replaced below: keeps the table aligned
    ],
)  # fmt: skip
def test_bad_fields_are_one_line_naming_file_joint_and_field(tmp_path, old, new, message):
    if old == "mass":
        old, new, message = "upper = 170.0", "upper = 170.0\nmass = -1.0", "joint 1 ('q1'): 'mass' must be 0.0001 to"
    assert old in ARM
    path = write(tmp_path, ARM.replace(old, new, 1))
    with pytest.raises(UsageError) as info:
        robot_file.read(path)
    text = str(info.value)
    assert text.startswith(f"robot file {path}: ") and message in text and "\n" not in text


def joint_block(i: int) -> str:
    return f'[[joints]]\nname = "j{i}"\ntype = "revolute"\na = 0.1\nalpha = 0.0\nd = 0.0\ntheta = 0.0\n'


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ('name = "x"\nconvention = "standard"\nangles = "deg"\n' + "".join(joint_block(i) for i in range(8)),
         "8 joints; at most 7"),
        ('name = "x"\nconvention = "standard"\nangles = "deg"\n' + joint_block(1).replace("a = 0.1", "a = 0.0"),
         "every link length, offset and tool offset is 0"),
        ('name = "x"\nconvention = "standard"\nangles = "deg"\njoints = []\n', "'joints' must be one or more"),
        ('name = "x"\nconvention = "standard"\nangles = "deg"\n' + joint_block(1).replace("revolute", "fixed"),
         "no joint: a chain needs at least one revolute or prismatic joint"),
        ('name = "x"\nconvention = "standard"\nangles = "deg"\n' + joint_block(1).replace("revolute", "fixed")
         + joint_block(2), "joint 1 ('j1'): a fixed row may only follow the last joint"),
        ("name = [", "not valid TOML"),
        ('name = "x"\nconvention = "standard"\nangles = "deg"\n[lengths]\nL = 20.0\n' + joint_block(1),
         "[lengths] L: 'value' = 20 m is outside the allowed ±10 m"),
        # Control characters went raw into the MJCF/URDF comment (not well-formed XML) and onto the terminal:
        ('name = "x"\nsummary = "a\\u001b[2Jb"\nconvention = "standard"\nangles = "deg"\n' + joint_block(1),
         "'summary' must be one line of text (at most 200 characters); got 'a\\x1b[2Jb'"),
        ('name = "x"\nsummary = "a\\u0000b\\uffff"\nconvention = "standard"\nangles = "deg"\n' + joint_block(1),
         "'summary' must be one line of text"),
        ('name = "x"\nsummary = "a\\u202eb"\nconvention = "standard"\nangles = "deg"\n' + joint_block(1),
         "'summary' must be one line of text"),  # a bidi override reordered the terminal line
        ('name = "x"\nconvention = "standard"\nangles = "deg"\n[lengths]\nL = { value = 0.1, doc = "a\\u0007" }\n'
         + joint_block(1), "[lengths] L: 'doc' must be one line of text"),
        # 12,000 fixed rows made kin run for minutes, 40,000 lengths took 24 s (each a file under 1 MiB):
        ('name = "x"\nconvention = "standard"\nangles = "deg"\n' + joint_block(0)
         + "".join(joint_block(i).replace("revolute", "fixed") for i in range(1, 16)),
         "16 [[joints]] rows; at most 7 joints and 8 fixed rows after them"),
        ('name = "x"\nconvention = "standard"\nangles = "deg"\n' + "".join(joint_block(i) for i in range(6))
         + "".join(joint_block(i).replace("revolute", "fixed") for i in range(6, 15)), "9 fixed rows; at most 8"),
        ('name = "x"\nconvention = "standard"\nangles = "deg"\n[lengths]\n'
         + "".join(f"l{i} = 0.1\n" for i in range(65)) + joint_block(1), "[lengths]: 65 lengths; at most 64"),
        # A length named "l-1" printed as c1*l-1 in --symbolic (c1 l minus 1):
        ('name = "x"\nconvention = "standard"\nangles = "deg"\n[lengths]\n"l-1" = 0.1\n' + joint_block(1),
         "a length name must be 1 to 64 letters, digits, _ (starting with a letter or _; it is a symbol in"),
        # A chain of 1e-300 m was accepted: every q "solved" every target near 0 and J was "not singular"
        ('name = "x"\nconvention = "standard"\nangles = "deg"\n' + joint_block(1).replace("a = 0.1", "a = 1e-300"),
         "add up to 1e-300 m, less than 1 mm: the tool point barely moves"),
    ],
)  # fmt: skip
def test_bad_tables(tmp_path, text, message):
    path = write(tmp_path, text)
    with pytest.raises(UsageError, match=None) as info:
        robot_file.read(path)
    assert message in str(info.value) and str(info.value).startswith(f"robot file {path}: ")


def test_big_binary_missing_and_folder_files(tmp_path):
    big = write(tmp_path, "# " + "x" * robot_file.MAX_FILE_BYTES + "\n" + ARM, "big.toml")
    binary = tmp_path / "bin.toml"
    binary.write_bytes(b"\xff\xfe" + ARM.encode())
    for path, message in (
        (big, "larger than 1024 KiB"),
        (binary, "not UTF-8 text"),
        (tmp_path / "none.toml", "no such file"),
        (tmp_path, "is a folder"),
    ):
        with pytest.raises(UsageError, match=message):
            robots.resolve(path if path != tmp_path else str(tmp_path) + "/")


def test_kin_on_a_bad_file_is_one_line_and_exit_2(tmp_path, capsys):
    path = write(tmp_path, ARM.replace("d = 0.4", "d = 0.4\nd_offset = 1"))
    code, out, err = cli(capsys, "kin", str(path))
    assert code == 2 and out == "" and err.count("\n") == 1
    assert f"robot file {path}: joint 1 ('q1'): unknown key 'd_offset'" in err


def test_the_package_robots_are_files_that_ship_in_the_package():
    files = robot_file.builtin_files()
    assert set(files) == set(robots.ROBOTS) == {"rrp", "elbow", "stanford", "scara", "leg"}
    for name, spec in robots.ROBOTS.items():
        assert spec.builtin and spec.source == str(files[name]) and files[name].parent.parent.name == "kinematics"
        assert isinstance(spec.chain(), SerialChain)
    # The wheel ships everything inside the hexabot_sim package (pyproject: packages = ["hexabot_sim"]).
    pyproject = (Path(__file__).resolve().parents[2] / "pyproject.toml").read_text()
    assert 'packages = ["hexabot_sim"]' in pyproject


def test_the_leg_file_has_report_000s_foot_row():
    spec = robots.get("leg")
    (foot,) = spec.fixed_rows({"l3": 0.12})
    assert (foot.name, foot.a, foot.alpha, foot.d, foot.theta) == ("foot", 0.12, 0.0, 0.0, 0.0)
    np.testing.assert_array_equal(spec.chain({"l3": 0.12}).tool[:3, 3], [0.12, 0.0, 0.0])


def test_a_name_or_a_path_resolves(tmp_path):
    assert robots.resolve("scara") is robots.ROBOTS["scara"]
    assert robots.resolve(write(tmp_path, ARM)).name == "textbook-arm"
    with pytest.raises(UsageError, match="unknown robot 'puma'; known: rrp, elbow, stanford, scara, leg, or the path"):
        robots.resolve("puma")


def test_a_fifo_or_a_device_is_refused_at_once_not_waited_on(tmp_path):
    fifo = tmp_path / "pipe.toml"
    os.mkfifo(fifo)  # no writer: a blocking open would wait forever
    for path in (fifo, Path(os.devnull)):
        with pytest.raises(UsageError, match=r"not a regular file \(a pipe or a device\)"):
            robot_file.read(path)
    with pytest.raises(UsageError, match="is a folder, not a file"):
        robot_file.read(tmp_path)


@pytest.mark.parametrize("value", ["[" * 5000 + "]" * 5000, "{a=" * 5000 + "1" + "}" * 5000])
def test_deeply_nested_toml_is_one_line_not_a_recursion_error(tmp_path, capsys, value):
    path = write(tmp_path, ARM + f"x = {value}\n")
    code, out, err = cli(capsys, "kin", str(path))
    assert code == 2 and out == "" and err.count("\n") == 1
    assert "not valid TOML: arrays or tables nested too deeply" in err


def test_a_byte_order_mark_is_read_as_params_read_config_reads_it(tmp_path):
    spec = robot_file.read(write(tmp_path, "\ufeff" + ARM))
    assert spec.name == "textbook-arm" and spec.file_id is not None


def test_lengths_set_to_zero_are_checked_like_the_files_own(tmp_path, capsys):
    """--set L=0 (a length with zero = true) made a chain that is a point: kin "solved" every target with any q and
    export wrote its model; the file's own all-zero table was already refused."""
    text = ARM.replace("[[joints]]", "[lengths]\nL = { value = 0.3, zero = true }\n[[joints]]", 1)
    text = text.replace("d = 0.4", 'd = "L"').replace("a = 0.3", 'a = "L"').replace("xyz = [0.0, 0.0, 0.1]", "")
    text = text.replace('type = "prismatic"', 'type = "revolute"').replace("d = 0.1", "d = 0.0")
    text = text.replace("lower = 0.0\nupper = 0.2\n", "")
    path = write(tmp_path, text)
    assert robot_file.read(path).chain({"L": 0.2}).n == 3
    for argv in (["kin", str(path), "--set", "L=0", "--target", "0,0,0"],
                 ["export", str(path), "--set", "L=0", "--mjcf", str(tmp_path / "out.xml")]):  # fmt: skip
        code, out, err = cli(capsys, *argv)
        assert code == 2 and out == "" and err.count("\n") == 1 and "the tool point never moves" in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["arm.toml"]


@pytest.mark.parametrize(
    ("value", "message"),
    [("1" + "0" * 400, "'a' must be a finite number [m]; got 1000"),
     ("1" + "0" * 5000, "not valid TOML: an integer of more than 4300 digits")],
)  # fmt: skip
def test_an_integer_beyond_a_float_is_one_line_not_an_internal_error(tmp_path, capsys, value, message):
    """TOML integers have any number of digits: a = 1e400 written out was an OverflowError in math.isfinite, and
    one of 5,000 digits a ValueError from tomllib (exit 1, "internal error")."""
    path = write(tmp_path, ARM.replace("a = 0.3", f"a = {value}", 1))
    code, out, err = cli(capsys, "kin", str(path))
    assert code == 2 and out == "" and err.count("\n") == 1 and message in err, err
    assert "internal error" not in err


def test_the_smallest_mass_allowed_makes_a_model_mujoco_loads(tmp_path, capsys):
    """mass = 1e-12 kg scaled a link's inertia below MuJoCo's minimum: export wrote an MJCF that MuJoCo refused to
    load ("inertia must have positive eigenvalues") and arm-track ended in an internal error."""
    import mujoco

    text = ARM.replace("theta = 0.0\n", "theta = 0.0\nmass = 0.0001\n")
    assert text.count("mass = ") == 3
    code, _, err = cli(capsys, "export", str(write(tmp_path, text)), "--mjcf", str(tmp_path / "light.xml"))
    assert code == 0, err
    mujoco.MjModel.from_xml_path(str(tmp_path / "light.xml"))
    code, out, err = cli(capsys, "export", str(write(tmp_path, text.replace("0.0001", "1e-12"))), "--mjcf",
                         str(tmp_path / "lighter.xml"))  # fmt: skip
    assert code == 2 and out == "" and err.count("\n") == 1 and "'mass' must be 0.0001 to 1000 kg; got 1e-12" in err
    assert not (tmp_path / "lighter.xml").exists()


@pytest.mark.parametrize("key", ["x" + ".a" * 1000, '"x"' + ' . "a"' * 1000, "[" + "a." * 1000 + "b]"])
def test_a_dotted_key_of_many_parts_is_refused_before_tomllib_reads_it(tmp_path, capsys, key):
    """tomllib's time and memory grow with the square of a key's depth: a 600 KB file with one key of 300,000 parts
    ran 7 minutes and took 24 GB before it was killed. Refused at once (1,000 parts here: tomllib reads those)."""
    path = write(tmp_path, ARM + (f"{key}\n" if key.startswith("[") else f"{key} = 1\n"))
    code, out, err = cli(capsys, "kin", str(path))
    assert code == 2 and out == "" and err.count("\n") == 1, err
    assert f"robot file {path}: line 32: a dotted key of more than 32 parts; a robot file's keys have at most 3" in err
    assert not params.deep_key_line(ARM + 'x.y.z = "a.b.c.d" # 1.2.3\nhips = [[0.1, 0.2], [1.5, 2.5]]\n')


def test_lengths_set_that_empty_a_slides_range_are_refused_naming_the_file(tmp_path, capsys):
    """lower = "off", upper = "L": --set off=0.3 (= L) made a zero-width range the file itself refuses, and --set
    off=0.5 was "joint 'q3': lower limit 0.5 exceeds upper limit 0.3", naming neither the file nor the rule."""
    text = ARM.replace("[[joints]]", "[lengths]\nL = 0.3\noff = { value = 0.05, zero = true }\n[[joints]]", 1)
    path = write(tmp_path, text.replace("lower = 0.0\nupper = 0.2", 'lower = "off"\nupper = "L"'))
    assert robot_file.read(path).chain({"off": 0.29}).joints[2].upper == 0.3
    for value in ("0.3", "0.5"):
        code, out, err = cli(capsys, "kin", str(path), "--set", f"off={value}")
        assert code == 2 and out == "" and err.count("\n") == 1
        assert f"robot file {path}: joint 3 ('q3'): with these lengths its range is empty: 'lower' ({value} m)" in err
