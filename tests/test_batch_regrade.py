"""Regrading a class after a grader or a submission changed, and only what changed (issue 39).

The jobs are replaced by a fake grader (no ROS): its score is read from the submission's ``src/score.txt``,
its check ids from the "grader version" the test sets, so each row's fate is known in advance.
"""

from __future__ import annotations

import concurrent.futures as cf
import json
import os
from pathlib import Path

import pytest

from ros2course.batch import provenance
from ros2course.batch import runner as batch
from ros2course.batch.archive import Submission
from ros2course.batch.job import JobResult
from ros2course.errors import CourseError
from ros2course.grade.results import CheckResult, LessonResult, Status
from ros2course.report import gradebook

LESSON = "workspace-setup"


class FakeGrader:
    """Grades ``src/score.txt`` (an integer 0-2) of each submission; ``fingerprint`` is its version."""

    def __init__(self) -> None:
        self.fingerprint = "aaaaaaaaaaaaaaaa"
        self.graded: list[str] = []
        self.fail: set[str] = set()

    def job(self, job) -> JobResult:
        self.graded.append(job.student)
        if job.student in self.fail:
            raise OSError("the grading machine ran out of disk")
        points = float((Path(job.entry) / "src" / "score.txt").read_text().strip())
        checks = [CheckResult("built", "built", 1.0, 1.0, True, "", "", ""),
                  CheckResult("answer", "answer", points, 2.0, points == 2.0, "", "", "")]
        result = LessonResult(LESSON, 1.0 + points, 3.0, Status.PASSED if points == 2.0 else Status.FAILED, checks)
        result.student = job.student
        return JobResult(job.student, [result], None)


@pytest.fixture
def grader(monkeypatch) -> FakeGrader:
    fake = FakeGrader()
    monkeypatch.setattr(batch, "run_job", fake.job)
    monkeypatch.setattr(batch, "grader_fingerprint", lambda lesson: fake.fingerprint)
    return fake


def _class(root: Path, scores: dict[str, int]) -> Path:
    for student, score in scores.items():
        (root / student / "src").mkdir(parents=True, exist_ok=True)
        (root / student / "src" / "score.txt").write_text(f"{score}\n")
    return root


def _grade(subs: Path, out: Path, **options) -> batch.BatchReport:
    with cf.ThreadPoolExecutor(max_workers=1) as pool:
        return batch.run_batch(subs, [LESSON], out, executor=pool, **options)


def _scores(out: Path) -> dict[str, float]:
    return {r.student: r.score for r in gradebook.latest(gradebook.read_results(out / "results.jsonl")).values()}


def test_regrade_changed_regrades_exactly_the_rows_whose_grader_or_submission_changed(tmp_path: Path, grader) -> None:
    subs, out = _class(tmp_path / "subs", {"alice": 2, "bob": 0, "carol": 1}), tmp_path / "out"
    _grade(subs, out)
    assert sorted(grader.graded) == ["alice", "bob", "carol"] and _scores(out) == {"alice": 3, "bob": 1, "carol": 2}
    rows = provenance.read_graded_with(out / "results.jsonl")
    assert {w["grader"] for w in rows.values()} == {grader.fingerprint} and len({w["submission"] for w in rows.values()}) == 3
    assert json.loads((out / "run.json").read_text())["submissions"] == str(subs.absolute())

    # nothing changed: nothing regraded; new times alone are no change (a verdict is about the files)
    grader.graded.clear()
    os.utime(subs / "alice" / "src" / "score.txt", (1, 1))
    report = _grade(subs, out, regrade="changed")
    assert grader.graded == [] and report.regrades == [] and report.skipped == 3

    # bob fixes his file: only bob is regraded, and regrades.jsonl says what moved
    (subs / "bob" / "src" / "score.txt").write_text("2\n")
    report = _grade(subs, out, regrade="changed")
    assert grader.graded == ["bob"] and _scores(out)["bob"] == 3
    (change,) = report.regrades
    assert (change.why, change.direction, change.checks) == ("submission changed", "up", {"answer": [0.0, 2.0]})
    assert gradebook.read_regrades(out)[-1]["student"] == "bob"

    # the grader changes: every row is regraded once, the report names both fingerprints
    grader.graded.clear()
    grader.fingerprint = "bbbbbbbbbbbbbbbb"
    report = _grade(subs, out, regrade="changed")
    assert sorted(grader.graded) == ["alice", "bob", "carol"]
    assert {c.why for c in report.regrades} == {"grader aaaaaaaaaaaaaaaa -> bbbbbbbbbbbbbbbb"}
    assert {c.direction for c in report.regrades} == {"same"}
    grader.graded.clear()
    assert _grade(subs, out, regrade="changed").regrades == [] and grader.graded == []


def test_a_failed_regrade_keeps_the_previous_row_and_says_so(tmp_path: Path, grader) -> None:
    subs, out = _class(tmp_path / "subs", {"alice": 2, "bob": 1}), tmp_path / "out"
    _grade(subs, out)
    grader.fingerprint, grader.fail = "cccccccccccccccc", {"bob"}
    report = _grade(subs, out, regrade="changed")
    kept = {c.student: c for c in report.regrades}["bob"]
    assert kept.direction == "kept" and "grader error" in kept.kept and "out of disk" in kept.kept
    assert _scores(out) == {"alice": 3, "bob": 2}  # bob's row is the one graded before, not a grader error
    rows = provenance.read_graded_with(out / "results.jsonl")
    assert rows[("bob", LESSON)]["grader"] == "aaaaaaaaaaaaaaaa" and "out of disk" in rows[("bob", LESSON)]["regrade_failed"]
    # so the next --regrade changed tries bob again (his row still names the old grader)
    grader.fail, grader.graded = set(), []
    _grade(subs, out, regrade="changed")
    assert grader.graded == ["bob"]


def test_only_regrades_one_student_an_appeal(tmp_path: Path, grader) -> None:
    subs, out = _class(tmp_path / "subs", {"alice": 2, "bob": 1}), tmp_path / "out"
    _grade(subs, out)
    grader.graded.clear()
    report = _grade(subs, out, only=["bob"])
    assert grader.graded == ["bob"] and [c.why for c in report.regrades] == ["asked (--only)"]
    assert set(_scores(out)) == {"alice", "bob"}


def test_rows_graded_before_provenance_was_kept_count_as_changed(tmp_path: Path, grader) -> None:
    subs, out = _class(tmp_path / "subs", {"alice": 2}), tmp_path / "out"
    out.mkdir()
    old = LessonResult(LESSON, 3.0, 3.0, Status.PASSED, [])
    old.student = "alice"
    gradebook.append_record(out / "results.jsonl", old)  # no graded_with: an older ros2course wrote it
    report = _grade(subs, out, regrade="changed")
    assert [c.why for c in report.regrades] == ["graded before grader fingerprints were recorded"]


def test_bad_regrade_input_is_refused_before_anything_is_graded(tmp_path: Path, grader) -> None:
    subs, out = _class(tmp_path / "subs", {"alice": 2}), tmp_path / "out"
    with pytest.raises(CourseError, match="holds no results to regrade"):
        _grade(subs, out, regrade="changed")
    _grade(subs, out)
    grader.graded.clear()
    with pytest.raises(CourseError, match="unknown --regrade"):
        _grade(subs, out, regrade="some")
    with pytest.raises(CourseError, match="no submission of zed"):
        _grade(subs, out, only=["zed"])
    with pytest.raises(CourseError, match="already holds results"):
        _grade(subs, out)
    assert grader.graded == []


def test_the_submission_digest_is_about_content_not_times_and_never_follows_links(tmp_path: Path) -> None:
    folder = _class(tmp_path / "subs", {"alice": 2}) / "alice"
    first = provenance.submission_digest(Submission("alice", folder))
    os.utime(folder / "src" / "score.txt", (5, 5))
    (folder / ".git").mkdir()
    (folder / ".git" / "HEAD").write_text("ref: x\n")  # never copied by the batch: no change
    assert provenance.submission_digest(Submission("alice", folder)) == first
    (folder / "src" / "link").symlink_to("/etc/passwd")
    linked = provenance.submission_digest(Submission("alice", folder))
    assert linked != first
    (folder / "src" / "link").unlink()
    (folder / "src" / "link").symlink_to("/etc/hostname")
    assert provenance.submission_digest(Submission("alice", folder)) not in (first, linked)
    assert provenance.submission_digest(Submission("x", folder, "a dangling symbolic link")) != first


def test_cli_regrade_options_are_refused_in_one_line(tmp_path: Path, cli) -> None:
    subs = _class(tmp_path / "subs", {"alice": 2})
    proc = cli("grade", str(subs), "--lesson", LESSON, "--out", str(tmp_path / "out"), "--regrade", "changed")
    assert proc.returncode == 5 and "Traceback" not in proc.stderr and "holds no results to regrade" in proc.stderr
    assert "hint:" in proc.stderr


def test_the_report_shows_what_each_regrade_changed(tmp_path: Path, grader) -> None:
    from ros2course.report.html import regrades_section, render_report

    subs, out = _class(tmp_path / "subs", {"alice": 2, "bob": 0}), tmp_path / "out"
    _grade(subs, out)
    assert regrades_section(out) is None
    (subs / "bob" / "src" / "score.txt").write_text("2\n")
    _grade(subs, out, regrade="changed")
    section = regrades_section(out)
    (row,) = section["rows"]
    assert row["student"] == "bob" and row["score"] == "1 -> 3 of 3" and row["checks"] == "answer 0.0 -> 2.0"
    assert "1 up" in section["note"]
    assert "Regrades" in render_report(out, similarity=False)
