"""Figures and videos that do not mislead: continuous angles, honest legends and ticks, exact video size."""

import math
import subprocess
import sys

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

from hexabot_sim import params, registry, render
from hexabot_sim.robots.leg import figures as leg_figures
from hexabot_sim.robots.leg import step as leg
from hexabot_sim.robots.leg import step_sweep as leg_sweep
from hexabot_sim.robots.pendulum import pendulum
from hexabot_sim.robots.rrp import velocity as rrp_velocity
from hexabot_sim.simulate import site_trajectory


def _run(name, **sets):
    scenario = registry.get(name)
    p = params.resolve(scenario.params_type, scenario.defaults, {}, {k: str(v) for k, v in sets.items()})
    return scenario.runner(name, p)


@pytest.fixture(scope="module")
def leg_outside():
    """Driven out of the workspace: q2 + q3 crosses 90 deg (gimbal lock of the principal ZYX angles)."""
    return _run("leg-step", amplitude=0.1, omega=0.5236, duration=4, mode="kinematic")


def _drawn(figures):
    for fig in figures.values():
        FigureCanvasAgg(fig).draw()
    return figures


def _zyx(roll, pitch, yaw):
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    return rz @ ry @ rx


def test_foot_orientation_is_continuous_and_is_the_foot_rotation(leg_outside):
    result = leg_outside
    c = result.columns
    foot = site_trajectory(result.model, result.trajectory, "foot").xmat  # (n, 3, 3), world = hip axes here
    # The physical rotation between samples (angle of R_i^T R_i+1).
    rel = np.einsum("nji,njk->nik", foot[:-1], foot[1:])
    sin = 0.5 * np.linalg.norm(
        np.c_[rel[:, 2, 1] - rel[:, 1, 2], rel[:, 0, 2] - rel[:, 2, 0], rel[:, 1, 0] - rel[:, 0, 1]], axis=1
    )
    step = np.arctan2(sin, (np.trace(rel, axis1=1, axis2=2) - 1) / 2)  # accurate for small angles too
    # The CSV's principal angles jump by pi here while the foot turns by milliradians: the case to fix.
    assert np.max(np.abs(np.diff(c["yaw"]))) > 3 and np.max(step) < 0.05
    fig = leg_figures.foot_orientation_figure(result)
    series = [ax.get_lines()[0].get_ydata() for ax in fig.axes[:3]]  # roll, pitch, yaw as plotted
    for values in series:
        assert np.all(np.abs(np.diff(values)) <= step * (1 + 1e-6) + 1e-12)
    roll, pitch, yaw = series
    assert np.allclose(yaw, c["q1"], atol=1e-12) and np.allclose(pitch, c["q2"] + c["q3"], atol=1e-12)
    assert np.allclose(roll, -np.pi / 2, atol=1e-12)
    for i in range(0, len(roll), 97):  # the angles rebuild the measured rotation
        assert np.allclose(_zyx(roll[i], pitch[i], yaw[i]), foot[i], atol=1e-12)
    # The instants where the principal angles jump are marked on the pitch panel.
    jumps = c["t"][1:][np.abs(np.diff(c["yaw"])) > 3]
    marked = [line.get_xdata()[0] for line in fig.axes[1].get_lines()[1:] if line.get_linestyle() == ":"]
    assert len(jumps) >= 1 and all(np.min(np.abs(np.array(marked) - tj)) < 0.01 for tj in jumps)


def _legend_outside_data(fig):
    renderer = FigureCanvasAgg(fig).get_renderer()
    for ax in fig.axes:
        legend = ax.get_legend()
        if legend is not None:
            box, frame = legend.get_window_extent(renderer), ax.get_window_extent(renderer)
            overlap_w = min(box.x1, frame.x1) - max(box.x0, frame.x0)
            overlap_h = min(box.y1, frame.y1) - max(box.y0, frame.y0)
            assert overlap_w <= 1 or overlap_h <= 1, f"legend over the data in '{ax.get_ylabel()}'"


def _readable_ticks(fig):
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            assert axis.get_offset_text().get_text() == "", f"offset label on '{axis.get_label_text()}'"
            for label in axis.get_ticklabels(which="both"):
                assert "times" not in label.get_text(), f"tick label {label.get_text()!r}"


@pytest.mark.slow
def test_leg_figures_legends_ticks_and_labels(leg_outside):
    figures = _drawn(leg.figures(leg_outside))
    for fig in figures.values():
        _legend_outside_data(fig)
        _readable_ticks(fig)
        _labels_inside(fig)
    sing = figures["singularity"].axes
    assert "det J" in sing[0].get_ylabel() and "σ_min" in sing[0].get_ylabel()
    # The world-frame figure states its start in the world frame too.
    assert "world frame: hip at (0, 0, 300) mm, start at (50, 0, 220) mm" in figures["foot_position"].get_suptitle()


@pytest.mark.slow
def test_pendulum_figures_and_energy_label():
    figures = _drawn(pendulum.figures(_run("pendulum", duration=2)))
    for fig in figures.values():
        _legend_outside_data(fig)
        _readable_ticks(fig)
    energy = figures["energy"].axes
    labels = [line.get_label() for line in energy[0].get_lines()]
    assert any("dissipated" in label and "kinetic" in label for label in labels)  # the sum drawn in black
    assert "E(t) − E(0)" in energy[1].get_ylabel()


@pytest.mark.slow
def test_rrp_velocity_draws_mujoco_for_all_six_and_one_unit_per_axis():
    fig = rrp_velocity.figures(_run("rrp-velocity", duration=3))["velocity"]
    FigureCanvasAgg(fig).draw()
    _legend_outside_data(fig)
    _readable_ticks(fig)
    axes = fig.axes
    for ax in axes[:2]:
        dotted = [line for line in ax.get_lines() if line.get_color() == "black"]
        assert len(dotted) == 3  # MuJoCo's site velocity over each of the three components
    units = [ax.get_ylabel()[ax.get_ylabel().rindex("[") :] for ax in axes]
    assert units == ["[m/s]", "[rad/s]", "[rad]", "[m]", "[m²]"]


@pytest.mark.slow
def test_leg_sweep_figure_on_a_small_grid():
    result = _run("leg-sweep", amplitudes="0.03,0.05", omegas="1,2", workers=1)
    fig = _drawn({"sweep": leg_sweep.figures(result)["sweep"]})["sweep"]
    _legend_outside_data(fig)
    _readable_ticks(fig)
    heat = fig.axes[0]
    low, high = heat.get_ylim()
    assert 0 < low < 30 and 50 < high  # no negative amplitudes, every grid row inside
    mesh = heat.collections[0]
    x_edges = mesh.get_coordinates()[0, :, 0]
    assert np.allclose(heat.get_xlim(), (x_edges[0], x_edges[-1]))  # no empty columns
    circles = [line for line in heat.get_lines() if line.get_marker() == "o"]
    assert [(line.get_xdata()[0], line.get_ydata()[0]) for line in circles] == [(1.0, 50.0)]  # only cases in the grid
    one = leg_sweep.figures(_run("leg-sweep", amplitudes="0.03", omegas="1", workers=1))["sweep"]
    assert one.axes[0].get_ylim()[0] > 0 and not [line for line in one.axes[0].get_lines() if line.get_marker() == "o"]


def test_walk_body_figure_plans_the_height_over_the_ground_and_the_legend_says_what_the_command_is():
    """On a slope the planned body height rises with the ground under the body (it was a constant line at the
    flat floor's 98 mm while the body climbed 150 mm); the command's legend names heading hold only when it is on."""
    from hexabot_sim.walking import figures as walk_figures

    result = _run("hexabot-slope", duration=3)
    figures = walk_figures.figures(result)
    c, ground = result.columns, result.extras["terrain"]
    body, planned = figures["body"].axes[0].get_lines()[:2]
    assert planned.get_label().startswith("planned: ground under")
    expected = (ground.height(c["x"], c["y"]) + result.params.stand_height + 0.008) * 1000  # sphere foot 8 mm
    assert np.allclose(planned.get_ydata(), expected, atol=1e-9)
    z = np.asarray(body.get_ydata())
    assert np.ptp(planned.get_ydata()) > 20  # the body climbs, and the plan with it
    assert np.max(np.abs(z - planned.get_ydata())) < 10  # the level body stays near its plan above the slope [mm]
    labels = {line.get_label() for ax in figures["velocity"].axes for line in ax.get_lines()}
    assert "command (with ramp)" in labels and not any("heading hold" in label for label in labels)


@pytest.mark.slow
def test_plots_module_picks_no_matplotlib_backend():
    code = "import matplotlib; matplotlib.use('svg'); import hexabot_sim.plots; print(matplotlib.get_backend())"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip().lower() == "svg"


# ---------------------------------------------------------------------------------------------
# Pendulum: a settling time only once the motion has settled for good.


def test_settling_time_is_not_reported_before_the_motion_settles():
    short = _run("pendulum-damped", duration=1)
    assert short.metrics["settled"].value is False and short.metrics["settling_time"].value is None
    done = _run("pendulum-damped", duration=6)
    settling = done.metrics["settling_time"].value
    assert done.metrics["settled"].value is True and 1.0 < settling < 5.0
    # From then on theta stays within the 2 % band, and the energy left cannot carry it out again.
    c = done.columns
    rest = done.extras["rest_angle"]
    band = 0.02 * abs(c["theta"][0] - rest)
    assert np.all(np.abs(c["theta"][c["t"] >= settling] - rest) <= band)


def test_settled_for_good_uses_the_energy_barrier():
    from hexabot_sim.robots.pendulum.closed_forms import settled_for_good

    def potential(theta):  # m g c = 1 J
        return 1 - math.cos(theta)

    band = 0.1
    barrier = 1 - math.cos(band)
    assert settled_for_good(0.99 * barrier, potential, 0.0, band)
    assert not settled_for_good(1.01 * barrier, potential, 0.0, band)
    assert not settled_for_good(0.0, potential, 0.0, 0.0)


# ---------------------------------------------------------------------------------------------
# Video: exact size, text overlay, framing.


def test_text_overlay_draws_into_the_frame():
    frame = np.zeros((480, 640, 3), np.uint8)
    render.draw_text(frame, ["t = 1.00 s", "θ = 23.32°"])
    lit = frame.max(axis=2) > 200
    ys, xs = np.nonzero(lit)
    assert xs.size > 100 and ys.max() < 0.15 * 480 and xs.max() < 0.3 * 640  # small, top-left
    other = np.zeros_like(frame)
    render.draw_text(other, ["t = 2.00 s", "θ = 23.32°"])
    assert np.any(other != frame)


def test_fit_camera_keeps_every_point_in_view():
    rng = np.random.default_rng(1)
    points = rng.uniform(-1, 1, (200, 3)) * [2.0, 0.5, 1.0] + [1.0, 3.0, 0.5]
    xyaxes = [0.8, 0.6, 0.0, -0.2, 0.27, 0.94]
    for aspect in (4 / 3, 16 / 9):
        eye = render.fit_camera(points, xyaxes, 45.0, aspect=aspect, margin=0.0)
        right = np.array(xyaxes[:3]) / np.linalg.norm(xyaxes[:3])
        up = np.array(xyaxes[3:]) - (np.dot(xyaxes[3:], right)) * right
        up /= np.linalg.norm(up)
        forward = np.cross(up, right)
        rel = points - eye
        depth = rel @ forward
        tan_v = math.tan(math.radians(22.5))
        assert np.all(depth > 0)
        assert np.all(np.abs(rel @ up) / depth <= tan_v * (1 + 1e-9))
        assert np.all(np.abs(rel @ right) / depth <= tan_v * aspect * (1 + 1e-9))
        # Tight: some point touches the edge of the view.
        assert (
            max(np.max(np.abs(rel @ up) / depth) / tan_v, np.max(np.abs(rel @ right) / depth) / tan_v / aspect) > 0.99
        )


def test_video_has_exactly_the_requested_size_and_odd_sizes_are_refused(tmp_path, gl_backend):
    import imageio.v2 as imageio

    result = _run("pendulum", duration=0.5)
    t, qpos = result.trajectory.t, result.trajectory.qpos
    path = tmp_path / "v.mp4"
    frames = render.render_video(
        result.model, t, qpos, path, camera=result.camera, width=330, height=250, fps=10, overlay=result.overlay
    )
    reader = imageio.get_reader(str(path))
    try:
        first, count = reader.get_data(0), reader.count_frames()
    finally:
        reader.close()
    assert first.shape == (250, 330, 3) and count == frames == 6  # 330 x 250 is no multiple of 16: not padded
    assert np.any(first[:20, :80].min(axis=2) > 200)  # the time is written top left
    for width, height in ((641, 480), (640, 481), (0, 480)):
        with pytest.raises(ValueError, match="even"):
            render.render_video(result.model, t, qpos, tmp_path / "odd.mp4", camera="side", width=width, height=height)
    assert not (tmp_path / "odd.mp4").exists()


def _labels_inside(fig):
    """Every axis label and drawn tick label lies inside the figure (the saved PNG shows all of it)."""
    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw(renderer)
    width, height = fig.bbox.width, fig.bbox.height
    for ax in fig.axes:
        texts = [ax.xaxis.label, ax.yaxis.label]
        for axis in (ax.xaxis, ax.yaxis):
            texts += [tick.label1 for tick in axis.get_major_ticks() if tick.get_visible() and tick.label1.get_text()
                      and _shown(axis, tick)]  # fmt: skip
        for text in texts:
            if not text.get_visible() or not text.get_text():
                continue
            box = text.get_window_extent(renderer)
            assert box.x0 >= -0.5 and box.x1 <= width + 0.5 and box.y0 >= -0.5 and box.y1 <= height + 0.5, (
                f"{text.get_text()!r} outside the figure: {box}"
            )


def _shown(axis, tick) -> bool:
    low, high = sorted(axis.get_view_interval())
    return low - 1e-9 * (high - low) <= tick.get_loc() <= high + 1e-9 * (high - low)


@pytest.mark.slow
def test_walk_figures_keep_their_labels_inside_the_figure():
    """The foot-force figure's y labels once sat 9 px left of the figure's edge (cut off in the PNG) when the
    forces' axis ended between two ticks: the tick beyond it (not drawn) still pushed the label left."""
    from hexabot_sim.walking import figures as walk_figures

    result = _run("hexabot-walk", gait="wave", vx=0.05, duration=4, load_sharing="force", feet="pad", swing="quintic")
    for fig in walk_figures.figures(result).values():
        _labels_inside(fig)
