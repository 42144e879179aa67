"""MJCF generated from DH tables: MuJoCo's sites and Jacobians against SerialChain, the files against the generator."""

import dataclasses
import importlib.util
import math
import re
from pathlib import Path

import mujoco
import numpy as np
import pytest

from hexabot_sim import models
from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics import mjcf, robots
from hexabot_sim.kinematics.chain import Joint, SerialChain

N = 500  # random configurations per robot
N_CONSTRUCTED = 200  # random configurations per chain built in this file (keeps the file under 10 s)
GENERATED = ("rrp", "elbow", "stanford", "scara")
SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "generate_models.py"


def load_generator():
    """scripts/generate_models.py as a module (scripts/ is not a package)."""
    spec = importlib.util.spec_from_file_location("generate_models", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def rot(axis: str, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    m = {"x": [[1, 0, 0], [0, c, -s], [0, s, c]], "y": [[c, 0, s], [0, 1, 0], [-s, 0, c]]}
    m["z"] = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
    t = np.eye(4)
    t[:3, :3] = m[axis]
    return t


def translate(x: float, y: float, z: float) -> np.ndarray:
    t = np.eye(4)
    t[:3, 3] = (x, y, z)
    return t


# A standard chain on a tilted, shifted base with every kind of row: theta offsets on hinges and a slide,
# a slide with an offset and twist, a general tool.
BASED = SerialChain(
    "based",
    (
        Joint("j1", theta=0.3, d=0.2, a=0.1, alpha=0.7),
        Joint("j2", kind="prismatic", theta=-0.4, d=0.15, a=0.05, alpha=-1.1, lower=-0.1, upper=0.3),
        Joint("j3", theta=1.2, d=-0.05, a=0.25, alpha=math.pi / 2, lower=-2.0, upper=2.5),
        Joint("j4", d=0.08, alpha=-math.pi / 2),
    ),
    "standard",
    base=translate(0.3, -0.2, 0.5) @ rot("z", 0.8) @ rot("x", 0.4),
    tool=translate(0.02, 0.01, 0.06) @ rot("y", 0.5),
)
# A modified-DH chain with slides (one whose range excludes 0: home is the midpoint) and a base.
MODIFIED = SerialChain(
    "modified",
    (
        Joint("m1", theta=0.2, d=0.1, lower=-math.pi, upper=math.pi),
        Joint("m2", kind="prismatic", theta=0.5, d=0.05, a=0.12, alpha=-math.pi / 2, lower=0.1, upper=0.4),
        Joint("m3", theta=-0.3, d=0.02, a=0.2, alpha=0.9),
        Joint("m4", kind="prismatic", a=0.03, alpha=math.pi / 2),
        Joint("m5", a=0.1, alpha=-0.6, d=0.04),
    ),
    "modified",
    base=translate(0.0, 0.1, 0.2) @ rot("y", -0.3),
    tool=translate(0.05, 0.0, 0.02) @ rot("z", 0.25) @ rot("x", -0.4),
)
CHAINS = {name: robots.get(name).chain() for name in (*GENERATED, "leg")} | {"based": BASED, "modified": MODIFIED}


@pytest.fixture(scope="module")
def generator():
    return load_generator()


@pytest.fixture(scope="module")
def compiled() -> dict[str, mujoco.MjModel]:
    """Every chain's model: from models/ for the generated robots, from to_mjcf for the others."""
    out = {}
    for name, chain in CHAINS.items():
        if name in GENERATED:
            out[name] = mujoco.MjModel.from_xml_path(str(models.model_path(name)))
        else:
            out[name] = mujoco.MjModel.from_xml_string(mjcf.to_mjcf(chain))
    return out


def random_q(chain: SerialChain, rng: np.random.Generator, size: int) -> np.ndarray:
    """(size, n): hinges anywhere in [-2 pi, 2 pi]; slides over their range and 0.2 beyond (qpos == q off-range too)."""
    cols = []
    for j in chain.joints:
        if j.prismatic:
            lo, hi = (j.lower, j.upper) if j.lower is not None else (-0.5, 0.5)
            cols.append(rng.uniform(lo - 0.2, hi + 0.2, size))
        else:
            cols.append(rng.uniform(-2 * math.pi, 2 * math.pi, size))
    return np.stack(cols, axis=1)


def set_q(model: mujoco.MjModel, data: mujoco.MjData, chain: SerialChain, q: np.ndarray) -> None:
    for joint, value in zip(chain.joints, q, strict=True):
        data.qpos[model.joint(joint.name).qposadr[0]] = value
    mujoco.mj_kinematics(model, data)
    mujoco.mj_comPos(model, data)


def site_pose(data: mujoco.MjData, site: str) -> np.ndarray:
    t = np.eye(4)  # (4, 4)
    t[:3, :3] = data.site(site).xmat.reshape(3, 3)
    t[:3, 3] = data.site(site).xpos
    return t


def site_jacobian(model: mujoco.MjModel, data: mujoco.MjData, chain: SerialChain, site: str) -> np.ndarray:
    """mj_jacSite stacked (linear; rotational), world frame, columns in the chain's joint order, (6, n)."""
    jacp = np.zeros((3, model.nv))  # (3, nv)
    jacr = np.zeros((3, model.nv))  # (3, nv)
    mujoco.mj_jacSite(model, data, jacp, jacr, model.site(site).id)
    cols = [model.joint(j.name).dofadr[0] for j in chain.joints]
    return np.vstack([jacp[:, cols], jacr[:, cols]])


# --- The files ---------------------------------------------------------------------------------------


def test_committed_models_are_the_generators_output(generator):
    files = generator.generate()
    # Every committed model that says it is generated, and only those (the hand-written ones do not say so).
    expected = {p.name for p in models.models_dir().glob("*.xml") if "scripts/generate_models.py" in p.read_text()}
    assert {f"{n}.xml" for n in (*GENERATED, "hexabot")} <= expected
    assert set(files) == expected
    for file_name, text in files.items():
        assert (models.models_dir() / file_name).read_text() == text, f"{file_name} drifted: rerun the generator"
    assert generator.generate() == files  # deterministic


def test_generator_check_mode_finds_no_drift(generator, capsys):
    assert generator.main(["--check"]) == 0
    assert "0 file(s) differ" in capsys.readouterr().out


@pytest.mark.parametrize("name", [*GENERATED, *(f"{n}_scene" for n in GENERATED), "based", "modified"])
def test_model_compiles_and_steps_with_random_controls_without_warnings(name):
    chain = CHAINS.get(name)
    if name in ("based", "modified"):
        model = mujoco.MjModel.from_xml_string(mjcf.to_mjcf(chain))
    else:
        model = mujoco.MjModel.from_xml_path(str(models.model_path(name)))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    rng = np.random.default_rng(1)
    lo, hi = model.actuator_ctrlrange.T  # unlimited controls: a +-1 band
    lo, hi = np.where(model.actuator_ctrllimited, lo, -1.0), np.where(model.actuator_ctrllimited, hi, 1.0)
    for step in range(600):
        if step % 100 == 0:
            data.ctrl[:] = rng.uniform(lo, hi)
        mujoco.mj_step(model, data)
    assert all(w.number == 0 for w in data.warning), [(i, w.number) for i, w in enumerate(data.warning)]
    assert np.isfinite(data.qpos).all() and np.isfinite(data.qvel).all()


def test_files_state_their_report_table_and_default_lengths():
    for name in GENERATED:
        spec = robots.get(name)
        header = models.model_path(name).read_text().split("-->", 1)[0]
        assert spec.summary in header
        for key, length in spec.lengths.items():
            assert f"{key} = {length.default!r} m" in header, (name, key)
        for i, joint in enumerate(spec.chain().joints, start=1):
            assert re.search(rf"^\s+{i}\s+{joint.name}\s+{joint.kind}\s", header, re.MULTILINE), (name, joint.name)
        assert "standard convention: A_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)" in header
        scene = models.model_path(f"{name}_scene").read_text()
        assert f'<include file="{name}.xml"/>' in scene


def test_models_follow_the_conventions(compiled):
    for name, model in compiled.items():
        chain = CHAINS[name]
        assert model.nq == model.nv == model.nu == chain.n, name
        assert np.all(model.geom_contype == 0) and np.all(model.geom_conaffinity == 0), name
        assert np.all(model.geom_group == 2), name
        assert model.site("base").id >= 0 and model.site("tool").id >= 0
        for k, joint in enumerate(chain.joints, start=1):
            assert model.site(f"frame{k}").id >= 0
            jnt = model.joint(joint.name)
            assert jnt.type[0] == (mujoco.mjtJoint.mjJNT_SLIDE if joint.prismatic else mujoco.mjtJoint.mjJNT_HINGE)
            assert bool(jnt.limited[0]) == (joint.lower is not None), (name, joint.name)
            if joint.lower is not None:
                assert list(jnt.range) == [joint.lower, joint.upper], (name, joint.name)
            act = model.actuator(joint.name)  # the actuator takes its joint's name
            assert act.trnid[0] == jnt.id and act.trntype[0] == mujoco.mjtTrn.mjTRN_JOINT
            assert model.body_gravcomp[model.jnt_bodyid[jnt.id]] == 1
        assert all(model.body(b).name for b in range(model.nbody))
        assert all(model.geom(g).name for g in range(model.ngeom))
        home = model.key("home").qpos
        assert np.array_equal(home, mjcf.home_pose(chain)) and np.array_equal(model.key("home").ctrl, home)


# --- Kinematics against SerialChain --------------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("name", [*GENERATED, "leg", "based", "modified"])
def test_sites_and_jacobians_are_the_chains(name, compiled):
    """At N random q (N_CONSTRUCTED for chains built here): sites = chain.frames(q), mj_jacSite = chain's Jacobians."""
    model, chain = compiled[name], CHAINS[name]
    data = mujoco.MjData(model)
    worst = dict(frames=0.0, tool=0.0, lin=0.0, ang=0.0, fk_derivative=0.0, numerical=0.0)
    count = N if name in robots.ROBOTS else N_CONSTRUCTED
    for q in random_q(chain, np.random.default_rng(sum(map(ord, name))), count):
        set_q(model, data, chain, q)
        frames = chain.frames(q)  # T0 (base), T1 .. Tn, tool
        sites = ["base", *(f"frame{k}" for k in range(1, chain.n + 1)), "tool"]
        for site, frame in zip(sites[:-1], frames[:-1], strict=True):
            worst["frames"] = max(worst["frames"], np.max(np.abs(site_pose(data, site) - frame)))
        worst["tool"] = max(worst["tool"], np.max(np.abs(site_pose(data, "tool") - chain.fk(q))))
        jac = site_jacobian(model, data, chain, "tool")
        analytic = chain.jacobian(q)
        worst["lin"] = max(worst["lin"], np.max(np.abs(jac[:3] - analytic[:3])))
        worst["ang"] = max(worst["ang"], np.max(np.abs(jac[3:] - analytic[3:])))
        worst["fk_derivative"] = max(worst["fk_derivative"], np.max(np.abs(jac - chain.jacobian_fk_derivative(q))))
        worst["numerical"] = max(worst["numerical"], np.max(np.abs(jac - chain.jacobian_numerical(q))))
    assert worst["frames"] <= 1e-10 and worst["tool"] <= 1e-10, worst
    assert worst["lin"] <= 1e-10 and worst["ang"] <= 1e-10 and worst["fk_derivative"] <= 1e-10, worst
    assert worst["numerical"] <= 1e-7, worst


def test_qpos_is_q_the_joint_acts_on_its_dh_axis(compiled):
    """Each joint's world axis is the z of the frame it acts in (z_{i-1} standard, z_i modified), through its origin."""
    for name, model in compiled.items():
        chain = CHAINS[name]
        data = mujoco.MjData(model)
        q = random_q(chain, np.random.default_rng(5), 1)[0]
        set_q(model, data, chain, q)
        axes = chain.joint_axes(chain.frames(q))
        for joint, frame in zip(chain.joints, axes, strict=True):
            jnt = model.joint(joint.name).id
            assert data.xaxis[jnt] == pytest.approx(frame[:3, 2], abs=1e-12), (name, joint.name)
            # The anchor (body origin) lies on the axis line through the frame's origin (standard DH: Tz(d) along it).
            offset = np.cross(data.xanchor[jnt] - frame[:3, 3], frame[:3, 2])
            assert offset == pytest.approx(np.zeros(3), abs=1e-12), (name, joint.name)


# --- The hand-written leg against its table ----------------------------------------------------------


def test_hand_written_leg_is_the_model_generated_from_its_table(compiled):
    """models/leg.xml (hip site at (0, 0, 0.3)) and to_mjcf(leg chain): same foot pose and Jacobian rel. to frame 0."""
    chain = CHAINS["leg"]
    generated = compiled["leg"]
    hand = mujoco.MjModel.from_xml_path(str(models.model_path("leg")))
    data_gen, data_hand = mujoco.MjData(generated), mujoco.MjData(hand)
    worst = dict(pos=0.0, rot=0.0, jac=0.0)
    for q in random_q(chain, np.random.default_rng(2), N):
        set_q(generated, data_gen, chain, q)
        set_q(hand, data_hand, chain, q)
        base, hip = site_pose(data_gen, "base"), site_pose(data_hand, "hip")
        tool = np.linalg.solve(base, site_pose(data_gen, "tool"))  # (4, 4) in frame 0
        foot = np.linalg.solve(hip, site_pose(data_hand, "foot"))  # (4, 4) in frame 0
        worst["pos"] = max(worst["pos"], np.max(np.abs(tool[:3, 3] - foot[:3, 3])))
        worst["rot"] = max(worst["rot"], np.max(np.abs(tool[:3, :3] - foot[:3, :3])))
        jac_gen = site_jacobian(generated, data_gen, chain, "tool")
        jac_hand = site_jacobian(hand, data_hand, chain, "foot")
        rot_gen, rot_hand = np.kron(np.eye(2), base[:3, :3]), np.kron(np.eye(2), hip[:3, :3])  # (6, 6)
        worst["jac"] = max(worst["jac"], np.max(np.abs(rot_gen.T @ jac_gen - rot_hand.T @ jac_hand)))
    assert np.array_equal(site_pose(data_hand, "hip")[:3, 3], [0, 0, 0.3])
    assert max(worst.values()) <= 1e-12, worst
    for joint in chain.joints:  # same ranges
        assert np.array_equal(generated.joint(joint.name).range, hand.joint(joint.name).range), joint.name


# --- Inertials and gains against MuJoCo's own computations ------------------------------------------


def inertia_from_geoms(xml: str, density: float) -> mujoco.MjModel:
    """The same model with its <inertial>s removed and every geom a solid cylinder: MuJoCo computes the inertia."""
    xml = re.sub(r"\s*<inertial [^>]*/>", "", xml)
    xml = xml.replace('type="capsule"', 'type="cylinder"')
    xml = xml.replace('autolimits="true"', 'autolimits="true" inertiafromgeom="true"')
    xml = xml.replace('<geom contype="0"', f'<geom density="{density!r}" contype="0"')
    return mujoco.MjModel.from_xml_string(xml)


def full_inertia(model: mujoco.MjModel, body: int) -> np.ndarray:
    """Inertia tensor about the body's centre of mass in the body frame, (3, 3)."""
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, model.body_iquat[body])
    rot = rot.reshape(3, 3)
    return rot @ np.diag(model.body_inertia[body]) @ rot.T


@pytest.mark.parametrize("name", [*GENERATED, "based", "modified"])
def test_inertials_are_the_stated_cylinders(name, compiled):
    """The <inertial> numbers equal MuJoCo's own inertia of the drawn geoms taken as solid cylinders."""
    model = compiled[name]
    xml = models.model_path(name).read_text() if name in GENERATED else mjcf.to_mjcf(CHAINS[name])
    reference = inertia_from_geoms(xml, mjcf.ALUMINIUM_DENSITY)
    for k in range(1, CHAINS[name].n + 1):
        body = model.body(f"link{k}").id
        assert model.body_mass[body] == pytest.approx(reference.body_mass[body], rel=1e-12)
        assert model.body_ipos[body] == pytest.approx(reference.body_ipos[body], abs=1e-12)
        scale = np.max(np.abs(full_inertia(reference, body)))
        assert np.max(np.abs(full_inertia(model, body) - full_inertia(reference, body))) <= 1e-10 * scale


@pytest.mark.parametrize("name", [*GENERATED, "based", "modified"])
def test_servo_gains_follow_from_the_home_mass_matrix(name, compiled):
    model = compiled[name]
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    mass = np.zeros((model.nv, model.nv))  # (nv, nv)
    mujoco.mj_fullM(model, data, mass)
    w_n = 2 * math.pi * mjcf.SERVO_BANDWIDTH  # [rad/s]
    for joint in CHAINS[name].joints:
        act, dof = model.actuator(joint.name), model.joint(joint.name).dofadr[0]
        assert act.gainprm[0] == pytest.approx(mass[dof, dof] * w_n**2, rel=1e-10), joint.name
        assert act.biasprm[1] == -act.gainprm[0] and act.biasprm[2] < 0, joint.name  # kp and kv (dampratio)


def test_gravity_compensation_holds_the_home_pose():
    model = mujoco.MjModel.from_xml_path(str(models.model_path("stanford")))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    for _ in range(500):
        mujoco.mj_step(model, data)
    assert np.max(np.abs(data.qpos - model.key("home").qpos)) < 1e-12


# --- Inputs --------------------------------------------------------------------------------------------


def test_text_is_full_precision_and_readable():
    chain = dataclasses.replace(CHAINS["elbow"], joints=(Joint("t1", d=1 / 3, alpha=math.pi / 2), Joint("t2", a=0.1)))
    xml = mjcf.to_mjcf(chain, comment="Made up: d = 1/3 m.")
    model = mujoco.MjModel.from_xml_string(xml)
    assert model.body("link1").pos[2] == 1 / 3  # repr round-trips
    assert "6.123233995736766e-17" not in xml  # quarter turns are exact: cos(pi/2) is written 0
    assert re.search(r"-0\.0(?![\d])", xml) is None  # no negative zeros
    assert xml.startswith("<!--\n  Made up: d = 1/3 m.\n")
    assert '<compiler angle="radian" autolimits="true"' in xml


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"link_radius": 0.0}, "link_radius"),
        ({"density": -1.0}, "density"),
        ({"comment": "a -- b"}, "--"),
    ],
)
def test_bad_arguments_are_refused_with_a_message(kwargs, message):
    with pytest.raises(UsageError, match=message):
        mjcf.to_mjcf(CHAINS["scara"], **kwargs)


@pytest.mark.parametrize(
    ("joints", "message"),
    [
        (lambda: (Joint("a"), Joint("a")), "unique"),
        (lambda: (Joint("a", lower=0.0),), "both"),
        (lambda: (Joint("a", lower=1.0, upper=0.0),), "exceeds"),
        (lambda: (), "no joints"),
    ],
)
def test_bad_tables_are_refused_with_a_message(joints, message):
    # Half-given or inverted limits are refused by Joint itself, the rest by to_mjcf.
    with pytest.raises(UsageError, match=message):
        mjcf.to_mjcf(SerialChain("bad", joints()))


def test_base_and_tool_rotations_of_every_kind_round_trip():
    """Half turns about each axis (every branch of the matrix-to-quaternion conversion) and random rotations."""
    rng = np.random.default_rng(4)
    rotations = [rot(axis, math.pi) for axis in "xyz"] + [rot("x", 2.5) @ rot("y", -2.8) @ rot("z", 3.0)]
    for _ in range(20):
        quat = rng.normal(size=4)
        mat = np.zeros(9)
        mujoco.mju_quat2Mat(mat, quat / np.linalg.norm(quat))
        t = np.eye(4)
        t[:3, :3] = mat.reshape(3, 3)
        rotations.append(t)
    for t in rotations:
        chain = SerialChain("turned", (Joint("j", a=0.1, alpha=0.4),), base=t @ translate(0.1, 0.2, 0.3), tool=t)
        model = mujoco.MjModel.from_xml_string(mjcf.to_mjcf(chain))
        data = mujoco.MjData(model)
        set_q(model, data, chain, np.array([0.7]))
        assert np.max(np.abs(site_pose(data, "base") - chain.base)) <= 1e-14
        assert np.max(np.abs(site_pose(data, "tool") - chain.fk([0.7]))) <= 1e-14
