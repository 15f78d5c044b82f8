"""Progress as ``list`` and ``check`` read it: progress.json without pydantic (issues 13 and 36).

:func:`progress_view` accepts only files whose every known field has the type the
pydantic model declares (:func:`ros2course.lesson.workspace.plain_progress`,
:mod:`ros2course.lesson.progress`); anything else goes through the validating
loader, which returns the same data or raises the same error. The lessons
themselves come from the kept catalog (:func:`ros2course.lesson.catalog.load_catalog`,
keyed by the contents of what validation reads), which ``list`` reads as
``check`` does: a second cache of the catalog for ``list`` alone was retired
once the kept catalog loaded as fast (25 ms for 34 lessons either way).
"""

from __future__ import annotations

import contextlib
import json
from dataclasses import dataclass, field

from ros2course.lesson.status import lesson_status
from ros2course.lesson.workspace import Workspace, plain_progress


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
