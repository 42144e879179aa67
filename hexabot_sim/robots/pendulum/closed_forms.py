"""The simple pendulum's closed forms, which its run uses for its own predictions (the tests re-derive them
independently): the rest angles of spring + gravity, the exact period, settling."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

SETTLING_BAND: float = 0.02  # settled once |theta - rest| stays within 2 % of |theta0 - rest|

ENERGY_FLOOR: float = 1e-8  # energy_drift_rel needs E(0) above this fraction of (m g c + k) [J]
# `settled` compares energies rounded to ~1e-16 of (m g c + k) with the 2 % band's energy barrier: the barrier must be
# 1e4 times that (a start >= ~0.004 deg from rest for the default pendulum), or rounding would give the verdict.
BARRIER_FLOOR: float = 1e-12


EQUILIBRIA_SPAN: float = 64 * math.pi  # [rad] widest window searched for rest angles (32 turns)


def equilibria(stiffness: float, mgc: float, target: float, lo: float = -math.inf, hi: float = math.inf) -> list[float]:
    """Stable rest angles [rad] of  k (theta - target) + m g c sin(theta) = 0 within lo..hi, in increasing order.

    With k > 0 every root lies within |theta - target| <= m g c / k. The search covers that interval
    clipped to lo..hi and to at most EQUILIBRIA_SPAN next to the target, on a grid of 32 points per pi:
    bounded work for any k, even a spring so weak that there are millions of roots. With k = 0 the
    stable ones are 2 pi n (only 0 is returned when lo..hi is not given).
    """
    if mgc == 0:
        return [target] if stiffness > 0 and lo <= target <= hi else []
    if stiffness == 0:
        if math.isinf(lo) and math.isinf(hi):
            return [0.0]
        first, last = math.ceil(lo / (2 * math.pi)), math.floor(hi / (2 * math.pi))
        return [2 * math.pi * n for n in range(first, min(last, first + 64) + 1)]
    from scipy.optimize import brentq

    def f(theta: float) -> float:
        return stiffness * (theta - target) + mgc * math.sin(theta)

    half = mgc / stiffness  # may be inf for a vanishing spring
    start, stop = max(target - half, lo), min(target + half, hi)
    if not start <= stop:
        return []
    if stop - start > EQUILIBRIA_SPAN:  # the window of that width closest to the target
        centre = min(max(target, start + EQUILIBRIA_SPAN / 2), stop - EQUILIBRIA_SPAN / 2)
        start, stop = centre - EQUILIBRIA_SPAN / 2, centre + EQUILIBRIA_SPAN / 2
    grid = np.linspace(start, stop, 32 * (int((stop - start) / math.pi) + 1) + 1)  # at most 2081 points
    values = np.array([f(x) for x in grid])
    roots = [float(x) for x, v in zip(grid, values, strict=True) if v == 0]
    for i in np.flatnonzero(values[:-1] * values[1:] < 0):
        roots.append(brentq(f, grid[i], grid[i + 1], xtol=1e-15, rtol=4 * np.finfo(float).eps))
    return sorted(r for r in roots if stiffness + mgc * math.cos(r) > 0)


def rest_angle(stiffness: float, mgc: float, target: float, near: float) -> float | None:
    """The stable equilibrium [rad] closest to `near` (unique whenever k > m g c); None if there is none."""
    if stiffness == 0 and mgc > 0:  # stable equilibria are every 2 pi n
        return 2 * math.pi * round(near / (2 * math.pi))
    stable = equilibria(stiffness, mgc, target, near - 2 * math.pi, near + 2 * math.pi) or equilibria(
        stiffness, mgc, target
    )
    return min(stable, key=lambda r: abs(r - near)) if stable else None


def exact_period(inertia: float, mgc: float, theta0: float) -> float:
    """Large-amplitude period [s] of the undamped, spring-free pendulum released from rest at theta0.

    T = 4 sqrt(I / (m g c)) K(k^2),  k = sin(theta0 / 2)  (complete elliptic integral of the first kind).
    """
    from scipy.special import ellipk

    return 4.0 * math.sqrt(inertia / mgc) * float(ellipk(math.sin(theta0 / 2) ** 2))


def upward_crossings(t: np.ndarray, x: np.ndarray, dx: np.ndarray, level: float = 0.0) -> np.ndarray:
    """Times [s] where x rises through `level`, located by cubic Hermite interpolation of (x, dx)."""
    y = x - level
    idx = np.flatnonzero((y[:-1] < 0) & (y[1:] >= 0))
    h = t[idx + 1] - t[idx]
    p0, p1, m0, m1 = y[idx], y[idx + 1], dx[idx] * h, dx[idx + 1] * h
    s = p0 / (p0 - p1)  # linear first guess, refined by Newton on the Hermite cubic
    for _ in range(4):
        s2, s3 = s * s, s * s * s
        value = (2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * m0 + (-2 * s3 + 3 * s2) * p1 + (s3 - s2) * m1
        slope = (6 * s2 - 6 * s) * p0 + (3 * s2 - 4 * s + 1) * m0 + (-6 * s2 + 6 * s) * p1 + (3 * s2 - 2 * s) * m1
        s = np.clip(s - value / np.where(slope == 0, 1.0, slope), 0.0, 1.0)
    return t[idx] + s * h


def settled_for_good(energy_left: float, potential: Callable[[float], float], rest: float, band: float) -> bool:
    """True if the motion can never again leave |theta - rest| <= band.

    Damping only removes energy, so from now on U(theta) - U(rest) <= energy_left; theta moves
    continuously, so it cannot cross a band edge where U - U(rest) exceeds energy_left.

    Args:
        energy_left: Kinetic + potential energy now, minus U(rest), in [J].
        potential: U(theta) in [J] (gravity + spring) for theta in [rad].
        rest: The stable rest angle [rad] the motion is settling to.
        band: Half-width of the band around `rest` [rad].
    """
    barrier = min(potential(rest - band), potential(rest + band)) - potential(rest)
    return band > 0 and energy_left < barrier


def settling_time(t: np.ndarray, theta: np.ndarray, rest: float, band: float) -> float | None:
    """First time [s] after which |theta - rest| stays <= band to the end; None if it never does."""
    outside = np.flatnonzero(np.abs(theta - rest) > band)
    if outside.size == 0:
        return float(t[0])
    if outside[-1] == len(t) - 1:
        return None
    return float(t[outside[-1] + 1])


ENERGY_WARNING: float = 0.1  # energy_drift_rel above this is warned of: the motion is the integrator's
LEAST_TIMESTEP: float = 1e-6  # [s] the pendulum's smallest timestep (its parameter's lower bound)
STEP_SHARE: float = 0.1  # the timestep advised: this over the pendulum's fastest rate (RK4: drift ~1e-6 of E there)


def energy_warning(
    drift: float | None, inertia: float, mgc: float, k: float, b: float, timestep: float, integrator: str
) -> str | None:
    """The warning for an energy balance the integration broke (None: kept within ENERGY_WARNING, or not measured).

    The fastest rates of the motion are the undamped frequency sqrt((k + m g c) / I) and, for RK4, the damper's b / I
    (MuJoCo's Euler and implicit integrators take joint damping implicitly: b / I does not limit them). A step that
    is not small against them (RK4 near its stability edge at omega dt = 2.8, say) loses or gains energy without
    diverging, and the run's figures are then the integrator's, not the pendulum's.
    """
    if drift is None or not drift > ENERGY_WARNING:
        return None
    omega, decay = math.sqrt(max(k + mgc, 0.0) / inertia), (b / inertia if integrator == "RK4" else 0.0)
    rate = max(omega, decay)
    fastest = f"sqrt((k + m g c) / I) = {omega:.4g} rad/s" if omega >= decay else f"b / I = {decay:.4g} 1/s"
    head = (
        f"energy_drift_rel = {drift:.3g}: the integration broke the energy balance by {100 * drift:.3g} % of E(0), "
        f"so the motion is not the pendulum's; the timestep {timestep:g} s is coarse against its fastest rate "
        f"({fastest}; rate x timestep = {rate * timestep:.3g})"
    )
    unit = 10.0 ** (math.floor(math.log10(STEP_SHARE / rate)) - 1)
    advice = float(f"{math.floor(STEP_SHARE / rate / unit) * unit:.2g}")  # rounded down to two digits
    if advice >= LEAST_TIMESTEP:
        return f"{head}: try timestep <= {advice:g} s"
    implicit = ", or integrator=implicit, which takes the damper implicitly" if decay > omega else ""
    return (f"{head}; no timestep down to the least, {LEAST_TIMESTEP:g} s, is that fine: lower the stiffness or "
            f"damping{implicit}")  # fmt: skip
