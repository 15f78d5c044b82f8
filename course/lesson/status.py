"""A lesson's status in the learner's progress, computed without pydantic.

Both the pydantic schema (:mod:`ros2course.lesson.progress`) and the plain
readers (:mod:`ros2course.lesson.workspace`, :mod:`ros2course.lesson.progress_view`) use it,
so neither imports the other at module level.
"""

from __future__ import annotations

from typing import Protocol

#: The progress file's format version (``Progress.version``); another version is refused, never guessed.
PROGRESS_VERSION = 1


class LessonRecord(Protocol):
    """What :func:`lesson_status` reads of one lesson's progress record (scores in points)."""

    best_score: float | None
    max_score: float | None
    started: bool
    attempts: int


def lesson_status(record: LessonRecord | None, lesson_id: str, current: str | None) -> str:
    """``done`` (full marks once), ``current``, ``started`` or ``not started``.

    Args:
        record: the lesson's progress record, None if it has none.
        lesson_id: the lesson's id.
        current: the workspace's current lesson id (``next`` sets it), or None.
    """
    if record and record.best_score is not None and record.max_score and record.best_score >= record.max_score:
        return "done"
    if lesson_id == current:
        return "current"
    if record and (record.started or record.attempts):
        return "started"
    return "not started"
