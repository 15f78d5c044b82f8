"""Visibility per check (issue 39): ``check`` shows the learner the visible checks only and says how many more
are graded at hand-in; Gradescope's per-test visibility follows the grader's declaration and the class file."""

from __future__ import annotations

import io
import json

import pytest
from rich.console import Console

from ros2course.batch.runner import class_visibility, write_outputs
from ros2course.errors import CourseError
from ros2course.grade.checklist import Check, check_dependencies
from ros2course.grade.results import CheckResult, LessonResult, Status
from ros2course.grade.session import GradingSession
from ros2course.report.table import render_result


def result(*checks: CheckResult, student: str = "") -> LessonResult:
    return LessonResult("print-forever-node", sum(c.points for c in checks), sum(c.max_points for c in checks),
                        Status.PASSED if all(c.passed for c in checks) else Status.FAILED, list(checks),
                        student=student)


def verdict(check_id: str, passed: bool, visibility: str = "visible", points: float = 1.0) -> CheckResult:
    return CheckResult(check_id, f"the {check_id} check", points if passed else 0.0, points, passed,
                       f"{check_id} observed", f"{check_id} expected", "", visibility=visibility)


def test_a_check_declares_its_visibility_and_the_session_carries_it_into_the_verdict(tmp_path):
    session = GradingSession(None, [Check("rate", "r", 1), Check("late", "l", 1, visibility="after_due")],
                             tmp_path, tmp_path / "log", {})
    session.record("rate", True, "", "")
    session.record("late", False, "", "")
    assert [r.visibility for r in session.ordered_results()] == ["visible", "after_due"]
    with pytest.raises(CourseError, match="visibility 'secret'"):
        check_dependencies([Check("a", "a", 1, visibility="secret")])


def test_the_learner_sees_the_visible_checks_scored_over_them_and_how_many_more_are_graded_at_hand_in():
    whole = result(verdict("rate", True, points=2), verdict("log", True),
                   verdict("edge", False, "hidden"), verdict("late", False, "after_due"))
    shown = whole.for_learner()
    assert [c.id for c in shown.checks] == ["rate", "log"]
    assert (shown.score, shown.max_score, shown.status, shown.withheld) == (3.0, 3.0, Status.PASSED, 2)
    assert whole.status is Status.FAILED and whole.withheld == 0  # the whole result is untouched
    assert shown.to_json()["withheld"] == 2 and "withheld" not in whole.to_json()
    out = io.StringIO()
    render_result(shown, Console(file=out, width=200))
    text = out.getvalue()
    assert "All 2 visible checks passed; 2 more check(s) are graded when you hand in your work." in text
    assert "edge" not in text and "late" not in text  # never what the withheld checks are
    plain = result(verdict("rate", True))
    assert plain.for_learner() is plain


def test_a_learner_who_fails_a_visible_check_is_told_more_are_graded_without_saying_which():
    shown = result(verdict("rate", False), verdict("edge", True, "hidden")).for_learner()
    assert shown.status is Status.FAILED and shown.withheld == 1
    out = io.StringIO()
    render_result(shown, Console(file=out, width=200))
    assert "1 more check(s) are graded when you hand in your work; they are not shown here." in out.getvalue()


def test_visibility_survives_the_results_record_and_only_when_not_visible():
    whole = result(verdict("rate", True), verdict("late", False, "after_due"))
    record = whole.to_record()
    assert "visibility" not in record["checks"][0] and record["checks"][1]["visibility"] == "after_due"
    assert [c.visibility for c in LessonResult.from_record(record).checks] == ["visible", "after_due"]


def test_gradescope_tests_follow_the_declared_visibility_and_a_class_file_overrides_it(tmp_path):
    whole = result(verdict("rate", True), verdict("edge", False, "hidden"), verdict("late", False, "after_due"))
    assert [t["visibility"] for t in whole.gradescope_tests(prefix=False)] == ["visible", "hidden", "after_due_date"]
    overridden = whole.with_visibility({"rate": "after_due", "edge": "visible", "nope": "hidden"})
    assert [c.visibility for c in overridden.checks] == ["after_due", "visible", "after_due"]

    out_dir = tmp_path / "out"
    (out_dir / "alice").mkdir(parents=True)
    (out_dir / "class.yaml").write_text("lessons:\n  print-forever-node: {due: 2026-03-01T23:59:00+01:00}\n"
                                        "visibility:\n  print-forever-node: {rate: hidden}\n", encoding="utf-8")
    write_outputs(out_dir, [result(verdict("rate", True), verdict("log", True), student="alice")],
                  ["print-forever-node"], ["alice"])
    tests = json.loads((out_dir / "alice" / "results.json").read_text(encoding="utf-8"))["tests"]
    assert [t["visibility"] for t in tests] == ["hidden", "visible"]


def test_a_bad_class_file_in_outdir_is_one_line_error(tmp_path):
    assert class_visibility(tmp_path) == {}
    (tmp_path / "class.yaml").write_text("lessons:\n  print-forever-node: {due: 2026-03-01T23:59:00+01:00}\n"
                                         "visibility:\n  print-forever-node: {rate: secret}\n", encoding="utf-8")
    with pytest.raises(CourseError, match="not a visibility"):
        class_visibility(tmp_path)
