"""The leg's MuJoCo scene: models/leg_scene.xml with the run's options and, when they differ, the run's link lengths."""

from __future__ import annotations

from typing import TYPE_CHECKING

from hexabot_sim import models
from hexabot_sim.kinematics import leg as leg_kin

if TYPE_CHECKING:
    import xml.etree.ElementTree as ET

    from hexabot_sim.robots.leg.step import LegParams

JOINTS = ("coxa", "femur", "tibia")


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

    Each link keeps its mass as a uniform rod along its x axis (I_perp = m L^2 / 12 about its centre, I_axial
    unchanged); the femur and tibia bodies move to (L1, 0, 0) and (L2, 0, 0), the foot to (L3, 0, 0). The servo
    gains and the home keyframe stay those of the default leg.
    """
    lengths = {"coxa": geom.l1, "femur": geom.l2, "tibia": geom.l3}
    for link, length in lengths.items():
        body = models.find(root, "body", link)
        inertial = body.find("inertial")
        mass = float(inertial.get("mass"))
        axial = float(inertial.get("diaginertia").split()[0])
        perp = mass * length**2 / 12
        inertial.attrib.update(pos=models.fmt((length / 2, 0.0, 0.0)), diaginertia=models.fmt((axial, perp, perp)))
        models.find(root, "geom", link).set("fromto", models.fmt((0.0, 0.0, 0.0, length, 0.0, 0.0)))
    models.find(root, "body", "femur").set("pos", models.fmt((geom.l1, 0.0, 0.0)))
    models.find(root, "body", "tibia").set("pos", models.fmt((geom.l2, 0.0, 0.0)))
    models.find(root, "geom", "foot").set("pos", models.fmt((geom.l3, 0.0, 0.0)))
    models.find(root, "site", "foot").set("pos", models.fmt((geom.l3, 0.0, 0.0)))
