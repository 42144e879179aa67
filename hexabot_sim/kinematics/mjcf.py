"""MJCF from a DH table: one body per joint, in the frame the joint acts in, so that MuJoCo's qpos is the DH q."""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Sequence

import numpy as np

from hexabot_sim.errors import UsageError
from hexabot_sim.kinematics.chain import Joint, SerialChain
from hexabot_sim.kinematics.xml_text import comment_line
from hexabot_sim.kinematics.xml_text import num as _num
from hexabot_sim.kinematics.xml_text import nums as _nums
from hexabot_sim.kinematics.xml_text import quat as _quat

ALUMINIUM_DENSITY = 2700.0  # [kg/m^3] density of the links' material (aluminium alloy, handbook value)
SERVO_BANDWIDTH = 5.0  # [Hz] natural frequency f_n of each position servo on its own joint inertia at home
SERVO_DAMPING_RATIO = 1.0  # critical damping (MuJoCo's `dampratio` turns it into kv at qpos0)
HOUSING_SCALE = 1.5  # joint housing: a cylinder of radius and half-length HOUSING_SCALE * link_radius
SITE_SCALE = 0.25  # site radius as a fraction of link_radius (sites are markers, group 4)
MIN_SEGMENT = 1e-9  # [m] shorter link segments are not drawn (a zero-length capsule does not compile)
TIMESTEP = 0.002  # [s] MuJoCo's default; the servos' w_n dt = 0.06 is far inside implicitfast's stable range
HALF_PI = math.pi / 2


@dataclasses.dataclass(frozen=True)
class _Solid:
    """A solid cylinder in a body's frame: drawn (capsule or cylinder) and counted in the body's inertia."""

    name: str
    start: np.ndarray  # (3,) [m]
    end: np.ndarray  # (3,) [m]
    radius: float  # [m]
    geom_class: str  # "link" (capsule) or "axis" (cylinder)


@dataclasses.dataclass(frozen=True)
class _Site:
    """A named frame in a body: pose (4, 4) in the body's frame; euler (alpha, theta) when it is Rx Rz."""

    name: str
    pose: np.ndarray
    comment: str
    euler: tuple[float, float] | None = None


@dataclasses.dataclass
class _Body:
    """Body k (1-based) of the chain: its placement in the parent, its joint, what it carries."""

    name: str
    joint: Joint
    local: np.ndarray  # (4, 4) parent frame -> this body's frame at q = 0: Tx(a) Rx(alpha) Rz(theta) Tz(d)
    a: float
    alpha: float
    description: str
    solids: list[_Solid] = dataclasses.field(default_factory=list)
    sites: list[_Site] = dataclasses.field(default_factory=list)
    mass: float = 0.0  # [kg]
    com: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))  # (3,) [m], body frame
    inertia: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((3, 3)))  # (3, 3) about the com


def to_mjcf(
    chain: SerialChain,
    *,
    comment: str = "",
    link_radius: float = 0.02,
    density: float = ALUMINIUM_DENSITY,
    masses: Sequence[float | None] = (),
) -> str:
    """The MJCF of a serial chain whose body frames are the frames its joints act in (qpos == q).

    Standard DH (A_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i), joint i about/along z_{i-1}): body i sits at
    Tx(a_{i-1}) Rx(alpha_{i-1}) Rz(theta_i) Tz(d_i) in body i-1 (the previous row's fixed part, then the
    constant part of row i); Rz and Tz commute, so a hinge (slide) about (along) local z with qpos = q gives A_i.
    Modified DH (A_i = Rx(alpha_i) Tx(a_i) Rz(theta_i) Tz(d_i), joint i about/along z_i): body i sits at
    Rx(alpha_i) Tx(a_i) Rz(theta_i) Tz(d_i) in body i-1. Here theta_i, d_i are the table's constants (q adds to
    one of them). A fixed body `base` carries `chain.base`; sites: `base` (frame 0), `frame1`..`frameN`, `tool`.

    Args:
        chain: The serial chain (its joint names name the joints and actuators).
        comment: Text for the header comment (e.g. the report the table comes from); must not contain "--".
        link_radius: Radius of the link capsules in [m]; joint housings are HOUSING_SCALE times larger.
        density: Density of the solid cylinders that give each link its mass and inertia in [kg/m^3].
        masses: Each link's mass in [kg] (a robot file's `mass`), or None for the cylinders' own: the inertia
            scales with it, the centre of mass stays.

    Returns:
        The MJCF text (one robot, no floor or lights: a scene file includes it).
    """
    _validate(chain, comment, link_radius, density)
    bodies, base_solids, base_sites = link_bodies(chain, link_radius, density, masses)
    q_home = home_pose(chain)
    kp = _mass_diagonal(chain, bodies, q_home) * (2 * math.pi * SERVO_BANDWIDTH) ** 2  # (n,) [N m/rad or N/m]
    return _write(chain, bodies, base_solids, base_sites, q_home, kp, comment, link_radius, density)


def _validate(chain: SerialChain, comment: str, link_radius: float, density: float) -> None:
    if chain.n == 0:
        raise UsageError(f"chain '{chain.name}' has no joints; a model needs at least one")
    if not (math.isfinite(link_radius) and link_radius > 0):
        raise UsageError(f"link_radius must be a finite number > 0 [m]; got {link_radius!r}")
    if not (math.isfinite(density) and density > 0):
        raise UsageError(f"density must be a finite number > 0 [kg/m^3]; got {density!r}")
    if "--" in comment:
        raise UsageError("comment must not contain '--' (it ends an XML comment)")
    if not chain.name or any(c in chain.name for c in "<>&\"'"):
        raise UsageError(f"chain name must be non-empty and XML-safe (no < > & quotes); got {chain.name!r}")
    names = [j.name for j in chain.joints]
    for name in names:
        if not name or names.count(name) > 1 or any(c in name for c in "<>&\"'"):
            raise UsageError(f"joint names must be unique, non-empty and XML-safe; got {names}")
    for joint in chain.joints:
        values = (joint.theta, joint.d, joint.a, joint.alpha)
        if not all(math.isfinite(v) for v in values):
            raise UsageError(f"joint '{joint.name}': DH parameters must be finite; got {values}")
        if (joint.lower is None) != (joint.upper is None):
            raise UsageError(f"joint '{joint.name}': give both lower and upper limits or neither")
        if joint.lower is not None and joint.upper is not None and not joint.lower <= joint.upper:
            raise UsageError(f"joint '{joint.name}': lower limit {joint.lower} exceeds upper {joint.upper}")
    for label, t in (("base", chain.base), ("tool", chain.tool)):
        t = np.asarray(t, dtype=float)
        ok = t.shape == (4, 4) and np.all(np.isfinite(t)) and np.allclose(t[3], [0, 0, 0, 1], atol=0)
        if not ok or not np.allclose(t[:3, :3] @ t[:3, :3].T, np.eye(3), atol=1e-9) or np.linalg.det(t[:3, :3]) < 0:
            raise UsageError(f"chain.{label} must be a rigid transform (4, 4) with a rotation block; got {t}")


def _cos_sin(angle: float) -> tuple[float, float]:
    """cos and sin, exact at quarter turns (cos(pi/2) is 6.1e-17 in floating point; the table means 0)."""
    quarter = round(angle / HALF_PI)
    if angle == quarter * HALF_PI:
        return ((1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0))[quarter % 4]
    return math.cos(angle), math.sin(angle)


def _placement(a: float, alpha: float, theta: float, d: float) -> np.ndarray:
    """Tx(a) Rx(alpha) Rz(theta) Tz(d), (4, 4)."""
    ca, sa = _cos_sin(alpha)
    ct, st = _cos_sin(theta)
    t = np.eye(4)  # (4, 4)
    t[:3, :3] = [[ct, -st, 0.0], [ca * st, ca * ct, -sa], [sa * st, sa * ct, ca]]
    t[:3, 3] = (a, -sa * d, ca * d)
    return t


def link_bodies(
    chain: SerialChain, radius: float, density: float, masses: Sequence[float | None] = ()
) -> tuple[list[_Body], list[_Solid], list[_Site]]:
    """The bodies (frames, solids, sites, mass, centre of mass, inertia) of the MJCF, also used by the URDF writer."""
    bodies, base_solids, base_sites = _bodies(chain, radius)
    for k, body in enumerate(bodies):
        body.mass, body.com, body.inertia = _cylinders_inertia(body.solids, density)
        mass = masses[k] if k < len(masses) else None
        if mass is not None:  # a given mass: the same shape, scaled in density
            body.inertia, body.mass = body.inertia * (mass / body.mass), float(mass)
    return bodies, base_solids, base_sites


def _bodies(chain: SerialChain, radius: float) -> tuple[list[_Body], list[_Solid], list[_Site]]:
    """Bodies 1..n with their placements, solids and sites; the base body's solids and sites."""
    standard = chain.convention == "standard"
    rows = chain.joints
    bodies: list[_Body] = []
    for k, joint in enumerate(rows, start=1):
        if standard:  # previous row's fixed part Tx(a_{k-1}) Rx(alpha_{k-1}); none before row 1
            a, alpha = (rows[k - 2].a, rows[k - 2].alpha) if k > 1 else (0.0, 0.0)
            before = f"frame {k - 1}" if k > 1 else "frame 0 (site base)"
            description = f"{before} · Rz({_theta_text(joint)}) Tz({_d_text(joint)}); joint {joint.name} on z{k - 1}"
        else:
            a, alpha = joint.a, joint.alpha
            description = (
                f"frame {k - 1} · Rx({_num(alpha)}) Tx({_num(a)}) Rz({_theta_text(joint)}) Tz({_d_text(joint)})"
                f" = frame {k}; joint {joint.name} on z{k}"
            )
        local = _placement(a, alpha, joint.theta, joint.d)
        bodies.append(_Body(f"link{k}", joint, local, a, alpha, description))

    # Link segments: each body draws origin -> Tx(a) (along its x) -> next origin (along the next z).
    base_solids = _segments("base", bodies[0], radius)
    for body, child in itertools.pairwise(bodies):
        body.solids += _segments(body.name, child, radius)
    # The frame each body's joint variable moves (frame k), and the tool.
    last = bodies[-1]
    for k, body in enumerate(bodies, start=1):
        if standard:
            frame = _placement(rows[k - 1].a, rows[k - 1].alpha, 0.0, 0.0)
            text = f"frame {k} = {body.name} · Tx(a{k}) Rx(alpha{k})"
            body.sites.append(_Site(f"frame{k}", frame, text, (rows[k - 1].alpha, 0.0)))
        else:
            body.sites.append(_Site(f"frame{k}", np.eye(4), f"frame {k} = {body.name}'s frame"))
    frame_n = last.sites[0].pose
    tool = frame_n @ np.asarray(chain.tool, dtype=float)
    last.sites.append(_Site("tool", tool, f"tool = frame {chain.n} · chain.tool"))
    x_end = frame_n[:3, 3]
    for name, start, end in ((f"{last.name}_a", np.zeros(3), x_end), (f"{last.name}_tool", x_end, tool[:3, 3])):
        if np.linalg.norm(end - start) > MIN_SEGMENT:
            last.solids.append(_Solid(name, start, end, radius, "link"))
    # The joint itself: a housing cylinder on a hinge's axis; a ram along -z from a slide's origin.
    for body in bodies:
        body.solids.insert(0, _axis_solid(body, radius, chain))
    base_sites = [_Site("base", np.eye(4), "frame 0")]
    return bodies, base_solids, base_sites


def _segments(name: str, child: _Body, radius: float) -> list[_Solid]:
    """Capsules from the parent's origin to Tx(a), then along the child's z to the child's origin."""
    corner = np.array([child.a, 0.0, 0.0])  # (3,)
    out = []
    for suffix, start, end in (("a", np.zeros(3), corner), ("d", corner, child.local[:3, 3])):
        if np.linalg.norm(end - start) > MIN_SEGMENT:
            out.append(_Solid(f"{name}_{suffix}", start, end, radius, "link"))
    return out


def _axis_solid(body: _Body, radius: float, chain: SerialChain) -> _Solid:
    joint = body.joint
    if not joint.prismatic:
        h = HOUSING_SCALE * radius
        return _Solid(f"{body.name}_axis", np.array([0, 0, -h]), np.array([0, 0, h]), h, "axis")
    # Ram: reaches back to the previous frame's origin at the upper limit (at every q when unlimited: scale).
    length = (joint.upper if joint.upper is not None else _scale(chain)) + joint.d
    length = max(length, 4 * radius)
    return _Solid(f"{body.name}_axis", np.zeros(3), np.array([0.0, 0.0, -length]), radius, "axis")


def _scale(chain: SerialChain) -> float:
    """A length for unlimited slides: the sum of the table's |a| and |d| (0.5 m when that is 0)."""
    total = sum(abs(j.a) + abs(j.d) for j in chain.joints)
    return total if total > 0 else 0.5


def _cylinders_inertia(solids: list[_Solid], density: float) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass [kg], centre of mass (3,) [m] and inertia (3, 3) [kg m^2] about it of a union of solid cylinders.

    Cylinder of radius r, length L, unit axis u: m = density pi r^2 L, centre at its midpoint,
    I = m r^2 / 2 u u^T + m (3 r^2 + L^2) / 12 (E - u u^T); summed with the parallel-axis term
    m (|c_i - c|^2 E - (c_i - c)(c_i - c)^T). Overlaps are counted twice (a documented approximation).
    """
    masses, centres, tensors = [], [], []
    for s in solids:
        axis = s.end - s.start  # (3,)
        length = float(np.linalg.norm(axis))
        u = axis / length  # (3,)
        m = density * math.pi * s.radius**2 * length
        uu = np.outer(u, u)  # (3, 3)
        tensors.append(m * s.radius**2 / 2 * uu + m * (3 * s.radius**2 + length**2) / 12 * (np.eye(3) - uu))
        masses.append(m)
        centres.append((s.start + s.end) / 2)
    mass = float(sum(masses))
    com = sum(m * c for m, c in zip(masses, centres, strict=True)) / mass  # (3,)
    inertia = np.zeros((3, 3))  # (3, 3)
    for m, c, tensor in zip(masses, centres, tensors, strict=True):
        r = c - com  # (3,)
        inertia += tensor + m * (r @ r * np.eye(3) - np.outer(r, r))
    return mass, com, inertia


def home_pose(chain: SerialChain) -> np.ndarray:
    """The `home` keyframe: q = 0, except the range midpoint for a joint whose range excludes 0, (n,)."""
    q = np.zeros(chain.n)  # (n,)
    for i, j in enumerate(chain.joints):
        if j.lower is not None and j.upper is not None and not j.lower <= 0.0 <= j.upper:
            q[i] = (j.lower + j.upper) / 2
    return q


def _mass_diagonal(chain: SerialChain, bodies: list[_Body], q: np.ndarray) -> np.ndarray:
    """Diagonal of the joint-space inertia matrix at q, (n,): M_jj = sum_{k>=j} m_k |v_kj|^2 + z_j^T I_k z_j.

    v_kj = z_j × (c_k − o_j) for a hinge, z_j for a slide (no rotational term) — the composite rigid body sum.
    """
    world = [np.asarray(chain.base, dtype=float)]
    for body, value in zip(bodies, q, strict=True):
        motion = np.eye(4)  # (4, 4) the joint's own motion along/about local z
        if body.joint.prismatic:
            motion[2, 3] = value
        else:
            motion[:2, :2] = [[math.cos(value), -math.sin(value)], [math.sin(value), math.cos(value)]]
        world.append(world[-1] @ body.local @ motion)
    diagonal = np.zeros(chain.n)  # (n,)
    for j, body in enumerate(bodies):
        z, o = world[j + 1][:3, 2], world[j + 1][:3, 3]
        for k in range(j, chain.n):
            rot = world[k + 1][:3, :3]
            centre = world[k + 1][:3, 3] + rot @ bodies[k].com
            if body.joint.prismatic:
                diagonal[j] += bodies[k].mass
            else:
                v = np.cross(z, centre - o)
                diagonal[j] += bodies[k].mass * v @ v + z @ rot @ bodies[k].inertia @ rot.T @ z
    return diagonal


def _pose_attributes(t: np.ndarray, euler: tuple[float, float] | None = None) -> str:
    """` pos=".." quat=".."` of a transform (each omitted when trivial); `euler="alpha 0 theta"` when given."""
    out = ""
    if np.any(t[:3, 3] != 0):
        out += f' pos="{_nums(t[:3, 3])}"'
    if euler is not None:
        if euler != (0.0, 0.0):
            out += f' euler="{_num(euler[0])} 0 {_num(euler[1])}"'
    elif np.any(t[:3, :3] != np.eye(3)):
        out += f' quat="{_nums(_quat(t[:3, :3]))}"'
    return out


def _theta_text(joint: Joint) -> str:
    if joint.prismatic:
        return _num(joint.theta)
    return joint.name if joint.theta == 0 else f"{joint.name} + {_num(joint.theta)}"


def _d_text(joint: Joint) -> str:
    if not joint.prismatic:
        return _num(joint.d)
    return joint.name if joint.d == 0 else f"{joint.name} + {_num(joint.d)}"


def _limits(joint: Joint) -> tuple[float, float] | None:
    """(lower, upper), or None for an unlimited joint (_validate refuses one limit without the other)."""
    if joint.lower is None or joint.upper is None:
        return None
    return joint.lower, joint.upper


def _range_text(joint: Joint) -> str:
    limits = _limits(joint)
    if limits is None:
        return "unlimited"
    return f"[{_num(limits[0])}, {_num(limits[1])}] {'m' if joint.prismatic else 'rad'}"


def _table(chain: SerialChain) -> list[str]:
    """The DH table as comment lines."""
    if chain.convention == "standard":
        head = [
            "DH table, standard convention: A_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i);",
            "joint i turns about / slides along z_{i-1}. Angles in [rad], lengths in [m].",
        ]
    else:
        head = [
            "DH table, modified (Khalil/Craig) convention: A_i = Rx(alpha_i) Tx(a_i) Rz(theta_i) Tz(d_i);",
            "joint i turns about / slides along z_i. Angles in [rad], lengths in [m].",
        ]
    rows = [("i", "joint", "type", "theta", "d", "a", "alpha", "range")]
    for i, j in enumerate(chain.joints, start=1):
        rows.append((str(i), j.name, j.kind, _theta_text(j), _d_text(j), _num(j.a), _num(j.alpha), _range_text(j)))
    widths = [max(len(r[c]) for r in rows) for c in range(len(rows[0]))]
    lines = ["  ".join(cell.ljust(w) for cell, w in zip(r, widths, strict=True)).rstrip() for r in rows]
    extra = []
    for label, t in (("base", chain.base), ("tool", chain.tool)):
        t = np.asarray(t, dtype=float)
        if np.array_equal(t, np.eye(4)):
            extra.append(f"{label} = identity")
        else:
            extra.append(f"{label} (rows 1-3 of the 4x4):")
            extra += [f"  {_nums(row)}" for row in t[:3]]
    return head + ["  " + line for line in lines] + extra


def _write(
    chain: SerialChain,
    bodies: list[_Body],
    base_solids: list[_Solid],
    base_sites: list[_Site],
    q_home: np.ndarray,
    kp: np.ndarray,
    comment: str,
    radius: float,
    density: float,
) -> str:
    cls = chain.name.replace(" ", "_") or "chain"
    housing = HOUSING_SCALE * radius
    header = [*(comment.strip().splitlines() if comment.strip() else []), *([""] if comment.strip() else [])]
    header += _table(chain)
    header += [
        "",
        "Generated by hexabot_sim.kinematics.mjcf.to_mjcf from this table: edit the table, not this file.",
        "Body link_i is the frame joint i acts in, so qpos == q exactly; the fixed body `base` carries",
        "chain.base. Sites: base (frame 0), frame1..frameN (the DH frames), tool (frame N · chain.tool).",
        'A body at Tx(a) Rx(alpha) Rz(theta) Tz(d) in its parent is written pos="a -sin(alpha) d cos(alpha) d"',
        'euler="alpha 0 theta" (eulerseq xyz is intrinsic: Rx(alpha) Rz(theta)); sin and cos of quarter turns',
        "are written exactly (0, 1, -1).",
        "",
        f"Mass: every link segment is a solid cylinder of radius r = {_num(radius)} m along a capsule's axis;",
        f"a hinge adds a housing cylinder (radius and half-length {_num(housing)} m) on its axis, a slide a ram",
        "of radius r from its origin back along -z, long enough to reach the previous frame at the upper limit.",
        f"Density {_num(density)} kg/m^3 (aluminium alloy). Cylinder: m = density pi r^2 L,",
        "I = m r^2/2 along the axis, m (3 r^2 + L^2)/12 across it, about its midpoint; a link's <inertial> is",
        "the sum, moved to the common centre of mass by the parallel-axis theorem (overlaps counted twice).",
        "",
        f"Actuators: a position servo per joint, kp = M_jj (2 pi f_n)^2 with f_n = {_num(SERVO_BANDWIDTH)} Hz and",
        "M_jj the joint-space inertia at the home pose (composite rigid body sum of the inertials below);",
        f'dampratio="{_num(SERVO_DAMPING_RATIO)}" (critical damping). gravcomp="1" on every link: the servos',
        "see no gravity load, so they hold any pose without sag (kinematic study model; no contacts).",
        "Home: q = 0, or the range midpoint for a joint whose range excludes 0.",
    ]
    out = ["<!--", *[f"  {comment_line(line)}".rstrip() for line in header], "-->"]
    out.append(f'<mujoco model="{chain.name}">')
    out.append('  <compiler angle="radian" autolimits="true" eulerseq="xyz"/>')
    out.append("")
    out.append(
        f"  <!-- implicitfast: the servos' damping is integrated implicitly; {_num(TIMESTEP)} s: MuJoCo's default. -->"
    )
    out.append(f'  <option timestep="{_num(TIMESTEP)}" integrator="implicitfast"/>')
    out.append("")
    out.append("  <default>")
    out.append(f'    <default class="{cls}">')
    out.append('      <joint axis="0 0 1"/>')
    out.append("      <!-- Visual only (group 2, no contacts); mass comes from the explicit <inertial>s. -->")
    out.append('      <geom contype="0" conaffinity="0" group="2"/>')
    out.append(f'      <site group="4" size="{_num(SITE_SCALE * radius)}"/>')
    out.append('      <default class="link">')
    out.append(f'        <geom type="capsule" size="{_num(radius)}" material="link"/>')
    out.append("      </default>")
    out.append('      <default class="axis">')
    out.append('        <geom type="cylinder" material="axis"/>')
    out.append("      </default>")
    out.append("    </default>")
    out.append("  </default>")
    out.append("")
    out.append("  <asset>")
    out.append('    <material name="base" rgba="0.35 0.35 0.38 1"/>')
    out.append('    <material name="link" rgba="0.20 0.45 0.80 1"/>')
    out.append('    <material name="axis" rgba="0.85 0.55 0.15 1"/>')
    out.append("  </asset>")
    out.append("")
    out.append("  <worldbody>")
    base = np.asarray(chain.base, dtype=float)
    out.append("    <!-- base: chain.base, the world pose of DH frame 0. -->")
    out.append(f'    <body name="base"{_pose_attributes(base)} childclass="{cls}">')
    indent = "      "
    out += _sites(base_sites, indent)
    out += _geoms(base_solids, indent, material="base")
    closers = ["    </body>"]
    for body in bodies:
        joint = body.joint
        out.append(f"{indent}<!-- {comment_line(f'{body.name}: {body.description}')}. -->")
        pose = _pose_attributes(body.local, (body.alpha, joint.theta))
        out.append(f'{indent}<body name="{body.name}"{pose} gravcomp="1">')
        inner = indent + "  "
        bounds = _limits(joint)
        limits = "" if bounds is None else f' range="{_nums(bounds)}"'
        kind = "slide" if joint.prismatic else "hinge"
        out.append(f'{inner}<joint name="{joint.name}" type="{kind}"{limits}/>')
        inertia = body.inertia
        full = (inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[0, 1], inertia[0, 2], inertia[1, 2])
        out.append(f'{inner}<inertial pos="{_nums(body.com)}" mass="{_num(body.mass)}" fullinertia="{_nums(full)}"/>')
        out += _geoms(body.solids, inner)
        out += _sites(body.sites, inner)
        closers.append(f"{indent}</body>")
        indent = inner
    out += reversed(closers)
    out.append("  </worldbody>")
    out.append("")
    out.append("  <actuator>")
    for body, gain in zip(bodies, kp, strict=True):
        joint = body.joint
        bounds = _limits(joint)
        limits = "" if bounds is None else f' ctrlrange="{_nums(bounds)}"'
        out.append(
            f'    <position name="{joint.name}" joint="{joint.name}" kp="{_num(gain)}"'
            f' dampratio="{_num(SERVO_DAMPING_RATIO)}"{limits}/>'
        )
    out.append("  </actuator>")
    out.append("")
    out.append("  <keyframe>")
    out.append("    <!-- ctrl holds the servos at the home pose. -->")
    out.append(f'    <key name="home" qpos="{_nums(q_home)}" ctrl="{_nums(q_home)}"/>')
    out.append("  </keyframe>")
    out.append("</mujoco>")
    return "\n".join(out) + "\n"


def _geoms(solids: list[_Solid], indent: str, material: str | None = None) -> list[str]:
    out = []
    for s in solids:
        size = "" if s.geom_class == "link" else f' size="{_num(s.radius)}"'
        mat = "" if material is None else f' material="{material}"'
        fromto = _nums([*s.start, *s.end])
        out.append(f'{indent}<geom name="{s.name}" class="{s.geom_class}" fromto="{fromto}"{size}{mat}/>')
    return out


def _sites(sites: list[_Site], indent: str) -> list[str]:
    return [
        f'{indent}<site name="{s.name}"{_pose_attributes(s.pose, s.euler)}/>  <!-- {comment_line(s.comment)} -->'
        for s in sites
    ]
