"""The hexabot walking a schedule of commands and a waypoint course (issue 22): refusals before the walk, the
rows' steady speeds against the schedule, the course's cross-track error against the circle it samples."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from helpers import cli, walk, walk_params

from hexabot_sim import params
from hexabot_sim.errors import UsageError
from hexabot_sim.walking.commands import MAX_TABLE_BYTES


def _write(path: Path, text: str) -> str:
    path.write_text(text)
    return str(path)


BAD_SCHEDULES = {
    "t,vx,vy,yaw_rate\n0,0.1,0,0\n2,0.1,0,0\n2,0,0,0.3\n": "line 4: t = 2 s is not after the previous row's 2 s",
    "t,vx,vy,yaw_rate\n0,0.1,0,0\n2,nan,0,0\n": "line 3: vx must be a number from -1 to 1 m/s; got 'nan'",
    # float() reads "0_0.05" as 0.05 and full-width digits as digits: a slip, refused as params' numbers are
    "t,vx,vy,yaw_rate\n0,0_0.05,0,0\n": "line 2: vx must be a number from -1 to 1 m/s; got '0_0.05'",
    "t,vx,vy,yaw_rate\n0,0.05,0,\uff10\n": "line 2: yaw_rate must be a number from -3 to 3 rad/s",
    "t,vx,vy,yaw_rate,gait\n0,0.1,0,0,trot\n": "schedule row 1 (t = 0 s): unknown gait 'trot'; known: tripod",
    "t,vx,vy,yaw_rate\n0,0.1,0,0\n3,0.6,0,0\n": "schedule row 2 (t = 3 s): the legs cannot deliver this command",
    "t,vx,vy,yaw_rate,stand_height\n0,0.1,0,0,0.19\n": "schedule row 1 (t = 0 s): ",
    # A row the walk (20 s) never reaches is a slip in the file or in the duration: not dropped without a word.
    "t,vx,vy,yaw_rate\n0,0.1,0,0\n20,0,0,0.3\n": (
        "schedule row 2 (t = 20 s): starts at or after the walk's end (20 s); raise 'duration' above 20 s or leave"
    ),
    "t,speed\n0,1\n": "unknown column 'speed'; it needs columns t, vx, vy, yaw_rate",
    "t,vx,vy,yaw_rate\n": "has a header but no rows",
    "t,vx,vy,yaw_rate,gait\n0,0.1,0,0,tripod\n5,0.15,0,0,ripple\n11,0.35,0,0,tripod\n": (
        "schedule: at t = 12.4 s (after the switch to the tripod gait at 11 s) foot lr would leave its reachable"
    ),
    "t,vx,vy,yaw_rate\n0,0.1,0\n": "line 2: 3 values for the 4 columns",
    # numpy.savetxt(..., header=...) writes '# ' before the header: not "the header '0,0.05,0,0' has unknown column"
    "# t,vx,vy,yaw_rate\n0,0.05,0,0\n": "line 1 is the header as a '#' comment (numpy.savetxt writes it so); remove",
    "# t,vx,vy,yaw_rate\n# 0,0.05,0,0\n": "has only blank and '#' comment lines; it needs a header row",  # not empty
    # Lines end at \n, \r\n or \r only (str.splitlines also broke at \f, \v, U+2028 ...: a wrong line number).
    "t,vx,vy,yaw_rate\r\n0,0.05,0,0\u2028\r\n1\f,nan,0,0\r\n": "line 3: vx must be a number",
}


@pytest.mark.parametrize("text", list(BAD_SCHEDULES))
def test_bad_schedules_are_refused_before_the_walk_with_one_line_naming_the_row(tmp_path, capsys, text):
    out = tmp_path / "out"
    code, _, err = cli(capsys, "run", "hexabot-walk", "--set", f"schedule={_write(tmp_path / 's.csv', text)}",
                       "--out", str(out))  # fmt: skip
    assert code == 2 and BAD_SCHEDULES[text] in err and len(err.strip().splitlines()) == 1
    assert "Traceback" not in err and not out.exists()


def test_unreadable_and_huge_tables_are_refused(tmp_path, capsys):
    huge = tmp_path / "huge.csv"
    huge.write_text("t,vx,vy,yaw_rate\n" + "0,0,0,0\n" * (MAX_TABLE_BYTES // 8 + 1))
    many = tmp_path / "many.csv"
    many.write_text("t,vx,vy,yaw_rate\n" + "".join(f"{i},0.05,0,0\n" for i in range(1001)))
    wide = tmp_path / "wide.csv"
    wide.write_text("t,vx,vy,yaw_rate\n0,0,0,0\n1," + "1" * 200_000 + ",0,0\n")  # a cell above csv's field limit
    for value, words in ((huge, "is larger than 1024 KiB"), (tmp_path, "is a directory"), (wide, "line 3: "),
                         (tmp_path / "none.csv", "not found"), (many, "has 1001 rows; the limit is 1000")):  # fmt: skip
        code, _, err = cli(capsys, "run", "hexabot-walk", "--set", f"schedule={value}", "--out", str(tmp_path / "o"))
        assert code == 2 and words in err and len(err.strip().splitlines()) == 1


def test_bad_waypoints_are_refused(tmp_path, capsys):
    cases = {
        "x,y\n0.3,0\n0.3,nan\n": "line 3: y must be a number",
        "x,y\n0.3,0\n0.3,0.0001\n": "within 1 mm of the point before it",
        "x,y\n0,0\n0,0.0005\n": "line 3: (0, 0.0005) is within 1 mm of the point before it (or the start)",
        "x,y,heading\n0,0,1\n": "line 2: (0, 0) is within 1 mm",
        "x,y,heading\n0,0,0\n0.3,0,\n": "(or the start); a first row there is left out only without a heading",
        "x,y\n0.3,0\n0.3,0\n0,0\n": "line 3: (0.3, 0) is within 1 mm",
        "x,y\n0.4,0\n5,0\n": "the course is 5 m long",
        "x,y\n5,0\n": "the course is 5 m long; at path_speed 0.1 m/s the walk needs about",
        "x,y\n0,0\n": "line 2: the start itself is the only waypoint",  # not a walk without waypoints
        "# a course\nx, y\n0, 0.0005\n": "line 3: the start itself is the only waypoint; the course needs a point",
    }
    for text, words in cases.items():
        path = _write(tmp_path / "w.csv", text)
        code, _, err = cli(capsys, "run", "hexabot-walk", "--set", f"waypoints={path}", "--out", str(tmp_path / "o"))
        assert code == 2 and words in err and len(err.strip().splitlines()) == 1, err


def test_table_files_take_comments_and_quoted_numbers_as_spreadsheets_write_them(tmp_path):
    from hexabot_sim.walking.commands import read_schedule

    path = _write(
        tmp_path / "s.csv", '# forward, then faster\nt, vx, vy, yaw_rate\n0, 0.05, 0, 0\n  # now\n2, "0.08", 0, 0\n'
    )
    assert [row[:4] for row in read_schedule("schedule", str(path))] == [(0.0, 0.05, 0.0, 0.0), (2.0, 0.08, 0.0, 0.0)]
    bad = _write(tmp_path / "b.csv", 't, vx, vy, yaw_rate\n# c\n0, "x", 0, 0\n')
    with pytest.raises(UsageError, match="line 3: vx must be a number"):  # the file's own line number
        read_schedule("schedule", str(bad))


def test_a_tab_or_semicolon_separated_file_is_told_to_use_commas(tmp_path):
    from hexabot_sim.walking.commands import read_schedule

    for sep, words in (("\t", "separated by tabs; use commas"), (";", "separated by ';'; use commas")):
        path = _write(tmp_path / "s.csv", sep.join(["t", "vx", "vy", "yaw_rate"]) + "\n0" + sep + "0.1\n")
        with pytest.raises(UsageError, match=re.escape(words)):
            read_schedule("schedule", str(path))


def test_a_closed_course_may_start_at_the_start(tmp_path):
    from hexabot_sim.walking.commands import read_waypoints

    path = _write(tmp_path / "square.csv", "x, y\n0, 0\n0.3, 0\n0.3, 0.3\n0, 0.3\n0, 0\n")
    assert read_waypoints("waypoints", str(path)) == ((0.3, 0.0, None), (0.3, 0.3, None), (0.0, 0.3, None),
                                                      (0.0, 0.0, None))  # fmt: skip


def test_waypoint_refusals_name_the_follower_s_parameters(tmp_path, capsys):
    far = _write(tmp_path / "far.csv", "x, y\n400, 0\n")
    fast = ("--set", "path_speed=0.5")
    code, _, err = cli(capsys, "run", "hexabot-walk", "--set", f"waypoints={far}", *fast, "--out", str(tmp_path / "o"))
    assert code == 2 and err.startswith("hexabot-sim: error: waypoints: the follower may ask for path_speed 0.5")
    assert err.rstrip().endswith("lower path_speed or path_yaw_rate")
    long = ("--set", "duration=600")
    code, _, err = cli(capsys, "run", "hexabot-walk", "--set", f"waypoints={far}", *long, "--out", str(tmp_path / "o"))
    # The longest walk the run budget takes at 2 ms (1999.998 s), not the 3600 s the duration's range allows.
    assert code == 2 and "longer than the longest walk (1.99e+03 s at timestep 0.002 s): shorten the course" in err
    assert not (tmp_path / "o").exists()


def test_the_api_takes_rows_as_lists_or_arrays_and_fills_what_they_leave_out(tmp_path):
    rows = [[0, 0.1, 0, 0], [3, 0, 0, 0.3, None, 0.04]]
    p = walk_params(schedule=rows, duration=6)
    assert p.schedule == ((0.0, 0.1, 0.0, 0.0, None, None, None), (3.0, 0.0, 0.0, 0.3, None, 0.04, None))
    assert walk_params(schedule=np.array([[0, 0.1, 0, 0], [3, 0, 0, 0.3]]), duration=6).schedule[1][3] == 0.3
    csv = _write(tmp_path / "s.csv", "t, vx, vy, yaw_rate, step_height\n0, 0.1, 0, 0,\n3, 0, 0, 0.3, 0.04\n")
    assert walk_params(schedule=csv, duration=6).schedule == p.schedule
    with pytest.raises(UsageError, match="schedule row 2 must be a list of 4 to 7 values"):
        walk_params(schedule=[[0, 0.1, 0, 0], [3, 0.1]])
    with pytest.raises(UsageError, match="a schedule or waypoints, not both"):
        walk_params(schedule=rows, waypoints=[[0.2, 0]], duration=20)


def test_the_api_takes_a_path_and_refuses_an_int_too_large_for_a_float(tmp_path):
    """Found by fuzzing: schedule=Path(...) was refused as not 'a CSV file' (robot=Path(...) is taken), and an int of
    hundreds of digits in a row was an OverflowError from float(), not a refusal naming the row."""
    csv = tmp_path / "s.csv"
    csv.write_text("t,vx,vy,yaw_rate\n0,0.1,0,0\n")
    assert walk_params(schedule=csv, duration=6).schedule == ((0.0, 0.1, 0.0, 0.0, None, None, None),)
    (tmp_path / "w.csv").write_text("x,y\n0.2,0\n")
    assert walk_params(waypoints=tmp_path / "w.csv", duration=20).waypoints == ((0.2, 0.0, None),)
    with pytest.raises(UsageError, match=r"^schedule row 1: vx must be a number from -1 to 1 m/s; got 1000000000"):
        walk_params(schedule=[[0, 10**400, 0, 0]])
    with pytest.raises(UsageError, match=r"^waypoints row 1: x must be a number from -1000 to 1000 m; got 1000000000"):
        walk_params(waypoints=[[10**400, 0]])


@pytest.mark.slow
def test_a_schedule_is_walked_at_each_rows_speed():
    """Forward 0.1 m/s, then turning on the spot at 0.3 rad/s: each row's steady walk (whole cycles after its ramp)
    within 3 % of its command (the issue's target; measured over 5 s rows: 0.2 %, docs/hexabot.md)."""
    r = walk(schedule=[[0, 0.1, 0, 0], [3.5, 0, 0, 0.3]], duration=7.0)
    table = r.extras["schedule_table"]
    assert [row["row"] for row in table] == [1, 2]
    assert abs(table[0]["vx"] - 0.1) < 0.003 and abs(table[1]["yaw_rate"] - 0.3) < 0.009
    assert r.metrics["schedule_speed_error_max"].value < 0.03
    assert r.metrics["schedule_yaw_rate_error_max"].value < 0.03
    assert r.metrics["vx_error"].value is None and not r.metrics["fell"].value
    # The commanded columns follow the schedule: the first row's twist before the second row's ramp (to a step),
    # then the turn.
    t = r.columns["t"]
    assert r.columns["cmd_vx"][(t > 2.0) & (t < 3.49)] == pytest.approx(0.1)
    assert r.columns["cmd_yaw_rate"][t > 4.6] == pytest.approx(0.3)


@pytest.mark.slow
def test_a_waypoint_course_is_walked_close_to_the_circle_it_samples():
    """A quarter of a 0.5 m circle in 12 waypoints: the body's distance from the circle itself (not the follower's
    polyline) stays under the chords' sagitta (0.5 m (1 - cos(pi / 24)) = 4.3 mm) plus 5 mm."""
    radius = 0.5
    angles = np.linspace(0, math.pi / 2, 13)[1:]
    points = [[radius * math.sin(a), radius * (1 - math.cos(a))] for a in angles]
    r = walk(waypoints=points, duration=13.0)
    m = r.metrics
    assert m["course_arrived"].value and 7.0 < m["course_time"].value < 11.0
    assert m["cross_track_rms"].value < 0.02 and not m["fell"].value
    t, x, y = r.columns["t"], r.columns["x"], r.columns["y"]
    walking = t >= 0.5
    off_circle = np.abs(np.hypot(x[walking], y[walking] - radius) - radius)
    assert off_circle.max() < radius * (1 - math.cos(math.pi / 24)) + 0.005
    assert abs(x[-1] - points[-1][0]) < 0.01 and abs(y[-1] - points[-1][1]) < 0.01
    assert 0.0 < m["course_cost_of_transport"].value < 5.0
    from hexabot_sim.robots.hexabot.walk import figures

    assert "course" in figures(r)


@pytest.mark.slow
def test_a_tripod_to_wave_switch_walks_on_without_a_dip_or_extra_bounces():
    """The issue's transition at 0.05 m/s: no fall, the speed (mean over a period) dips under 10 %, and the feet
    bounce (foot_bounces' definition: a loaded foot unloading under 60 ms, from mj_contactForce) no more in the
    2.5 s from the switch than in as long of steady wave walking (the wave's own bounces are issue 19's)."""
    from hexabot_sim.robots.hexabot.walk import figures
    from hexabot_sim.walking import course

    r = walk(schedule=[[0, 0.05, 0, 0, "tripod"], [3.5, 0.05, 0, 0, "wave"]], duration=9.0)
    t, switch = r.columns["t"], r.extras["gait_switches"][0][0]
    assert switch == pytest.approx(3.5) and not r.metrics["fell"].value
    assert course.speed_dip(t, r.columns["vx_body"], 0.05, 1.0, switch - 1.0, switch + 3.0) < 0.10
    loaded = r.extras["contacts"].loaded(float(r.model.body_subtreemass[r.model.body("torso").id]))
    across = course.count_bounces(loaded, t, switch, switch + 2.5)
    steady = course.count_bounces(loaded, t, 6.5, 9.0)
    assert across <= steady
    assert "gait_switch_1" in figures(r)


@pytest.mark.slow
def test_a_tripod_wave_tripod_change_does_not_bounce_when_the_legs_share_the_load():
    """With issue 19's stance force control on the pad the change has no bounce at all, there and back: the switch
    leaves every foot down for gait.SETTLE before the wave lifts one (lifting it as the tripod landed bounced lf)."""
    from hexabot_sim.walking import course

    rows = [[0, 0.05, 0, 0, "tripod"], [5, 0.05, 0, 0, "wave"], [8.5, 0.05, 0, 0, "tripod"]]
    r = walk(schedule=rows, duration=10.5, load_sharing="force", feet="pad", swing="quintic")
    t = r.columns["t"]
    assert [g for _, g in r.extras["gait_switches"]] == ["wave", "tripod"] and not r.metrics["fell"].value
    loaded = r.extras["contacts"].loaded(float(r.model.body_subtreemass[r.model.body("torso").id]))
    assert course.count_bounces(loaded, t, 2.0, 10.5) == 0


def test_schedule_scale_multiplies_the_rows_twists_and_is_checked_like_them(tmp_path):
    from hexabot_sim import sweep
    from hexabot_sim.walking import commands

    rows = [[0, 0.05, 0.01, 0], [3, 0, 0, 0.2]]
    p = walk_params(schedule=rows, schedule_scale=1.5, duration=6)
    twists = [(s.command.vx, s.command.vy, s.command.yaw_rate) for s in commands.setpoints(p)]
    assert np.array(twists) == pytest.approx(np.array([(0.075, 0.015, 0.0), (0.0, 0.0, 0.3)]))
    # The refusal's speeds are the scaled ones (a feasible vx 0.096 for a file that says 0.05): it says so.
    with pytest.raises(UsageError, match=r"schedule row 1 \(t = 0 s, its twist times schedule_scale 10\): the legs"):
        walk_params(schedule=rows, schedule_scale=10, duration=6)
    csv = _write(tmp_path / "s.csv", "t,vx,vy,yaw_rate\n0,0.05,0,0\n3,0,0,0.2\n")
    plan = sweep.plan("hexabot-walk", ["schedule_scale=0.5,1,2"], {}, {"schedule": csv, "duration": "6"})
    assert [c.schedule_scale for c in plan.cells] == [0.5, 1.0, 2.0]


@pytest.mark.slow
def test_a_gait_switch_on_rough_ground_with_feet_that_find_it():
    """Tripod -> wave at 0.05 m/s on 1 cm rough ground (hexabot-rough: sensed touchdown): no fall, a dip under 10 %,
    and every touchdown dated against its own swing (a tripod swing under way that lands late is not dated against
    the wave's shorter swing): no touchdown further from its plan than in steady tripod walking (0.088 s, seed 0)."""
    from hexabot_sim.robots.hexabot import walk as scenario
    from hexabot_sim.walking import course

    rows = [[0, 0.05, 0, 0, "tripod"], [3.5, 0.05, 0, 0, "wave"]]
    p = params.resolve(scenario.HexabotParams, {"roughness": 0.01, "touchdown": "sensed"}, {"schedule": rows,
                       "duration": 8.0})  # fmt: skip
    r = scenario.run("hexabot-rough", p)
    t = r.columns["t"]
    assert r.extras["gait_switches"][0][1] == "wave" and not r.metrics["fell"].value
    assert course.speed_dip(t, r.columns["vx_body"], 0.05, 1.0, 2.5, 6.5) < 0.10
    assert r.metrics["touchdown_error_max"].value < 0.1


@pytest.mark.slow
def test_a_schedules_heights_raise_the_body_and_the_swings():
    """stand_height 0.09 -> 0.11 m and step_height 0.03 -> 0.05 m at 2.5 s: the body rises by 20 mm and each foot's
    highest point in a swing (its site, from mj_kinematics) by 20 mm (measured: 20.0 and 19.9 mm)."""
    import mujoco

    r = walk(schedule=[[0, 0.05, 0, 0, None, 0.03, 0.09], [2.5, 0.05, 0, 0, None, 0.05, 0.11]], duration=6.0)
    t, z = r.columns["t"], r.columns["z"]
    assert z[t > 4.5].mean() - z[(t > 1.5) & (t < 2.5)].mean() == pytest.approx(0.02, abs=0.001)
    model, data = r.model, mujoco.MjData(r.model)
    site = model.site("lf_foot").id
    rows = np.arange(0, len(t), 5)
    apex = np.empty(len(rows))
    for i, k in enumerate(rows):
        data.qpos[:] = r.trajectory.qpos[k]
        mujoco.mj_kinematics(model, data)
        apex[i] = data.site_xpos[site][2]
    before, after = apex[(t[rows] > 1.0) & (t[rows] < 2.5)].max(), apex[t[rows] > 4.0].max()
    assert after - before == pytest.approx(0.02, abs=0.002) and not r.metrics["fell"].value


def test_bounces_and_the_speed_dip_are_counted_as_defined():
    """count_bounces on a hand-made contact pattern (2 ms rows): a 40 ms gap between loads is a bounce, a 60 ms or
    longer one a swing; speed_dip of a speed that drops to half for exactly one period is 50 %."""
    from hexabot_sim.walking import course

    t = np.arange(0, 2.0, 0.002)
    loaded = np.ones((len(t), 2), dtype=bool)
    loaded[(t >= 0.5) & (t < 0.54), 0] = False  # 40 ms: a bounce
    loaded[(t >= 1.0) & (t < 1.06), 0] = False  # 60 ms: not one
    loaded[(t >= 1.2) & (t < 1.21), 1] = False  # 10 ms: a bounce
    loaded[(t >= 1.5), 1] = False  # lifted and not back: not one
    assert course.count_bounces(loaded, t, 0.0, 2.0) == 2
    assert course.count_bounces(loaded, t, 0.6, 2.0) == 1
    v = np.where((t >= 0.8) & (t < 1.3), 0.05, 0.1)
    assert course.speed_dip(t, v, 0.1, 0.5, 0.0, 2.0) == pytest.approx(0.5)
    assert course.speed_dip(t, v, 0.1, 0.5, 0.0, 0.7) == pytest.approx(0.0)


def test_vx_vy_and_yaw_rate_that_a_schedule_or_waypoints_replace_are_not_checked():
    """With a schedule or waypoints the walk's own twist is never commanded (standing before the first row, the
    follower's after), so a wave walk is not refused for the default vx = 0.1 m/s its gait cannot deliver; the
    rows, the follower and stepping in place are still checked."""
    rows = [[0, 0.05, 0, 0]]
    assert walk_params(gait="wave", schedule=rows, duration=6).schedule[0][1] == 0.05
    course = walk_params(gait="wave", waypoints=[[0.3, 0]], path_speed=0.04, path_yaw_rate=0.2, duration=30)
    assert course.waypoints == ((0.3, 0.0, None),)
    with pytest.raises(ValueError, match=r"^schedule row 1 \(t = 0 s\): the legs cannot deliver"):
        walk_params(gait="wave", schedule=[[0, 0.1, 0, 0]], duration=6)
    with pytest.raises(ValueError, match="even stepping in place is infeasible"):
        walk_params(gait="wave", schedule=rows, period=0.2, duration=6)


def test_the_twist_a_schedule_or_waypoints_replace_does_not_enter_the_terrain_checks():
    """The kerb, stairs and level-slope checks planned the walk's own vx, vy, yaw_rate, never commanded with a schedule
    or waypoints: with vx = 1 m/s a kerb's climbable height was 0 mm ('raise stand_height', which did not help) and a
    level 15 deg slope was refused, where the same schedule with vx = 0.1 m/s walked. The rows and the follower's
    commands are still checked on the terrain."""
    rows = [[0, 0.05, 0, 0]]
    for terrain in ({"kerb_height": 0.02}, {"stairs_rise": 0.02}, {"slope_deg": 15, "level_body": "on"}):
        assert walk_params(schedule=rows, vx=1.0, duration=6, **terrain).vx == 1.0
        assert walk_params(waypoints=[[0.6, 0]], vx=1.0, duration=12, **terrain).vx == 1.0
    with pytest.raises(ValueError, match=r"^schedule row 1 \(t = 0 s\): a 30 mm kerb is above the largest climbable"):
        walk_params(schedule=rows, kerb_height=0.03, duration=6)
    # Nor the ground-finding controller's depth range (vx = 1 m/s left it (0.09, 0.09) m: a different walk).
    from hexabot_sim.walking.scene import _walk_depth_range

    ranges = {_walk_depth_range(walk_params(schedule=rows, vx=vx, touchdown="sensed", duration=6)) for vx in (0.1, 1)}
    assert len(ranges) == 1 and min(ranges)[0] < 0.05 < 0.15 < min(ranges)[1]


def test_the_slope_kerb_and_stairs_face_the_way_a_schedule_or_course_sets_out_not_the_replaced_vx_vy():
    """The terrain's direction came from the walk's own vx, vy (0.1, 0 by default), which a schedule or waypoints
    replace: a schedule crabbing left (+y) met a kerb laid across +x, beside it. Now the kerb, the stairs and the
    slope face the course's first 5 cm (the kerb and stairs: the way to where it first reaches their distance), and
    the kerb's pavement runs on as far as the course goes."""
    from hexabot_sim.walking import commands
    from hexabot_sim.walking.constants import SETTLE_TIME
    from hexabot_sim.walking.ground import terrain, walking_direction

    crab = walk_params(schedule=[[0, 0, 0.08, 0]], kerb_height=0.02, duration=8)
    assert walking_direction(crab) == pytest.approx([0.0, 1.0])
    assert terrain(crab).obstacles[0].along == pytest.approx((0.0, 1.0))
    course = walk_params(waypoints=[[-0.3, -0.3], [-0.6, 0]], slope_deg=5, duration=40)
    assert walking_direction(course) == pytest.approx([-math.sqrt(0.5), -math.sqrt(0.5)])
    assert terrain(course).slope.uphill == pytest.approx((-math.sqrt(0.5), -math.sqrt(0.5)))
    # A quarter turn on the spot (with the schedule's ramps), then forward: the course sets out along its new heading.
    turn = walk_params(schedule=[[0, 0, 0, 0.3], [5.736, 0.1, 0, 0]], stairs_rise=0.02, duration=20)
    along = walking_direction(turn)
    assert abs(math.atan2(along[1], along[0])) > 1.0 and terrain(turn).obstacles[0].along == pytest.approx(
        along, abs=0.03
    )
    # Standing or turning on the spot all along: +x, as a walk without a schedule.
    assert walking_direction(walk_params(schedule=[[0, 0, 0, 0.2]], duration=6)) == pytest.approx([1.0, 0.0])
    # A short crab left (5 cm) before a long walk ahead: the slope faces the first 5 cm (+y), but a kerb or stairs
    # 0.5 m ahead face the way to where the course first gets 0.5 m away (they faced +y, beside the walk).
    for obstacle in ({"kerb_height": 0.02}, {"stairs_rise": 0.02}):
        crab_first = walk_params(schedule=[[0, 0, 0.05, 0], [2.5, 0.1, 0, 0]], duration=14, **obstacle)
        course = commands.path(crab_first, SETTLE_TIME)
        first = course[np.flatnonzero(np.hypot(*course.T) >= 0.5)[0]]
        assert walking_direction(crab_first) == pytest.approx([0.0, 1.0])
        assert terrain(crab_first).obstacles[0].along == pytest.approx(first / np.hypot(*first), abs=1e-3)
        assert 0.15 < first[1] / first[0] < 0.25  # ~11 deg off +x
    # Waypoints: where the polyline crosses 0.5 m, (0.4, 0.3) on its second leg, not its next corner (2, 0.3).
    corner = walk_params(waypoints=[[0.3, 0.3], [2, 0.3]], kerb_height=0.02, duration=40)
    assert terrain(corner).obstacles[0].along == pytest.approx((0.8, 0.6))
    # The pavement runs on past a 0.3 m/s schedule's 29 m (the walk's own 0.01 m/s laid the least, 20 m).
    fast = walk_params(schedule=[[0, 0.3, 0, 0]], vx=0.01, kerb_height=0.02, duration=100)
    kerb = terrain(fast).obstacles[0]
    assert kerb.distance + kerb.length > 0.3 * 98


def test_a_row_at_or_after_the_end_is_refused_with_the_digits_that_tell_its_time_from_the_duration():
    """A row at 6.0000000001 s of a 6 s walk was refused as "(t = 6 s): starts at or after the walk's end (6 s);
    raise 'duration' above 6 s", and a 9.9999999999 s walk's row at 10 s as ending at 10 s."""
    with pytest.raises(UsageError, match=re.escape("(t = 6.0000000001 s): starts at or after the walk's end (6 s)")):
        walk_params(schedule=[[0, 0.1, 0, 0], [6.0000000001, 0, 0, 0]], duration=6)
    with pytest.raises(UsageError, match=re.escape("(t = 10 s): starts at or after the walk's end (9.9999999999 s)")):
        walk_params(schedule=[[0, 0.1, 0, 0], [10, 0, 0, 0]], duration=9.9999999999)
    with pytest.raises(UsageError, match=re.escape("(t = 8 s): starts at or after the walk's end (8 s); raise")):
        walk_params(schedule=[[0, 0.1, 0, 0], [8, 0, 0, 0]], duration=8)
    # Nor does the row's twist (schedule_scale) enter a refusal about its time.
    with pytest.raises(UsageError, match=re.escape("schedule row 2 (t = 8 s): starts at or after the walk's end")):
        walk_params(schedule=[[0, 0.1, 0, 0], [8, 0, 0, 0]], duration=8, schedule_scale=0.5)


def test_a_row_after_the_last_step_s_start_is_refused_and_one_at_it_is_walked():
    """A row at 1.9981 s of a 2 s walk at 2 ms steps passed the check and was never walked: the last step starts at
    1.998 s. A row at the last step's start takes over for that step (its command is in the last CSV row)."""
    with pytest.raises(UsageError, match=re.escape(
        "schedule row 2 (t = 1.9981 s): starts after the walk's last step (at 1.998 s with 'timestep' 0.002 s) and "
        "before its end (2 s): it would never be walked"
    )):  # fmt: skip
        walk_params(schedule=[[0, 0.05, 0, 0], [1.9981, 0, 0, 0.2]], duration=2)
    # The digits tell the row's time from both the last step's start and the end.
    with pytest.raises(UsageError, match=re.escape("(t = 5.9999 s): starts after the walk's last step (at 5.998 s")):
        walk_params(schedule=[[0, 0.05, 0, 0], [5.9999, 0, 0, 0.2]], duration=6)
    r = walk(schedule=[[0, 0.05, 0, 0], [1.998, 0, 0, 0.2]], duration=2)
    assert r.columns["cmd_yaw_rate"][-1] > 0 and r.columns["cmd_yaw_rate"][-3] == 0.0


def test_a_schedule_s_terrain_speed_error_and_stride_are_not_against_the_replaced_vx_vy():
    """speed_made_good_error (terrain) and stride were the walk's own vx = 0.1 m/s, which a schedule replaces: a
    schedule standing still by a kerb read -100 % (a crab at 0.08 m/s making 0.078 m/s, -22 %)."""
    r = walk(schedule=[[0, 0, 0, 0]], kerb_height=0.02, duration=3)
    assert "speed_made_good" in r.metrics
    for key in ("speed_made_good_error", "stride"):
        assert r.metrics[key].value is None and "null here" in r.metrics[key].doc, key


def test_the_terrain_figure_draws_a_turning_schedule_against_time_and_a_straight_course_against_distance():
    """The terrain figure's axis was the distance along the start's direction whenever the walk's own (replaced) vx,
    vy went straight: an arcing schedule's body and feet folded back on themselves."""
    from hexabot_sim.walking.figures import _straight
    from hexabot_sim.walking.ground import walking_direction

    def straight(**kw):
        p = walk_params(**({"duration": 12} | kw))
        return _straight(p, walking_direction(p))

    assert not straight(schedule=[[0, 0.08, 0, 0.2]])
    assert not straight(schedule=[[0, 0, 0, 0]]) and not straight(schedule=[[0, 0.1, 0, 0], [4, -0.1, 0, 0]])
    assert straight(schedule=[[0, 0, 0.08, 0]]) and straight(schedule=[[0, -0.05, -0.05, 0]])
    assert straight(waypoints=[[0, 0.6]], kerb_height=0.02) and not straight(waypoints=[[0.3, 0], [0.3, 0.3]])
    assert straight(vx=0.1) and not straight(vx=0.1, yaw_rate=0.1)


def test_a_duty_with_a_schedule_in_another_gait_is_refused_naming_both_gaits_not_a_change_the_schedule_lacks():
    # Every row walks the wave, the walk's gait is the tripod: the duty would be dropped (the walk starts in the
    # first row's gait at its own duty). The refusal said "a schedule that changes gait" of a schedule keeping one.
    rows = [[0, 0.03, 0, 0, "wave"], [2, 0.03, 0, 0, "wave"]]
    with pytest.raises(UsageError, match=r"schedule row 1 \(t = 0 s\): its wave gait is not the walk's tripod") as e:
        walk_params(schedule=rows, duty=0.6, period=1.5, duration=4)
    assert "set duty=0 or gait=wave" in str(e.value)
    assert walk_params(schedule=rows, duty=0.9, period=2.0, duration=4, gait="wave").duty == 0.9
    changes = [[0, 0.03, 0, 0, "ripple"], [2, 0.03, 0, 0, "wave"]]
    with pytest.raises(UsageError, match=r"schedule row 2 \(t = 2 s\): a schedule that changes gait walks each gait"):
        walk_params(schedule=changes, duty=0.7, period=1.5, duration=4, gait="ripple")


def test_a_gait_change_is_checked_at_the_rows_heights_not_the_walks():
    """The gait change's replay planned the feet at the walk's stand_height, not the rows' the walker lowers them
    to: stand_height=0.183 with rows at 0.09 and 0.12 m was refused ('at t = 0.7 s foot lr would leave its
    reachable workspace ...; change gait at a lower speed or keep one gait', before any change; found by fuzzing)."""
    rows = [[0, 0.05, 0, 0, "tripod", 0.03, 0.09], [1.5, 0.05, 0, 0, "wave", 0.02, 0.12]]
    assert walk_params(schedule=rows, stand_height=0.183, duration=4).stand_height == 0.183


def test_the_body_height_sag_is_against_the_schedules_stand_heights():
    """body_height_sag measured a schedule's walk against the walk's own stand_height, which its rows replace: rows
    at 0.08 then 0.11 m read a sag of about -19 mm for a body at its planned heights (found by fuzzing)."""
    r = walk(schedule=[[0, 0.05, 0, 0, None, 0.03, 0.08], [1.5, 0.05, 0, 0, None, 0.03, 0.11]], duration=4.0)
    assert abs(r.metrics["body_height_sag"].value) < 0.002


def test_the_duty_title_and_overlay_name_the_gaits_walked_not_the_walks_gait_the_rows_replace():
    """A schedule in the ripple gait (the walk's gait: tripod) reported duty 0.5 and 'tripod gait at the start'; a
    gait change kept its first gait's duty and the video's 'tripod gait' throughout (found by fuzzing)."""
    r = walk(schedule=[[0, 0.05, 0, 0, "ripple"], [2, 0.05, 0, 0, "wave"]], duration=4.0)
    assert r.metrics["duty"].value is None and "changes gait" in r.metrics["duty"].doc
    t, gait = r.columns["t"], r.overlay[0]
    assert gait(np.searchsorted(t, 1.0)).startswith("ripple gait") and gait(len(t) - 1).startswith("wave gait")
    one = walk(schedule=[[0, 0.05, 0, 0, "ripple"]], duration=2.0)
    assert one.metrics["duty"].value == pytest.approx(2 / 3)
    from hexabot_sim.walking.figures import _title

    assert "ripple gait at the start" in _title(one, "body")
