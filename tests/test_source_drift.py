"""A verdict is about the files the learner has now, whatever their timestamps (issue 36).

colcon, CMake and setuptools rebuild a file only when it is newer than what they built. Files that
keep an older time (unzip, tar x, cp -a, rsync -a, a restore), files dated in the future, removed
files, renamed and moved packages and interrupted builds all leave a build that is not the sources.
The engine records what it built by content and rebuilds from clean what colcon would get wrong.

The integration tests build real packages with colcon and run what was installed; the learner's
files are compared before and after (never modified).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from ros2course.builder.colcon import RECORDS, BuildRecords, build_packages, overlay_env
from ros2course.builder.sources import (
    MAX_SOURCE_BYTES,
    PackageRecord,
    PackageSources,
    SourceFile,
    rebuild_reason,
    scan_package,
)
from ros2course.errors import NotGradable
from ros2course.grade.engine import grade_lesson
from ros2course.grade.results import Status
from ros2course.lesson.catalog import load_catalog
from ros2course.lesson.starter import copy_starter
from ros2course.ros import env as env_mod
from tests.conftest import SOLUTIONS

DAY = 24 * 3600
PKG = "drift_demo"


def _env() -> dict[str, str]:
    env = env_mod.activate()
    return env


def _snapshot(folder: Path) -> dict[str, tuple[bytes, int]]:
    """Every file under ``folder``: bytes and mtime (ns), to prove the learner's files were left alone."""
    return {str(p.relative_to(folder)): (p.read_bytes(), p.stat().st_mtime_ns)
            for p in sorted(folder.rglob("*")) if p.is_file() and ".egg-info" not in str(p)
            and "__pycache__" not in str(p)}


def _dated(path: Path, offset: float) -> None:
    """Date ``path`` ``offset`` seconds from now (negative: in the past), as unzip or cp -a leave it."""
    when = time.time() + offset
    os.utime(path, (when, when))


def _package(src: Path, name: str = PKG, message: str = "one", folder: str | None = None) -> Path:
    """An ament_python package with a console script ``hello`` printing ``message``, a module ``extra``
    and a launch file (installed by a glob, as the tutorial's setup.py does)."""
    root = src / (folder or name)
    (root / name).mkdir(parents=True, exist_ok=True)
    (root / "resource").mkdir(exist_ok=True)
    (root / "launch").mkdir(exist_ok=True)
    (root / "resource" / name).write_text("")
    (root / name / "__init__.py").write_text("")
    (root / name / "hello.py").write_text(f"def main():\n    print({message!r})\n")
    (root / name / "extra.py").write_text("VALUE = 1\n")
    (root / "launch" / "demo.launch.py").write_text("from launch import LaunchDescription\n\n\n"
                                                    "def generate_launch_description():\n"
                                                    "    return LaunchDescription([])\n")
    (root / "package.xml").write_text(f"""<?xml version="1.0"?>
<package format="3">
  <name>{name}</name><version>0.0.1</version><description>d</description>
  <maintainer email="learner@example.com">a</maintainer><license>MIT</license>
  <export><build_type>ament_python</build_type></export>
</package>
""")
    (root / "setup.py").write_text(f"""from glob import glob
from setuptools import setup
setup(name='{name}', version='0.0.1', packages=['{name}'],
      data_files=[('share/ament_index/resource_index/packages', ['resource/{name}']),
                  ('share/{name}', ['package.xml']), ('share/{name}/launch', glob('launch/*.launch.py'))],
      entry_points={{'console_scripts': ['hello = {name}.hello:main']}})
""")
    return root


def _build(ws: Path, name: str = PKG):
    result = build_packages(ws, [name], _env(), ws / "log" / f"build-{time.monotonic_ns()}.log")
    assert result.ok, result.excerpt
    return result


def _run(ws: Path, code: str) -> str:
    """Run ``code`` with python in the workspace's overlay (what `source install/setup.bash` gives)."""
    env = overlay_env(ws, _env())
    proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                          timeout=60, check=False)
    return (proc.stdout + proc.stderr).strip()


def _hello(ws: Path, name: str = PKG) -> str:
    return _run(ws, f"from {name}.hello import main; main()")


# --- the rule, without colcon ----------------------------------------------------------------------


def _sources(**files: tuple[str, int]) -> PackageSources:
    return PackageSources("src/p", {rel: SourceFile(sha, 0o644, mtime) for rel, (sha, mtime) in files.items()})


def test_the_rule_trusts_only_changes_dated_after_the_last_build() -> None:
    built = PackageRecord("src/p", _sources(a=("1", 100)).digest, {"a": ["1", 0o644, 100]}, built_ns=1000)
    assert rebuild_reason(built, _sources(a=("1", 5)), built=True) is None  # same content, any time
    assert rebuild_reason(built, _sources(a=("2", 2000)), built=True) is None  # newer: colcon sees it
    assert "older than the last build: a" in rebuild_reason(built, _sources(a=("2", 900)), built=True)
    assert "older than the last build: b" in rebuild_reason(built, _sources(a=("1", 100), b=("3", 10)), built=True)
    assert "removed since the last build" in rebuild_reason(built, _sources(b=("1", 2000)), built=True)
    assert rebuild_reason(None, _sources(a=("1", 5)), built=False) is None  # nothing built: nothing stale
    assert "without ros2course's record" in rebuild_reason(None, _sources(a=("1", 5)), built=True)
    moved = PackageSources("src/q", _sources(a=("1", 100)).files)
    assert "moved from src/p to src/q" in rebuild_reason(built, moved, built=True)
    stopped = PackageRecord("src/p", built.digest, built.files, built_ns=1000, complete=False)
    assert "interrupted" in rebuild_reason(stopped, _sources(a=("1", 100)), built=True)
    mode = PackageSources("src/p", {"a": SourceFile("1", 0o755, 100)})  # chmod +x: no new time at all
    assert "older than the last build" in rebuild_reason(built, mode, built=True)
    future = PackageRecord("src/p", "x", {"a": ["1", 0o644, 10 * 10**9]}, built_ns=1000)  # built from a future file
    assert "dated in the future" in rebuild_reason(future, _sources(a=("2", 5 * 10**9)), built=True)


def test_scan_reads_content_not_times_and_skips_caches(tmp_path: Path) -> None:
    root = _package(tmp_path / "src")
    (root / PKG / "__pycache__").mkdir()
    (root / PKG / "__pycache__" / "hello.cpython-311.pyc").write_bytes(b"x")
    (root / f"{PKG}.egg-info").mkdir()
    (root / ".git").mkdir()
    (root / ".git" / "HEAD").write_text("ref")
    first = scan_package(tmp_path, root)
    assert first.folder == f"src/{PKG}" and "drift_demo/hello.py" in first.files
    assert not any("__pycache__" in rel or "egg-info" in rel or ".git" in rel for rel in first.files)
    _dated(root / PKG / "hello.py", -DAY)
    assert scan_package(tmp_path, root).digest == first.digest  # a new time alone changes nothing
    (root / PKG / "hello.py").write_text("def main():\n    print('two')\n")
    assert scan_package(tmp_path, root).digest != first.digest
    (root / "setup.py").chmod(0o755)
    assert scan_package(tmp_path, root).files["setup.py"].mode == 0o755


def test_unreadable_looping_special_and_huge_files_are_named_never_graded(tmp_path: Path, monkeypatch) -> None:
    root = _package(tmp_path / "src")
    loop = root / "loop"
    loop.symlink_to(root)
    with pytest.raises(NotGradable) as info:
        scan_package(tmp_path, root)
    assert "symbolic link loop" in info.value.message and str(loop) in info.value.message
    loop.unlink()
    (root / "self").symlink_to(root / "self")
    with pytest.raises(NotGradable) as info:
        scan_package(tmp_path, root)
    assert "symbolic link loop" in info.value.message and "self" in info.value.message
    (root / "self").unlink()
    os.mkfifo(root / "pipe")
    with pytest.raises(NotGradable) as info:  # never opened: a fifo would block the check
        scan_package(tmp_path, root)
    assert "not a regular file" in info.value.message and "pipe" in info.value.message
    (root / "pipe").unlink()
    with open(root / "bag.db3", "wb") as handle:  # sparse: no disk used
        handle.truncate(MAX_SOURCE_BYTES + 1)
    with pytest.raises(NotGradable) as info:
        scan_package(tmp_path, root)
    assert "bag.db3" in info.value.message and "MiB" in info.value.message and "src/" in info.value.hint
    (root / "bag.db3").unlink()
    secret = root / "secret.txt"
    secret.write_text("s")
    real_open = open

    def refusing(path, *args, **kwargs):  # root reads every file: refuse this one as a learner's chmod 000 would
        if str(path) == str(secret):
            raise PermissionError(13, "Permission denied")
        return real_open(path, *args, **kwargs)

    monkeypatch.setattr("builtins.open", refusing)
    with pytest.raises(NotGradable) as info:
        scan_package(tmp_path, root)
    assert "secret.txt: Permission denied" in info.value.message and "chmod" in info.value.hint


def test_a_broken_source_gives_no_verdict_through_the_check(tmp_path: Path) -> None:
    """Through grade_lesson: the lesson is not gradable, the message names the file, no check is judged."""
    lesson = load_catalog().get("print-forever-node")
    ws = tmp_path / "ws"
    shutil.copytree(SOLUTIONS / "python_package_with_a_node", ws / "src" / "python_package_with_a_node")
    os.mkfifo(ws / "src" / "python_package_with_a_node" / "fifo")
    result = grade_lesson(lesson, ws)
    assert result.status == Status.NOT_GRADABLE and not result.checks
    assert "fifo" in result.message and "not a regular file" in result.message


# --- each way a workspace drifts from its sources, with real colcon builds ----------------------------


@pytest.mark.ros
def test_files_older_than_the_build_are_built(tmp_path: Path) -> None:
    root = _package(tmp_path / "src")
    assert _build(tmp_path).repairs == []
    assert _hello(tmp_path) == "one"
    mine = _snapshot(tmp_path / "src")
    hello = root / PKG / "hello.py"
    hello.write_text("def main():\n    print('two')\n")
    _dated(hello, -DAY)  # as unzip / cp -a leave it
    mine = _snapshot(tmp_path / "src")
    result = _build(tmp_path)
    assert not result.cached and len(result.repairs) == 1
    assert "rebuilt from clean (drift_demo: sources changed but were older than the last build: " \
           "drift_demo/hello.py)" in result.repairs[0]
    assert _hello(tmp_path) == "two"
    assert _snapshot(tmp_path / "src") == mine  # never touched: no `touch`, no new times
    again = _build(tmp_path)
    assert again.cached and again.repairs == []


@pytest.mark.ros
def test_files_dated_in_the_future_do_not_hide_a_later_edit(tmp_path: Path) -> None:
    root = _package(tmp_path / "src")
    for path in root.rglob("*"):
        if path.is_file():
            _dated(path, DAY)  # a clock skew: the files come from a machine a day ahead
    _build(tmp_path)
    assert _hello(tmp_path) == "one"
    hello = root / PKG / "hello.py"
    hello.write_text("def main():\n    print('two')\n")  # now: older than the build of the future-dated copy
    result = _build(tmp_path)
    assert "dated in the future" in result.repairs[0] and "drift_demo/hello.py" in result.repairs[0]
    assert _hello(tmp_path) == "two"
    hello.write_text("def main():\n    print('three')\n")
    _build(tmp_path)
    assert _hello(tmp_path) == "three"


@pytest.mark.ros
def test_a_removed_module_and_launch_file_leave_the_install(tmp_path: Path) -> None:
    root = _package(tmp_path / "src")
    _build(tmp_path)
    assert _run(tmp_path, f"import {PKG}.extra; print({PKG}.extra.VALUE)") == "1"
    share = tmp_path / "install" / PKG / "share" / PKG / "launch" / "demo.launch.py"
    assert share.is_file()
    (root / PKG / "extra.py").unlink()
    (root / "launch" / "demo.launch.py").unlink()
    result = _build(tmp_path)
    assert "files were removed since the last build" in result.repairs[0]
    assert "No module named 'drift_demo.extra'" in _run(tmp_path, f"import {PKG}.extra")
    assert not share.exists()


@pytest.mark.ros
def test_a_renamed_package_no_longer_satisfies_imports(tmp_path: Path) -> None:
    root = _package(tmp_path / "src")
    _build(tmp_path)
    shutil.rmtree(root)
    _package(tmp_path / "src", name="drift_renamed")
    result = _build(tmp_path, "drift_renamed")
    assert any("install/ held drift_demo, no longer in src/" in line for line in result.repairs)
    assert not (tmp_path / "install" / PKG).exists() and not (tmp_path / "build" / PKG).exists()
    assert "No module named 'drift_demo'" in _run(tmp_path, "import drift_demo")
    assert _hello(tmp_path, "drift_renamed") == "one"


@pytest.mark.ros
def test_a_package_moved_between_folders_is_rebuilt_from_its_new_place(tmp_path: Path) -> None:
    _package(tmp_path / "src", folder="first/drift_demo")
    _build(tmp_path)
    shutil.move(str(tmp_path / "src" / "first"), str(tmp_path / "src" / "second"))
    result = _build(tmp_path)
    assert "it moved from src/first/drift_demo to src/second/drift_demo" in result.repairs[0]
    assert _hello(tmp_path) == "one"


@pytest.mark.ros
def test_a_cmake_package_moved_and_edited_with_old_times_builds_and_runs_the_new_code(tmp_path: Path) -> None:
    """CMake keeps the source folder in its cache (a moved package would not configure) and compiles by time."""
    root = tmp_path / "src" / "one" / "drift_cmake"
    root.mkdir(parents=True)
    (root / "package.xml").write_text("""<?xml version="1.0"?>
<package format="3"><name>drift_cmake</name><version>0.0.1</version><description>d</description>
  <maintainer email="learner@example.com">a</maintainer><license>MIT</license>
  <export><build_type>cmake</build_type></export></package>
""")
    (root / "CMakeLists.txt").write_text("cmake_minimum_required(VERSION 3.8)\nproject(drift_cmake CXX)\n"
                                         "add_executable(say say.cpp)\ninstall(TARGETS say DESTINATION bin)\n")
    (root / "say.cpp").write_text('#include <cstdio>\nint main() { std::puts("one"); }\n')
    _build(tmp_path, "drift_cmake")
    say = tmp_path / "install" / "drift_cmake" / "bin" / "say"
    assert subprocess.run([say], capture_output=True, text=True, check=True).stdout == "one\n"
    (root / "say.cpp").write_text('#include <cstdio>\nint main() { std::puts("two"); }\n')
    _dated(root / "say.cpp", -DAY)
    result = _build(tmp_path, "drift_cmake")
    assert "older than the last build: say.cpp" in result.repairs[0]
    assert subprocess.run([say], capture_output=True, text=True, check=True).stdout == "two\n"
    shutil.move(str(tmp_path / "src" / "one"), str(tmp_path / "src" / "two"))
    result = _build(tmp_path, "drift_cmake")
    assert "moved from src/one/drift_cmake to src/two/drift_cmake" in result.repairs[0]


@pytest.mark.ros
def test_an_interrupted_build_is_rebuilt_from_clean(tmp_path: Path) -> None:
    root = _package(tmp_path / "src")
    _build(tmp_path)
    (root / PKG / "hello.py").write_text("def main():\n    print('two')\n")
    stopped = build_packages(tmp_path, [PKG], _env(), tmp_path / "log" / "stopped.log", timeout=0.05)
    assert not stopped.ok and "build stopped after" in (tmp_path / "log" / "stopped.log").read_text()
    assert BuildRecords.load(tmp_path).get(PKG).complete is False
    result = _build(tmp_path)
    assert "its last build was interrupted" in result.repairs[0]
    assert _hello(tmp_path) == "two"
    assert BuildRecords.load(tmp_path).get(PKG).complete is True


@pytest.mark.ros
def test_a_build_made_outside_the_engine_is_rebuilt_once_then_trusted(tmp_path: Path) -> None:
    """The learner's own `colcon build` leaves no record: the first check rebuilds from clean, says so, then
    a fresh edit is an ordinary incremental build."""
    root = _package(tmp_path / "src")
    proc = subprocess.run([str(Path(sys.executable).parent / "colcon"), "build"], cwd=tmp_path, env=_env(),
                          capture_output=True, text=True, timeout=300, check=False)
    assert proc.returncode == 0, proc.stdout[-2000:]
    assert not (tmp_path / "build" / RECORDS).exists()
    first = _build(tmp_path)
    assert "without ros2course's record" in first.repairs[0]
    (root / PKG / "hello.py").write_text("def main():\n    print('two')\n")
    second = _build(tmp_path)
    assert second.repairs == [] and not second.cached
    assert _hello(tmp_path) == "two"


# --- the course walk in miniature: three lessons in one workspace -------------------------------------

WALK = (("print-forever-node", "python_package_with_a_node"),
        ("custom-interfaces", "package_with_interfaces"),
        ("cpp-node", "cpp_package_with_a_node"))


@pytest.mark.ros
@pytest.mark.timeout(1500)
@pytest.mark.parametrize("offset", [-DAY, DAY], ids=["files-a-day-old", "files-a-day-ahead"])
def test_course_walk_with_kept_times_gets_full_marks(tmp_path: Path, offset: float) -> None:
    """As a learner who unzips the correct files (times kept) over their workspace: for an ament_python node,
    the interface package and a C++ package, the starter is checked, then the correct files are put in with
    ``shutil.copy2`` from files dated ``offset`` from now, and checked again: full marks each time. Then one
    fresh edit that breaks the node is seen (a build of future-dated files must not hide it)."""
    catalog = load_catalog()
    ws = tmp_path / "ws"
    (ws / "src").mkdir(parents=True)
    staged = tmp_path / "staged"
    for lesson_id, package in WALK:
        lesson = catalog.get(lesson_id)
        copy_starter(lesson, ws)
        first = grade_lesson(lesson, ws)
        assert first.status != Status.PASSED, lesson_id
        shutil.copytree(SOLUTIONS / package, staged / package, ignore=shutil.ignore_patterns("__pycache__"))
        for path in (staged / package).rglob("*"):
            _dated(path, offset)
        shutil.copytree(staged / package, ws / "src" / package, dirs_exist_ok=True, copy_function=shutil.copy2)
        mine = _snapshot(ws / "src")
        second = grade_lesson(lesson, ws)
        assert second.status == Status.PASSED, (lesson_id, [(c.id, c.observed) for c in second.checks if not c.passed])
        build = next(c for c in second.checks if c.id == "build")
        if offset < 0:
            assert "rebuilt from clean" in build.observed and build.observed.count("rebuilt from clean") == 1
        assert _snapshot(ws / "src") == mine
    node = ws / "src" / "python_package_with_a_node" / "python_package_with_a_node" / "print_forever_node.py"
    node.write_text(node.read_text().replace("Printed", "Wrote"))  # a fresh edit, dated now
    broken = grade_lesson(catalog.get("print-forever-node"), ws)
    assert broken.status == Status.FAILED
    assert not next(c for c in broken.checks if c.id == "log_format").passed


@pytest.mark.ros
def test_a_hand_in_never_brings_its_own_record_of_what_its_build_holds(tmp_path: Path) -> None:
    """`grade` builds a hand-in from its sources alone: a build/ and install/ it brings, even with a record that
    claims they hold its sources (made by hand, or by a stale build), are rebuilt from clean."""
    from ros2course.batch.archive import Submission, prepare  # noqa: PLC0415 - batch sits above build

    student = tmp_path / "alice"
    root = _package(student / "src")
    _build(student)
    (root / PKG / "hello.py").write_text("def main():\n    print('two')\n")
    _dated(root / PKG / "hello.py", -DAY)
    forged = BuildRecords.load(student)
    forged.put(PKG, PackageRecord.of(scan_package(student, root)))  # claims the build holds 'two'
    forged.save()
    assert _build(student).cached and _hello(student) == "one"  # what trusting the record would grade
    ws = prepare(Submission("alice", student, ""), tmp_path / "scratch")
    assert not (ws / "build" / RECORDS).exists() and (ws / "install" / PKG).is_dir()
    result = _build(ws)
    assert "without ros2course's record" in result.repairs[0]
    assert _hello(ws) == "two"
