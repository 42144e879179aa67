"""Benchmarks with their targets; every ratio is measured side by side in one run.

Usage: python scripts/bench.py [--repeat N] [--check]

  sim-loop   the pendulum scenario's stepping loop (simulate(): recording + divergence checks)
             vs a bare `mj_step` loop over the same model and number of steps   target <= 1.5x
  video      frames rendered and encoded per second, 640x480, preview preset     target >= 100 fps
  leg-loop   the leg-step loop (resolved-rate controller + recording + mj_step, dynamic mode)
             vs a bare `mj_step` loop over the same model and number of steps   target <= 2x
  hexabot    the walking hexabot's loop (mj_step + 18-joint controller + recording) at its 2 ms
             implicitfast step: real-time factor                                 target >= 50x
             vs bare `mj_step` replaying the recorded controls on the same walk  target <= 2.5x
  rough      the same on 1 cm rough ground (the hexabot-rough preset: heightfield, feet that find
             the ground), tripod, ripple and wave: real-time factor              target >= 40x
  sweep      a 64-cell pendulum sweep on 2 local workers vs 1 (pool start included) target >= 1.7x
             and the per-cell overhead of the Dask path (LocalCluster) vs the local pool
  list       wall time of `hexabot-sim list` (python -m hexabot_sim list)        target <= 0.5 s

Timings alternate between the two sides of a ratio and keep each side's best (least disturbed)
repeat, because these machines are shared and noisy. `--check` exits 1 if a target is missed.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

import mujoco

from hexabot_sim import gl, params, registry, render
from hexabot_sim.result import at_home
from hexabot_sim.robots.leg import step as leg
from hexabot_sim.robots.pendulum import pendulum
from hexabot_sim.simulate import simulate, step_count
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


def bench_video(repeat: int) -> dict[str, float] | str:
    backend, reason, _notice = gl.choose()
    if backend is None:
        return reason
    scenario = registry.get("pendulum")
    p = params.resolve(scenario.params_type, scenario.defaults)
    result = scenario.runner("pendulum", p)
    t, qpos = result.trajectory.t, result.trajectory.qpos
    out: dict[str, float] = {"backend": backend}  # type: ignore[dict-item]
    with tempfile.TemporaryDirectory() as tmp:
        for quality in ("preview", "high"):
            best = 0.0
            for _ in range(repeat if quality == "preview" else 1):
                start = time.perf_counter()
                frames = render.render_video(result.model, t, qpos, Path(tmp) / "v.mp4", camera="side", quality=quality)
                best = max(best, frames / (time.perf_counter() - start))
            out[f"{quality}_fps"] = best
    out["frames"] = frames
    return out


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
    with LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None, silence_logs=50) as cluster:
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


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--check", action="store_true", help="exit 1 if a target is missed")
    args = parser.parse_args()

    failures = []
    for label, result, target in (
        ("sim-loop", bench_sim_loop(args.repeat), 1.5),
        ("leg-loop", bench_leg_loop(args.repeat), 2.0),
    ):
        ok = result["ratio"] <= target
        failures += [] if ok else [label]
        print(
            f"{label:<9} {result['steps']} steps: bare mj_step {result['bare_us_per_step']:.2f} us/step, "
            f"loop {result['loop_us_per_step']:.2f} us/step, ratio {result['ratio']:.2f}x (target <= {target:g}x) "
            f"{'ok' if ok else 'MISSED'}"
        )

    walk = bench_hexabot(args.repeat)
    ok = walk["ratio"] <= 2.5 and walk["real_time_factor"] >= 50
    failures += [] if ok else ["hexabot"]
    print(
        f"hexabot   {walk['steps']} steps of 2 ms: loop {walk['loop_us_per_step']:.1f} us/step = "
        f"{walk['real_time_factor']:.0f}x real time (target >= 50x); bare mj_step replaying its controls "
        f"{walk['bare_us_per_step']:.1f} us/step ({walk['bare_real_time_factor']:.0f}x); ratio {walk['ratio']:.2f}x "
        f"(target <= 2.5x) {'ok' if ok else 'MISSED'}"
    )

    # Rough ground: the hexabot-rough preset (1 cm heightfield, feet that find the ground), every gait.
    for gait, vx in (("tripod", 0.1), ("ripple", 0.1), ("wave", 0.05)):
        rough = bench_hexabot(args.repeat, name="hexabot-rough", gait=gait, vx=vx)
        ok = rough["real_time_factor"] >= 40
        failures += [] if ok else [f"hexabot-rough {gait}"]
        print(
            f"rough     hexabot-rough --set gait={gait} --set vx={vx:g}: "
            f"loop {rough['loop_us_per_step']:.1f} us/step = {rough['real_time_factor']:.0f}x real time "
            f"(target >= 40x) {'ok' if ok else 'MISSED'}; bare mj_step "
            f"{rough['bare_us_per_step']:.1f} us/step (heightfield contacts), ratio {rough['ratio']:.2f}x"
        )

    video = bench_video(max(1, args.repeat // 2))
    if isinstance(video, str):
        print(f"video     skipped: {video}")
    else:
        ok = video["preview_fps"] >= 100
        failures += [] if ok else ["video"]
        print(
            f"video     {video['frames']} frames 640x480 via {video['backend']}: "
            f"preview {video['preview_fps']:.0f} fps "
            f"(target >= 100) {'ok' if ok else 'MISSED'}; high {video['high_fps']:.0f} fps "
            f"(preview/high = {video['preview_fps'] / video['high_fps']:.1f}x)"
        )

    sw = bench_sweep(max(1, args.repeat // 2))
    ok = sw["speedup"] >= 1.7 or (os.cpu_count() or 1) < 2
    failures += [] if ok else ["sweep"]
    dask = (
        f"; per cell (2 workers, {sw['tiny_cells']} cells of 10 steps): pool {sw['pool_ms_per_cell']:.2f} ms, "
        f"Dask LocalCluster {sw['dask_ms_per_cell']:.2f} ms (+{sw['dask_ms_per_cell'] - sw['pool_ms_per_cell']:.2f} ms)"
        if "dask_ms_per_cell" in sw
        else "; Dask: skipped (distributed not installed)"
    )
    print(
        f"sweep     {sw['cells']} pendulum cells: 1 worker {sw['one_s']:.2f} s, 2 workers {sw['two_s']:.2f} s, "
        f"speed-up {sw['speedup']:.2f}x (target >= 1.7x) {'ok' if ok else 'MISSED'}{dask}"
    )

    lst = bench_list(args.repeat)
    ok = lst["list_s"] <= 0.5
    failures += [] if ok else ["list"]
    print(
        f"list      hexabot-sim list {lst['list_s']:.3f} s (python start-up alone {lst['python_startup_s']:.3f} s) "
        f"(target <= 0.5 s) {'ok' if ok else 'MISSED'}"
    )
    if failures:
        print(f"missed: {', '.join(failures)}")
    return 1 if (failures and args.check) else 0


if __name__ == "__main__":
    sys.exit(main())
