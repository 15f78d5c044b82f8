"""What a grader declares: its checks (:class:`Check`, with points and needs) and :class:`Unmet`.

A grader module lists ``CHECKS`` (a list of :class:`Check`); the engine validates their
``needs`` (:func:`check_dependencies`) before grading. Re-exported by the public grading
module, :mod:`ros2course.kit`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence

from ros2course.errors import CourseError
from ros2course.grade.results import VISIBILITIES, CheckResult, Visibility


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
        visibility: who sees its verdict (:data:`~ros2course.grade.results.Visibility`): ``visible``
            (default), ``after_due`` (shown once the deadline passed) or ``hidden`` (never shown;
            such a check belongs in an instructor's private course, not in one learners install).
            ``check`` shows the visible ones only; a class file may override it.
    """

    id: str
    name: str
    points: float
    hint: str = ""
    needs: tuple[str, ...] = ()
    part: str = ""
    visibility: Visibility = "visible"


class Unmet(Exception):  # noqa: N818 - a grading outcome, not an error of the course
    """A check that later steps depend on did not pass: the current part of the grader ends.

    Raised by :meth:`GradingSession.require` and by grader-kit steps that
    return a value the rest of the part needs (an executable, a node). Caught
    by :meth:`GradingSession.part` (and by the engine around ``grade()``),
    which then runs the part's closing actions; the checks left unrecorded
    become "not checked" with the reason.
    """


@dataclasses.dataclass(frozen=True)
class StopWhen:
    """When ``dev validate --until-settled`` stops grading a case: once its verdict can no longer change.

    Attributes:
        judged: check ids; settled once every one is recorded (a wrong solution's named checks: only
            they decide its fixture's verdict, :meth:`ros2course.dev.validate.Fixture.judged_by`).
        any_loss: settled once any check is recorded without full points (a starter, which must only
            not get full marks).

    Never given by ``check``, ``grade`` or ``gradescope``: a learner's and a class's gradings run whole.
    """

    judged: frozenset[str] = frozenset()
    any_loss: bool = False

    def __bool__(self) -> bool:
        return bool(self.judged) or self.any_loss

    def reached(self, results: Mapping[str, CheckResult]) -> bool:
        """True when ``results`` (check id -> verdict recorded so far) settle the case."""
        if self.any_loss and any(r.points < r.max_points for r in results.values()):
            return True
        return bool(self.judged) and self.judged <= results.keys()


class VerdictSettled(BaseException):  # noqa: N818 - an end of grading, not an error
    """The case's verdict is settled (:class:`StopWhen`): ``dev validate --until-settled`` stops grading here.

    Raised by :class:`~ros2course.grade.session.GradingSession` (only when it was given a
    ``stop_when``, on the thread that runs ``grade()``) at the grader's next step after the
    verdict that settled it; caught by the engine around ``grade()``, which closes the session
    (every process stopped) and records the checks left as not judged (:data:`STOPPED_SETTLED`).
    A ``BaseException``: a grader's ``except Exception`` must not swallow it.
    """


#: The reason a check left unjudged by ``dev validate --until-settled`` shows ("not checked: " + this).
STOPPED_SETTLED = "dev validate --until-settled stopped grading once the case's verdict was settled"


def check_dependencies(checks: Sequence[Check]) -> None:
    """Validate ``needs``: every id names an earlier check of the same list; and each ``visibility``.

    Raises:
        CourseError: a duplicate id, a need that is unknown or not earlier (a cycle), an unknown visibility.
    """
    seen: set[str] = set()
    for check in checks:
        if check.id in seen:
            raise CourseError(f"check id {check.id!r} is declared twice", "check ids are unique within a lesson")
        if check.visibility not in VISIBILITIES:
            raise CourseError(f"check {check.id!r} has visibility {check.visibility!r}",
                              "use " + ", ".join(VISIBILITIES))
        for need in check.needs:
            if need not in seen:
                raise CourseError(f"check {check.id!r} needs {need!r}, which is not an earlier check",
                                  "list a check's needs before it in CHECKS")
        seen.add(check.id)
