"""The leg-step scenario and the resolved-rate controller against FK, Jacobians, closed forms and the CLI."""

import functools
import inspect
import json
import math

import mujoco
import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation

from hexabot_sim import models, params, registry
from hexabot_sim.__main__ import main
from hexabot_sim.control.resolved_rate import (
    ResolvedRateController,
    ResolvedRateGains,
    damped_solve,
    sigma_min,
)
from hexabot_sim.kinematics import leg
from hexabot_sim.robots.leg import step
from hexabot_sim.robots.leg.parameters import LegStepParams
from hexabot_sim.robots.leg.step import GEOMETRY

HIP = np.array([0.0, 0.0, 0.3])  # hip site in the world [m], axes aligned (tests/test_leg_model.py checks it)
_MODEL = mujoco.MjModel.from_xml_path(str(models.model_path("leg")))
LOWER, UPPER = np.array([_MODEL.jnt_range[_MODEL.joint(j).id] for j in ("coxa", "femur", "tibia")]).T  # [rad]
OUTSIDE = {"amplitude": 0.1, "omega": 0.5236}  # report 004: 100 mm/s at pi/6 leaves the workspace
COLUMNS = (
    "t q1 q2 q3 dq1 dq2 dq3 foot_x foot_y foot_z foot_x_des foot_y_des foot_z_des "
    "vx vy vz vx_des vy_des vz_des det_j roll pitch yaw"
).split()
METRICS = (
    "max_lateral_deviation",
    "max_vertical_deviation",
    "max_x_error",
    "min_abs_det_j",
    "singular_first_time",
    "singular_duration",
)


@functools.cache
def _run(overrides: tuple):
    scenario = registry.get("leg-step")
    p = params.resolve(scenario.params_type, scenario.defaults, dict(overrides))
    return p, scenario.runner("leg-step", p)


def run(**overrides):
    """(params, result) of leg-step; each distinct set of overrides is simulated once per session."""
    return _run(tuple(sorted(overrides.items())))


def fresh_run(**overrides):
    scenario = registry.get("leg-step")
    p = params.resolve(scenario.params_type, scenario.defaults, overrides)
    return scenario.runner("leg-step", p)


def joints(c) -> tuple[np.ndarray, np.ndarray]:
    return np.c_[c["q1"], c["q2"], c["q3"]], np.c_[c["dq1"], c["dq2"], c["dq3"]]  # (n, 3), (n, 3)


def start_world(p) -> np.ndarray:
    return HIP + np.array([p.start_x, p.start_y, p.start_z])


def reachable(x: float, y: float, z: float, ranges: bool) -> bool:
    """Some IK branch reaches (x, y, z) (hip frame), within the joint ranges if `ranges`."""
    try:
        branches = leg.ik((x, y, z), GEOMETRY, q1=0.0)
    except leg.IKError:
        return False
    return not ranges or any(np.all((q >= LOWER - 1e-12) & (q <= UPPER + 1e-12)) for q in branches)


def reach_by_bisection(start, sign: float, ranges: bool) -> float:
    """Travel [m] along sign * x from `start` before the foot target becomes unreachable."""
    x0, y0, z0 = start
    inside, outside = 0.0, 1.0  # 1 m is far past the 0.25 m reach
    assert reachable(x0, y0, z0, ranges) and not reachable(x0 + sign * outside, y0, z0, ranges)
    for _ in range(60):
        mid = 0.5 * (inside + outside)
        inside, outside = (mid, outside) if reachable(x0 + sign * mid, y0, z0, ranges) else (inside, mid)
    return inside


@pytest.fixture(scope="module", params=["dynamic", "kinematic"])
def default_run(request):
    return run(mode=request.param)


@pytest.fixture(scope="module", params=["dynamic", "kinematic"])
def outside_run(request):
    return run(mode=request.param, **OUTSIDE)


@pytest.fixture(scope="module", params=["default", "outside", "cosine"])
def any_run(request, default_run, outside_run):
    return {"default": default_run, "outside": outside_run, "cosine": run(profile="cosine")}[request.param]


# --- acceptance with the defaults ---


def test_default_step_stays_on_its_line(default_run):
    p, r = default_run
    c = r.columns
    tol = {"dynamic": 0.5e-3, "kinematic": 1e-6}[p.mode]  # [m]
    x0, y0, z0 = start_world(p)
    lateral = np.max(np.abs(c["foot_y"] - y0))
    vertical = np.max(np.abs(c["foot_z"] - z0))
    x_error = np.max(np.abs(c["foot_x"] - c["foot_x_des"]))
    assert lateral <= tol and vertical <= tol and x_error <= tol, (p.mode, lateral, vertical, x_error)
    assert c["t"][-1] >= 4 * math.pi / p.omega and c["foot_x"][0] == pytest.approx(x0, abs=1e-12)
    # The whole step was taken: the foot reached x0 + 2A/omega and came back.
    assert np.max(c["foot_x"]) - x0 == pytest.approx(2 * p.amplitude / p.omega, abs=tol)
    # The run's own metrics say the same.
    m = r.metrics
    assert m["max_lateral_deviation"].value == pytest.approx(lateral, abs=1e-15)
    assert m["max_vertical_deviation"].value == pytest.approx(vertical, abs=1e-15)
    assert m["max_x_error"].value == pytest.approx(x_error, abs=1e-15)


@pytest.mark.slow
def test_desired_columns_are_the_exact_integral_of_the_command(any_run):
    p, r = any_run
    c = r.columns
    t, (x0, y0, z0) = c["t"], start_world(p)
    a, w = p.amplitude, p.omega
    if p.profile == "sine":
        assert np.max(np.abs(c["vx_des"] - a * np.sin(w * t))) <= 1e-15
        assert np.max(np.abs(c["foot_x_des"] - x0 - a / w * (1 - np.cos(w * t)))) <= 1e-15
    else:
        assert np.max(np.abs(c["vx_des"] - a * np.cos(w * t))) <= 1e-15
        assert np.max(np.abs(c["foot_x_des"] - x0 - a / w * np.sin(w * t))) <= 1e-15
    assert np.all(c["foot_y_des"] == y0) and np.all(c["foot_z_des"] == z0)
    assert np.all(c["vy_des"] == 0) and np.all(c["vz_des"] == 0)
    assert np.max(np.abs(np.diff(t) - p.timestep)) <= 1e-12 and t[0] == 0


@pytest.mark.slow
def test_measured_columns_are_fk_and_jacobian_of_the_joint_columns(any_run):
    _, r = any_run
    c = r.columns
    q, dq = joints(c)
    foot = np.c_[c["foot_x"], c["foot_y"], c["foot_z"]]
    assert np.max(np.abs(foot - (HIP + leg.fk(q, GEOMETRY)))) <= 1e-12
    jac = leg.jacobian(q, GEOMETRY)  # (n, 3, 3)
    vel = np.einsum("nij,nj->ni", jac, dq)  # (n, 3)
    assert np.max(np.abs(np.c_[c["vx"], c["vy"], c["vz"]] - vel)) <= 1e-10
    assert np.max(np.abs(c["det_j"] - leg.det_jacobian(q, GEOMETRY))) <= 1e-18
    assert np.max(np.abs(c["det_j"] - np.linalg.det(jac))) <= 1e-15
    # roll, pitch, yaw rebuild the foot orientation T04 (ZYX: R = Rz(yaw) Ry(pitch) Rx(roll)), even at gimbal lock.
    rebuilt = Rotation.from_euler("ZYX", np.c_[c["yaw"], c["pitch"], c["roll"]]).as_matrix()
    assert np.max(np.abs(rebuilt - leg.transforms(q, GEOMETRY)[3][:, :3, :3])) <= 1e-9


def test_kinematic_foot_velocity_follows_the_command():
    p, r = run(mode="kinematic")
    c = r.columns
    t, vx = c["t"], c["vx"]
    # Row i holds dq_i, the command that moved q from t_(i-1) to t_i: its feedforward is the command's mean
    # over that step, A sin(omega (t_i - dt/2)) + O(dt^2), i.e. a half-step lag of at most A omega dt / 2
    # = 2.5e-5 m/s against vx_des(t_i). On top come the feedback K (x_des - x) (measured <= 4.6e-6 m/s)
    # and the change of J over one step (measured <= 9.2e-6 m/s); we allow 1e-5 m/s for both.
    # Row 0 is the state before any command (dq = 0) and is excluded.
    half_step = p.amplitude * p.omega * p.timestep / 2
    assert np.max(np.abs(vx[1:] - p.amplitude * np.sin(p.omega * (t[1:] - p.timestep / 2)))) <= 1e-5
    assert np.max(np.abs(vx[1:] - c["vx_des"][1:])) <= half_step + 1e-5
    assert np.max(np.abs(c["vy"])) <= 1e-15 and np.max(np.abs(c["vz"][1:])) <= 1e-4


def joint_rate_mismatch(p, c) -> float:
    """max |(q_i - q_(i-1)) / dt - dq_i|: in kinematic mode q_i = q_(i-1) + dq_i dt is imposed."""
    q, dq = joints(c)
    return float(np.max(np.abs(np.diff(q, axis=0) / p.timestep - dq[1:])))


def test_kinematic_dq_is_the_rate_of_change_of_q():
    for overrides in ({}, {"profile": "cosine"}):
        p, r = run(mode="kinematic", **overrides)
        assert joint_rate_mismatch(p, r.columns) <= 1e-9, overrides  # rounding: ~|q| eps / dt ~ 1e-12


def test_kinematic_dq_is_the_rate_of_change_of_q_at_a_joint_limit():
    p, r = run(mode="kinematic", **OUTSIDE)
    assert np.min(r.columns["q3"]) == 0  # the knee sits on its lower limit for a while
    assert joint_rate_mismatch(p, r.columns) <= 1e-9


def test_same_params_twice_give_identical_arrays():
    _, first = run(mode="kinematic")
    second = fresh_run(mode="kinematic")
    assert first.columns.keys() == second.columns.keys()
    for name in first.columns:
        assert np.array_equal(first.columns[name], second.columns[name]), name
    assert np.array_equal(first.trajectory.qpos, second.trajectory.qpos)


# --- out of the workspace ---


def test_out_of_workspace_run_is_finite_and_respects_joint_speed(outside_run):
    p, r = outside_run
    c = r.columns
    for name, values in c.items():
        assert np.all(np.isfinite(values)), name
    q, dq = joints(c)
    assert np.max(np.abs(dq)) <= p.max_joint_speed * (1 + 1e-9)
    assert np.max(np.abs(dq)) >= 0.9 * p.max_joint_speed  # the limit was really approached
    if p.mode == "kinematic":  # q is the command itself: ranges and the acceleration limit hold exactly
        assert np.all((q >= LOWER) & (q <= UPPER))
        # The acceleration limit holds wherever no joint sits on a range limit: a hard stop at a limit may
        # need any deceleration (see test_kinematic_dq_is_the_rate_of_change_of_q_at_a_joint_limit).
        on_limit = np.any((q == LOWER) | (q == UPPER), axis=1)
        free = ~(on_limit[1:] | on_limit[:-1])
        assert free.sum() > 0.5 * len(free)
        ddq = np.max(np.abs(np.diff(dq, axis=0)[free]))
        assert ddq <= p.max_joint_acceleration * p.timestep * (1 + 1e-9)


def test_out_of_workspace_singularity_is_the_stretched_knee(outside_run):
    p, r = outside_run
    c, m = r.columns, r.metrics
    q, _ = joints(c)
    t = c["t"]
    # Smallest singular value by SVD, independent of the closed form the scenario uses.
    sv = np.linalg.svd(leg.jacobian(q, GEOMETRY), compute_uv=False)[:, -1]
    assert np.min(np.abs(sv - p.sigma_threshold)) > 1e-9  # no row sits on the threshold within round-off
    assert np.max(np.abs(c["sigma_min"] - sv)) <= 1e-15
    near = sv < p.sigma_threshold
    assert set(np.unique(c["near_singular"])) <= {0.0, 1.0}
    assert np.array_equal(c["near_singular"] == 1, near)
    first = int(np.argmax(near))
    assert m["singular_first_time"].value == t[first] and near.any()
    assert m["singular_duration"].value == pytest.approx(near.sum() * p.timestep, rel=1e-9)
    assert m["singular_duration"].value > 0
    assert "knee" in m["singular_family"].value
    # At that time the knee is nearly stretched: with l2 = l3 = l the planar block has
    # F = |J|_F^2 = l^2 (3 + 2 cos q3) and D = l^2 sin q3, sigma^2 = (F - sqrt(F^2 - 4 D^2)) / 2.
    l = GEOMETRY.l2  # noqa: E741
    assert GEOMETRY.l3 == l

    def planar_sigma(q3):
        f, d = l**2 * (3 + 2 * math.cos(q3)), l**2 * math.sin(q3)
        return math.sqrt((f - math.sqrt(f * f - 4 * d * d)) / 2) - p.sigma_threshold

    q3_star = brentq(planar_sigma, 1e-6, 1.0)
    assert q3_star < 0.25
    assert c["q3"][first] == pytest.approx(q3_star, abs=0.01)
    assert math.hypot(*leg.fk(q[first], GEOMETRY)[:2]) > 0.1  # rho far from 0: not the coxa-axis family
    # ... and the foot target is at the edge of the reach along the line.
    x_edge = GEOMETRY.l1 + math.sqrt((GEOMETRY.l2 + GEOMETRY.l3) ** 2 - p.start_z**2)
    assert c["foot_x_des"][first] - HIP[0] == pytest.approx(x_edge, abs=2e-3)


def test_out_of_workspace_is_predicted(outside_run):
    p, r = outside_run
    m = r.metrics
    assert m["excursion_forward"].value == pytest.approx(2 * p.amplitude / p.omega, rel=1e-15)
    assert m["predicted_to_leave_workspace"].value is True
    assert r.metrics["max_x_error"].value > 0.1  # it really left: the foot lags x_des by > 10 cm


def test_reach_forward_is_the_workspace_boundary_along_the_line():
    p, r = run(mode="kinematic")
    start = (p.start_x, p.start_y, p.start_z)
    closed = GEOMETRY.l1 + math.sqrt((GEOMETRY.l2 + GEOMETRY.l3) ** 2 - p.start_z**2) - p.start_x
    assert closed == pytest.approx(reach_by_bisection(start, +1, ranges=False), abs=1e-9)
    assert closed == pytest.approx(reach_by_bisection(start, +1, ranges=True), abs=1e-9)  # ranges don't limit it
    # The scenario may find the boundary numerically: 1 um is far below anything the prediction decides.
    assert r.metrics["reach_forward"].value == pytest.approx(closed, abs=1e-6)


def test_reach_backward_respects_the_joint_ranges():
    """Going back, the femur reaches +90 deg long before the leg is stretched (HEAD 00e0da7 ignored that)."""
    p, r = run(profile="cosine", amplitude=0.12, duration=4.75)  # the backward travel ends at 3 pi / 2 omega
    start = (p.start_x, p.start_y, p.start_z)
    backward = reach_by_bisection(start, -1, ranges=True)  # ~0.098 m: femur straight down at +90 deg
    assert backward < r.metrics["excursion_backward"].value == 0.12
    assert r.metrics["reach_backward"].value == pytest.approx(backward, abs=1e-6)
    assert r.metrics["predicted_to_leave_workspace"].value is True


@pytest.mark.slow
@pytest.mark.parametrize(
    ("amplitude", "omega", "leaves"),
    [(0.05, 1.0, False), (0.01, 1.0, False), (0.1, 1.0, True), (0.08, 1.0, False), (0.08, math.pi / 6, True)],
)
def test_the_reports_cases_leave_the_workspace_or_not(amplitude, omega, leaves):
    p, r = run(mode="kinematic", amplitude=amplitude, omega=omega)
    m = r.metrics
    reach = GEOMETRY.l1 + math.sqrt((GEOMETRY.l2 + GEOMETRY.l3) ** 2 - p.start_z**2) - p.start_x
    assert (2 * amplitude / omega > reach) is leaves
    assert m["predicted_to_leave_workspace"].value is leaves
    assert (m["singular_first_time"].value is not None) is leaves
    assert (m["max_x_error"].value > 1e-3) is leaves
    if not leaves:
        sv = np.linalg.svd(leg.jacobian(joints(r.columns)[0], GEOMETRY), compute_uv=False)[:, -1]
        assert np.min(sv) > p.sigma_threshold and m["singular_duration"].value == 0


# --- the coxa-axis singularity ---


def test_cosine_profile_crosses_the_coxa_axis():
    p, r = run(profile="cosine")
    c, m = r.columns, r.metrics
    x0, y0, _ = start_world(p)
    t_cross = 3 * math.pi / (2 * p.omega)
    assert x0 - HIP[0] - p.amplitude / p.omega == pytest.approx(0, abs=1e-15)  # x_des(t_cross) = 0
    i = int(np.argmin(np.abs(c["t"] - t_cross)))
    assert abs(c["foot_x"][i] - HIP[0]) < 1e-3
    assert "coxa axis" in m["singular_family"].value
    # sigma_min = |rho| drops below the threshold when x_des = x0 + (A/omega) sin(omega t) does; the foot
    # lags x_des by < 0.5 mm at 30 mm/s there, i.e. by < 0.02 s.
    t_near = (math.pi + math.asin((x0 - HIP[0] - p.sigma_threshold) / (p.amplitude / p.omega))) / p.omega
    assert m["singular_first_time"].value == pytest.approx(t_near, abs=0.02)
    # y is not commanded and nothing pushes the foot sideways, even where q1 is undetermined.
    assert np.max(np.abs(c["foot_y"] - y0)) < 1e-9 and m["max_lateral_deviation"].value < 1e-9
    assert np.max(np.abs(c["q1"])) < 1e-9


# --- the controller on its own ---


def random_well_conditioned(rng) -> np.ndarray:
    u, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    v, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return u @ np.diag(rng.uniform(0.5, 2.0, 3)) @ v.T  # (3, 3), condition number <= 4


def as_tuple(a: np.ndarray):
    return tuple(tuple(float(x) for x in row) for row in a) if a.ndim == 2 else tuple(float(x) for x in a)


def test_damped_solve_is_the_linear_solve_and_the_dls_formula():
    rng = np.random.default_rng(5)
    for _ in range(200):
        jac, u = random_well_conditioned(rng), rng.normal(size=3)
        exact = np.linalg.solve(jac, u)
        assert np.asarray(damped_solve(as_tuple(jac), as_tuple(u), 0.0)) == pytest.approx(exact, rel=1e-12, abs=1e-14)
        lam = rng.uniform(1e-3, 1.0)
        dls = jac.T @ np.linalg.solve(jac @ jac.T + lam**2 * np.eye(3), u)
        assert np.asarray(damped_solve(as_tuple(jac), as_tuple(u), lam)) == pytest.approx(dls, rel=1e-12, abs=1e-14)
        # Damping changes the answer (the check can fail).
        assert np.max(np.abs(dls - exact)) > 1e-9


def call_sigma_min(q1: float, q2: float, q3: float) -> float:
    """resolved_rate.sigma_min at q, its arguments matched by parameter name (jac, rho, sin_q3, cos_q3, l*)."""
    g = GEOMETRY
    _, jac = leg.foot_and_jacobian(q1, q2, q3, g.l1, g.l2, g.l3)
    available = {
        "jac": jac,
        "rho": g.l1 + g.l2 * math.cos(q2) + g.l3 * math.cos(q2 + q3),  # horizontal foot distance from the coxa axis
        "sin_q3": math.sin(q3),
        "cos_q3": math.cos(q3),
        "l1": g.l1,
        "l2": g.l2,
        "l3": g.l3,
    }
    return sigma_min(**{name: available[name] for name in inspect.signature(sigma_min).parameters})


def test_sigma_min_is_the_smallest_singular_value():
    qs = np.random.default_rng(6).uniform(-math.pi, math.pi, size=(1000, 3))
    # Plus both singular families and configurations next to the knee one.
    qs = np.r_[qs, [[0.3, 0.5, 0.0], [0.1, 0.2, math.pi]], qs[:5] * [1, 1, 1e-9]]
    for q1, q2, q3 in qs:
        _, jac = leg.foot_and_jacobian(q1, q2, q3, GEOMETRY.l1, GEOMETRY.l2, GEOMETRY.l3)
        svd = np.linalg.svd(np.array(jac), compute_uv=False)[-1]
        assert call_sigma_min(q1, q2, q3) == pytest.approx(svd, abs=1e-15), (q1, q2, q3)


def home_controller(offset, max_joint_speed: float, max_joint_acceleration: float = math.inf):
    """A controller at the home pose whose reference is held still at home + offset [m]."""
    q0 = leg.ik((0.05, 0.0, -0.08), GEOMETRY)[0]
    target = tuple(leg.fk(q0, GEOMETRY) + np.asarray(offset))
    gains = ResolvedRateGains(max_joint_speed=max_joint_speed, max_joint_acceleration=max_joint_acceleration)
    ctrl = ResolvedRateController(GEOMETRY, gains, lambda t: target, as_tuple(q0), as_tuple(LOWER), as_tuple(UPPER))
    return ctrl, q0, gains


def test_joint_speed_limit_scales_dq_as_a_whole():
    offset = np.array([0.01, 0.01, -0.01])  # [m]: K * offset = 0.5 m/s, far more than 2 rad/s allows
    free, q0, gains = home_controller(offset, max_joint_speed=1e9)
    free.update(as_tuple(q0), 0.0, 1e-3)
    expected = np.linalg.solve(leg.jacobian(q0, GEOMETRY), gains.task_gain * offset)  # sigma_min 0.05: no damping
    assert np.asarray(free.dq) == pytest.approx(expected, rel=1e-9)
    assert np.max(np.abs(expected)) > 2.0
    limited, _, _ = home_controller(offset, max_joint_speed=2.0)
    limited.update(as_tuple(q0), 0.0, 1e-3)
    dq = np.asarray(limited.dq)
    assert np.max(np.abs(dq)) == pytest.approx(2.0, rel=1e-15)
    assert dq == pytest.approx(expected * 2.0 / np.max(np.abs(expected)), rel=1e-12)  # same direction
    assert np.asarray(limited.q_cmd) == pytest.approx(q0 + dq * 1e-3, abs=1e-15)


@pytest.mark.parametrize(("velocity", "joint", "bound"), [(0.2, 2, LOWER), (-0.2, 1, UPPER)])
def test_joint_command_never_leaves_the_ranges(velocity, joint, bound):
    """Forward past the reach stretches the knee onto q3 = 0; backward past it drives the femur to +90 deg."""
    q0 = leg.ik((0.05, 0.0, -0.08), GEOMETRY)[0]
    x0 = leg.fk(q0, GEOMETRY)
    ctrl = ResolvedRateController(
        GEOMETRY,
        ResolvedRateGains(),
        lambda t: (x0[0] + velocity * t, x0[1], x0[2]),
        as_tuple(q0),
        as_tuple(LOWER),
        as_tuple(UPPER),
    )
    dt, hit = 1e-3, False
    for k in range(3000):  # 0.6 m of command: well past the reach either way
        ctrl.update(tuple(ctrl.q_cmd), k * dt, dt)
        q = np.asarray(ctrl.q_cmd)
        assert np.all((q >= LOWER) & (q <= UPPER)), (k, q)
        hit |= q[joint] == bound[joint]
    assert hit  # the range was really reached


# --- the command line ---


@pytest.mark.parametrize(
    ("setting", "fragment"),
    [
        ("mode=fast", "parameter 'mode' must be one of dynamic, kinematic; got 'fast'"),
        ("max_joint_speed=-1", "parameter 'max_joint_speed' must be a number with 0.001 <= max_joint_speed"),
        ("omega=0", "parameter 'omega' must be a number with 0.01 <= omega <= 20 rad/s"),
        ("start_x=5", "parameter 'start_x' must be a number with -3 <= start_x <= 3 m; got '5'"),
        (
            "start_x=-0.1",
            "the start point (-0.1, 0.0, -0.08) m is outside the workspace of the leg l1, l2, l3 = 0.05, 0.1, 0.1 m or",
        ),
    ],
)
def test_bad_input_exit_2_one_line_nothing_written(tmp_path, capsys, setting, fragment):
    if setting == "start_x=-0.1":  # behind the hip: reachable, but only with the femur past +90 deg
        assert reachable(-0.1, 0.0, -0.08, ranges=False) and not reachable(-0.1, 0.0, -0.08, ranges=True)
    code = main(["run", "leg-step", "--set", setting, "--out", str(tmp_path / "run"), "--no-plots"])
    _, err = capsys.readouterr()
    assert code == 2, err
    assert err.startswith("hexabot-sim: error: ") and err.count("\n") == 1 and err.endswith("\n"), err
    assert fragment in err, err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_start_on_the_coxa_axis_is_not_called_outside_the_workspace(tmp_path, capsys):
    assert reachable(0.0, 0.0, -0.08, ranges=True)
    code = main(["run", "leg-step", "--set", "start_x=0", "--set", "duration=0.01", "--out", str(tmp_path / "r")])
    _, err = capsys.readouterr()
    assert code == 0 or ("outside the workspace" not in err and "q1=" not in err), err


@pytest.mark.slow
def test_cli_run_writes_the_columns_and_metrics(tmp_path, capsys):
    out = tmp_path / "run"
    code = main(["run", "leg-step", "--out", str(out), "--no-plots"])
    _, err = capsys.readouterr()
    assert code == 0, err
    assert {f.name for f in out.iterdir()} == {
        "timeseries.csv",
        "run.json",
        "model.xml",
        "trajectory.npz",
        "report.html",
    }
    header = (out / "timeseries.csv").read_text().splitlines()[0].split(",")
    assert set(COLUMNS) <= set(header) and header[0] == "t"
    record = json.loads((out / "run.json").read_text())
    assert set(METRICS) <= set(record["metrics"])
    # The files hold the same run as the API (CSV at %.17g is exact).
    _, r = run(mode="dynamic")
    table = np.loadtxt(out / "timeseries.csv", delimiter=",", skiprows=1)
    for k, name in enumerate(header):
        assert np.array_equal(table[:, k], r.columns[name]), name
    for name in METRICS:
        assert record["metrics"][name] == r.metrics[name].value, name


@pytest.mark.parametrize(("duration", "profile"), [(1.0, "sine"), (3.0, "sine"), (2.0, "cosine"), (4.0, "cosine")])
def test_the_excursion_is_what_the_command_asks_for_within_the_run(duration, profile):
    """A 1 s run at 0.52 rad/s was told it asks for 2A/omega = 0.38 m and leaves the workspace; its command travels
    (A/omega)(1 - cos(omega t)) = 26 mm by its end (found by fuzzing). Independent: the command's integral sampled."""
    p = params.resolve(LegStepParams, {}, {"duration": duration, "profile": profile, "amplitude": 0.1, "omega": 0.5236})
    t = np.linspace(0.0, duration, 200001)
    v = p.amplitude * (np.sin(p.omega * t) if profile == "sine" else np.cos(p.omega * t))
    x = np.concatenate([[0.0], np.cumsum((v[1:] + v[:-1]) / 2 * np.diff(t))])
    forward, backward = step.excursion(p)
    assert forward == pytest.approx(max(x.max(), 0.0), abs=1e-9)
    assert backward == pytest.approx(max(-x.min(), 0.0), abs=1e-9)
