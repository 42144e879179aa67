"""The quadbot: its model is the generator's and the leg's DH maths, its scenarios, and the issue-18 targets.

Targets (issue 18): crawl at 0.05 m/s and trot at 0.1 m/s within 3 % of the command, no fall, on flat ground
and on 1 cm rough ground (seeds 0-4), 8 s walks: quadbot-walk, quadbot-trot, and on rough ground quadbot-rough
and quadbot-trot-rough (sensed touchdown, level body). Measured numbers: docs/quadbot.md.
"""

import mujoco
import numpy as np
import pytest
from helpers import foot_and_jacobian_errors

from hexabot_sim import models, params, registry
from hexabot_sim.errors import UsageError
from hexabot_sim.robots.quadbot import model as quadbot_model
from hexabot_sim.robots.quadbot import walk as quadbot

LAYOUT = quadbot_model.LAYOUT


def test_committed_models_are_the_generator_output():
    assert models.model_path("quadbot").read_text() == quadbot_model.robot_xml()
    assert models.model_path("quadbot_scene").read_text() == quadbot_model.scene_xml()


def test_four_legs_in_the_gaits_order_and_the_model_stands_on_them():
    assert LAYOUT.legs == ("lf", "lr", "rf", "rr") and quadbot.QUADBOT.layout is LAYOUT
    model = mujoco.MjModel.from_xml_path(str(models.model_path("quadbot_scene")))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    assert (model.nq, model.nu) == (7 + 12, 24)
    feet = np.array([data.site(f"{leg}_foot").xpos for leg in LAYOUT.legs])
    np.testing.assert_allclose(feet[:, 2], LAYOUT.foot_radius, atol=1e-9)
    assert model.body_subtreemass[model.body("torso").id] == pytest.approx(LAYOUT.total_mass)


def test_every_foot_and_jacobian_equal_the_legs_dh_maths():
    """Foot sites and mj_jacSite against the layout's FK and Jacobians (legged.py), rotated by the body."""
    worst_p, worst_j = foot_and_jacobian_errors("quadbot_scene", LAYOUT, 50)
    assert worst_p < 1e-12 and worst_j < 1e-12


def test_its_scenarios_and_gaits():
    names = [name for name in registry.SCENARIOS if name.startswith("quadbot-")]
    assert names == ["quadbot-walk", "quadbot-trot", "quadbot-rough", "quadbot-trot-rough"]
    p = params.resolve(quadbot.QuadbotParams, registry.get("quadbot-walk").defaults)
    assert (p.gait, p.vx, p.the_gait().duty) == ("crawl", 0.05, 0.75)
    p = params.resolve(quadbot.QuadbotParams, registry.get("quadbot-trot").defaults)
    assert (p.gait, p.vx, p.the_gait().duty, p.the_gait().offsets) == ("trot", 0.1, 0.5, (0.0, 0.5, 0.5, 0.0))
    with pytest.raises(UsageError, match="tripod"):
        params.resolve(quadbot.QuadbotParams, {}, {"gait": "tripod"})  # a six-legged gait


def _walk(scenario: str, **overrides):
    p = params.resolve(
        registry.get(scenario).params_type, registry.get(scenario).defaults, {"duration": 8.0}, overrides
    )
    return {k: m.value for k, m in quadbot.run(scenario, p).metrics.items()}


CASES = [("crawl", "flat", "quadbot-walk", {}), ("trot", "flat", "quadbot-trot", {})]
CASES += [("crawl", f"rough-{s}", "quadbot-rough", {"seed": s}) for s in range(5)]
CASES += [("trot", f"rough-{s}", "quadbot-trot-rough", {"seed": s}) for s in range(5)]
QUICK = {"flat", "rough-0"}  # one flat and one rough walk per gait run in the quick check


@pytest.mark.parametrize(
    "scenario, overrides, flat",
    [
        pytest.param(sc, ov, ground == "flat", id=f"{gait}-{ground}",
                     marks=() if ground in QUICK else pytest.mark.slow)
        for gait, ground, sc, ov in CASES
    ],
)  # fmt: skip
def test_crawl_and_trot_hold_their_speed_within_3_percent(scenario, overrides, flat):
    m = _walk(scenario, **overrides)
    assert not m["fell"]
    assert abs(m["vx_error"]) <= 0.03, m["vx_error"]
    tilt = 2.0 if flat else 6.0  # [deg] peak to peak
    assert m["roll_ptp"] <= tilt and m["pitch_ptp"] <= tilt, (m["roll_ptp"], m["pitch_ptp"])


@pytest.mark.slow
@pytest.mark.parametrize(
    "command, key",
    [({"vx": 0.0, "vy": 0.1}, "vy_error"), ({"vx": 0.0, "yaw_rate": 0.3}, "yaw_rate_error"),
     ({"vx": -0.1}, "vx_error")],
    ids=["sideways", "turn", "backward"],
)  # fmt: skip
def test_the_trot_walks_any_direction(command, key):
    m = _walk("quadbot-trot", **command)
    assert not m["fell"] and abs(m[key]) <= 0.03, m[key]


@pytest.mark.slow
@pytest.mark.parametrize("command", [{"vx": 0.0, "vy": 0.05}, {"vx": 0.0, "yaw_rate": 0.2}, {"vx": -0.05}],
                         ids=["sideways", "turn", "backward"])  # fmt: skip
def test_the_crawl_walks_any_direction_slower(command):
    """The crawl's leg order (lr, lf, rr, rf) is the forward one: sideways, turning and backward it keeps walking
    without a fall, but turning and backward it is 4-6 % slow and tilts up to 9 deg (docs/quadbot.md)."""
    m = _walk("quadbot-walk", **command)
    assert not m["fell"]
    speed = (
        abs(m["mean_vy"]) if "vy" in command else abs(m["mean_yaw_rate"]) if "yaw_rate" in command else -m["mean_vx"]
    )
    wanted = abs(command.get("vy") or command.get("yaw_rate") or command["vx"])
    assert 0.8 * wanted <= speed <= 1.03 * wanted


def test_the_stance_force_control_is_refused_for_a_gait_with_two_feet_down(capsys, tmp_path):
    """load_sharing=force distributes the weight and moments over the feet down; the trot's two span no plane (it
    walked worse with it: 99 bounces against 42, a slower, rolling walk; at 0.02 m/s a sixth of the speed): refused
    in one line, for the walk's gait and for a schedule's; the crawl (three down) takes it."""
    from helpers import cli

    from hexabot_sim.control.gait import GAITS, gaits_for

    assert [g.least_down() for g in GAITS.values()] == [3, 4, 5]  # tripod, ripple, wave
    assert {g.name: g.least_down() for g in gaits_for(4).values()} == {"crawl": 3, "trot": 2}
    assert gaits_for(4)["trot"].least_down(0.6) == 2 and GAITS["tripod"].least_down(0.9) == 3
    code, _, err = cli(capsys, "run", "quadbot-trot", "--set", "load_sharing=force", "--set", "duration=3")
    assert code == 2 and "the trot gait has 2" in err and len(err.strip().splitlines()) == 1
    schedule = tmp_path / "change.csv"
    schedule.write_text("t,vx,vy,yaw_rate,gait\n0,0.03,0,0,crawl\n4,0.03,0,0,trot\n")
    code, _, err = cli(capsys, "run", "quadbot-walk", "--set", "load_sharing=force", "--set", f"schedule={schedule}",
                       "--set", "duration=6")  # fmt: skip
    assert code == 2 and "the trot gait has 2" in err, err
    scenario = registry.get("quadbot-walk")
    p = params.resolve(scenario.params_type, scenario.defaults, {}, {"load_sharing": "force", "duration": "3"})
    assert p.load_sharing == "force" and p.gait == "crawl"


def test_the_stance_force_control_checks_the_gaits_a_schedule_walks_not_the_one_it_replaces():
    """A schedule whose first row names a gait walks that gait from the start (walking/scene.make_controller): the
    walk's own gait is never walked then. quadbot-trot with a crawl-only schedule walks the same crawl as quadbot-walk
    with it (at its period, 1.5 s), and takes load_sharing=force as quadbot-walk does (it was refused: 'the trot gait
    has 2')."""
    crawl = {"load_sharing": "force", "schedule": [[0, 0.03, 0, 0, "crawl"]], "period": 1.5}
    for name in ("quadbot-walk", "quadbot-trot"):
        scenario = registry.get(name)
        p = params.resolve(scenario.params_type, scenario.defaults, crawl)
        assert p.load_sharing == "force"
    # A row without a gait keeps the walk's: the trot is walked there and still refused.
    scenario = registry.get("quadbot-trot")
    trot = {"load_sharing": "force", "schedule": [[0, 0.03, 0, 0]]}
    with pytest.raises(UsageError, match="the trot gait has 2"):
        params.resolve(scenario.params_type, scenario.defaults, trot)
    with pytest.raises(UsageError, match="the trot gait has 2"):
        params.resolve(
            scenario.params_type, scenario.defaults,
            {"load_sharing": "force", "schedule": [[0, 0.03, 0, 0, "crawl"], [4, 0.03, 0, 0, "trot"]]},
        )  # fmt: skip


def test_stepping_in_place_is_checked_in_the_gait_a_schedule_starts_in():
    """A schedule whose first row names another gait walks that gait from the start: the walk's own gait is not checked
    for stepping in place. quadbot-walk at period 0.3 s with a trot-only schedule is quadbot-trot's walk with it (it
    was refused: 'even stepping in place is infeasible with the crawl gait'); a duty of the walk's own, not the
    schedule gait's, gets the schedule's advice (set duty=0 or gait=...), not 'lower duty' for a gait never walked."""
    trot = {"period": 0.3, "schedule": [[0, 0.1, 0, 0, "trot"]]}
    for name in ("quadbot-walk", "quadbot-trot"):
        scenario = registry.get(name)
        assert params.resolve(scenario.params_type, scenario.defaults, trot).period == 0.3
    scenario = registry.get("quadbot-walk")
    with pytest.raises(UsageError, match=r"with the crawl gait at period 0\.3 s"):  # the crawl is walked: still refused
        params.resolve(scenario.params_type, scenario.defaults, {"period": 0.3, "schedule": [[0, 0.05, 0, 0]]})
    scenario = registry.get("hexabot-walk")
    with pytest.raises(UsageError, match=r"set duty=0 or gait=wave$"):
        params.resolve(scenario.params_type, scenario.defaults, {"duty": 0.9, "schedule": [[0, 0.05, 0, 0, "wave"]]})


def test_the_stance_force_control_with_a_level_body_needs_the_centre_inside_the_feet(capsys, tmp_path):
    """With level_body=on the force control levels the body by the feet's forces alone: the crawl, whose body centre
    reaches the edge of its three feet down (no body shift), rolled 32 deg peak to peak and lost 64 % of its speed,
    with fell false (found by fuzzing; quadbot-rough the same). Refused below 2 mm of margin; the margin is checked
    against the hexabot's tripod stepping in place, its feet at their neutral points: the distance from the centre
    to the nearest edge of each tripod's triangle, by hand."""
    from helpers import cli, walk_params

    from hexabot_sim.control.gait import Command
    from hexabot_sim.walking.support import least_support_margin

    for overrides, margin in (({}, "0.0"), ({"duty": 0.8}, "1.2")):
        args = [f"--set={k}={v}" for k, v in {"load_sharing": "force", "level_body": "on", **overrides}.items()]
        out = tmp_path / "out"
        code, stdout, err = cli(capsys, "run", "quadbot-walk", *args, "--out", str(out))
        assert code == 2 and stdout == "" and err.count("\n") == 1 and not out.exists()
        assert f"the crawl gait of quadbot comes within {margin} mm of their edge" in err, err
    code, _, err = cli(capsys, "run", "quadbot-rough", "--set", "load_sharing=force", "--out", str(tmp_path / "r"))
    assert code == 2 and "needs the body's centre at least 2 mm inside the feet down" in err
    scenario = registry.get("quadbot-walk")
    accepted = {"load_sharing": "force", "level_body": "on", "duty": "0.85"}
    assert params.resolve(scenario.params_type, scenario.defaults, accepted).duty == 0.85
    p = walk_params(vx=0.0)
    feet = p.ROBOT.layout.neutral_feet_body()[:, :2]
    edges = []
    for tripod in ((0, 4, 2), (3, 1, 5)):  # lf, rm, lr and rf, lm, rr
        for i, j in ((0, 1), (1, 2), (2, 0)):
            a, b = feet[tripod[i]], feet[tripod[j]]
            edges.append(abs(a[0] * b[1] - a[1] * b[0]) / np.linalg.norm(b - a))  # the origin's distance to line ab
    assert least_support_margin(p, Command()) == pytest.approx(min(edges), abs=1e-9)
