"""Numeric IK on random 6-DOF robot files: how often the q a target was made from is among the solutions, and how
long a call takes.

Usage: python scripts/ik_check.py [--cases N]   (default 1,000; about a minute)

Each case: a random 6-joint table (revolute ranges ±0.9π; each joint prismatic with probability 0.3, a 0.5 m
stroke, at most 2 of them: with 3 or more of 6 joints sliding, a random table is a chain whose J has rank < 6
everywhere, with no isolated solution to recover; standard and modified DH alternating; a random tool offset), a
random q inside the ranges where J has full rank (σmin / σmax > 1e-6; drawn again otherwise), the target pose
FK(q), and numeric_ik.solve (as `kin FILE --target` calls it). Recovered: one solution equals q within
numeric_ik.DEDUP_TOL
(angles mod 2π). Prints the rate, the worst residuals and the time per call (mean, median, 95th percentile, max).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from hexabot_sim.kinematics import numeric_ik
from hexabot_sim.kinematics.chain import Joint, SerialChain


def random_chain(rng: np.random.Generator, k: int) -> SerialChain:
    joints: list[Joint] = []
    for i in range(6):
        dh = {"theta": rng.uniform(-math.pi, math.pi), "d": rng.uniform(-0.3, 0.3), "a": rng.uniform(-0.3, 0.3),
              "alpha": rng.uniform(-math.pi, math.pi)}  # fmt: skip
        if rng.random() < 0.3 and sum(j.prismatic for j in joints) < 2:
            joints.append(Joint(f"j{i + 1}", "prismatic", lower=-0.2, upper=0.3, **dh))
        else:
            joints.append(Joint(f"j{i + 1}", lower=-0.9 * math.pi, upper=0.9 * math.pi, **dh))
    frame = np.eye(4)
    frame[:3, 3] = rng.uniform(-0.1, 0.1, 3)
    return SerialChain("random", tuple(joints), ("standard", "modified")[k % 2], tool=frame)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cases", type=int, default=1000)
    args = parser.parse_args()
    rng = np.random.default_rng(2026)
    recovered, times, cpu_times, worst_pos, worst_rot, counts = 0, [], [], 0.0, 0.0, []
    for k in range(args.cases):
        while True:
            chain = random_chain(rng, k)
            q = np.array([rng.uniform(j.lower, j.upper) for j in chain.joints])
            sigma = np.linalg.svd(chain.jacobian(q), compute_uv=False)
            if sigma[-1] > 1e-6 * sigma[0]:
                break
        target = chain.fk(q)
        started, cpu = time.perf_counter(), time.process_time()
        solutions = numeric_ik.solve(chain, target)
        times.append(time.perf_counter() - started)
        cpu_times.append(time.process_time() - cpu)
        revolute = np.array([not j.prismatic for j in chain.joints])
        recovered += any(numeric_ik._same(q.copy(), s.q.copy(), revolute) for s in solutions)
        worst_pos = max([worst_pos, *(s.position_residual for s in solutions)])
        worst_rot = max([worst_rot, *(s.orientation_residual or 0.0 for s in solutions)])
        counts.append(len(solutions))
    ms = np.array(times) * 1e3
    print(f"{args.cases} random 6-DOF targets: q recovered in {recovered} ({100 * recovered / args.cases:.1f} %); "
          f"solutions per target {np.mean(counts):.2f} (max {max(counts)}); worst residuals {worst_pos:.1e} m, "
          f"{worst_rot:.1e} rad")  # fmt: skip
    cpu = np.array(cpu_times) * 1e3
    print(f"time per call: mean {ms.mean():.1f} ms, median {np.median(ms):.1f} ms, "
          f"95th percentile {np.percentile(ms, 95):.1f} ms, max {ms.max():.1f} ms; CPU time per call: mean "
          f"{cpu.mean():.1f} ms, median {np.median(cpu):.1f} ms (load average {os.getloadavg()[0]:.1f} on "
          f"{os.cpu_count()} cores)")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
