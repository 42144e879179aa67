"""The shared walking machinery for any number of legs (issue 18): layout, gaits, MJCF writer, controllers.

The hexabot's own behaviour is pinned by tests/test_hexabot.py (its model file byte for byte, its walks);
here a four-legged layout goes through the same code: it builds, compiles in MuJoCo, and trots.
"""

from __future__ import annotations

import itertools

import mujoco
import numpy as np
import pytest

from hexabot_sim.control import kernels
from hexabot_sim.control.gait import GAITS, Command, Gait, GaitPlanner, gaits_for
from hexabot_sim.control.resolved_rate import ResolvedRateGains
from hexabot_sim.control.walk_settings import GroundSettings, WalkSettings
from hexabot_sim.control.walker import GroundController, WalkingController
from hexabot_sim.kinematics import legged, legged_mjcf
from hexabot_sim.robots.hexabot import model as hx

QUAD = legged.Layout(*legged.mirrored(("f", "r"), ((0.12, 0.06), (-0.12, 0.06)), (45.0, 135.0)))


def quad_model() -> mujoco.MjModel:
    robot = legged_mjcf.robot_xml(QUAD, "quad", "<!-- a four-legged test robot -->", stance_legs=2)
    scene = legged_mjcf.scene_xml("quad", "<!-- on flat ground -->")
    return mujoco.MjModel.from_xml_string(scene, {"quad.xml": robot.encode()})


def test_the_hexabot_layout_is_a_legged_layout_with_its_six_legs():
    layout = hx.DEFAULT_LAYOUT
    assert isinstance(layout, legged.Layout) and layout.legs == hx.LEGS and layout.n_legs == 6
    # Its two rows mirror each other.
    assert legged.mirrored(("f", "m", "r"), layout.hips[:3], layout.yaws_deg[:3]) == (
        layout.legs,
        layout.hips,
        layout.yaws_deg,
    )
    assert QUAD.legs == ("lf", "lr", "rf", "rr") and QUAD.hips[3] == (-0.12, -0.06) and QUAD.yaws_deg[3] == -135.0


def test_a_layout_refuses_too_few_legs_or_mismatched_lists():
    with pytest.raises(ValueError, match="at least 3 legs"):
        legged.Layout(("a", "b"), ((0.1, 0.0), (-0.1, 0.0)), (0.0, 180.0))
    with pytest.raises(ValueError, match="3 legs need 3 hips and 3 yaws"):
        legged.Layout(("a", "b", "c"), ((0.1, 0.0), (-0.1, 0.0)), (0.0, 180.0, 90.0))
    with pytest.raises(ValueError, match="unique"):
        legged.Layout(("a", "a", "c"), ((0.1, 0.0), (-0.1, 0.0), (0.0, 0.1)), (0.0, 180.0, 90.0))


def test_kinematics_of_any_leg_count():
    """IK and FK agree, the Jacobians match finite differences: for three legs in a ring and for four."""
    tri = legged.Layout(("a", "b", "c"), tuple((0.1 * np.cos(a), 0.1 * np.sin(a)) for a in (0, 2.1, 4.2)),
                        (0.0, 120.0, 240.0))  # fmt: skip
    for layout in (tri, QUAD):
        n = layout.n_legs
        feet = layout.neutral_feet_body()
        q = legged.ik_body(layout, feet)
        assert q.shape == (n, 3)
        np.testing.assert_allclose(legged.feet_body(layout, q), feet, atol=1e-12)
        jac = legged.jacobians_body(layout, q)
        assert jac.shape == (n, 3, 3)
        eps = 1e-7
        for j in range(3):
            dq = np.zeros((n, 3))
            dq[:, j] = eps
            fd = (legged.feet_body(layout, q + dq) - legged.feet_body(layout, q - dq)) / (2 * eps)
            np.testing.assert_allclose(jac[:, :, j], fd, atol=1e-7)
    assert QUAD.total_mass == pytest.approx(1.0 + 4 * 0.13)


def test_a_four_legged_model_compiles_standing_on_its_feet():
    model = quad_model()
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    assert (model.nq, model.nu) == (7 + 12, 24)
    assert [model.sensor(i).name for i in range(model.nsensor)][3:] == [f"{leg}_touch" for leg in QUAD.legs]
    feet = np.array([data.site(f"{leg}_foot").xpos for leg in QUAD.legs])
    np.testing.assert_allclose(feet[:, 2], QUAD.foot_radius, atol=1e-9)  # every foot just on the floor
    # The servos are sized for two feet carrying the body (a trot), stiffer than for a tripod's three.
    q0 = legged.ik_body(QUAD, QUAD.neutral_feet_body())[0]
    two, three = legged_mjcf.loaded_joint_inertia(QUAD, q0, 2), legged_mjcf.loaded_joint_inertia(QUAD, q0, 3)
    assert np.all(two > three)
    assert model.actuator("lf_femur").gainprm[0] == pytest.approx(round(legged_mjcf.servo_gains(QUAD, 2)[1][1], 4))


def test_gaits_come_per_leg_count():
    assert list(gaits_for(6)) == ["tripod", "ripple", "wave"] and gaits_for(6) is GAITS
    assert list(gaits_for(4)) == ["crawl", "trot"]
    with pytest.raises(ValueError, match="no gaits for 5 legs"):
        gaits_for(5)
    with pytest.raises(ValueError, match="the trot gait is for 4 legs; the robot has 6"):
        GaitPlanner(gaits_for(4)["trot"], 1.0, 0.03, hx.DEFAULT_LAYOUT.neutral_feet_body(), 0.002)
    t = np.linspace(0.0, 4.0, 4001)[:-1]
    planner = GaitPlanner(gaits_for(4)["trot"], 1.0, 0.03, QUAD.neutral_feet_body(), 0.002)
    stance = planner.in_stance(t)
    assert (stance.sum(axis=1) == 2).all()
    assert (stance[:, 0] == stance[:, 3]).all() and (stance[:, 1] == stance[:, 2]).all()  # lf+rr, lr+rf
    planner = GaitPlanner(gaits_for(4)["crawl"], 1.0, 0.03, QUAD.neutral_feet_body(), 0.002)
    stance = planner.in_stance(t)
    assert (stance.sum(axis=1) == 3).all()  # one leg at a time
    lifts = [QUAD.legs[i] for k in range(1, len(t)) for i in range(4) if stance[k - 1, i] and not stance[k, i]]
    assert lifts[:5] == ["lf", "rr", "rf", "lr", "lf"]  # lr, lf, rr, rf, ... (lr lifts at t = 0)


def _support_margin(feet_xy: np.ndarray) -> float:
    """Signed distance [m] of the body origin inside the convex polygon of the feet (negative: outside)."""
    centre = feet_xy.mean(axis=0)
    p = feet_xy[np.argsort(np.arctan2(feet_xy[:, 1] - centre[1], feet_xy[:, 0] - centre[0]))]
    edges = np.roll(p, -1, axis=0) - p
    normals = np.stack([edges[:, 1], -edges[:, 0]], axis=1) / np.hypot(edges[:, 0], edges[:, 1])[:, None]
    return float(np.min(np.sum(normals * p, axis=1)))


def _straight_plan(gait: Gait, feet: np.ndarray, period: float, speed: float, seconds: int, skip: float):
    """The planned feet (n, legs, 3) and stance flags (n + 1, legs; row 0 the step before) of a straight walk at
    `speed` [m/s], 2 ms steps, planned in 1 s chunks for `seconds`, the first `skip` seconds dropped."""
    planner = GaitPlanner(gait, period, 0.03, feet, 0.002)
    rows, stance = [], []
    for _ in range(seconds):
        rows.append(planner.plan(Command(speed), 500)[1:])
        stance.append(planner.in_stance(planner.time - 0.002 * np.arange(500, -1, -1))[1 if stance else 0 :])
    first = round(skip / 0.002)
    return np.concatenate(rows)[first:], np.concatenate(stance)[first:]


def _crawl_margin(offsets: tuple[float, ...], duty: float) -> float:
    """Smallest support margin [m] over the second and third cycles of a straight crawl at 0.05 m/s."""
    rows, stance = _straight_plan(Gait("crawl", offsets, duty, ""), QUAD.neutral_feet_body(), 2.0, 0.05, 6, 2.0)
    return min(_support_margin(rows[k, stance[k + 1], :2]) for k in range(len(rows)))


def test_the_crawl_keeps_the_body_over_its_three_feet():
    """Of the six orders of one leg at a time, the crawl's (lr, lf, rr, rf) keeps the body origin inside the
    support triangle best: on an edge at worst at duty 3/4, inside at duty 0.85; every other order leaves it."""
    crawl = gaits_for(4)["crawl"]
    best = _crawl_margin(crawl.offsets, crawl.duty)
    assert best > -1e-9
    assert _crawl_margin(crawl.offsets, 0.85) > 0.002
    for order in itertools.permutations((1, 2, 3)):
        offsets = [0.0] * 4
        for k, leg in enumerate((0, *order)):
            offsets[leg] = (1.0 - k / 4) % 1.0
        if np.allclose(np.mod(np.array(offsets) - crawl.offsets, 1.0), np.mod(offsets[0] - crawl.offsets[0], 1.0)):
            continue  # the crawl itself, shifted in phase
        assert _crawl_margin(tuple(offsets), 0.75) < best - 0.004, order


def _hand_over_margin(gait: Gait, speed: float) -> float:
    """Smallest support margin [m] at the hand-overs of a straight hexabot walk (1 s period) at `speed`: where a
    foot lands as another lifts, over the feet down on both sides of that step (the landing foot not yet loaded,
    the lifting one unloaded), over the second and third cycles."""
    rows, stance = _straight_plan(gait, hx.DEFAULT_LAYOUT.neutral_feet_body(), 1.0, speed, 3, 1.0)
    both = stance[1:] & stance[:-1]  # down on both sides of each step
    changes = np.flatnonzero((stance[1:] != stance[:-1]).any(axis=1))
    return min(_support_margin(rows[k, both[k], :2]) for k in changes)


@pytest.mark.parametrize("name, speed", [("ripple", 0.1), ("wave", 0.05)])
def test_the_ripple_and_wave_run_rear_to_front(name, speed):
    """Walking forward, the ripple and the wave swing each side's legs rear to front (forward waves): at every
    hand-over the body's centre stays inside the feet that stay down. The same gait in the other direction (front
    to rear: the backward wave, these gaits until 2026-11-27; its offsets 2 duty - offset) leaves it outside."""
    gait = GAITS[name]
    lift = {leg: (gait.duty - o) % 1.0 for leg, o in zip(hx.DEFAULT_LAYOUT.legs, gait.offsets, strict=True)}
    for side in "lr":  # each side: the rear leg lifts, then the middle, then the front, a swing apart
        rear, middle, front = (lift[side + row] for row in "rmf")
        assert (middle - rear) % 1.0 == pytest.approx((front - middle) % 1.0) == pytest.approx(1 - gait.duty)
    forward = _hand_over_margin(gait, speed)
    backward = _hand_over_margin(Gait(name, tuple((2 * gait.duty - o) % 1.0 for o in gait.offsets), gait.duty, ""),
                                 speed)  # fmt: skip
    assert forward > 0.004, forward
    assert backward < -0.004, backward


@pytest.mark.parametrize("ground", [False, True], ids=["planned", "ground-finding"])
def test_a_four_legged_robot_trots(ground):
    """A 4-leg layout with the trot: the controllers step it, it stands, lifts its feet and walks forward,
    on the same compiled kernels as the hexabot (one compiled version for any leg count)."""
    model = quad_model()
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    dt = model.opt.timestep
    planner = GaitPlanner(gaits_for(4)["trot"], 0.5, 0.03, QUAD.neutral_feet_body(), dt, start_time=0.2)
    settings = WalkSettings(Command(0.1), settle_time=0.2, ramp_time=0.3)
    gains = ResolvedRateGains(50.0, 0.01, 0.01, 10.0, 400.0)
    q0 = model.key("home").qpos[7:].reshape(4, 3)
    if ground:
        controller = GroundController(model, data, QUAD, planner, gains, settings, q0, GroundSettings())
    else:
        controller = WalkingController(model, data, QUAD, planner, gains, settings, q0)
    n = round(1.2 / dt)
    height, touching = np.empty(n), np.empty((n, 4), dtype=bool)
    touch = [model.sensor_adr[model.sensor(f"{leg}_touch").id] for leg in QUAD.legs]
    for k in range(n):
        controller(model, data)
        mujoco.mj_step(model, data)
        height[k], touching[k] = data.qpos[2], data.sensordata[touch] > 0.3
    assert np.isfinite(data.qpos).all() and np.isfinite(data.qvel).all()
    assert height.min() > 0.09 and height.max() < 0.1  # stands at its neutral height (0.098 m) throughout
    assert data.qpos[0] > 0.05  # walked forward (0.075 m commanded)
    assert abs(data.qpos[1]) < 0.01
    steps = touching[round(0.4 / dt) :]
    assert (~steps).any(axis=0).all()  # every foot lifted off
    assert np.median(steps.sum(axis=1)) == 2  # mostly on one diagonal pair
    assert controller.q_cmd.shape == (12,) and controller.trims.shape == (12,)
    for kernel in (kernels.servo, kernels.targets, kernels.ground_step, kernels.feed):
        assert len(kernel.signatures) <= 1, (kernel, kernel.signatures)


def test_the_controller_refuses_a_layout_that_is_not_the_model_s():
    model = quad_model()
    data = mujoco.MjData(model)
    planner = GaitPlanner(GAITS["tripod"], 1.0, 0.03, hx.DEFAULT_LAYOUT.neutral_feet_body(), 0.002)
    with pytest.raises(ValueError, match="the gait planner has 6 legs; the layout has 4"):
        WalkingController(model, data, QUAD, planner, ResolvedRateGains(), WalkSettings(Command()), np.zeros(12))
    planner = GaitPlanner(gaits_for(4)["trot"], 1.0, 0.03, QUAD.neutral_feet_body(), 0.002)
    with pytest.raises(ValueError, match="4 legs need 12 servo trims; got 18"):
        WalkingController(
            model, data, QUAD, planner, ResolvedRateGains(), WalkSettings(Command(), trims=(0.0,) * 18), np.zeros(12)
        )
