"""ros2course installs like any Python tool (issue 18): a wheel built from a clean checkout, installed
non-editable into a fresh venv outside the repository, runs the learner's loop on the bundled course.

The venv installs ``ros2course[ros]`` from the wheel with pip, as a learner would (the ROS wheels
come from pip's cache in CI: about a minute). It has no underlay (no ``ros2`` CLI), which
print-forever-node does not need.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

pytestmark = pytest.mark.ros


def _run(argv: list[str], cwd: Path, timeout: float = 600, env: dict | None = None) -> subprocess.CompletedProcess:
    environ = {k: v for k, v in os.environ.items()
               # nothing of the test run's own install may leak into the fresh venv
               if k not in ("ROS2COURSE_CONTENT", "PYTHONPATH", "VIRTUAL_ENV", "AMENT_PREFIX_PATH", "CMAKE_PREFIX_PATH",
                            "LD_LIBRARY_PATH", "ROS_DISTRO", "ROS2COURSE_ENV", "COLCON_PREFIX_PATH",
                            # the ROS wheels re-exec a new interpreter with their LD_LIBRARY_PATH unless this is set
                            "_ROS_WHEELS_BOOTSTRAP_COMPLETE")}
    environ["PATH"] = os.pathsep.join(p for p in environ.get("PATH", "").split(os.pathsep)
                                      if not p.startswith(sys.prefix))
    proc = subprocess.run(argv, cwd=cwd, capture_output=True, text=True, timeout=timeout, check=False,
                          env={**environ, **(env or {}), "COLUMNS": "200"})
    assert proc.returncode == 0, f"{argv}: exit {proc.returncode}\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    return proc


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The wheel, built from a copy of the checkout's tracked and new files (no build/, no egg-info)."""
    files = subprocess.run(["git", "ls-files", "-co", "--exclude-standard"], cwd=ROOT, capture_output=True, text=True,
                           check=True).stdout.split("\n")
    source = tmp_path_factory.mktemp("checkout")
    for name in filter(None, files):
        if (ROOT / name).is_file() and not name.startswith(".venv/"):
            (source / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / name, source / name)
    out = tmp_path_factory.mktemp("dist")
    _run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "--no-build-isolation", "-w", str(out),
          str(source)], cwd=source)
    (built,) = out.glob("ros2course-*.whl")
    return built


def test_the_wheel_holds_only_ros2course_and_the_bundled_course(wheel: Path) -> None:
    names = zipfile.ZipFile(wheel).namelist()
    top = {name.split("/")[0] for name in names}
    assert top == {"ros2course", wheel.name.split("-py3")[0] + ".dist-info"}, top
    course = "ros2course/_courses/tutorial/"
    for part in ("course.yaml", "chapters/print-forever-node/lesson.yaml", "graders/print_forever_node.py",
                 "solutions/src/python_package_with_a_node/setup.py", "tests/fixtures/print-forever-node/"):
        assert any(name.startswith(course + part) for name in names), part
    assert "ros2course/kit/__init__.py" in names
    assert not any("__pycache__" in name or ".egg-info" in name for name in names)


def test_installed_from_the_wheel_the_learner_loop_gives_full_marks(wheel: Path, tmp_path: Path) -> None:
    venv = tmp_path / "venv"
    _run([sys.executable, "-m", "venv", str(venv)], cwd=tmp_path)
    _run([str(venv / "bin" / "python"), "-m", "pip", "install", "--quiet", f"{wheel}[ros]"], cwd=tmp_path, timeout=900)
    site = next((venv / "lib").glob("python3*/site-packages"))
    assert not (site / "course").exists() and not (site / "graders").exists()
    tool = str(venv / "bin" / "ros2course")
    version = _run([tool, "--version"], cwd=tmp_path).stdout
    assert "ros2course 0." in version and f"at {site / 'ros2course' / '_courses' / 'tutorial'}" in version

    _run([tool, "init", "ws"], cwd=tmp_path)
    ws = tmp_path / "ws"
    shown = _run([tool, "next"], cwd=ws)
    assert "terminal-basics" in shown.stdout and (ws / "terminal_basics").is_dir()
    reference = site / "ros2course" / "_courses" / "tutorial" / "solutions" / "src" / "python_package_with_a_node"
    shutil.rmtree(ws / "src" / "python_package_with_a_node", ignore_errors=True)
    shutil.copytree(reference, ws / "src" / "python_package_with_a_node")
    checked = _run([tool, "check", "print-forever-node", "--json"], cwd=ws, timeout=300)
    result = json.loads(checked.stdout)
    assert result["score"] == result["max_score"] > 0, checked.stdout
    listed = _run([tool, "list"], cwd=ws).stdout
    assert "print-forever-node" in listed and "terminal-basics" in listed
