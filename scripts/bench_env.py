"""bench.py's `env` line: the Gymnasium environments' step against the bare physics it contains, beside Ant-v5's.

For each environment (ours and Gymnasium's Ant-v5, unwrapped, random actions drawn beforehand, the episode run on
through falls so the physics is one trajectory): the time of `step`, and the time of its bare physics, the same
controls replayed from the same start on a second MjData (`frame_skip` x mj_step: mj_step(nstep=frame_skip) with the
action's controls for the joint-level envs and Ant-v5, as their step calls it; for HexabotCommand-v0 the controls the
gait controller wrote before every physics step, recorded in a first run, one mj_step each). Env step and bare
replay alternate step by step (the shared machine's load weighs on both alike); the replay must end in the env's
final state bit for bit, or the line fails: it would not time the same physics. Of `repeat` runs, each side's best.
"""

from __future__ import annotations

import time

import mujoco
import numpy as np

STEPS: dict[str, int] = {  # env steps timed per repeat (~5000 physics steps each)
    "hexabot_sim/HexabotJoints-v0": 500,
    "hexabot_sim/QuadbotJoints-v0": 500,
    "hexabot_sim/HexabotCommand-v0": 100,
    "Ant-v5": 1000,
}


def _make(env_id: str):
    import gymnasium

    import hexabot_sim.envs  # noqa: F401 (registers our ids)

    kwargs = {"terminate_when_unhealthy": False} if env_id == "Ant-v5" else {}
    return gymnasium.make(env_id, **kwargs).unwrapped


def _record(env, actions: np.ndarray) -> tuple[list[np.ndarray], np.ndarray, np.ndarray]:
    """(controls per physics call, start state, end qpos) of a run from reset(seed=0)."""
    env.reset(seed=0)
    m, d = env.model, env.data
    spec = mujoco.mjtState.mjSTATE_INTEGRATION
    start = np.empty(mujoco.mj_stateSize(m, spec))
    mujoco.mj_getState(m, d, start, spec)
    controls: list[np.ndarray] = []
    per_step = hasattr(env, "controller")  # the command env: its controller writes the controls before every mj_step
    if per_step:  # MuJoCo's control callback sees them at every physics step (it changes nothing)
        mujoco.set_mjcb_control(lambda model, data: controls.append(data.ctrl.copy()))
    try:
        for a in actions:
            env.step(a)
            if not per_step:
                controls.append(d.ctrl.copy())
    finally:
        mujoco.set_mjcb_control(None)
    return controls, start, d.qpos.copy()


def _side_by_side(env, actions, controls, start, end, per_call: int) -> tuple[float, float]:
    """(seconds in env.step, seconds of its bare physics), interleaved step by step so the machine's load weighs on
    both alike: after each env.step, a second MjData of the same model replays that step's controls (`per_call`
    mj_steps each) from the same start. Both must end in the recorded final state."""
    m = env.model
    env.reset(seed=0)
    bare = mujoco.MjData(m)
    mujoco.mj_setState(m, bare, start, mujoco.mjtState.mjSTATE_INTEGRATION)
    mujoco.mj_forward(m, bare)
    per_action = len(controls) // len(actions)
    env_s = bare_s = 0.0
    clock = time.perf_counter
    for k, a in enumerate(actions):
        began = clock()
        env.step(a)
        env_s += clock() - began
        chunk = controls[k * per_action : (k + 1) * per_action]
        began = clock()
        for ctrl in chunk:
            bare.ctrl[:] = ctrl
            mujoco.mj_step(m, bare, nstep=per_call)
        bare_s += clock() - began
    if not (np.array_equal(env.data.qpos, end) and np.array_equal(bare.qpos, end)):
        raise RuntimeError("the replay did not reproduce the episode: the bare loop would not time the same physics")
    return env_s, bare_s


def bench_env(repeat: int) -> dict | str:
    try:
        import gymnasium  # noqa: F401
    except ImportError:
        return "gymnasium is not installed (pip install 'hexabot-sim[rl]')"
    out: dict = {}
    for env_id, n in STEPS.items():
        try:
            env = _make(env_id)
        except Exception as e:  # Ant-v5 where its requirements are missing: say so, measure the rest
            out[env_id] = f"{type(e).__name__}: {e}"
            continue
        env.action_space.seed(0)
        actions = np.array([env.action_space.sample() for _ in range(n)])
        frame_skip = env.frame_skip
        per_call = 1 if hasattr(env, "controller") else frame_skip  # the command env: one control per mj_step
        controls, start, end = _record(env, actions)
        env_s, bare_s = [], []
        for _ in range(repeat):
            seconds, bare_seconds = _side_by_side(env, actions, controls, start, end, per_call)
            env_s.append(seconds)
            bare_s.append(bare_seconds)
        env.close()
        env_us, bare_us = min(env_s) / n * 1e6, min(bare_s) / n * 1e6
        out[env_id] = {
            "steps": n, "frame_skip": frame_skip, "dt": env.dt, "env_us": env_us, "bare_us": bare_us,
            "steps_per_s": 1e6 / env_us, "ratio": env_us / bare_us,
        }  # fmt: skip
    return out


def fmt_env(r: dict | str) -> tuple[str, bool]:
    if isinstance(r, str):
        return f"env       skipped: {r}", True
    ant = r.get("Ant-v5")
    ant_ratio = ant["ratio"] if isinstance(ant, dict) else None
    lines, ok = [], True
    for env_id, v in r.items():
        if isinstance(v, str):
            lines.append(f"env       {env_id}: not measured ({v})")
            continue
        verdict = ""
        if env_id != "Ant-v5" and ant_ratio is not None:
            met = v["ratio"] <= ant_ratio
            ok &= met
            verdict = f" (target <= Ant-v5's {ant_ratio:.3f}x) {'ok' if met else 'MISSED'}"
        lines.append(
            f"env       {env_id}: {v['steps_per_s']:.0f} steps/s ({v['env_us']:.0f} us/step, {v['frame_skip']} physics "
            f"steps = {v['dt'] * 1e3:g} ms); bare physics {v['bare_us']:.0f} us; ratio {v['ratio']:.3f}x{verdict}"
        )
    return "\n".join(lines), ok
