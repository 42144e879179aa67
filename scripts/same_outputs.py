"""Are every scenario's run folders byte-identical in two source trees? (issue 18, "What must not change")

Usage: python scripts/same_outputs.py [--base REV_OR_DIR] [--new DIR] [--scenario NAME ...] [--keep DIR] [--jobs N]

  --base   the old tree: a git revision, checked out into a temporary `git worktree` (removed at the end,
           also on Ctrl-C), or a directory holding a hexabot_sim package. Default: 36ed1b2, the last commit
           before the redesign of issue 18 (the redesign baseline).
  --new    the new tree; default: the tree this script is in (uncommitted edits included).
  --scenario  only these scenarios (repeatable); default: every scenario either tree lists.
  --keep   write the run folders to DIR/old/NAME and DIR/new/NAME and keep them (default: a temporary folder).
  --jobs   subprocesses at a time (default: the number of cores).

Every scenario runs in both trees as `python -m hexabot_sim run NAME --set ... --out NAME` (PYTHONPATH = the
tree, the same relative --out in both, no --video), with the short settings in SHORT below. The two run folders
are compared file by file, byte for byte, except:
  run.json     simulation.wall_time and metrics.real_time_factor (wall clock, different on every run) are
               removed before comparing;
  report.html  the metrics-table row of real_time_factor is removed;
and in every text file the tree's own path, if it occurs, reads <TREE>.
Also compared: the output of `hexabot-sim list`, and of `hexabot-sim kin ROBOT --json` (alone, with --q and
with --target; stdout and stderr) and of `kin ROBOT --q .. --target ..` and `kin ROBOT --deg --q ..` (text) for
every robot; --kin-only compares only these (seconds).

Prints one line per scenario ("same", or "DIFFERENT" with the files and, for text files, the first differing
line and column) and exits 1 on any difference, 2 on a usage error. About 130 s of CPU time: 1-2 minutes on 2
idle cores, ~4 minutes on a busy shared machine (the baseline's first hexabot run also compiles its numba
kernels). A command that runs longer than JOB_TIMEOUT is stopped and counts as a difference.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

BASELINE = "36ed1b2"  # the last commit before the redesign of issue 18
HERE = Path(__file__).resolve().parents[1]

# Short but still characteristic settings per scenario (defaults otherwise): the pendulums swing a few
# periods, the leg makes half its sine step, the grid keeps 2 x 2 cells (both profiles' amplitudes, a slow and a
# fast omega), the walks take two gait cycles, the kerb walk reaches and climbs its kerb (0.5 m ahead at 0.1 m/s).
SHORT: dict[str, list[str]] = {
    "pendulum-undamped": ["duration=2"],
    "pendulum-damped": ["duration=2"],
    "pendulum": ["duration=2"],
    "leg-step": ["duration=3.2"],
    "leg-sweep": ["amplitudes=0.02,0.08", "omegas=1,3", "periods=0.5", "workers=1"],
    "hexabot-walk": ["duration=2"],
    "hexabot-turn": ["duration=2"],
    "hexabot-crab": ["duration=2"],
    "hexabot-force": ["duration=3.6"],  # the shortest its 3 s period allows
    "hexabot-slope": ["duration=2"],
    "hexabot-rough": ["duration=2"],
    "hexabot-kerb": ["duration=6"],
    "hexabot-stairs": ["duration=1.6"],  # the shortest each allows (1 s was refused in both trees: no comparison)
    "quadbot-walk": ["duration=2.1"],
    "quadbot-rough": ["duration=2.1"],
    "rrp-velocity": ["duration=4"],
}
UNKNOWN_DURATION = "1"  # [s] a scenario not in SHORT that has a 'duration' parameter runs this long
# hexabot-sim kin ROBOT --json, also with --q (forward kinematics, J) and --target (every IK branch): the
# targets are the tool positions of those q, so they are reachable.
KIN: dict[str, tuple[str, str]] = {
    "rrp": ("0.3,-0.4,0.5", "1.32,0.408,0.416"),
    "elbow": ("0.3,-0.4,0.5", "0.6227,0.0879,0.2937"),
    "stanford": ("0.3,-0.4,0.5,0.2,-0.6,0.7", "-0.4316,-0.0032,0.6038,0.2,-0.3,0.4"),
    "scara": ("0.3,-0.4,0.1,0.2", "0.6329,0.0735,0.25,0.5"),
    "leg": ("0.3,-0.4,0.5", "0.2308,0.0714,0.029"),
}

# Wall-clock entries of run.json: (path of keys). Anything else in run.json must be equal.
VOLATILE_JSON = (("simulation", "wall_time"), ("metrics", "real_time_factor"))
VOLATILE_HTML = re.compile(r"^<tr><td><code>real_time_factor</code>.*$", re.MULTILINE)
JOB_TIMEOUT = 600.0  # [s] a run or kin command still running after this long is stopped (a hang)
TEXT_SUFFIXES = {".csv", ".json", ".xml", ".html", ".txt", ".md", ".toml"}


@dataclass
class Job:
    key: tuple[str, str]  # (what, side)
    argv: list[str]
    cwd: Path
    env: dict[str, str]
    proc: subprocess.Popen | None = None
    out: Path | None = None
    err: Path | None = None
    rc: int | None = None
    seconds: float = 0.0
    started: float = field(default=0.0, repr=False)


class Stop(Exception):
    """SIGTERM/SIGHUP: unwinds like Ctrl-C so the worktree is removed."""


def _on_signal(signum, _frame):
    raise Stop(signal.Signals(signum).name)


def git(repo: Path, *args: str) -> str:
    return subprocess.run(["git", "-C", str(repo), *args], check=True, capture_output=True, text=True).stdout.strip()


@contextlib.contextmanager
def base_tree(rev_or_dir: str, scratch: Path) -> Iterator[tuple[Path, str]]:
    """(tree, label): a directory as it is, or a revision checked out into a temporary worktree."""
    if Path(rev_or_dir).is_dir():
        yield Path(rev_or_dir).resolve(), str(Path(rev_or_dir).resolve())
        return
    repo = HERE
    commit = git(repo, "rev-parse", "--verify", f"{rev_or_dir}^{{commit}}")
    path = scratch / f"base-{commit[:10]}"
    git(repo, "worktree", "add", "--detach", "--quiet", str(path), commit)
    try:
        yield path, f"{rev_or_dir} ({commit[:10]})"
    finally:
        with contextlib.suppress(subprocess.CalledProcessError):
            git(repo, "worktree", "remove", "--force", str(path))
        shutil.rmtree(path, ignore_errors=True)
        with contextlib.suppress(subprocess.CalledProcessError):
            git(repo, "worktree", "prune")


def tree_env(tree: Path) -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(tree)
    env.pop("HEXABOT_SIM_DEBUG", None)
    env["PYTHONHASHSEED"] = "0"
    return env


def check_imports(tree: Path, cwd: Path) -> None:
    """The tree's own package is the one imported (not an installed copy)."""
    found = subprocess.run(
        [sys.executable, "-c", "import hexabot_sim; print(hexabot_sim.__file__)"],
        cwd=cwd, env=tree_env(tree), capture_output=True, text=True,
    )  # fmt: skip
    path = Path(found.stdout.strip() or "?").resolve()
    if found.returncode or not path.is_relative_to(tree):
        raise SystemExit(f"same_outputs: {tree} does not provide hexabot_sim (imported: {path}) {found.stderr[-300:]}")


def run_jobs(jobs: list[Job], n: int, logs: Path, on_done) -> None:
    """Runs `jobs` at most `n` at a time, in order; on_done(job) after each. Kills what runs if interrupted."""
    pending, running = list(jobs), []
    try:
        while pending or running:
            while pending and len(running) < n:
                job = pending.pop(0)
                stem = "-".join(job.key).replace("/", "_")
                job.out, job.err = logs / f"{stem}.out", logs / f"{stem}.err"
                with open(job.out, "wb") as out, open(job.err, "wb") as err:
                    job.started = time.perf_counter()
                    job.proc = subprocess.Popen(job.argv, cwd=job.cwd, env=job.env, stdout=out, stderr=err)
                running.append(job)
            time.sleep(0.02)
            for job in running:
                if job.proc.poll() is None and time.perf_counter() - job.started > JOB_TIMEOUT:
                    job.proc.kill()
                    with open(job.err, "a") as err:
                        err.write(f"\nstopped after {JOB_TIMEOUT:g} s\n")
            for job in [j for j in running if j.proc.poll() is not None]:
                running.remove(job)
                job.rc, job.seconds = job.proc.returncode, time.perf_counter() - job.started
                on_done(job)
    finally:
        for job in running:
            if job.proc.poll() is None:
                job.proc.kill()
            job.proc.wait()


def list_scenarios(text: str) -> dict[str, set[str]]:
    """`hexabot-sim list` output -> {scenario: its parameter names}."""
    found: dict[str, set[str]] = {}
    current = None
    for line in text.splitlines():
        if line and not line[0].isspace():
            current = line.strip()
            found[current] = set()
        elif current and line.startswith("    ") and "=" in line:
            found[current].add(line.split("=", 1)[0].strip())
    return found


def short_settings(name: str, params: set[str]) -> list[str]:
    if name in SHORT:
        return SHORT[name]
    return [f"duration={UNKNOWN_DURATION}"] if "duration" in params else []


# --------------------------------------------------------------------------------------------- comparing


def _drop(record, path):
    node = record
    for key in path[:-1]:
        if not isinstance(node, dict) or key not in node:
            return
        node = node[key]
    if isinstance(node, dict):
        node.pop(path[-1], None)


def normalise(name: str, data: bytes, tree: Path) -> bytes:
    """The bytes that must be equal: wall-clock fields out, the tree's path as <TREE>."""
    suffix = Path(name).suffix
    if suffix not in TEXT_SUFFIXES:
        return data
    text = data.decode("utf-8", errors="surrogateescape").replace(str(tree), "<TREE>")
    if name == "run.json":
        with contextlib.suppress(ValueError):
            record = json.loads(text)
            for path in VOLATILE_JSON:
                _drop(record, path)
            text = json.dumps(record, indent=2, ensure_ascii=False)
    elif name == "report.html":
        text = VOLATILE_HTML.sub("", text)
    return text.encode("utf-8", errors="surrogateescape")


def first_difference(name: str, old: bytes, new: bytes) -> str:
    """Where two normalised files first differ, in a few words."""
    suffix = Path(name).suffix
    if suffix in TEXT_SUFFIXES:
        a, b = old.decode(errors="replace").splitlines(), new.decode(errors="replace").splitlines()
        for i, (x, y) in enumerate(zip(a, b, strict=False)):
            if x != y:
                c = next((k for k, (u, v) in enumerate(zip(x, y, strict=False)) if u != v), min(len(x), len(y)))
                start = max(0, c - 40)
                lead = "..." if start else ""
                return f"line {i + 1}, column {c + 1}: {lead + _short(x[start:])!r} -> {lead + _short(y[start:])!r}"
        return f"{len(a)} vs {len(b)} lines" if len(a) != len(b) else "line endings"
    if suffix == ".npz":
        with contextlib.suppress(Exception):
            import numpy as np

            za, zb = np.load(io.BytesIO(old)), np.load(io.BytesIO(new))
            if za.files != zb.files:
                return f"arrays {za.files} -> {zb.files}"
            for key in za.files:
                x, y = za[key], zb[key]
                if x.shape != y.shape or x.dtype != y.dtype:
                    return f"{key}: {x.dtype}{x.shape} -> {y.dtype}{y.shape}"
                if x.tobytes() != y.tobytes():
                    i = np.flatnonzero(x.ravel() != y.ravel())
                    where = f" first at flat index {i[0]}: {x.ravel()[i[0]]!r} -> {y.ravel()[i[0]]!r}" if len(i) else ""
                    return f"array {key} differs{where}"
    return f"{len(old)} vs {len(new)} bytes" if len(old) != len(new) else "same size, different bytes"


def _short(s: str, n: int = 90) -> str:
    return s if len(s) <= n else s[: n - 3] + "..."


def compare_folders(old: Path, new: Path, old_tree: Path, new_tree: Path) -> list[str]:
    """Differences between two run folders, one string per file."""
    names_old = {p.name for p in old.iterdir()} if old.is_dir() else set()
    names_new = {p.name for p in new.iterdir()} if new.is_dir() else set()
    problems = [f"{n}: only in old" for n in sorted(names_old - names_new)]
    problems += [f"{n}: only in new" for n in sorted(names_new - names_old)]
    for name in sorted(names_old & names_new):
        a = normalise(name, (old / name).read_bytes(), old_tree)
        b = normalise(name, (new / name).read_bytes(), new_tree)
        if a != b:
            problems.append(f"{name}: {first_difference(name, a, b)}")
    return problems


def compare_outputs(what: str, old: Job, new: Job, old_tree: Path, new_tree: Path, stderr: bool = True) -> list[str]:
    """Differences between the stdout, stderr and exit status of two commands."""
    problems = []
    if old.rc != new.rc:
        problems.append(f"exit status {old.rc} -> {new.rc}" + _stderr_tail(new if new.rc else old))
    a = normalise(what + ".txt", old.out.read_bytes(), old_tree)
    b = normalise(what + ".txt", new.out.read_bytes(), new_tree)
    if a != b:
        problems.append(f"output: {first_difference(what + '.txt', a, b)}")
    if stderr:
        a = normalise(what + ".txt", old.err.read_bytes(), old_tree)
        b = normalise(what + ".txt", new.err.read_bytes(), new_tree)
        if a != b:
            problems.append(f"stderr: {first_difference(what + '.txt', a, b)}")
    return problems


def _stderr_tail(job: Job) -> str:
    lines = job.err.read_text(errors="replace").strip().splitlines() if job.err else []
    return f" ({_short(lines[-1], 120)})" if lines else ""


# --------------------------------------------------------------------------------------------- main


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--base", default=BASELINE, help=f"old tree: git revision or directory (default {BASELINE})")
    parser.add_argument("--new", type=Path, default=HERE, help="new tree (default: this script's tree)")
    parser.add_argument("--scenario", action="append", default=[], metavar="NAME", help="only this scenario")
    parser.add_argument("--keep", type=Path, metavar="DIR", help="keep the run folders in DIR/old and DIR/new")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--kin-only", action="store_true", help="only `list` and the `kin` commands (seconds)")
    args = parser.parse_args()
    if args.keep is not None and args.keep.exists() and any(args.keep.iterdir()):
        parser.error(f"--keep {args.keep}: not empty")

    signal.signal(signal.SIGINT, signal.default_int_handler)  # also when started in the background (ignored there)
    for signum in (signal.SIGTERM, signal.SIGHUP):
        signal.signal(signum, _on_signal)
    started = time.perf_counter()
    new_tree = args.new.resolve()
    scratch = Path(tempfile.mkdtemp(prefix="same_outputs-"))
    try:
        with base_tree(args.base, scratch) as (old_tree, label):
            print(f"old: {label}\nnew: {new_tree}", flush=True)
            return compare_trees(args, old_tree, new_tree, scratch)
    except (KeyboardInterrupt, Stop) as e:
        print(
            f"\nsame_outputs: interrupted ({str(e) or 'SIGINT'}); worktree and temporary files removed", file=sys.stderr
        )
        return 130
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
        print(f"same_outputs: {time.perf_counter() - started:.0f} s", file=sys.stderr)


def compare_trees(args, old_tree: Path, new_tree: Path, scratch: Path) -> int:
    root = args.keep.resolve() if args.keep else scratch / "runs"
    trees = {"old": old_tree, "new": new_tree}
    for side, tree in trees.items():
        (root / side).mkdir(parents=True, exist_ok=True)
        check_imports(tree, root / side)
    logs = scratch / "logs"
    logs.mkdir()
    py = [sys.executable, "-m", "hexabot_sim"]

    def job(what: str, side: str, argv: list[str]) -> Job:
        return Job((what, side), py + argv, root / side, tree_env(trees[side]))

    # `list` first: it names the scenarios (either tree's) and their parameters.
    listing: dict[str, Job] = {}
    run_jobs([job("list", s, ["list"]) for s in trees], args.jobs, logs, lambda j: listing.__setitem__(j.key[1], j))
    params = {s: list_scenarios(listing[s].out.read_text(errors="replace")) for s in trees}
    names = list(params["old"]) + [n for n in params["new"] if n not in params["old"]]
    if args.scenario:
        unknown = [n for n in args.scenario if n not in names]
        if unknown:
            print(f"same_outputs: unknown scenario(s): {', '.join(unknown)}", file=sys.stderr)
            return 2
        names = [n for n in names if n in args.scenario]
    if args.kin_only:
        names = []

    checks: list[str] = []  # in the order the lines are printed
    jobs: list[Job] = []
    settings = {}
    for name in names:
        settings[name] = short_settings(name, params["old"].get(name, set()) | params["new"].get(name, set()))
        sets = [a for s in settings[name] for a in ("--set", s)]
        checks.append(name)
        jobs += [job(name, side, ["run", name, *sets, "--out", name]) for side in trees]
    for robot, (q, target) in KIN.items() if not args.scenario else ():
        for what, extra in (
            (f"kin {robot}", []),
            (f"kin {robot} --q", ["--q", q]),
            (f"kin {robot} --target", [f"--target={target}"]),
        ):
            checks.append(what)
            jobs += [job(what, side, ["kin", robot, "--json", *extra]) for side in trees]
        for what, extra in (  # the text output too, and degrees
            (f"kin {robot} text", ["--q", q, f"--target={target}"]),
            (f"kin {robot} --deg", ["--deg", "--q", q]),
        ):
            checks.append(what)
            jobs += [job(what, side, ["kin", robot, *extra]) for side in trees]
    # Longest first, so the two cores stay busy to the end (both sides of a check next to each other).
    order = sorted(range(len(checks)), key=lambda i: -_cost(checks[i]))
    jobs = [j for i in order for j in jobs[2 * i : 2 * i + 2]]

    differences = 0
    done: dict[tuple[str, str], Job] = {}
    printed = [0]

    def report(what: str) -> None:
        nonlocal differences
        old, new = done[(what, "old")], done[(what, "new")]
        if what.startswith("kin "):
            problems = compare_outputs(what, old, new, old_tree, new_tree)
            detail = " ".join(done[(what, "old")].argv[3:])
        else:
            problems = []
            if old.rc != new.rc or old.rc:
                problems.append(f"exit status {old.rc} -> {new.rc}" + _stderr_tail(new if new.rc else old))
            if old.rc == 0 or new.rc == 0:
                problems += compare_folders(root / "old" / what, root / "new" / what, old_tree, new_tree)
            detail = " ".join(settings[what]) or "defaults"
        differences += bool(problems)
        verdict = "same" if not problems else "DIFFERENT"
        head = f"{what:<22} {verdict}  ({detail}; {old.seconds:.1f} s / {new.seconds:.1f} s)"
        print(head + "".join(f"\n    {p}" for p in problems), flush=True)

    def on_done(j: Job) -> None:
        done[j.key] = j
        while printed[0] < len(checks) and all((checks[printed[0]], s) in done for s in trees):
            report(checks[printed[0]])
            printed[0] += 1

    lst = compare_outputs("list", listing["old"], listing["new"], old_tree, new_tree)
    differences += bool(lst)
    print(f"{'list':<22} {'same' if not lst else 'DIFFERENT'}" + "".join(f"\n    {p}" for p in lst), flush=True)
    run_jobs(jobs, args.jobs, logs, on_done)

    print(f"{differences} difference(s)" if differences else "all same", flush=True)
    return 1 if differences else 0


def _cost(check: str) -> float:
    """Rough seconds of a check, for scheduling only."""
    if check.startswith("kin "):
        return 0.5
    return {"hexabot-kerb": 9, "leg-sweep": 6, "rrp-velocity": 5}.get(check, 4)


if __name__ == "__main__":
    sys.exit(main())
