"""``list`` reads the kept catalog and progress.json without pydantic (course/lesson/progress_view.py).

The kept catalog must never show something the validated catalog would not: it is
rebuilt whenever what validation reads changes (by content), and a malformed lesson
is reported exactly as without it.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from ros2course.errors import ProgressError
from ros2course.lesson.catalog import Catalog, content_root, load_catalog
from ros2course.lesson.progress_view import progress_view
from ros2course.lesson.progress import Progress
from ros2course.lesson.workspace import Workspace, plain_progress, progress_text
from tests.test_cli import assert_clean_error, copy_course


@pytest.fixture
def cli():
    """The CLI in this process (typer's CliRunner): no process boundary is under test here (issue 23)."""
    from conftest import run_cli_in_process

    return run_cli_in_process

CHAPTERS = content_root() / "chapters"


@pytest.fixture
def learner_ws(tmp_path: Path, cli) -> Path:
    """A workspace made by ``ros2course init``."""
    assert cli("init", "ws", cwd=tmp_path).returncode == 0
    return tmp_path / "ws"


def test_list_shows_the_validated_catalog_from_miss_and_hit(tmp_path, monkeypatch, learner_ws, cli):
    monkeypatch.setenv("ROS2COURSE_CACHE_DIR", str(tmp_path / "cache"))
    from ros2course.lesson import catalog as catalog_module

    ids = [lesson.id for lesson in Catalog(CHAPTERS).lessons]
    for _ in range(2):  # miss (the kept catalog is written), then hit
        catalog_module._catalog_of.cache_clear()  # as in a new process: only the kept file is shared
        proc = cli("list", cwd=learner_ws, env={"ROS2COURSE_CACHE_DIR": str(tmp_path / "cache"), "COLUMNS": "320"})
        assert proc.returncode == 0, proc.stderr
        shown = [line.split("│")[2].strip() for line in proc.stdout.splitlines() if line.count("│") > 3]
        assert [name for name in shown if name and name != "lesson"] == ids
    assert any(p.name.startswith("catalog-") for p in (tmp_path / "cache").iterdir())


def test_a_changed_title_is_seen_at_once(tmp_path, monkeypatch):
    from ros2course.lesson import catalog as catalog_module

    monkeypatch.setenv("ROS2COURSE_CACHE_DIR", str(tmp_path / "cache"))
    course = copy_course(tmp_path / "c")
    chapters = course / "chapters"
    first = load_catalog(course).lessons[0].title  # kept
    path = chapters / "terminal-basics" / "lesson.yaml"  # course.yaml's first lesson
    data = yaml.safe_load(path.read_text(encoding="utf-8"))
    data["title"] = "A title the kept catalog has never seen"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    catalog_module._catalog_of.cache_clear()  # as in a new process: only the kept file is shared
    assert load_catalog(course).lessons[0].title == "A title the kept catalog has never seen" != first


def test_list_reports_a_lesson_broken_after_the_catalog_was_kept(tmp_path, learner_ws, cli):
    course = copy_course(tmp_path / "c")
    env = {"ROS2COURSE_CONTENT": str(course), "ROS2COURSE_CACHE_DIR": str(tmp_path / "cache")}
    assert cli("list", cwd=learner_ws, env=env).returncode == 0
    assert any((tmp_path / "cache").iterdir())
    path = course / "chapters" / "terminal-basics" / "lesson.yaml"  # course.yaml's first lesson
    data = yaml.safe_load(path.read_text(encoding="utf-8"))
    data["hints"] = data["hints"][:1]
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    from ros2course.lesson import catalog as catalog_module

    catalog_module._catalog_of.cache_clear()  # as in a new process: only the kept file is shared
    assert_clean_error(cli("list", cwd=learner_ws, env=env), 5, str(path.resolve()), "hints")


def test_list_works_when_the_cache_folder_cannot_be_written(tmp_path, learner_ws, cli):
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("a file where the cache folder would be\n", encoding="utf-8")
    proc = cli("list", cwd=learner_ws, env={"ROS2COURSE_CACHE_DIR": str(blocker / "cache")})
    assert proc.returncode == 0, proc.stderr
    assert "terminal-basics" in proc.stdout and not proc.stderr


def test_list_imports_neither_pydantic_nor_yaml_once_kept(learner_ws, cli):
    probe = ("import sys; from ros2course.cli import main; sys.argv = ['ros2course', 'list']\n"
             "try:\n    main()\nexcept SystemExit:\n    pass\n"
             "print('LOADED', sorted(m for m in ('pydantic', 'yaml', 'rclpy') if m in sys.modules), file=sys.stderr)")
    for _ in range(2):  # the first process keeps the catalog if none is kept for this course yet
        proc = subprocess.run([sys.executable, "-c", probe], cwd=learner_ws, capture_output=True, text=True,
                              timeout=60, env={**os.environ, "COLUMNS": "320"}, check=False)
    assert "LOADED []" in proc.stderr, proc.stderr


PROGRESS_FILES = [
    {"version": 1, "current": "parameters", "lessons": {}},
    {"version": 1, "current": "parameters",
     "lessons": {"parameters": {"attempts": 2, "best_score": 4.0, "max_score": 9.0, "started": True},
                 "terminal-basics": {"best_score": 7, "max_score": 7, "attempts": 1, "hints_shown": 2},
                 "cpp-node": {"started": True}, "cpp-library": {"attempts": 1, "last_status": "failed"}}},
    # types pydantic coerces: the plain reader declines, the validating loader decides
    {"version": 1, "current": None, "lessons": {"parameters": {"attempts": "2", "best_score": "9", "max_score": 9}}},
    {"version": 1, "lessons": {"parameters": {"started": "yes", "best_score": 1, "max_score": 1}}},
    {"version": 1, "lessons": {"parameters": {"attempts": True}}},
]


@pytest.mark.parametrize("data", PROGRESS_FILES)
def test_progress_view_gives_the_validated_statuses(tmp_path, data):
    workspace = Workspace(tmp_path)
    workspace.init()
    workspace.progress_path.write_text(json.dumps(data), encoding="utf-8")
    view, validated = progress_view(workspace), Progress.model_validate(data)
    for lesson_id in ("parameters", "terminal-basics", "cpp-node", "cpp-library", "sas-robot-driver"):
        assert view.status(lesson_id) == validated.status(lesson_id), lesson_id
        record, truth = view.lessons.get(lesson_id), validated.lessons.get(lesson_id)
        assert (record is None) == (truth is None)
        if record is not None:
            assert (record.best_score, record.max_score) == (truth.best_score, truth.max_score)


@pytest.mark.parametrize("data", [{"version": 2, "lessons": {}}, {"version": 1, "lessons": {"x": {"attempts": -1}}},
                                  {"version": 1, "lessons": []}])
def test_progress_view_raises_what_the_validating_loader_raises(tmp_path, data):
    workspace = Workspace(tmp_path)
    workspace.init()
    workspace.progress_path.write_text(json.dumps(data), encoding="utf-8")
    with pytest.raises(ProgressError):
        workspace.load_progress()
    with pytest.raises(ProgressError):
        progress_view(workspace)


def test_no_progress_file_means_nothing_started(tmp_path):
    view = progress_view(Workspace(tmp_path))
    assert view.status("terminal-basics") == "not started" and not view.lessons


def test_the_kept_catalog_is_keyed_by_content_not_file_times(tmp_path, monkeypatch):
    """`check` loads the validated catalog kept in the cache folder (issue 36); a lesson.yaml changed
    with its size and mtime kept (a copy with old times) must still be read anew, and a cache file
    another user could have written is never loaded."""
    from ros2course.lesson import catalog as catalog_mod

    monkeypatch.setenv("ROS2COURSE_CACHE_DIR", str(tmp_path / "cache"))
    course = copy_course(tmp_path / "course")
    (course / "course.yaml").write_bytes((content_root() / "course.yaml").read_bytes())
    load = catalog_mod._catalog_of.__wrapped__  # past the in-process lru_cache: a new process each call
    chapters = course / "chapters"
    first = load(course)
    key = catalog_mod._catalog_key(chapters)
    kept = catalog_mod._cached_catalog(chapters, key)
    assert kept is not None and kept.ids() == first.ids()
    lesson = kept.get("print-forever-node")
    assert lesson == first.get("print-forever-node") and lesson.folder == chapters / "print-forever-node"
    assert [p.name for p in kept.get("launch-files").starter_layers] == [
        p.name for p in first.get("launch-files").starter_layers]

    path = chapters / "print-forever-node" / "lesson.yaml"
    text, stat = path.read_text(encoding="utf-8"), path.stat()
    title = first.get("print-forever-node").title
    changed = text.replace(title, title[::-1], 1)
    assert len(changed) == len(text) and changed != text
    path.write_text(changed, encoding="utf-8")
    os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns))  # same size, same time: only the content differs
    assert load(course).get("print-forever-node").title == title[::-1]

    cache_file = catalog_mod._catalog_cache_path(chapters)
    cache_file.chmod(0o666)  # anyone could have written it: not trusted
    assert catalog_mod._cached_catalog(chapters, catalog_mod._catalog_key(chapters)) is None
    assert load(course).get("print-forever-node").title == title[::-1]  # full load, kept again as 0600
    assert cache_file.stat().st_mode & 0o777 == 0o600


def test_a_warm_check_reads_its_lesson_and_progress_without_pydantic_or_yaml(learner_ws):
    """What `check` reads before the learner's node starts: the kept catalog (plain dataclasses) and the
    progress file as `list` reads it; neither pydantic nor PyYAML is imported (about 60 ms, issue 36)."""
    probe = ("import sys; from pathlib import Path\n"
             "from ros2course.lesson.catalog import load_catalog\n"
             "from ros2course.lesson.progress_view import progress_view\n"
             "from ros2course.lesson.workspace import Workspace\n"
             "lesson = load_catalog().get('print-forever-node'); view = progress_view(Workspace(Path('.')))\n"
             "print('READ', lesson.packages, lesson.graph is not None, view.status(lesson.id))\n"
             "print('LOADED', sorted(m for m in ('pydantic', 'yaml') if m in sys.modules))")
    for _ in range(2):  # the first run keeps the catalog if none is kept yet
        proc = subprocess.run([sys.executable, "-c", probe], cwd=learner_ws, capture_output=True, text=True,
                              timeout=60, check=False)
    assert "READ ['python_package_with_a_node'] True" in proc.stdout and "LOADED []" in proc.stdout, \
        proc.stdout + proc.stderr


@pytest.mark.parametrize("data", PROGRESS_FILES + [
    {"version": 1, "current": "qos", "course": {"id": "ros2-tutorial", "version": "1.6.0", "path": "/c"},
     "lessons": {"qos": {"attempts": 3, "best_score": 20, "max_score": 30.5, "last_status": "failed",
                         "extra": "dropped"}}}])
def test_the_plain_reading_is_what_the_validating_loader_writes(data):
    """One file format, whoever writes it: what plain_progress makes of a file is, to the byte, what the
    pydantic model writes for it; files it declines are the ones the model coerces."""
    plain = plain_progress(data)
    validated = Progress.model_validate(data).model_dump(mode="json")
    if plain is None:
        assert any(isinstance(v, (str, bool)) for r in data["lessons"].values() for k, v in r.items()
                   if k in ("attempts", "best_score", "started"))
    else:
        assert progress_text(plain) == progress_text(validated)


def test_a_check_records_its_attempt_without_pydantic(tmp_path):
    """record_attempt on a file the plain reader accepts: the same file the validating path writes, and no
    pydantic imported (about 90 ms of every check of an init-ed workspace, issue 36)."""
    workspace = Workspace(tmp_path)
    workspace.init()
    data = PROGRESS_FILES[1]
    workspace.progress_path.write_text(json.dumps(data), encoding="utf-8")
    probe = ("import sys; from pathlib import Path; from ros2course.lesson.workspace import Workspace\n"
             f"Workspace(Path({str(tmp_path)!r})).record_attempt('parameters', 'passed', 9, 9)\n"
             "Workspace(Path({!r})).record_attempt('qos', 'failed', 3, 30)\n".format(str(tmp_path))
             + "print('LOADED', 'pydantic' in sys.modules)")
    proc = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=60, check=False)
    assert "LOADED False" in proc.stdout, proc.stdout + proc.stderr
    expected = Progress.model_validate(data)
    for lesson_id, status, score, most in (("parameters", "passed", 9, 9), ("qos", "failed", 3, 30)):
        record = expected.lesson(lesson_id)
        record.attempts += 1
        record.last_status, record.max_score = status, float(most)
        if record.best_score is None or score > record.best_score:
            record.best_score = float(score)
    assert workspace.progress_path.read_text(encoding="utf-8") == progress_text(expected.model_dump(mode="json"))
    assert workspace.load_progress().status("parameters") == "done"
