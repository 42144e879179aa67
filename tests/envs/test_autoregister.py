"""The ids registered when a program imports gymnasium, without importing hexabot_sim (envs/ids.py and the .pth)."""

import importlib.metadata
import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

pytest.importorskip("gymnasium", reason="the Gymnasium environments need gymnasium (the rl extra)")

import hexabot_sim.envs.ids as ids

PTH = "hexabot_sim_gymnasium.pth"
IDS = sorted(f"{ids.NAMESPACE}/{name}" for name in ids.ENVS)
SHOW = (
    "import sys, gymnasium\n"
    "print(sorted(k for k in gymnasium.registry if k.startswith('hexabot_sim/')))\n"
    "print('hexabot_sim' in sys.modules, 'mujoco' in sys.modules)\n"
)


def _python(code: str, *flags: str, **env: str) -> list[str]:
    out = subprocess.run(
        [sys.executable, *flags, "-c", code], capture_output=True, text=True, timeout=120, env={**os.environ, **env},
        cwd=Path(__file__).parent,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    return out.stdout.splitlines()


def _installed_pth() -> bool:
    """Whether the installed distribution carries the .pth (a wheel or editable install from pyproject.toml)."""
    try:
        files = importlib.metadata.files("hexabot-sim") or []
    except importlib.metadata.PackageNotFoundError:
        return False
    return any(f.name == PTH for f in files)


def _pth_file() -> Path:
    """The .pth: beside ids.py in a source tree (its source), at site-packages' top where a wheel installed it."""
    here = Path(ids.__file__)
    found = [path for path in (here.with_name(PTH), here.parents[2] / PTH) if path.is_file()]
    assert found, f"no {PTH} beside {here} nor at {here.parents[2]}"
    return found[0]


def test_the_wheel_carries_the_pth_that_loads_ids_py():
    assert "ids.py" in _pth_file().read_text()
    pyproject = Path(ids.__file__).parents[2] / "pyproject.toml"
    if pyproject.is_file():  # a source tree: the wheel's force-include puts it at site-packages' top
        assert f'"hexabot_sim/envs/{PTH}" = "{PTH}"' in pyproject.read_text()


@pytest.mark.skipif(not _installed_pth(), reason="hexabot-sim is not installed with its .pth (source tree on a path)")
def test_importing_gymnasium_alone_registers_the_ids_lazily():
    registered, imported = _python(SHOW)
    assert registered == str(IDS)
    assert imported == "False False"  # strings only: neither hexabot_sim nor MuJoCo is imported to register
    out = _python(
        "import gymnasium\nenv = gymnasium.make('hexabot_sim/HexabotJoints-v0')\nprint(env.reset(seed=0)[0].shape)"
    )
    assert out == ["(54,)"]


@pytest.mark.skipif(not _installed_pth(), reason="hexabot-sim is not installed with its .pth (source tree on a path)")
def test_the_hook_is_off_when_the_user_says_so():
    registered, _ = _python(SHOW, **{ids.OPT_OUT: "1"})
    assert registered == "[]"


def test_the_hook_registers_on_import_and_leaves_gymnasium_whole():
    """The hook as the .pth installs it, in a fresh interpreter whatever the installation: loaded from ids.py's
    path, then gymnasium imported; gymnasium's resources still load through the wrapped loader, and the finder
    is gone from sys.meta_path once it has fired."""
    code = (
        "import importlib.util, sys, importlib.resources\n"
        f"spec = importlib.util.spec_from_file_location('ids_copy', {ids.__file__!r})\n"
        "m = importlib.util.module_from_spec(spec); spec.loader.exec_module(m)\n"
        "m.install_import_hook(); m.install_import_hook()  # twice, as a site dir seen twice does\n"
        "print(sum(getattr(f, 'hexabot_sim_autoregister', False) for f in sys.meta_path))\n"
        + SHOW
        + "print(sum(getattr(f, 'hexabot_sim_autoregister', False) for f in sys.meta_path))\n"
        "print(importlib.resources.files('gymnasium').joinpath('__init__.py').is_file())\n"
    )
    before, registered, imported, after, resources = _python(code, **{ids.OPT_OUT: "0"})
    assert (before, after) == ("1", "0")
    assert registered == str(IDS) and imported == "False False" and resources == "True"


def test_gymnasium_imported_first_is_registered_at_once():
    code = (
        "import importlib.util, sys, gymnasium\n"
        f"spec = importlib.util.spec_from_file_location('ids_copy', {ids.__file__!r})\n"
        "m = importlib.util.module_from_spec(spec); spec.loader.exec_module(m)\n"
        "m.install_import_hook()\n"
        "print(sorted(k for k in gymnasium.registry if k.startswith('hexabot_sim/')))\n"
    )
    assert _python(code, **{ids.OPT_OUT: "0"}) == [str(IDS)]


def test_ids_py_imports_no_more_than_os_and_sys():
    """Loaded at every interpreter start: no import beyond os and sys (without site, which imports those)."""
    code = (
        "import sys\nbefore = set(sys.modules)\n{}\nprint(sorted(set(sys.modules) - before))\n"
    )  # fmt: skip
    load = f"exec(compile(open({ids.__file__!r}).read(), 'ids.py', 'exec'), {{'__name__': 'x'}})"
    assert _python(code.format(load), "-S") == _python(code.format("import os, sys"), "-S")


def test_gymnasium_keeps_its_own_loader_once_imported():
    """The registering loader is a wrapper for the import only: gymnasium's module and spec carry its own loader
    afterwards, so copying, pickling and isinstance checks of them behave as without the hook (the wrapper's
    __getattr__ made copy.deepcopy(gymnasium.__spec__) recurse without end)."""
    code = (
        "import copy, importlib.machinery, importlib.util, pickle, sys\n"
        f"spec = importlib.util.spec_from_file_location('ids_copy', {ids.__file__!r})\n"
        "m = importlib.util.module_from_spec(spec); spec.loader.exec_module(m); m.install_import_hook()\n"
        "import gymnasium\n"
        "loader = gymnasium.__loader__\n"
        "print(isinstance(loader, importlib.machinery.SourceFileLoader), gymnasium.__spec__.loader is loader)\n"
        "print(type(copy.deepcopy(gymnasium.__spec__).loader).__name__, type(copy.copy(loader)).__name__)\n"
        "print(type(pickle.loads(pickle.dumps(loader))).__name__)\n"
    )
    assert _python(code, **{ids.OPT_OUT: "0"}) == [
        "True True",
        "SourceFileLoader SourceFileLoader",
        "SourceFileLoader",
    ]


@pytest.mark.parametrize(("value", "on"), [("", True), ("0", True), ("false", True), ("No", True), (" off ", True),
                                           ("1", False), ("true", False), ("yes", False)])  # fmt: skip
def test_the_opt_out_reads_its_value_as_a_switch(value, on, monkeypatch):
    """HEXABOT_SIM_NO_AUTOREGISTER=false (or no, off, 0, empty) leaves the hook on; any other value turns it off."""
    monkeypatch.setattr(sys, "meta_path", list(sys.meta_path))
    monkeypatch.delitem(sys.modules, "gymnasium", raising=False)  # install_import_hook then installs the finder
    monkeypatch.setenv(ids.OPT_OUT, value)
    ids.install_import_hook()
    assert any(getattr(f, "hexabot_sim_autoregister", False) for f in sys.meta_path) == on


def _through_the_pth(tmp_path: Path, first: Path, code: str) -> subprocess.CompletedProcess:
    """A fresh interpreter without site (-S) that processes this tree's .pth as site does (site.addsitedir), with
    `first` at the front of sys.path, then runs `code` with the interpreter's own packages on sys.path."""
    site_dir = tmp_path / "site"
    site_dir.mkdir(exist_ok=True)
    shutil.copy(_pth_file(), site_dir / PTH)
    purelib = sysconfig.get_paths()["purelib"]
    setup = f"import site, sys; sys.path.insert(0, {str(first)!r}); site.addsitedir({str(site_dir)!r}); "
    setup += f"sys.path.append({purelib!r})\n"
    return subprocess.run(
        [sys.executable, "-S", "-c", setup + code], capture_output=True, text=True, timeout=120,
        env={**os.environ, ids.OPT_OUT: "0"}, cwd=tmp_path,
    )  # fmt: skip


def test_the_pth_installs_the_hook_from_the_first_ids_py_on_sys_path(tmp_path):
    out = _through_the_pth(tmp_path, Path(ids.__file__).parents[2], SHOW)
    assert out.returncode == 0 and out.stderr == ""
    assert out.stdout.splitlines()[0] == str(IDS)


@pytest.mark.parametrize("text", ["def broken(:\n", "NAMESPACE = 'an older ids.py without the hook'\n"])
def test_the_pth_says_nothing_at_start_up_when_that_ids_py_is_broken(tmp_path, text):
    """Every interpreter start runs the .pth: an ids.py it cannot use (a checkout mid-edit first on PYTHONPATH, an
    older one) must not print a traceback at each start of every program (site did, twice with lib64)."""
    other = tmp_path / "other"
    (other / "hexabot_sim" / "envs").mkdir(parents=True)
    (other / "hexabot_sim" / "envs" / "ids.py").write_text(text)
    out = _through_the_pth(tmp_path, other, "print('ran')")
    assert out.returncode == 0 and out.stdout == "ran\n" and out.stderr == ""


def test_the_opt_out_set_by_the_program_before_it_imports_gymnasium_is_heeded():
    """os.environ[HEXABOT_SIM_NO_AUTOREGISTER] = "1" in a program (a notebook's first cell) comes after the
    interpreter's start, where the hook was installed: it is read again when gymnasium is imported."""
    code = (
        "import importlib.util, os, sys\n"
        f"spec = importlib.util.spec_from_file_location('ids_copy', {ids.__file__!r})\n"
        "m = importlib.util.module_from_spec(spec); spec.loader.exec_module(m); m.install_import_hook()\n"
        f"os.environ[{ids.OPT_OUT!r}] = '1'\n"
        "import gymnasium\n"
        "print(sorted(k for k in gymnasium.registry if k.startswith('hexabot_sim/')))\n"
        "print(sum(getattr(f, 'hexabot_sim_autoregister', False) for f in sys.meta_path))\n"
    )
    assert _python(code, **{ids.OPT_OUT: "0"}) == ["[]", "0"]


@pytest.mark.parametrize(("script", "message"), [("hexabot-sim", "hexabot-sim: interrupted; nothing written\n"),
                                                 ("other_program.py", "")])  # fmt: skip
def test_ctrl_c_while_python_starts_ends_as_an_interrupt_not_a_fatal_error(tmp_path, script, message):
    """Found by fuzzing: Ctrl-C in the first ~20 ms of `hexabot-sim run`, while site ran the .pth, printed "Fatal
    Python error: init_import_site" and a traceback, exit 1. Now exit 130, and one line for hexabot-sim (the .pth
    runs at every start of Python in the environment: other programs exit quietly)."""
    fake = tmp_path / "hexabot_sim" / "envs"
    fake.mkdir(parents=True)
    (fake / "ids.py").write_text("raise KeyboardInterrupt  # the Ctrl-C, as it lands while the .pth loads ids.py\n")
    program = tmp_path / script
    program.write_text(f"import sys\nsys.path.insert(0, {str(tmp_path)!r})\nexec({_pth_file().read_text()!r})\n"
                       "print('not reached')\n")  # fmt: skip
    proc = subprocess.run([sys.executable, "-S", str(program)], capture_output=True, text=True, timeout=60)
    assert (proc.returncode, proc.stdout, proc.stderr) == (130, "", message)
