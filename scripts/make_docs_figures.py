"""Regenerates the figures and the video frame shown in README.md and the pages in docs/ (docs/*.png).

Usage: python scripts/make_docs_figures.py [--hexabot | --terrain | --forces | --rough-forces | --slow-forces |
                                           --commands]
       (only the walking hexabot's / the terrain's / the foot forces' (flat and rough) / the rough ground's foot forces'
       / the foot forces' at a 3 s period / the changing commands' figures)
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

from hexabot_sim.__main__ import main  # the same path a user takes

DOCS = Path(__file__).resolve().parent.parent / "docs"


def run(scenario: str, *extra: str) -> Path:
    out = Path(tempfile.mkdtemp()) / scenario
    code = main(["run", scenario, "--out", str(out), *extra])
    if code != 0:
        sys.exit(code)
    return out


def save_frame(video: Path, index: int, png: Path) -> None:
    """Writes frame `index` of an MP4 as a PNG."""
    import imageio.v2 as imageio

    reader = imageio.get_reader(str(video))
    try:
        imageio.imwrite(png, reader.get_data(index))
    finally:
        reader.close()


def main_() -> int:

    DOCS.mkdir(exist_ok=True)
    spring = run("pendulum", "--video")
    for name in ("angle_velocity", "phase", "energy"):
        (DOCS / f"pendulum_{name}.png").write_bytes((spring / f"{name}.png").read_bytes())
    save_frame(spring / "video.mp4", 12, DOCS / "pendulum_frame.png")  # t = 0.4 s
    undamped = run("pendulum-undamped")
    (DOCS / "pendulum_undamped_angle_velocity.png").write_bytes((undamped / "angle_velocity.png").read_bytes())

    step = run("leg-step", "--video")
    for name in ("foot_position", "joints", "singularity", "workspace"):
        (DOCS / f"leg_{name}.png").write_bytes((step / f"{name}.png").read_bytes())
    outside = run("leg-step", "--set", "amplitude=0.1", "--set", "omega=0.5236", "--video")
    for name in ("foot_position", "singularity"):
        (DOCS / f"leg_outside_{name}.png").write_bytes((outside / f"{name}.png").read_bytes())
    save_frame(outside / "video.mp4", 150, DOCS / "leg_outside_frame.png")  # t = 5 s: stretched, off the line
    sweep = run("leg-sweep")
    (DOCS / "leg_sweep.png").write_bytes((sweep / "sweep.png").read_bytes())
    hexabot_figures()
    command_figures()
    terrain_figures()
    force_figures()
    print(f"wrote figures to {DOCS}")
    return 0


def hexabot_figures() -> None:
    """The walking hexabot: the default walk with its video, and an imperfect robot without/with heading hold."""

    walk = run("hexabot-walk", "--video")
    for name in ("path", "gait_diagram", "velocity", "body", "slip"):
        (DOCS / f"hexabot_{name}.png").write_bytes((walk / f"{name}.png").read_bytes())
    save_frame(walk / "video.mp4", 300, DOCS / "hexabot_frame.png")  # t = 10 s
    imperfect = ["--set", "vx=0.15", "--set", "trim_error_deg=1", "--set", "com_offset=0.01"]
    imperfect += ["--set", "friction_spread=0.2", "--set", "duration=25", "--no-plots"]
    for hold in ("off", "on"):
        folder = run("hexabot-walk", *imperfect[:-1], "--set", f"heading_hold={hold}")
        (DOCS / f"hexabot_imperfect_hold_{hold}_path.png").write_bytes((folder / "path.png").read_bytes())


def command_figures() -> None:
    """Commands that change (issue 22): the figure-eight course, the schedule's velocities, a gait change."""
    examples = DOCS.parent / "examples"
    eight = run("hexabot-walk", "--set", f"waypoints={examples / 'figure_eight.csv'}", "--set", "duration=80")
    (DOCS / "hexabot_course_eight.png").write_bytes((eight / "course.png").read_bytes())
    schedule = run("hexabot-walk", "--set", f"schedule={examples / 'schedule.csv'}", "--set", "duration=20.5")
    (DOCS / "hexabot_schedule_velocity.png").write_bytes((schedule / "velocity.png").read_bytes())
    change = run("hexabot-walk", "--set", f"schedule={examples / 'gait_change.csv'}", "--set", "duration=17")
    (DOCS / "hexabot_gait_switch.png").write_bytes((change / "gait_switch_1.png").read_bytes())


def terrain_figures() -> None:
    """The hexabot on real ground: the terrain presets with their videos, and the slope with levelling off."""
    for name, frame in (("slope", 240), ("rough", 300), ("kerb", 210)):  # t = 8, 10, 7 s (astride the kerb)
        folder = run(f"hexabot-{name}", "--video")
        stem = "terrain_slope_level_on" if name == "slope" else f"terrain_{name}"
        (DOCS / f"{stem}.png").write_bytes((folder / "terrain.png").read_bytes())
        save_frame(folder / "video.mp4", frame, DOCS / f"terrain_{name}_frame.png")
        if name == "slope":
            (DOCS / f"{stem}_body.png").write_bytes((folder / "body.png").read_bytes())
    off = run("hexabot-slope", "--set", "level_body=off")
    for name, suffix in (("terrain", ""), ("body", "_body")):
        (DOCS / f"terrain_slope_level_off{suffix}.png").write_bytes((off / f"{name}.png").read_bytes())


FORCE_MODES: dict[str, tuple[str, ...]] = {  # the force figures' stance modes: their --set values
    "off": ("load_sharing=off",),
    "admittance": ("load_sharing=admittance",),
    "pad": ("feet=pad", "swing=quintic"),
    "force": ("load_sharing=force", "feet=pad", "swing=quintic"),
}


def force_figures(modes: tuple[str, ...] = tuple(FORCE_MODES), stairs: bool = True) -> None:
    """The feet's forces against the gait plan (issue 19): each gait at the issue's speed with stiff stance legs
    (the default), with the admittance (load_sharing=admittance), with the foot pad and quintic swing, and with the
    stance force control on the pad; and the stairs."""
    for gait, vx in (("tripod", "0.1"), ("ripple", "0.1"), ("wave", "0.05")):
        for mode in modes:
            sets = [word for value in FORCE_MODES[mode] for word in ("--set", value)]
            folder = run("hexabot-walk", "--set", f"gait={gait}", "--set", f"vx={vx}", "--set", "duration=8", *sets)
            (DOCS / f"forces_{gait}_{mode}.png").write_bytes((folder / "foot_forces.png").read_bytes())
    rough_force_figures()
    slow_force_figures()
    if not stairs:
        return
    folder = run("hexabot-stairs", "--video")
    (DOCS / "terrain_stairs.png").write_bytes((folder / "terrain.png").read_bytes())
    save_frame(folder / "video.mp4", 270, DOCS / "terrain_stairs_frame.png")  # t = 9 s, on the second step


def rough_force_figures() -> None:
    """The feet's forces on 1 cm rough ground (seed 0), with the stance force control on the pad, without and with the
    terrain map (issue 19: the landings)."""
    for gait, vx in (("tripod", "0.1"), ("ripple", "0.1"), ("wave", "0.05")):
        for name, extra in (("force", ()), ("map", ("--set", "terrain_map=on"))):
            sets = [word for value in FORCE_MODES["force"] for word in ("--set", value)]
            folder = run("hexabot-rough", "--set", f"gait={gait}", "--set", f"vx={vx}", "--set", "duration=8", *sets,
                         *extra)  # fmt: skip
            (DOCS / f"forces_rough_{gait}_{name}.png").write_bytes((folder / "foot_forces.png").read_bytes())


def slow_force_figures() -> None:
    """The feet's forces at a 3 s period with the stance force control on the pad (issue 19's targets met): each gait
    on the flat and on 1 cm rough ground (seed 0, with the terrain map), 20 s walks."""
    sets = [word for value in (*FORCE_MODES["force"], "period=3", "duration=20") for word in ("--set", value)]
    for gait, vx in (("tripod", "0.1"), ("ripple", "0.1"), ("wave", "0.05")):
        for scenario, stem, extra in (
            ("hexabot-walk", "forces", ()),
            ("hexabot-rough", "forces_rough", ("--set", "terrain_map=on")),
        ):
            folder = run(scenario, "--set", f"gait={gait}", "--set", f"vx={vx}", *sets, *extra)
            (DOCS / f"{stem}_{gait}_slow.png").write_bytes((folder / "foot_forces.png").read_bytes())


if __name__ == "__main__":
    if "--slow-forces" in sys.argv[1:]:
        slow_force_figures()
        sys.exit(0)
    if "--rough-forces" in sys.argv[1:]:
        rough_force_figures()
        sys.exit(0)
    if "--forces" in sys.argv[1:]:
        force_figures()
        sys.exit(0)
    if "--hexabot" in sys.argv[1:]:
        hexabot_figures()
        sys.exit(0)
    if "--terrain" in sys.argv[1:]:
        terrain_figures()
        sys.exit(0)
    if "--commands" in sys.argv[1:]:
        command_figures()
        sys.exit(0)
    sys.exit(main_())
