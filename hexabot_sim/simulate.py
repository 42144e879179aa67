"""The stepping loop: preallocated arrays in, a Trajectory out; divergence is detected, never recorded."""

from __future__ import annotations

import contextlib
import dataclasses
import math
from collections.abc import Callable, Iterator

import mujoco
import numpy as np

from hexabot_sim.errors import SimulationError
from hexabot_sim.signals import RECEIVED_SIGNALS, stop_request

# Steps between two divergence checks (warning counters, finiteness of the recorded block).
CHECK_EVERY: int = 100
# Steps between two progress reports (a multiple of CHECK_EVERY).
PROGRESS_EVERY: int = 10_000

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
    ctrl: np.ndarray | None = None  # (n, nu) controls in force during the step that ended at row i (row 0: initial)


def warning_counts(data: mujoco.MjData) -> np.ndarray:
    """Number of times each MuJoCo warning fired."""
    return data.warning.number.copy()


def simulate(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    n_steps: int,
    controller: Controller | None = None,
    step: Controller = mujoco.mj_step,
    progress: Callable[[int, int], None] | None = None,
    record_ctrl: bool = False,
) -> Trajectory:
    """Steps `data` n_steps times from its current state, recording every step.

    Args:
        model: Compiled model.
        data: State to start from; it is advanced in place.
        n_steps: Number of mj_step calls.
        controller: Called before every step to set data.ctrl (or the state, for kinematic playback).
        step: Advances data by one timestep: mj_step (dynamics) or a kinematic update.
        progress: Called with (steps done, n_steps) every PROGRESS_EVERY steps and at the end.
        record_ctrl: Also record data.ctrl after every step (Trajectory.ctrl).

    Raises:
        SimulationError: naming the time and the cause, when MuJoCo warns or the state is non-finite.
    """
    t = np.empty(n_steps + 1)  # (n,)
    qpos = np.empty((n_steps + 1, model.nq))  # (n, nq)
    qvel = np.empty((n_steps + 1, model.nv))  # (n, nv)
    ctrl = np.empty((n_steps + 1, model.nu)) if record_ctrl else None  # (n, nu)
    warnings0 = warning_counts(data)
    # Views into mjData, bound once: reading them in the loop costs only the copy into the record.
    data_qpos, data_qvel, data_ctrl = data.qpos, data.qvel, data.ctrl

    # MuJoCo prints its warnings by default; collect them instead, for one clear error message.
    messages: list[str] = []
    previous_handler = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(messages.append)
    try:
        t[0], qpos[0], qvel[0] = data.time, data_qpos, data_qvel
        if ctrl is not None:
            ctrl[0] = data_ctrl
        for first in range(1, n_steps + 1, CHECK_EVERY):
            last = min(first + CHECK_EVERY - 1, n_steps)
            if controller is None:
                for i in range(first, last + 1):
                    # Step, record.
                    step(model, data)
                    t[i], qpos[i], qvel[i] = data.time, data_qpos, data_qvel
            elif ctrl is None:
                for i in range(first, last + 1):
                    # Command, step, record.
                    controller(model, data)
                    step(model, data)
                    t[i], qpos[i], qvel[i] = data.time, data_qpos, data_qvel
            else:
                for i in range(first, last + 1):
                    # Command, step, record (with the command).
                    controller(model, data)
                    step(model, data)
                    t[i], qpos[i], qvel[i], ctrl[i] = data.time, data_qpos, data_qvel, data_ctrl
            _check(data, warnings0, messages, t, qpos, qvel, first - 1, last)
            if RECEIVED_SIGNALS:  # a stop request whose exception some library swallowed: stop now
                raise stop_request(RECEIVED_SIGNALS[-1])
            if progress is not None and (last % PROGRESS_EVERY < CHECK_EVERY or last == n_steps):
                progress(last, n_steps)
    finally:
        mujoco.set_mju_user_warning(previous_handler)
    return Trajectory(t=t, qpos=qpos, qvel=qvel, ctrl=ctrl)


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
    raise SimulationError(
        f"simulation diverged after t = {t_last:.6g} s ({cause}); {likely_cause(data.model, qpos[0], qvel[0])}"
    )


# Largest |lambda * dt| of a linear mode each integrator keeps stable. RK4's stability region reaches
# 2.83 along the imaginary axis and 2.79 along the negative real one; MuJoCo's Euler and the implicit
# integrators advance positions explicitly (semi-implicit Euler: stable for omega * dt < 2) and treat
# damping implicitly, so for them only the undamped frequencies count.
STABILITY_LIMIT: dict[str, float] = {"mjINT_RK4": 2.8}
SEMI_IMPLICIT_LIMIT: float = 2.0
MIN_TIMESTEP: float = 1e-6  # [s] the smallest timestep any scenario accepts


def _fastest_mode(model: mujoco.MjModel, qpos0: np.ndarray, qvel0: np.ndarray, with_damping: bool) -> float:
    """|lambda| [1/s] of the fastest mode of the dynamics linearised at (qpos0, qvel0), by central differences."""
    data = mujoco.MjData(model)
    nv, eps = model.nv, 1e-6
    rows = np.zeros((nv, 2 * nv))  # (nv, 2 nv) d qacc / d (q, v)
    for j in range(2 * nv):
        acc = []
        for sign in (1.0, -1.0):
            data.qpos[:], data.qvel[:] = qpos0, qvel0
            if j < nv:
                dq = np.zeros(nv)
                dq[j] = sign * eps
                mujoco.mj_integratePos(model, data.qpos, dq, 1.0)
            else:
                data.qvel[j - nv] += sign * eps
            mujoco.mj_forward(model, data)
            acc.append(data.qacc.copy())
        rows[:, j] = (acc[0] - acc[1]) / (2 * eps)
    if not np.isfinite(rows).all():
        return math.nan
    if not with_damping:  # undamped frequencies: omega^2 = eigenvalues of -d qacc / d q
        return float(np.sqrt(np.max(np.abs(np.linalg.eigvals(rows[:, :nv]))))) if nv else 0.0
    system = np.block([[np.zeros((nv, nv)), np.eye(nv)], [rows]])  # (2 nv, 2 nv) d (q, v)/dt
    return float(np.max(np.abs(np.linalg.eigvals(system)))) if nv else 0.0


def _largest_term(model: mujoco.MjModel) -> str:
    """The stiffest spring, servo gain or damper of the model against its inertia, in words."""
    terms: list[tuple[float, str]] = []
    for dof in range(model.nv):
        inertia = float(model.dof_M0[dof])
        joint = int(model.dof_jntid[dof])
        name = model.joint(joint).name or f"#{joint}"
        hinge = model.jnt_type[joint] == mujoco.mjtJoint.mjJNT_HINGE
        k_unit, b_unit, i_unit = ("N*m/rad", "N*m*s/rad", "kg*m^2") if hinge else ("N/m", "N*s/m", "kg")
        if inertia <= 0:
            continue
        k = float(model.jnt_stiffness[joint])
        b = float(model.dof_damping[dof])
        for act in range(model.nu):  # position / velocity servos on this joint
            if model.actuator_trntype[act] == mujoco.mjtTrn.mjTRN_JOINT and model.actuator_trnid[act, 0] == joint:
                k += max(-float(model.actuator_biasprm[act, 1]), 0.0)
                b += max(-float(model.actuator_biasprm[act, 2]), 0.0)
        if k > 0:
            rate = math.sqrt(k / inertia)
            terms.append((rate, f"stiffness {k:.3g} {k_unit} on inertia {inertia:.3g} {i_unit} of joint '{name}' "
                                f"gives sqrt(k/I) = {rate:.3g} rad/s"))  # fmt: skip
        if b > 0:
            rate = b / inertia
            terms.append((rate, f"damping {b:.3g} {b_unit} on inertia {inertia:.3g} {i_unit} of joint '{name}' "
                                f"gives b/I = {rate:.3g} 1/s"))  # fmt: skip
    return max(terms)[1] if terms else ""


def likely_cause(model: mujoco.MjModel, qpos0: np.ndarray, qvel0: np.ndarray) -> str:
    """Why a run diverged, from the model's fastest mode against its timestep (computed only on divergence).

    Returns one of: the timestep is too large for the fastest mode (and the timestep that would do);
    an absurd input (a mode no timestep >= MIN_TIMESTEP can follow); or not the timestep at all.
    """
    dt = float(model.opt.timestep)
    integrator = mujoco.mjtIntegrator(model.opt.integrator).name
    limit = STABILITY_LIMIT.get(integrator, SEMI_IMPLICIT_LIMIT)
    try:
        rate = _fastest_mode(model, np.asarray(qpos0, float), np.asarray(qvel0, float), integrator in STABILITY_LIMIT)
        term = _largest_term(model)
    except (mujoco.FatalError, ValueError, np.linalg.LinAlgError):
        rate, term = math.nan, ""
    source = f" ({term})" if term else ""
    if not math.isfinite(rate):
        return "the model cannot be linearised at its start: look for an absurd input (masses, gains, lengths)"
    if rate * dt <= limit:
        return (
            f"not the timestep: the fastest mode of the model{source} is {rate:.3g} 1/s and rate * timestep = "
            f"{rate * dt:.2g} is inside the integrator's stability limit {limit:g}; look for an absurd input "
            f"(huge speeds, gains or forces)"
        )
    stable = limit / rate
    name = integrator.removeprefix("mjINT_")
    if stable < MIN_TIMESTEP:
        return (
            f"an absurd input: the fastest mode of the model is {rate:.3g} 1/s{source}; {name} would need a "
            f"timestep below {stable:.2g} s, less than the smallest allowed ({MIN_TIMESTEP:g} s): lower the "
            f"stiffness, gains or damping, or raise the masses"
        )
    return (
        f"the timestep {dt:g} s is too large for the fastest mode of the model, {rate:.3g} 1/s{source}: {name} "
        f"is stable only below {stable:.2g} s; try a timestep <= {0.5 * stable:.2g} s"
    )


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


@contextlib.contextmanager
def mujoco_warnings(report: Callable[[str], None]) -> Iterator[None]:
    """Collects MuJoCo's warnings during the block and hands each distinct one to `report` (one line) after it.

    MuJoCo's default handler prints them and appends them to MUJOCO_LOG.TXT in the working folder.
    """
    seen: list[str] = []
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(seen.append)
    try:
        yield
    finally:
        mujoco.set_mju_user_warning(previous)
        for message in dict.fromkeys(seen):
            report(" ".join(message.split()))
