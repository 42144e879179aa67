"""The reports' amplitude and frequency studies as one grid of leg-step runs, in parallel on all cores."""

from __future__ import annotations

import concurrent.futures
import dataclasses
import math
import multiprocessing
import os
from typing import Any

import mujoco
import numpy as np

from hexabot_sim.params import param
from hexabot_sim.scenarios import leg
from hexabot_sim.scenarios.base import Metric, Progress, ScenarioResult

# Grid columns written to grid.csv, from each cell's leg-step metrics.
CELL_METRICS = (
    "max_lateral_deviation",
    "max_vertical_deviation",
    "max_x_error",
    "min_abs_det_j",
    "min_sigma",
    "max_joint_speed_reached",
    "singular_duration",
    "excursion_forward",
    "reach_forward",
)


@dataclasses.dataclass(frozen=True)
class LegSweepParams(leg.LegParams):
    """Parameters of the leg-sweep scenario: a grid of leg-step runs over amplitude x omega."""

    amplitudes: tuple = param(
        (0.01, 0.02, 0.03, 0.04, 0.05, 0.06, 0.07, 0.08, 0.09, 0.10),
        "m/s", "grid of amplitudes A (report: 10, 50, 100 mm/s at 1 rad/s, 80 mm/s at 1 and pi/6)", "positive",
    )  # fmt: skip
    omegas: tuple = param(
        (math.pi / 6, 0.75, 1.0, 1.5, 2.0, 3.0), "rad/s", "grid of omegas (comma-separated)", "positive"
    )
    periods: float = param(2.0, "1", "simulated periods of the command per cell", "positive")
    workers: int = param(0, "1", "parallel processes; 0 = one per core", "nonnegative")
    mode: str = param(
        "kinematic", "", "kinematic (default here: the reports' setup, fastest) or dynamic",
        choices=("dynamic", "kinematic"),
    )  # fmt: skip

    def __post_init__(self) -> None:
        if len(self.amplitudes) * len(self.omegas) > 400:
            raise ValueError("the grid must have at most 400 cells (amplitudes x omegas)")

    def cell(self, amplitude: float, omega: float) -> leg.LegStepParams:
        """The leg-step parameters of one grid cell."""
        common = {f.name: getattr(self, f.name) for f in dataclasses.fields(leg.LegParams)}
        return leg.LegStepParams(
            **common, amplitude=amplitude, omega=omega, duration=self.periods * 2 * math.pi / omega
        )


def _run_cell(cell: leg.LegStepParams) -> dict[str, Any]:
    """One leg-step run; only its metrics travel back to the parent process."""
    result = leg.run("leg-step", cell)
    return {name: metric.value for name, metric in result.metrics.items()}


def _pool(workers: int) -> concurrent.futures.ProcessPoolExecutor:
    # fork is cheap and safe here (no GL, no threads yet); spawn elsewhere.
    methods = multiprocessing.get_all_start_methods()
    context = multiprocessing.get_context("fork" if "fork" in methods else "spawn")
    return concurrent.futures.ProcessPoolExecutor(max_workers=workers, mp_context=context)


def run(name: str, p: LegSweepParams, progress: Progress | None = None) -> ScenarioResult:
    """Runs every (amplitude, omega) cell and tabulates the deviations from the line."""
    cells = [(a, w) for a in p.amplitudes for w in p.omegas]
    workers = p.workers or os.cpu_count() or 1
    results: dict[int, dict[str, Any]] = {}
    with _pool(min(workers, len(cells))) as pool:
        futures = {pool.submit(_run_cell, p.cell(a, w)): i for i, (a, w) in enumerate(cells)}
        for done, future in enumerate(concurrent.futures.as_completed(futures), start=1):
            results[futures[future]] = future.result()
            if progress is not None:
                progress(done, len(cells))

    amplitude = np.array([a for a, _ in cells])
    omega = np.array([w for _, w in cells])
    columns: dict[str, np.ndarray] = {"amplitude": amplitude, "omega": omega}
    for metric in CELL_METRICS:
        columns[metric] = np.array([float(results[i][metric]) for i in range(len(cells))])
    columns["max_deviation"] = np.maximum(columns["max_lateral_deviation"], columns["max_vertical_deviation"])
    columns["reached_singular"] = np.array(
        [float(results[i]["singular_first_time"] is not None) for i in range(len(cells))]
    )
    columns["predicted_to_leave"] = (columns["excursion_forward"] > columns["reach_forward"]).astype(float)
    units = {"amplitude": "m/s", "omega": "rad/s", "min_abs_det_j": "m^3/rad^3", "min_sigma": "m/rad"}
    units |= {"max_joint_speed_reached": "rad/s", "singular_duration": "s", "reached_singular": "1"}
    units |= {"predicted_to_leave": "1"}
    units = {k: units.get(k, "m") for k in columns}

    agree = columns["reached_singular"] == columns["predicted_to_leave"]
    reach = float(columns["reach_forward"][0])
    metrics = {
        "cells": Metric(len(cells), "1", "runs in the grid"),
        "reach_forward": Metric(reach, "m", "travel along +x from the start before leaving the workspace"),
        "cells_leaving": Metric(
            int(columns["predicted_to_leave"].sum()), "1", "cells whose 2A/omega exceeds the reach"
        ),
        "cells_singular": Metric(int(columns["reached_singular"].sum()), "1", "cells that came near a singularity"),
        "prediction_agreement": Metric(
            float(agree.mean()), "1", "fraction of cells where 'reached a singularity' == '2A/omega > reach'"
        ),
        "max_deviation_inside": Metric(
            float(columns["max_deviation"][columns["predicted_to_leave"] == 0].max(initial=0.0)),
            "m",
            "largest deviation from the line among cells predicted to stay inside",
        ),
    }
    model = mujoco.MjModel.from_xml_string(xml := leg.build_xml(p))
    return ScenarioResult(
        scenario=name,
        params=p,
        model=model,
        model_xml=xml,
        trajectory=None,
        columns=columns,
        column_units=units,
        metrics=metrics,
        summary=["cells", "reach_forward", "cells_leaving", "cells_singular", "prediction_agreement"],
        camera=None,
        figures="leg_sweep",
        csv_name="grid.csv",
    )
