"""FK and J of random robot files against Robotics Toolbox for Python (a peer library), both DH conventions.

Usage: python scripts/dh_peer_check.py [--tables N]   (needs `pip install roboticstoolbox-python`, not a
dependency of hexabot-sim; the test suite checks the same against an independent implementation in
tests/kinematics/test_robot_file_kinematics.py)

Random tables of 1 to 7 joints (revolute and prismatic mixed, standard and modified DH, random base and tool
transforms) are written as robot files, read by hexabot_sim.kinematics.robot_file, and compared with
roboticstoolbox's DHRobot (RevoluteDH/PrismaticDH, RevoluteMDH/PrismaticMDH) at random q: fkine (tool pose) and
jacob0 (geometric Jacobian in the world frame). Prints the worst differences; exits 1 if one exceeds 1e-12.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
import roboticstoolbox as rtb  # type: ignore[import-not-found]
from spatialmath import SE3  # type: ignore[import-not-found]

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from hexabot_sim.kinematics import robot_file

TOL = 1e-12


def random_table(rng: np.random.Generator, n: int, convention: str) -> tuple[str, list[dict], np.ndarray, np.ndarray]:
    rows = []
    for i in range(n):
        kind = "prismatic" if rng.random() < 0.3 else "revolute"
        row = {"name": f"j{i + 1}", "type": kind, "a": float(rng.uniform(-0.5, 0.5)),
               "d": float(rng.uniform(-0.5, 0.5)), "theta": float(rng.uniform(-math.pi, math.pi)),
               "alpha": float(rng.uniform(-math.pi, math.pi))}  # fmt: skip
        row["lower"], row["upper"] = (-0.3, 0.4) if kind == "prismatic" else (-3.0, 3.0)
        rows.append(row)
    frames = [rng.uniform(-0.3, 0.3, 3).tolist() + rng.uniform(-math.pi, math.pi, 3).tolist() for _ in range(2)]
    lines = ['name = "peer"', f'convention = "{convention}"', 'angles = "rad"']
    for row in rows:
        lines.append("[[joints]]")
        lines += [f'{k} = "{v}"' if isinstance(v, str) else f"{k} = {v!r}" for k, v in row.items()]
    for key, frame in zip(("tool", "base"), frames, strict=True):
        lines += [f"[{key}]", f"xyz = {frame[:3]!r}", f"rpy = {frame[3:]!r}"]
    return "\n".join(lines) + "\n", rows, np.array(frames[0]), np.array(frames[1])


def se3(frame: np.ndarray) -> SE3:
    x, y, z, roll, pitch, yaw = frame
    return SE3(x, y, z) * SE3.Rz(yaw) * SE3.Ry(pitch) * SE3.Rx(roll)


def peer(rows: list[dict], convention: str, tool: np.ndarray, base: np.ndarray) -> rtb.DHRobot:
    links = []
    for r in rows:
        if convention == "standard":
            if r["type"] == "revolute":
                links.append(rtb.RevoluteDH(d=r["d"], a=r["a"], alpha=r["alpha"], offset=r["theta"]))
            else:
                links.append(rtb.PrismaticDH(theta=r["theta"], a=r["a"], alpha=r["alpha"], offset=r["d"], qlim=[-1, 1]))
        elif r["type"] == "revolute":
            links.append(rtb.RevoluteMDH(d=r["d"], a=r["a"], alpha=r["alpha"], offset=r["theta"]))
        else:
            links.append(rtb.PrismaticMDH(theta=r["theta"], a=r["a"], alpha=r["alpha"], offset=r["d"], qlim=[-1, 1]))
    return rtb.DHRobot(links, base=se3(base), tool=se3(tool))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument(
        "--tables", type=int, default=700, help="random tables (default 700: 50 per size and convention)"
    )
    args = parser.parse_args()
    rng = np.random.default_rng(2026)
    worst = {"fk": 0.0, "J": 0.0}
    for k in range(args.tables):
        convention = ("standard", "modified")[k % 2]
        text, rows, tool, base = random_table(rng, 1 + (k // 2) % 7, convention)
        chain = robot_file.parse(text).chain()
        robot = peer(rows, convention, tool, base)
        for _ in range(5):
            q = np.array([rng.uniform(r["lower"], r["upper"]) for r in rows])
            worst["fk"] = max(worst["fk"], float(np.max(np.abs(chain.fk(q) - robot.fkine(q).A))))
            worst["J"] = max(worst["J"], float(np.max(np.abs(chain.jacobian(q) - robot.jacob0(q)))))
    print(f"{args.tables} random tables x 5 configurations against roboticstoolbox {rtb.__version__}: "
          f"worst |FK difference| {worst['fk']:.2e}, worst |J difference| {worst['J']:.2e} "
          f"(limit {TOL:g})")  # fmt: skip
    return 0 if max(worst.values()) <= TOL else 1


if __name__ == "__main__":
    sys.exit(main())
