"""Parameter resolution: defaults, config files, --set, and the messages for bad values."""

import dataclasses
from pathlib import Path

import pytest

from hexabot_sim import params, registry
from hexabot_sim.errors import UsageError
from hexabot_sim.robots.pendulum.pendulum import PendulumParams


def test_layers_apply_in_order():
    p = params.resolve(PendulumParams, {"damping": 0.0}, {"mass": 0.2, "damping": 0.5}, {"mass": "0.3"})
    assert (p.mass, p.damping, p.length) == (0.3, 0.5, 0.3)


def test_scenario_defaults():
    undamped = registry.get("pendulum-undamped")
    p = params.resolve(undamped.params_type, undamped.defaults)
    assert p.damping == 0 and p.stiffness == 0 and p.theta0_deg == 90
    spring = registry.get("pendulum")
    p = params.resolve(spring.params_type, spring.defaults)
    assert p.damping == 0.01 and p.stiffness > 0 and p.target_deg == 30


@pytest.mark.parametrize(
    ("overrides", "fragment"),
    [
        ({"dampin": "1"}, "unknown parameter 'dampin'; known: mass, length"),
        ({"mass": "abc"}, "'mass' must be a number with 0.001 <= mass <= 1000 kg; got 'abc'"),
        ({"mass": "nan"}, "'mass' must be a number with 0.001 <= mass <= 1000 kg; got 'nan'"),
        ({"mass": "inf"}, "'mass' must be a number with 0.001 <= mass <= 1000 kg; got 'inf'"),
        ({"mass": "0"}, "'mass' must be a number with 0.001 <= mass <= 1000 kg; got '0'"),
        ({"damping": "-0.1"}, "'damping' must be a number with 0 <= damping <= 1e+06 N*m*s/rad"),
        ({"duration": "0"}, "'duration' must be a number with 0 < duration <= 86400 s"),
        ({"timestep": "-1e-3"}, "'timestep' must be a number with 1e-06 <= timestep <= 0.1 s"),
        ({"theta0_deg": "-inf"}, "'theta0_deg' must be a number with -720 <= theta0_deg <= 720 deg"),
        ({"integrator": "rk45"}, "'integrator' must be one of RK4, Euler, implicit, implicitfast"),
        ({"integrator": 4}, "'integrator' must be one of RK4, Euler, implicit, implicitfast; got 4"),
        ({"timestep": "0.1", "duration": "0.05"}, "'timestep' must not exceed 'duration'"),
        ({"radius": "0.5"}, "'radius' must be smaller than 'length'"),
        ({"mass": True}, "'mass' must be a number with 0.001 <= mass <= 1000 kg; got True"),
        ({"mass": 10**400}, "got an integer of 401 digits"),
        ({"mass": "x" * 200}, "got 'xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx..."),
        # float() reads these as 10 and 5: a slip for "1,0" or "1.0", and digits of another script
        ({"damping": "1_0"}, "'damping' must be a number with 0 <= damping <= 1e+06 N*m*s/rad; got '1_0'"),
        ({"mass": "\uff15"}, "'mass' must be a number with 0.001 <= mass <= 1000 kg; got '\uff15'"),
    ],
)
def test_bad_values_name_the_problem(overrides, fragment):
    with pytest.raises(UsageError, match=None) as info:
        params.resolve(PendulumParams, {}, overrides)
    assert fragment in str(info.value)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("item", ["mass", "=1", ""])
def test_malformed_assignment(item):
    with pytest.raises(UsageError, match="expected name=value"):
        params.parse_assignments([item])


def test_config_file(tmp_path):
    path = tmp_path / "run.toml"
    path.write_text("mass = 0.25\nintegrator = 'Euler'\n")
    assert params.read_config(path) == {"mass": 0.25, "integrator": "Euler"}
    path.write_text("[params]\nlength = 0.5\n")
    assert params.read_config(path) == {"length": 0.5}
    path.write_text("mass = 0.25\n[params]\nlength = 0.5\n")  # top-level lines and [params] together
    assert params.read_config(path) == {"mass": 0.25, "length": 0.5}


def test_negative_zero_and_whole_numbers():
    p = params.resolve(PendulumParams, {}, {"damping": "-0", "stiffness": -0.0})
    assert str(p.damping) == "0.0" and str(p.stiffness) == "0.0"
    from hexabot_sim.robots.leg.step import LegStepParams

    assert params.resolve(LegStepParams, {}, {"substeps": "2.0"}).substeps == 2
    with pytest.raises(UsageError, match="'substeps' must be a whole number"):
        params.resolve(LegStepParams, {}, {"substeps": "2.5"})


@pytest.mark.parametrize(
    ("text", "fragment"),
    [("mass = = 1", "is not valid TOML"), ("[pendulum]\nmass = 1", "unexpected table [pendulum]")],
)
def test_bad_config_file(tmp_path, text, fragment):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(UsageError) as info:
        params.read_config(path)
    assert fragment in str(info.value)


def test_missing_config_file(tmp_path):
    with pytest.raises(UsageError, match="not found"):
        params.read_config(tmp_path / "nope.toml")


def test_every_parameter_has_unit_and_doc():
    for scenario in registry.SCENARIOS.values():
        for name, (info, _) in params.infos(scenario.params_type).items():
            assert info.doc, name
        assert dataclasses.is_dataclass(scenario.params_type)
        assert set(scenario.defaults) <= set(params.infos(scenario.params_type))


def test_exact_python_numbers_are_accepted():
    """From the Python API: Fraction and Decimal are numbers too (they were refused as "must be a number")."""
    import decimal
    import fractions

    p = params.resolve(PendulumParams, {}, {"duration": decimal.Decimal("2.5"), "damping": fractions.Fraction(1, 50)})
    assert (p.duration, p.damping) == (2.5, 0.02)
    with pytest.raises(UsageError, match="got Decimal"):
        params.resolve(PendulumParams, {}, {"duration": decimal.Decimal("NaN")})


# --- a parameter that is a built-in name or a file's path (arm-track's robot) ------------------------------------


def _name_or_file_class():
    def check(path):
        if Path(path).read_text() != "ok":
            raise UsageError(f"file {path}: not ok")

    kind = params.NameOrFile(("alpha", "beta"), "thing file (.txt)", check)

    @dataclasses.dataclass(frozen=True)
    class Things:
        thing: str = params.param("alpha", "", "a thing", name_or_file=kind)

    return Things


def test_name_or_file_takes_a_name_in_any_case_or_a_good_file_as_given(tmp_path):
    cls = _name_or_file_class()
    assert params.resolve(cls, {}, {"thing": " BETA "}).thing == "beta"
    good = tmp_path / "good.txt"
    good.write_text("ok")
    assert params.resolve(cls, {}, {"thing": str(good)}).thing == str(good)
    assert params.resolve(cls, {}, {"thing": good}).thing == str(good)  # a Path from Python
    allowed = params.describe_range(params.infos(cls)["thing"][0])
    assert allowed == "one of alpha, beta, or the path of a thing file (.txt)"


@pytest.mark.parametrize(
    ("value", "fragment"),
    [
        ("gamma", "must be one of alpha, beta, or the path of a thing file (.txt); got 'gamma' (no such name or file)"),
        (5, "got 5"),
        ("", "got ''"),
        ("a\0b", "(no such name or file)"),
        ("x" * 5000, "(no such name or file)"),
        ("BAD", "parameter 'thing': file "),
    ],
)
def test_name_or_file_refusals_are_one_line(tmp_path, value, fragment):
    bad = tmp_path / "BAD"
    bad.write_text("no")
    if value == "BAD":
        value = str(bad)
    with pytest.raises(UsageError) as info:
        params.resolve(_name_or_file_class(), {}, {"thing": value})
    assert fragment in str(info.value) and "\n" not in str(info.value)


def test_a_config_names_its_files_relative_to_its_own_folder(tmp_path, monkeypatch):
    """A schedule or robot file named by a config is read beside the config (a config and its files travel
    together); a built-in name stays a name; a file that is not there is read from the working folder, and one in
    neither place is refused naming both."""
    cls = registry.get("hexabot-walk").params_type
    folder = tmp_path / "study"
    folder.mkdir()
    (folder / "sched.csv").write_text("t, vx, vy, yaw_rate\n0, 0.05, 0, 0\n")
    (folder / "hexabot").write_text("a file named like the built-in robot\n")
    config = folder / "walk.toml"
    config.write_text('schedule = "sched.csv"\nrobot = "hexabot"\nwaypoints = "elsewhere.csv"\n')
    monkeypatch.chdir(tmp_path)
    (tmp_path / "elsewhere.csv").write_text("x, y\n0.3, 0\n")  # in the working folder only
    data = params.read_config(Path("study/walk.toml"), cls)
    assert data == {"schedule": str(Path("study") / "sched.csv"), "robot": "hexabot", "waypoints": "elsewhere.csv"}
    assert params.read_config(config) == {"schedule": "sched.csv", "robot": "hexabot", "waypoints": "elsewhere.csv"}
    (tmp_path / "elsewhere.csv").unlink()
    with pytest.raises(UsageError, match=r"waypoints file 'elsewhere.csv' \(named in config file 'study/walk.toml'\) "
                       r"is in neither 'study' nor the working folder"):  # fmt: skip
        params.read_config(Path("study/walk.toml"), cls)


def test_a_file_name_from_home_is_expanded_in_a_config_and_in_set(tmp_path, monkeypatch):
    """`~/file` in a config file or after `--set name=` (where no shell expands it) is the user's home's file: it was
    looked for beside the config, or taken literally, and refused."""
    cls = registry.get("hexabot-walk").params_type
    home, study = tmp_path / "home", tmp_path / "study"
    home.mkdir()
    study.mkdir()
    monkeypatch.setenv("HOME", str(home))
    (home / "sched.csv").write_text("t, vx, vy, yaw_rate\n0, 0.05, 0, 0\n")
    (study / "walk.toml").write_text('schedule = "~/sched.csv"\n')
    data = params.read_config(study / "walk.toml", cls)
    assert data == {"schedule": "~/sched.csv"}
    for layer in (data, {"schedule": "~/sched.csv"}):  # the config's value, and --set's
        resolved = params.resolve(cls, {}, layer)
        assert [list(row[:4]) for row in resolved.schedule] == [[0.0, 0.05, 0.0, 0.0]]
    with pytest.raises(UsageError, match="schedule"):
        params.resolve(cls, {}, {"schedule": "~/missing.csv"})


@pytest.mark.slow
def test_run_with_a_config_from_another_folder_reads_the_schedule_beside_it(tmp_path, monkeypatch):
    from hexabot_sim import api

    folder = tmp_path / "study"
    folder.mkdir()
    (folder / "sched.csv").write_text("t, vx, vy, yaw_rate\n0, 0.05, 0, 0\n2, 0.08, 0, 0\n")
    (folder / "walk.toml").write_text('schedule = "sched.csv"\nduration = 2.5\n')
    monkeypatch.chdir(tmp_path)  # the schedule is not in the working folder
    result = api.run("hexabot-walk", config="study/walk.toml")
    assert [list(row[:4]) for row in result.params["schedule"]] == [[0.0, 0.05, 0.0, 0.0], [2.0, 0.08, 0.0, 0.0]]


def test_a_linked_config_finds_its_files_beside_the_link_or_else_beside_the_file_it_links_to(tmp_path, monkeypatch):
    """A config reached through a symbolic link: its files are looked for beside the link, then beside the real
    file (the link's folder alone lost them, or silently took the working folder's file of the same name)."""
    cls = registry.get("hexabot-walk").params_type
    real, linked = tmp_path / "configs", tmp_path / "study"
    real.mkdir()
    linked.mkdir()
    (real / "walk.toml").write_text('schedule = "sched.csv"\nwaypoints = "course.csv"\n')
    (real / "sched.csv").write_text("t, vx, vy, yaw_rate\n0, 0.05, 0, 0\n")
    (real / "course.csv").write_text("x, y\n0.3, 0\n")
    (linked / "course.csv").write_text("x, y\n0.2, 0\n")  # beside the link: taken first
    (linked / "walk.toml").symlink_to(real / "walk.toml")
    monkeypatch.chdir(tmp_path)
    (tmp_path / "sched.csv").write_text("t, vx, vy, yaw_rate\n0, 0.09, 0, 0\n")  # the working folder's: not taken
    data = params.read_config(Path("study/walk.toml"), cls)
    assert data == {"schedule": str(real / "sched.csv"), "waypoints": str(Path("study") / "course.csv")}


def test_a_parameter_set_twice_is_refused_and_an_empty_value_goes_to_its_check(tmp_path, capsys):
    """--set mass=1 --set mass=2 silently ran with 2; `--set name=` was 'malformed', so a config file's schedule
    could not be cleared from the command line (`list`: 'empty: one command throughout')."""
    from hexabot_sim.__main__ import main

    with pytest.raises(UsageError, match=r"parameter 'mass' is given twice with --set \('1' and '2'\): give it once"):
        params.parse_assignments(["mass=1", "mass=2"])
    assert params.parse_assignments(["mass=1", "mass=1", "schedule="]) == {"mass": "1", "schedule": ""}
    with pytest.raises(UsageError, match="malformed --set"):
        params.parse_assignments(["=1"])
    schedule = tmp_path / "s.csv"
    schedule.write_text("t, vx, vy, yaw_rate\n0, 0.05, 0, 0\n")
    config = tmp_path / "walk.toml"
    config.write_text(f'schedule = "{schedule.name}"\nduration = 2\n')
    out = tmp_path / "out"
    argv = ["run", "hexabot-walk", "--config", str(config), "--set", "schedule=", "--no-plots", "--out", str(out)]
    assert main(argv) == 0, capsys.readouterr().err
    import json

    assert json.loads((out / "run.json").read_text())["params"]["schedule"] in ("", None, [])
    assert main(["run", "pendulum", "--set", "mass=", "--out", str(tmp_path / "p")]) == 2
    assert "'mass' must be a number with" in capsys.readouterr().err
