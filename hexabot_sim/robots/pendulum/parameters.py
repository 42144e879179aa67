"""The pendulum scenarios' parameters, apart from the simulation: `hexabot-sim list` reads them without MuJoCo."""

from __future__ import annotations

import dataclasses

from hexabot_sim.budget import check_duration, check_run_cost, step_count
from hexabot_sim.params import apart, param
from hexabot_sim.robots.pendulum.closed_forms import LEAST_TIMESTEP

INTEGRATORS = ("RK4", "Euler", "implicit", "implicitfast")
# Cost of a run for budget.check_run_cost, measured on the 2-core development machine: seconds per
# mj_step, seconds per recorded row (energies, metrics; the CSV is counted apart), peak bytes per row.
RUN_COST: tuple[float, float, float] = (10e-6, 15e-6, 400.0)


@dataclasses.dataclass(frozen=True)
class PendulumParams:
    """Parameters of the pendulum scenarios (a uniform solid cylinder on a hinge at one end)."""

    mass: float = param(0.1, "kg", "mass of the link", ge=1e-3, le=1000.0)
    length: float = param(0.3, "m", "length of the link, pivot to tip", ge=0.01, le=100.0, typo=("mm", 1e-3))
    radius: float = param(
        0.01, "m", "radius of the link (solid cylinder), < length", ge=1e-4, le=10.0, typo=("mm", 1e-3)
    )
    damping: float = param(0.01, "N*m*s/rad", "joint viscous damping b (report: 0.01)", ge=0.0, le=1e6)
    stiffness: float = param(0.5, "N*m/rad", "joint spring stiffness k", ge=0.0, le=1e6)
    target_deg: float = param(
        30.0, "deg", "spring equilibrium position (Simscape 'equilibrium position')", ge=-720.0, le=720.0
    )
    theta0_deg: float = param(90.0, "deg", "initial angle, 0 = hanging down; released from rest", ge=-720.0, le=720.0)
    gravity: float = param(9.81, "m/s^2", "gravitational acceleration (0 switches gravity off)", ge=0.0, le=100.0)
    duration: float = param(10.0, "s", "simulated time", gt=0.0, le=86400.0)
    timestep: float = param(0.001, "s", "integration timestep", ge=LEAST_TIMESTEP, le=0.1)
    integrator: str = param("RK4", "", "MuJoCo integrator", choices=INTEGRATORS)

    def __post_init__(self) -> None:
        if self.radius >= self.length:
            radius, length = apart(self.radius, self.length, "down")
            raise ValueError(f"parameter 'radius' must be smaller than 'length' ({length} m); got {radius}")
        check_duration(self.duration, self.timestep)
        n = step_count(self.duration, self.timestep)
        check_run_cost(n, n + 1, 8, *RUN_COST, "raise 'timestep' or lower 'duration'")
