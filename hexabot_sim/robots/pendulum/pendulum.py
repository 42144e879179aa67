"""Simple pendulum (report 000, section 1): undamped, damped, and damped with a spring toward a target."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from hexabot_sim import models, render
from hexabot_sim.budget import step_count
from hexabot_sim.result import Live, Marker, Metric, Progress, ScenarioResult, at_home
from hexabot_sim.robots.pendulum.closed_forms import (
    BARRIER_FLOOR,
    ENERGY_FLOOR,
    SETTLING_BAND,
    energy_warning,
    equilibria,
    exact_period,
    rest_angle,
    settled_for_good,
    settling_time,
    upward_crossings,
)
from hexabot_sim.robots.pendulum.parameters import PendulumParams
from hexabot_sim.simulate import simulate

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


def build_xml(p: PendulumParams, camera_pos: tuple[float, float, float] | None = None) -> str:
    """The pendulum scene with every parameter written in at full precision.

    Args:
        p: The parameters.
        camera_pos: Where the side camera stands [m] (run() frames the swept disc with it); None: far
            enough back that any swing fits.
    """
    root = models.load_tree("pendulum_scene")
    L, r, c = p.length, p.radius, p.length / 2
    height = 1.1 * L  # pivot height above the floor
    target = math.radians(p.target_deg)

    models.find(root, "option").attrib.update(
        timestep=models.fmt(p.timestep), integrator=p.integrator, gravity=models.fmt((0, 0, -p.gravity))
    )
    link = models.find(root, "body", "link")
    link.set("pos", models.fmt((0, 0, height)))
    i_perp = p.mass * (3 * r**2 + L**2) / 12
    models.find(link, "inertial").attrib.update(
        pos=models.fmt((0, 0, -c)), mass=models.fmt(p.mass), diaginertia=models.fmt((i_perp, i_perp, p.mass * r**2 / 2))
    )
    models.find(link, "joint", "hinge").attrib.update(
        damping=models.fmt(p.damping), stiffness=models.fmt(p.stiffness), springref=models.fmt(target)
    )
    models.find(link, "geom", "rod").attrib.update(fromto=models.fmt((0, 0, 0, 0, 0, -L)), size=models.fmt(r))
    models.find(link, "site", "tip").set("pos", models.fmt((0, 0, -L)))
    models.find(root, "key", "home").set("qpos", models.fmt(math.radians(p.theta0_deg)))

    # Visual-only stand, marker and camera scale with the link so the whole swing stays in frame.
    s = 0.1 * L
    models.find(root, "geom", "post").attrib.update(
        pos=models.fmt((0, s, height / 2)), size=models.fmt((0.25 * s, 0.25 * s, height / 2))
    )
    models.find(root, "geom", "axle").attrib.update(
        fromto=models.fmt((0, -0.5 * s, height, 0, s, height)), size=models.fmt(max(0.2 * s, 0.6 * r))
    )
    if p.stiffness > 0:
        models.find(root, "geom", "target_marker").attrib.update(
            fromto=models.fmt((0, -0.4 * s, height, L * math.sin(target), -0.4 * s, height - L * math.cos(target))),
            size=models.fmt(0.1 * s),
        )
    else:
        models.remove(root, "geom", "target_marker")
    reach = 1.15 * (L + r)
    if camera_pos is None:
        camera_pos = (0, -reach / math.tan(math.radians(22.5)), height)
    models.find(root, "camera", "side").set("pos", models.fmt(camera_pos))
    models.find(root, "geom", "floor").set("size", models.fmt((3 * reach, 3 * reach, 0.05)))
    # A backdrop where the floor ends, so the sky behind the swing is not a black half of the frame.
    models.find(root, "geom", "backdrop").attrib.update(
        pos=models.fmt((0, 3 * reach, 3 * reach)), size=models.fmt((3 * reach, 3 * reach, 0.01 * reach))
    )
    models.find(root, "statistic").attrib.update(center=models.fmt((0, 0, height)), extent=models.fmt(2 * reach))
    return models.to_xml(root)


def run(name: str, p: PendulumParams, progress: Progress | None = None) -> ScenarioResult:
    """Simulates the pendulum from rest at theta0 and derives energies and metrics."""
    from scipy.integrate import cumulative_simpson

    xml = build_xml(p)
    model, data = at_home(xml)
    traj = simulate(model, data, step_count(p.duration, p.timestep), progress=progress)

    # Constants read back from the compiled model: I about the hinge (mass matrix) and m g c.
    hinge = model.joint("hinge")
    qadr, dadr = int(hinge.qposadr[0]), int(hinge.dofadr[0])
    mass_matrix = np.zeros((model.nv, model.nv))  # (nv, nv), constant for a hinge about a fixed axis
    mujoco.mj_fullM(model, data, mass_matrix)
    inertia = float(mass_matrix[dadr, dadr])
    link = model.body("link").id
    mgc = float(model.body_mass[link] * -model.opt.gravity[2] * np.linalg.norm(model.body_ipos[link]))
    k, b = float(model.jnt_stiffness[hinge.id]), float(model.dof_damping[dadr])
    target = float(model.qpos_spring[qadr])

    t = traj.t
    theta = traj.qpos[:, qadr]
    omega = traj.qvel[:, dadr]
    e_kin = 0.5 * inertia * omega**2
    e_grav = mgc * (1 - np.cos(theta))
    e_spring = 0.5 * k * (theta - target) ** 2
    e_diss = cumulative_simpson(b * omega**2, x=t, initial=0.0)  # energy the damper has taken out
    e_total = e_kin + e_grav + e_spring + e_diss

    theta0 = float(theta[0])
    metrics: dict[str, Metric] = {
        "theta0_deg": Metric(math.degrees(theta0), "deg", "initial angle"),
        "final_theta_deg": Metric(math.degrees(theta[-1]), "deg", "angle at the end of the run"),
        "final_omega": Metric(float(omega[-1]), "rad/s", "angular velocity at the end of the run"),
        "max_abs_omega": Metric(float(np.abs(omega).max()), "rad/s", "largest angular speed"),
        "inertia_pivot": Metric(inertia, "kg*m^2", "moment of inertia about the hinge (from the compiled model)"),
        "energy_initial": Metric(
            float(e_total[0]), "J", "total mechanical energy at t = 0 (zero: hanging, spring at rest)"
        ),
    }
    e_scale = float(e_total[0])
    # The energies are differences of order (m g c + k) [J]: rounding alone leaves ~1e-16 of that in each, so E(0)
    # must be far above it (1e-8 of it: a swing of ~0.01 deg) for the relative balance error to mean anything.
    least = ENERGY_FLOOR * (mgc + k)
    drift = float(np.max(np.abs(e_total - e_total[0])) / e_scale) if e_scale > max(least, 0.0) else None
    why = "" if drift is not None else (
        f"; null here: E(0) = {e_scale:.3g} J is not above {least:.3g} J, where rounding would dominate the ratio"
    )  # fmt: skip
    metrics["energy_drift_rel"] = Metric(
        drift, "1", "max |E(t) + dissipated(t) - E(0)| / E(0): energy balance error of the integration" + why
    )

    # Period: the large-amplitude closed form exists for the free (b = 0, k = 0) pendulum.
    rest = rest_angle(k, mgc, target, near=float(theta[-1]))
    crossings = upward_crossings(t, theta, omega, level=rest if rest is not None else 0.0)
    measured = float((crossings[-1] - crossings[0]) / (len(crossings) - 1)) if len(crossings) >= 2 else None
    metrics["period_measured"] = Metric(measured, "s", "mean time between upward crossings of the rest angle")
    # Small oscillations about the rest angle: the restoring stiffness there is k + m g c cos(rest) (a spring pulls
    # the rest angle off 0, where gravity's part is m g c; 2 pi sqrt(I / (m g c + k)) is right only at rest = 0).
    linear = k + mgc * math.cos(rest if rest is not None else 0.0)  # [N*m/rad]
    if mgc > 0 and linear > 0:
        metrics["period_small_angle"] = Metric(
            2 * math.pi * math.sqrt(inertia / linear),
            "s",
            "2 pi sqrt(I / (k + m g c cos(rest))): undamped small oscillations about the rest angle",
        )
    if b == 0 and k == 0 and mgc > 0 and abs(theta0) < math.pi and omega[0] == 0:
        exact = exact_period(inertia, mgc, theta0)
        metrics["period_exact"] = Metric(exact, "s", "4 sqrt(I / m g c) K(sin^2(theta0 / 2)), elliptic integral")
        rel = abs(measured - exact) / exact if measured is not None else None
        metrics["period_rel_error"] = Metric(rel, "1", "|measured - exact| / exact")

    if rest is not None and b > 0:
        metrics["rest_angle_predicted_deg"] = Metric(
            math.degrees(rest), "deg", "stable solution of k (theta - target) + m g c sin(theta) = 0"
        )
        metrics["rest_angle_error"] = Metric(
            abs(float(theta[-1]) - rest), "rad", "|final angle - predicted rest angle|"
        )
        band = SETTLING_BAND * abs(theta0 - rest)

        def potential(angle: float) -> float:
            return mgc * (1 - math.cos(angle)) + 0.5 * k * (angle - target) ** 2

        energy_left = float(e_kin[-1] + e_grav[-1] + e_spring[-1]) - potential(rest)
        # A start at (or within rounding of) the rest angle leaves a band, and an energy barrier at its edges, that
        # rounding alone would cross or not: the verdict would be noise ("settled = false" for a pendulum at rest).
        barrier = min(potential(rest - band), potential(rest + band)) - potential(rest)
        meaningful = barrier > BARRIER_FLOOR * (mgc + k)
        settled = settled_for_good(energy_left, potential, rest, band) if meaningful else None
        why = "" if meaningful else (
            f"; null here: theta0 is {abs(theta0 - rest):.3g} rad from the rest angle, and the band's energy barrier "
            f"{barrier:.3g} J is not above {BARRIER_FLOOR * (mgc + k):.3g} J, where rounding would decide"
        )  # fmt: skip
        metrics["settled"] = Metric(
            settled,
            "",
            "true if at the end of the run the energy left is below the potential at the edges of the 2 % band "
            "around the rest angle, so theta can never leave the band again" + why,
        )
        metrics["settling_time"] = Metric(
            settling_time(t, theta, rest, band) if settled else None,
            "s",
            "time after which |theta - rest| stays within 2 % of |theta0 - rest| for good; null if the motion "
            "has not settled by the end of the run (settled = false)" + why,
        )
    if k > 0:
        metrics["target_deg"] = Metric(math.degrees(target), "deg", "spring equilibrium position")

    markers = []
    if rest is not None and b > 0:  # the predicted rest angle, drawn in green beside the link
        pivot = model.body("link").pos
        length = float(np.linalg.norm(model.site("tip").pos))
        markers.append(
            Marker(
                start=(pivot[0], pivot[1] - 0.02 * length, pivot[2]),
                end=(
                    pivot[0] + length * math.sin(rest),
                    pivot[1] - 0.02 * length,
                    pivot[2] - length * math.cos(rest),
                ),
                radius=0.008 * length,
                rgba=(0.1, 0.75, 0.2, 0.6),
            )
        )

    # Frame the side camera on the disc the link swept (and the markers), then recompile: the
    # camera is visual only, so the recompiled model steps exactly like the one just run.
    pivot, reach = model.body("link").pos.copy(), float(np.linalg.norm(model.site("tip").pos)) + p.radius
    shown = np.r_[theta[:: max(1, len(theta) // 2000)], theta[-1:]]
    shown = np.r_[shown, [a for a in (rest if b > 0 else None, target if k > 0 else None) if a is not None]]
    envelope = np.r_[pivot[None], pivot + reach * np.c_[np.sin(shown), np.zeros_like(shown), -np.cos(shown)]]
    camera = model.camera("side")
    axes = model.cam_mat0[camera.id].reshape(3, 3)  # columns: the camera's x (right), y (up), z axes

    # Video text under the time: the angle, and what the coloured markers are.
    theta_deg, marks = np.degrees(theta), []
    if rest is not None and b > 0:
        marks.append(f"green: rest {math.degrees(rest):.2f}°")
    if k > 0:
        marks.append(f"red: target {math.degrees(target):.1f}°")
    overlay = [lambda i: f"θ = {theta_deg[i]:7.2f}°  ω = {omega[i]:6.2f} rad/s"]
    overlay += [lambda i, text=text: text for text in marks]
    camera_pos = render.fit_camera(
        envelope, [*axes[:, 0], *axes[:, 1]], float(model.cam_fovy[camera.id]), text_lines=1 + len(overlay)
    )
    xml = build_xml(p, camera_pos=tuple(camera_pos.tolist()))
    model = mujoco.MjModel.from_xml_string(xml)
    summary = {
        "pendulum-undamped": ["period_measured", "period_exact", "period_rel_error", "energy_drift_rel"],
        "pendulum-damped": ["settling_time", "settled", "final_theta_deg", "energy_drift_rel"],
        "pendulum": [
            "target_deg",
            "rest_angle_predicted_deg",
            "final_theta_deg",
            "rest_angle_error",
            "settling_time",
            "settled",
        ],
    }.get(name, ["final_theta_deg", "energy_drift_rel"])
    return ScenarioResult(
        scenario=name,
        params=p,
        model=model,
        model_xml=xml,
        trajectory=traj,
        columns={
            "t": t,
            "theta": theta,
            "omega": omega,
            "energy_kinetic": e_kin,
            "energy_gravity": e_grav,
            "energy_spring": e_spring,
            "energy_dissipated": e_diss,
            "energy_total": e_total,
        },
        column_units={
            "t": "s",
            "theta": "rad",
            "omega": "rad/s",
            "energy_kinetic": "J",
            "energy_gravity": "J",
            "energy_spring": "J",
            "energy_dissipated": "J",
            "energy_total": "J",
        },
        metrics=metrics,
        summary=[m for m in summary if m in metrics],
        camera="side",
        markers=markers,
        overlay=overlay,
        extras={
            "rest_angle": rest,
            "target": target if k > 0 else None,
            "stable_equilibria": equilibria(k, mgc, target, float(theta.min()) - 7.0, float(theta.max()) + 7.0),
        },
        warnings=[w for w in [energy_warning(drift, inertia, mgc, k, b, float(model.opt.timestep), p.integrator)] if w],
    )


# ---------------------------------------------------------------------------------------------
# Figures (matplotlib is imported only when they are drawn: `hexabot-sim list` never loads it)


def _title(result: ScenarioResult, text: str) -> str:
    p = result.params
    return (
        f"{result.scenario}: {text}\n"
        f"m = {p.mass:g} kg, L = {p.length:g} m, b = {p.damping:g} N·m·s/rad, k = {p.stiffness:g} N·m/rad, "
        f"θ0 = {p.theta0_deg:g}°"
    )


def _angle_lines(ax: Axes, result: ScenarioResult, horizontal: bool = True) -> None:
    """Draws the spring target and the predicted rest angle."""
    from hexabot_sim import plots

    draw = ax.axhline if horizontal else ax.axvline
    target, rest = result.extras.get("target"), result.extras.get("rest_angle")
    if target is not None:
        draw(target, label=f"spring target {math.degrees(target):.1f}°", **plots.TARGET_STYLE)
    if rest is not None and result.params.damping > 0:
        draw(rest, label=f"predicted rest angle {math.degrees(rest):.2f}°", **plots.REST_STYLE)


def figures(result: ScenarioResult) -> dict[str, Figure]:
    """Angle and angular velocity vs time (report Figs. 5-8), phase portrait, energy balance."""
    from hexabot_sim import plots

    c = result.columns
    t, theta, omega = c["t"], c["theta"], c["omega"]
    figures: dict[str, Figure] = {}

    fig, (ax1, ax2) = plots.figure(2, 1, figsize=(9, 6.5), sharex=True)
    ax1.plot(t, theta, color="tab:blue", label="θ")
    _angle_lines(ax1, result)
    ax1.set_ylabel("angle θ [rad]")
    deg = ax1.secondary_yaxis("right", functions=(np.degrees, np.radians))
    deg.set_ylabel("θ [deg]")
    plots.legend_above(ax1)
    ax1.grid(alpha=0.3)
    ax2.plot(t, omega, color="tab:orange")
    ax2.set_ylabel("angular velocity ω [rad/s]")
    ax2.set_xlabel("time t [s]")
    ax2.grid(alpha=0.3)
    fig.suptitle(_title(result, "angle and angular velocity"), fontsize=plots.TITLE_FONTSIZE)
    figures["angle_velocity"] = fig

    fig, ax = plots.figure(figsize=(6.5, 6))
    ax.plot(theta, omega, color="tab:purple", linewidth=0.9)
    ax.plot(theta[0], omega[0], "o", color="black", label="start")
    ax.plot(theta[-1], omega[-1], "s", color="tab:purple", label="end")
    _angle_lines(ax, result, horizontal=False)
    ax.set_xlabel("angle θ [rad]")
    ax.set_ylabel("angular velocity ω [rad/s]")
    plots.legend_above(ax, ncol=2)
    ax.grid(alpha=0.3)
    fig.suptitle(_title(result, "phase portrait"), fontsize=plots.TITLE_FONTSIZE)
    figures["phase"] = fig

    fig, (ax1, ax2) = plots.figure(2, 1, figsize=(9, 7), sharex=True, gridspec_kw={"height_ratios": [3, 1.4]})
    ax1.plot(t, c["energy_kinetic"], label="kinetic ½Iω²")
    ax1.plot(t, c["energy_gravity"], label="gravity mgc(1 − cos θ)")
    if result.params.stiffness > 0:
        ax1.plot(t, c["energy_spring"], label="spring ½k(θ − θ_t)²")
    if result.params.damping > 0:
        ax1.plot(t, c["energy_dissipated"], label="dissipated by damping ∫bω² dt")
    ax1.plot(t, c["energy_total"], color="black", linewidth=2, label="sum E(t): kinetic + potential + dissipated")
    ax1.set_ylabel("energy [J]")
    plots.legend_above(ax1, ncol=2)
    ax1.grid(alpha=0.3)
    fig.suptitle(_title(result, "energy"), fontsize=plots.TITLE_FONTSIZE)
    e0 = c["energy_total"][0]
    if e0 > 0:
        err = np.abs(c["energy_total"] - e0) / e0
        ax2.semilogy(t[1:], np.maximum(err[1:], 1e-17), color="black", linewidth=0.8)
        ax2.set_ylabel("|E(t) − E(0)| / E(0)\n(energy balance error)")
    else:
        ax2.text(0.5, 0.5, "E(0) = 0: no relative balance error", transform=ax2.transAxes, ha="center")
    ax2.set_xlabel("time t [s]")
    ax2.grid(alpha=0.3, which="both")
    figures["energy"] = fig
    return figures


def live(p: PendulumParams) -> Live:
    """The pendulum released from theta0, for the interactive viewer (no controller: it swings freely)."""
    model, data = at_home(build_xml(p))
    hinge = model.joint("hinge")
    qadr, dadr = int(hinge.qposadr[0]), int(hinge.dofadr[0])
    link = model.body("link").id
    mgc = float(model.body_mass[link] * -model.opt.gravity[2] * np.linalg.norm(model.body_ipos[link]))
    markers = []
    rest = rest_angle(p.stiffness, mgc, math.radians(p.target_deg), near=math.radians(p.theta0_deg))
    if rest is not None and p.damping > 0:  # the predicted rest angle, green beside the link (as in the video)
        pivot, length = model.body("link").pos, float(np.linalg.norm(model.site("tip").pos))
        end = (pivot[0] + length * math.sin(rest), pivot[1] - 0.02 * length, pivot[2] - length * math.cos(rest))
        markers.append(
            Marker((pivot[0], pivot[1] - 0.02 * length, pivot[2]), end, 0.008 * length, (0.1, 0.75, 0.2, 0.6))
        )

    def step() -> None:
        mujoco.mj_step(model, data)

    return Live(
        model, data, step, p.timestep, p.duration, camera="side", markers=markers,
        overlay=[lambda d: f"theta = {math.degrees(d.qpos[qadr]):7.2f} deg  omega = {d.qvel[dadr]:6.2f} rad/s"],
    )  # fmt: skip
