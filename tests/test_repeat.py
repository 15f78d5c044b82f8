"""``dev validate --repeat N --load K``: a check whose verdict changes between runs is found (issue 24)."""

from __future__ import annotations

import json

import pytest

from ros2course.dev.repeat import Steadiness, unsteady
from ros2course.grade.results import CheckResult, LessonResult, Status
from ros2course.lesson import active_course


def _result(listed: bool, status: Status = Status.PASSED, observed: str = "") -> LessonResult:
    checks = [CheckResult("script", "script", 1, 1, True, "valid bash", "bash", ""),
              CheckResult("listed", "listed", 1 if listed else 0, 1, listed,
                          observed or ("/what_is_the_point" if listed else "no list of services"), "a list", "")]
    score = sum(c.points for c in checks)
    if status == Status.PASSED and not listed:
        status = Status.FAILED
    return LessonResult("inspect-services", score, 2, status, checks, "" if status.graded else "boom")


def test_steady_runs_report_nothing() -> None:
    assert unsteady([_result(True), _result(True), _result(True)]) == []
    assert unsteady([_result(False), _result(False)]) == []


def test_a_check_that_changes_its_verdict_is_named_with_both_observations() -> None:
    flakes = unsteady([_result(True), _result(False), _result(True)])
    by_check = {f.check: f for f in flakes}
    assert set(by_check) == {"status", "listed"}
    listed = by_check["listed"]
    assert (listed.passed, listed.failed) == (2, 1)
    assert listed.observed_pass == "/what_is_the_point" and listed.observed_fail == "no list of services"
    assert "listed: passed 2, failed 1" in listed.describe()
    row = Steadiness("inspect-services", "reference", 3, 2, flakes, 2, 1.0)
    assert not row.ok and row.to_dict()["flakes"][1]["check"] == "listed"


def test_a_grader_error_in_one_run_is_a_change_of_status() -> None:
    error = LessonResult.unfinished("inspect-services", Status.GRADER_ERROR, "RuntimeError: no domain id free")
    flakes = unsteady([_result(True), error])
    assert flakes[0].check == "status" and "no domain id free" in flakes[0].observed_fail


@pytest.mark.parametrize("args,words", [(["--repeat", "1"], "at least 2 runs"),
                                        (["--repeat", "2", "--load", "0"], "--load must be 1 or more"),
                                        (["--repeat", "2", "--batch"], "do not go together"),
                                        (["--jobs", "0"], "--jobs must be 1 or more")])
def test_bad_repeat_and_jobs_options_are_one_line_errors(cli, args, words) -> None:
    proc = cli("dev", "validate", "print-forever-node", *args)
    assert proc.returncode != 0 and words in proc.stderr and "Traceback" not in proc.stderr


@pytest.mark.ros
@pytest.mark.timeout(900)
def test_inspect_services_lists_the_graph_steadily_under_load(cli) -> None:
    """The reference's `ros2 service list --spin-time 2` used to print nothing in 7 of 16 runs two at a time."""
    proc = cli("dev", "validate", "inspect-services", "--repeat", "3", "--load", "2", "--case", "reference", "--json",
               timeout=850)
    rows = json.loads(proc.stdout)
    assert [r["case"] for r in rows] == ["reference"]
    assert rows[0]["runs"] == 3 and rows[0]["load"] == 2
    assert rows[0]["ok"], rows[0]["flakes"] or rows[0]


def test_a_reference_s_repeat_run_is_recorded_and_shown(tmp_path) -> None:
    """benchmarks/grader_strength.py --repeat records each reference's steadiness with its lesson; the
    doc and the README's table show it (issue 24)."""
    import types

    from ros2course.dev.repeat import Flake
    from ros2course.dev.strength import STEADINESS_FILE, steadiness_text, write_steadiness

    lesson = types.SimpleNamespace(folder=tmp_path, course=active_course(), grader="inspect_services", packages=["package_with_interfaces"],
                                   folders=["cli"])
    assert steadiness_text(lesson) == "not measured"
    write_steadiness(lesson, Steadiness("inspect-services", "reference", 20, 2, [], 20, 300.0))
    recorded = json.loads((tmp_path / STEADINESS_FILE).read_text())
    assert recorded["runs"] == 20 and recorded["load"] == 2 and recorded["ok"] and recorded["date"]
    assert steadiness_text(lesson) == "steady, 20 runs (2 at once)"
    flake = Flake("listed", 13, 7, "/what_is_the_point", "no list of services")
    write_steadiness(lesson, Steadiness("inspect-services", "reference", 20, 2, [flake], 13, 300.0))
    assert steadiness_text(lesson) == "UNSTEADY in 20 runs (2 at once): listed (passed 13, failed 7)"
