"""A walk's changing command: the schedule and waypoint tables (CSV files or rows), their refusals, their sources.

Both are parameters of a walk (`schedule`, `waypoints`): `--set schedule=FILE` names a CSV file with a header
row; the Python API (and a run folder's run.json) gives the rows themselves. The readers here check each
value on its own; the checks that need the robot (its gaits, what its legs can deliver) run in the walk's
parameter checks (`schedule_problem`, `waypoints_problem`), before the walk, naming the row.
"""

from __future__ import annotations

import csv
import dataclasses
import math
import os
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from hexabot_sim.budget import step_count
from hexabot_sim.control.commands import Schedule, Setpoint, add_heights
from hexabot_sim.control.follower import PathFollower
from hexabot_sim.control.gait import Command, GaitPlanner
from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics import legged
from hexabot_sim.params import _show, allowed, apart, read_bounded
from hexabot_sim.walking.constants import MEASURE_TIME, SETTLE_TIME, STAND_HEIGHT_MAX, STAND_HEIGHT_MIN

# Rows of a table. Each schedule row's check plans its cycle (~6 ms for a new twist: 200 distinct rows took 1.2 s),
# so a schedule is kept to what a few seconds check; a waypoint costs nothing to check.
MAX_ROWS: dict[str, int] = {"schedule": 1000, "waypoints": 10_000}
MAX_TABLE_BYTES: int = 1 << 20  # a table file of more than 1 MiB is not a schedule
MAX_TIME: float = 3600.0  # [s] latest schedule time (the longest walk)
MAX_DISTANCE: float = 1000.0  # [m] farthest waypoint from the start
MAX_SHOWN_PATH: int = 300  # characters of a file name quoted whole in a refusal (longer: cut short)

SCHEDULE_COLUMNS = ("t", "vx", "vy", "yaw_rate", "gait", "step_height", "stand_height")
SCHEDULE_REQUIRED = 4
WAYPOINT_COLUMNS = ("x", "y", "heading")
WAYPOINT_REQUIRED = 2

SCHEDULE_DOC = (
    "commands in time: from each row's t [s] on, its twist (ramped in over a period), gait and heights (vx, vy, "
    "yaw_rate are then ignored)"
)
WAYPOINTS_DOC = "walk through these points (path follower: control/follower.py; vx, vy, yaw_rate are then ignored)"
SCHEDULE_ALLOWED = (
    "a CSV file with the header t, vx, vy, yaw_rate[, gait, step_height, stand_height] (or, from the Python API, "
    "a list of such rows); empty: one command throughout"
)
WAYPOINTS_ALLOWED = (
    "a CSV file with the header x, y[, heading] [m, m, rad] from the start pose (or, from the Python API, a list "
    "of such rows); empty: no waypoints"
)


def _rows(name: str, raw: Any, columns: tuple[str, ...], required: int) -> list[tuple[str, list[Any]]]:
    """(where, values in column order, None where not given) of each row of a table file or of API rows."""
    limit = MAX_ROWS[name]
    allowed = f"columns {', '.join(columns[:required])}" + (
        f" and optionally {', '.join(columns[required:])}" if len(columns) > required else ""
    )
    if isinstance(raw, os.PathLike):  # a pathlib.Path from the Python API, as `robot` takes it
        raw = os.fsdecode(raw)
    if isinstance(raw, str):
        if raw.strip() == "":
            return []
        shown = repr(raw)
        try:
            data = read_bounded(Path(raw), f"{name} file", MAX_TABLE_BYTES, f"a {name} table is at most {limit} rows")
        except UsageError as e:  # a name of thousands of characters is not quoted whole
            raise UsageError(str(e).replace(shown, _show(raw))) if len(shown) > MAX_SHOWN_PATH else e from None
        try:
            text = data.decode("utf-8").removeprefix("\ufeff")
        except UnicodeDecodeError:
            raise UsageError(f"{name} file {shown} is not UTF-8 text") from None
        # Blank lines and '#' comment lines are skipped (numpy.loadtxt's convention); line numbers are the file's.
        # Lines end at \n, \r\n or \r, as in an editor (str.splitlines also breaks at \f, \v, U+2028 ...).
        numbered = list(enumerate(re.split(r"\r\n|\r|\n", text), start=1))
        lines = [(i, line) for i, line in numbered if line.strip()[:1] not in ("", "#")]
        if not lines:
            what = "has only blank and '#' comment lines" if text.strip() else "is empty"
            raise UsageError(f"{name} file {shown} {what}; it needs a header row ({allowed}) and rows")
        header = [h.strip().lower() for h in _cells(name, shown, *lines[0])]
        problem = _header_problem(header, columns, required)
        if problem:
            # The last comment before it, if it is the header: numpy.savetxt(header=...) writes '# ' before it.
            comment = next((c for c in reversed(numbered[: lines[0][0] - 1]) if c[1].strip()), None)
            if comment is not None:
                cells = [h.strip().lower() for h in _cells(name, shown, *comment)]
                if cells and cells[0].startswith("#"):
                    cells[0] = cells[0].lstrip("#").strip()
                if not _header_problem(cells, columns, required):
                    raise UsageError(
                        f"{name} file {shown}: line {comment[0]} is the header as a '#' comment (numpy.savetxt "
                        "writes it so); remove the '#'"
                    )
            separated = next((sep for sep in ("\t", ";") if "," not in lines[0][1] and sep in lines[0][1]), None)
            if separated is not None:  # a spreadsheet's other export: say what the separator must be
                shown_sep = "tabs" if separated == "\t" else "';'"
                raise UsageError(f"{name} file {shown}: its columns are separated by {shown_sep}; use commas (CSV)")
            raise UsageError(f"{name} file {shown}: the header {lines[0][1][:60]!r} has {problem}; it needs {allowed}")
        if len(lines) - 1 > limit:
            raise UsageError(f"{name} file {shown} has {len(lines) - 1} rows; the limit is {limit}")
        out = []
        for number, line in lines[1:]:
            cells = [c.strip() for c in _cells(name, shown, number, line)]
            if len(cells) != len(header):
                raise UsageError(
                    f"{name} file {shown}, line {number}: {len(cells)} values for the {len(header)} columns"
                )
            by_name = dict(zip(header, cells, strict=True))
            out.append((f"{name} file {shown}, line {number}", [by_name.get(c) or None for c in columns]))
        if not out:
            raise UsageError(f"{name} file {shown} has a header but no rows")
        return out
    if isinstance(raw, np.ndarray):
        raw = raw.tolist()
    if not isinstance(raw, (list, tuple)):
        raise UsageError(f"parameter '{name}' must be {SCHEDULE_ALLOWED if name == 'schedule' else WAYPOINTS_ALLOWED}")
    if len(raw) > limit:
        raise UsageError(f"parameter '{name}' has {len(raw)} rows; the limit is {limit}")
    out = []
    for i, row in enumerate(raw):
        where = f"{name} row {i + 1}"
        if isinstance(row, np.ndarray):
            row = row.tolist()
        if not isinstance(row, (list, tuple)) or not required <= len(row) <= len(columns):
            raise UsageError(
                f"{where} must be a list of {required} to {len(columns)} values ({allowed}); got {row!r:.60}"
            )
        out.append((where, [*row, *[None] * (len(columns) - len(row))]))
    return out


def _header_problem(header: list[str], columns: tuple[str, ...], required: int) -> str:
    """'' if these (lower-case) names are a table's header, else what is wrong with them."""
    unknown = [h for h in header if h not in columns]
    if unknown or len(set(header)) != len(header) or not set(columns[:required]) <= set(header):
        return f"unknown column {unknown[0]!r}" if unknown else "a column missing or repeated"
    return ""


def _cells(name: str, shown: str, number: int, line: str) -> list[str]:
    """The cells of one line of a table file ('0, "0.08"' too), or a UsageError naming the line."""
    try:
        return next(csv.reader([line], skipinitialspace=True))
    except csv.Error as e:  # e.g. a cell above csv's field size limit (128 KiB)
        raise UsageError(f"{name} file {shown}, line {number}: {e}") from None


def _number(where: str, column: str, value: Any, low: float, high: float, unit: str) -> float:
    """A finite number in [low, high] (a CSV cell or an API value), or a UsageError naming the row."""
    text = value.strip() if isinstance(value, str) else None
    try:  # float() reads "0_0.5" as 0.5 and "５" as 5: a slip, or not our digits (as params' numbers)
        number = math.nan if text is not None and ("_" in text or not text.isascii()) else float(value)
    except (TypeError, ValueError, OverflowError):  # OverflowError: an int of hundreds of digits (from the API)
        number = math.nan
    if isinstance(value, bool) or not math.isfinite(number) or not low <= number <= high:
        raise UsageError(f"{where}: {column} must be a number from {low:g} to {high:g} {unit}; got {value!r:.40}")
    return number + 0.0


def read_schedule(name: str, raw: Any) -> tuple:
    """The schedule's rows (t, vx, vy, yaw_rate, gait or None, step_height or None, stand_height or None)."""
    out = []
    previous = -math.inf
    for where, (t, vx, vy, w, gait, step, stand) in _rows(name, raw, SCHEDULE_COLUMNS, SCHEDULE_REQUIRED):
        if t is None or vx is None or vy is None or w is None:
            raise UsageError(f"{where}: t, vx, vy and yaw_rate must all be given")
        time = _number(where, "t", t, 0.0, MAX_TIME, "s")
        if time <= previous:
            raise UsageError(
                f"{where}: t = {time:g} s is not after the previous row's {previous:g} s; times must increase"
            )
        previous = time
        row: list[float | str | None] = [time, _number(where, "vx", vx, -1.0, 1.0, "m/s")]
        row.append(_number(where, "vy", vy, -1.0, 1.0, "m/s"))
        row.append(_number(where, "yaw_rate", w, -3.0, 3.0, "rad/s"))
        row.append(None if gait is None else str(gait).strip().lower())
        row.append(None if step is None else _number(where, "step_height", step, 0.002, 0.1, "m"))
        stand = (
            None if stand is None else _number(where, "stand_height", stand, STAND_HEIGHT_MIN, STAND_HEIGHT_MAX, "m")
        )
        row.append(stand)
        out.append(tuple(row))
    return tuple(out)


def read_waypoints(name: str, raw: Any) -> tuple:
    """The waypoints (x, y, heading or None) [m, m, rad] from the start pose; a first row at the start (within
    1 mm, no heading) is the start itself and left out."""
    out = []
    previous = (0.0, 0.0)
    rows = _rows(name, raw, WAYPOINT_COLUMNS, WAYPOINT_REQUIRED)
    for k, (where, (x, y, heading)) in enumerate(rows):
        if x is None or y is None:
            raise UsageError(f"{where}: x and y must both be given")
        px = _number(where, "x", x, -MAX_DISTANCE, MAX_DISTANCE, "m")
        py = _number(where, "y", y, -MAX_DISTANCE, MAX_DISTANCE, "m")
        h = None if heading is None else _number(where, "heading", heading, -2 * math.pi, 2 * math.pi, "rad")
        if math.hypot(px - previous[0], py - previous[1]) < 1e-3:
            if k == 0 and h is None:  # the start itself, as a closed course written from (0, 0) begins
                continue
            start = "; a first row there is left out only without a heading (leave the cell empty)" if k == 0 else ""
            raise UsageError(f"{where}: ({px:g}, {py:g}) is within 1 mm of the point before it (or the start){start}")
        previous = (px, py)
        out.append((px, py, h))
    if rows and not out:  # only the start: not a walk without waypoints (the fixed command) in disguise
        raise UsageError(f"{rows[0][0]}: the start itself is the only waypoint; the course needs a point away from it")
    return tuple(out)


def setpoints(p: Any) -> list[Setpoint]:
    """The schedule's rows with what they leave out taken from the row before (the first: from the walk's values),
    their twists times schedule_scale."""
    out = []
    gait, step, stand = p.gait, p.step_height, p.stand_height
    for t, vx, vy, w, g, h, s in p.schedule:
        gait, step, stand = g or gait, step if h is None else h, stand if s is None else s
        out.append(Setpoint(t, Command(vx, vy, w).scaled(p.schedule_scale), gait, step, stand))
    return out


def start_gait(p: Any) -> Any:
    """The gait (control.gait.Gait) the walk starts in: a schedule's first row's at its own duty, else the walk's
    (walking.scene.make_controller)."""
    first = setpoints(p)[0].gait if p.schedule else p.gait
    return p.the_gait() if first == p.gait else p.gaits()[first]


def problem(p: Any, check: Callable[[Any], str], neutral: np.ndarray, settle: float) -> str:
    """'' if the walk's schedule or waypoints can be walked, else one line saying why not (the checks below)."""
    return schedule_problem(p, check) or switch_problem(p, neutral, settle) or waypoints_problem(p, check, settle)


def _shortest(p: Any) -> float:
    """The shortest walk [s]: a row's or the follower's twist is checked as a walk of its own this long, so what
    grows with the duration (the rough ground's size: a row of 0.35 m/s for 10 s in a 1990 s walk was refused as a
    698 m heightfield) is the walk's own check, over the course it plans."""
    return SETTLE_TIME + p.period + MEASURE_TIME


def schedule_problem(p: Any, check: Callable[[Any], str]) -> str:
    """'' if every row can be walked, else one line naming the row: its gait, its values as a walk's parameters,
    what its legs can deliver (`check(params)`: walking.parameters.feasibility)."""
    if p.schedule and p.waypoints:
        return "give a schedule or waypoints, not both"
    gaits = p.gaits()
    rows = setpoints(p)
    for i, row in enumerate(rows):
        where = f"schedule row {i + 1} (t = {row.t:g} s)"
        if p.schedule_scale != 1.0:  # the speeds below are the file's times the scale
            where = f"schedule row {i + 1} (t = {row.t:g} s, its twist times schedule_scale {p.schedule_scale:g})"
        if row.t >= p.duration:  # never walked: a slip in the file or in 'duration', not something to drop unsaid
            # As many digits as tell the two apart: a row at 6.0000000001 s of a 6 s walk is not "t = 6 s ... (6 s)".
            # (Its twist, and so schedule_scale, has nothing to do with it.)
            t, end = apart(row.t, p.duration, "nearest")
            return (
                f"schedule row {i + 1} (t = {t} s): starts at or after the walk's end ({end} s); raise 'duration' "
                f"above {t} s or leave the row out"
            )
        last = (step_count(p.duration, p.timestep) - 1) * p.timestep  # the last control step starts here
        if row.t > last + 1e-9 * max(1.0, last):  # after it: the walk ends before the row takes over
            (t, start), (t_end, end) = apart(row.t, last, "nearest"), apart(row.t, p.duration, "nearest")
            t = max(t, t_end, key=len)  # told apart from both
            return (
                f"schedule row {i + 1} (t = {t} s): starts after the walk's last step (at {start} s with 'timestep' "
                f"{p.timestep:g} s) and before its end ({end} s): it would never be walked; raise 'duration' or "
                "leave the row out"
            )
        if row.gait not in gaits:
            return f"{where}: unknown gait {row.gait!r}; known: {', '.join(gaits)}"
        if row.gait != p.gait and p.duty:
            if all(r.gait == row.gait for r in rows):  # one gait throughout, not the walk's: it has its own duty
                return (
                    f"{where}: its {row.gait} gait is not the walk's {p.gait}, and a walk in a schedule's gait takes "
                    f"that gait's own duty; set duty=0 or gait={row.gait}"
                )
            return f"{where}: a schedule that changes gait walks each gait at its own duty; set duty=0"
        c = row.command
        try:
            q = dataclasses.replace(
                p, vx=c.vx, vy=c.vy, yaw_rate=c.yaw_rate, gait=row.gait, step_height=row.step_height,
                stand_height=row.stand_height, schedule=(), waypoints=(), duration=_shortest(p),
            )  # fmt: skip
        except ValueError as e:
            return f"{where}: {e}"
        problem = check(q)
        if problem:
            return f"{where}: {problem}"
    return ""


REPLAY_SAMPLES: int = 120  # targets per gait period in the kinematic replay of a schedule with gait changes


def switch_problem(p: Any, neutral: np.ndarray, settle: float) -> str:
    """'' if every foot target of a schedule's gait changes is reachable, else when and which foot is not.

    The schedule is planned as the walking controller plans it (its segments, the planner's gait switches),
    without the physics, at REPLAY_SAMPLES targets a period, and every target goes through the legs' IK: a
    switch stretches some stances (a foot waits for the new gait's clock) beyond any row's own cycle.
    """
    rows = setpoints(p)
    if all(r.gait == rows[0].gait for r in rows):
        return ""
    dt = p.period / REPLAY_SAMPLES
    schedule = Schedule(rows, settle, p.period, p.step_height, p.stand_height)
    gaits = p.gaits()
    first = p.the_gait() if rows[0].gait == p.gait else gaits[rows[0].gait]  # as walking.scene.make_controller
    planner = GaitPlanner(first, p.period, p.step_height, neutral, dt, start_time=settle, profile=p.swing)
    layout = p.ROBOT.layout
    rot, hips = layout.hip_rotations(), layout.hip_positions()
    while planner.time < p.duration - 1e-9:
        t = planner.time
        segment = schedule.segment(t)
        n = planner.max_chunk
        if math.isfinite(segment.until):
            n = min(n, max(1, round((segment.until - t) / dt)))
        if segment.gait != planner.gait.name:
            planner.switch(gaits[segment.gait])
        body = planner.plan(segment.command, n)
        times = planner.time - dt * np.arange(n, -1, -1)
        # The rows' heights as the walker adds them (a walk's stand_height of 0.183 m with rows at 0.09 m was
        # replayed at 0.183 m and refused; rows higher than the walk's were replayed lower than walked).
        add_heights(body, schedule, (p.step_height, p.stand_height), times, *planner.flags(times))
        hip = np.einsum("lji,klj->kli", rot, body - hips)
        _, ok = legged.ik_hip_batch(layout, hip)
        if not ok.all():
            k, leg = np.argwhere(~ok)[0]
            last = [s for s in planner.switches if s[0] <= t + k * dt]
            why = f" (after the switch to the {last[-1][1]} gait at {last[-1][0]:.3g} s)" if last else ""
            return (
                f"schedule: at t = {t + k * dt:.3g} s{why} foot {layout.legs[leg]} would leave its reachable "
                "workspace or joint ranges; change gait at a lower speed or keep one gait"
            )
    return ""


def follower_twists(p: Any) -> list[Command]:
    """The fastest twists the path follower may ask for: path_speed in eight directions, turning either way at
    path_yaw_rate (none without waypoints)."""
    twists = []
    for angle in range(0, 360, 45) if p.waypoints else ():
        a = math.radians(angle)
        twists += [Command(p.path_speed * math.cos(a), p.path_speed * math.sin(a), w)
                   for w in (-p.path_yaw_rate, p.path_yaw_rate)]  # fmt: skip
    return twists


def waypoints_problem(p: Any, check: Callable[[Any], str], settle: float) -> str:
    """'' if the course can be walked: the follower's fastest twists are feasible and the walk is long enough."""
    if not p.waypoints:
        return ""
    for c in follower_twists(p):
        try:  # replace() checks the walk it makes: its own refusal is the problem to report
            q = dataclasses.replace(p, vx=c.vx, vy=c.vy, yaw_rate=c.yaw_rate, schedule=(), waypoints=(),
                                    duration=_shortest(p))  # fmt: skip
            problem = check(q)
        except ValueError as e:
            problem = str(e)
        if problem:
            return (
                f"waypoints: the follower may ask for path_speed {p.path_speed:g} m/s in any direction while "
                f"turning at path_yaw_rate {p.path_yaw_rate:g} rad/s, and {problem}; lower path_speed or "
                "path_yaw_rate"
            )
    follower = course(p, settle)
    needed = settle + p.period + follower.total / p.path_speed * 1.2 + 1.0
    if follower.final_heading is not None:  # the turn to it, which may come after the point (it is reached first)
        before = follower.headings[-2] if len(follower.headings) > 1 else 0.0
        needed += abs(math.remainder(follower.final_heading - before, 2 * math.pi)) / p.path_yaw_rate * 1.2
    if p.duration < needed:
        # The longest walk this timestep's run budget takes (it advised a duration the budget then refused).
        limit = p.longest_duration()
        advice = (
            "raise 'duration' to at least that"
            if needed <= limit
            else f"that is longer than the longest walk ({allowed(limit, 'down')} s at timestep {p.timestep:g} s): "
            "shorten the course or raise path_speed"
        )
        return (
            f"waypoints: the course is {follower.total:.3g} m long; at path_speed {p.path_speed:g} m/s"
            + (f" (turning at path_yaw_rate {p.path_yaw_rate:g} rad/s)" if follower.final_heading is not None else "")
            + f" the walk needs about {allowed(needed, 'up')} s; {advice}"
        )
    return ""


def course(p: Any, settle: float) -> PathFollower:
    """The path follower of a walk's waypoints."""
    return PathFollower(p.waypoints, p.path_speed, p.path_yaw_rate, settle, p.gait, p.step_height, p.stand_height)


def source(p: Any, settle: float) -> Schedule | PathFollower | None:
    """The walk's changing command (None: its constant vx, vy, yaw_rate)."""
    if p.schedule:
        return Schedule(setpoints(p), settle, p.period, p.step_height, p.stand_height)
    if p.waypoints:
        return course(p, settle)
    return None


def path(p: Any, settle: float) -> np.ndarray:
    """The planned course (k, 2) [m] from the start: the waypoints, or the schedule's twist integrated every 10 ms."""
    if p.waypoints:
        return np.array([[0.0, 0.0], *[(x, y) for x, y, _ in p.waypoints]])
    schedule = Schedule(setpoints(p), settle, p.period, p.step_height, p.stand_height)
    t = np.arange(0.0, p.duration + 0.01, 0.01)
    v = schedule.value(t)
    yaw = np.concatenate([[0.0], np.cumsum(v[:-1, 2] * 0.01)])
    c, s = np.cos(yaw), np.sin(yaw)
    return np.cumsum(np.stack([c * v[:, 0] - s * v[:, 1], s * v[:, 0] + c * v[:, 1]], -1) * 0.01, axis=0)


HEADING_DISTANCE: float = 0.05  # [m] a course's direction is the one to its first point this far from the start


def direction(course: np.ndarray, reach: float = HEADING_DISTANCE) -> np.ndarray:
    """Unit vector (2,) from the start to where a course (k, 2), a polyline from the start, first gets `reach` [m]
    away (its farthest point if it never does; +x if it never leaves the start)."""
    distance = np.hypot(course[:, 0], course[:, 1])
    far = np.flatnonzero(distance >= reach)
    k = int(far[0]) if far.size else int(np.argmax(distance))
    point = course[k]
    if far.size and k > 0:  # on the segment into it, the point at exactly `reach` (|p0 + s (p1 - p0)| = reach)
        p0, step = course[k - 1], course[k] - course[k - 1]
        a, b, c = step @ step, 2.0 * (p0 @ step), p0 @ p0 - reach**2
        point = p0 + (-b + math.sqrt(max(b * b - 4.0 * a * c, 0.0))) / (2.0 * a) * step
    length = math.hypot(point[0], point[1])
    return point / length if length > 1e-9 else np.array([1.0, 0.0])


def extent(course: np.ndarray, margin: float) -> tuple[float, float, float, float]:
    """(x min, x max, y min, y max) [m] of the ground a course (k, 2) may cross, with a margin."""
    lo, hi = course.min(axis=0) - margin, course.max(axis=0) + margin
    return float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1])
