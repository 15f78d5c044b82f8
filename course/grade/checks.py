"""What a grader declares: its checks (:class:`Check`, with points and needs) and :class:`Unmet`.

A grader module lists ``CHECKS`` (a list of :class:`Check`); the engine validates their
``needs`` (:func:`check_dependencies`) before grading. Re-exported by the public grading
module, :mod:`ros2course.kit`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

from ros2course.errors import CourseError


@dataclasses.dataclass(frozen=True)
class Check:
    """One graded property of a submission.

    Attributes:
        id: stable, snake_case, unique within the lesson (fixtures and reports name it).
        name: one line, what is checked, in the learner's terms.
        points: points for passing (partial credit is spread over checks).
        hint: default learner-facing hint shown when it fails.
        needs: ids of earlier checks this one depends on. When one of them
            fails (or was itself not checked), the engine records this check
            as "not checked" with the reason, whatever the grader does.
        part: the independent part of the lesson it belongs to (e.g. one of two
            executables; see :meth:`GradingSession.part`); "" for the whole lesson.
    """

    id: str
    name: str
    points: float
    hint: str = ""
    needs: tuple[str, ...] = ()
    part: str = ""


class Unmet(Exception):  # noqa: N818 - a grading outcome, not an error of the course
    """A check that later steps depend on did not pass: the current part of the grader ends.

    Raised by :meth:`GradingSession.require` and by grader-kit steps that
    return a value the rest of the part needs (an executable, a node). Caught
    by :meth:`GradingSession.part` (and by the engine around ``grade()``),
    which then runs the part's closing actions; the checks left unrecorded
    become "not checked" with the reason.
    """


def check_dependencies(checks: Sequence[Check]) -> None:
    """Validate ``needs``: every id names an earlier check of the same list.

    Raises:
        CourseError: a duplicate id, or a need that is unknown or not earlier (a cycle).
    """
    seen: set[str] = set()
    for check in checks:
        if check.id in seen:
            raise CourseError(f"check id {check.id!r} is declared twice", "check ids are unique within a lesson")
        for need in check.needs:
            if need not in seen:
                raise CourseError(f"check {check.id!r} needs {need!r}, which is not an earlier check",
                                  "list a check's needs before it in CHECKS")
        seen.add(check.id)
