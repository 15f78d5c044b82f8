"""The engine's layers and its import graph are checked, not just declared (issue 23).

``lint-imports`` (import-linter, contracts in pyproject.toml) must pass on the
engine as it is, and must fail when a module imports a layer above its own:
the check is shown to bite, on a copy of the engine with one back-import added.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
LINT = Path(sys.executable).parent / "lint-imports"


def _lint(cwd: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(cwd)}  # the copy's `ros2course` before the installed one
    return subprocess.run([str(LINT), "--config", str(cwd / "pyproject.toml"), "--no-cache"], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=300, check=False)


def test_the_engine_keeps_its_layers_and_has_no_import_cycles() -> None:
    proc = _lint(ROOT)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-2000:]
    assert "BROKEN" not in proc.stdout and proc.stdout.count("KEPT") >= 3


def test_a_back_import_breaks_the_layers_contract(tmp_path: Path) -> None:
    shutil.copytree(ROOT / "course", tmp_path / "ros2course", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    process = tmp_path / "ros2course" / "run" / "process.py"
    # run is below grade: a learner process must not know about results
    process.write_text(process.read_text() + "\n\ndef _late() -> None:\n    from ros2course.grade import results  # noqa\n")
    proc = _lint(tmp_path)
    assert proc.returncode != 0
    assert "the engine's layers BROKEN" in proc.stdout
    assert "ros2course.run.process -> ros2course.grade.results" in proc.stdout
