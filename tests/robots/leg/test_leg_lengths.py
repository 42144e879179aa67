"""leg-step with other link lengths (l1, l2, l3): the generated MJCF against analytic FK/J, a run, refusals, sweeps."""

from pathlib import Path

import mujoco
import numpy as np
import pytest
from helpers import cli

from hexabot_sim import params, registry, sweep
from hexabot_sim.kinematics import leg, robot_file
from hexabot_sim.robots.leg.model import build_xml

LENGTHS = {"l1": 0.04, "l2": 0.08, "l3": 0.12}
GEOM = leg.LegGeometry(0.04, 0.08, 0.12)


def leg_params(name="leg-step", **overrides):
    scenario = registry.get(name)
    return params.resolve(scenario.params_type, scenario.defaults, overrides)


def test_generated_model_foot_site_and_mj_jacsite_are_the_analytic_fk_and_jacobian():
    model = mujoco.MjModel.from_xml_string(build_xml(leg_params(**LENGTHS)))
    data = mujoco.MjData(model)
    rng = np.random.default_rng(20)
    site = model.site("foot").id
    worst_p = worst_j = 0.0
    for _ in range(300):
        q = rng.uniform(-np.pi, np.pi, 3)
        data.qpos[:3] = q
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        hip_pos, hip_rot = data.site("hip").xpos, data.site("hip").xmat.reshape(3, 3)
        jacp = np.zeros((3, model.nv))
        mujoco.mj_jacSite(model, data, jacp, None, site)
        worst_p = max(worst_p, np.max(np.abs(hip_rot.T @ (data.site_xpos[site] - hip_pos) - leg.fk(q, GEOM))))
        worst_j = max(worst_j, np.max(np.abs(hip_rot.T @ jacp[:, :3] - leg.jacobian(q, GEOM))))
    assert worst_p <= 1e-12 and worst_j <= 1e-12
    # The links' inertias follow their lengths (uniform rods): the tibia's I_perp = m L^2 / 12.
    tibia = model.body("tibia")
    assert tibia.inertia[1] == pytest.approx(tibia.mass[0] * 0.12**2 / 12, rel=1e-12)
    assert tibia.ipos[0] == pytest.approx(0.06, abs=1e-15)


def test_default_lengths_leave_the_committed_model_untouched():
    p = leg_params()
    assert (p.robot, p.l1, p.l2, p.l3) == ("leg", 0.0, 0.0, 0.0) and p.geometry == leg.DEFAULT_GEOMETRY
    assert 'pos="0.05 0 0"' in build_xml(p)  # the committed text, not rewritten numbers


def test_a_run_with_other_lengths_follows_their_kinematics_and_tracks():
    scenario = registry.get("leg-step")
    p = leg_params(**LENGTHS, start_x=0.04, start_z=-0.1, duration=1.0)
    r = scenario.runner("leg-step", p)
    c = r.columns
    q = np.stack([c["q1"], c["q2"], c["q3"]], axis=1)
    foot = np.stack([c["foot_x"], c["foot_y"], c["foot_z"]], axis=1)
    hip = r.extras["hip"]
    assert np.max(np.abs(foot - (hip + leg.fk(q, GEOM)))) <= 1e-12  # MuJoCo's foot = FK of the given lengths
    assert np.max(np.abs(c["det_j"] - leg.det_jacobian(q, GEOM))) <= 1e-18
    m = {k: v.value for k, v in r.metrics.items()}
    assert m["max_tracking_error"] < 1e-5  # measured 2.1e-6 m (dynamic mode)
    assert m["max_lateral_deviation"] < 1e-4 and m["singular_first_time"] is None
    # The reach metric is the closed form of these lengths: l1 + sqrt((l2 + l3)^2 - z0^2) - x0.
    closed = GEOM.l1 + np.sqrt((GEOM.l2 + GEOM.l3) ** 2 - 0.1**2) - 0.04
    assert m["reach_forward"] == pytest.approx(closed, abs=2e-7)


@pytest.mark.parametrize(
    ("sets", "fragment"),
    [
        (["l1=0.04", "l2=0.08", "l3=0.12", "start_x=0.25"], "outside the workspace of the leg l1, l2, l3 = 0.04, 0.08"),
        (["l2=0.03", "l3=0.03"], "the start point (0.05, 0.0, -0.08) m is outside the workspace of the leg"),
        (["l2=80"], "parameter 'l2' must be a number with 0 <= l2 <= 1 m; got '80'"),
        (["l2=0.005"], "parameter 'l2' must be 0 (the robot's) or 0.01 to 1 m; got 0.005"),
        (["robot=elbow"], "of the leg's form; got 'elbow' (no such name or file)"),
        (["robot=nowhere.toml"], "got 'nowhere.toml' (no such name or file)"),
    ],
)
def test_refusals_one_line_exit_2_nothing_written(tmp_path, capsys, sets, fragment):
    argv = ["run", "leg-step", "--out", str(tmp_path / "run"), "--no-plots"]
    for s in sets:
        argv += ["--set", s]
    code, _, err = cli(capsys, *argv)
    assert code == 2 and err.count("\n") == 1 and fragment in err, err
    assert list(tmp_path.iterdir()) == []


def test_a_sweep_over_l2_plans_one_leg_per_cell():
    plan = sweep.plan("leg-step", ["l2=0.08,0.1,0.12"], {}, {"duration": "0.5"})
    assert [cell.geometry.l2 for cell in plan.cells] == [0.08, 0.1, 0.12]
    models = [mujoco.MjModel.from_xml_string(build_xml(cell)) for cell in plan.cells]
    assert [m.body("tibia").pos[0] for m in models] == [0.08, 0.1, 0.12]
    # leg-sweep carries the lengths into every grid cell
    grid = leg_params("leg-sweep", l3=0.12, amplitudes=(0.02,), omegas=(1.0,))
    assert grid.cell(0.02, 1.0).geometry == leg.LegGeometry(0.05, 0.1, 0.12)


def leg_file(tmp_path, replace):
    """The package's leg.toml with text replaced, written to tmp_path."""
    text = (Path(robot_file.ARMS_DIR) / "leg.toml").read_text()
    for old, new in replace.items():
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "my_leg.toml"
    path.write_text(text)
    return str(path)


FILE_LENGTHS = {
    "l1 = { value = 0.05": "l1 = { value = 0.04",
    "l2 = { value = 0.10": "l2 = { value = 0.08",
    "l3 = { value = 0.10": "l3 = { value = 0.12",
}


def test_a_robot_file_of_the_legs_form_gives_its_lengths_and_set_overrides_them(tmp_path):
    path = leg_file(tmp_path, FILE_LENGTHS)
    assert leg_params(robot=path, start_x=0.04, start_z=-0.1).geometry == GEOM
    assert leg_params(robot=path, l3=0.1).geometry == leg.LegGeometry(0.04, 0.08, 0.1)
    # The same leg by file or by lengths: the same MJCF.
    by_file = build_xml(leg_params(robot=path, start_x=0.04, start_z=-0.1))
    assert by_file == build_xml(leg_params(**LENGTHS, start_x=0.04, start_z=-0.1))


@pytest.mark.parametrize(
    "replace",
    [
        {"alpha = -90.0": "alpha = 90.0"},  # another twist
        {"upper = 160.0": "upper = 150.0"},  # another joint range than the model's
        {'type = "fixed"': 'type = "revolute"'},  # a fourth joint
    ],
)
def test_a_robot_file_not_of_the_legs_form_is_refused_in_one_line(tmp_path, capsys, replace):
    path = leg_file(tmp_path, replace)
    code, _, err = cli(capsys, "run", "leg-step", "--set", f"robot={path}", "--out", str(tmp_path / "run"))
    assert code == 2 and err.count("\n") == 1 and f"robot file {path} is not of the leg's form" in err, err
    assert not (tmp_path / "run").exists()


def test_links_shorter_than_their_radius_are_still_physical_bodies():
    """A 1 cm coxa (allowed) made MuJoCo refuse the inertia (A + B < C: the rod formula across so short a link is
    below half its axial term), an internal error found by fuzzing; the perpendicular term is now at least that."""
    model = mujoco.MjModel.from_xml_string(build_xml(leg_params(l1=0.01)))
    inertia = model.body_inertia[model.body("coxa").id]
    assert inertia[1] + inertia[2] >= inertia[0] and inertia[0] + inertia[1] >= inertia[2]
    from hexabot_sim.kinematics import legged_mjcf

    mass, axial = 0.05, 0.05 * 0.01**2 / 2
    assert legged_mjcf.rod_inertia(mass, 0.1, axial) == (axial, mass * 0.1**2 / 12, mass * 0.1**2 / 12)  # a rod
    assert legged_mjcf.rod_inertia(mass, 0.001, axial) == (axial, axial / 2, axial / 2)
