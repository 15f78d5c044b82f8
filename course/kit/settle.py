"""Which parts of a lesson a case still needs: ``dev validate --until-settled`` grades a wrong solution only
until the checks its fixture names are judged (:class:`~ros2course.grade.checklist.StopWhen`), so a part
none of whose checks those need can be left out (issue 37's CI budget).

A learner's ``check``, a class's ``grade`` and a reference's validation want every check: there
:func:`part_needed` is always True, and every part runs.
"""

from __future__ import annotations

from collections.abc import Iterable

from ros2course.grade.checklist import Check
from ros2course.kit.session_protocol import Session


def part_needed(s: Session, checks: Iterable[Check], part: str) -> bool:
    """Whether any check declared with ``part=part`` among ``checks`` (the grader's ``CHECKS``) can still change
    the case's verdict (:meth:`Session.wanted`: False only under ``--until-settled``, for a check none of the
    named ones needs, directly or through other needs).

    A grader wraps a part in ``if part_needed(s, CHECKS, "wrench"): with s.part("wrench", ...): ...``; the
    checks of a part left out are written "not checked" when the case settles. A part whose values a later
    part reads must stay needed: declare that later part's checks as needing one of its checks.

    Raises:
        ValueError: no check of ``checks`` belongs to ``part`` (a misspelt part name would skip it silently).
    """
    own = [check.id for check in checks if check.part == part]
    if not own:
        raise ValueError(f"no check is declared with part={part!r}")
    return any(s.wanted(check_id) for check_id in own)
