"""bench.py's `env` line: the Gymnasium environments' step against the bare physics it contains, beside Ant-v5's.

For each environment (ours and Gymnasium's Ant-v5, unwrapped, random actions drawn beforehand, the episode run on
through falls so the physics is one trajectory): the time of `step`, and the time of its bare physics, the same
controls replayed from the same start on a second MjData (`frame_skip` x mj_step: mj_step(nstep=frame_skip) with the
action's controls for the joint-level envs and Ant-v5, as their step calls it; for HexabotCommand-v0 the controls the
gait controller wrote before every physics step, recorded in a first run, one mj_step each). Env step and bare
replay alternate step by step (the shared machine's load weighs on both alike); the replay must end in the env's
final state bit for bit, or the line fails: it would not time the same physics. Every repeat runs the same physics,
so each step keeps its best time of the repeats, on either side (load spikes of a shared machine drop out).
Then the batched vector environment (envs/vector.py) against Gymnasium's AsyncVectorEnv and SyncVectorEnv.
"""

from __future__ import annotations

import os
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


def _side_by_side(env, actions, controls, start, end, per_call: int) -> tuple[np.ndarray, np.ndarray]:
    """Seconds of each env.step and of its bare physics (two arrays of len(actions)), interleaved step by step so
    the machine's load weighs on both alike: after each env.step, a second MjData of the same model replays that
    step's controls (`per_call` mj_steps each) from the same start. Both must end in the recorded final state."""
    m = env.model
    env.reset(seed=0)
    bare = mujoco.MjData(m)
    mujoco.mj_setState(m, bare, start, mujoco.mjtState.mjSTATE_INTEGRATION)
    mujoco.mj_forward(m, bare)
    per_action = len(controls) // len(actions)
    env_s, bare_s = np.zeros(len(actions)), np.zeros(len(actions))
    clock = time.perf_counter
    for k, a in enumerate(actions):
        began = clock()
        env.step(a)
        env_s[k] = clock() - began
        chunk = controls[k * per_action : (k + 1) * per_action]
        began = clock()
        for ctrl in chunk:
            bare.ctrl[:] = ctrl
            mujoco.mj_step(m, bare, nstep=per_call)
        bare_s[k] = clock() - began
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
        # Every repeat runs the same physics: each step's least disturbed time, on either side, is its best.
        env_s, bare_s = np.full(n, np.inf), np.full(n, np.inf)
        for _ in range(repeat):
            seconds, bare_seconds = _side_by_side(env, actions, controls, start, end, per_call)
            np.minimum(env_s, seconds, out=env_s)
            np.minimum(bare_s, bare_seconds, out=bare_s)
        env.close()
        env_us, bare_us = env_s.sum() / n * 1e6, bare_s.sum() / n * 1e6
        out[env_id] = {
            "steps": n, "frame_skip": frame_skip, "dt": env.dt, "env_us": env_us, "bare_us": bare_us,
            "steps_per_s": 1e6 / env_us, "ratio": env_us / bare_us,
        }  # fmt: skip
    out["vector"] = bench_vector(repeat)
    return out


VECTOR_ENVS: int = 8  # environments of the vector comparison
VECTOR_STEPS: int = 50  # vector steps timed per repeat


def bench_vector(repeat: int, env_id: str = "hexabot_sim/HexabotJoints-v0") -> dict:
    """Environment steps per second of `VECTOR_ENVS` copies: the rollout-batched env against Gymnasium's
    AsyncVectorEnv (a subprocess each) and SyncVectorEnv, alternating step by step, random actions, autoreset
    included; each one's every step deterministic, so each step keeps its best time of the repeats."""
    import gymnasium

    import hexabot_sim.envs  # noqa: F401 (registers our ids)

    modes = ("vector_entry_point", "async", "sync")
    envs = {mode: gymnasium.make_vec(env_id, num_envs=VECTOR_ENVS, vectorization_mode=mode) for mode in modes}
    space = envs["sync"].action_space
    space.seed(0)
    actions = [space.sample() for _ in range(VECTOR_STEPS)]
    best = {mode: np.full(VECTOR_STEPS, np.inf) for mode in modes}  # each step's best time of the repeats
    try:
        for _ in range(repeat):
            for env in envs.values():
                env.reset(seed=0)
            for k, a in enumerate(actions):  # the three alternate step by step: the same load on each
                for mode, env in envs.items():
                    began = time.perf_counter()
                    env.step(a)
                    best[mode][k] = min(best[mode][k], time.perf_counter() - began)
    finally:
        for env in envs.values():
            env.close()
    best = {mode: float(times.sum()) for mode, times in best.items()}
    n = VECTOR_ENVS * VECTOR_STEPS
    return {"env_id": env_id, "num_envs": VECTOR_ENVS, **{f"{mode}_steps_per_s": n / best[mode] for mode in modes}}


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
        if env_id == "vector":
            batched, asynchronous, sync = (v[f"{m}_steps_per_s"] for m in ("vector_entry_point", "async", "sync"))
            lines.append(
                f"env       {v['env_id']} x{v['num_envs']} on {os.cpu_count()} cores: batched by mujoco.rollout "
                f"{batched:.0f} env-steps/s, AsyncVectorEnv {asynchronous:.0f} ({batched / asynchronous:.2f}x), "
                f"SyncVectorEnv {sync:.0f} ({batched / sync:.2f}x)"
            )
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
