"""A course is a unit (issue 18): its manifest, finding it, scaffolding lessons, workspaces that follow one course.

No ROS needed: these run the CLI on the catalog and the progress file only.
``tests/test_second_course.py`` grades the test course with real nodes.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from ros2course.errors import CourseError, LessonFormatError
from ros2course.grade.engine import load_grader
from ros2course.lesson import bundled_course
from ros2course.lesson.catalog import Catalog
from ros2course.lesson.courses import find_course, installed_courses, load_manifest
from ros2course.dev.scaffold import new_lesson

ROOT = Path(__file__).resolve().parent.parent
LAB_COURSE = ROOT / "tests" / "data" / "lab_course"


def ros2course(*args: str, cwd: Path, env: dict | None = None) -> subprocess.CompletedProcess:
    """``ros2course ARGS`` as a user types it, in this process (typer's CliRunner: no process boundary is
    under test here, issue 23); no ROS2COURSE_CONTENT from the test run leaks in."""
    from conftest import run_cli_in_process

    return run_cli_in_process(*args, cwd=cwd, env={"ROS2COURSE_CONTENT": None, **(env or {})})


def test_the_tutorial_course_is_bundled_and_registered() -> None:
    assert (bundled_course() / "course.yaml").is_file()
    manifest = load_manifest(bundled_course())
    assert manifest.id == "ros2-tutorial" and manifest.ros_distro == "jazzy"
    assert "ros2-tutorial" in installed_courses()
    assert find_course("ros2-tutorial") == bundled_course()
    # the manifest orders the catalog, and names every lesson folder
    assert Catalog(bundled_course() / "chapters").ids() == manifest.lessons


def test_a_malformed_manifest_names_the_file_the_field_and_a_hint(tmp_path: Path) -> None:
    course = tmp_path / "broken"
    shutil.copytree(LAB_COURSE, course)
    manifest = course / "course.yaml"
    manifest.write_text(manifest.read_text().replace('version: "0.1.0"', "version: one"))
    with pytest.raises(LessonFormatError) as info:
        load_manifest(course)
    assert str(manifest) in info.value.message and "version" in info.value.message and info.value.hint
    # a lesson the manifest lists but no folder holds
    manifest.write_text(manifest.read_text().replace("version: one", 'version: "0.1.0"') + "  - hello-nod\n")
    load_manifest.cache_clear()
    with pytest.raises(LessonFormatError) as info:
        Catalog(course / "chapters")
    assert "lessons: 'hello-nod'" in info.value.message and "hello-node" in info.value.hint
    # and the other course still works
    assert Catalog(bundled_course() / "chapters").ids()[0] == "terminal-basics"


def test_a_course_written_for_another_grading_api_is_refused(tmp_path: Path) -> None:
    course = tmp_path / "future"
    shutil.copytree(LAB_COURSE, course)
    (course / "course.yaml").write_text((course / "course.yaml").read_text().replace('kit: "2"', 'kit: "7"'))
    with pytest.raises(LessonFormatError, match="grading API 7"):
        load_manifest(course)


def test_two_courses_never_see_each_others_graders(tmp_path: Path) -> None:
    copy = tmp_path / "lab_copy"
    shutil.copytree(LAB_COURSE, copy)
    (copy / "graders" / "hello_node.py").write_text((copy / "graders" / "hello_node.py").read_text()
                                                    .replace('NODE = "hello_node"', 'NODE = "other_node"'))
    mine, theirs = load_grader("hello_node", LAB_COURSE), load_grader("hello_node", copy)
    assert mine is not theirs and mine.NODE == "hello_node" and theirs.NODE == "other_node"
    with pytest.raises(CourseError, match="graders/hello_node.py cannot be imported"):
        load_grader("hello_node", bundled_course())
    assert "graders" not in sys.modules  # no global `graders` package


def test_new_lesson_scaffolds_a_complete_lesson_and_never_overwrites(tmp_path: Path) -> None:
    course = tmp_path / "my-course"
    written = new_lesson(course, "first-node", "My first node")
    names = {p.relative_to(course).as_posix() for p in written}
    assert {"course.yaml", "graders/__init__.py", "graders/first_node.py", "chapters/first-node/lesson.yaml",
            "fixtures/first-node/never-registered.yaml", "solutions/src/first_node_pkg/setup.py",
            "chapters/first-node/starter/src/first_node_pkg/first_node_pkg/first_node.py"} <= names
    new_lesson(course, "second-step")
    assert load_manifest(course).lessons == ["first-node", "second-step"]
    assert Catalog(course / "chapters").ids() == ["first-node", "second-step"]
    lesson = Catalog(course / "chapters").get("first-node")
    assert lesson.title == "My first node" and len(lesson.hints) >= 3
    assert {c.id for c in load_grader("first_node", course).CHECKS} == {"build", "executable", "node_name"}
    before = (course / "graders" / "first_node.py").read_text()
    with pytest.raises(CourseError, match="exists already"):
        new_lesson(course, "first-node")
    with pytest.raises(CourseError, match="kebab-case"):
        new_lesson(course, "First_Node")
    assert (course / "graders" / "first_node.py").read_text() == before


def test_a_workspace_follows_its_course_and_refuses_another(tmp_path: Path) -> None:
    init = ros2course("init", "--course", str(LAB_COURSE), "ws", cwd=tmp_path)
    assert init.returncode == 0, init.stderr
    ws = tmp_path / "ws"
    record = json.loads((ws / ".ros2course" / "progress.json").read_text())["course"]
    assert record == {"id": "lab-course", "version": "0.1.0", "path": str(LAB_COURSE)}
    listed = ros2course("list", cwd=ws)  # no --course: the workspace's own course
    assert listed.returncode == 0 and "hello-node" in listed.stdout and "terminal-basics" not in listed.stdout
    nxt = ros2course("next", cwd=ws)
    assert nxt.returncode == 0, nxt.stderr
    assert (ws / "src" / "hello_node_pkg" / "setup.py").is_file()
    progress = (ws / ".ros2course" / "progress.json").read_text()
    other = ros2course("--course", "ros2-tutorial", "list", cwd=ws)
    assert other.returncode != 0
    assert "follows course lab-course 0.1.0, not ros2-tutorial" in other.stderr.replace("\n", " ")
    assert (ws / ".ros2course" / "progress.json").read_text() == progress  # nothing lost


def test_a_moved_course_is_named_with_how_to_get_it_back(tmp_path: Path) -> None:
    course = tmp_path / "lab"
    shutil.copytree(LAB_COURSE, course)
    assert ros2course("init", "--course", str(course), "ws", cwd=tmp_path).returncode == 0
    course.rename(tmp_path / "moved")
    gone = ros2course("list", cwd=tmp_path / "ws")
    assert gone.returncode != 0
    assert "follows course lab-course 0.1.0, which is not at" in gone.stderr.replace("\n", " ")
    assert "--course PATH" in gone.stderr
    back = ros2course("--course", str(tmp_path / "moved"), "list", cwd=tmp_path / "ws")
    assert back.returncode == 0 and "hello-node" in back.stdout


def test_version_names_the_engine_the_grading_api_and_the_course(tmp_path: Path) -> None:
    proc = ros2course("--version", cwd=tmp_path)
    assert proc.returncode == 0
    assert proc.stdout.startswith("ros2course ") and "ros2course.kit 2." in proc.stdout
    assert "course ros2-tutorial" in proc.stdout
    lab = ros2course("--course", str(LAB_COURSE), "--version", cwd=tmp_path)
    assert "course lab-course 0.1.0" in lab.stdout


def test_an_unknown_course_name_lists_the_installed_ones(tmp_path: Path) -> None:
    proc = ros2course("init", "--course", "no-such-course", "ws", cwd=tmp_path)
    assert proc.returncode != 0
    assert "no course named 'no-such-course' is installed (installed: ros2-tutorial" in proc.stderr
    assert not (tmp_path / "ws").exists()  # nothing made for a course that is not there


def test_a_lesson_dropped_by_a_newer_course_version_is_reported_and_kept(tmp_path: Path) -> None:
    assert ros2course("init", "--course", str(LAB_COURSE), "ws", cwd=tmp_path).returncode == 0
    progress_file = tmp_path / "ws" / ".ros2course" / "progress.json"
    progress = json.loads(progress_file.read_text())
    progress["lessons"]["old-lesson"] = {"best_score": 3.0, "max_score": 5.0, "attempts": 2, "started": True}
    progress_file.write_text(json.dumps(progress))
    listed = ros2course("list", cwd=tmp_path / "ws")
    assert listed.returncode == 0
    assert "no longer has: old-lesson" in listed.stderr
    assert json.loads(progress_file.read_text())["lessons"]["old-lesson"]["best_score"] == 3.0


@pytest.mark.parametrize("course", [bundled_course(), LAB_COURSE], ids=["tutorial", "lab"])
def test_graders_use_only_the_public_kit(course: Path) -> None:
    """The narrow door (issues 18 and 23): a course's graders import ``ros2course.kit`` and its modules,
    their own siblings (``from . import _helper``), and nothing else of the engine."""
    import ast

    wide = []
    for path in sorted((course / "graders").glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = ([node.module or ""] if isinstance(node, ast.ImportFrom) and not node.level else
                     [alias.name for alias in node.names] if isinstance(node, ast.Import) else [])
            for name in names:
                if name.split(".")[0] in ("ros2course", "course", "graders") and not (
                        name == "ros2course.kit" or name.startswith("ros2course.kit.")
                        or (name == "ros2course" and isinstance(node, ast.ImportFrom)
                            and [a.name for a in node.names] == ["kit"])):
                    wide.append(f"{path.name}:{node.lineno} imports {name}")
    assert not wide, wide


def test_the_public_kit_is_documented_and_its_reference_builds(tmp_path: Path) -> None:
    """Every public step of ``ros2course.kit`` has a docstring, and scripts/api_docs.sh builds the reference."""
    import importlib
    import inspect

    from ros2course import kit

    missing = []
    for module_path in sorted((ROOT / "course" / "kit").glob("*.py")):
        name = "ros2course.kit" + ("" if module_path.stem == "__init__" else f".{module_path.stem}")
        module = importlib.import_module(name)
        if not (module.__doc__ or "").strip():
            missing.append(name)
        for attr, value in vars(module).items():
            if attr.startswith("_") or getattr(value, "__module__", None) != name:
                continue
            if (inspect.isfunction(value) or inspect.isclass(value)) and not (value.__doc__ or "").strip():
                missing.append(f"{name}.{attr}")
    assert not missing, missing
    assert kit.API_VERSION.split(".")[0] == load_manifest(bundled_course()).kit
    proc = subprocess.run(["bash", str(ROOT / "scripts" / "api_docs.sh"), str(tmp_path / "api")], cwd=ROOT,
                          capture_output=True, text=True, timeout=120, env={**os.environ, "PYTHON": sys.executable})
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert (tmp_path / "api" / "ros2course" / "kit" / "nodes.html").is_file()
    assert (ROOT / "docs" / "api" / "index.html").is_file()  # the committed reference the README links
