"""Parameter ranges, unit-trap hints, run-cost limits, hostile config files and divergence causes: exit 2, one line."""

import math
import os
import random

import numpy as np
import pytest

from hexabot_sim import params, registry
from hexabot_sim.__main__ import main
from hexabot_sim.control.resolved_rate import MIN_DAMPING, ResolvedRateController, ResolvedRateGains
from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics.leg import LegGeometry
from hexabot_sim.robots.leg import step as leg
from hexabot_sim.robots.pendulum import closed_forms, pendulum


def refused(capsys, tmp_path, *argv, code=2):
    """Runs the CLI expecting one line on stderr, exit `code`, and nothing written; returns the line."""
    before = set(tmp_path.iterdir())
    out_dir = tmp_path / "out"
    assert main(["run", *argv, "--out", str(out_dir), "--no-plots"]) == code
    _, err = capsys.readouterr()
    assert err.startswith("hexabot-sim: error: ") and err.count("\n") == 1 and "Traceback" not in err, err
    assert set(tmp_path.iterdir()) == before, "something was written"
    return err


# --- the examples of issue 8 -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("argv", "fragments"),
    [
        (["pendulum", "--set", "length=1e308"], ["'length'", "0.01 <= length <= 100 m", "got '1e308'"]),
        (["pendulum", "--set", "radius=1e-300"], ["'radius'", "0.0001 <= radius <= 10 m", "got '1e-300'"]),
        (["leg-step", "--set", "max_joint_speed=1e200"], ["max_joint_speed <= 100 rad/s", "got '1e200'"]),
        (["leg-step", "--set", "substeps=1e308"], ["1 <= substeps <= 1000", "got '1e308'"]),
        (["leg-sweep", "--set", "periods=1e6"], ["0 < periods <= 100", "got '1e6'"]),
        (["leg-sweep", "--set", "omegas=1e-9"], ["0.01 <= omegas <= 20 rad/s", "got '1e-9'"]),
        (["leg-step", "--set", "amplitude=100"], ["-1 <= amplitude <= 1 m/s", "did you mean 100 mm/s = 0.1 m/s?"]),
        (["leg-sweep", "--set", "amplitudes=10,50,100"], ["did you mean 10 mm/s = 0.01 m/s?"]),
        (["leg-step", "--set", "omega=30"], ["did you mean 30 deg/s = 0.523599 rad/s?"]),
        (["leg-step", "--set", "start_x=50"], ["did you mean 50 mm = 0.05 m?"]),
        (["leg-step", "--set", "start_z=-80"], ["did you mean -80 mm = -0.08 m?"]),
        (["leg-step", "--set", "max_joint_speed=300"], ["did you mean 300 deg/s = 5.23599 rad/s?"]),
        (["pendulum", "--set", "length=300"], ["did you mean 300 mm = 0.3 m?"]),
        (["rrp-velocity", "--set", "a2=1000"], ["did you mean 1000 mm = 1 m?"]),
        (["leg-step", "--set", "start_x=5"], ["-3 <= start_x <= 3 m; got '5'\n"]),  # no mm hint
        (["leg-step", "--set", "amplitude=2"], ["-1 <= amplitude <= 1 m/s; got '2'\n"]),
        (["leg-step", "--set", "start_x=-0.1"], ["outside the workspace of the leg"]),
        (["leg-step", "--set", "timestep=0.05"], ["'task_gain' * 'timestep' must be <= 1"]),
        (["leg-step", "--set", "omega=20", "--set", "timestep=0.04", "--set", "task_gain=1"], ["'omega' * 'timestep'"]),
        (["pendulum", "--set", "integrator=rk45"], ["one of RK4, Euler, implicit, implicitfast", "got 'rk45'"]),
    ],
)
def test_bad_values_exit_2_with_one_line(capsys, tmp_path, argv, fragments):
    err = refused(capsys, tmp_path, *argv)
    for fragment in fragments:
        assert fragment in err, err


@pytest.mark.parametrize(
    ("argv", "fragments"),
    [
        (
            ["pendulum", "--set", "timestep=1e-6", "--set", "duration=5000"],
            ["would take 5e+09 steps", "GB of output", "in memory", "the limit is 2e+07 steps", "raise 'timestep'"],
        ),
        (["pendulum", "--set", "duration=8000"], ["would take 8e+06 steps", "GB in memory"]),
        (["leg-step", "--set", "substeps=1000", "--set", "duration=1000"], ["would take 1e+09 steps", "'substeps'"]),
        (["rrp-velocity", "--set", "duration=5000"], ["would take 5e+06 steps", " h)", "1 h"]),
        (
            ["leg-sweep", "--set", "periods=100", "--set", "timestep=1e-4", "--set", "workers=1"],
            ["would take 3.61e+08 steps", "fewer cells"],
        ),
        (["leg-sweep", "--set", "amplitudes=" + ",".join(f"0.0{i:02d}" for i in range(1, 22)), "--set",
          "omegas=" + ",".join(f"1.{i:02d}" for i in range(20))],
         ["at most 400 cells", "21 x 20 = 420"]),
        # A video is estimated too (rendering is software OpenGL here): 4.5 h of 4K frames at 240 fps.
        (["pendulum", "--set", "duration=600", "--video", "--size", "3840x2160", "--fps", "240"],
         ["the video would take ~4.5 h to render (144001 frames of 3840x2160 at the preview preset)", "lower --fps"]),
        (["hexabot-walk", "--set", "duration=600", "--video", "--quality", "high", "--size", "1920x1080",
          "--fps", "60"], ["~1.4 h to render", "or use --quality preview"]),
    ],
)  # fmt: skip
def test_runs_too_large_are_refused_with_the_numbers(capsys, tmp_path, argv, fragments):
    err = refused(capsys, tmp_path, *argv)
    for fragment in fragments:
        assert fragment in err, err


def test_integrator_and_choices_are_case_insensitive():
    p = params.resolve(pendulum.PendulumParams, {}, {"integrator": "rk4"})
    assert p.integrator == "RK4"
    p = params.resolve(leg.LegStepParams, {}, {"integrator": " IMPLICITFAST ", "mode": "Dynamic", "profile": "SINE"})
    assert (p.integrator, p.mode, p.profile) == ("implicitfast", "dynamic", "sine")
    assert params.resolve(leg.LegStepParams, {}, {"mode": "Kinematic"}).mode == "kinematic"


# --- every parameter of every scenario: just outside refused, just inside accepted -------------------------

# Other parameters a bound needs to pass the cross-checks (radius < length, task_gain * timestep <= 1,
# the run-cost limits, a reachable start point). Keyed by (params class, parameter, "lo" or "hi").
COMPANIONS = {
    ("PendulumParams", "length", "lo"): {"radius": 1e-4},
    ("PendulumParams", "radius", "hi"): {"length": 100},
    ("PendulumParams", "timestep", "lo"): {"duration": 1},
    ("PendulumParams", "duration", "lo"): {"timestep": 1e-6},
    ("PendulumParams", "duration", "hi"): {"timestep": 0.1},
    ("LegStepParams", "timestep", "lo"): {"duration": 1},
    ("LegStepParams", "timestep", "hi"): {"task_gain": 10},
    ("LegStepParams", "task_gain", "hi"): {"timestep": 1e-4},
    ("LegStepParams", "duration", "hi"): {"timestep": 0.05, "task_gain": 10},
    ("LegStepParams", "omega", "hi"): {"timestep": 1e-3},
    ("LegSweepParams", "timestep", "lo"): {"amplitudes": "0.05", "omegas": "3", "periods": 0.1},
    ("LegSweepParams", "timestep", "hi"): {"task_gain": 10},
    ("LegSweepParams", "task_gain", "hi"): {"timestep": 1e-4, "amplitudes": "0.05"},
    ("LegSweepParams", "periods", "lo"): {"timestep": 1e-6, "omegas": "0.01", "amplitudes": "0.05"},
    ("LegSweepParams", "periods", "hi"): {"amplitudes": "0.05", "omegas": "1"},
    ("LegSweepParams", "omegas", "lo"): {"amplitudes": "0.05"},
    ("LegSweepParams", "substeps", "hi"): {"mode": "dynamic", "amplitudes": "0.05", "omegas": "3", "periods": 1},
    ("LegStepParams", "substeps", "hi"): {"duration": 1},
    **{
        (cls, length, side): start
        for cls in ("LegStepParams", "LegSweepParams")
        for (length, side), start in {
            ("l1", "hi"): {"start_x": 1.05},
            ("l2", "hi"): {"start_x": 1.05, "start_z": 0.0},
            ("l2", "lo"): {"start_z": -0.1},
            ("l3", "hi"): {"start_z": -1.0},
            ("l3", "lo"): {"start_z": -0.1},
        }.items()
    },  # a start point the leg of that length reaches
    ("RrpVelocityParams", "timestep", "lo"): {"duration": 1},
    ("RrpVelocityParams", "duration", "lo"): {"timestep": 1e-6},
    ("RrpVelocityParams", "duration", "hi"): {"timestep": 0.1},
}
# A foot start on a bound of the +-3 m box is mostly outside the workspace: with the other two
# coordinates chosen to reach it where that is possible, else it may only fail the workspace check.
START_AT_BOUND = {
    ("start_x", "hi"): {"start_y": 0.0, "start_z": 0.0},
    ("start_y", "hi"): {"start_x": 0.0, "start_z": 0.0},
    ("start_y", "lo"): {"start_x": 0.0, "start_z": 0.0},
    ("start_z", "lo"): {"start_x": 0.0, "start_y": 0.0},
}
CHECKED_HERE = {"PendulumParams", "LegStepParams", "LegSweepParams", "RrpVelocityParams"}  # COMPANIONS cover them
BASE = {"LegSweepParams": {"workers": 1}}  # the memory estimate of a sweep depends on the worker count


def _bounds():
    classes = {s.params_class: s for s in registry.SCENARIOS.values()}
    for cls_name, scenario in sorted(classes.items()):
        cls = scenario.params_type
        for name, (info, default) in params.infos(cls).items():
            if not info.text and info.table is None:  # a table's rows are checked by its reader
                yield pytest.param(scenario, name, info, type(default), id=f"{cls_name}.{name}")


def _outside_inside(info, kind):
    """(just outside, just inside) for the lower and for the upper bound."""
    if kind is int:
        lo, hi = info.ge, info.le
        return {"lo": (lo - 1, lo), "hi": (hi + 1, hi)}
    out = {}
    if info.ge is not None:
        out["lo"] = (math.nextafter(info.ge, -math.inf), info.ge)
    else:
        out["lo"] = (info.gt, info.gt + max(1e-6, abs(info.gt) * 1e-9))
    if info.le is not None:
        out["hi"] = (math.nextafter(info.le, math.inf), info.le)
    else:
        out["hi"] = (info.lt, info.lt - max(1e-6, abs(info.lt) * 1e-9))
    return out


@pytest.mark.parametrize(("scenario", "name", "info", "kind"), list(_bounds()))
def test_every_parameter_range(scenario, name, info, kind):
    cls = scenario.params_type
    for side, (outside, inside) in _outside_inside(info, kind).items():
        extra = {**BASE.get(cls.__name__, {}), **COMPANIONS.get((cls.__name__, name, side), {})}
        extra |= START_AT_BOUND.get((name, side), {})
        with pytest.raises(UsageError) as bad:
            params.resolve(cls, scenario.defaults, extra, {name: repr(outside)})
        message = str(bad.value)
        what = "a whole number" if kind is int else "a number"
        assert f"parameter '{name}' must be {what} with" in message and "\n" not in message, message
        assert params.describe_range(info, name) in message
        if cls.__name__ not in CHECKED_HERE:  # a newer scenario: its own tests cover its cross-checks
            info.contains(inside) or pytest.fail(f"{name}: {inside} should be inside")
            continue
        try:
            p = params.resolve(cls, scenario.defaults, extra, {name: repr(inside)})
        except UsageError as e:  # only a start point on the box's edge may be out of the leg's reach
            assert name.startswith("start_") and "outside the workspace of the leg" in str(e), (side, str(e))
            continue
        value = getattr(p, name)
        if (cls.__name__, name, inside) == ("LegStepParams", "duration", 0.0):
            value = 0.0  # 0 stands for two periods of the command
        assert (value[0] if isinstance(value, tuple) else value) == inside, side


def test_every_number_has_a_range_and_every_text_choices():
    for scenario in registry.SCENARIOS.values():
        for name, (info, default) in params.infos(scenario.params_type).items():
            if info.choices is not None:
                assert default in info.choices, name
            elif info.table is not None:  # a table (a CSV file or rows): empty by default, and its reader takes that
                assert default == () and info.table[1](name, default) == (), name
            elif info.name_or_file is not None:
                assert default in info.name_or_file.names, name
            else:
                assert (info.ge is None) != (info.gt is None) and (info.le is None) != (info.lt is None), name
                values = default if isinstance(default, tuple) else (default,)
                assert all(info.contains(v) for v in values), name
    with pytest.raises(ValueError, match="one lower"):
        params.param(1.0, "m", "no upper bound", ge=0.0)


def test_describe_range():
    info = params.ParamInfo("kg", "mass", gt=0.0, le=1000.0)
    assert params.describe_range(info, "mass") == "0 < mass <= 1000 kg"
    assert params.describe_range(params.ParamInfo("1", "n", ge=1, lt=10)) == "1 <= value < 10"
    assert params.describe_range(params.ParamInfo("", "x", choices=("a", "b"))) == "one of a, b"


# --- fuzzing: whatever the value, a UsageError of one short line or a valid object --------------------------

ODD = [
    math.nan, math.inf, -math.inf, -0.0, 1e308, -1e308, 1e-308, 5e-324, 10**400, -(10**400), 2**63, True, False,
    None, [], [1.0], {}, "", " ", "nan", "-inf", "-0", "1e999", "9" * 5000, "0x10", "abc", "rk4", "\n", ",", "0.1,",
    "1,2", 1000, 64.5, -1e-300,
]  # fmt: skip


def test_fuzz_resolve_never_crashes():
    rng = random.Random(8)
    for scenario in registry.SCENARIOS.values():
        cls = scenario.params_type
        names = list(params.infos(cls))
        for _ in range(150):
            layer = {}
            for name in rng.sample(names, rng.randint(1, 3)):
                r = rng.random()
                layer[name] = rng.choice(ODD) if r < 0.5 else 10 ** rng.uniform(-12, 12) * rng.choice((1, -1))
            try:
                p = params.resolve(cls, scenario.defaults, BASE.get(cls.__name__, {}), layer)
            except UsageError as e:
                assert "\n" not in str(e) and len(str(e)) < 400, str(e)
                continue
            for name in names:
                values = getattr(p, name) if isinstance(getattr(p, name), tuple) else (getattr(p, name),)
                assert all(not isinstance(v, float) or (math.isfinite(v) and str(v) != "-0.0") for v in values)


# --- config files -------------------------------------------------------------------------------------------


def _fifo(path):
    os.mkfifo(path)
    return path


@pytest.mark.parametrize(
    ("make", "fragment"),
    [
        (lambda p: p.write_text("mass = " + "[" * 100_000 + "]" * 100_000), "nested too deeply"),
        (lambda p: p.write_text("a = " + "{b = " * 5000 + "1" + "}" * 5000), "nested too deeply"),
        (lambda p: p.write_text("mass = 0.1\n" + "# padding\n" * 200_000), "larger than 1024 KiB"),
        (lambda p: p.write_text('mass = "' + "x" * 2_000_000 + '"'), "larger than 1024 KiB"),
        (lambda p: p.write_bytes(bytes(range(256)) * 20), "not UTF-8"),
        (lambda p: p.write_text("mass = " + "9" * 5000), "not a parameter file: an integer of more than 4300 digits"),
        (lambda p: p.write_text("mass = " + "9" * 400), "'mass' must be a number"),
        # tomllib's time and memory grow with the square of a key's depth (300,000 parts: 7 minutes, 24 GB, killed)
        (lambda p: p.write_text("mass = 0.1\na" + ".a" * 1000 + " = 1\n"), "line 2: a dotted key of more than 32"),
        (
            lambda p: p.write_text("mass = 1979-05-27"),
            "'mass' must be a number with 0.001 <= mass <= 1000 kg; got the date 1979-05-27",
        ),
        (lambda p: p.write_text("mass = 0.2\n[params]\nmass = 0.3\n"), "'mass' is given both at the top level and"),
        (lambda p: p.write_text("[[params]]\nmass = 0.3\n"), "'params' must be a table"),
        (lambda p: p.write_text("[pendulum]\nmass = 0.3\n"), "unexpected table [pendulum]"),
        (lambda p: p.mkdir(), "is a directory"),
        (_fifo, "not a regular file"),
        (lambda p: p.symlink_to("/dev/zero"), "not a regular file"),
    ],
)
def test_hostile_config_files(capsys, tmp_path, make, fragment):
    path = tmp_path / "cfg.toml"
    make(path)
    err = refused(capsys, tmp_path, "pendulum", "--config", str(path))
    assert fragment in err, err


def test_config_dev_zero(capsys, tmp_path):
    assert "not a regular file" in refused(capsys, tmp_path, "pendulum", "--config", "/dev/zero")


# --- max_damping 0 at an exact singularity (the knee stretched on its 0 limit) ------------------------------


@pytest.mark.parametrize("max_damping", [0.0, 1e-9, 0.01])
def test_controller_at_exact_singularity_is_finite(max_damping):
    gains = ResolvedRateGains(max_damping=max_damping)
    far = (0.3, 0.0, -0.05)  # out of reach: the command pulls the stretched leg further

    controller = ResolvedRateController(
        LegGeometry(), gains, lambda t: far, (0.0, -0.3, 0.0), (-1.6, -1.6, 0.0), (1.6, 1.6, 2.8)
    )
    for k in range(200):
        out = controller.update(tuple(controller.q_cmd), k * 1e-3, 1e-3)
        assert all(math.isfinite(v) for v in out)
        assert max(abs(v) for v in out[3:]) <= gains.max_joint_speed + 1e-9
    assert controller.q_cmd[2] < 1e-5  # it sits on (or next to) the singular q3 = 0 limit
    assert MIN_DAMPING > 0


@pytest.mark.parametrize("max_damping", ["0", "1e-9"])
def test_kinematic_leg_through_the_singularity_with_no_damping(max_damping):
    p = params.resolve(
        leg.LegStepParams,
        {},
        {"mode": "kinematic", "max_damping": max_damping, "amplitude": 0.1, "omega": 0.5236, "duration": 4},
    )
    result = leg.run("leg-step", p)
    assert all(np.isfinite(column).all() for column in result.columns.values())
    assert result.metrics["singular_first_time"].value is not None


# --- the divergence message names the likely cause ---------------------------------------------------------


@pytest.mark.parametrize(
    ("argv", "fragments"),
    [
        (
            ["pendulum", "--set", "stiffness=1e6", "--set", "timestep=0.01"],
            ["diverged after t = 0.01 s", "the timestep 0.01 s is too large", "sqrt(k/I) = 1.82e+04 rad/s",
             "try a timestep <= 7.7e-05 s"],
        ),
        (
            ["pendulum", "--set", "stiffness=1e6", "--set", "mass=0.001", "--set", "length=0.01",
             "--set", "radius=0.0001"],
            ["an absurd input", "stiffness 1e+06 N*m/rad", "less than the smallest allowed (1e-06 s)"],
        ),
        (
            ["pendulum", "--set", "damping=1e4", "--set", "timestep=0.01"],
            ["an absurd input", "b/I = 3.33e+06 1/s"],
        ),
    ],
)  # fmt: skip
def test_divergence_names_the_cause(capsys, tmp_path, argv, fragments):
    err = refused(capsys, tmp_path, *argv, code=1)
    for fragment in fragments:
        assert fragment in err, err
    assert "try a smaller timestep" not in err


# --- the rest-angle search is bounded for any allowed spring ----------------------------------------------


@pytest.mark.parametrize("stiffness", [1e-300, 5e-324, 1e-9, 0.5, 1e6])
def test_equilibria_bounded(stiffness):
    mgc = 1000 * 100 * 50  # the heaviest, longest pendulum under the strongest gravity allowed
    stable = closed_forms.equilibria(stiffness, mgc, 0.5)
    assert len(stable) <= 2 * closed_forms.EQUILIBRIA_SPAN / (2 * math.pi) + 2
    for root in stable:
        assert abs(stiffness * (root - 0.5) + mgc * math.sin(root)) <= 1e-6 * mgc
    rest = closed_forms.rest_angle(stiffness, mgc, 0.5, near=12.0)
    assert rest is not None and (abs(rest - 12.0) < 2 * math.pi or rest == min(stable, key=lambda r: abs(r - 12)))


# --- issue 17: a value just past its bound is never printed as the bound ------------------------------------

_NUM = r"(-?[0-9.]+(?:e[+-]?[0-9]+)?)"


@pytest.mark.parametrize(
    "argv, pattern",
    [
        (["pendulum", "--set", "duration=0.01", "--set", "timestep=0.0100000001"],
         rf"must not exceed 'duration' \({_NUM} s\); got {_NUM}"),
        (["pendulum", "--set", "length=0.5", "--set", "radius=0.5000001"], rf"'length' \({_NUM} m\); got {_NUM}"),
        (["leg-step", "--set", "task_gain=1000.0001", "--set", "timestep=0.001"],
         rf"must be <= {_NUM} \(the foot error.* = {_NUM}$"),
        (["leg-step", "--set", "omega=10.000001", "--set", "timestep=0.05", "--set", "task_gain=1"],
         rf"must be <= {_NUM} rad .* = {_NUM} rad$"),
        (["pendulum", "--set", "duration=20000.001", "--set", "timestep=0.001"],
         rf"the limit is {_NUM} steps.*would take {_NUM} steps|would take {_NUM} steps.*the limit is {_NUM} steps"),
        (["hexabot-walk", "--set", "kerb_height=0.0480001", "--set", "stand_height=0.06"],
         rf"a {_NUM} mm kerb would hit the plate.*at most {_NUM} mm"),
        (["hexabot-walk", "--set", "slope_deg=10", "--set", f"friction={math.tan(math.radians(10)) * (1 - 1e-12)!r}"],
         rf"at least tan\(slope\) = {_NUM} to hold the feet; friction is {_NUM}"),
    ],
)  # fmt: skip
def test_a_value_just_past_its_bound_is_printed_apart_from_it(capsys, tmp_path, argv, pattern):
    """Not "must not exceed 'duration' (0.01 s); got 0.01", "= 1 ... must be <= 1", "2e+07 steps; the limit is 2e+07
    steps", "a 48 mm kerb ... at most 48 mm": every refusal prints the pair with params.apart."""
    import re

    err = refused(capsys, tmp_path, *argv).strip()
    match = re.search(pattern, err)
    assert match is not None, err
    numbers = [float(g) for g in match.groups() if g is not None]
    assert len(numbers) == 2 and numbers[0] != numbers[1], err


@pytest.mark.parametrize(
    "value, bound, toward, expected",
    [(0.5, 0.5, "down", ("0.5", "0.5")), (1000.0000001, 1000.0, "down", ("1000.0000001", "1000")),
     (0.80000001, 0.7500000000000001, "up", ("0.8", "0.75"))],
)  # fmt: skip
def test_apart_rounds_in_decimal(value, bound, toward, expected):
    """allowed() rounded in binary: 1000 to 6 digits came out as 999.99999, a radius equal to length as 0.499999999."""
    assert params.apart(value, bound, toward, least=6 if value > 1 else 3) == expected


def test_the_kin_limits_are_printed_apart_from_the_value(capsys):
    for argv, shown, bound in [
        (["kin", "leg", "--q", "-1000.0000001,0,0"], "-1000.0000001 rad", "±1000 rad"),
        (["kin", "leg", "--deg", "--q", "-57295.78,0,0"], "-57295.8 deg", "±57295.7 deg"),
        (["kin", "rrp", "--q", "0,0,100.0000001"], "100.0000001 m", "±100 m"),
        (["kin", "leg", "--target", "1000.0000001,0,0"], "1000.0000001 m", "±1000 m"),
    ]:
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert f"= {shown} is outside the allowed {bound}" in err and err.count("\n") == 1, err
    assert main(["kin", "leg", "--q", "1.5708,0,0"]) == 0  # a warning, not "1.5708 outside [.., 1.5708]"
    err = capsys.readouterr().err
    assert "coxa = 1.5708 rad is outside its joint range [-1.5708, 1.570796] rad" in err, err


def test_a_value_equal_to_its_excluded_bound_is_shown_as_it_is(capsys, tmp_path):
    """radius=0.3 with length 0.3 read "smaller than 'length' (0.29999999999999999 m); got 0.3": no digit count
    tells equal numbers apart, so both are shown as they are; an out-of-range whole number says "whole number"."""
    assert params.apart(0.3, 0.3, "down") == ("0.3", "0.3")
    assert params.apart(1 / 3, 1 / 3, "up") == (repr(1 / 3), repr(1 / 3))
    assert main(["run", "pendulum", "--set", "radius=0.3", "--out", str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err
    assert "smaller than 'length' (0.3 m); got 0.3" in err and "0.2999" not in err, err
    assert main(["run", "hexabot-walk", "--set", "seed=-1", "--out", str(tmp_path / "b")]) == 2
    assert "'seed' must be a whole number with" in capsys.readouterr().err
