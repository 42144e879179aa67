"""The walking controllers' compiled kernels (hexabot_sim/control/kernels.py).

The walking hexabot runs `resolved_rate.rate_steps` compiled by numba, the single leg of leg-step the
same source as plain Python: both must give the same joint commands, including the damped singular
neighbourhood, the speed and acceleration limits and braking before the joint ranges.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys

import numpy as np
import pytest
from helpers import walk_params

from hexabot_sim.control import kernels
from hexabot_sim.control.resolved_rate import ResolvedRateGains, step_constants
from hexabot_sim.robots.hexabot import model as hx


@pytest.mark.parametrize("acceleration", [200.0, math.inf])
def test_compiled_rate_step_equals_the_python_one(acceleration):
    rng = np.random.default_rng(7)
    lower, upper = hx.JOINT_LOWER, hx.JOINT_UPPER
    k = step_constants(hx.DEFAULT_LAYOUT.geometry, ResolvedRateGains(50.0, 0.01, 0.01, 5.0, acceleration), lower, upper)
    n = 600  # legs, 3 joints each
    q = rng.uniform(np.tile(lower, n), np.tile(upper, n))
    q[2:300:3] = rng.uniform(0.0, 1e-3, 100)  # near the stretched-leg singularity (q3 = 0)
    q[0:150:3] = np.tile(lower, 50)[0::3] + rng.uniform(0, 0.01, 50)  # coxa near its lower limit
    cmd = q + rng.normal(0, 0.01, q.size)
    cmd = np.clip(cmd, np.tile(lower, n), np.tile(upper, n))
    dq = rng.uniform(-5.0, 5.0, q.size)  # the previous step's rates, inside the speed limit
    feed = rng.normal(0, 3.0, q.size)  # includes rates far beyond the speed limit
    previous, start = dq.copy(), cmd.copy()
    cmd_py, dq_py = cmd.tolist(), dq.tolist()
    kernels.rate_steps.py_func(k, q.tolist(), cmd_py, dq_py, feed.tolist(), 0.002)
    kernels.rate_steps(np.array(k), q, cmd, dq, feed, 0.002)
    np.testing.assert_allclose(cmd, cmd_py, rtol=0, atol=1e-12)
    np.testing.assert_allclose(dq, dq_py, rtol=0, atol=1e-9)
    # The limits were exercised, and held.
    assert np.abs(dq).max() <= 5.0 + 1e-9
    if math.isinf(acceleration):
        assert (np.abs(dq).reshape(-1, 3).max(axis=1) > 5.0 - 1e-9).sum() > 10
    else:
        # Away from the ranges (beyond the braking zone v^2 / 2a), the command's acceleration is limited.
        zone = 5.0**2 / (2 * acceleration)
        lo, hi = np.tile(lower, n) + zone, np.tile(upper, n) - zone
        free = ((start > lo) & (start < hi) & (cmd > lo) & (cmd < hi)).reshape(-1, 3).all(axis=1)
        change = np.abs(dq - previous).reshape(-1, 3).max(axis=1)[free]
        assert change.max() <= acceleration * 0.002 + 1e-9
        assert (change > acceleration * 0.002 - 1e-9).sum() > 10


@pytest.mark.slow
def test_kernels_work_where_no_cache_directory_is_writable():
    """A read-only install with no writable user cache: numba cannot cache, the kernels compile per process."""
    code = (
        "import numba.core.caching as c\n"
        "def refuse(self):\n"
        "    raise PermissionError('read-only')\n"
        "c._CacheLocator.ensure_cache_path = refuse\n"
        "import numpy as np\n"
        "from hexabot_sim.control import kernels\n"
        "assert type(kernels.plane_fit._cache).__name__ == 'NullCache', kernels.plane_fit._cache\n"
        "out = np.zeros(3)\n"
        "x, y, z = np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0]), np.array([1.0, 3.0, 4.0])\n"
        "ok = kernels.plane_fit(x, y, z, 3, out)\n"
        "print(ok, out.tolist())\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env=os.environ)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["True", "[1.0,", "2.0,", "3.0]"]


def test_kernels_compile_outside_the_signal_hold(monkeypatch):
    """The controllers' loaders compile the kernels with stop signals not held: a cold compile takes tens of seconds
    under load, and a SIGTERM then waited for all of it (a minute; the run must end within seconds)."""
    from hexabot_sim import signals
    from hexabot_sim.control import gait
    from hexabot_sim.control import walker as control

    held = []
    monkeypatch.setattr(kernels, "warm_up", lambda *groups: held.append(signals.HOLD[0]))
    monkeypatch.setattr(gait, "_KERNELS", [])
    assert control.kernels() is kernels
    gait._kernels()
    assert held == [0, 0]


@pytest.fixture
def clean_signals():
    from hexabot_sim import signals

    signals.reset()
    yield signals
    signals.reset()


@pytest.mark.parametrize("where", ["compile", "failed compile"])
def test_a_stop_request_swallowed_in_the_compile_stops_it_at_numbas_next_pass(monkeypatch, clean_signals, where):
    """A SIGTERM whose handler ran in the __del__ of one of numba's LLVM objects (its exception dropped by Python)
    stops the compile at numba's next compiler pass: the cold compile went on with every kernel, a minute under load
    (found by fuzzing). Simulated as test_pool does: the stop request recorded, its exception gone."""
    import signal

    import numba

    signals = clean_signals
    compiled = []

    def compile_all():
        signals.RECEIVED_SIGNALS.append(signal.SIGTERM)  # received; its exception never left numba's __del__

        @numba.njit
        def twice(x):
            return 2.0 * x

        if where == "failed compile":
            raise RuntimeError("no compiled object yet")  # the cache is not retried, nor the error reported
        twice(1.0)
        compiled.append(twice.signatures)

    from hexabot_sim.control import compliance_kernels  # the first kernels warm_up compiles

    monkeypatch.setattr(compliance_kernels, "compile_all", compile_all)
    monkeypatch.setattr(kernels, "_WARM", set())
    saved = [(k, k._cache) for k in kernels._all_kernels()]
    try:
        with pytest.raises(signals.Interrupted) as raised:
            kernels.warm_up(*kernels.GROUPS)
    finally:
        for k, cache in saved:
            k._cache = cache
    assert raised.value.signum == signal.SIGTERM
    assert compiled == [] and not kernels._WARM


def test_warm_up_compiles_what_a_walk_uses():
    """After a walk on rough ground and one on the flat, each kernel the controllers call has the one signature
    warm_up compiled (a walk passing other argument types would compile again, in the middle of the walk)."""
    from hexabot_sim import params, registry
    from hexabot_sim.result import at_home
    from hexabot_sim.simulate import simulate
    from hexabot_sim.walking import scene as hexabot_scene

    for name in ("hexabot-rough", "hexabot-walk"):
        scenario = registry.get(name)
        p = params.resolve(scenario.params_type, scenario.defaults, {"duration": 3.0})
        model, data = at_home(hexabot_scene.build_xml(p))
        simulate(model, data, 50, controller=hexabot_scene.make_controller(p, model, data))
    from hexabot_sim.control import plan_kernels as plan

    for kernel in (kernels.servo, kernels.targets, kernels.ground_step, plan.segments, plan.targets, plan.flags,
                   plan.hip_targets):  # fmt: skip
        assert len(kernel.signatures) == 1, (kernel, kernel.signatures)


def test_a_walk_compiles_only_the_kernels_it_runs(monkeypatch):
    """The force control's and the admittance's kernels were compiled for every walk: a first default walk paid for
    all three groups (37 s cold here; its own: 15-20 s, scripts/bench.py's compile line). Each walk now compiles its
    own groups, once per process."""
    from hexabot_sim.result import at_home
    from hexabot_sim.walking import scene as hexabot_scene

    compiled = []
    monkeypatch.setattr(kernels, "_compile_each", lambda groups: compiled.append(groups))
    monkeypatch.setattr(kernels, "_WARM", set())
    for options, groups in (({}, ("walk",)), ({"load_sharing": "force"}, ("force",)), ({}, None),
                            ({"load_sharing": "admittance", "touchdown": "sensed"}, ("admittance",))):  # fmt: skip
        p = walk_params(duration=3.0, **options)
        model, data = at_home(hexabot_scene.build_xml(p))
        hexabot_scene.make_controller(p, model, data)
        assert compiled.pop() == groups if groups else compiled == []
    assert kernels._WARM == {"walk", "force", "admittance"}
    with pytest.raises(ValueError, match="kernel groups"):
        kernels.warm_up("forces")


def _warm_up_in_a_new_process(cache, prelude=""):
    code = prelude + "from hexabot_sim.control import kernels\nkernels.warm_up()\nprint('warm')\n"
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, env=env)


@pytest.mark.slow
def test_an_unusable_numba_cache_does_not_stop_a_walk(tmp_path):
    """A corrupted cache file (truncated, foreign) or a full disk under the cache: the kernels are compiled in
    memory with a one-line note naming the folder (they ended the run as an internal error, found by fuzzing)."""
    cache = tmp_path / "cache"
    # The kernels warm_up compiles first (the admittance's): the full compile fails at once on their unreadable
    # index, so the test pays for one compile in memory, not a cached one before it as well.
    one = "from hexabot_sim.control import compliance_kernels\ncompliance_kernels.compile_all()\n"
    subprocess.run(
        [sys.executable, "-c", one], check=True, timeout=300, env={**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    )
    index = list(cache.rglob("*.nbi"))  # the admittance's, which the full compile finds and cannot read
    assert index
    for path in index:
        path.write_bytes(b"\x0cnot a pickle")
    # warm_up's real path (numba's load fails, every kernel's cache turned off, compiled again in memory, the note)
    # over the admittance's kernels only: the whole set compiled in memory took a minute of the suite under load.
    only = (
        "from hexabot_sim.control import compliance_kernels, kernels\n"
        "kernels._all_kernels = lambda: compliance_kernels.KERNELS\n"
        "kernels._compile_each = lambda groups: compliance_kernels.compile_all()\n"
    )
    done = _warm_up_in_a_new_process(cache, prelude=only)
    assert done.returncode == 0 and done.stdout.split() == ["warm"], done.stderr
    assert done.stderr.startswith("hexabot-sim: note: numba's cache in ") and done.stderr.count("\n") == 1
    assert "could not be used (UnpicklingError" in done.stderr and str(cache) in done.stderr


def test_a_full_disk_under_the_cache_compiles_in_memory_with_a_note(monkeypatch, capsys):
    """numba's cache save failing (ENOSPC): warm_up retries with every kernel's cache off and says so in one line.
    (The compile itself is real in the test above; here the first attempt fails as numba's save does.)"""
    import errno

    from numba.core.caching import NullCache

    calls = []

    def compile_all(groups):
        calls.append([type(k._cache) for k in kernels._all_kernels()])
        if len(calls) == 1:
            raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(kernels, "_compile_all", compile_all)
    monkeypatch.setattr(kernels, "_WARM", set())
    saved = [(k, k._cache) for k in kernels._all_kernels()]
    try:
        kernels.warm_up()
    finally:
        for k, cache in saved:
            k._cache = cache
    err = capsys.readouterr().err
    assert len(calls) == 2 and all(t is NullCache for t in calls[1]) and not all(t is NullCache for t in calls[0])
    assert err.startswith("hexabot-sim: note: numba's cache in ") and err.count("\n") == 1
    assert "could not be used (OSError: [Errno 28] No space left on device)" in err and kernels._WARM == {"walk"}


def test_admittance_reference_is_the_least_norm_force_distribution():
    """The stance feet's reference forces carry the total with no moment about the origin, and of all such
    forces have the least weighted norm sum F_i^2 / w_i: numpy's least-squares solution of the same equations in
    G = F / sqrt(w) (the pseudo-inverse of A sqrt(W))."""
    from hexabot_sim.control import compliance_kernels

    rng = np.random.default_rng(3)
    for n in (3, 4, 5, 6):
        x, y = rng.uniform(-0.2, 0.2, n), rng.uniform(-0.2, 0.2, n)
        for w in (np.ones(n), rng.uniform(0.05, 1.0, n)):
            out = np.empty(n)
            compliance_kernels.reference(x, y, w, 17.0, out)
            a = np.vstack([np.ones(n), x, y])  # (3, n): total force, moments about y and x
            g = np.linalg.lstsq(a * np.sqrt(w), np.array([17.0, 0.0, 0.0]), rcond=None)[0]
            np.testing.assert_allclose(out, np.sqrt(w) * g, rtol=1e-9, atol=1e-12)
    out = np.empty(3)
    line = np.array([0.0, 0.1, 0.2])
    compliance_kernels.reference(line, line, np.ones(3), 9.0, out)  # collinear feet: equal shares
    np.testing.assert_allclose(out, 3.0)


def test_admittance_yields_to_an_overloaded_foot_and_springs_back():
    """A constant force error e on a stance foot settles its offset at e / K (D dz/dt + K dz = e); in swing, with
    no force, the offset returns to zero; the feed correction is K_task dz + dz/dt on the foot's z only."""
    import mujoco

    from hexabot_sim import models
    from hexabot_sim.control import compliance_kernels
    from hexabot_sim.control.compliance import Admittance, AdmittanceSettings
    from hexabot_sim.robots.hexabot.walk import HEXABOT

    layout = HEXABOT.layout
    model = mujoco.MjModel.from_xml_path(str(models.model_path("hexabot_scene")))
    settings = AdmittanceSettings(damping=600.0, stiffness=2000.0)
    adm = Admittance(model, layout.legs, layout.hip_positions(), layout.yaws, 50.0, 0.002, 10.0, settings)
    sensors = np.zeros(model.nsensordata)
    adr = [model.sensor_adr[model.sensor(f"{leg}_touch").id] for leg in layout.legs]
    row = layout.neutral_feet_hip().ravel()
    stance = np.ones(6, dtype=bool)
    sensors[adr] = 3.0
    sensors[adr[0]] = 9.0  # lf carries 6 N more than the others
    for _ in range(3000):  # 6 s: 20 times D / K = 0.3 s
        extra = adm.update(sensors, row, stance)
    ref = np.empty(6)
    feet = layout.neutral_feet_body()
    compliance_kernels.reference(feet[:, 0].copy(), feet[:, 1].copy(), np.ones(6), sensors[adr].sum(), ref)
    np.testing.assert_allclose(adm.offsets, (sensors[adr] - ref) / 2000.0, atol=1e-8)
    assert adm.offsets[0] > 0.002  # lifted: the overloaded foot yields
    np.testing.assert_allclose(extra[2::3], 50.0 * adm.offsets, atol=1e-6)
    assert not extra[0::3].any() and not extra[1::3].any()
    sensors[adr] = 0.0
    for _ in range(1000):
        adm.update(sensors, row, np.zeros(6, dtype=bool))
    np.testing.assert_allclose(adm.offsets, 0.0, atol=1e-9)
