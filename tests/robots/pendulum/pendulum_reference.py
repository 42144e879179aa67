"""Independent pendulum physics for the tests: written from the textbook, not from the package."""

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.special import ellipk

G = 9.81


def constants(mass, length, radius, gravity=G):
    """(I about the pivot, m g c) of a uniform solid cylinder hinged at one end."""
    inertia = mass * (3 * radius**2 + length**2) / 12 + mass * (length / 2) ** 2  # parallel-axis theorem
    return inertia, mass * gravity * length / 2


def ode_solution(t, theta0, inertia, mgc, damping, stiffness, target):
    """theta(t), omega(t) of  I theta'' = -m g c sin(theta) - b theta' - k (theta - target), from rest."""

    def rhs(_, y):
        theta, omega = y
        return [omega, (-mgc * math.sin(theta) - damping * omega - stiffness * (theta - target)) / inertia]

    sol = solve_ivp(rhs, (t[0], t[-1]), [theta0, 0.0], method="DOP853", t_eval=t, rtol=1e-12, atol=1e-13)
    assert sol.success
    return sol.y[0], sol.y[1]


def elliptic_period(inertia, mgc, theta0):
    """Exact period of the free pendulum released from rest at theta0."""
    return 4 * math.sqrt(inertia / mgc) * ellipk(math.sin(theta0 / 2) ** 2)


def spring_rest_angle(mgc, stiffness, target):
    """Root of k (theta - target) + m g c sin(theta) = 0 for k > m g c (then unique)."""
    assert stiffness > mgc
    return brentq(
        lambda x: stiffness * (x - target) + mgc * math.sin(x), target - math.pi, target + math.pi, xtol=1e-15
    )


def simpson_cumulative(y, t):
    """Cumulative integral of samples y(t) on a uniform grid: Simpson on pairs, trapezoid-corrected odd ends."""
    h = t[1] - t[0]
    out = np.zeros_like(y)
    # Composite Simpson over each pair of intervals, filled in at even indices.
    pair = h / 3 * (y[0:-2:2] + 4 * y[1:-1:2] + y[2::2])
    out[2::2] = np.cumsum(pair)
    # Odd indices: the even point before plus a 3-point (quadratic) integral over one interval.
    odd = np.arange(1, len(y) - 1, 2)
    out[odd] = out[odd - 1] + h / 12 * (5 * y[odd - 1] + 8 * y[odd] - y[odd + 1])
    if len(y) % 2 == 0:
        last = len(y) - 1
        out[last] = out[last - 1] + h / 12 * (5 * y[last] + 8 * y[last - 1] - y[last - 2])
    return out
