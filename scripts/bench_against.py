"""bench.py --against REV_OR_DIR: every benchmark line for an old tree and this one, alternating in one run.

Each side is measured by its own tree's scripts/bench.py in fresh processes; per figure the best of all runs
of a side, then old, new and new/old. Judged: the ratios measured within one process (the machine's load
weighs on both of their sides); absolute figures are shown in brackets only.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from bench import derive  # beside this file: the ratios a line's raw timings make

# How the best of several results is taken (per figure) and which way is better.
LOWER_BETTER = ("_us_per_step", "_s", "_ms_per_cell", "_ms_per_frame", "ratio", "share", "vs_bare")
HIGHER_BETTER = ("fps", "real_time_factor", "speedup")


def _lower_better(key: str) -> bool | None:
    if key.endswith(HIGHER_BETTER) or "_fps" in key:
        return False
    if key.endswith(LOWER_BETTER):
        return True
    return None


def best_of(results: list[dict]) -> dict:
    """One result from several runs of a line: each timing's best (least disturbed), then the ratios."""
    out = dict(results[0])
    for key, value in results[0].items():
        lower = _lower_better(key)
        if lower is not None and isinstance(value, (int, float)) and not isinstance(value, bool):
            values = [r[key] for r in results if r.get(key) is not None]
            out[key] = min(values) if lower else max(values)
    return derive(out)


NO_WORSE_TOLERANCE = 0.05  # default --tolerance: new/old within 5 % of "no worse" counts as no worse (noise)


# Runs in a fresh process with PYTHONPATH = a tree: that tree's own scripts/bench.py measures one line and the
# result is printed as JSON (a string: why not). A bench.py without LINES (before --against, e.g. 36ed1b2) is
# called the way its main() calls its functions.
DRIVER = r"""
import functools, importlib.util, json, sys
path, line, repeat = sys.argv[1], sys.argv[2], int(sys.argv[3])
spec = importlib.util.spec_from_file_location("tree_bench", path)
bench = importlib.util.module_from_spec(spec)
sys.modules["tree_bench"] = bench
spec.loader.exec_module(bench)
if hasattr(bench, "LINES"):
    measure = bench.LINES[line][0] if line in bench.LINES else None
else:
    rough = {"rough-tripod": ("tripod", 0.1), "rough-ripple": ("ripple", 0.1), "rough-wave": ("wave", 0.05)}
    measure = {
        "sim-loop": bench.bench_sim_loop,
        "leg-loop": bench.bench_leg_loop,
        "hexabot": bench.bench_hexabot,
        "video": bench.bench_video,
        "sweep": lambda r: bench.bench_sweep(max(1, r // 2)),
        "list": bench.bench_list,
        **{
            k: functools.partial(bench.bench_hexabot, name="hexabot-rough", gait=g, vx=v)
            for k, (g, v) in rough.items()
        },
    }.get(line)
print(json.dumps(measure(repeat) if measure else f"no line {line} in {path}"))
"""


def run_line(tree: Path, line: str, repeat: int, cwd: Path) -> dict | str:
    """One line measured by `tree`'s own scripts/bench.py in a fresh process importing hexabot_sim from `tree`."""
    script = tree / "scripts" / "bench.py"
    env = dict(os.environ, PYTHONPATH=str(tree))
    argv = [sys.executable, "-c", DRIVER, str(script), line, str(repeat)]
    done = subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True)
    if done.returncode:
        lines = done.stderr.strip().splitlines()
        return f"failed (exit {done.returncode}): {lines[-1] if lines else ''}"
    result = json.loads(done.stdout.strip().splitlines()[-1])
    return result if isinstance(result, dict) else f"not measured: {result}"


def against(LINES: dict, base: str, lines: list[str], rounds: int, repeat: int, tolerance: float) -> int:
    """Every line for the old tree and this one, alternating in one run; per figure: old, new, new/old."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from same_outputs import base_tree

    new_tree = Path(__file__).resolve().parents[1]
    worse = []
    with tempfile.TemporaryDirectory(prefix="bench-against-") as tmp, base_tree(base, Path(tmp)) as (old_tree, label):
        print(f"old: {label}\nnew: {new_tree}\n{rounds} rounds of old and new alternating, each line --repeat "
              f"{repeat} in a fresh process; best of all per side; no worse = new/old within "
              f"{100 * tolerance:.0f} % (noise); judged: the ratios measured within one process (and list's "
              f"time); [in brackets]: absolute figures, shown only (the load of a shared machine moves them)",
              flush=True)  # fmt: skip
        for line in lines:
            _, text, judged, shown = LINES[line]
            runs: dict[str, list] = {"old": [], "new": []}
            for n in range(rounds):
                for side in ("old", "new") if n % 2 == 0 else ("new", "old"):  # neither side always goes first
                    runs[side].append(run_line(old_tree if side == "old" else new_tree, line, repeat, Path(tmp)))
            failed = {side: next((r for r in rs if isinstance(r, str)), None) for side, rs in runs.items()}
            if any(failed.values()):
                print(f"{line:<12} " + "; ".join(f"{side}: {why}" for side, why in failed.items() if why), flush=True)
                worse.append(line)
                continue
            best = {side: best_of(rs) for side, rs in runs.items()}
            cells = []
            for key in (*judged, *shown):
                old, new = best["old"].get(key), best["new"].get(key)
                if not isinstance(old, (int, float)) or not isinstance(new, (int, float)):
                    if isinstance(old, (int, float)) or isinstance(new, (int, float)):
                        cells.append(f"{key} only measured by the {'old' if new is None else 'new'} tree's bench.py")
                    continue
                if key.endswith("share"):  # a share can be ~0 or negative: compare the difference
                    change = new - old
                    bad = change > tolerance * 0.5
                    cell = f"{key} {100 * old:.1f} % -> {100 * new:.1f} % ({100 * change:+.1f} points)"
                else:
                    ratio = new / old if old else float("nan")
                    bad = ratio > 1 + tolerance if _lower_better(key) else ratio < 1 - tolerance
                    cell = f"{key} {old:.4g} -> {new:.4g} (new/old {ratio:.3f})"
                if key in judged:
                    cells.append(cell + (" WORSE" if bad else " ok"))
                    worse += [f"{line} {key}"] if bad else []
                else:
                    cells.append(f"[{cell}]")
            print(f"{line:<12} " + "; ".join(cells), flush=True)
            print("    new: " + text(best["new"])[0].replace("\n", "\n    new: "), flush=True)
    print(f"worse: {', '.join(worse)}" if worse else "no line worse")
    return 1 if worse else 0
