"""The learner's progress file ``.ros2course/progress.json``: its schema, validated with pydantic.

The file is small and versioned; :class:`ros2course.lesson.workspace.Workspace`
reads and writes it (atomically). ``list`` reads it without this module
(:mod:`ros2course.lesson.progress_view`) and falls back to it for any file it does not
recognise, so both give the same statuses.
"""

from __future__ import annotations

from pydantic import BaseModel, Field

from ros2course.lesson.status import PROGRESS_VERSION, lesson_status


class LessonProgress(BaseModel):
    """What the learner did in one lesson (scores in points)."""

    best_score: float | None = None
    max_score: float | None = None
    last_status: str | None = None
    attempts: int = Field(default=0, ge=0)
    hints_shown: int = Field(default=0, ge=0)
    started: bool = False


class CourseRecord(BaseModel):
    """Which course a workspace follows (issue 18): the manifest's id and version, and where it was found."""

    id: str
    version: str
    path: str | None = None


class Progress(BaseModel):
    """The whole progress file (``version`` guards future format changes)."""

    version: int = PROGRESS_VERSION
    current: str | None = None
    #: None in workspaces made before courses were recorded: they follow the bundled tutorial course
    course: CourseRecord | None = None
    lessons: dict[str, LessonProgress] = Field(default_factory=dict)

    def lesson(self, lesson_id: str) -> LessonProgress:
        """This lesson's record, created empty on first use."""
        return self.lessons.setdefault(lesson_id, LessonProgress())

    def status(self, lesson_id: str) -> str:
        """``done`` (full marks once), ``current``, ``started`` or ``not started`` (:func:`lesson_status`)."""
        return lesson_status(self.lessons.get(lesson_id), lesson_id, self.current)
