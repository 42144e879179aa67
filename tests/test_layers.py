"""The package's layers are a contract (pyproject.toml [tool.importlinter]): no import runs up, no cycle."""

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
pytest.importorskip("importlinter", reason="import-linter (the 'test' extra) checks the layers")


def lint(root: Path) -> subprocess.CompletedProcess:
    code = "import sys; from importlinter.cli import lint_imports_command; sys.exit(lint_imports_command())"
    return subprocess.run(
        [sys.executable, "-c", code, "--config", str(root / "pyproject.toml"), "--no-cache"],
        cwd=root,
        env={"PYTHONPATH": str(root), "PATH": "/usr/bin:/bin"},
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_the_layer_contracts_are_kept():
    done = lint(ROOT)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]
    assert "0 broken" in done.stdout


@pytest.mark.slow
@pytest.mark.parametrize(
    ("module", "line", "contract"),
    [
        ("errors.py", "from hexabot_sim import cli", "layers"),  # an import that runs up
        ("robots/leg/step.py", "from hexabot_sim.robots.hexabot import walk", "robots are independent"),
        ("kinematics/dh.py", "import mujoco", "kinematics and terrain are pure numpy"),
    ],
)
def test_a_broken_contract_is_caught(tmp_path, module, line, contract):
    """The check bites: a copy of the package with one forbidden import fails it, naming the contract."""
    shutil.copytree(ROOT / "hexabot_sim", tmp_path / "hexabot_sim", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    path = tmp_path / "hexabot_sim" / module
    path.write_text(path.read_text() + f"\n{line}  # noqa\n")
    done = lint(tmp_path)
    assert done.returncode != 0
    assert f"{contract}" in done.stdout and "BROKEN" in done.stdout, done.stdout[-3000:]


def test_test_modules_import_the_shared_helpers_as_ci_can():
    """tests/ is on the path as a folder (pyproject's pythonpath), not a package: `from tests.helpers import ...`
    works only where the repository root happens to be on sys.path (an editable install), and failed on a clean
    clone in CI; `from helpers import ...` works everywhere."""
    tests = Path(__file__).parent
    line = re.compile(r"^\s*(from|import) tests\.", re.MULTILINE)
    wrong = [str(p.relative_to(tests)) for p in tests.rglob("*.py") if line.search(p.read_text(encoding="utf-8"))]
    assert wrong == [], wrong
