"""``dev validate --until-settled``: a case's grading stops once its verdict is settled (a wrong solution's named
checks judged, a starter's first lost point), and nothing it judged changes (no ROS: a grader of plain records,
run by the engine's own loop)."""

from __future__ import annotations

import json
import threading
import types

import pytest

from ros2course.dev.parity import differing_checks, own_race, same_verdicts
from ros2course.dev.validate import Fixture
from ros2course.grade.checklist import STOPPED_SETTLED, Check, StopWhen, VerdictSettled
from ros2course.grade.engine import _run_grader
from ros2course.grade.results import NOT_CHECKED, CheckResult, LessonResult, Status
from ros2course.grade.session import GradingSession

CHECKS = [Check("exists", "e", 1), Check("rate", "r", 2, needs=("exists",)), Check("log", "l", 1),
          Check("ctrl_c", "c", 1, needs=("log",))]


def session(tmp_path, until=(), any_loss=False) -> GradingSession:
    return GradingSession(None, list(CHECKS), tmp_path, tmp_path / "log", {},
                          stop_when=StopWhen(frozenset(until), any_loss))


def run(s: GradingSession, grade) -> tuple[Status | None, dict[str, CheckResult], list[str]]:
    status, _, _ = _run_grader(types.SimpleNamespace(grade=grade), s, {})
    return status, {r.id: r for r in s.ordered_results()}, s.notes


def test_grading_stops_at_the_step_after_the_last_named_verdict_and_keeps_its_amendment(tmp_path):
    steps = []

    def grade(s):
        s.record("exists", True, "found", "an executable")
        s.record("rate", False, "1 Hz", "2 Hz")
        s.amend("rate", hint="the timer period is in seconds")  # the verdict's own amendment stays
        steps.append("amended")
        s.require("exists")  # the grader's next step: stopped here
        steps.append("went on")
        s.record("log", True, "", "")

    status, results, _ = run(session(tmp_path, ("rate",)), grade)
    assert status is None and steps == ["amended"]
    assert results["rate"].hint == "the timer period is in seconds" and results["rate"].points == 0
    assert results["exists"].passed
    for left in ("log", "ctrl_c"):
        assert results[left].skipped and results[left].observed == NOT_CHECKED + STOPPED_SETTLED


def test_a_named_check_not_checked_stops_grading_when_its_part_ends(tmp_path):
    checks = [Check("exists", "e", 1, part="talker"), Check("rate", "r", 2, needs=("exists",), part="talker"),
              Check("log", "l", 1, part="listener")]
    s = GradingSession(None, checks, tmp_path, tmp_path / "log", {}, stop_when=StopWhen(frozenset({"exists", "rate"})))
    steps = []

    def grade(s):
        with s.part("talker"):
            s.record("exists", False, "no executable", "an executable")
            s.require("exists")
        steps.append("listener")
        s.record("log", True, "", "")

    _, results, _ = run(s, grade)
    assert results["rate"].skipped and "'e' failed" in results["rate"].observed  # its own reason, not the stop
    assert steps == [] and results["log"].observed == NOT_CHECKED + STOPPED_SETTLED


def test_a_verdict_on_a_worker_thread_stops_grading_on_the_grading_thread_only(tmp_path):
    seen = []

    def grade(s):
        def half():
            s.record("rate", False, "1 Hz", "2 Hz")
            s.record("log", True, "", "")  # the worker's half runs on to its end
            seen.append("worker done")
        worker = threading.Thread(target=half)
        worker.start()
        worker.join()
        s.record("ctrl_c", True, "", "")

    _, results, _ = run(session(tmp_path, ("rate",)), grade)
    assert seen == ["worker done"] and results["log"].passed
    assert results["ctrl_c"].observed == NOT_CHECKED + STOPPED_SETTLED


def test_without_stop_when_nothing_stops_and_a_graders_except_exception_cannot_swallow_the_stop(tmp_path):
    def grade(s):
        for check_id in ("exists", "rate", "log", "ctrl_c"):
            try:
                s.record(check_id, check_id != "rate", "", "")
            except Exception:  # noqa: BLE001 - a careless grader
                pass

    _, whole, _ = run(session(tmp_path), grade)
    assert all(not r.skipped for r in whole.values())
    _, cut, _ = run(session(tmp_path, ("rate",)), grade)
    assert cut["log"].observed == NOT_CHECKED + STOPPED_SETTLED
    assert issubclass(VerdictSettled, BaseException) and not issubclass(VerdictSettled, Exception)


def test_a_fixture_is_judged_by_its_named_checks_unless_it_expects_any_checks_diagnosis():
    fixture = Fixture(description="d", fails=["rate", "log"], skips=["ctrl_c"], says={"rate": ["Hz"], "exists": ["x"]},
                      diagnosis=[{"kind": "silent", "check": "log"}])
    assert fixture.judged_by() == ("rate", "log", "ctrl_c", "exists")
    assert Fixture(description="d", fails=["rate"], diagnosis=[{"kind": "silent"}]).judged_by() == ()
    assert Fixture(description="d", expect="full_marks").judged_by() == ()


def test_grades_batch_verdicts_are_compared_on_the_checks_check_judged():
    def result(*checks: CheckResult) -> LessonResult:
        return LessonResult("l", sum(c.points for c in checks), 5.0, Status.FAILED, list(checks))

    exists, rate = CheckResult("exists", "e", 1, 1, True, "", "", ""), CheckResult("rate", "r", 0, 2, False, "", "", "")
    stopped = CheckResult("log", "l", 0, 1, False, NOT_CHECKED + STOPPED_SETTLED, "", "", skipped=True)
    checked = result(exists, rate, stopped)
    assert same_verdicts(checked, result(exists, rate, CheckResult("log", "l", 1, 1, True, "", "", "")))
    assert not same_verdicts(checked, result(exists, CheckResult("rate", "r", 2, 2, True, "", "", ""),
                                             CheckResult("log", "l", 1, 1, True, "", "", "")))
    whole = result(exists, rate, CheckResult("log", "l", 0, 1, False, "", "", ""))
    assert not same_verdicts(whole, result(exists, rate, CheckResult("log", "l", 1, 1, True, "", "", "")))
    # grade stopped too (dev validate --batch --until-settled hands the fixture's checks to the batch):
    # compared on the checks both judged, the named ones always among them
    assert same_verdicts(checked, result(exists, rate, stopped))
    assert not same_verdicts(checked, result(exists, CheckResult("rate", "r", 2, 2, True, "", "", ""), stopped))


def test_a_wrong_solution_racing_itself_on_a_check_its_fixture_does_not_name_is_not_a_parity_failure():
    """CI of 893e21c: check lost goal_sent and sigint_exit of actions-client's main-called-at-import, grade only
    sigint_exit (the start-over's second goal came before or after the count). A second check run that gives
    grade's verdict shows the race is the program's; one on a named check, or not reproduced, still fails."""
    def result(*checks: CheckResult) -> LessonResult:
        return LessonResult("l", sum(c.points for c in checks), 5.0, Status.FAILED, list(checks))

    exists, lost_rate = CheckResult("exists", "e", 1, 1, True, "", "", ""), CheckResult("rate", "r", 0, 2, False, "", "", "")
    rate = CheckResult("rate", "r", 2, 2, True, "", "", "")
    log, lost_log = CheckResult("log", "l", 1, 1, True, "", "", ""), CheckResult("log", "l", 0, 1, False, "", "", "")
    checked, graded = result(exists, lost_rate, lost_log), result(exists, rate, lost_log)
    assert differing_checks(checked, graded) == ["rate"] and not same_verdicts(checked, graded)
    # the fixture names log; rate changed between check's runs and grade got the second run's verdict
    assert own_race(checked, graded, result(exists, rate, lost_log), ("log",)) == ["rate"]
    # check did not reproduce grade's verdict: parity fails
    assert own_race(checked, graded, result(exists, lost_rate, lost_log), ("log",)) == []
    assert own_race(checked, graded, None, ("log",)) == []
    # the check that changed is one the fixture names: what it claims to prove is a race, which never passes
    assert own_race(checked, graded, result(exists, rate, lost_log), ("rate", "log")) == []
    # a check stopped by --until-settled in either run is not compared
    stopped = CheckResult("log", "l", 0, 1, False, NOT_CHECKED + STOPPED_SETTLED, "", "", skipped=True)
    assert differing_checks(result(exists, lost_rate, stopped), result(exists, lost_rate, log)) == []
    assert own_race(result(exists, lost_rate, log), result(exists, rate, log), result(exists, rate, log), ()) == ["rate"]


def test_the_stop_is_raised_at_the_next_step_once_and_only_on_the_grading_thread(tmp_path):
    s = session(tmp_path, ("exists",))
    s.record("exists", True, "", "")  # the last named verdict itself never raises (the engine's build check)
    with pytest.raises(VerdictSettled):
        s.record("rate", True, "", "")
    assert "rate" not in s.results
    s.record("rate", True, "", "")  # disarmed: the engine records what is left
    assert s.results["rate"].passed


def test_a_starter_stops_at_its_first_lost_point_on_any_check(tmp_path):
    def grade(s):
        s.record("exists", True, "found", "an executable")
        s.record("rate", True, "1.9 Hz", "2 Hz", fraction=0.5)  # a partial verdict loses points too
        s.record("log", False, "", "")

    _, results, _ = run(session(tmp_path, any_loss=True), grade)
    assert results["exists"].passed and results["rate"].points == 1.0
    assert results["log"].observed == NOT_CHECKED + STOPPED_SETTLED
    assert not StopWhen() and StopWhen(any_loss=True) and StopWhen(frozenset({"a"}))


def test_a_grading_process_that_crashes_once_is_graded_again(monkeypatch, tmp_path) -> None:
    """dev validate's child killed by a signal with no output (a crash of the grading process, not a verdict) is run
    once more; a second crash, or a plain failure, is a grader error that names the exit status."""
    import subprocess

    from ros2course.dev import child
    from ros2course.grade.results import LessonResult, Status

    record = json.dumps(LessonResult("print-forever-node", 1.0, 1.0, Status.PASSED, []).to_record())
    answers = [subprocess.CompletedProcess([], -11, "", ""), subprocess.CompletedProcess([], 0, record + "\n", "")]
    monkeypatch.setattr(child.subprocess, "run", lambda *a, **k: answers.pop(0))
    result = child.grade_in_child("print-forever-node", tmp_path, (), tmp_path / "log")
    assert result.status == Status.PASSED and not answers
    answers[:] = [subprocess.CompletedProcess([], -11, "", "")] * 2
    again = child.grade_in_child("print-forever-node", tmp_path, (), tmp_path / "log")
    assert again.status == Status.GRADER_ERROR and "exit -11, twice" in again.message and not answers
    answers[:] = [subprocess.CompletedProcess([], 1, "", "Boom"), subprocess.CompletedProcess([], 0, record, "")]
    failed = child.grade_in_child("print-forever-node", tmp_path, (), tmp_path / "log")
    assert failed.status == Status.GRADER_ERROR and failed.message.endswith("Boom (exit 1)") and len(answers) == 1


def test_a_mutant_stopped_at_its_first_loss_is_killed_by_the_checks_it_lost_before_the_stop():
    """``dev mutate --first-loss``: the checks left "not checked" by the stop are not counted as lost."""
    from ros2course.dev.mutants import KILLED, SURVIVED, classify  # noqa: PLC0415

    stopped = CheckResult("log", "l", 0, 1, False, NOT_CHECKED + STOPPED_SETTLED, "", "", skipped=True)
    rate = CheckResult("rate", "r", 0, 2, False, "2.0 Hz", "", "")
    exists = CheckResult("exists", "e", 1, 1, True, "", "", "")
    assert classify(LessonResult("l", 1.0, 4.0, Status.FAILED, [exists, rate, stopped])) == (KILLED, ["rate"])
    whole = CheckResult("log", "l", 0, 1, False, "no record", "", "")
    assert classify(LessonResult("l", 1.0, 4.0, Status.FAILED, [exists, rate, whole])) == (KILLED, ["rate", "log"])
    full = LessonResult("l", 1.0, 1.0, Status.PASSED, [exists])
    assert classify(full) == (SURVIVED, [])


def test_a_stop_or_a_crash_inside_a_part_still_closes_the_part_every_action_of_it(tmp_path):
    """A world or a stand-in server left spinning when the session shuts its graph down crashed the grading
    process (SIGSEGV in CI): the part's closing actions run on every way out, newest first, each however the
    one before ended, and the stop or the crash goes on."""
    closed = []

    def broken_closer():
        closed.append("broken")
        raise RuntimeError("a closer that fails")

    def grade_settled(s):
        with s.part("talker"):
            s.on_close(lambda: closed.append("world"))
            s.on_close(broken_closer)
            s.record("exists", True, "", "")
            s.record("rate", False, "1 Hz", "2 Hz")  # settles: the next step stops
            s.record("log", True, "", "")

    status, results, _ = run(session(tmp_path, ("exists",)), grade_settled)
    assert status is None and closed == ["broken", "world"]
    assert results["log"].observed == NOT_CHECKED + STOPPED_SETTLED

    closed.clear()

    def grade_crashing(s):
        with s.part("talker"):
            s.on_close(lambda: closed.append("world"))
            raise KeyError("a grader's own bug")

    (tmp_path / "log").mkdir(exist_ok=True)
    status, _, _ = run(session(tmp_path), grade_crashing)
    assert status == Status.GRADER_ERROR and closed == ["world"]


def test_a_hung_grading_says_where_its_main_thread_was(monkeypatch, tmp_path) -> None:
    """A child that runs past its deadline is killed, and the grader error names where its grading thread was:
    the stacks faulthandler wrote (``--dump-stacks-after``) from a real hung Python process, read by hung_at."""
    import subprocess
    import sys

    from ros2course.dev import child
    from ros2course.grade.results import LessonResult, Status

    hang = ("import faulthandler, threading, time\n"
            "def wait_for_peer():\n    time.sleep(30)\n"
            "def _main():\n    faulthandler.dump_traceback_later(0.5, exit=False)\n"
            "    threading.Thread(target=time.sleep, args=(30,), daemon=True).start()\n    wait_for_peer()\n"
            "_main()\n")
    with pytest.raises(subprocess.TimeoutExpired) as hung:
        subprocess.run([sys.executable, "-c", hang], capture_output=True, text=True, timeout=3, check=False)
    seen: list[list[str]] = []

    def run(argv, **kwargs):
        seen.append(argv)
        raise hung.value

    monkeypatch.setattr(child.subprocess, "run", run)
    result = child.grade_in_child("print-forever-node", tmp_path, (), tmp_path / "log", timeout=3)
    assert result.status == Status.GRADER_ERROR
    assert "ran past 3 s; its main thread was at <string>:3 in wait_for_peer <- <string>:7 in _main" in result.message
    assert "most recent call first" in (tmp_path / "log" / "hung-child.stderr.log").read_text()
    assert seen[0][seen[0].index("--dump-stacks-after") + 1] == "1.5"  # half the deadline when it is short
    assert child.hung_at(b"no stacks here", tmp_path) == ""
    # the grading printed its result and only the child's exit hung: the result stands
    record = json.dumps(LessonResult("print-forever-node", 1.0, 1.0, Status.PASSED, []).to_record())
    hung.value.stdout = (record + "\n").encode()
    assert child.grade_in_child("print-forever-node", tmp_path, (), tmp_path / "log").status == Status.PASSED
