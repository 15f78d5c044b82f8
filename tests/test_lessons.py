"""Schema-level tests of the course content: lessons, graders, fixtures, starters.

No ROS node is started here: fixtures are applied to a copy of the reference
solution with :func:`ros2course.dev.validate.apply_edits`, never graded.
"""

from __future__ import annotations

import dataclasses
import re
import shutil
from pathlib import Path

import pytest
import yaml

from ros2course.errors import LessonFormatError
from ros2course.grade.checklist import Check
from ros2course.grade.engine import load_grader
from ros2course.dev.validate import (
    apply_edits,
    fixtures_dir,
    load_fixtures,
    reference_workspace,
)
from ros2course.lesson.catalog import content_root, load_catalog, load_lesson
from ros2course.lesson.starter import copy_starter, starter_files, starter_sources
from ros2course.ros.manifests import find_packages

ROOT = content_root()
CATALOG = load_catalog()
LESSON_IDS = CATALOG.ids()
SNAKE = re.compile(r"^[a-z][a-z0-9_]*$")

#: (lesson id, fixture file stem) for every fixture file on disk (collected from
#: the files, not the loader, so a broken fixture is a failing case, not a collection error).
FIXTURE_CASES = [(lesson_id, path.stem) for lesson_id in LESSON_IDS
                 for path in sorted(fixtures_dir(lesson_id).glob("*.yaml"))]


def snapshot(root: Path) -> dict[str, bytes | None]:
    """Every path under ``root``: file -> content, folder -> None."""
    return {str(p.relative_to(root)): (None if p.is_dir() else p.read_bytes())
            for p in sorted(root.rglob("*")) if "__pycache__" not in p.parts}


# --- the catalog ---------------------------------------------------------------

def test_catalog_has_the_known_lessons_in_order():
    # shared/LESSONS.md order: the preamble (ch. 1-2) first, then workspace-setup opens the ROS 2 Python track
    assert LESSON_IDS[0] == "terminal-basics"
    assert LESSON_IDS.index("terminal-basics") < LESSON_IDS.index("workspace-setup")
    assert LESSON_IDS.index("workspace-setup") < LESSON_IDS.index("print-forever-node")
    manifest = yaml.safe_load((ROOT / "course.yaml").read_text(encoding="utf-8"))
    assert LESSON_IDS == manifest["lessons"], "the catalog runs in course.yaml's order, its only source"
    assert len(set(LESSON_IDS)) == len(LESSON_IDS)
    on_disk = sorted(p.parent for p in (ROOT / "chapters").glob("*/lesson.yaml"))
    assert len(on_disk) == len(CATALOG.lessons), "every lesson.yaml is in the catalog"


@pytest.mark.parametrize("lesson_id", LESSON_IDS)
def test_lesson_loads_with_enough_hints(lesson_id):
    lesson = CATALOG.get(lesson_id)
    again = load_lesson(lesson.folder / "lesson.yaml")
    assert again.id == lesson_id
    assert lesson.folder.name == lesson_id  # named by its id: no number that could disagree with course.yaml
    assert len(lesson.hints) >= 3
    assert len(set(lesson.hints)) == len(lesson.hints), "no hint repeats another"
    assert all(len(h.strip()) >= 5 for h in lesson.hints)
    assert len(lesson.instructions.strip()) >= 20
    assert lesson.chapters or lesson.beyond.strip()


@pytest.mark.parametrize("lesson_id", LESSON_IDS)
def test_grader_declares_unique_checks_with_points(lesson_id):
    lesson = CATALOG.get(lesson_id)
    module = load_grader(lesson.grader)
    assert callable(module.grade)
    checks = list(module.CHECKS)
    assert checks
    assert all(isinstance(c, Check) for c in checks)
    ids = [c.id for c in checks]
    assert len(set(ids)) == len(ids), f"duplicate check ids in graders/{lesson.grader}.py: {ids}"
    for check in checks:
        assert SNAKE.match(check.id), check.id
        assert check.points > 0, check
        assert check.name.strip(), check


@pytest.mark.parametrize("lesson_id", LESSON_IDS)
def test_lesson_packages_are_in_the_reference_solution(lesson_id, tmp_path):
    """reference_workspace silently skips unknown package names: a typo would grade an empty workspace."""
    lesson = CATALOG.get(lesson_id)
    found = find_packages(ROOT / "solutions" / "src")
    assert set(lesson.packages) <= set(found), f"not in solutions/src: {set(lesson.packages) - set(found)}"
    ref = reference_workspace(lesson, tmp_path / "ref")
    assert set(lesson.packages) <= set(find_packages(ref / "src"))


# --- fixtures ------------------------------------------------------------------

def test_fixture_folders_belong_to_lessons():
    folders = [p.name for p in (ROOT / "tests" / "fixtures").iterdir() if p.is_dir()]
    assert folders
    assert set(folders) <= set(LESSON_IDS), f"fixtures for unknown lessons: {set(folders) - set(LESSON_IDS)}"
    stray = [p.name for p in (ROOT / "tests" / "fixtures").rglob("*")
             if p.is_file() and p.suffix != ".yaml"]
    assert stray == [], f"files the loader would silently ignore: {stray}"


@pytest.mark.parametrize("lesson_id", LESSON_IDS)
def test_every_fixture_file_loads_and_names_declared_checks(lesson_id):
    lesson = CATALOG.get(lesson_id)
    declared = {c.id for c in load_grader(lesson.grader).CHECKS}
    files = sorted(fixtures_dir(lesson_id).glob("*.yaml"))
    fixtures = load_fixtures(lesson_id)
    assert [f.name for f in fixtures] == [p.stem for p in files]
    for fixture in fixtures:
        assert fixture.description.strip(), fixture.name
        assert set(fixture.fails) <= declared, (
            f"{fixture.name}: unknown check ids {set(fixture.fails) - declared}; declared: {sorted(declared)}")
        assert set(fixture.skips) <= declared, (
            f"{fixture.name}: unknown skipped check ids {set(fixture.skips) - declared}; declared: {sorted(declared)}")
        assert not set(fixture.fails) & set(fixture.skips), f"{fixture.name}: a check both in fails and skips"
        assert len(set(fixture.skips)) == len(fixture.skips), f"{fixture.name}: a check twice in skips"
        if fixture.expect == "full_marks":
            assert fixture.fails == [], f"{fixture.name} expects full marks but names failing checks"
            assert fixture.skips == [], f"{fixture.name} expects full marks but names skipped checks"
        else:
            assert fixture.fails, fixture.name
        assert fixture.edits or fixture.commands is not None, f"{fixture.name} changes nothing"
        diagnosed = {d.check for d in fixture.diagnosis if d.check}
        assert diagnosed <= declared, f"{fixture.name}: diagnosis of unknown checks {diagnosed - declared}"
        assert not fixture.diagnosis or lesson.graph is not None, (
            f"{fixture.name} expects a diagnosis but lesson {lesson_id} declares no graph:")


def test_print_forever_node_has_wrong_solution_fixtures():
    assert len(load_fixtures("print-forever-node")) >= 5


@pytest.mark.parametrize(("lesson_id", "fixture_name"), FIXTURE_CASES)
def test_fixture_edits_apply_exactly_once_to_the_reference(lesson_id, fixture_name, tmp_path):
    lesson = CATALOG.get(lesson_id)
    fixture = {f.name: f for f in load_fixtures(lesson_id)}[fixture_name]
    ref = reference_workspace(lesson, tmp_path / "ref")
    work = reference_workspace(lesson, tmp_path / "work")
    assert snapshot(work) == snapshot(ref)
    for edit in fixture.edits:
        if edit.replace is not None:
            target = work / edit.file
            assert target.is_file(), f"{fixture_name}: {edit.file} is not in the reference"
            text = target.read_text(encoding="utf-8")
            assert text.count(edit.replace) == 1, (
                f"{fixture_name}: {edit.replace!r} occurs {text.count(edit.replace)} times in {edit.file}")
            assert edit.replace != edit.with_, f"{fixture_name}: a replace that changes nothing"
        elif edit.delete is not None:
            assert (work / edit.delete).exists(), f"{fixture_name}: deletes {edit.delete}, which is not there"
        before = snapshot(work)
        apply_edits(work, [edit])
        assert snapshot(work) != before, f"{fixture_name}: the edit {edit} changed nothing"
        if edit.replace is not None:
            after = (work / edit.file).read_text(encoding="utf-8")
            assert after == text.replace(edit.replace, edit.with_)
    if fixture.edits:
        assert snapshot(work) != snapshot(ref)


def test_apply_edits_rejects_a_replace_that_is_not_unique(tmp_path):
    """The guard the previous test relies on: a replace text found 0 or 2 times is an error."""
    from ros2course.dev.validate import Edit

    (tmp_path / "f.txt").write_text("a a\n")
    with pytest.raises(LessonFormatError, match="2 times"):
        apply_edits(tmp_path, [Edit(file="f.txt", replace="a", with_="b")])
    with pytest.raises(LessonFormatError, match="0 times"):
        apply_edits(tmp_path, [Edit(file="f.txt", replace="zzz", with_="b")])
    assert (tmp_path / "f.txt").read_text() == "a a\n"


# --- starters ------------------------------------------------------------------

@pytest.mark.parametrize("lesson_id", LESSON_IDS)
def test_starter_differs_from_the_reference(lesson_id, tmp_path):
    lesson = CATALOG.get(lesson_id)
    ref = reference_workspace(lesson, tmp_path / "ref")
    start = tmp_path / "start"
    (start / "src").mkdir(parents=True)
    copied, kept = copy_starter(lesson, start)
    assert kept == []
    assert sorted(copied) == starter_files(lesson)
    assert snapshot(start) != snapshot(ref)
    if not lesson.packages:
        return
    # the starter holds the same packages, and at least one of their files is not the solution's
    starter_pkgs = find_packages(start / "src")
    ref_pkgs = find_packages(ref / "src")
    for name in lesson.packages:
        assert name in starter_pkgs, f"the starter lacks package {name}"
        mine, theirs = snapshot(starter_pkgs[name][0]), snapshot(ref_pkgs[name][0])
        common = set(mine) & set(theirs)
        assert common, f"starter and reference of {name} share no file"
        assert any(mine[p] != theirs[p] for p in common), f"the starter of {name} is the reference solution"


# --- the schema rejects malformed lessons ------------------------------------------

def _mutated_lesson(tmp_path: Path, mutate, folder_name: str | None = None) -> Path:
    lesson = CATALOG.get("print-forever-node")
    data = yaml.safe_load((lesson.folder / "lesson.yaml").read_text(encoding="utf-8"))
    data = mutate(data)
    folder = tmp_path / (folder_name or lesson.folder.name)
    folder.mkdir()
    path = folder / "lesson.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


def _with(**changes):
    def mutate(data):
        data.update(changes)
        return data
    return mutate


def _without(key):
    def mutate(data):
        data.pop(key)
        return data
    return mutate


@pytest.mark.parametrize(("mutate", "field", "words"), [
    (lambda d: {**d, "hints": d["hints"][:2]}, "hints", "at least 3"),
    (lambda d: {**d, "hints": [*d["hints"][:3], "x"]}, "hints.3", "at least 5"),
    (_without("grader"), "grader", "required"),
    (_with(grader="Print-Forever"), "grader", "pattern"),
    (_with(requires=["rclpy", "ros1"]), "requires", "ros1"),
    (_with(hint=["typo for hints"]), "hint", "not permitted"),
    (_with(chapters=[]), "chapters", "at least 1"),
    (_with(reference={"command": ["colcon build"]}), "reference.command", "not permitted"),
], ids=["two-hints", "short-hint", "no-grader", "bad-grader-name", "unknown-requirement", "extra-field",
        "no-chapters", "reference-extra-field"])
def test_schema_rejects_malformed_lessons(tmp_path, mutate, field, words):
    path = _mutated_lesson(tmp_path, mutate)
    with pytest.raises(LessonFormatError) as info:
        load_lesson(path)
    message = info.value.message
    assert f"{path}: {field}: " in message, message
    assert words in message, message
    assert info.value.hint


def test_schema_rejects_an_id_that_does_not_match_its_folder(tmp_path):
    path = _mutated_lesson(tmp_path, lambda d: d, folder_name="13-print-forever")
    with pytest.raises(LessonFormatError, match=r": id: 'print-forever-node' does not match"):
        load_lesson(path)


def test_schema_rejects_a_top_level_list(tmp_path):
    folder = tmp_path / "13-print-forever-node"
    folder.mkdir()
    (folder / "lesson.yaml").write_text("- id: print-forever-node\n")
    with pytest.raises(LessonFormatError, match=r"\(top level\)"):
        load_lesson(folder / "lesson.yaml")


def test_unmodified_copy_of_a_lesson_loads(tmp_path):
    path = _mutated_lesson(tmp_path, lambda d: d)
    copy = load_lesson(path)
    original = CATALOG.get("print-forever-node")
    def fields(lesson):  # what lesson.yaml says: the loader sets folder, course and included_starters
        return {k: v for k, v in dataclasses.asdict(lesson).items() if k not in ("folder", "included_starters", "course")}

    assert fields(copy) == fields(original)
    assert copy.folder == path.parent


def test_fixture_schema_rejects_a_failing_fixture_without_fails(tmp_path, monkeypatch):
    """load_fixtures names the file and field of a malformed fixture (via ROS2COURSE_CONTENT)."""
    folder = tmp_path / "tests" / "fixtures" / "print-forever-node"
    folder.mkdir(parents=True)
    (folder / "bad.yaml").write_text("description: forgot fails\nedits: []\n")
    monkeypatch.setenv("ROS2COURSE_CONTENT", str(tmp_path))
    with pytest.raises(LessonFormatError) as info:
        load_fixtures("print-forever-node")
    assert str((folder / "bad.yaml").resolve()) in info.value.message
    assert "fails" in info.value.message
    shutil.rmtree(folder)
    assert load_fixtures("print-forever-node") == []


@pytest.mark.parametrize(("text", "words"), [
    ("description: d\nexpect: full_marks\nskips: [rate]\nedits: []\n", ["full marks", "skips"]),
    ("description: d\nfails: [rate]\nskips: [rate, log]\nedits: []\n", ["rate", "both", "fails", "skips"]),
])
def test_fixture_schema_rejects_misplaced_skips(tmp_path, monkeypatch, text, words):
    """``skips:`` (checks a fixture leaves not checked) is not for a full-marks fixture, nor for a check
    in ``fails:``."""
    folder = tmp_path / "tests" / "fixtures" / "print-forever-node"
    folder.mkdir(parents=True)
    (folder / "bad.yaml").write_text(text)
    monkeypatch.setenv("ROS2COURSE_CONTENT", str(tmp_path))
    with pytest.raises(LessonFormatError) as info:
        load_fixtures("print-forever-node")
    assert all(word in info.value.message for word in words), info.value.message


# --- starters that build on an earlier lesson's (starter_includes) ----------------

def _tiny_lesson(chapters: Path, folder: str, extra: str = "", files: dict[str, str] | None = None) -> None:
    lesson_id = folder.split("-", 1)[1]
    (chapters / folder).mkdir(parents=True)
    (chapters / folder / "lesson.yaml").write_text(
        f"id: {lesson_id}\ntitle: Lesson {lesson_id}\nchapters: [1]\ngrader: print_forever_node\n"
        "instructions: |\n  Twenty characters of instructions at least.\n"
        "hints: [first hint, second hint, third hint]\n" + extra)
    for rel, text in (files or {}).items():
        path = chapters / folder / "starter" / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)


def test_starter_includes_lay_earlier_starters_under_the_lessons_own(tmp_path):
    from ros2course.lesson.catalog import Catalog  # noqa: PLC0415

    chapters = tmp_path / "chapters"
    _tiny_lesson(chapters, "01-alpha", files={"src/p/node.py": "alpha", "src/p/setup.py": "alpha"})
    _tiny_lesson(chapters, "02-beta", "starter_includes: [alpha]\n", files={"src/p/launch/x.py": "beta"})
    _tiny_lesson(chapters, "03-gamma", "starter_includes: [beta]\n", files={"src/p/setup.py": "gamma"})
    catalog = Catalog(chapters)
    gamma = catalog.get("gamma")
    assert [p.parent.name for p in gamma.starter_layers] == ["01-alpha", "02-beta", "03-gamma"]
    assert {str(rel): src.read_text() for rel, src in starter_sources(gamma).items()} == {
        "src/p/launch/x.py": "beta", "src/p/node.py": "alpha", "src/p/setup.py": "gamma"}  # its own file wins
    ws = tmp_path / "ws"
    (ws / "src/p").mkdir(parents=True)
    (ws / "src/p/node.py").write_text("the learner's")
    copied, kept = copy_starter(gamma, ws)
    assert [str(p) for p in kept] == ["src/p/node.py"] and (ws / "src/p/node.py").read_text() == "the learner's"
    assert sorted(map(str, copied)) == ["src/p/launch/x.py", "src/p/setup.py"]
    assert (ws / "src/p/setup.py").read_text() == "gamma"


def test_starter_solutions_offer_finished_packages_under_the_lessons_own(tmp_path, monkeypatch):
    from ros2course.lesson.catalog import Catalog  # noqa: PLC0415

    course = tmp_path / "course"
    (course / "solutions/src/ifaces/msg").mkdir(parents=True)
    (course / "solutions/src/ifaces/msg/Quote.msg").write_text("string quote\n")
    (course / "solutions/src/ifaces/package.xml").write_text("finished")
    _tiny_lesson(course / "chapters", "01-pub", "starter_solutions: [src/ifaces]\n",
                 files={"src/ifaces/package.xml": "the lesson's own", "src/pub/node.py": "TODO"})
    monkeypatch.setenv("ROS2COURSE_CONTENT", str(course))
    lesson = Catalog(course / "chapters").get("pub")
    assert {str(rel): src.read_text() for rel, src in starter_sources(lesson).items()} == {
        "src/ifaces/msg/Quote.msg": "string quote\n", "src/ifaces/package.xml": "the lesson's own",
        "src/pub/node.py": "TODO"}
    ws = tmp_path / "ws"
    (ws / "src/ifaces/msg").mkdir(parents=True)
    (ws / "src/ifaces/msg/Quote.msg").write_text("the learner's own quote\n")
    copied, kept = copy_starter(lesson, ws)
    assert [str(p) for p in kept] == ["src/ifaces/msg/Quote.msg"]
    assert (ws / "src/ifaces/msg/Quote.msg").read_text() == "the learner's own quote\n"
    assert sorted(map(str, copied)) == ["src/ifaces/package.xml", "src/pub/node.py"]


def test_the_publisher_lesson_offers_the_finished_interfaces():
    from ros2course.lesson.catalog import content_root, load_catalog  # noqa: PLC0415

    solution = content_root() / "solutions/src/package_with_interfaces"
    for lesson_id in ("publisher-subscriber", "service-server-client"):
        sources = starter_sources(load_catalog().get(lesson_id))
        for name in ("CMakeLists.txt", "package.xml", "msg/AmazingQuote.msg", "srv/WhatIsThePoint.srv"):
            assert sources[Path("src/package_with_interfaces") / name] == solution / name


@pytest.mark.parametrize("include, problem", [("delta", "no such lesson"),
                                              ("gamma", "does not come earlier")])
def test_starter_includes_must_name_an_earlier_lesson(tmp_path, include, problem):
    from ros2course.lesson.catalog import Catalog  # noqa: PLC0415

    chapters = tmp_path / "chapters"
    _tiny_lesson(chapters, "01-alpha")
    _tiny_lesson(chapters, "02-beta", f"starter_includes: [{include}]\n")
    _tiny_lesson(chapters, "03-gamma")
    with pytest.raises(LessonFormatError) as info:
        Catalog(chapters)
    assert f"{chapters / '02-beta' / 'lesson.yaml'}: starter_includes: '{include}': " in info.value.message
    assert problem in info.value.message and info.value.hint


def test_course_starters_that_build_on_earlier_ones():
    # launch-files and param-dump-load hand out the parameters lesson's package plus their own new file
    params = set(starter_files(CATALOG.get("parameters")))
    launch = set(starter_files(CATALOG.get("launch-files")))
    dump = set(starter_files(CATALOG.get("param-dump-load")))
    assert params < launch < dump
    assert {p.parts[-2] for p in launch - params} == {"launch"}
    assert {p.parts[-2] for p in dump - launch} == {"config"}


def test_a_lesson_beyond_the_tutorial_names_its_source_instead_of_chapters(tmp_path):
    """``chapters: []`` is accepted only with ``beyond:`` (issue 20's QoS and lifecycle lessons)."""
    lesson = load_lesson(_mutated_lesson(tmp_path, _with(chapters=[], beyond="ROS 2 docs: About QoS settings")))
    assert lesson.chapters == [] and lesson.beyond.startswith("ROS 2 docs")
    with pytest.raises(LessonFormatError) as info:
        load_lesson(_mutated_lesson(tmp_path, _with(chapters=[], beyond="  "), folder_name="13-blank"))
    assert "beyond" in str(info.value)


def test_the_readme_lesson_table_is_current() -> None:
    """README.md's lesson table (checks, wrong solutions, grader strength) matches the course (issue 24)."""
    from ros2course.dev.validate import with_lessons_table

    readme = (Path(__file__).resolve().parent.parent / "README.md").read_text(encoding="utf-8")
    assert with_lessons_table(readme) == readme, (
        "README.md's lesson table is stale: run python benchmarks/grader_strength.py --readme")


def test_a_readme_without_the_table_markers_is_a_one_line_error() -> None:
    from ros2course.errors import CourseError
    from ros2course.dev.validate import with_lessons_table

    with pytest.raises(CourseError, match="no generated lesson table"):
        with_lessons_table("# a course\n")


def test_the_lesson_schema_and_the_lesson_values_have_the_same_fields():
    """lesson/schema.py validates what lesson/catalog.py holds: each model names exactly its value class's
    fields (the loader's own, folder, course and included_starters, aside), so nothing validated is dropped."""
    from ros2course.lesson import catalog, schema  # noqa: PLC0415

    for name in ("ReferenceSolution", "GraphNode", "GraphEndpoint", "LessonGraph", "Lesson"):
        values = {f.name for f in dataclasses.fields(getattr(catalog, name))} - {"folder", "included_starters", "course"}
        assert set(getattr(schema, f"{name}Schema").model_fields) == values, name
