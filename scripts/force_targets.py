"""Measures issue 19's foot-force targets: flat and 1 cm rough ground (seeds), the three gaits at the issue's speeds.

Usage: python scripts/force_targets.py [--set name=value ...] [--seeds 0,1,2,3,4] [--gaits tripod,ripple,wave]
                                       [--flat-only | --rough-only] [--jobs 2] [--duration 8]

Prints one line per walk: foot_bounces, stance_force_ripple (of W/6), touchdown_impact_ratio,
stance_loaded_fraction (all / worst foot), load_share_min, speed error, slip per stance, sag, roll/pitch p-p,
fell. Targets: bounces 0, ripple <= 3 %, impact <= 1.6, loaded >= 0.95. Flat walks use hexabot-walk (planned
touchdown), rough ones hexabot-rough (roughness 1 cm, touchdown=sensed) at the same durations.
"""

from __future__ import annotations

import argparse
import math
import sys
from concurrent.futures import ProcessPoolExecutor

SPEEDS = {"tripod": 0.1, "ripple": 0.1, "wave": 0.05}


def _value(text: str):
    try:
        return float(text) if "." in text or "e" in text else int(text)
    except ValueError:
        return text


def one(case: tuple) -> str:
    import hexabot_sim as hs

    scenario, gait, seed, duration, options = case
    r = hs.run(scenario, gait=gait, vx=SPEEDS[gait], duration=duration, seed=seed, **options)
    m = {k: (math.nan if v.value is None else v.value) for k, v in r.metrics.items()}  # None: none measured
    ground = "flat" if scenario == "hexabot-walk" else f"rough {seed}"
    speed = m["vx_error"] if m.get("vx_error") is not None else m.get("speed_made_good_error", float("nan"))
    return (
        f"{gait:6s} {ground:8s} bounces {m['foot_bounces']:4.0f}  ripple {100 * m['stance_force_ripple']:5.1f} %  "
        f"impact {m['touchdown_impact_ratio']:5.2f}  loaded {m['stance_loaded_fraction']:.3f} / "
        f"{m['stance_loaded_fraction_min']:.3f}  share_min {m['load_share_min']:.2f}  speed {100 * speed:+6.2f} %  "
        f"slip {m['slip_per_stance']:5.2f} mm  sag {1000 * m['body_height_sag']:5.2f} mm  roll/pitch p-p "
        f"{m['roll_ptp']:.2f}/{m['pitch_ptp']:.2f} deg  fell {m['fell']}  rtf {m['real_time_factor']:.0f}"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--set", action="append", default=[], help="a walk parameter name=value (repeatable)")
    parser.add_argument("--seeds", default="0,1,2,3,4")
    parser.add_argument("--gaits", default="tripod,ripple,wave")
    parser.add_argument("--flat-only", action="store_true")
    parser.add_argument("--rough-only", action="store_true")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--duration", type=float, default=8.0)
    args = parser.parse_args(argv)
    options = dict((k, _value(v)) for k, v in (item.split("=", 1) for item in args.set))
    gaits = args.gaits.split(",")
    cases = []
    if not args.rough_only:
        cases += [("hexabot-walk", g, 0, args.duration, options) for g in gaits]
    if not args.flat_only:
        rough = {"touchdown": "sensed", **options}
        cases += [("hexabot-rough", g, int(s), args.duration, rough) for g in gaits for s in args.seeds.split(",")]
    print("options:", " ".join(f"{k}={v}" for k, v in options.items()) or "defaults", flush=True)
    with ProcessPoolExecutor(args.jobs) as pool:
        for line in pool.map(one, cases):
            print(line, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
