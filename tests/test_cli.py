"""The learner's flow and bad input, through the real command line (``python -m ros2course`` in a subprocess).

Every test works in ``tmp_path``; nothing is written into the repository.
Tests that build and run real ROS 2 nodes are marked ``ros``.
"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pytest
import yaml
from ros2course.lesson.catalog import content_root, load_catalog
from ros2course.lesson.starter import starter_files, starter_sources

ROOT = content_root()
CATALOG = load_catalog()
FIRST, LAST = CATALOG.lessons[0], CATALOG.lessons[-1]
#: The first lesson of the ROS 2 track (after the preamble): the colcon workspace.
WS_SETUP = CATALOG.get("workspace-setup")
PRINT_FOREVER = "print-forever-node"
PKG = "src/python_package_with_a_node"

RESULT_KEYS = {"lesson", "score", "max_score", "status", "checks"}
CHECK_KEYS = {"id", "name", "points", "max_points", "passed", "observed", "expected", "hint"}


# --- helpers -----------------------------------------------------------------

def next_until(ws: Path, cli, lesson_id: str) -> None:
    """Run ``next`` until ``lesson_id`` is the current lesson (course order)."""
    for _ in range(len(CATALOG.lessons)):
        proc = cli("next", cwd=ws)
        assert proc.returncode == 0, proc.stderr
        if progress_of(ws)["current"] == lesson_id:
            return
    raise AssertionError(f"'next' never reached {lesson_id}")


def first_lesson_shipping(rel: str):
    """The first lesson (course order) whose starter has the workspace-relative file ``rel``."""
    return next(lesson for lesson in CATALOG.lessons if Path(rel) in starter_files(lesson))


def progress_of(root: Path) -> dict:
    return json.loads((root / ".ros2course" / "progress.json").read_text(encoding="utf-8"))


def assert_clean_error(proc, code: int, *needles: str, one_line: bool = False) -> str:
    """Exit ``code``; stderr holds one ``error:`` message then one ``hint:`` line; no traceback anywhere.

    Messages that embed a tmp path can be longer than the 320 columns the ``cli``
    fixture forces, and the CLI currently wraps them (see
    ``test_long_error_message_stays_on_one_line``): continuation lines of the
    error are tolerated unless ``one_line``. Returns the error message (unwrapped);
    every ``needle`` must occur in it.
    """
    everything = proc.stdout + proc.stderr
    assert "Traceback" not in everything, everything
    assert proc.returncode == code, (proc.returncode, proc.stdout, proc.stderr)
    assert proc.stdout.strip() == "", f"errors go to stderr, stdout was: {proc.stdout!r}"
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert [line for line in lines if line.startswith("error:")] == lines[:1], f"one error message first: {lines}"
    hints = [i for i, line in enumerate(lines) if line.startswith("hint:")]
    assert len(hints) == 1 and hints[0] >= 1, f"one hint line after the error: {lines}"
    assert len(lines[hints[0]]) > len("hint: ") + 3, lines
    error_block, hint_block = lines[:hints[0]], lines[hints[0]:]
    if one_line:
        assert len(error_block) == 1 and len(hint_block) == 1, f"expected exactly two lines, got: {lines}"
    message = "".join(error_block)
    squeezed = "".join(message.split())
    for needle in needles:
        assert "".join(needle.split()) in squeezed, f"{needle!r} not in {message!r}"
    return message


def hint_line(proc) -> str:
    return [line for line in proc.stderr.splitlines() if line.startswith("hint:")][0]


def plain(markdown: str) -> str:
    """A hint's markdown as rich renders it (no backticks or emphasis), whitespace normalised."""
    return " ".join(re.sub(r"[`*]", "", markdown).split())


def normalised(text: str) -> str:
    return " ".join(text.split())


def row_of(listing: str, lesson_id: str) -> str:
    # the id column is the second cell: match it exactly (a title may contain another id's word)
    rows = [line for line in listing.splitlines()
            if len(cells := [c.strip() for c in line.split("│")]) > 2 and cells[2] == lesson_id]
    assert len(rows) == 1, listing
    return rows[0]


def copy_course(dest: Path) -> Path:
    """A private copy of the course content, for ROS2COURSE_CONTENT (course.yaml too: it alone orders the lessons)."""
    for part in ("chapters", "graders", "solutions", "tests/fixtures"):
        shutil.copytree(ROOT / part, dest / part, ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    shutil.copy2(ROOT / "course.yaml", dest / "course.yaml")
    return dest


@pytest.fixture
def cli(request):
    """The CLI in this process (typer's CliRunner: messages, exit codes and files, issue 23), except for
    the tests that grade real ROS nodes (marked ``ros``), which run ``python -m ros2course`` as a learner
    would (a process of its own: its ROS contexts, learner processes and exit)."""
    from conftest import run_cli, run_cli_in_process

    return run_cli if request.node.get_closest_marker("ros") else run_cli_in_process


@pytest.fixture
def ws(tmp_path: Path, cli) -> Path:
    """A workspace made by ``ros2course init`` (through the CLI)."""
    proc = cli("init", "ws", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    return tmp_path / "ws"


# --- init ------------------------------------------------------------------------

def test_init_creates_src_and_progress_file(tmp_path, cli):
    proc = cli("init", "myws", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    root = tmp_path / "myws"
    assert (root / "src").is_dir()
    data = progress_of(root)
    assert data["version"] == 1
    assert data["current"] is None
    assert data["lessons"] == {}
    assert "Initialised" in proc.stdout and str(root) in proc.stdout
    assert "Traceback" not in proc.stderr


def test_init_twice_keeps_progress(ws, cli):
    assert cli("next", cwd=ws).returncode == 0
    assert cli("hint", cwd=ws).returncode == 0
    progress_file = ws / ".ros2course" / "progress.json"
    before = progress_file.read_bytes()
    assert json.loads(before)["current"] == FIRST.id

    proc = cli("init", str(ws), cwd=ws.parent)
    assert proc.returncode == 0, proc.stderr
    assert "already a ros2course workspace" in proc.stdout
    assert progress_file.read_bytes() == before
    assert progress_of(ws)["lessons"][FIRST.id]["hints_shown"] == 1


def test_init_on_a_regular_file_fails(tmp_path, cli):
    target = tmp_path / "notadir"
    target.write_text("mine\n")
    proc = cli("init", "notadir", cwd=tmp_path)
    assert_clean_error(proc, 5, "notadir", "not a folder", one_line=True)
    assert target.read_text() == "mine\n"


def test_init_when_src_is_a_regular_file_fails_cleanly(tmp_path, cli):
    (tmp_path / "ws").mkdir()
    (tmp_path / "ws" / "src").write_text("not a folder\n")
    proc = cli("init", "ws", cwd=tmp_path)
    assert_clean_error(proc, 5, "src")


def test_init_below_a_regular_file_fails_cleanly(tmp_path, cli):
    (tmp_path / "afile").write_text("x\n")
    proc = cli("init", "afile/ws", cwd=tmp_path)
    assert_clean_error(proc, 5, "afile")


# --- list / next -----------------------------------------------------------------

def test_list_shows_every_lesson_and_current_after_next(ws, cli):
    proc = cli("list", cwd=ws)
    assert proc.returncode == 0, proc.stderr
    for lesson in CATALOG.lessons:
        assert "not started" in row_of(proc.stdout, lesson.id)
        assert lesson.title in row_of(proc.stdout, lesson.id)
    # course order
    positions = [proc.stdout.index(f" {lesson.id} ") for lesson in CATALOG.lessons]
    assert positions == sorted(positions)

    assert cli("next", cwd=ws).returncode == 0
    proc = cli("list", cwd=ws)
    assert proc.returncode == 0, proc.stderr
    assert "current" in row_of(proc.stdout, FIRST.id)
    for lesson in CATALOG.lessons[1:]:
        assert "not started" in row_of(proc.stdout, lesson.id)


def test_next_renders_instructions_and_copies_starters(ws, cli):
    proc = cli("next", cwd=ws)
    assert proc.returncode == 0, proc.stderr
    out = normalised(proc.stdout)
    assert FIRST.title in out
    assert f"lesson id: {FIRST.id}" in out
    heading = next(line[3:].strip() for line in FIRST.instructions.splitlines() if line.startswith("## "))
    assert heading in out  # a heading of the lesson's markdown instructions
    files = starter_files(FIRST)
    assert files, "the first lesson has starter files"
    sources = starter_sources(FIRST)
    for rel in files:
        assert (ws / rel).read_bytes() == sources[rel].read_bytes()
        assert f"created {rel}" in proc.stdout
    assert progress_of(ws)["current"] == FIRST.id
    assert progress_of(ws)["lessons"][FIRST.id]["started"] is True

    proc = cli("next", cwd=ws)
    assert proc.returncode == 0, proc.stderr
    second = CATALOG.after(FIRST.id)
    assert f"lesson id: {second.id}" in proc.stdout
    assert f"lesson {FIRST.id} is not done yet" in proc.stderr
    for rel, source in starter_sources(second).items():
        assert (ws / rel).read_bytes() == source.read_bytes()
        assert f"created {rel}" in proc.stdout
    assert progress_of(ws)["current"] == second.id


def test_next_keeps_the_learners_files(ws, cli):
    mine_top = b"#!/bin/bash\n# my own notes \xc3\xa9\n"
    first_file = sorted(starter_files(FIRST))[0]
    (ws / first_file).parent.mkdir(parents=True, exist_ok=True)
    (ws / first_file).write_bytes(mine_top)
    proc = cli("next", cwd=ws)
    assert proc.returncode == 0, proc.stderr
    assert (ws / first_file).read_bytes() == mine_top
    assert f"kept your file {first_file}" in proc.stderr
    assert f"created {first_file}" not in proc.stdout

    target = first_lesson_shipping(f"{PKG}/setup.py")
    before = CATALOG.lessons[CATALOG.ids().index(target.id) - 1]
    if before.id != FIRST.id:
        next_until(ws, cli, before.id)
    setup = ws / PKG / "setup.py"
    setup.parent.mkdir(parents=True)
    mine_setup = b"# my setup.py\nfrom setuptools import setup\nsetup()\n"
    setup.write_bytes(mine_setup)
    proc = cli("next", cwd=ws)
    assert progress_of(ws)["current"] == target.id
    assert proc.returncode == 0, proc.stderr
    assert setup.read_bytes() == mine_setup
    assert f"kept your file {PKG}/setup.py" in proc.stderr
    assert f"created {PKG}/setup.py" not in proc.stdout
    # the other starter files were still copied
    assert f"created {PKG}/package.xml" in proc.stdout
    assert (ws / PKG / "package.xml").is_file()


def test_next_past_the_last_lesson(ws, cli):
    for _ in CATALOG.lessons:
        assert cli("next", cwd=ws).returncode == 0
    assert progress_of(ws)["current"] == LAST.id
    before = (ws / ".ros2course" / "progress.json").read_bytes()
    proc = cli("next", cwd=ws)
    assert proc.returncode == 0, proc.stderr
    assert "end of the course" in proc.stdout
    assert "created" not in proc.stdout
    assert progress_of(ws)["current"] == LAST.id
    assert (ws / ".ros2course" / "progress.json").read_bytes() == before


# --- hint ----------------------------------------------------------------------

def test_hints_in_order_remembered_and_stay_on_the_last(ws, cli):
    assert cli("next", cwd=ws).returncode == 0
    hints = FIRST.hints
    total = len(hints)
    for number in range(1, total + 2):
        proc = cli("hint", cwd=ws)
        assert proc.returncode == 0, proc.stderr
        shown = min(number, total)
        assert f"Hint {shown}/{total} for {FIRST.id}" in proc.stdout
        out = normalised(proc.stdout)
        assert plain(hints[shown - 1]) in out
        for other, text in enumerate(hints, 1):
            if other != shown:
                assert plain(text) not in out
        assert progress_of(ws)["lessons"][FIRST.id]["hints_shown"] == shown
        assert ("That was the last hint." in proc.stdout) == (number > total)

    # counts are per lesson: an explicit lesson starts at its own first hint
    other = CATALOG.get(PRINT_FOREVER)
    proc = cli("hint", PRINT_FOREVER, cwd=ws)
    assert proc.returncode == 0, proc.stderr
    assert f"Hint 1/{len(other.hints)} for {PRINT_FOREVER}" in proc.stdout
    assert plain(other.hints[0]) in normalised(proc.stdout)
    assert progress_of(ws)["lessons"][FIRST.id]["hints_shown"] == total


# --- reset ---------------------------------------------------------------------

def test_reset_backs_up_and_restores_the_starter(ws, cli):
    next_until(ws, cli, PRINT_FOREVER)
    lesson = CATALOG.get(PRINT_FOREVER)
    node = ws / PKG / "python_package_with_a_node" / "print_forever_node.py"
    mine = b"# my attempt\nprint('hello')\n"
    node.write_bytes(mine)
    untouched = ws / PKG / "setup.py"
    # files that differ from this lesson's starter (an earlier lesson may have shipped its own version)
    sources = starter_sources(lesson)
    differing = sorted(rel for rel, source in sources.items()
                       if (ws / rel).is_file() and (ws / rel).read_bytes() != source.read_bytes())
    assert node.relative_to(ws) in differing

    proc = cli("reset", PRINT_FOREVER, cwd=ws)
    assert proc.returncode == 0, proc.stderr
    rel = node.relative_to(ws)
    starter = sources[rel].read_bytes()
    assert node.read_bytes() == starter != mine
    assert untouched.read_bytes() == sources[untouched.relative_to(ws)].read_bytes()

    stamps = list((ws / ".ros2course" / "backups" / PRINT_FOREVER).iterdir())
    assert len(stamps) == 1
    backup = stamps[0]
    assert (backup / rel).read_bytes() == mine
    backed_up = sorted(p.relative_to(backup) for p in backup.rglob("*") if p.is_file())
    assert backed_up == differing, "exactly the files that differed from the starter are backed up"
    assert f"restored {rel}" in proc.stdout
    assert "".join(f"Your previous files are in {backup}".split()) in "".join(proc.stdout.split())


# --- check: real ROS nodes ----------------------------------------------------------

@pytest.mark.ros
def test_check_json_on_the_reference_solution(solution_workspace, cli):
    root = solution_workspace.root
    proc = cli("check", PRINT_FOREVER, "--json", cwd=root)
    assert proc.returncode == 0, (proc.stdout, proc.stderr)
    result = json.loads(proc.stdout)  # the whole of stdout is one JSON document
    assert set(result) == RESULT_KEYS
    assert result["lesson"] == PRINT_FOREVER
    assert result["status"] == "passed"
    assert result["score"] == result["max_score"] > 0
    assert result["checks"], "a passed result lists its checks"
    for check in result["checks"]:
        assert set(check) == CHECK_KEYS
        assert check["passed"] is True
        assert check["points"] == check["max_points"]
    assert sum(c["max_points"] for c in result["checks"]) == result["max_score"]

    record = progress_of(root)["lessons"][PRINT_FOREVER]
    assert record["attempts"] == 1
    assert record["last_status"] == "passed"
    assert record["best_score"] == record["max_score"] == result["max_score"]
    listing = cli("list", cwd=root)
    row = row_of(listing.stdout, PRINT_FOREVER)
    assert "done" in row
    assert f"{result['max_score']:g}/{result['max_score']:g}" in row


@pytest.mark.ros
def test_check_on_the_starter_fails_and_explains(ws, cli):
    next_until(ws, cli, PRINT_FOREVER)
    proc = cli("check", cwd=ws)  # the current lesson
    assert proc.returncode == 1, (proc.stdout, proc.stderr)
    assert "Traceback" not in proc.stdout + proc.stderr
    out = proc.stdout
    assert f"{PRINT_FOREVER}: failed" in out
    # every failed check is named, with observed and expected lines
    failed = [line for line in out.splitlines() if line.startswith("✘ ")]
    assert "✘ package.xml declares the rclpy dependency" in failed
    assert "✘ ros2 run finds print_forever_node" in failed
    assert len([line for line in out.splitlines() if line.strip().startswith("observed:")]) == len(failed)
    assert len([line for line in out.splitlines() if line.strip().startswith("expected:")]) == len(failed)
    assert "observed: package.xml dependencies: none" in out
    assert "no executable print_forever_node" in out
    assert "check(s) not run" in out  # the checks that depend on the executable are summarised
    record = progress_of(ws)["lessons"][PRINT_FOREVER]
    assert record["attempts"] == 1 and record["last_status"] == "failed"
    assert record["best_score"] < record["max_score"]


@pytest.mark.ros
def test_check_unbuilt_workspace_setup_reports(ws, cli):
    proc = cli("check", WS_SETUP.id, "--json", cwd=ws)
    assert proc.returncode == 1, (proc.stdout, proc.stderr)
    result = json.loads(proc.stdout)
    assert set(result) == RESULT_KEYS
    assert result["status"] == "failed"
    checks = {c["id"]: c for c in result["checks"]}
    assert checks["src_folder"]["passed"] is True
    assert checks["built"]["passed"] is False
    assert "build/" in checks["built"]["observed"] and "install/" in checks["built"]["observed"]
    assert checks["sourceable"]["passed"] is False
    assert 0 < result["score"] < result["max_score"]
    assert progress_of(ws)["lessons"][WS_SETUP.id]["last_status"] == "failed"


@pytest.mark.ros
def test_check_workspace_setup_does_not_see_its_own_log_folder(ws, cli):
    proc = cli("check", WS_SETUP.id, "--json", cwd=ws)
    result = json.loads(proc.stdout)
    checks = {c["id"]: c for c in result["checks"]}
    assert "log/" in checks["built"]["observed"]  # the learner never built: log/ is missing too
    assert "log/" not in checks["src_folder"]["observed"]


@pytest.mark.ros
def test_check_with_invalid_package_xml_is_not_gradable(solution_workspace, cli):
    root = solution_workspace.root
    xml = root / PKG / "package.xml"
    xml.write_text(xml.read_text().replace("</package>", "</packag>"))
    proc = cli("check", PRINT_FOREVER, "--json", cwd=root)
    assert proc.returncode == 3, (proc.stdout, proc.stderr)
    assert "Traceback" not in proc.stdout + proc.stderr
    result = json.loads(proc.stdout)
    assert set(result) == RESULT_KEYS | {"message"}
    assert result["status"] == "not gradable"
    assert result["score"] == 0 and result["checks"] == []
    assert "package.xml" in result["message"]
    assert progress_of(root)["lessons"][PRINT_FOREVER]["last_status"] == "not gradable"


@pytest.mark.ros
def test_not_gradable_message_says_what_is_wrong_in_package_xml(solution_workspace, cli):
    root = solution_workspace.root
    xml = root / PKG / "package.xml"
    xml.write_text(xml.read_text().replace("</package>", "</packag>"))
    result = json.loads(cli("check", PRINT_FOREVER, "--json", cwd=root).stdout)
    assert "mismatched tag" in result["message"] or "line " in result["message"]


@pytest.mark.ros
def test_check_a_workspace_never_initialised(tmp_path, cli):
    plain_ws = tmp_path / "plain"
    (plain_ws / "src").mkdir(parents=True)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    proc = cli("check", WS_SETUP.id, "--json", "--workspace", str(plain_ws), cwd=elsewhere)
    assert proc.returncode == 1, (proc.stdout, proc.stderr)
    result = json.loads(proc.stdout)
    assert set(result) == RESULT_KEYS
    assert result["lesson"] == WS_SETUP.id
    assert {c["id"]: c for c in result["checks"]}["src_folder"]["passed"] is True
    assert not (plain_ws / ".ros2course").exists()
    assert not (elsewhere / ".ros2course").exists()


# --- bad input ------------------------------------------------------------------

@pytest.mark.parametrize("args", [["list"], ["next"], ["hint"], ["check"], ["reset", "workspace-setup"]])
def test_no_workspace(tmp_path, cli, args):
    empty = tmp_path / "empty"
    empty.mkdir()
    proc = cli(*args, cwd=empty)
    assert_clean_error(proc, 5, "no ros2course workspace", str(empty))
    assert "init" in hint_line(proc)
    assert list(empty.iterdir()) == []


@pytest.mark.parametrize("args", [["list"], ["next"], ["hint", FIRST.id], ["check", FIRST.id]])
def test_workspace_option_to_a_missing_folder(tmp_path, cli, args):
    missing = tmp_path / "nowhere"
    proc = cli(*args, "--workspace", str(missing), cwd=tmp_path)
    assert_clean_error(proc, 5, str(missing), "does not exist", one_line=True)
    assert not missing.exists()


def test_workspace_option_to_a_folder_without_src(tmp_path, cli):
    folder = tmp_path / "nosrc"
    folder.mkdir()
    proc = cli("check", FIRST.id, "--json", "-w", str(folder), cwd=tmp_path)
    assert_clean_error(proc, 5, str(folder), "src/")


@pytest.mark.parametrize("command", ["check", "hint", "reset"])
def test_unknown_lesson(ws, cli, command):
    proc = cli(command, "no-such-lesson", cwd=ws)
    assert_clean_error(proc, 5, "unknown lesson 'no-such-lesson'", one_line=True)
    assert "ros2course list" in hint_line(proc)


@pytest.mark.parametrize("command", ["check", "hint", "reset"])
def test_unknown_lesson_close_match(ws, cli, command):
    proc = cli(command, "print-forever", cwd=ws)
    assert_clean_error(proc, 5, "unknown lesson 'print-forever'", one_line=True)
    assert "did you mean" in hint_line(proc) and PRINT_FOREVER in hint_line(proc)
    assert not (ws / PKG).exists(), "reset of an unknown lesson must not touch the workspace"


def _break_lesson(course: Path, folder: str, mutate) -> Path:
    path = course / "chapters" / folder / "lesson.yaml"
    data = yaml.safe_load(path.read_text(encoding="utf-8"))
    mutate(data)
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


@pytest.mark.parametrize("args", [["list"], ["check", "workspace-setup"], ["next"]])
def test_malformed_lesson_names_file_and_field(tmp_path, ws, cli, args):
    course = copy_course(tmp_path / "c")
    folder = CATALOG.get(PRINT_FOREVER).folder.name
    path = _break_lesson(course, folder, lambda d: d.update(hints=d["hints"][:1]))
    before = (ws / ".ros2course" / "progress.json").read_bytes()
    proc = cli(*args, cwd=ws, env={"ROS2COURSE_CONTENT": str(course)})
    line = assert_clean_error(proc, 5, str(path.resolve()), "hints")
    assert "at least 3" in line
    assert (ws / ".ros2course" / "progress.json").read_bytes() == before


def test_malformed_lesson_missing_field(tmp_path, ws, cli):
    course = copy_course(tmp_path / "c")
    path = _break_lesson(course, FIRST.folder.name, lambda d: d.pop("grader"))
    proc = cli("list", cwd=ws, env={"ROS2COURSE_CONTENT": str(course)})
    assert_clean_error(proc, 5, str(path.resolve()), "grader", "required")


def test_lesson_file_that_is_not_yaml(tmp_path, ws, cli):
    course = copy_course(tmp_path / "c")
    path = course / "chapters" / FIRST.folder.name / "lesson.yaml"
    path.write_text("id: workspace-setup\ntitle: [unclosed\nhints: x\n", encoding="utf-8")
    proc = cli("list", cwd=ws, env={"ROS2COURSE_CONTENT": str(course)})
    assert_clean_error(proc, 5, str(path.resolve()), "YAML")
    assert "YAML" in hint_line(proc)


def test_lesson_file_that_is_not_yaml_says_where(tmp_path, ws, cli):
    course = copy_course(tmp_path / "c")
    path = course / "chapters" / FIRST.folder.name / "lesson.yaml"
    path.write_text("id: workspace-setup\ntitle: [unclosed\nhints: x\n", encoding="utf-8")
    proc = cli("list", cwd=ws, env={"ROS2COURSE_CONTENT": str(course)})
    line = assert_clean_error(proc, 5, str(path.resolve()))
    assert "line " in line


@pytest.mark.parametrize("args", [["list"], ["next"], ["hint"], ["check", FIRST.id, "--json"]])
def test_corrupt_progress_file(ws, cli, args):
    progress_file = ws / ".ros2course" / "progress.json"
    garbage = b"{this is not json\x00"
    progress_file.write_bytes(garbage)
    proc = cli(*args, cwd=ws)
    assert_clean_error(proc, 5, str(progress_file), "progress file")
    assert "init" in hint_line(proc)
    assert progress_file.read_bytes() == garbage
    assert sorted(p.name for p in progress_file.parent.iterdir()) == [".gitignore", "progress.json"]


def test_next_with_a_stale_current_lesson(ws, cli):
    (ws / ".ros2course" / "progress.json").write_text(
        json.dumps({"version": 1, "current": "old-lesson", "lessons": {}}), encoding="utf-8")
    proc = cli("next", cwd=ws)
    assert proc.returncode == 0, proc.stderr
    assert "old-lesson" in proc.stderr and "Traceback" not in proc.stderr
    assert json.loads((ws / ".ros2course" / "progress.json").read_text())["current"] == FIRST.id


def test_hint_with_a_negative_hint_count_in_progress(ws, cli):
    (ws / ".ros2course" / "progress.json").write_text(json.dumps(
        {"version": 1, "current": FIRST.id, "lessons": {FIRST.id: {"hints_shown": -7}}}), encoding="utf-8")
    proc = cli("hint", cwd=ws)
    assert "Traceback" not in proc.stdout + proc.stderr
    if proc.returncode == 0:
        assert f"Hint 1/{len(FIRST.hints)}" in proc.stdout
    else:
        assert_clean_error(proc, 5, "progress")


def test_long_error_message_stays_on_one_line(tmp_path, cli):
    missing = tmp_path / ("d" * 220) / "missing"
    proc = cli("list", "--workspace", str(missing), cwd=tmp_path)
    assert_clean_error(proc, 5, str(missing), "does not exist", one_line=True)
