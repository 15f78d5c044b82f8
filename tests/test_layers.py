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


def function_level_imports_without_a_reason(root: Path) -> list[str]:
    """``file:line`` of every import inside a function of ``root`` whose ``noqa: ... PLC0415`` gives no reason
    (``PLC0415 - why``): the habit pyproject's ruff section states (issue 38), which ruff itself cannot check."""
    import ast  # noqa: PLC0415 - only this helper parses

    found = []
    for path in sorted(root.rglob("*.py")):
        lines = path.read_text(encoding="utf-8").split("\n")
        for node in ast.walk(ast.parse("\n".join(lines))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                for inner in ast.walk(node):
                    text = " ".join(lines[inner.lineno - 1:inner.end_lineno]) if isinstance(
                        inner, (ast.Import, ast.ImportFrom)) else None
                    if text is not None and "PLC0415 -" not in text:
                        found.append(f"{path.relative_to(root.parent)}:{inner.lineno}")
    return sorted(set(found))


def test_every_import_inside_a_function_says_why(tmp_path: Path) -> None:
    assert function_level_imports_without_a_reason(ROOT / "course") == []
    bare = tmp_path / "course" / "m.py"
    bare.parent.mkdir()
    bare.write_text("def f():\n    import json  # noqa: PLC0415\n    import os  # noqa: PLC0415 - why\n")
    assert function_level_imports_without_a_reason(tmp_path / "course") == ["course/m.py:2"]
