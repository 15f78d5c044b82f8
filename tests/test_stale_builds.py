"""Workspaces as learners leave them (issue 19): install states that make a correct package fail
are repaired by a clean rebuild of that package, and the build check says so.

Each test starts from a workspace built one way (the starter, --merge-install, --symlink-install,
another build type) and then edited, as a learner's is.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from ros2course.builder.colcon import build_packages, colcon_command, stale_metadata
from ros2course.errors import NotGradable
from ros2course.grade.engine import grade_lesson
from ros2course.grade.results import Status
from ros2course.lesson.catalog import load_catalog
from ros2course.lesson.starter import copy_starter
from ros2course.ros import env as env_mod
from tests.conftest import SOLUTIONS

PKG = "stale_demo"


def _env() -> dict[str, str]:
    env = dict(__import__("os").environ)
    env = env_mod.activate(env)
    return env


def _python_package(src: Path, version: str = "0.0.1") -> Path:
    """A minimal ament_python package ``stale_demo`` with one console script."""
    root = src / PKG
    (root / PKG).mkdir(parents=True, exist_ok=True)
    (root / "resource").mkdir(exist_ok=True)
    (root / "resource" / PKG).write_text("")
    (root / PKG / "__init__.py").write_text("")
    (root / PKG / "hello.py").write_text("def main():\n    print('hello')\n")
    (root / "package.xml").write_text(f"""<?xml version="1.0"?>
<package format="3">
  <name>{PKG}</name><version>{version}</version><description>d</description>
  <maintainer email="learner@example.com">a</maintainer><license>MIT</license>
  <export><build_type>ament_python</build_type></export>
</package>
""")
    (root / "setup.py").write_text(f"""from setuptools import setup
setup(name='{PKG}', version='{version}', packages=['{PKG}'],
      data_files=[('share/ament_index/resource_index/packages', ['resource/{PKG}']), ('share/{PKG}', ['package.xml'])],
      entry_points={{'console_scripts': ['hello = {PKG}.hello:main']}})
""")
    return root


def _colcon(root: Path, *extra: str) -> None:
    proc = subprocess.run([*colcon_command(_env()), "build", *extra], cwd=root, env=_env(), capture_output=True,
                          text=True, timeout=300, check=False)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]


@pytest.mark.ros
def test_new_learner_sequence_with_a_changed_version_gets_full_marks(tmp_path: Path) -> None:
    """Starter checked, then the tutorial's files pasted (setup.py version 0.0.0, the starter's 0.0.1), checked
    again: colcon leaves both .egg-info folders and the old one has no entry point. The check repairs it."""
    lesson = load_catalog().get("print-forever-node")
    ws = tmp_path / "ws"
    (ws / "src").mkdir(parents=True)
    copy_starter(lesson, ws)
    first = grade_lesson(lesson, ws)
    assert first.status != Status.PASSED
    package = ws / "src" / "python_package_with_a_node"
    # pasted: fresh modification times, so colcon's own incremental build sees the change (files that keep
    # older times are rebuilt from clean first: tests/test_source_drift.py)
    shutil.copytree(SOLUTIONS / "python_package_with_a_node", package, dirs_exist_ok=True, copy_function=shutil.copy,
                    ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    setup = package / "setup.py"
    setup.write_text(setup.read_text().replace("version='0.0.1'", "version='0.0.0'"))
    second = grade_lesson(lesson, ws)
    assert second.status == Status.PASSED, [(c.id, c.observed) for c in second.checks if not c.passed]
    build = next(c for c in second.checks if c.id == "build")
    assert "versions 0.0.0 and 0.0.1" in build.observed and "rm -rf build/python_package_with_a_node" in build.observed
    assert second.build["repairs"] and stale_metadata(ws, ["python_package_with_a_node"]) == {}


@pytest.mark.ros
def test_a_merge_install_workspace_is_rebuilt_isolated(tmp_path: Path) -> None:
    _python_package(tmp_path / "src")
    _colcon(tmp_path, "--merge-install")
    built = build_packages(tmp_path, [PKG], _env(), tmp_path / "build.log")
    assert built.ok, built.excerpt
    assert len(built.repairs) == 1 and "--merge-install" in built.repairs[0]
    assert (tmp_path / "install" / PKG / "share" / PKG / "package.xml").is_file()


@pytest.mark.ros
def test_a_symlink_install_is_rebuilt_cleanly_and_the_sources_are_untouched(tmp_path: Path) -> None:
    source = _python_package(tmp_path / "src")
    before = {p.relative_to(source): p.read_bytes() for p in source.rglob("*") if p.is_file()}
    _colcon(tmp_path, "--symlink-install")
    assert (tmp_path / "install" / PKG / "share" / PKG / "package.xml").is_symlink()
    built = build_packages(tmp_path, [PKG], _env(), tmp_path / "build.log")
    assert built.ok, built.excerpt
    assert len(built.repairs) == 1 and "--symlink-install" in built.repairs[0]
    assert not (tmp_path / "install" / PKG / "share" / PKG / "package.xml").is_symlink()
    after = {p.relative_to(source): p.read_bytes() for p in source.rglob("*") if p.is_file() and "egg-info" not in str(p)}
    assert after == before


@pytest.mark.ros
def test_a_package_that_changed_build_type_is_rebuilt_cleanly(tmp_path: Path) -> None:
    root = _python_package(tmp_path / "src")
    _colcon(tmp_path)
    manifest = root / "package.xml"
    manifest.write_text(manifest.read_text().replace("ament_python", "ament_cmake").replace(
        "<export>", "<buildtool_depend>ament_cmake</buildtool_depend><export>"))
    (root / "CMakeLists.txt").write_text(f"cmake_minimum_required(VERSION 3.8)\nproject({PKG})\n"
                                         "find_package(ament_cmake REQUIRED)\nament_package()\n")
    (root / "setup.py").unlink()
    built = build_packages(tmp_path, [PKG], _env(), tmp_path / "build.log")
    assert built.ok, built.excerpt
    assert len(built.repairs) == 1 and "was built as a Python package before" in built.repairs[0]
    assert not list((tmp_path / "install" / PKG).glob("lib/python*/site-packages/*.egg-info"))


def test_a_colcon_ignore_left_in_a_package_is_named(tmp_path: Path) -> None:
    root = _python_package(tmp_path / "src")
    (root / "COLCON_IGNORE").touch()
    with pytest.raises(NotGradable) as info:
        build_packages(tmp_path, [PKG], _env(), tmp_path / "build.log")
    assert "COLCON_IGNORE" in info.value.message and f"delete {root / 'COLCON_IGNORE'}" in info.value.hint


@pytest.mark.ros
@pytest.mark.timeout(600)
def test_new_learner_sequence_under_watch_gets_full_marks(tmp_path: Path) -> None:
    """The same sequence as a learner lives it in ``watch``: the starter is checked, then the tutorial's three files
    are saved one by one (setup.py at version 0.0.0), each save re-checked; the last check gives full marks."""
    import os  # noqa: PLC0415
    import sys  # noqa: PLC0415

    import pexpect  # noqa: PLC0415

    def run(cwd: Path, *args: str) -> None:
        proc = subprocess.run([sys.executable, "-m", "ros2course", *args], cwd=cwd, capture_output=True, text=True,
                              timeout=120, check=False, stdin=subprocess.DEVNULL)
        assert proc.returncode == 0, proc.stdout[-1500:] + proc.stderr[-1500:]

    run(tmp_path, "init", "ws")
    ws = tmp_path / "ws"
    ids = load_catalog().ids()
    for _ in range(ids.index("print-forever-node") + 1):
        run(ws, "next")
    package = ws / "src" / "python_package_with_a_node"
    assert package.is_dir()
    child = pexpect.spawn(sys.executable, ["-m", "ros2course", "watch"], cwd=str(ws), encoding="utf-8", timeout=240,
                          dimensions=(60, 200), env={**os.environ, "TERM": "xterm"})
    try:
        child.expect("watching print-forever-node")
        child.expect(r"\d+/15")  # the starter's verdict
        assert "Full marks" not in child.before
        reference = SOLUTIONS / "python_package_with_a_node"
        setup = (reference / "setup.py").read_text().replace("version='0.0.1'", "version='0.0.0'")
        (package / "setup.py").write_text(setup)
        for rel in ("package.xml", "python_package_with_a_node/print_forever_node.py"):
            (package / rel).write_text((reference / rel).read_text())
        child.expect("Full marks", timeout=240)
        child.send("q")
        child.expect(pexpect.EOF, timeout=30)
    finally:
        child.close(force=True)
    assert stale_metadata(ws, ["python_package_with_a_node"]) == {}
