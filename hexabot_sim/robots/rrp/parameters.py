"""The rrp-velocity scenario's parameters, apart from the computation: `hexabot-sim list` reads them without
MuJoCo (the scenario module is rrp/velocity.py)."""

from __future__ import annotations

import dataclasses

from hexabot_sim.budget import check_duration, check_run_cost, step_count
from hexabot_sim.kinematics import robots
from hexabot_sim.params import param

# Cost of a run for budget.check_run_cost, measured on the 2-core development machine: no physics
# steps; per sample the Jacobian in Python and mj_forward (~1.1 ms; the CSV is counted apart); peak bytes.
RUN_COST: tuple[float, float, float] = (0.0, 1.1e-3, 600.0)
LENGTH_MIN, LENGTH_MAX = robots.LENGTH_MIN, robots.LENGTH_MAX  # [m] the lengths `kin` accepts too
MM: tuple[str, float] = ("mm", 1e-3)  # the unit users type by mistake for a length in m


@dataclasses.dataclass(frozen=True)
class RrpVelocityParams:
    """Parameters of the rrp-velocity scenario (joint trajectory fixed by the report)."""

    d1: float = param(1.0, "m", "height of the q2 axis (report: 1 m)", ge=LENGTH_MIN, le=LENGTH_MAX, typo=MM)
    a2: float = param(1.0, "m", "offset of the prismatic stage (report: 1 m)", ge=LENGTH_MIN, le=LENGTH_MAX, typo=MM)
    duration: float = param(20.0, "s", "t from 0 to duration (report: 20 s)", gt=0.0, le=86400.0)
    timestep: float = param(0.001, "s", "sample period", ge=1e-6, le=0.1)

    def __post_init__(self) -> None:
        check_duration(self.duration, self.timestep)
        n = step_count(self.duration, self.timestep)
        check_run_cost(n, n + 1, 20, *RUN_COST, "raise 'timestep' or lower 'duration'")
