"""An instructor's private course that extends the public one (issue 39): hidden checks that never ship.

tests/data/private_course holds only a course.yaml (``extends: ../lab_course``), one grader that adds a hidden
and an after-the-deadline check to the public grader, and a wrong solution for the hidden check.
"""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path

import pytest

from ros2course.errors import CourseError, LessonFormatError
from ros2course.grade.engine import load_grader
from ros2course.lesson import use_course
from ros2course.lesson.catalog import load_catalog
from ros2course.lesson.courses import PARENT_GRADERS, course_fixtures, find_course, load_manifest

DATA = Path(__file__).resolve().parent / "data"
PRIVATE, PUBLIC = DATA / "private_course", DATA / "lab_course"
PACKAGE = "hello_node_pkg"


def test_the_merged_course_has_the_public_lessons_and_the_private_checks() -> None:
    root = find_course(str(PRIVATE))
    assert root != PRIVATE and find_course(str(PRIVATE)) == root  # made once for this content
    manifest = load_manifest(root)
    assert (manifest.id, manifest.lessons, manifest.extends) == ("lab-course-private", ["hello-node"], None)
    assert load_catalog(root).ids() == ["hello-node"]
    grader = load_grader("hello_node", root)
    assert [(c.id, c.visibility) for c in grader.CHECKS] == [
        ("build", "visible"), ("executable", "visible"), ("node_name", "visible"),
        ("license", "hidden"), ("maintainer", "after_due")]
    public = load_grader("hello_node", PUBLIC)
    assert [c.id for c in public.CHECKS] == ["build", "executable", "node_name"]  # the public course is untouched
    assert (root / "graders" / PARENT_GRADERS / "hello_node.py").read_bytes() == (PUBLIC / "graders/hello_node.py").read_bytes()
    assert sorted(p.stem for p in (course_fixtures(root) / "hello-node").glob("*.yaml")) == ["mit-license",
                                                                                          "never-registered"]
    assert (root / "solutions/src" / PACKAGE / "package.xml").is_file()


def test_the_private_grader_s_fingerprint_covers_the_public_grader_it_imports() -> None:
    from ros2course.grade.fingerprint import grader_files

    root = find_course(str(PRIVATE))
    use_course(root)
    try:
        files = grader_files(load_catalog(root).get("hello-node"))
    finally:
        use_course(None)
    assert root / "graders" / "hello_node.py" in files
    assert root / "graders" / PARENT_GRADERS / "hello_node.py" in files


def test_a_changed_private_file_makes_a_new_merged_course(tmp_path: Path) -> None:
    shutil.copytree(PUBLIC, tmp_path / "lab_course")
    shutil.copytree(PRIVATE, tmp_path / "private_course")
    first = find_course(str(tmp_path / "private_course"))
    grader = tmp_path / "private_course/graders/hello_node.py"
    grader.write_text(grader.read_text() + "\n# edited\n")
    second = find_course(str(tmp_path / "private_course"))
    assert second != first and (second / "graders/hello_node.py").read_text().endswith("# edited\n")


def test_an_extended_course_that_cannot_be_found_or_a_loop_is_one_line(tmp_path: Path) -> None:
    lost = tmp_path / "lost"
    lost.mkdir()
    (lost / "course.yaml").write_text("id: lost\ntitle: Lost course\nversion: '1'\nextends: ../nowhere\n")
    with pytest.raises(CourseError, match=r"course.yaml: extends: no course named '../nowhere'|no course at"):
        find_course(str(lost))
    for name, other in (("a", "b"), ("b", "a")):
        (tmp_path / name).mkdir()
        (tmp_path / name / "course.yaml").write_text(f"id: {name}\ntitle: Course {name}\nversion: '1'\n"
                                                     f"extends: ../{other}\n")
    with pytest.raises(CourseError, match="in a loop"):
        find_course(str(tmp_path / "a"))
    (tmp_path / "empty").mkdir()
    (tmp_path / "empty" / "course.yaml").write_text("id: empty\ntitle: No lessons\nversion: '1'\n")
    with pytest.raises(LessonFormatError, match="at least one lesson"):
        load_manifest(tmp_path / "empty")


@pytest.mark.ros
def test_grade_runs_the_hidden_checks_and_gradescope_hides_them(cli, tmp_path: Path) -> None:
    submissions = tmp_path / "submissions"
    shutil.copytree(PUBLIC / "solutions" / "src" / PACKAGE, submissions / "ada" / "src" / PACKAGE)
    bob = submissions / "bob" / "src" / PACKAGE
    shutil.copytree(PUBLIC / "solutions" / "src" / PACKAGE, bob)
    xml = bob / "package.xml"
    xml.write_text(xml.read_text().replace("<license>Apache-2.0</license>", "<license>MIT</license>"))
    out = tmp_path / "out"
    proc = cli("grade", str(submissions), "--lesson", "hello-node", "--out", str(out), "--course", str(PRIVATE),
               "--jobs", "2", cwd=tmp_path, env={"ROS2COURSE_CONTENT": ""}, timeout=600)
    assert proc.returncode in (0, 1), proc.stdout[-2000:] + proc.stderr[-2000:]
    rows = {row["student"]: row for row in csv.DictReader((out / "gradebook.csv").open())}
    assert (float(rows["ada"]["score"]), float(rows["ada"]["max_score"])) == (7.0, 7.0), rows["ada"]
    assert float(rows["bob"]["score"]) == 6.0, rows["bob"]
    tests = {t["name"].split(":")[-1].strip(): t for t in json.loads((out / "bob" / "results.json").read_text())["tests"]}
    by_visibility = sorted(t["visibility"] for t in tests.values())
    assert by_visibility == ["after_due_date", "hidden", "visible", "visible", "visible"], tests
    lost = [t for t in tests.values() if t["score"] < t["max_score"]]
    assert [t["visibility"] for t in lost] == ["hidden"], lost


@pytest.mark.ros
def test_check_on_the_private_course_withholds_what_it_hides(cli, tmp_path: Path) -> None:
    """An instructor trying the private course as a learner would: ``check`` shows the visible checks and says
    how many more are graded at hand-in, never their names or verdicts."""
    ws = tmp_path / "ws"
    env = {"ROS2COURSE_CONTENT": ""}
    assert cli("init", "--course", str(PRIVATE), str(ws), cwd=tmp_path, env=env).returncode == 0
    shutil.rmtree(ws / "src" / PACKAGE, ignore_errors=True)
    shutil.copytree(PUBLIC / "solutions" / "src" / PACKAGE, ws / "src" / PACKAGE)
    proc = cli("check", "hello-node", cwd=ws, env=env, timeout=300)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    assert "All 3 visible checks passed; 2 more check(s) are graded when you hand in your work." in proc.stdout
    assert "license" not in proc.stdout.lower() and "maintainer" not in proc.stdout.lower()


def test_a_merged_course_unused_for_two_weeks_is_deleted_when_another_is_made(tmp_path: Path) -> None:
    import os
    import time
    import uuid

    from ros2course.lesson.courses import MERGED_MAX_AGE

    shutil.copytree(PUBLIC, tmp_path / "lab_course")
    shutil.copytree(PRIVATE, tmp_path / "private_course")
    grader = tmp_path / "private_course/graders/hello_node.py"
    # content no earlier run had: merged courses are kept by path and content in the venv's cache, which outlives
    # pytest's numbered temp folders (a temp path used again found its "new" course already made, and nothing
    # was pruned)
    grader.write_text(grader.read_text() + f"\n# {uuid.uuid4()}\n")
    old = find_course(str(tmp_path / "private_course"))
    then = time.time() - MERGED_MAX_AGE - 60
    os.utime(old / "course.yaml", (then, then))
    grader.write_text(grader.read_text() + "\n# edited\n")
    new = find_course(str(tmp_path / "private_course"))
    assert new.is_dir() and not old.exists()


def test_batch_grading_hides_the_private_course_and_the_public_solutions(tmp_path: Path) -> None:
    """A submission never sees the folders the merged course was made from: the private course whole (its graders
    name the hidden checks), the public course's solutions and fixtures; nor the merged course's own."""
    from ros2course.batch.runner import default_hidden
    from ros2course.lesson.courses import course_sources

    root = find_course(str(PRIVATE))
    assert course_sources(root) == [PRIVATE.resolve(), PUBLIC.resolve()]
    use_course(root)
    try:
        hidden = default_hidden(load_catalog().course, tmp_path / "subs", tmp_path / "out", tmp_path / "scratch")
    finally:
        use_course(None)
    for folder in (PRIVATE, PUBLIC / "solutions", PUBLIC / "fixtures", root / "solutions", root / "fixtures"):
        assert str(folder.resolve()) in hidden, (folder, hidden)
    assert str((root / "graders").resolve()) not in hidden  # the worker grades with them
