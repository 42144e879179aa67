"""Legs that share the load: sensed foot forces and an admittance per leg around the position servos (issue 19).

A position-controlled leg in a stance of four or more feet holds a height, not a force: the loads are
undetermined, and a foot whose share falls near zero unloads and lands again. Here each stance leg's foot
target gets a vertical offset dz from a virtual damper and weak spring driven by its foot's force error,
an admittance as CSIRO's OpenSHC runs on its hexapods:

    D dz/dt + K dz = F - F_ref          (dz > 0 lifts the foot: an overloaded foot yields, an unloaded one presses)

F is the foot's touch sensor (what a real robot has: a force-sensing foot pad, or the load from the servo
current), low-passed over `filter_time`; F_ref is the force distribution of the feet the plan has down: the
least-norm forces that carry the measured total with no moment about the body origin (weighted, so a foot's
share can ramp up after touchdown and down before lift-off). In swing dz returns to zero. The offset enters
the resolved-rate step as a feed term (K_task dz + dz/dt on the foot's z, which the body and hip frames
share), so the servos stay position servos. With a stance leg's own stiffness k_leg the force error decays
in about D / k_leg.

The per-step work is compiled (numba: compliance_kernels.py, warmed up with control/kernels.py); importing
this module for its settings stays cheap. `Admittance` owns its state.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np


def sensed_foot_forces(model: mujoco.MjModel, data: mujoco.MjData, legs: tuple[str, ...] | None = None) -> np.ndarray:
    """Normal force [N] (n_legs,) on each foot as its touch sensor `<leg>_touch` reads it (what a real robot's foot
    pad measures; not MuJoCo's contact list). `legs`: the legs' names in the order wanted; None: every
    `<leg>_touch` sensor of the model, in the model's order. `data` must be forward-computed (mj_step, mj_forward)."""
    if legs is None:
        names = [model.sensor(i).name for i in range(model.nsensor)]
        legs = tuple(name[: -len("_touch")] for name in names if name.endswith("_touch"))
    return np.array([float(data.sensordata[model.sensor_adr[model.sensor(f"{leg}_touch").id]]) for leg in legs])


@dataclasses.dataclass(frozen=True)
class AdmittanceSettings:
    """The virtual leg D dz/dt + K dz = F - F_ref of every stance foot, and how its reference is shared.

    Attributes:
        damping: D [N s/m]: with a stance leg's own stiffness k_leg, the force error decays in D / k_leg.
        stiffness: K [N/m]: a weak spring that keeps dz from drifting (F - F_ref settles at K dz).
        filter_time: The touch sensor's low-pass time constant [s].
        limit: The largest offset [m] either way.
        return_time: In swing, dz returns to zero with this time constant [s].
        ramp_time: A foot's share ramps up over this time after touchdown and down before lift-off [s].
        least_weight: Its smallest weight in the force distribution (at touchdown and lift-off).
    """

    damping: float = 600.0
    stiffness: float = 200.0
    filter_time: float = 0.004
    limit: float = 0.01
    return_time: float = 0.05
    ramp_time: float = 0.08
    least_weight: float = 1.0


class Admittance:
    """The admittance of every leg of a walking controller: call `update` once per control step."""

    def __init__(
        self,
        model: mujoco.MjModel,
        legs: tuple[str, ...],
        hips: np.ndarray,
        yaws: np.ndarray,
        task_gain: float,
        dt: float,
        stance_time: float,
        settings: AdmittanceSettings,
    ) -> None:
        from hexabot_sim.control import compliance_kernels as ck

        self._kernel = ck.admittance
        self._dz, self._stance_time = ck.DZ, ck.STANCE_TIME
        n = len(legs)
        self.settings = settings
        self.geo = np.zeros((n, 5))
        self.geo[:, ck.COS], self.geo[:, ck.SIN] = np.cos(yaws), np.sin(yaws)
        self.geo[:, ck.HIP_X], self.geo[:, ck.HIP_Y] = hips[:, 0], hips[:, 1]
        self.geo[:, ck.TOUCH_ADR] = [model.sensor_adr[model.sensor(f"{leg}_touch").id] for leg in legs]
        self.par = np.zeros(ck.NPAR)
        self.par[ck.DAMPING], self.par[ck.STIFFNESS] = settings.damping, settings.stiffness
        self.par[ck.ALPHA] = dt / (settings.filter_time + dt)
        self.par[ck.DT], self.par[ck.LIMIT], self.par[ck.TASK_GAIN] = dt, settings.limit, task_gain
        self.par[ck.RETURN_TIME], self.par[ck.RAMP_TIME] = settings.return_time, settings.ramp_time
        self.par[ck.STANCE_TIME], self.par[ck.LEAST_WEIGHT] = stance_time, settings.least_weight
        self.state = np.zeros((n, 4))
        self.extra = np.zeros(3 * n)  # the feed correction of the step (z entries only)

    @property
    def stance_time(self) -> float:
        """The gait's stance time [s]: a foot's share ramps down over the last ramp_time of it."""
        return float(self.par[self._stance_time])

    @stance_time.setter
    def stance_time(self, value: float) -> None:
        self.par[self._stance_time] = value

    @property
    def offsets(self) -> np.ndarray:
        """Each foot target's vertical offset dz [m] (n_legs,) now (positive: lifted)."""
        return self.state[:, self._dz].copy()

    def update(self, sensordata: np.ndarray, row: np.ndarray, stance: np.ndarray) -> np.ndarray:
        """Advances the legs by one step; returns the feed correction (3 n_legs,) for the resolved-rate step."""
        self._kernel(self.par, self.geo, self.state, sensordata, row, stance, self.extra)
        return self.extra
