"""The leg's MuJoCo scene: models/leg_scene.xml with the run's options and, when they differ, the run's link lengths."""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from hexabot_sim import models
from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics import leg as leg_kin
from hexabot_sim.kinematics import legged_mjcf, robots
from hexabot_sim.params import NameOrFile

if TYPE_CHECKING:
    import xml.etree.ElementTree as ET

    from hexabot_sim.kinematics.robot_file import RobotSpec
    from hexabot_sim.robots.leg.parameters import LegParams

JOINTS = ("coxa", "femur", "tibia")
MIN_LENGTH, MAX_LENGTH = 0.01, 1.0  # [m] each of l1, l2, l3


def build_xml(p: LegParams) -> str:
    """The leg scene with the run's options and link lengths written in."""
    root = models.load_tree("leg_scene")
    physics_dt = p.timestep / p.substeps
    models.find(root, "option").attrib.update(timestep=models.fmt(physics_dt), integrator=p.integrator)
    for name in JOINTS:
        models.find(root, "body", name).set("gravcomp", "1" if p.gravity_compensation == "on" else "0")
    geom = p.geometry
    if geom != leg_kin.DEFAULT_GEOMETRY:  # the committed model is written for the default lengths: left untouched
        set_lengths(root, geom)
    return models.to_xml(root)


def set_lengths(root: ET.Element, geom: leg_kin.LegGeometry) -> None:
    """Rewrites the leg's link lengths in the tree (models/leg.xml's layout: body frames = modified-DH frames).

    Each link keeps its mass as a uniform rod along its x axis (legged_mjcf.rod_inertia: I_perp = m L^2 / 12, I_axial
    unchanged); the femur and tibia bodies move to (L1, 0, 0) and (L2, 0, 0), the foot to (L3, 0, 0). The servo
    gains and the home keyframe stay those of the default leg.
    """
    lengths = {"coxa": geom.l1, "femur": geom.l2, "tibia": geom.l3}
    for link, length in lengths.items():
        body = models.find(root, "body", link)
        inertial = body.find("inertial")
        mass = float(inertial.get("mass"))
        axial = float(inertial.get("diaginertia").split()[0])
        inertia = legged_mjcf.rod_inertia(mass, length, axial)
        inertial.attrib.update(pos=models.fmt((length / 2, 0.0, 0.0)), diaginertia=models.fmt(inertia))
        models.find(root, "geom", link).set("fromto", models.fmt((0.0, 0.0, 0.0, length, 0.0, 0.0)))
    models.find(root, "body", "femur").set("pos", models.fmt((geom.l1, 0.0, 0.0)))
    models.find(root, "body", "tibia").set("pos", models.fmt((geom.l2, 0.0, 0.0)))
    models.find(root, "geom", "foot").set("pos", models.fmt((geom.l3, 0.0, 0.0)))
    models.find(root, "site", "foot").set("pos", models.fmt((geom.l3, 0.0, 0.0)))


def leg_geometry(spec: RobotSpec) -> leg_kin.LegGeometry:
    """The link lengths of a robot of the leg's form (report 000's Table 1, modified DH), else one-line UsageError.

    The form: 3 revolute joints, modified convention, no base transform; rows (alpha, a, theta, d) = (0, 0, 0, 0),
    (-90 deg, L1, 0, 0), (0, L2, 0, 0) with the leg's joint ranges; the tool (the foot) = Tx(L3). Angles and
    offsets within 1e-9, lengths 0.01 to 1 m.
    """
    chain = spec.chain()
    where = f"robot file {spec.source}" if spec.source else f"robot {spec.name}"
    allowed = (
        "3 revolute joints in modified DH, rows (alpha, a, theta, d) = (0, 0, 0, 0), (-90 deg, l1, 0, 0), "
        "(0, l2, 0, 0), coxa and femur within +-90 deg, tibia 0..160 deg, tool = foot at (l3, 0, 0), no base"
    )
    joints = chain.joints
    leg = robots.get("leg").chain().joints
    tool = np.eye(4)
    tool[0, 3] = chain.tool[0, 3]
    near = lambda x, y: x is not None and y is not None and abs(x - y) <= 1e-9  # noqa: E731
    form = (
        chain.convention == "modified"
        and len(joints) == 3
        and np.max(np.abs(chain.base - np.eye(4))) <= 1e-9
        and np.max(np.abs(chain.tool - tool)) <= 1e-9
        and all(j.kind == "revolute" and near(j.theta, 0.0) and near(j.d, 0.0) for j in joints)
        and all(near(j.alpha, ref.alpha) and near(j.lower, ref.lower) and near(j.upper, ref.upper)
                for j, ref in zip(joints, leg, strict=True))
        and near(joints[0].a, 0.0)
    )  # fmt: skip
    if not form:
        raise UsageError(f"{where} is not of the leg's form; a leg has {allowed}")
    geom = leg_kin.LegGeometry(float(joints[1].a), float(joints[2].a), float(chain.tool[0, 3]))
    for name, value in dataclasses.asdict(geom).items():
        if not MIN_LENGTH <= value <= MAX_LENGTH:
            raise UsageError(f"{where}: the leg's {name} must be {MIN_LENGTH:g} to {MAX_LENGTH:g} m; got {value!r}")
    return geom


LEG_ROBOT = NameOrFile(
    ("leg",), "robot file (.toml) of the leg's form", lambda path: leg_geometry(robots.resolve(path))
)
