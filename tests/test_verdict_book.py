"""The verdict book on its own (issue 38): verdicts, needs, parts and closing actions, settling a case.

No ROS, no process, no file: :class:`ros2course.grade.verdicts.VerdictBook` is the part of a grading
session these rules live in, so they are tested here directly rather than through a grading.
"""

from __future__ import annotations

import threading

import pytest

from ros2course.errors import CourseError
from ros2course.grade.checklist import Check, StopWhen, Unmet, VerdictSettled
from ros2course.grade.results import NOT_CHECKED
from ros2course.grade.verdicts import VerdictBook

CHECKS = [
    Check("build", "It builds", 1, hint="colcon build"),
    Check("starts", "The node starts", 2, needs=("build",), part="a"),
    Check("rate", "It publishes at 2 Hz", 3, needs=("starts",), part="a"),
    Check("other", "The other node starts", 2, needs=("build",), part="b"),
]


def test_a_check_whose_need_failed_is_not_checked_with_the_need_named() -> None:
    book = VerdictBook(CHECKS)
    assert book.record("build", False, "no install/", "a built package") is False
    assert book.record("starts", True, "started", "a node") is False
    result = book.results["starts"]
    assert result.skipped and result.points == 0 and result.observed == f"{NOT_CHECKED}'It builds' failed"
    # followed through: rate needs starts, which was not checked
    assert book.unmet_need("rate") == "'The node starts' was not checked"


def test_points_hint_and_partial_credit() -> None:
    book = VerdictBook(CHECKS)
    book.record("build", True, "built", "built", hint="never shown")
    assert book.results["build"].hint == "" and book.results["build"].points == 1
    failed = VerdictBook(CHECKS)
    failed.record("build", False, "no install/", "built")
    assert failed.results["build"].hint == "colcon build"  # the check's own hint, on failure
    failed.amend("build", hint="run colcon build --symlink-install")
    assert failed.results["build"].hint == "run colcon build --symlink-install"
    book.record("other", False, "x", "y", fraction=1.7)  # clipped to [0, 1]
    assert book.results["other"].points == 2
    book.amend("other", observed="x, and more")
    assert book.results["other"].observed == "x, and more" and book.results["other"].points == 2
    with pytest.raises(KeyError):
        book.amend("rate", observed="never recorded")
    with pytest.raises(KeyError):
        book.record("undeclared", True, "", "")


def test_needs_are_validated_when_the_book_is_made() -> None:
    with pytest.raises(CourseError):
        VerdictBook([Check("a", "A", 1, needs=("later",)), Check("later", "Later", 1)])


def test_unmet_in_a_part_runs_its_closers_newest_first_and_ends_only_that_part() -> None:
    book = VerdictBook(CHECKS)
    ran: list[str] = []
    book.record("build", True, "built", "built")
    with book.part("a"):
        book.on_close(lambda: ran.append("first"))
        book.on_close(lambda: ran.append("second"))
        book.record("starts", False, "no node", "a node")
        book.require("starts")
        ran.append("never")
    assert ran == ["second", "first"]
    assert book.results["rate"].skipped and "'The node starts' failed" in book.results["rate"].observed
    assert "other" not in book.results  # part b is untouched
    with book.part("b"):
        book.record("other", True, "started", "a node")
    assert [r.id for r in book.ordered()] == ["build", "starts", "rate", "other"]


def test_a_crash_inside_a_part_runs_every_closer_and_goes_on() -> None:
    book = VerdictBook(CHECKS)
    ran: list[str] = []

    def broken() -> None:
        raise RuntimeError("a probe that fails to close")

    with pytest.raises(ZeroDivisionError), book.part("a"):
        book.on_close(lambda: ran.append("kept"))
        book.on_close(broken)
        _ = 1 / 0
    assert ran == ["kept"]


def test_stop_when_settles_at_the_next_step_on_the_grading_thread_only() -> None:
    book = VerdictBook(CHECKS, StopWhen(judged=frozenset({"build"})))
    book.record("build", False, "no", "yes")
    book.amend("build", observed="no, amended")  # an amendment right after the verdict is kept
    seen: list[str] = []

    def other_thread() -> None:
        book.require()  # a worker thread's half runs on
        seen.append("ran")

    worker = threading.Thread(target=other_thread)
    worker.start()
    worker.join()
    assert seen == ["ran"]
    with pytest.raises(VerdictSettled):
        book.record("other", True, "", "")
    book.record("other", True, "", "")  # raised once: disarmed
    book.leave_unjudged("stopped once settled")
    assert book.results["rate"].observed == f"{NOT_CHECKED}stopped once settled"


def test_a_named_check_whose_need_failed_settles_the_case_at_once() -> None:
    """--until-settled: a named check blocked by a failed need can only be "not checked" (record() would write
    it so), so the case settles at the next step instead of grading on until the grader reaches that check."""
    book = VerdictBook(CHECKS, StopWhen(judged=frozenset({"rate"})))
    book.record("build", True, "built", "built")
    book.record("starts", False, "no node", "a node")
    with pytest.raises(VerdictSettled):
        book.require()
    assert book.results["rate"].skipped and book.results["rate"].observed == f"{NOT_CHECKED}'The node starts' failed"
    # without a stop_when nothing is written ahead: the grading reaches the check itself
    whole = VerdictBook(CHECKS)
    whole.record("build", True, "built", "built")
    whole.record("starts", False, "no node", "a node")
    whole.require()
    assert "rate" not in whole.results


def test_only_the_named_checks_and_what_they_need_are_wanted_while_a_case_settles() -> None:
    assert all(VerdictBook(CHECKS).wanted(c.id) for c in CHECKS)  # a learner's grading wants every check
    assert all(VerdictBook(CHECKS, StopWhen(any_loss=True)).wanted(c.id) for c in CHECKS)  # a starter's too
    book = VerdictBook(CHECKS, StopWhen(judged=frozenset({"rate"})))
    assert [c.id for c in CHECKS if book.wanted(c.id)] == ["build", "starts", "rate"]  # needs followed through
    assert not book.wanted("other")


def test_windows_and_evidence() -> None:
    book = VerdictBook(CHECKS)
    book.record("build", True, "built", "built")
    book.record("starts", False, "no node", "a node", window=(10.0, 12.5), band=(0.4, 0.6), band_of="median")
    assert book.windows["starts"] == (10_000_000_000, 12_500_000_000)
    assert book.bands["starts"].metadata() == {"band": [0.4, 0.6], "band_of": "median"}
    start, end = book.windows["build"]
    assert start <= end
    results = {r.id: r for r in book.ordered(recording="/logs/observed.mcap")}
    assert results["starts"].evidence == {"recording": "/logs/observed.mcap", "start_ns": 10_000_000_000,
                                          "end_ns": 12_500_000_000}
    assert results["build"].evidence is None  # passed: no evidence
    assert results["rate"].skipped and results["rate"].evidence is None  # not checked: none either
    assert all(r.evidence is None for r in book.ordered())  # no recording: none at all


def test_on_verdict_sees_every_verdict_and_only_a_failure_keeps_its_diagnosis() -> None:
    book = VerdictBook(CHECKS)
    calls: list[tuple[str, bool]] = []

    def on_verdict(check: Check, passed: bool) -> list[str]:
        calls.append((check.id, passed))
        return ["a diagnosis"]

    book.record("build", True, "built", "built", on_verdict=on_verdict)
    book.record("starts", False, "no node", "a node", on_verdict=on_verdict)
    book.record("rate", True, "", "", on_verdict=on_verdict)  # its need failed: never judged, never observed
    assert calls == [("build", True), ("starts", False)]
    assert book.results["build"].diagnosis == [] and book.results["starts"].diagnosis == ["a diagnosis"]


def test_a_verdict_the_engine_marked_not_checked_stays() -> None:
    book = VerdictBook(CHECKS)
    book.record("build", True, "built", "built")
    book.stop_part("a", "the part stopped")
    assert book.record("starts", True, "started late", "a node") is False
    assert book.results["starts"].skipped and book.results["starts"].observed.endswith("the part stopped")
    with pytest.raises(Unmet, match="^'The node starts' did not pass$"):
        book.require("starts")


def test_a_part_is_needed_while_a_check_of_it_can_still_change_the_verdict() -> None:
    """kit.settle.part_needed: every part for a learner's grading; under --until-settled only the parts of the
    named checks and of what they need; a part no check names is an error, not a silent skip."""
    from ros2course.kit.settle import part_needed  # noqa: PLC0415

    class Book:  # the one member of Session that part_needed reads
        def __init__(self, book: VerdictBook) -> None:
            self.wanted = book.wanted

    whole = Book(VerdictBook(CHECKS))
    assert part_needed(whole, CHECKS, "a") and part_needed(whole, CHECKS, "b")
    settling = Book(VerdictBook(CHECKS, StopWhen(judged=frozenset({"rate"}))))
    assert part_needed(settling, CHECKS, "a") and not part_needed(settling, CHECKS, "b")
    needing = Book(VerdictBook([*CHECKS, Check("late", "A later run", 1, needs=("other",), part="c")],
                               StopWhen(judged=frozenset({"late"}))))
    assert part_needed(needing, CHECKS, "b")  # "late" needs "other": part b must still run
    with pytest.raises(ValueError, match="part='nope'"):
        part_needed(whole, CHECKS, "nope")
