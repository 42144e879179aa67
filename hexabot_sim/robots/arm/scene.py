"""An arm's MuJoCo scene for arm-track: the exported MJCF with gravity, servos sized from mj_fullM, floor, camera."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import mujoco
import numpy as np

from hexabot_sim import models, render
from hexabot_sim.kinematics.chain import SerialChain
from hexabot_sim.kinematics.mjcf import to_mjcf
from hexabot_sim.kinematics.xml_text import comment_line

CAMERA_DIRECTION = np.array([1.1, -1.1, 0.7])  # from the arm toward the three-quarter camera (as models/*_scene.xml)
FOVY: float = 45.0  # [deg] the camera's vertical field of view
FLOOR_CLEARANCE: float = 0.05  # [m] the floor is at z = 0, or this far below the lowest point the arm's frames reach
LINK_RADIUS: float = 0.02  # [m] to_mjcf's default link radius (mass and inertia come from these solid cylinders)


def _camera_axes() -> tuple[np.ndarray, np.ndarray]:
    forward = -CAMERA_DIRECTION / np.linalg.norm(CAMERA_DIRECTION)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    return right, np.cross(right, forward)


def servo_gains(
    model: mujoco.MjModel, q: np.ndarray, qadr: list[int], dadr: list[int], bandwidth: float, damping: float
) -> tuple[np.ndarray, np.ndarray]:
    """(kp, kv) (n,) each: kp = M_jj w^2, kv = 2 zeta M_jj w, w = 2 pi bandwidth, M_jj the diagonal of the joint-space
    inertia (mj_fullM) at q: each joint alone is a second-order system of that natural frequency and damping ratio."""
    data = mujoco.MjData(model)
    data.qpos[qadr] = q
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))  # (nv, nv)
    mujoco.mj_fullM(model, data, full)
    inertia = np.diag(full)[dadr]  # (n,) [kg m^2 or kg]
    omega = 2 * math.pi * bandwidth
    return inertia * omega**2, 2 * damping * omega * inertia


def build(
    chain: SerialChain,
    masses: tuple[float | None, ...],
    comment: str,
    q_start: np.ndarray,
    frame_points: np.ndarray,
    timestep: float,
    bandwidth: float,
    damping: float,
) -> tuple[str, mujoco.MjModel]:
    """The scene's MJCF and model: the robot as `hexabot-sim export` writes it, with gravity (no gravcomp), per joint
    a position servo (name = joint), a velocity servo (JOINT_velocity) and a feedforward motor (JOINT_bias); a floor
    under `frame_points` (k, 3), a light and the camera "three_quarter" framing them; keyframe home = q_start."""
    root = ET.fromstring(to_mjcf(chain, comment=comment_line(comment), masses=masses))
    models.find(root, "option").attrib.update(timestep=models.fmt(timestep), integrator="implicitfast")
    for body in root.iter("body"):
        body.attrib.pop("gravcomp", None)  # the servos carry the arm's weight (with the bias feedforward)
    lowest = float(frame_points[:, 2].min())
    lowest = 0.0 if lowest >= 0.0 else lowest - FLOOR_CLEARANCE  # at z = 0, or below an arm that reaches under it
    extent = float(np.ptp(frame_points, axis=0).max()) + 0.5
    visual = ET.Element("visual")
    ET.SubElement(visual, "headlight", diffuse="0.6 0.6 0.6", ambient="0.3 0.3 0.3", specular="0 0 0")
    ET.SubElement(visual, "global", offwidth="1920", offheight="1080")
    root.insert(list(root).index(models.find(root, "asset")), visual)
    asset = models.find(root, "asset")
    ET.SubElement(
        asset,
        "texture",
        type="2d",
        name="groundplane",
        builtin="checker",
        mark="edge",
        rgb1="0.2 0.3 0.4",
        rgb2="0.1 0.2 0.3",
        markrgb="0.8 0.8 0.8",
        width="300",
        height="300",
    )
    ET.SubElement(asset, "material", name="groundplane", texture="groundplane", texuniform="true", texrepeat="8 8")
    world = models.find(root, "worldbody")
    centre = frame_points.mean(axis=0)
    light = centre + extent * np.array([0.5, -1.0, 2.5])
    right, up = _camera_axes()
    xyaxes = [*right, *up]
    eye = render.fit_camera(frame_points, xyaxes, FOVY, text_lines=2)
    scene = [
        ET.Element("light", name="key", pos=models.fmt(light), dir="-0.2 0.4 -1", directional="true"),
        ET.Element(
            "geom",
            name="floor",
            type="plane",
            size=f"{2 * extent!r} {2 * extent!r} 0.05",
            pos=models.fmt((centre[0], centre[1], lowest)),
            material="groundplane",
            contype="0",
            conaffinity="0",
        ),
        ET.Element("camera", name="three_quarter", pos=models.fmt(eye), xyaxes=models.fmt(xyaxes), fovy=repr(FOVY)),
    ]
    for k, element in enumerate(scene):
        world.insert(k, element)
    actuator = models.find(root, "actuator")
    ranges: dict[str, str] = {}
    for element in list(actuator):
        ranges[element.get("joint", "")] = element.get("ctrlrange", "")
        actuator.remove(element)
    names = [j.name for j in chain.joints]
    for kind in ("position", "velocity", "motor"):
        for name in names:
            attrs = {"name": name if kind == "position" else f"{name}_{'velocity' if kind == 'velocity' else 'bias'}"}
            attrs["joint"] = name
            if kind == "position":
                attrs["kp"] = "1"
                if ranges.get(name):
                    attrs["ctrlrange"] = ranges[name]
            elif kind == "velocity":
                attrs["kv"] = "1"
            ET.SubElement(actuator, kind, attrs)
    key = models.find(root, "key", "home")
    key.attrib.update(qpos=models.fmt(q_start), ctrl=models.fmt([*q_start, *np.zeros(2 * chain.n)]))
    # Servo gains from the mass matrix at the start pose, written into the file that is compiled and saved.
    model = mujoco.MjModel.from_xml_string(models.to_xml(root))
    qadr = [int(model.joint(n).qposadr[0]) for n in names]
    dadr = [int(model.joint(n).dofadr[0]) for n in names]
    kp, kv = servo_gains(model, q_start, qadr, dadr, bandwidth, damping)
    for name, p_gain, v_gain in zip(names, kp, kv, strict=True):
        models.find(actuator, "position", name).set("kp", repr(float(p_gain)))
        models.find(actuator, "velocity", f"{name}_velocity").set("kv", repr(float(v_gain)))
    xml = models.to_xml(root)
    return xml, mujoco.MjModel.from_xml_string(xml)
