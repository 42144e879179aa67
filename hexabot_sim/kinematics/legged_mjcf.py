"""Writes a legged robot's MJCF from the leg's modified DH table and the body layout (one source of truth).

Any number of the 3-DOF legs (kinematics/legged.py): a plate body with a free joint, per leg the
coxa/femur/tibia chain with its sphere foot, a position and a velocity servo per joint, an IMU and a
touch sensor per foot. The hexabot's models/hexabot.xml is robot_xml with its layout and comment
(robots/hexabot/model.py).
"""

from __future__ import annotations

import math

import numpy as np

from hexabot_sim.kinematics import leg as leg_kin
from hexabot_sim.kinematics import legged

SERVO_BANDWIDTH_HZ: float = 20.0  # f_n of every joint servo (as leg.xml)
SERVO_DAMPING_RATIO: float = 1.0
SERVO_TORQUE_LIMIT: float = 1.5  # [N m] hobby servo stall torque (e.g. 15 kg cm class)
# [kg m^2] reflected rotor inertia of a hobby servo: rotor ~5e-8 kg m^2 through a ~250:1 gear train
# (N^2 J = 3e-3). It also keeps a swing leg's servo loop resolved at a 2 ms step: with leg.xml's
# 2e-5 the tibia servo (kp ~100 N m/rad on 1.7e-4 kg m^2) rings at w dt ~ 1.5 and the walk wanders.
ARMATURE: float = 3e-3
LINK_RADIUS: float = 0.01  # [m] tube radius of the axial inertia m r^2 / 2 (as leg.xml)
# Foot contact: time constant 6 ms (3x the 2 ms timestep), critically damped, impedance 0.9 -> 0.97
# over 1 mm: a standing foot sinks 0.15 mm (MuJoCo's default 20 ms: 0.5 mm). Stiffer settings
# (5 ms with d = 0.99, or 4 ms) make the stance chatter at a 2 ms step (measured: feet hop at ~40 Hz).
FOOT_SOLREF: tuple[float, float] = (0.006, 1.0)
FOOT_SOLIMP: tuple[float, float, float] = (0.9, 0.97, 0.001)
FOOT_FRICTION: float = 1.0  # rubber foot on a hard floor
# The compliant foot pad (a walk's feet=pad, written into the scene: walking/scene.py; docs/hexabot.md, issue 19).
# The rigid foot above sinks 5-70 um, so a few um of body motion at another foot's touchdown unload a stance foot
# for a 2 ms step (the ripple and wave gaits' "bounces"). The pad: solref 4 ms with damping ratio 1.5 keeps that
# normal stiffness (1 / (timeconst dampratio)^2) and shortens the friction's time constant to 4 ms (2x the step;
# MuJoCo's friction only damps slip, b = 2 / (dmax timeconst), so the feet creep less); the impedance 0.4 -> 0.95
# over 2 mm softens the first millimetre, so a loaded foot compresses ~0.8 mm; the margin (the pad's thickness)
# puts that compression outside the sphere, so the loaded foot rests where the rigid one does. It needs the
# quintic swing (swing=quintic): a cubic's foot skids over the ground while the pad is loaded before touchdown.
FOOT_PAD_SOLREF: tuple[float, float] = (0.004, 1.5)
FOOT_PAD_SOLIMP: tuple[float, float, float] = (0.4, 0.95, 0.002)
FOOT_PAD_MARGIN: float = 0.0008  # [m]


TRACK_EYE = np.array([-0.45, -0.75, 0.42])  # [m] chase camera, relative to the body (world-aligned, follows the CoM)


def _look_at(eye: np.ndarray, target: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> np.ndarray:
    """MJCF xyaxes of a camera at `eye` looking at `target` with the world z up, rounded to 4 digits."""
    forward = (np.asarray(target) - eye) / np.linalg.norm(np.asarray(target) - eye)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    return np.round(np.r_[right, up], 4)


def num(value: float) -> str:
    """A float as MJCF text: its shortest repr, no negative zero."""
    return repr(float(value) + 0.0)


def nums(values) -> str:
    return " ".join(num(v) for v in values)


def _quat_z(angle: float) -> np.ndarray:
    return np.array([math.cos(angle / 2), 0.0, 0.0, math.sin(angle / 2)])


def _quat_x(angle: float) -> np.ndarray:
    return np.array([math.cos(angle / 2), math.sin(angle / 2), 0.0, 0.0])


def link_inertia(mass: float, length: float) -> tuple[float, float, float]:
    """Diagonal inertia of a link [kg m^2] (a uniform rod along x, axial term of a tube; as leg.xml)."""
    return rod_inertia(mass, length, mass * LINK_RADIUS**2 / 2)


def rod_inertia(mass: float, length: float, axial: float) -> tuple[float, float, float]:
    """(axial, perpendicular, perpendicular) [kg m^2] of a rod of `length` along x about its centre: m L^2 / 12
    across it, but at least half the axial term - a link shorter than ~1.7 radii is no rod, and a thinner inertia
    is no physical body (MuJoCo refuses A + B < C: a 1 cm coxa was an internal error, found by fuzzing)."""
    perp = max(mass * length**2 / 12, axial / 2)
    return (axial, perp, perp)


def loaded_joint_inertia(layout: legged.Layout, q: np.ndarray, stance_legs: int) -> np.ndarray:
    """Inertia each servo of a stance leg drives [kg m^2], (3,): the leg's own links about the joint axis,
    the armature, and the body mass share m_total / stance_legs reflected through the leg Jacobian column
    (stance_legs: the fewest feet that carry the body in the robot's gaits, the worst case for its servos).

    The leg's own part is the joint-space mass-matrix diagonal of a fixed-base leg; tests compare it
    with MuJoCo's mj_fullM.
    """
    g = layout.geometry
    q1, q2, q3 = q
    # Joint axes and origins in the hip frame (modified DH z axes: femur and tibia axes are horizontal,
    # normal to the leg plane).
    c1, s1 = math.cos(q1), math.sin(q1)
    radial = np.array([c1, s1, 0.0])
    normal = np.array([-s1, c1, 0.0])  # femur and tibia axes (z of frames 2 and 3 = -normal... sign irrelevant)
    up = np.array([0.0, 0.0, 1.0])
    femur_origin = g.l1 * radial
    knee = femur_origin + g.l2 * (math.cos(q2) * radial - math.sin(q2) * up)
    foot = knee + g.l3 * (math.cos(q2 + q3) * radial - math.sin(q2 + q3) * up)
    links = [  # (mass, length, start, end)
        (layout.link_masses[0], g.l1, np.zeros(3), femur_origin),
        (layout.link_masses[1], g.l2, femur_origin, knee),
        (layout.link_masses[2], g.l3, knee, foot),
    ]
    axes = [(up, np.zeros(3)), (normal, femur_origin), (normal, knee)]
    inertia = np.zeros(3)
    for j, (axis, origin) in enumerate(axes):
        for mass, length, start, end in links[j:]:
            direction = (end - start) / length if length > 0 else axis  # l1 = 0 (allowed): a disc, no rod
            i_axial, i_perp, _ = link_inertia(mass, length)
            # Rod inertia about the parallel axis through its centre, then Steiner.
            cos_a = float(direction @ axis)
            i_centre = i_axial * cos_a**2 + i_perp * (1 - cos_a**2)
            centre = (start + end) / 2 - origin
            d_perp = centre - (centre @ axis) * axis
            inertia[j] += i_centre + mass * float(d_perp @ d_perp)
    _, jac = leg_kin.foot_and_jacobian(q1, q2, q3, g.l1, g.l2, g.l3)
    column_sq = np.sum(np.array(jac, dtype=float) ** 2, axis=0)  # |dp/dq_j|^2 [m^2]
    return inertia + ARMATURE + layout.total_mass / stance_legs * column_sq


def servo_gains(layout: legged.Layout, stance_legs: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(M, kp, kv) per joint: kp = M w_n^2, kv = 2 zeta M w_n on the loaded inertia at the neutral stance."""
    q0 = legged.ik_body(layout, layout.neutral_feet_body())[0]
    inertia = loaded_joint_inertia(layout, q0, stance_legs)
    w_n = 2 * math.pi * SERVO_BANDWIDTH_HZ
    return inertia, inertia * w_n**2, 2 * SERVO_DAMPING_RATIO * inertia * w_n


def _leg_lines(layout: legged.Layout, i: int, name: str, indent: str) -> list[str]:
    g = layout.geometry
    rows = leg_kin.modified_dh_table(g)  # (alpha, d, theta offset, r) of frames 1..4
    masses = layout.link_masses
    lengths = (g.l1, g.l2, g.l3)
    materials = ("coxa", "femur", "tibia")
    radii = (0.008, 0.007, 0.005)
    servo = (0.012, 0.011, 0.010)
    lo, hi = legged.JOINT_LOWER, legged.JOINT_UPPER
    hip = layout.hip_positions()[i]
    lines = [f'{indent}<site name="{name}_hip" pos="{nums(hip)}" quat="{nums(_quat_z(layout.yaws[i]))}"/>']
    pos, quat = hip, _quat_z(layout.yaws[i])
    depth = indent
    for j, joint in enumerate(legged.JOINTS):
        alpha, d, theta, r = rows[j]
        if j > 0:  # frame j+1 = Rx(alpha) Tx(d) Rz(theta) Tz(r) in frame j
            if theta != 0 or r != 0:
                raise ValueError("the leg's DH rows must have zero theta offset and r")
            pos, quat = np.array([d, 0.0, 0.0]), _quat_x(alpha)
        quat_attr = "" if np.allclose(quat, [1, 0, 0, 0]) else f' quat="{nums(quat)}"'
        lines.append(f'{depth}<body name="{name}_{joint}" pos="{nums(pos)}"{quat_attr}>')
        inner = depth + "  "
        lines.append(f'{inner}<joint name="{name}_{joint}" range="{num(lo[j])} {num(hi[j])}"/>')
        length = lengths[j]
        lines.append(
            f'{inner}<inertial pos="{num(length / 2)} 0 0" mass="{num(masses[j])}" '
            f'diaginertia="{nums(link_inertia(masses[j], length))}"/>'
        )
        lines.append(
            f'{inner}<geom name="{name}_{joint}_servo" type="cylinder" '
            f'fromto="0 0 {num(-servo[j])} 0 0 {num(servo[j])}" size="{num(servo[j])}" material="{materials[j]}"/>'
        )
        if length > 0:  # l1 = 0 (allowed): no coxa rod (MuJoCo refuses a fromto of one point), its servo only
            lines.append(
                f'{inner}<geom name="{name}_{joint}" fromto="0 0 0 {num(length)} 0 0" size="{num(radii[j])}" '
                f'material="{materials[j]}"/>'
            )
        depth = inner
    foot = num(rows[3][1])
    lines.append(f'{depth}<geom name="{name}_foot" class="foot" pos="{foot} 0 0"/>')
    lines.append(f'{depth}<site name="{name}_foot" pos="{foot} 0 0"/>')
    lines.append(f'{depth}<site name="{name}_touch" class="touch" pos="{foot} 0 0"/>')
    for j in reversed(range(3)):
        lines.append(f"{indent}{'  ' * j}</body>")
    return lines


def robot_xml(
    layout: legged.Layout, model: str, comment: str, stance_legs: int, torque_limit: float = SERVO_TORQUE_LIMIT
) -> str:
    """The robot file models/<model>.xml (no floor: the scene adds it), opening with `comment` (an XML
    comment, "<!-- ... -->"); its default class is named after the model. Servo gains: servo_gains; every joint's
    actuatorfrcrange is +-torque_limit [N m]."""
    _, kp, kv = servo_gains(layout, stance_legs)
    q0 = legged.ik_body(layout, layout.neutral_feet_body())
    px, py, pz = layout.plate
    m = layout.body_mass
    plate_inertia = (m * (py**2 + pz**2) / 3, m * (px**2 + pz**2) / 3, m * (px**2 + py**2) / 3)  # box, half sizes
    z0 = layout.body_height()
    lo, hi = legged.JOINT_LOWER, legged.JOINT_UPPER
    lines = [
        comment,
        f'<mujoco model="{model}">',
        '  <compiler angle="radian" autolimits="true"/>',
        "",
        '  <option timestep="0.002" integrator="implicitfast" cone="elliptic"/>',
        "",
        "  <default>",
        f'    <default class="{model}">',
        f'      <joint type="hinge" axis="0 0 1" armature="{num(ARMATURE)}" damping="0" '
        f'actuatorfrcrange="{num(-torque_limit)} {num(torque_limit)}"/>',
        '      <geom type="capsule" contype="0" conaffinity="0" group="2" mass="0"/>',
        '      <site group="4" size="0.004"/>',
        '      <default class="foot">',
        f'        <geom type="sphere" size="{num(layout.foot_radius)}" contype="2" conaffinity="0" group="3" '
        f'condim="3" priority="1" friction="{num(FOOT_FRICTION)} 0.005 0.0001" solref="{nums(FOOT_SOLREF)}" '
        f'solimp="{nums(FOOT_SOLIMP)}" material="foot"/>',
        "      </default>",
        '      <default class="touch">',
        f'        <site type="sphere" size="{num(layout.foot_radius * 1.25)}" group="5"/>',
        "      </default>",
        "    </default>",
        "  </default>",
        "",
        "  <asset>",
        '    <material name="body" rgba="0.35 0.35 0.38 1"/>',
        '    <material name="coxa" rgba="0.85 0.55 0.15 1"/>',
        '    <material name="femur" rgba="0.20 0.45 0.80 1"/>',
        '    <material name="tibia" rgba="0.15 0.65 0.45 1"/>',
        '    <material name="foot" rgba="0.9 0.2 0.2 1"/>',
        "  </asset>",
        "",
        "  <worldbody>",
        f'    <body name="torso" pos="0 0 {num(z0)}" childclass="{model}">',
        '      <freejoint name="root"/>',
        f'      <inertial pos="0 0 0" mass="{num(m)}" diaginertia="{nums(plate_inertia)}"/>',
        f'      <geom name="torso" type="box" size="{nums(layout.plate)}" contype="2" conaffinity="0" '
        'group="2" material="body"/>',
        '      <site name="imu" pos="0 0 0"/>',
        f'      <camera name="track" mode="trackcom" pos="{nums(TRACK_EYE)}" xyaxes="{nums(_look_at(TRACK_EYE))}"/>',
        '      <camera name="top" mode="trackcom" pos="0 0 1.2" xyaxes="1 0 0 0 1 0"/>',
    ]
    for i, name in enumerate(layout.legs):
        lines += _leg_lines(layout, i, name, "      ")
    lines += ["    </body>", "  </worldbody>", "", "  <actuator>"]
    for name in layout.legs:
        for j, joint in enumerate(legged.JOINTS):
            lines.append(
                f'    <position name="{name}_{joint}" joint="{name}_{joint}" kp="{num(round(kp[j], 4))}" '
                f'ctrlrange="{num(lo[j])} {num(hi[j])}"/>'
            )
    for name in layout.legs:
        for j, joint in enumerate(legged.JOINTS):
            lines.append(
                f'    <velocity name="{name}_{joint}_velocity" joint="{name}_{joint}" kv="{num(round(kv[j], 6))}"/>'
            )
    lines += ["  </actuator>", "", "  <sensor>"]
    lines += [
        '    <framequat name="imu_quat" objtype="site" objname="imu"/>',
        '    <gyro name="imu_gyro" site="imu"/>',
        '    <accelerometer name="imu_acc" site="imu"/>',
    ]
    lines += [f'    <touch name="{name}_touch" site="{name}_touch"/>' for name in layout.legs]
    lines += ["  </sensor>", ""]
    qpos = [0.0, 0.0, z0, 1.0, 0.0, 0.0, 0.0, *q0.ravel()]
    ctrl = [*q0.ravel(), *np.zeros(q0.size)]
    lines += [
        "  <keyframe>",
        "    <!-- Neutral stance: every foot (neutral_reach, 0, -stand_height) in its hip frame, on the ground. -->",
        f'    <key name="home" qpos="{nums(qpos)}"',
        f'         ctrl="{nums(ctrl)}"/>',
        "  </keyframe>",
        "</mujoco>",
        "",
    ]
    return "\n".join(lines)


def scene_xml(model: str, comment: str) -> str:
    """models/<model>_scene.xml: the robot (models/<model>.xml) on a replaceable flat floor (geom "floor"),
    light and sky, opening with `comment` (an XML comment)."""
    return f"""{comment}
<mujoco model="{model} scene">
  <include file="{model}.xml"/>

  <visual>
    <headlight ambient="0.35 0.35 0.35" diffuse="0.5 0.5 0.5"/>
    <global offwidth="1920" offheight="1080"/>
  </visual>

  <asset>
    <texture name="grid" type="2d" builtin="checker" rgb1="0.82 0.84 0.86" rgb2="0.70 0.72 0.75"
             width="512" height="512" mark="edge" markrgb="0.5 0.5 0.55"/>
    <material name="floor" texture="grid" texrepeat="40 40" texuniform="false"/>
    <texture name="sky" type="skybox" builtin="gradient" rgb1="0.55 0.7 0.9" rgb2="0.95 0.97 1"
             width="256" height="256"/>
  </asset>

  <worldbody>
    <light name="sun" pos="0 0 3" dir="0 0 -1" directional="true" diffuse="0.6 0.6 0.6"/>
    <geom name="floor" type="plane" size="10 10 0.05" material="floor" contype="0" conaffinity="2" group="0"/>
  </worldbody>
</mujoco>
"""
