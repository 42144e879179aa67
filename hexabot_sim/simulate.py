"""The stepping loop: preallocated arrays in, a Trajectory out; divergence is detected, never recorded."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import mujoco
import numpy as np

from hexabot_sim.errors import SimulationError

# Steps between two divergence checks (warning counters, finiteness of the recorded block).
CHECK_EVERY: int = 100

_WARNING_TEXT = {
    "mjWARN_INERTIA": "invalid inertia",
    "mjWARN_CONTACTFULL": "contact buffer full",
    "mjWARN_CNSTRFULL": "constraint buffer full",
    "mjWARN_BADQPOS": "bad qpos (NaN, inf or huge)",
    "mjWARN_BADQVEL": "bad qvel (NaN, inf or huge)",
    "mjWARN_BADQACC": "bad qacc (NaN, inf or huge): the integration is unstable",
    "mjWARN_BADCTRL": "bad ctrl (NaN, inf or huge)",
}

Controller = Callable[[mujoco.MjModel, mujoco.MjData], None]


@dataclasses.dataclass(frozen=True)
class Trajectory:
    """States recorded after every step (row 0 is the initial state)."""

    t: np.ndarray  # (n,) [s]
    qpos: np.ndarray  # (n, nq)
    qvel: np.ndarray  # (n, nv)


def step_count(duration: float, timestep: float) -> int:
    """Number of steps that covers `duration` (the last recorded time is >= duration)."""
    return max(1, math.ceil(duration / timestep - 1e-9))


def warning_counts(data: mujoco.MjData) -> np.ndarray:
    """Number of times each MuJoCo warning fired."""
    return np.array([w.number for w in data.warning])


def simulate(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    n_steps: int,
    controller: Controller | None = None,
    step: Controller = mujoco.mj_step,
) -> Trajectory:
    """Steps `data` n_steps times from its current state, recording every step.

    Args:
        model: Compiled model.
        data: State to start from; it is advanced in place.
        n_steps: Number of mj_step calls.
        controller: Called before every step to set data.ctrl (or the state, for kinematic playback).
        step: Advances data by one timestep: mj_step (dynamics) or a kinematic update.

    Raises:
        SimulationError: naming the time and the cause, when MuJoCo warns or the state is non-finite.
    """
    t = np.empty(n_steps + 1)  # (n,)
    qpos = np.empty((n_steps + 1, model.nq))  # (n, nq)
    qvel = np.empty((n_steps + 1, model.nv))  # (n, nv)
    warnings0 = warning_counts(data)
    # Views into mjData, bound once: reading them in the loop costs only the copy into the record.
    data_qpos, data_qvel = data.qpos, data.qvel

    # MuJoCo prints its warnings by default; collect them instead, for one clear error message.
    messages: list[str] = []
    previous_handler = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(messages.append)
    try:
        t[0], qpos[0], qvel[0] = data.time, data_qpos, data_qvel
        for first in range(1, n_steps + 1, CHECK_EVERY):
            last = min(first + CHECK_EVERY - 1, n_steps)
            if controller is None:
                for i in range(first, last + 1):
                    # Step, record.
                    step(model, data)
                    t[i], qpos[i], qvel[i] = data.time, data_qpos, data_qvel
            else:
                for i in range(first, last + 1):
                    # Command, step, record.
                    controller(model, data)
                    step(model, data)
                    t[i], qpos[i], qvel[i] = data.time, data_qpos, data_qvel
            _check(data, warnings0, messages, t, qpos, qvel, first - 1, last)
    finally:
        mujoco.set_mju_user_warning(previous_handler)
    return Trajectory(t=t, qpos=qpos, qvel=qvel)


def _check(
    data: mujoco.MjData,
    warnings0: np.ndarray,
    messages: list[str],
    t: np.ndarray,
    qpos: np.ndarray,
    qvel: np.ndarray,
    start: int,
    stop: int,
) -> None:
    """Raises SimulationError if rows start..stop hold a non-finite state or a warning fired."""
    block = slice(start, stop + 1)
    bad = ~(np.isfinite(qpos[block]).all(axis=1) & np.isfinite(qvel[block]).all(axis=1))
    # MuJoCo resets the state (and time) after a bad-qacc warning: time going backwards marks it.
    bad[1:] |= np.diff(t[block]) <= 0
    fired = np.flatnonzero(warning_counts(data) > warnings0)
    if not bad.any() and fired.size == 0:
        return
    first = start + int(np.argmax(bad)) if bad.any() else stop
    t_last = t[max(first - 1, 0)]
    if messages:
        cause = f"MuJoCo: {messages[0].rstrip('.')}"
    elif fired.size:
        cause = "; ".join(_WARNING_TEXT.get(mujoco.mjtWarning(k).name, str(k)) for k in fired)
    else:
        cause = "non-finite state"
    raise SimulationError(f"simulation diverged after t = {t_last:.6g} s ({cause}); try a smaller timestep")


@dataclasses.dataclass(frozen=True)
class SiteTrajectory:
    """A site's pose and velocity along a trajectory, as MuJoCo computes them, world frame."""

    pos: np.ndarray  # (n, 3) [m]
    xmat: np.ndarray  # (n, 3, 3)
    vel: np.ndarray  # (n, 3) [m/s], linear velocity = mj_jacSite(q) qvel


def site_trajectory(model: mujoco.MjModel, traj: Trajectory, site: str) -> SiteTrajectory:
    """Replays the recorded states through MuJoCo's kinematics and reads the site at every row."""
    data = mujoco.MjData(model)
    site_id = model.site(site).id
    n = len(traj.t)
    pos = np.empty((n, 3))  # (n, 3)
    xmat = np.empty((n, 3, 3))  # (n, 3, 3)
    vel = np.empty((n, 3))  # (n, 3)
    jacp = np.empty((3, model.nv))  # (3, nv)
    for i in range(n):
        data.qpos[:] = traj.qpos[i]
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        mujoco.mj_jacSite(model, data, jacp, None, site_id)
        pos[i] = data.site_xpos[site_id]
        xmat[i] = data.site_xmat[site_id].reshape(3, 3)
        vel[i] = jacp @ traj.qvel[i]
    return SiteTrajectory(pos=pos, xmat=xmat, vel=vel)
