"""Report 004's pinv note: why pinv of the 6x3 leg Jacobian against a zero angular velocity misses the foot velocity.

Report 004 drove the leg with dq = pinv(J_6x3) [v; 0, 0, 0] and saw "a minor discrepancy in the
Y-direction velocity", blamed on "the 6x3 Jacobian" or integration error. The cause is least squares:
the 3 joints cannot give the commanded linear velocity AND a zero angular velocity (6 equations, 3
unknowns), so pinv returns the joint rates that minimise |J_v dq - v|^2 + |J_w dq - 0|^2, a
compromise that under-delivers v. Only the part of v that needs coxa rotation (q1) or femur + tibia
rotation is penalised, so the error appears along the directions those joints serve - y as soon as
the leg is not aligned with x. The size of the compromise even depends on the length unit: in mm
(as in the report's MATLAB, a1 = 50) the linear rows weigh 1000x more and the error almost vanishes,
in m it is large. The exact 3x3 inverse of the linear rows has no such error.

Usage: python scripts/pinv_note.py [--out docs/pinv_note.png]
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from hexabot_sim.kinematics import robots
from hexabot_sim.kinematics.chain import SerialChain

AMPLITUDE = 0.05  # [m/s] v_x = A sin(w t), the leg-step default
OMEGA = 1.0  # [rad/s]
DT = 0.001  # [s]
DURATION = 2 * math.pi  # [s] one period


def integrate(chain: SerialChain, q0: np.ndarray, method: str, unit: float) -> tuple[np.ndarray, np.ndarray]:
    """Open-loop integration of dq (as in the report's Simulink); returns t and the foot velocity (n, 3) [m/s].

    Args:
        chain: The leg's SerialChain (lengths in m).
        q0: Start joint angles [rad].
        method: "pinv6" (report 004) or "inv3" (the exact inverse of the linear rows).
        unit: Length unit the Jacobian is written in, in m (1 for m, 1e-3 for mm): scales its linear rows.
    """
    n = round(DURATION / DT)
    t = np.arange(n) * DT
    q = q0.copy()
    v_foot = np.empty((n, 3))  # (n, 3)
    for i, ti in enumerate(t):
        jac = chain.jacobian(q)  # (6, 3), lengths in m
        v_des = np.array([AMPLITUDE * math.sin(OMEGA * ti), 0.0, 0.0])
        if method == "pinv6":
            scaled = jac.copy()
            scaled[:3] /= unit  # linear rows in unit/s per rad
            dq = np.linalg.pinv(scaled) @ np.r_[v_des / unit, 0.0, 0.0, 0.0]
        else:
            dq = np.linalg.solve(jac[:3], v_des)
        v_foot[i] = jac[:3] @ dq
        q = q + dq * DT
    return t, v_foot


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default=str(Path(__file__).resolve().parent.parent / "docs" / "pinv_note.png"))
    args = parser.parse_args()

    chain = robots.get("leg").chain()
    cases = {
        "coxa at 0 (leg along x)": np.array([0.0, 0.41151684606748806, 2.3185589614548174]),
        "coxa at 30 deg": np.array([math.radians(30), 0.41151684606748806, 2.3185589614548174]),
    }
    fig, axes = plt.subplots(3, 2, sharex=True, figsize=(12, 8), constrained_layout=True)
    for col, (label, q0) in enumerate(cases.items()):
        runs = {
            "exact inverse of the 3x3 linear rows": integrate(chain, q0, "inv3", 1.0),
            "report 004: pinv of 6x3 [v; 0], lengths in mm": integrate(chain, q0, "pinv6", 1e-3),
            "pinv of 6x3 [v; 0], lengths in m": integrate(chain, q0, "pinv6", 1.0),
        }
        for (name, (t, v)), style in zip(runs.items(), ("-", "--", ":"), strict=True):
            for row in range(3):
                axes[row, col].plot(t, v[:, row] * 1000, style, label=name)
            err = np.abs(v - np.c_[AMPLITUDE * np.sin(OMEGA * t), 0 * t, 0 * t]).max(axis=0)
            print(f"{label:26} {name:48} max |v - v_des| x, y, z = {err[0]:.2e}, {err[1]:.2e}, {err[2]:.2e} m/s")
        for row, axis in enumerate("xyz"):
            axes[row, col].set_ylabel(f"foot v_{axis} [mm/s]")
            axes[row, col].grid(alpha=0.3)
            low, high = axes[row, col].get_ylim()
            if high - low < 1.0:  # round-off only: show it as the zero it is
                axes[row, col].set_ylim(-0.5, 0.5)
        axes[0, col].set_title(f"start: {label}; command v = (50 sin t, 0, 0) mm/s, ω = 0", fontsize=10)
        axes[-1, col].set_xlabel("time t [s]")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle(
        "pinv of the 6x3 Jacobian asks for an impossible zero rotation:\n"
        "its least-squares compromise under-delivers v, by an amount that depends on the length unit"
    )
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
