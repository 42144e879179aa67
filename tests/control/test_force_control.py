"""The stance force control (`load_sharing=force`, control/force_control.py and force_kernels.py), against
independent truth: the force distribution against numpy's least squares and statics, the leg's kinematics and
Jacobian against MuJoCo's (mj_jacSite), and a standing robot's sensed foot forces against the commanded ones."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from hexabot_sim.control import force_kernels as fk

W = 1.78 * 9.81


def test_the_distribution_carries_the_wrench_with_the_least_weighted_norm():
    """Exact moments (soft = 0): the forces sum to fz with moments (px, py), and of all such forces have the least
    weighted norm sum f^2 / w: numpy's least-squares solution in g = f / sqrt(w) (the pseudo-inverse of A sqrt(W))."""
    rng = np.random.default_rng(5)
    for n in (3, 4, 5, 6):
        x, y = rng.uniform(-0.2, 0.2, n), rng.uniform(-0.2, 0.2, n)
        for w in (np.ones(n), rng.uniform(0.01, 1.0, n)):
            b = np.array([W, rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3)])
            out = np.empty(n)
            assert fk.distribute(x, y, w, b[0], b[1], b[2], 0.0, out)
            a = np.vstack([np.ones(n), x, y])
            np.testing.assert_allclose(a @ out, b, rtol=1e-9, atol=1e-10)  # statics: the wrench is carried
            g = np.linalg.lstsq(a * np.sqrt(w), b, rcond=None)[0]
            np.testing.assert_allclose(out, np.sqrt(w) * g, rtol=1e-9, atol=1e-10)


def test_soft_moments_minimise_the_penalised_norm():
    """soft = r > 0: f minimises sum f^2 / w + |moments - (px, py)|^2 / r with the sum held at fz (a hard
    constraint): the KKT system of that problem, solved by numpy."""
    rng = np.random.default_rng(8)
    n, r = 5, 0.01
    x, y, w = rng.uniform(-0.2, 0.2, n), rng.uniform(-0.2, 0.2, n), rng.uniform(0.01, 1.0, n)
    fz, px, py = W, 0.2, -0.1
    out = np.empty(n)
    fk.distribute(x, y, w, fz, px, py, r, out)
    m = np.vstack([x, y])  # (2, n)
    # minimise f^T (W^-1 + M^T M / r) f - 2 f^T M^T (px, py) / r subject to sum f = fz
    h = np.diag(1.0 / w) + m.T @ m / r
    kkt = np.block([[2 * h, np.ones((n, 1))], [np.ones((1, n)), np.zeros((1, 1))]])
    rhs = np.concatenate([2 * m.T @ np.array([px, py]) / r, [fz]])
    np.testing.assert_allclose(out, np.linalg.solve(kkt, rhs)[:n], rtol=1e-9, atol=1e-10)
    assert abs(out.sum() - fz) < 1e-9


def test_collinear_feet_share_the_force_by_weight():
    out = np.empty(3)
    line = np.array([0.0, 0.1, 0.2])
    assert not fk.distribute(line, line, np.array([1.0, 1.0, 2.0]), 8.0, 0.0, 0.0, 0.0, out)
    np.testing.assert_allclose(out, [2.0, 2.0, 4.0])


def test_foot_kinematics_and_jacobian_against_mujoco():
    """force_kernels.foot: the foot centre in the hip frame and the leg plane's Jacobian (radial and vertical rows
    by the femur and tibia columns) equal MuJoCo's site position and mj_jacSite of `<leg>_foot`, turned into the
    hip site's frame, at random joint angles."""
    from hexabot_sim import models
    from hexabot_sim.robots.hexabot.walk import HEXABOT

    layout = HEXABOT.layout
    model = mujoco.MjModel.from_xml_path(str(models.model_path("hexabot")))
    data = mujoco.MjData(model)
    par = np.zeros(fk.NPAR)
    par[[fk.L1, fk.L2, fk.L3]] = layout.geometry.l1, layout.geometry.l2, layout.geometry.l3
    rng = np.random.default_rng(2)
    jacp = np.zeros((3, model.nv))
    for leg in ("lf", "rm"):
        hip = model.site(f"{leg}_hip").id
        dofs = [model.joint(f"{leg}_{j}").dofadr[0] for j in ("coxa", "femur", "tibia")]
        for _ in range(5):
            q = rng.uniform([-0.8, -0.5, 0.5], [0.8, 1.0, 2.2])
            data.qpos[:] = model.qpos0
            data.qpos[[model.joint(f"{leg}_{j}").qposadr[0] for j in ("coxa", "femur", "tibia")]] = q
            mujoco.mj_forward(model, data)
            rot = data.site_xmat[hip].reshape(3, 3)  # hip -> world
            p = rot.T @ (data.site_xpos[model.site(f"{leg}_foot").id] - data.site_xpos[hip])
            x, y, z, b11, b12, b21, b22 = fk.foot(par, *q)
            np.testing.assert_allclose([x, y, z], p, atol=1e-12)
            mujoco.mj_jacSite(model, data, jacp, None, model.site(f"{leg}_foot").id)
            jac = rot.T @ jacp[:, dofs]  # hip frame, (x, y, z) by (coxa, femur, tibia)
            radial = np.array([np.cos(q[0]), np.sin(q[0]), 0.0])
            np.testing.assert_allclose(radial @ jac[:, 1:], [b11, b12], atol=1e-12)
            np.testing.assert_allclose(jac[2, 1:], [b21, b22], atol=1e-12)
            assert abs(jac[2, 0]) < 1e-12  # the coxa turns the foot about the vertical: no vertical speed


@pytest.mark.slow
def test_standing_feet_carry_the_commanded_forces():
    """A hexabot standing on its six feet (the 0.5 s before the walk) under force control: each foot's touch sensor
    reads the force the distribution commands (within 2 %), the commanded forces sum to the measured weight less
    the legs' own weight on the feet (the height's integral finds it), and the body stays at its height."""
    from hexabot_sim.result import at_home
    from hexabot_sim.robots.hexabot.walk import HexabotParams
    from hexabot_sim.walking.scene import build_xml, make_controller

    p = HexabotParams(load_sharing="force", duration=3.0)
    model, data = at_home(build_xml(p))
    controller = make_controller(p, model, data)
    touch = [model.sensor_adr[model.sensor(f"{leg}_touch").id] for leg in p.ROBOT.layout.legs]
    for _ in range(200):  # 0.4 s
        controller(model, data)
        mujoco.mj_step(model, data)
    sensed = data.sensordata[touch]
    np.testing.assert_allclose(controller.force.forces, sensed, rtol=0.02)
    assert abs(sensed.sum() - float(model.body_subtreemass[1]) * 9.81) < 0.02 * W
    assert abs(data.qpos[2] - (p.stand_height + p.ROBOT.layout.foot_radius)) < 3e-4


def test_force_mode_walks_and_is_a_choice_of_load_sharing():
    import hexabot_sim as hs

    r = hs.run("hexabot-walk", load_sharing="force", feet="pad", swing="quintic", duration=2.6, gait="ripple")
    m = r.metrics
    assert not m["fell"].value
    assert abs(m["vx_error"].value) < 0.02
    assert m["foot_bounces"].value == 0


@pytest.mark.parametrize(
    "gait, seed, roughness, direction",
    [("tripod", 0, 0.0, "vx"), ("ripple", 0, 0.0, "vx"), ("wave", 0, 0.0, "vx"), ("tripod", 0, 0.01, "vx"),
     ("wave", 1, 0.01, "vx"), ("wave", 0, 0.0, "vy")],
)  # fmt: skip
def test_the_hexabot_force_scenario_meets_the_foot_force_targets(gait, seed, roughness, direction):
    """Issue 19's targets (no foot bounce, force ripple <= 3 % of W/6, touchdown impact <= 1.6, every stance foot
    loaded >= 95 % of its stance) at its speeds with `hexabot-force`'s force control, pad, quintic swing, 3 s period
    and terrain map, flat (14 s) and on 1 cm rough ground (20 s; of the 15 rough walks of scripts/force_targets.py,
    20 s as here, the wave's seed 1 has the most force ripple, 2.8 %, and the tripod's seed 0 2.1 %; the tripod is
    the gait whose margin is thinnest: 2 and 3 lift-off bounces on seeds 5 and 7).
    Two defects were found this way: the tripod's feet still on the pad 60 ms after a slow lift-off were taken for
    early touchdowns and pushed on the floor through their swing (940 bounces, worst foot loaded 51 %), and a new
    tripod's plane on rough ground was reached over 50 ms at any period (tripod seed 0 3.13 %). Of the other
    directions (docs/hexabot.md) the wave walked sideways has the least margin (impact 1.52)."""
    import hexabot_sim as hs

    speed = 0.05 if gait == "wave" else 0.1
    duration = 20 if roughness else 14  # the flat walk repeats itself: 3 steady cycles are enough
    twist = {"vx": speed} if direction == "vx" else {"vx": 0.0, "vy": speed}
    m = hs.run("hexabot-force", gait=gait, seed=seed, roughness=roughness, duration=duration, **twist).metrics
    assert not m["fell"].value
    assert m["foot_bounces"].value == 0
    assert m["stance_force_ripple"].value <= 0.03
    assert m["touchdown_impact_ratio"].value <= 1.6
    assert m["stance_loaded_fraction_min"].value >= 0.95


def test_hexabot_force_is_the_force_control_with_the_pad_the_quintic_swing_a_3_s_period_and_the_map():
    """The scenario's settings are what docs/hexabot.md measured the targets with; on rough ground it is hexabot-rough
    with them (the same parameters, so the same walk)."""
    from hexabot_sim import api

    force = api.prepare("hexabot-force", {"roughness": 0.01}).params
    rough = api.prepare("hexabot-rough", {"load_sharing": "force", "feet": "pad", "swing": "quintic", "period": 3.0,
                                          "terrain_map": "on", "duration": 20.0}).params  # fmt: skip
    assert force == rough


@pytest.mark.parametrize("touchdown", ["planned", "sensed"])
def test_force_mode_follows_a_schedules_stand_height(touchdown):
    """The force control kept the stand height it started with: a schedule raising it 0.09 -> 0.12 m walked
    backwards (-0.045 m/s for +0.05) and the body overshot; now it rises along the row's 1 s ramp (found by fuzzing)."""
    import hexabot_sim as hs

    rows = [[0, 0.05, 0, 0, None, 0.03, 0.09], [1.5, 0.05, 0, 0, None, 0.03, 0.12]]
    r = hs.run("hexabot-walk", load_sharing="force", feet="pad", swing="quintic", touchdown=touchdown, schedule=rows,
               duration=3.5)  # fmt: skip
    t, z = r.columns["t"], r.columns["z"]
    ramp = 0.098 + 0.03 * np.clip(t - 1.5, 0.0, 1.0)  # the planned body height (stand height + foot radius)
    assert np.abs(z - ramp)[t > 1.0].max() < (0.004 if touchdown == "planned" else 0.007)
    assert r.metrics["mean_vx"].value == pytest.approx(0.05, rel=0.02)


@pytest.mark.parametrize(
    "scenario, sets",
    [("hexabot-stairs", []), ("hexabot-stairs", ["feet=pad", "swing=quintic", "gait=ripple"]),
     ("hexabot-kerb", ["feet=pad", "swing=quintic"])],
)  # fmt: skip
def test_force_control_on_stairs_or_a_kerb_is_refused(tmp_path, capsys, scenario, sets):
    """On feet at two levels the force control's errors step: on rigid feet hexabot-stairs' tripod fell (the body
    bounced 10 cm, 25 deg of pitch); with the pad the ripple gait rolled up to 30 deg on the steps and 15 deg at the
    kerb (pad alone: 5.6 and 1.8 deg). The walk is refused before it starts, in one line naming the remedy."""
    from helpers import cli

    out = tmp_path / "out"
    args = [a for s in ["load_sharing=force", *sets] for a in ("--set", s)]
    code, _, err = cli(capsys, "run", scenario, *args, "--out", str(out))
    assert code == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert "'load_sharing' = force is not for" in err and "load_sharing=off or admittance" in err and not out.exists()


def test_the_height_and_slope_errors_are_drawn_to_the_stance_plane_over_their_own_times():
    """Six feet down, one standing 3.6 mm lower; it lifts, so the plane through the other five steps (its height and
    slopes): with no foot moving, each error approaches the new plane's as err + (e0 - err)(1 - dt/(tau + dt))^k,
    the height with filter_time (50 ms) and the slopes with slope_filter_time (0.5 s: on uneven ground the plane
    tilts in steps as feet land and lift), against that closed form and numpy's least-squares plane."""
    from test_force_overlap import DT, _geo, _par

    par, geo = _par(0.01), _geo()
    par[fk.FILTER], par[fk.SLOPE_FILTER] = 0.05, 0.5
    state, body = np.zeros((6, fk.NSTATE)), np.zeros(fk.NBODY)
    state[:, fk.SINCE], state[:, fk.S] = 1.0, 1.0
    qpos = np.zeros(25)
    qpos[7:] = np.tile([0.0, 0.5, 1.2], 6)
    qpos[8] = 0.55  # leg 0's femur lower: its foot 3.6 mm below the others'
    extra, row, touch, until = np.zeros(18), np.zeros(18), np.zeros(6), np.full(6, 1e9)

    def plane_of(down):
        feet = np.array([fk.foot(par, *qpos[7 + 3 * i : 10 + 3 * i])[:3] for i in range(6)])
        c, s = geo[:, fk.COS], geo[:, fk.SIN]
        x, y = c * feet[:, 0] - s * feet[:, 1] + geo[:, fk.HIP_X], s * feet[:, 0] + c * feet[:, 1] + geo[:, fk.HIP_Y]
        a = np.stack([np.ones(6), x, y], axis=1)[down]
        return np.linalg.lstsq(a, feet[down, 2], rcond=None)[0]

    all_down = np.ones(6, dtype=np.bool_)
    fk.force_pre(par, geo, state, body, qpos, np.zeros(18), touch, row, all_down, until, extra)
    e0 = body[fk.E : fk.E + 3].copy()
    first = plane_of(all_down)
    np.testing.assert_allclose(e0, [first[0] + par[fk.STAND], first[1], first[2]], atol=1e-12)
    five = all_down.copy()
    five[0] = False
    new = plane_of(five)
    err = np.array([new[0] + par[fk.STAND], new[1], new[2]])
    assert abs(err[0] - e0[0]) > 5e-4 and abs(err[1] - e0[1]) > 2e-3  # the plane steps
    for k in range(1, 301):
        fk.force_pre(par, geo, state, body, qpos, np.zeros(18), touch, row, five, until, extra)
        for j, tau in enumerate((0.05, 0.5, 0.5)):
            expect = err[j] + (e0[j] - err[j]) * (1.0 - DT / (tau + DT)) ** k
            assert abs(body[fk.E + j] - expect) < 1e-12, (k, j)


def test_the_admittance_ramps_follow_the_gait_a_schedule_changes_to():
    """The admittance's share ramps end with the stance: after a tripod -> wave change its stance time stayed the
    tripod's 0.5 s of the wave's 0.833 s (found by fuzzing; the ramps act with least_weight < 1)."""
    from hexabot_sim import params
    from hexabot_sim.result import at_home
    from hexabot_sim.robots.hexabot.walk import HexabotParams
    from hexabot_sim.walking.scene import build_xml, make_controller

    rows = [[0, 0.05, 0, 0, "tripod"], [2, 0.05, 0, 0, "wave"]]
    p = params.resolve(HexabotParams, {}, {"load_sharing": "admittance", "schedule": rows, "duration": 6})
    model, data = at_home(build_xml(p))
    controller = make_controller(p, model, data)
    assert controller.admittance.stance_time == pytest.approx(0.5)
    for _ in range(2500):  # 5 s: the wave from 2 s on
        controller(model, data)
        mujoco.mj_step(model, data)
    assert controller.planner.gait.name == "wave"
    assert controller.admittance.stance_time == pytest.approx(controller.planner.stance_time) == pytest.approx(5 / 6)
