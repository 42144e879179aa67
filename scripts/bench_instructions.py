"""Instructions per step of the walking loops, counted by valgrind: figures a shared machine's load cannot move.

Usage: python scripts/bench_instructions.py [--against REV_OR_DIR] [--only LINE ...] [--duration S]

  hexabot     hexabot-walk (tripod 0.1 m/s, flat)
  rough-*     hexabot-rough (1 cm rough ground, touchdown=sensed), tripod, ripple and wave
  force       hexabot-walk with load_sharing=force feet=pad swing=quintic, the wave at 0.05 m/s

For each line: the instructions per 2 ms step of the whole loop (`simulate`: the controller, mj_step, recording,
checks) and of bare `mj_step` replaying the loop's recorded controls from Python (bench.py's two sides), and their
ratio. `bench.py` times the same two loops in seconds, which the machine's load moves by 20-50 % between runs
(the same code on the same VM: bare mj_step on rough ground at 30 us one day, 42-46 us another); an instruction
count is the same in every run of the same code and inputs. What it does not see: cache misses, memory stalls,
how instructions overlap, so it is a check that nothing does more work, not a real-time factor.

--against REV_OR_DIR: the same lines for an old tree (a git revision, checked out into a temporary worktree, or
a directory), old -> new and new/old per figure; a line the old tree cannot run says so. Each tree's own
hexabot_sim builds the scene, the controller and the loop; the counting is this script's, the same for both.

How: each count is one fresh process under `valgrind --tool=callgrind --toggle-collect=functools_reduce`, which
counts only what runs inside one `functools.reduce` call wrapping the loop (imports, the scene's build and numba's
cache loads are outside it). A native run first fills a numba cache of generic code (valgrind's CPU is not the
host's, so the host's cache would not serve) and records the controls. Needs
valgrind (Debian: apt-get install valgrind) and a Python with its symbols (pyenv's and Debian's have them).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from same_outputs import base_tree, tree_env  # beside this file

LINES = {
    "hexabot": ("hexabot-walk", {"gait": "tripod", "vx": 0.1}),
    "rough-tripod": ("hexabot-rough", {"gait": "tripod", "vx": 0.1}),
    "rough-ripple": ("hexabot-rough", {"gait": "ripple", "vx": 0.1}),
    "rough-wave": ("hexabot-rough", {"gait": "wave", "vx": 0.05}),
    "force": ("hexabot-walk", {"gait": "wave", "vx": 0.05, "load_sharing": "force", "feet": "pad", "swing": "quintic"}),
}

# Runs with PYTHONPATH = a tree, importing that tree's hexabot_sim (the layout moved in the redesign: both kinds).
CHILD = r"""
import functools, json, sys
import numpy as np, mujoco
mode, scenario, overrides, folder = sys.argv[1], sys.argv[2], json.loads(sys.argv[3]), sys.argv[5]
duration = float(sys.argv[4])
from hexabot_sim import params, registry
from hexabot_sim.result import at_home
from hexabot_sim.simulate import simulate
from hexabot_sim.walking import scene
try:
    from hexabot_sim.budget import step_count
except ImportError:
    from hexabot_sim.simulate import step_count
if mode == "bare":
    xml = open(folder + "/model.xml").read()
    ctrl = np.load(folder + "/ctrl.npy")
    model, data = at_home(xml)
    def replay(_a, _b):
        for i in range(1, len(ctrl)):
            data.ctrl[:] = ctrl[i]
            mujoco.mj_step(model, data)
    functools.reduce(replay, [0], None)
    same = bool((data.qpos == np.load(folder + "/qpos.npy")).all())
    print(json.dumps({"steps": len(ctrl) - 1, "same": same}))
    sys.exit(0)
s = registry.get(scenario)
try:
    p = params.resolve(s.params_type, s.defaults, {"duration": duration, **overrides})
except Exception as error:
    print(json.dumps(f"the tree cannot run {scenario} {overrides}: {str(error).split(';')[0]}"))
    sys.exit(0)
xml = scene.build_xml(p)
n = step_count(p.duration, p.timestep)
model, data = at_home(xml)
scene.make_controller(p, model, data)(model, data)  # numba's kernels compiled or loaded, as bench.py does
model, data = at_home(xml)
controller = scene.make_controller(p, model, data)
if mode == "prep":
    traj = simulate(model, data, n, controller=controller, record_ctrl=True)
    open(folder + "/model.xml", "w").write(xml)
    np.save(folder + "/ctrl.npy", traj.ctrl)
    np.save(folder + "/qpos.npy", traj.qpos[-1])
else:
    functools.reduce(lambda _a, _b: simulate(model, data, n, controller=controller, record_ctrl=True), [0], None)
print(json.dumps({"steps": n}))
"""


class CountError(Exception):
    """A count that could not be made (one line: why)."""


def _child(tree: Path, mode: str, line: str, duration: float, folder: Path, valgrind: bool) -> tuple[dict | str, int]:
    """Runs the child; returns its JSON answer and, under valgrind, the instructions it collected."""
    scenario, overrides = LINES[line]
    argv = [sys.executable, "-c", CHILD, mode, scenario, json.dumps(overrides), str(duration), str(folder)]
    out = folder / f"callgrind.{mode}"
    if valgrind:
        argv = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", "--toggle-collect=functools_reduce",
                *argv]  # fmt: skip
    env = tree_env(tree)  # this tree's hexabot_sim; PYTHONHASHSEED fixed, so the counts repeat
    # numba's cache is keyed by the CPU, and valgrind's emulated one is not the host's (here znver3 natively,
    # haswell inside): under valgrind every kernel would be compiled again, for ten minutes and more. Generic code
    # in a cache of the count's own serves both runs (and counts a little more than the host's own code would).
    env.update(NUMBA_CPU_NAME="generic", NUMBA_CACHE_DIR=str(folder.parent / "numba-cache"))
    done = subprocess.run(argv, cwd=folder, env=env, capture_output=True, text=True)
    if done.returncode:
        lines = [x for x in done.stderr.strip().splitlines() if not x.startswith("==")]
        raise CountError(f"{mode} failed (exit {done.returncode}): {lines[-1] if lines else ''}")
    answer = json.loads(done.stdout.strip().splitlines()[-1])
    if not valgrind:
        return answer, 0
    found = re.search(r"Collected : (\d+)", done.stderr)
    count = int(found.group(1)) if found else 0
    if count == 0:
        raise CountError("valgrind collected nothing: this Python has no symbol functools_reduce to count inside")
    return answer, count


def count_line(tree: Path, line: str, duration: float, scratch: Path) -> dict | str:
    """The line's instructions per step, loop and bare, for one tree (a string: why not)."""
    folder = Path(tempfile.mkdtemp(prefix=f"{line}-", dir=scratch))
    try:
        prep, _ = _child(tree, "prep", line, duration, folder, valgrind=False)
        if isinstance(prep, str):
            return prep
        loop, loop_count = _child(tree, "loop", line, duration, folder, valgrind=True)
        bare, bare_count = _child(tree, "bare", line, duration, folder, valgrind=True)
    except CountError as error:
        return str(error)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    if not bare["same"]:
        return "the replay did not reproduce the walk: the bare loop would not count the same physics"
    steps = loop["steps"]
    return {"loop": loop_count / steps, "bare": bare_count / steps, "ratio": loop_count / bare_count, "steps": steps}


def _fmt(result: dict) -> str:
    return (f"loop {result['loop'] / 1e3:.1f} k instructions/step, bare mj_step {result['bare'] / 1e3:.1f} k "
            f"(loop / bare {result['ratio']:.3f}; {result['steps']} steps)")  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", metavar="REV_OR_DIR", help="an old tree to count beside this one")
    parser.add_argument("--only", action="append", choices=list(LINES), metavar="LINE",
                        help=f"one of {', '.join(LINES)} (repeatable; default all)")  # fmt: skip
    parser.add_argument("--duration", type=float, default=4.0, help="simulated seconds per walk (default 4)")
    args = parser.parse_args(argv)
    if shutil.which("valgrind") is None:
        print("bench_instructions: valgrind is not installed (Debian: apt-get install valgrind)", file=sys.stderr)
        return 2
    if not 0.1 <= args.duration <= 60:
        print(f"bench_instructions: --duration {args.duration} s: choose 0.1 to 60 s", file=sys.stderr)
        return 2
    lines = args.only or list(LINES)
    new_tree = Path(__file__).resolve().parents[1]
    with tempfile.TemporaryDirectory(prefix="bench-instructions-") as tmp:
        scratch = Path(tmp)
        if not args.against:
            for line in lines:
                result = count_line(new_tree, line, args.duration, scratch)
                print(f"{line:<13} " + (_fmt(result) if isinstance(result, dict) else result), flush=True)
            return 0
        with contextlib.ExitStack() as stack:
            try:
                old_tree, label = stack.enter_context(base_tree(args.against, scratch))
            except subprocess.CalledProcessError:
                print(f"bench_instructions: --against {args.against}: neither a directory nor a git revision",
                      file=sys.stderr)  # fmt: skip
                return 2
            print(f"old: {label}\nnew: {new_tree}", flush=True)
            for line in lines:
                old = count_line(old_tree, line, args.duration, scratch)
                new = count_line(new_tree, line, args.duration, scratch)
                if isinstance(old, str) or isinstance(new, str):
                    why = "; ".join(f"{side}: {r}" for side, r in (("old", old), ("new", new)) if isinstance(r, str))
                    print(f"{line:<13} {why}", flush=True)
                    continue
                cells = [f"{key} {old[key] / 1e3:.1f} k -> {new[key] / 1e3:.1f} k (new/old {new[key] / old[key]:.3f})"
                         for key in ("loop", "bare")]  # fmt: skip
                cells.append(f"loop / bare {old['ratio']:.3f} -> {new['ratio']:.3f}")
                print(f"{line:<13} " + "; ".join(cells), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
