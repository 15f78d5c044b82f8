"""What ``ros2course list`` shows, read without validating the whole course each time.

Issue 13 wants ``list`` to start in under 0.25 s. Loading the catalog means
pydantic (its import and model construction, about 90 ms) and PyYAML for every
``lesson.yaml``; reading progress means pydantic again. This module gives
``list`` the same rows from:

* a **catalog index**: a small JSON file in the user's cache folder
  (platformdirs, ``~/.cache/ros2course`` on Linux; ``ROS2COURSE_CACHE_DIR``
  overrides) with each lesson's id, title, chapters and workspace paths,
  written after a full, validated :func:`ros2course.lesson.catalog.load_catalog`
  and used only while its *fingerprint* matches: the content folder and,
  per lesson folder, the ``lesson.yaml``'s size and
  mtime (ns) and the starter folder's mtime (a starter's top-level entries
  name the files of lessons without packages), and the mtimes of the loader's
  own code (``catalog.py``, ``schema.py``, this file). Any change, a malformed lesson
  included, fails the match, so the full loader runs and reports errors
  exactly as before. An unwritable cache folder only costs the speed-up.
* a **plain read of progress.json** (:func:`progress_view`) that accepts only
  files whose every known field has the type the pydantic model declares
  (:mod:`ros2course.lesson.progress`); anything else goes through the validating
  loader, which returns the same data or raises the same error.

Like git's index, the cache is an optimisation the tool can always rebuild.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

from ros2course.files import atomic_write_text, cache_dir
from ros2course.lesson.status import lesson_status
from ros2course.lesson.workspace import Workspace, plain_progress

#: Bumped when the index's layout changes (old files are then rebuilt).
INDEX_FORMAT = 1


class LessonEntry(NamedTuple):
    """One row of ``list``: what :class:`ros2course.lesson.catalog.Lesson` says about a lesson, nothing more."""

    id: str
    title: str
    chapters: list[int]
    workspace_paths: list[str]


def _loader_stamp() -> list[int]:
    """mtimes (ns) of the code that turns a ``lesson.yaml`` into a row: a changed loader rebuilds the index."""
    here = Path(__file__).resolve().parent
    return [os.stat(here / name).st_mtime_ns for name in ("catalog.py", "schema.py", "index.py", "courses.py")]


def fingerprint(chapters_dir: Path) -> list[list]:
    """Per lesson folder: ``[name, yaml size, yaml mtime ns, starter mtime ns or 0]``, sorted by name.

    Raises:
        OSError: the chapters folder cannot be listed.
    """
    rows = []
    with os.scandir(chapters_dir) as entries:
        for entry in entries:
            try:
                stat = os.stat(os.path.join(entry.path, "lesson.yaml"))
            except OSError:
                continue  # not a lesson folder (the catalog skips it too)
            try:
                starter = os.stat(os.path.join(entry.path, "starter")).st_mtime_ns
            except OSError:
                starter = 0
            rows.append([entry.name, stat.st_size, stat.st_mtime_ns, starter])
    try:  # the course's manifest orders the lessons (ros2course.lesson.courses)
        manifest = os.stat(os.path.join(os.path.dirname(chapters_dir), "course.yaml"))
        rows.append(["course.yaml", manifest.st_size, manifest.st_mtime_ns, 0])
    except OSError:
        pass
    return sorted(rows)


def _index_path(chapters_dir: Path) -> Path:
    digest = hashlib.sha256(str(chapters_dir).encode()).hexdigest()[:16]
    return cache_dir() / f"catalog-index-{digest}.json"


def catalog_entries(chapters_dir: Path) -> list[LessonEntry]:
    """Every lesson's :class:`LessonEntry` in course order, from the index when it matches the files.

    Args:
        chapters_dir: the course's ``chapters/`` folder (absolute).

    Raises:
        LessonFormatError: from the full loader, when the index does not match and a lesson is malformed.
    """
    try:
        current = fingerprint(chapters_dir)
    except OSError:
        current = None  # the full loader says what is wrong with the folder
    path = _index_path(chapters_dir)
    if current is not None:
        with contextlib.suppress(OSError, ValueError, KeyError, TypeError):
            index = json.loads(path.read_text(encoding="utf-8"))
            if index["format"] == INDEX_FORMAT and index["folders"] == current and index["loader"] == _loader_stamp():
                return [LessonEntry(*row) for row in index["lessons"]]
    from ros2course.lesson.catalog import Catalog  # noqa: PLC0415 - the validating loader (pydantic, PyYAML) only when the index misses

    lessons = [LessonEntry(lesson.id, lesson.title, list(lesson.chapters), lesson.workspace_paths)
               for lesson in Catalog(chapters_dir).lessons]
    if current is not None:
        with contextlib.suppress(OSError):  # a read-only cache folder costs only the speed-up
            path.parent.mkdir(parents=True, exist_ok=True)
            atomic_write_text(path, json.dumps({"format": INDEX_FORMAT, "loader": _loader_stamp(), "folders": current,
                                                "lessons": [list(entry) for entry in lessons]}))
    return lessons


@dataclass
class RecordView:
    """One lesson's progress record as ``list`` needs it (points); the fields of ``LessonProgress``."""

    best_score: float | None = None
    max_score: float | None = None
    started: bool = False
    attempts: int = 0


@dataclass
class ProgressView:
    """The progress file as ``list`` reads it: same ``current``, ``lessons`` and :meth:`status` as ``Progress``."""

    current: str | None = None
    lessons: dict[str, RecordView] = field(default_factory=dict)

    def status(self, lesson_id: str) -> str:
        """``done``, ``current``, ``started`` or ``not started`` (:func:`ros2course.lesson.status.lesson_status`)."""
        return lesson_status(self.lessons.get(lesson_id), lesson_id, self.current)


def _plain_progress(data: object) -> ProgressView | None:
    """The view of a decoded progress file whose fields all have their declared types
    (:func:`ros2course.lesson.workspace.plain_progress`), else None."""
    plain = plain_progress(data)
    if plain is None:
        return None
    view = ProgressView(current=plain["current"])
    for lesson_id, record in plain["lessons"].items():
        view.lessons[lesson_id] = RecordView(record["best_score"], record["max_score"], record["started"],
                                             record["attempts"])
    return view


def progress_view(ws: Workspace):
    """The workspace's progress for ``list``: a :class:`ProgressView`, or the validated ``Progress``.

    Raises:
        ProgressError: the file is unreadable or of an unknown version (from :meth:`Workspace.load_progress`).
    """
    if not ws.progress_path.is_file():
        return ProgressView()
    with contextlib.suppress(OSError, ValueError):
        view = _plain_progress(json.loads(ws.progress_path.read_text(encoding="utf-8")))
        if view is not None:
            return view
    return ws.load_progress()
