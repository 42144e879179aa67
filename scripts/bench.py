"""Benchmarks with their targets; every ratio is measured side by side in one run.

Usage: python scripts/bench.py [--repeat N] [--check] [--only LINE ...]
       python scripts/bench.py --against REV_OR_DIR [--rounds N] [--repeat N] [--only LINE ...] [--check]

  sim-loop   the pendulum scenario's stepping loop (simulate(): recording + divergence checks)
             vs a bare `mj_step` loop over the same model and number of steps   target <= 1.5x
  leg-loop   the leg-step loop (resolved-rate controller + recording + mj_step, dynamic mode)
             vs a bare `mj_step` loop over the same model and number of steps   target <= 2x
  hexabot    the walking hexabot's loop (mj_step + 18-joint controller + recording) at its 2 ms
             implicitfast step: real-time factor                                 target >= 50x
             vs bare `mj_step` replaying the recorded controls on the same walk  target <= 2.5x
  rough-*    the same on 1 cm rough ground (the hexabot-rough preset: heightfield, feet that find
             the ground), tripod, ripple and wave: real-time factor              target >= 40x
  video      the pendulum run's video (640x480, preview preset, its markers and text overlay), rendered
             and encoded, frames per second                                      target >= 100 fps
             and, alternating with it on the same frames (issue 18):
             - the same without the text overlay: the overlay's share of a frame target <= 10 %
               (the time in draw_text within the pipeline's own runs: the target; the with/without
               difference, in wall and in CPU time, is printed too but is at the mercy of the load)
             - bare mujoco.Renderer + the bundled encoder (imageio-ffmpeg, same preset settings):
               render_video / bare in CPU time (the process's threads + the encoder's; the wall-clock
               ratio is printed too)                                             target <= 1.1x
             the high preset on the first 2 s: preview/high
  sweep      a 64-cell pendulum sweep on 2 local workers vs 1 (pool start included) target >= 1.7x
             and the per-cell overhead of the Dask path (LocalCluster) vs the local pool
  list       wall time of `hexabot-sim list` (python -m hexabot_sim list)        target <= 0.5 s
  compile    a first walk's cold numba compile (fresh process, empty cache): a default walk's kernels vs
             every group's (load_sharing=force and admittance add theirs)        target <= 75 %
  env        the Gymnasium environments (scripts/bench_env.py): steps/s, and env step / its bare physics
             (frame_skip x mj_step, the same controls replayed), beside Ant-v5's   target <= Ant-v5's

Timings alternate between the two sides of a ratio and keep each side's best (least disturbed)
repeat, because these machines are shared and noisy. `--check` exits 1 if a target is missed.

--against REV_OR_DIR (issue 18: "every benchmark ratio is no worse, measured side by side, old and new, in
one run"): the old tree is a git revision (checked out into a temporary worktree, removed at the end) or a
directory; the redesign's baseline is 36ed1b2. Each line runs in fresh processes, `--rounds` times for each
tree, old and new alternating (which goes first alternates too), each process importing hexabot_sim from its
tree (PYTHONPATH) and measuring with `--repeat` (default 2); the best timings of all of a side's processes
make its figures. Per line it prints each figure old -> new and new/old, then the new tree's usual line. Judged
(ok / WORSE beyond --tolerance, default 5 %): the ratios each process measures side by side (loop vs bare
mj_step, overlay share, render_video vs bare renderer, sweep speed-up) and list's time; absolute figures (us
per step, real-time factors, fps) are shown in brackets only, since the load of a shared machine moves them
by 20-30 % between processes (seen here with identical code). Each tree is measured by its own
scripts/bench.py (the bench functions use internals that the redesign moves), so a line compares like with
like only where the two bench.py measure it the same way: 36ed1b2's video line films the pendulum with the
time line only, this one the run's video (markers, 3 more text lines), and only this one has the overlay and
bare-renderer figures.
`--check`: exit 1 if a line is worse.
"""

from __future__ import annotations

import argparse
import functools
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this tree's hexabot_sim, not an installed one

sys.path.insert(0, str(Path(__file__).resolve().parent))  # bench_env beside this file (also when run by path)

import mujoco
from bench_env import bench_env, fmt_env
from bench_video import bench_video, derive_video, fmt_video

from hexabot_sim import params, registry
from hexabot_sim.budget import step_count
from hexabot_sim.result import at_home
from hexabot_sim.robots.leg import step as leg
from hexabot_sim.robots.pendulum import pendulum
from hexabot_sim.simulate import simulate
from hexabot_sim.walking import scene as hexabot_scene


def paired_loops(prepare, loop, repeat: int) -> dict[str, float]:
    """Best-of-`repeat` seconds per step of a bare mj_step loop and of `loop`, alternating on fresh states.

    Args:
        prepare: () -> (model, data, n_steps), a fresh start state each call.
        loop: (model, data, n_steps) -> None, the loop under test.
    """
    bare, timed = [], []
    for _ in range(repeat):
        model, data, n = prepare()
        start = time.perf_counter()
        for _ in range(n):
            mujoco.mj_step(model, data)
        bare.append(time.perf_counter() - start)

        model, data, n = prepare()
        start = time.perf_counter()
        loop(model, data, n)
        timed.append(time.perf_counter() - start)
    return {
        "steps": n,
        "bare_us_per_step": min(bare) / n * 1e6,
        "loop_us_per_step": min(timed) / n * 1e6,
        "ratio": min(timed) / min(bare),
    }


def bench_sim_loop(repeat: int) -> dict[str, float]:
    """The pendulum scenario's simulate() (recording + divergence checks) vs bare mj_step."""
    scenario = registry.get("pendulum")
    p = params.resolve(scenario.params_type, scenario.defaults)
    model = mujoco.MjModel.from_xml_string(pendulum.build_xml(p))
    data = mujoco.MjData(model)

    def prepare():
        mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
        return model, data, step_count(p.duration, p.timestep)

    return paired_loops(prepare, simulate, repeat)


def bench_leg_loop(repeat: int) -> dict[str, float]:
    """The leg-step loop (resolved-rate controller + recording + mj_step) vs bare mj_step."""
    scenario = registry.get("leg-step")
    p = params.resolve(scenario.params_type, scenario.defaults)
    runs = []

    def prepare():
        runs.append(leg.prepare(p))
        return runs[-1].model, runs[-1].data, runs[-1].n_steps

    def loop(model, data, n):
        simulate(model, data, n, controller=runs[-1].control, step=runs[-1].step)

    return paired_loops(prepare, loop, repeat)


def bench_hexabot(repeat: int, duration: float = 10.0, name: str = "hexabot-walk", **overrides) -> dict[str, float]:
    """The walking loop vs bare mj_step replaying its recorded controls (the walking robot, not a standing one)."""
    scenario = registry.get(name)
    p = params.resolve(scenario.params_type, scenario.defaults, {"duration": duration, **overrides})
    xml = hexabot_scene.build_xml(p)
    n = step_count(p.duration, p.timestep)
    loop_s, bare_s = [], []
    model, data = at_home(xml)
    hexabot_scene.make_controller(p, model, data)(model, data)  # compiles the numba kernels (or loads them) untimed
    for _ in range(repeat):
        # The whole loop: controller (gait targets, 6 resolved-rate steps), mj_step, recording, checks.
        model, data = at_home(xml)
        controller = hexabot_scene.make_controller(p, model, data)  # what a run uses
        start = time.perf_counter()
        traj = simulate(model, data, n, controller=controller, record_ctrl=True)
        loop_s.append(time.perf_counter() - start)
        # Bare physics on the same walk: the recorded controls, replayed step by step.
        model, data = at_home(xml)
        ctrl = traj.ctrl
        start = time.perf_counter()
        for i in range(1, n + 1):
            data.ctrl[:] = ctrl[i]
            mujoco.mj_step(model, data)
        bare_s.append(time.perf_counter() - start)
        if not (data.qpos == traj.qpos[-1]).all():
            raise RuntimeError("the replay did not reproduce the walk: the bare loop would not time the same physics")
    return {
        "steps": n,
        "bare_us_per_step": min(bare_s) / n * 1e6,
        "loop_us_per_step": min(loop_s) / n * 1e6,
        "ratio": min(loop_s) / min(bare_s),
        "real_time_factor": p.duration / min(loop_s),
        "bare_real_time_factor": p.duration / min(bare_s),
    }


def bench_sweep(repeat: int, duration: float = 5.0) -> dict[str, float]:
    """A 64-cell pendulum sweep on 2 local workers vs 1, and the per-cell cost of the Dask path vs the pool."""
    from hexabot_sim import dask_cluster, pool, sweep

    grid = ["damping=log:0.001:0.1:8", "stiffness=0.2:2:8"]
    plan = sweep.plan("pendulum", grid, {}, {"duration": str(duration)})

    def timed(executor, jobs) -> float:
        start = time.perf_counter()
        pool.run_cells(executor, jobs)
        return time.perf_counter() - start

    one, two = [], []
    for _ in range(repeat):  # pool start-up included: it is part of every sweep
        one.append(timed(pool.local_executor(1), sweep.jobs(plan)))
        two.append(timed(pool.local_executor(2), sweep.jobs(plan)))
    out = {"cells": len(plan.cells), "one_s": min(one), "two_s": min(two), "speedup": min(one) / min(two)}
    try:
        from distributed import LocalCluster
    except ImportError:
        return out
    # Per-cell overhead: cells of a few steps, so the time is the executor's, not the physics'.
    tiny = sweep.plan("pendulum", ["damping=0.001:0.1:200"], {}, {"duration": "0.01"})
    pool_s, dask_s = [], []
    with (
        tempfile.TemporaryDirectory(prefix="bench-dask-") as scratch,
        LocalCluster(
            n_workers=2, threads_per_worker=1, dashboard_address=None, silence_logs=50, local_directory=scratch
        ) as cluster,
    ):  # its scratch files in a folder of its own (they were left in /tmp/dask-scratch-space)
        for _ in range(repeat):
            pool_s.append(timed(pool.local_executor(2), sweep.jobs(tiny)))
            with dask_cluster.dask_executor(cluster.scheduler_address) as (executor, _workers):
                dask_s.append(timed(executor, sweep.jobs(tiny)))
    n = len(tiny.cells)
    return out | {"tiny_cells": n, "pool_ms_per_cell": min(pool_s) / n * 1e3, "dask_ms_per_cell": min(dask_s) / n * 1e3}


def bench_list(repeat: int) -> dict[str, float]:
    def timed(argv: list[str]) -> float:
        start = time.perf_counter()
        subprocess.run(argv, check=True, stdout=subprocess.DEVNULL)
        return time.perf_counter() - start

    empty, listing = [], []
    for _ in range(repeat):
        empty.append(timed([sys.executable, "-c", "pass"]))
        listing.append(timed([sys.executable, "-m", "hexabot_sim", "list"]))
    return {"python_startup_s": min(empty), "list_s": min(listing)}


def bench_compile(repeat: int) -> dict[str, float]:
    """Cold compiles of the walking kernels, each in a fresh process with an empty numba cache: a default walk's
    ("walk") and every group's (a walk with load_sharing=force, then one with admittance, compile the rest)."""

    def cold(groups: str) -> float:
        with tempfile.TemporaryDirectory() as cache:
            code = f"from hexabot_sim.control import kernels; kernels.warm_up({groups})"
            start = time.perf_counter()
            subprocess.run([sys.executable, "-c", code], check=True, env={**os.environ, "NUMBA_CACHE_DIR": cache})
            return time.perf_counter() - start

    walk, every = [], []
    for _ in range(repeat):
        walk.append(cold("'walk'"))
        every.append(cold("*kernels.GROUPS"))
    return {"walk_s": min(walk), "all_s": min(every), "share": min(walk) / min(every)}


def fmt_compile(r: dict) -> tuple[str, bool]:
    share = r["share"]
    ok = share <= 0.75
    return (
        f"compile   cold numba compile, fresh process: a default walk's kernels {r['walk_s']:.1f} s, every "
        f"group's (force control, admittance) {r['all_s']:.1f} s: {100 * share:.0f} % "
        "(target <= 75 %; every group for every walk: 100 %) "
        f"{'ok' if ok else 'MISSED'}",
        ok,
    )


# ------------------------------------------------------------------------------------------------ lines


def derive(r: dict) -> dict:
    """Ratios recomputed from the (best) raw timings they are made of."""
    r = dict(r)
    if "loop_us_per_step" in r and "bare_us_per_step" in r:
        r["ratio"] = r["loop_us_per_step"] / r["bare_us_per_step"]
    if "one_s" in r and "two_s" in r:
        r["speedup"] = r["one_s"] / r["two_s"]
    return derive_video(r)


def fmt_loop(label: str, target: float):
    def text(r: dict) -> tuple[str, bool]:
        ok = r["ratio"] <= target
        return (
            f"{label:<9} {r['steps']} steps: bare mj_step {r['bare_us_per_step']:.2f} us/step, "
            f"loop {r['loop_us_per_step']:.2f} us/step, ratio {r['ratio']:.2f}x (target <= {target:g}x) "
            f"{'ok' if ok else 'MISSED'}",
            ok,
        )

    return text


def fmt_hexabot(r: dict) -> tuple[str, bool]:
    ok = r["ratio"] <= 2.5 and r["real_time_factor"] >= 50
    return (
        f"hexabot   {r['steps']} steps of 2 ms: loop {r['loop_us_per_step']:.1f} us/step = "
        f"{r['real_time_factor']:.0f}x real time (target >= 50x); bare mj_step replaying its controls "
        f"{r['bare_us_per_step']:.1f} us/step ({r['bare_real_time_factor']:.0f}x); ratio {r['ratio']:.2f}x "
        f"(target <= 2.5x) {'ok' if ok else 'MISSED'}",
        ok,
    )


def fmt_rough(gait: str, vx: float):
    def text(r: dict) -> tuple[str, bool]:
        ok = r["real_time_factor"] >= 40
        return (
            f"rough     hexabot-rough --set gait={gait} --set vx={vx:g}: "
            f"loop {r['loop_us_per_step']:.1f} us/step = {r['real_time_factor']:.0f}x real time "
            f"(target >= 40x) {'ok' if ok else 'MISSED'}; bare mj_step "
            f"{r['bare_us_per_step']:.1f} us/step (heightfield contacts), ratio {r['ratio']:.2f}x",
            ok,
        )

    return text


def fmt_sweep(r: dict) -> tuple[str, bool]:
    ok = r["speedup"] >= 1.7 or (os.cpu_count() or 1) < 2
    dask = (
        f"; per cell (2 workers, {r['tiny_cells']} cells of 10 steps): pool {r['pool_ms_per_cell']:.2f} ms, "
        f"Dask LocalCluster {r['dask_ms_per_cell']:.2f} ms (+{r['dask_ms_per_cell'] - r['pool_ms_per_cell']:.2f} ms)"
        if "dask_ms_per_cell" in r
        else "; Dask: skipped (distributed not installed)"
    )
    return (
        f"sweep     {r['cells']} pendulum cells: 1 worker {r['one_s']:.2f} s, 2 workers {r['two_s']:.2f} s, "
        f"speed-up {r['speedup']:.2f}x (target >= 1.7x) {'ok' if ok else 'MISSED'}{dask}",
        ok,
    )


def fmt_list(r: dict) -> tuple[str, bool]:
    ok = r["list_s"] <= 0.5
    return (
        f"list      hexabot-sim list {r['list_s']:.3f} s (python start-up alone {r['python_startup_s']:.3f} s) "
        f"(target <= 0.5 s) {'ok' if ok else 'MISSED'}",
        ok,
    )


# name -> (measure(repeat) -> result, text(result) -> (printed line(s), target met),
#          figures --against judges (ratios measured within one process: the load weighs on both of their sides),
#          figures --against shows (absolute: at the mercy of the machine's load))
LINES: dict[str, tuple] = {
    "sim-loop": (bench_sim_loop, fmt_loop("sim-loop", 1.5), ("ratio",), ("loop_us_per_step",)),
    "leg-loop": (bench_leg_loop, fmt_loop("leg-loop", 2.0), ("ratio",), ("loop_us_per_step",)),
    "hexabot": (bench_hexabot, fmt_hexabot, ("ratio",), ("real_time_factor",)),
    **{
        f"rough-{gait}": (
            functools.partial(bench_hexabot, name="hexabot-rough", gait=gait, vx=vx),
            fmt_rough(gait, vx),
            ("ratio",),
            ("real_time_factor",),
        )
        for gait, vx in (("tripod", 0.1), ("ripple", 0.1), ("wave", 0.05))
    },
    "video": (
        bench_video,
        fmt_video,
        ("draw_text_share", "vs_bare_cpu"),
        ("preview_fps", "overlay_cpu_share", "vs_bare", "high_fps", "high_2s_fps"),
    ),
    "sweep": (lambda repeat: bench_sweep(max(1, repeat // 2)), fmt_sweep, ("speedup",), ("dask_ms_per_cell",)),
    "list": (bench_list, fmt_list, ("list_s",), ()),
    "compile": (lambda repeat: bench_compile(max(1, repeat // 3)), fmt_compile, ("share",), ("walk_s", "all_s")),
    "env": (lambda repeat: bench_env(max(1, repeat // 2)), fmt_env, (), ()),
}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, help="repeats per measurement (default 5; with --against 2)")
    parser.add_argument(
        "--check", action="store_true", help="exit 1 if a target is missed (with --against: a line worse)"
    )
    parser.add_argument("--only", action="append", choices=list(LINES), metavar="LINE",
                        help=f"only this line (repeatable): {', '.join(LINES)}")  # fmt: skip
    parser.add_argument("--against", metavar="REV_OR_DIR",
                        help="measure this git revision's tree (or a directory) too, alternating")  # fmt: skip
    parser.add_argument("--rounds", type=int, default=3, help="with --against: old/new alternations (default 3)")
    parser.add_argument("--tolerance", type=float, default=0.05,
                        help="with --against: worse by at most this fraction is no worse (default 0.05)")  # fmt: skip
    args = parser.parse_args()
    lines = args.only or list(LINES)

    if args.against:
        from bench_against import against  # beside this script

        code = against(LINES, args.against, lines, args.rounds, args.repeat or 2, args.tolerance)
        return code if args.check else 0

    failures = []
    for line in lines:
        measure, text, *_ = LINES[line]
        printed, ok = text(measure(args.repeat or 5))
        print(printed, flush=True)
        failures += [] if ok else [line]
    if failures:
        print(f"missed: {', '.join(failures)}")
    return 1 if (failures and args.check) else 0


if __name__ == "__main__":
    sys.exit(main())
