"""Measures issue 22's targets: a schedule's rows, a figure-eight of waypoints, a tripod -> wave -> tripod change.

Usage: python scripts/command_targets.py [--seeds N] [--quick]

  schedule    forward 0.1 m/s, turn 0.3 rad/s, crab 0.08 m/s, back 0.1 m/s, 5 s each (tripod, flat): each row's
              steady speed (whole cycles after its ramp) against its command          target within 3 %
  eight       a figure-eight of waypoints (two 0.5 m circles, 48 points each) at 0.1 m/s, tripod: cross-track
              error RMS and max, course time, cost of transport; flat                 target RMS <= 2 cm
              and 1 cm rough ground (hexabot-rough: sensed touchdown), seeds 0..N-1    target RMS <= 4 cm
  switch      tripod -> wave -> tripod at 0.05 m/s (rows 6 s apart, flat): no fall, the speed's dip (mean over
              a period) across each switch, and the feet's bounces (foot_bounces' definition, walking.forces:
              a loaded foot unloading for under 60 ms) in the 2.5 s from each switch against 2.5 s of the
              steady gait after that                                                target dip <= 10 %
              the same with load_sharing=admittance, with feet=pad swing=quintic (issue 19), with that at a
              2 s period and with load_sharing=force on the pad, and on 1 cm rough ground (hexabot-rough, sensed
              touchdown), seeds 0 and 1, with the defaults and with load_sharing=force on the pad

Prints one line per measurement; --quick runs the figure-eight on flat ground only.
"""

from __future__ import annotations

import argparse
import math
import sys
import time

import hexabot_sim as hs
from hexabot_sim.walking import course


def figure_eight(radius: float = 0.5, points: int = 48) -> list[list[float]]:
    """Waypoints of two circles of `radius` that touch at the start, the first to the left (counter-clockwise)."""
    out = []
    for k in range(1, points + 1):
        a = -math.pi / 2 + 2 * math.pi * k / points
        out.append([radius * math.cos(a), radius + radius * math.sin(a)])
    for k in range(1, points + 1):
        a = math.pi / 2 - 2 * math.pi * k / points
        out.append([radius * math.cos(a), -radius + radius * math.sin(a)])
    return out


def schedule() -> None:
    rows = [[0, 0.1, 0, 0], [5.5, 0, 0, 0.3], [10.5, 0, 0.08, 0], [15.5, -0.1, 0, 0]]
    r = hs.run("hexabot-walk", schedule=rows, duration=20.5)
    for row in r.raw.extras["schedule_table"]:
        cmd = rows[row["row"] - 1]
        print(
            f"schedule row {row['row']} (t = {cmd[0]:g} s, command vx {cmd[1]:g} vy {cmd[2]:g} m/s, yaw rate "
            f"{cmd[3]:g} rad/s): measured vx {row['vx']:.4f} vy {row['vy']:.4f} m/s, yaw rate {row['yaw_rate']:.4f} "
            f"rad/s over {row['window'][0]:.3g}-{row['window'][1]:.3g} s; speed error "
            f"{_pct(row['speed_error'])}, yaw-rate error {_pct(row['yaw_rate_error'])}"
        )
    print(f"schedule fell: {r.metrics['fell'].value}")


def _pct(value: float | None) -> str:
    return "-" if value is None else f"{100 * value:.2f} %"


def eight(scenario: str, seed: int) -> None:
    started = time.perf_counter()
    r = hs.run(scenario, waypoints=figure_eight(), duration=80.0, seed=seed)
    m = r.metrics
    print(
        f"figure-eight {scenario} seed {seed}: cross_track_rms {m['cross_track_rms'].value * 1000:.2f} mm, "
        f"cross_track_max {m['cross_track_max'].value * 1000:.2f} mm, course_time {m['course_time'].value:.1f} s "
        f"(length {m['course_length'].value:.3f} m), course_cost_of_transport "
        f"{m['course_cost_of_transport'].value:.3f}, fell {m['fell'].value} ({time.perf_counter() - started:.0f} s)"
    )


def switch(scenario: str = "hexabot-walk", seed: int = 0, **options: str | float) -> None:
    """The tripod -> wave -> tripod change; `options`: walk parameters, e.g. load_sharing, feet, swing."""
    rows = [[0, 0.05, 0, 0, "tripod"], [5, 0.05, 0, 0, "wave"], [11, 0.05, 0, 0, "tripod"]]
    r = hs.run(scenario, schedule=rows, duration=17.0, seed=seed, **options)
    shown = " ".join(f"{k}={v}" for k, v in options.items()) or "defaults"
    print(f"switch {scenario} seed {seed} {shown}:")
    raw = r.raw
    t = raw.columns["t"]
    loaded = raw.extras["contacts"].loaded(float(raw.model.body_subtreemass[raw.model.body("torso").id]))
    for when, gait in raw.extras["gait_switches"]:
        dip = course.speed_dip(t, raw.columns["vx_body"], 0.05, 1.0, when - 1.0, when + 3.0)
        across = course.count_bounces(loaded, t, when, when + 2.5)
        steady = course.count_bounces(loaded, t, when + 3.0, when + 5.5)
        print(
            f"switch to {gait} at {when:.3g} s: speed dip {100 * dip:.2f} %, bounces in the 2.5 s from it "
            f"{across}, in 2.5 s of steady {gait} after that {steady}"
        )
    late = r.metrics.get("touchdown_error_max")
    late_text = "" if late is None else f", touchdown_error_max {late.value:.3f} s"
    print(f"switch fell: {r.metrics['fell'].value}{late_text}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3, help="rough-ground seeds of the figure-eight (default 3)")
    parser.add_argument("--quick", action="store_true", help="the figure-eight on flat ground only")
    args = parser.parse_args(argv)
    eight("hexabot-walk", 0)
    if args.quick:
        return 0
    for seed in range(args.seeds):
        eight("hexabot-rough", seed)
    schedule()
    switch()
    switch(load_sharing="admittance")
    switch(feet="pad", swing="quintic")  # issue 19's bounce-free option
    switch(feet="pad", swing="quintic", period=2.0)  # its slower swings: no touchdown rebounds (docs/hexabot.md)
    switch(load_sharing="force", feet="pad", swing="quintic")  # the stance force control on the pad
    for seed in range(min(args.seeds, 2)):
        switch("hexabot-rough", seed)
        switch("hexabot-rough", seed, load_sharing="force", feet="pad", swing="quintic")
    return 0


if __name__ == "__main__":
    sys.exit(main())
