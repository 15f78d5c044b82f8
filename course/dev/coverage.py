"""Contract coverage of the course's lessons (issue 37): each ``contract.yaml`` against its grader's checks.

:mod:`ros2course.lesson.contract` reads a lesson's ``contract.yaml``; this module
gives it the lesson's check ids (the grader's ``CHECKS``, :func:`~ros2course.grade.engine.load_grader`),
for ``ros2course dev validate`` (:func:`lesson_coverage`) and for ``ros2course dev
contract-coverage``, which renders ``docs/contract-coverage.md`` (:func:`coverage_document`).
No ROS is needed: a grader module loads for its ``CHECKS`` alone.
"""

from __future__ import annotations

from pathlib import Path

from ros2course.errors import CourseError
from ros2course.grade.engine import load_grader
from ros2course.lesson.catalog import Lesson, content_root, load_catalog
from ros2course.lesson.contract import (
    ContractProblem,
    LessonCoverage,
    contract_path,
    coverage_markdown,
    load_contract,
)

#: The document, relative to the course folder.
COVERAGE_DOC = Path("docs") / "contract-coverage.md"


def lesson_coverage(lesson: Lesson) -> LessonCoverage:
    """The lesson's contract and its problems; ``contract`` None and no problems when it has no ``contract.yaml``."""
    path = contract_path(lesson.folder)
    row = LessonCoverage(lesson.id, lesson.folder.name, None)
    if not path.is_file():
        return row
    try:
        check_ids = {check.id for check in load_grader(lesson.grader).CHECKS}
    except CourseError as exc:
        row.problems = [ContractProblem(path, 1, f"its grader's checks cannot be read: {exc}")]
        return row
    row.contract, row.problems = load_contract(path, lesson.id, check_ids)
    return row


def course_coverage(lesson_ids: list[str] | None = None) -> list[LessonCoverage]:
    """:func:`lesson_coverage` of the given lessons (default: every lesson, in course order)."""
    catalog = load_catalog()
    lessons = [catalog.get(i) for i in lesson_ids] if lesson_ids else catalog.lessons
    return [lesson_coverage(lesson) for lesson in lessons]


def coverage_document() -> tuple[str, list[ContractProblem]]:
    """``docs/contract-coverage.md`` as it should read now, and every problem of every ``contract.yaml``."""
    rows = course_coverage()
    return coverage_markdown(rows), [p for row in rows for p in row.problems]


def coverage_doc_path() -> Path:
    """Where the document lives in the active course."""
    return content_root() / COVERAGE_DOC
