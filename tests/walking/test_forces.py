"""Foot forces as data: the metrics on synthetic traces with known answers, and the recorded forces against
MuJoCo's own mj_contactForce and against the robot's weight."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from hexabot_sim import params
from hexabot_sim.walking import forces

DT = 0.001  # [s] the synthetic traces' sample time


def _trace(pieces: list[tuple[float, float]]) -> np.ndarray:
    """A force trace of (duration [s], force [N]) pieces sampled every DT."""
    return np.concatenate([np.full(round(d / DT), f) for d, f in pieces])


def test_bounces_count_short_unloaded_gaps_between_loads():
    # Loaded, a 30 ms gap (a bounce), loaded, a 59 ms gap (a bounce), loaded, a 61 ms gap (a swing), loaded.
    f = _trace([(0.2, 5), (0.03, 0), (0.2, 5), (0.059, 0), (0.2, 5), (0.061, 0), (0.2, 5)])
    assert forces.bounces(f > 1, DT) == 2
    # Gaps at the trace's ends are not bounces (no landing seen, or no lift-off seen).
    assert forces.bounces(_trace([(0.02, 0), (0.2, 5), (0.02, 0)]) > 1, DT) == 0
    # The bounces are bridged: one stance per swing-separated run, only whole ones.
    assert forces.stances(f > 1, DT) == []  # both stances touch an end of the trace
    g = _trace([(0.1, 0), (0.2, 5), (0.03, 0), (0.2, 5), (0.1, 0)])
    assert forces.stances(g > 1, DT) == [(100, 530)]


def test_touchdown_impact_ratio_is_the_first_50_ms_peak_over_the_stance_mean():
    # A stance of 500 ms at 4 N with a 20 ms spike to 10 N starting 10 ms after touchdown.
    f = _trace([(0.1, 0), (0.01, 4), (0.02, 10), (0.47, 4), (0.1, 0)])
    mean = (0.48 * 4 + 0.02 * 10) / 0.5
    assert forces.impact_ratios(f, f > 1, DT) == pytest.approx([10 / mean])
    # A spike after the first 50 ms is not an impact: the peak is then the plateau.
    g = _trace([(0.1, 0), (0.1, 4), (0.02, 10), (0.38, 4), (0.1, 0)])
    assert forces.impact_ratios(g, g > 1, DT) == pytest.approx([4 / ((0.48 * 4 + 0.02 * 10) / 0.5)])


def test_ripple_is_the_rms_about_the_25_ms_moving_mean():
    t = np.arange(0, 1.0, DT)
    # A straight ramp has no ripple (a centred mean of a line is the line).
    ramp = 2.0 + 3.0 * t
    assert forces.ripple(ramp, np.ones_like(t, bool), DT) == pytest.approx(0.0, abs=1e-9)
    # 200 Hz: the 25-sample window holds exactly 5 periods, so the mean is the offset and the ripple A / sqrt(2).
    a = 0.7
    wave = 3.0 + a * np.sin(2 * math.pi * 200 * t + 0.3)
    assert forces.ripple(wave, np.ones_like(t, bool), DT) == pytest.approx(a / math.sqrt(2), rel=0.01)
    # Only loaded rows inside a stance count: a step at touchdown is not ripple.
    step = _trace([(0.2, 0), (0.5, 5), (0.2, 0)])
    assert forces.ripple(step, step > 1, DT) == pytest.approx(0.0, abs=1e-12)


def test_load_shares_relative_to_an_equal_share_while_every_planned_foot_is_down():
    planned = np.array([[1, 1, 1, 0]] * 4, bool)
    force = np.array([[1.0, 2.0, 3.0, 0.0]] * 3 + [[0.0, 4.0, 8.0, 0.0]])  # last row: foot 0 has lifted
    shares = forces.load_shares(force, force > 0.5, planned)
    assert shares[:3] == pytest.approx([0.5, 1.0, 1.5])  # the last row is left out
    assert math.isnan(shares[3])  # never in planned stance


def test_a_foot_the_plan_never_has_down_has_no_loaded_fraction():
    """A short walk at a long period can measure rows in which the plan has a foot only in swing: its loaded fraction
    read 0 (stance_loaded_fraction_min 0 with every stance foot loaded; found by fuzzing, period 10 s)."""
    force = np.stack([_trace([(0.5, 4)]), _trace([(0.5, 0)])], axis=1)
    planned = np.stack([np.ones(len(force), bool), np.zeros(len(force), bool)], axis=1)
    m = forces.force_metrics(force, force > 1, planned, DT, weight=8.0, legs=("a", "b"))
    assert m["stance_loaded_fraction_a"].value == 1.0 and m["stance_loaded_fraction_b"].value is None
    assert m["stance_loaded_fraction_min"].value == 1.0 and m["stance_loaded_fraction"].value == 1.0
    none = forces.force_metrics(force, force > 1, np.zeros_like(planned), DT, weight=8.0, legs=("a", "b"))
    assert none["stance_loaded_fraction"].value is None and none["stance_loaded_fraction_min"].value is None


def test_force_metrics_per_walk_and_per_foot():
    legs = ("a", "b")
    f0 = _trace([(0.1, 0), (0.3, 4), (0.03, 0), (0.3, 4), (0.1, 0)])
    f1 = _trace([(0.83, 4)])
    force = np.stack([f0, f1], axis=1)
    loaded = force > 1
    planned = np.ones_like(loaded)
    m = forces.force_metrics(force, loaded, planned, DT, weight=8.0, legs=legs)
    assert m["foot_bounces"].value == 1 and m["foot_bounces_a"].value == 1 and m["foot_bounces_b"].value == 0
    assert m["stance_loaded_fraction_a"].value == pytest.approx(0.6 / 0.83)
    assert m["stance_loaded_fraction_b"].value == 1.0
    assert m["stance_loaded_fraction"].value == pytest.approx((0.6 + 0.83) / 1.66)
    assert m["stance_loaded_fraction_min"].value == pytest.approx(0.6 / 0.83)
    assert m["stance_force_ripple_b"].value == pytest.approx(0.0, abs=1e-12)  # a plateau
    assert m["stance_force_ripple_a"].value > 0.05  # a bounce inside a stance is ripple
    pooled = math.sqrt(m["stance_force_ripple_a"].value ** 2 * 600 / (600 + 830))
    assert m["stance_force_ripple"].value == pytest.approx(pooled)  # the RMS over every loaded row
    assert m["touchdown_impact_ratio"].value == pytest.approx(630 / 600)  # the stance mean counts its bounce
    assert m["load_share_min"].value == pytest.approx(1.0)  # both down: 4 N each


def _recompute(model: mujoco.MjModel, qpos, qvel, ctrl, legs):
    """Per row: each foot geom's normal force and tangential magnitude, summed over its contacts (mj_contactForce)."""
    data = mujoco.MjData(model)
    wrench = np.zeros(6)
    normal, tangential = np.zeros((len(qpos), len(legs))), np.zeros((len(qpos), len(legs)))
    for k in range(len(qpos)):
        data.qpos[:], data.qvel[:], data.ctrl[:] = qpos[k], qvel[k], ctrl[k]
        mujoco.mj_forward(model, data)
        for c in range(data.ncon):
            contact = data.contact[c]
            for geom in (contact.geom1, contact.geom2):
                name = model.geom(geom).name
                if name.endswith("_foot"):
                    mujoco.mj_contactForce(model, data, c, wrench)
                    normal[k, legs.index(name[: -len("_foot")])] += wrench[0]
                    tangential[k, legs.index(name[: -len("_foot")])] += math.hypot(wrench[1], wrench[2])
    return normal, tangential


@pytest.mark.slow
def test_csv_forces_are_mj_contact_force_of_the_foot_geoms(tmp_path, capsys):
    from helpers import cli

    out = tmp_path / "wave"
    code, _, err = cli(capsys, "run", "hexabot-rough", "--set", "gait=wave", "--set", "vx=0.05",
                       "--set", "duration=1.7", "--no-plots", "--out", str(out))  # fmt: skip
    assert code == 0, err
    header = (out / "timeseries.csv").read_text().splitlines()[0].split(",")
    legs = ["lf", "lm", "lr", "rf", "rm", "rr"]
    table = np.loadtxt(out / "timeseries.csv", delimiter=",", skiprows=1)
    model = mujoco.MjModel.from_xml_path(str(out / "model.xml"))
    traj = np.load(out / "trajectory.npz")
    rows = np.arange(0, len(traj["t"]) - 1, 7)  # every 7th row: every phase of the gait, quickly
    ctrl = traj["ctrl"][np.minimum(rows + 1, len(traj["t"]) - 1)]  # the command in force over the step after
    normal, tangential = _recompute(model, traj["qpos"][rows], traj["qvel"][rows], ctrl, legs)
    for i, leg in enumerate(legs):
        np.testing.assert_allclose(table[rows, header.index(f"force_{leg}")], normal[:, i], rtol=1e-6, atol=1e-6)
        np.testing.assert_allclose(table[rows, header.index(f"force_t_{leg}")], tangential[:, i], rtol=1e-6,
                                   atol=1e-6)  # fmt: skip
    assert normal.max() > 1.0 and tangential.max() > 0.05  # the feet carry the robot, and friction acts
    import json

    units = json.loads((out / "run.json").read_text())["units"]["columns"]
    assert units["force_lf"] == "N" and units["force_t_rr"] == "N"


@pytest.mark.parametrize("robot", ["hexabot", "quadbot"])
def test_standing_feet_carry_the_weight(robot):
    """Standing still, the feet's normal forces add up to m g (the robot's total mass from the model)."""
    module = __import__(f"hexabot_sim.robots.{robot}.walk", fromlist=["run"])
    cls = module.HexabotParams if robot == "hexabot" else module.QuadbotParams
    p = params.resolve(cls, {}, {"vx": 0.0, "duration": 2.3})
    result = module.run(f"{robot}-walk", p)
    legs = p.ROBOT.layout.legs
    total = sum(result.columns[f"force_{leg}"] for leg in legs)
    weight = result.model.body_subtreemass[result.model.body("torso").id] * -result.model.opt.gravity[2]
    late = result.columns["t"] > 1.3  # stepping in place, always statically supported
    assert np.mean(total[late]) == pytest.approx(weight, rel=0.01)
    m = result.metrics
    per_foot = ("foot_bounces", "load_share", "stance_loaded_fraction")
    assert {f"{name}_{leg}" for name in per_foot for leg in legs} <= set(m)


@pytest.mark.parametrize("scene", ["hexabot_scene", "quadbot_scene"])
def test_sensed_foot_forces_are_the_feet_normal_forces(scene):
    """The touch sensors a controller (or a Gymnasium env) reads give each foot's normal contact force: MuJoCo's
    mj_contactForce over the foot geom's contacts, on the robot standing on its home keyframe."""
    from hexabot_sim import models
    from hexabot_sim.control.compliance import sensed_foot_forces

    model = mujoco.MjModel.from_xml_path(str(models.model_path(scene)))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    for _ in range(300):  # 0.6 s: settled on its feet
        mujoco.mj_step(model, data)
    names = [model.sensor(i).name for i in range(model.nsensor)]
    legs = [name[: -len("_touch")] for name in names if name.endswith("_touch")]
    sensed = sensed_foot_forces(model, data, tuple(legs))
    normal, _ = _recompute(model, data.qpos[None].copy(), data.qvel[None].copy(), data.ctrl[None].copy(), legs)
    np.testing.assert_allclose(sensed, normal[0], rtol=1e-3, atol=1e-3)
    np.testing.assert_array_equal(sensed_foot_forces(model, data), sensed)  # every foot, in the model's order
    weight = model.body_subtreemass[model.body("torso").id] * -model.opt.gravity[2]
    assert sensed.sum() == pytest.approx(weight, rel=0.01)


@pytest.mark.slow
def test_the_foot_pad_and_quintic_swing_walk_without_bounces():
    """feet=pad with swing=quintic (issue 19): the ripple and wave gaits at the issue's speeds walk without a bounce,
    every stance foot loaded through its planned stance, the ripple's feet sliding less per stance than the rigid
    feet and the wave's at most 10 % more (measured, 8 s: 1.35 / 1.89 mm and 2.17 / 2.19 mm), the speed within
    0.3 % of the rigid feet's (the wave -0.77 against -0.56 %, the ripple -0.18 against -0.34 %); the rigid feet
    bounce in the same walks. The pad is in the model as legged_mjcf gives it."""
    from hexabot_sim.kinematics import legged_mjcf
    from hexabot_sim.robots.hexabot import walk as hexabot

    def run(**values):
        p = params.resolve(hexabot.HexabotParams, {}, {"duration": 6.0, **values})
        return hexabot.run("hexabot-walk", p)

    for gait, vx, slip in (("ripple", 0.1, 1.0), ("wave", 0.05, 1.1)):
        padded = run(gait=gait, vx=vx, feet="pad", swing="quintic")
        rigid = run(gait=gait, vx=vx)
        m, r = padded.metrics, rigid.metrics
        assert m["foot_bounces"].value == 0 < r["foot_bounces"].value, gait
        assert m["stance_loaded_fraction_min"].value > 0.99, gait
        assert m["slip_per_stance"].value <= slip * r["slip_per_stance"].value, gait
        assert abs(m["vx_error"].value) <= abs(r["vx_error"].value) + 0.003, gait
    foot = padded.model.geom("lf_foot")
    np.testing.assert_allclose(foot.solref, legged_mjcf.FOOT_PAD_SOLREF)
    np.testing.assert_allclose(foot.solimp[:3], legged_mjcf.FOOT_PAD_SOLIMP)
    assert foot.margin[0] == pytest.approx(legged_mjcf.FOOT_PAD_MARGIN)
    assert rigid.model.geom("lf_foot").margin[0] == 0.0
