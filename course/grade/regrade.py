"""``check --all``: re-grade every lesson a learner has passed, in course order, after one build.

codecrafters' ``test --previous`` and rustlings' verify-all catch the same
mistake: editing a package for a later lesson breaks an earlier one (the
launch-files lesson edits the parameters lesson's package, the sas lesson's
client reuses the publisher's habits). A regression is a lesson whose
progress says "done" (full marks once) and whose new grade is not full marks.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from pathlib import Path

from ros2course.builder import colcon as build_mod
from ros2course.errors import NotGradable
from ros2course.grade.engine import check_lesson, new_log_dir
from ros2course.grade.results import LessonResult, Status
from ros2course.lesson.catalog import Lesson
from ros2course.lesson.progress import Progress
from ros2course.ros import env as env_mod


@dataclasses.dataclass(frozen=True)
class Regrade:
    """One lesson's new grade beside what the progress file said before.

    Attributes:
        lesson: the lesson.
        before: its best score before (points), None if never graded.
        result: the new grade.
    """

    lesson: Lesson
    before: float | None
    result: LessonResult

    @property
    def regression(self) -> bool:
        """It had full marks before and has not now."""
        return self.result.status is not Status.PASSED


def passed_lessons(lessons: Sequence[Lesson], progress: Progress) -> list[Lesson]:
    """The lessons marked "done" in ``progress`` (full marks at least once), in course order."""
    return [lesson for lesson in lessons if progress.status(lesson.id) == "done"]


def build_once(lessons: Sequence[Lesson], workspace_root: Path) -> build_mod.BuildResult | None:
    """Build the union of ``lessons``' packages with one colcon call (None when they have none).

    Each lesson's own build is then a fingerprint hit (``cached``) unless its
    build failed; a failure here is left to the lessons, each reporting its own
    package's error.
    """
    packages = sorted({name for lesson in lessons for name in lesson.packages})
    if not packages:
        return None
    env = env_mod.activate()
    try:
        return build_mod.build_packages(workspace_root, packages, env,
                                        new_log_dir(workspace_root, "check-all") / "build.log")
    except NotGradable:
        return None


def regrade(lessons: Sequence[Lesson], workspace_root: Path, progress: Progress,
            on_result: Callable[[Regrade], None] | None = None) -> list[Regrade]:
    """Grade each of ``lessons`` in order and pair it with its previous best score.

    Args:
        lessons: usually :func:`passed_lessons`.
        on_result: called after each lesson (for a live display).

    Raises:
        MissingRequirement: a lesson requires what this machine lacks (never a pass).
    """
    build_once(lessons, workspace_root)
    out = []
    for lesson in lessons:
        record = progress.lessons.get(lesson.id)
        item = Regrade(lesson, record.best_score if record else None, check_lesson(lesson, workspace_root))
        out.append(item)
        if on_result is not None:
            on_result(item)
    return out
