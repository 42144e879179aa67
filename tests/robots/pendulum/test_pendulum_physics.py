"""Pendulum physics against independent truth: ODE solve, elliptic period, energy balance, equilibrium."""

import math
import re

import numpy as np
import pytest
from pendulum_reference import (
    constants,
    elliptic_period,
    ode_solution,
    simpson_cumulative,
    spring_rest_angle,
)

from hexabot_sim import params, registry
from hexabot_sim.robots.pendulum import closed_forms


def run(name, **overrides):
    scenario = registry.get(name)
    p = params.resolve(scenario.params_type, scenario.defaults, overrides)
    return p, scenario.runner(name, p)


@pytest.fixture(scope="module", params=["pendulum-undamped", "pendulum-damped", "pendulum"])
def default_run(request):
    return request.param, *run(request.param)


def test_matches_high_accuracy_ode_solve(default_run):
    name, p, result = default_run
    t, theta = result.columns["t"], result.columns["theta"]
    assert t[-1] == pytest.approx(10.0)
    inertia, mgc = constants(p.mass, p.length, p.radius)
    theta_ref, omega_ref = ode_solution(
        t, math.radians(p.theta0_deg), inertia, mgc, p.damping, p.stiffness, math.radians(p.target_deg)
    )
    assert np.max(np.abs(theta - theta_ref)) <= 1e-6, name
    assert np.max(np.abs(result.columns["omega"] - omega_ref)) <= 1e-5, name


def test_default_integrator_is_the_accurate_one():
    """Euler at 1 ms is ~1e3 times further from the ODE solution than the default RK4."""
    p, result = run("pendulum-undamped", integrator="Euler")
    inertia, mgc = constants(p.mass, p.length, p.radius)
    t = result.columns["t"]
    theta_ref, _ = ode_solution(t, math.pi / 2, inertia, mgc, 0, 0, 0)
    assert np.max(np.abs(result.columns["theta"] - theta_ref)) > 1e-4


def test_undamped_period_is_the_elliptic_integral_period():
    p, result = run("pendulum-undamped")
    inertia, mgc = constants(p.mass, p.length, p.radius)
    exact = elliptic_period(inertia, mgc, math.pi / 2)
    # Independent measurement: upward zero crossings by linear interpolation (theta'' = 0 at theta = 0).
    t, theta = result.columns["t"], result.columns["theta"]
    i = np.flatnonzero((theta[:-1] < 0) & (theta[1:] >= 0))
    crossings = t[i] - theta[i] * (t[i + 1] - t[i]) / (theta[i + 1] - theta[i])
    measured = (crossings[-1] - crossings[0]) / (len(crossings) - 1)
    assert len(crossings) >= 8
    assert abs(measured - exact) / exact <= 1e-5
    # The run's own metrics agree with the closed form too.
    assert result.metrics["period_exact"].value == pytest.approx(exact, rel=1e-12)
    assert result.metrics["period_rel_error"].value <= 1e-5
    # Large amplitude is slower than the small-angle formula (K(1/2) / (pi/2) = 1.18034).
    assert exact / (2 * math.pi * math.sqrt(inertia / mgc)) == pytest.approx(1.18034060, rel=1e-7)


def test_undamped_total_energy_is_conserved():
    p, result = run("pendulum-undamped")
    inertia, mgc = constants(p.mass, p.length, p.radius)
    theta, omega = result.columns["theta"], result.columns["omega"]
    energy = 0.5 * inertia * omega**2 + mgc * (1 - np.cos(theta))
    assert energy[0] == pytest.approx(mgc)
    assert np.max(np.abs(energy - energy[0])) / energy[0] <= 1e-8


def test_damped_energy_balance():
    p, result = run("pendulum-damped")
    inertia, mgc = constants(p.mass, p.length, p.radius)
    t, theta, omega = result.columns["t"], result.columns["theta"], result.columns["omega"]
    mechanical = 0.5 * inertia * omega**2 + mgc * (1 - np.cos(theta))
    dissipated = simpson_cumulative(p.damping * omega**2, t)
    assert dissipated[-1] > 0.99 * mechanical[0]  # nearly everything has gone into the damper
    balance = mechanical + dissipated
    assert np.max(np.abs(balance - mechanical[0])) / mechanical[0] <= 1e-6
    # The energy columns the run writes satisfy the same balance.
    total = result.columns["energy_total"]
    assert np.max(np.abs(total - total[0])) / total[0] <= 1e-6


def test_simpson_helper_is_accurate():
    t = np.linspace(0, 3, 3001)
    assert np.max(np.abs(simpson_cumulative(np.cos(t), t) - np.sin(t))) < 1e-12


def test_damped_pendulum_comes_to_rest_within_a_few_seconds():
    _, result = run("pendulum-damped")
    settling = result.metrics["settling_time"].value
    assert settling is not None and 1.0 < settling < 5.0
    assert abs(result.columns["theta"][-1]) < 1e-4


def test_spring_rest_angle_balances_gravity():
    p, result = run("pendulum")
    _inertia, mgc = constants(p.mass, p.length, p.radius)
    rest = spring_rest_angle(mgc, p.stiffness, math.radians(p.target_deg))
    final = result.columns["theta"][-1]
    assert abs(final - rest) <= 1e-4
    assert result.metrics["rest_angle_predicted_deg"].value == pytest.approx(math.degrees(rest), abs=1e-9)
    # Near, but visibly not at, the 30 deg target: gravity pulls it down by several degrees.
    assert 3 < 30 - math.degrees(rest) < 10


def test_small_angle_period_is_about_the_spring_rest_angle():
    """With the spring the pendulum oscillates about the rest angle (23.3 deg), where the restoring stiffness is
    k + m g c cos(rest): the small-angle period is 2 pi sqrt(I / (k + m g c cos(rest))), not the 2 pi sqrt(I /
    (k + m g c)) of oscillations about 0 (0.9 % shorter, which the metric once reported)."""
    p, result = run("pendulum", damping=0.0, theta0_deg=24.0, duration=3.0)  # 0.68 deg from rest, undamped
    inertia, mgc = constants(p.mass, p.length, p.radius)
    rest = spring_rest_angle(mgc, p.stiffness, math.radians(p.target_deg))
    expected = 2 * math.pi * math.sqrt(inertia / (p.stiffness + mgc * math.cos(rest)))
    assert result.metrics["period_small_angle"].value == pytest.approx(expected, rel=1e-12)
    assert result.metrics["period_measured"].value == pytest.approx(expected, rel=1e-4)  # the small swing's own
    assert not result.metrics["period_measured"].value == pytest.approx(
        2 * math.pi * math.sqrt(inertia / (p.stiffness + mgc)), rel=1e-3
    )


def test_spring_without_gravity_rests_at_target():
    _, result = run("pendulum", gravity=0.0, target_deg=30.0)
    assert abs(result.columns["theta"][-1] - math.radians(30)) <= 1e-4
    assert result.metrics["rest_angle_predicted_deg"].value == pytest.approx(30.0)


@pytest.mark.parametrize(
    ("k", "mgc", "target"), [(0.5, 0.14715, 0.5), (2.0, 1.0, -1.0), (0.05, 1.0, 0.3), (1.0, 0.0, 0.7)]
)
def test_equilibria_solve_the_balance_and_are_stable(k, mgc, target):
    stable = closed_forms.equilibria(k, mgc, target)
    assert stable
    for r in stable:
        assert abs(k * (r - target) + mgc * math.sin(r)) < 1e-12
        assert k + mgc * math.cos(r) > 0
    if k > mgc:
        assert len(stable) == 1


def test_weak_spring_has_several_stable_rest_angles():
    """k < m g c: the spring cannot hold the link up everywhere; gravity wells near 2 pi n appear."""
    stable = closed_forms.equilibria(0.05, 1.0, 0.3)
    assert len(stable) >= 2


def test_a_broken_energy_balance_is_warned_of_with_a_timestep_that_keeps_it():
    """stiffness 24000 N m/rad: omega dt = 2.83 at 1 ms, just inside RK4's stability edge, so nothing diverges but
    the undamped pendulum loses all its energy; it was written out without a word."""
    p, result = run("pendulum-undamped", stiffness=24000.0, duration=0.5)
    drift = result.metrics["energy_drift_rel"].value
    assert drift > 0.9  # 95 % of it lost in 0.5 s
    [warning] = result.warnings
    assert f"the integration broke the energy balance by {100 * drift:.3g} % of E(0)" in warning
    inertia, mgc = constants(p.mass, p.length, p.radius)  # the reference's own closed forms
    omega = math.sqrt((p.stiffness + mgc) / inertia)
    assert f"rate x timestep = {omega * p.timestep:.3g}" in warning
    advised = float(re.search(r"try timestep <= (\S+) s$", warning).group(1))
    assert 0.97 * 0.1 / omega <= advised <= 0.1 / omega  # 0.1 / omega rounded down to two digits
    _, again = run("pendulum-undamped", stiffness=24000.0, duration=0.5, timestep=advised)
    assert again.warnings == [] and again.metrics["energy_drift_rel"].value < 1e-3


def test_sound_runs_warn_of_nothing(default_run):
    assert default_run[2].warnings == []


@pytest.mark.parametrize("drift", [None, 0.0, 0.05, closed_forms.ENERGY_WARNING])
def test_no_energy_warning_within_the_bound(drift):
    assert closed_forms.energy_warning(drift, 0.003, 0.15, 1.0, 0.0, 0.001, "RK4") is None


def test_the_advice_follows_the_integrator_and_the_least_timestep():
    """Found by fuzzing: b / I limited the advice for every integrator, though MuJoCo's Euler and implicit ones take
    joint damping implicitly (k 2000, b 100 at 10 ms with Euler was told 3e-6 s; 1.2e-4 keeps the energy), and
    a huge damper was told a timestep below the least allowed (3e-7 s, refused when tried)."""
    inertia, mgc = 0.003, 0.14715
    euler = closed_forms.energy_warning(0.19, inertia, mgc, 2000.0, 100.0, 0.01, "Euler")
    assert "sqrt((k + m g c) / I) = 816.5 rad/s" in euler and euler.endswith("try timestep <= 0.00012 s")
    rk4 = closed_forms.energy_warning(0.5, inertia, mgc, 2000.0, 1000.0, 1e-5, "RK4")  # b / I = 3.3e5 1/s
    assert "b / I = 3.333e+05 1/s" in rk4
    assert rk4.endswith("no timestep down to the least, 1e-06 s, is that fine: lower the stiffness or damping, or "
                        "integrator=implicit, which takes the damper implicitly")  # fmt: skip
