"""An instructor's term end to end, without ROS (issue 39): a Canvas download and a folder of git clones taken in,
graded, adjusted by a class file (deadlines, an extension, a late policy), exported for Canvas and Moodle, then
regraded after one lesson's grader changed: only that lesson's rows.

The grading itself is replaced by a fake job that prepares each submission as the real job does
(:func:`ros2course.batch.archive.prepare`: the same extraction and layout rules) and reads the points from a file
of the workspace; the real graders are tested against real nodes elsewhere (test_lessons, test_batch_ros).
"""

from __future__ import annotations

import concurrent.futures as cf
import csv
import io
import json
import os
import subprocess
import tempfile
import zipfile
from pathlib import Path

import pytest

from ros2course.batch import intake as intake_mod
from ros2course.batch import runner as batch
from ros2course.batch.archive import Submission, prepare
from ros2course.batch.job import JobResult
from ros2course.grade.results import CheckResult, LessonResult, Status
from ros2course.report import gradebook, lms, term

CANVAS_LESSONS = ["print-forever-node", "publisher-subscriber"]
GIT_LESSON = "parameters"


class FakeGrader:
    """A lesson's points are in the workspace's ``points/<lesson>`` (0-2); fingerprints per lesson are set by the test."""

    def __init__(self) -> None:
        self.fingerprints = {lesson: "1" * 16 for lesson in [*CANVAS_LESSONS, GIT_LESSON]}
        self.graded: list[tuple[str, str]] = []

    def job(self, job) -> JobResult:
        results = []
        with tempfile.TemporaryDirectory() as scratch:
            ws = prepare(Submission(job.student, Path(job.entry), job.problem), Path(scratch))
            for lesson in job.lessons:
                self.graded.append((job.student, lesson))
                points = float((ws / "points" / lesson).read_text()) if (ws / "points" / lesson).is_file() else 0.0
                checks = [CheckResult("builds", "builds", 1.0, 1.0, True, "", "", ""),
                          CheckResult("works", "works", points, 2.0, points == 2.0, "", "", "", visibility="hidden")]
                result = LessonResult(lesson, 1.0 + points, 3.0, Status.PASSED if points == 2 else Status.FAILED, checks)
                result.student = job.student
                results.append(result)
        return JobResult(job.student, results, None)


@pytest.fixture
def grader(monkeypatch) -> FakeGrader:
    fake = FakeGrader()
    monkeypatch.setattr(batch, "run_job", fake.job)
    monkeypatch.setattr(batch, "grader_fingerprint", lambda lesson: fake.fingerprints[lesson.id])
    return fake


def _workspace_zip(points: dict[str, int]) -> bytes:
    data = io.BytesIO()
    with zipfile.ZipFile(data, "w") as zf:
        zf.writestr("ws/src/my_pkg/package.xml", "<package format='3'><name>my_pkg</name></package>\n")
        for lesson, value in points.items():
            zf.writestr(f"ws/points/{lesson}", f"{value}\n")
    return data.getvalue()


def _canvas_download(path: Path) -> Path:
    """Six students as Canvas names their files (``lastfirst[_LATE]_userid_submissionid_file``), two marked LATE."""
    with zipfile.ZipFile(path, "w") as zf:
        for i, (name, late, points) in enumerate([("adaada", False, (2, 2)), ("babbagecharles", False, (2, 1)),
                                                  ("hopperg", False, (1, 0)), ("liskovb", False, (2, 2)),
                                                  ("knuthd", True, (2, 2)), ("lamportl", True, (0, 2))]):
            member = f"{name}{'_LATE' if late else ''}_{1001 + i}_{5001 + i}_workspace.zip"
            zf.writestr(member, _workspace_zip(dict(zip(CANVAS_LESSONS, points))))
    return path


def _git(repo: Path, *args: str, when: str = "") -> None:
    env = {**os.environ, "GIT_AUTHOR_NAME": "s", "GIT_AUTHOR_EMAIL": "s@example.org", "GIT_COMMITTER_NAME": "s",
           "GIT_COMMITTER_EMAIL": "s@example.org", **({"GIT_AUTHOR_DATE": when, "GIT_COMMITTER_DATE": when} if when else {})}
    subprocess.run(["git", "-C", str(repo), *args], check=True, env=env, capture_output=True)


def _clones(root: Path) -> Path:
    """Six clones; commits (time, points): two late, one late but with an extension, one with a commit after the
    cut-off that must not be taken."""
    history = {"g1": [("2026-03-01T12:00:00+01:00", 2)], "g2": [("2026-02-27T09:00:00+01:00", 1)],
               "g3": [("2026-03-01T20:00:00+01:00", 1), ("2026-03-09T10:00:00+01:00", 2)],
               "g4": [("2026-03-02T10:00:00+01:00", 2)],              # 1 started day late
               "g5": [("2026-03-03T08:00:00+01:00", 2)],              # 2 started days late
               "g6": [("2026-03-03T08:00:00+01:00", 2)]}              # late, but 3 more days by extension
    for student, commits in history.items():
        repo = root / student
        (repo / "src" / "my_pkg").mkdir(parents=True)
        (repo / "src" / "my_pkg" / "package.xml").write_text("<package format='3'><name>my_pkg</name></package>\n")
        (repo / "points").mkdir()
        _git(repo, "init", "-q")
        for when, points in commits:
            (repo / "points" / GIT_LESSON).write_text(f"{points}\n")
            _git(repo, "add", "-A")
            _git(repo, "commit", "-q", "-m", "work", when=when)
    return root


def _grade(source: Path, fmt: str, lessons: list[str], out: Path, before=None, **options) -> batch.BatchReport:
    taken = intake_mod.intake(source, fmt, out / "intake", before=before)
    with cf.ThreadPoolExecutor(max_workers=2) as pool:
        return batch.run_batch(taken.folder, lessons, out, executor=pool, not_taken=taken.problems, **options)


def _rows(text: str) -> list[list[str]]:
    return list(csv.reader(io.StringIO(text)))


def test_a_term_from_the_lms_download_to_the_lms_gradebook(tmp_path: Path, grader) -> None:
    # --- in: one Canvas download (two lessons) and one folder of git clones (a third), twelve submissions
    canvas_out, git_out = tmp_path / "canvas-grades", tmp_path / "git-grades"
    _grade(_canvas_download(tmp_path / "submissions.zip"), "canvas", CANVAS_LESSONS, canvas_out)
    cut_off = intake_mod.parse_deadline("2026-03-05T23:59:00+01:00")
    _grade(_clones(tmp_path / "clones"), "git", [GIT_LESSON], git_out, before=cut_off)
    assert len(grader.graded) == 6 * 2 + 6
    taken = intake_mod.load_intake(git_out / "intake")
    assert taken["g3"].submitted_at.startswith("2026-03-01T20:00")  # the commit after the cut-off is not taken
    assert {sid for sid, rec in intake_mod.load_intake(canvas_out / "intake").items() if rec.lms_late} == {"1005", "1006"}

    # --- the class file: due dates, an extension, a late policy
    (git_out / "class.yaml").write_text(
        "lessons:\n  parameters: {due: '2026-03-01T23:59:00+01:00'}\n"
        "extensions:\n  g6: {parameters: {days: 3}}\n"
        "late_policy: {penalty_per_day: 10, cap: 50, grace_minutes: 15}\n")
    book = term.adjust_out_dir(git_out)
    rows = {a.student: a for a in book.adjusted}
    assert (rows["g1"].score, rows["g1"].reason) == (3.0, "on time")
    assert rows["g4"].late and rows["g4"].penalty == 10 and rows["g4"].score == pytest.approx(2.7)
    assert rows["g5"].late and rows["g5"].penalty == 20 and "2 days late: -20 %" in rows["g5"].reason
    assert not rows["g6"].late and rows["g6"].extended and "extension to 2026-03-04" in rows["g6"].reason
    assert sum(a.late for a in book.adjusted) == 2

    # Canvas's download gives no times: the LATE flag is reported, no penalty is guessed
    (canvas_out / "class.yaml").write_text(
        "lessons:\n  print-forever-node: {due: '2026-02-15T23:59:00+01:00'}\n"
        "  publisher-subscriber: {due: '2026-02-22T23:59:00+01:00'}\n"
        "late_policy: {penalty_per_day: 10, cap: 50}\n"
        "visibility:\n  print-forever-node: {builds: after_due}\n")
    canvas_book = term.adjust_out_dir(canvas_out)
    flagged = [a for a in canvas_book.adjusted if a.student == "1005"]
    assert flagged and all(a.score == a.raw_score for a in flagged) and all("late" in a.reason.lower() for a in flagged)

    # --- out: the Canvas and Moodle imports, their documented columns
    canvas = _rows(lms.export(canvas_book.adjusted, "canvas", canvas_book.names, canvas_book.lessons,
                              canvas_user_ids=term.intake_format(canvas_out) == "canvas"))
    assert canvas[0] == ["Student", "ID", "SIS User ID", "SIS Login ID", "Section", *CANVAS_LESSONS, "Final Points"]
    assert canvas[1][0].strip() == "Points Possible" and canvas[1][5:] == ["3", "3", "6"]
    ada = next(row for row in canvas[2:] if row[1] == "1001")
    assert ada[0] == "adaada" and ada[5:] == ["3", "3", "6"]
    moodle = _rows(lms.export(book.adjusted, "moodle", lessons=book.lessons))
    assert moodle[0][0] == "ID number" and moodle[0][1] == GIT_LESSON
    assert {row[0]: row[1] for row in moodle[1:]}["g5"] == "2.4"

    # --- a fix to one lesson's grader: --regrade changed regrades that lesson's rows only
    grader.graded.clear()
    grader.fingerprints["publisher-subscriber"] = "2" * 16
    report = _grade(tmp_path / "submissions.zip", "canvas", CANVAS_LESSONS, canvas_out, regrade="changed")
    assert sorted(grader.graded) == sorted((f"{1001 + i}", "publisher-subscriber") for i in range(6))
    assert {c.lesson for c in report.regrades} == {"publisher-subscriber"} and len(report.regrades) == 6
    assert len(gradebook.latest(gradebook.read_results(canvas_out / "results.jsonl"))) == 12

    # --- visibility: a hidden check (the grader's) and an after-due one (the class file's) reach Gradescope as such
    tests = json.loads((canvas_out / "1001" / "results.json").read_text(encoding="utf-8"))["tests"]
    assert sorted((t["name"].split(":")[0], t["name"].split(":")[-1].strip(), t["visibility"]) for t in tests) == [
        ("print-forever-node", "builds", "after_due_date"), ("print-forever-node", "works", "hidden"),
        ("publisher-subscriber", "builds", "visible"), ("publisher-subscriber", "works", "hidden")], tests


def test_a_member_the_lms_naming_cannot_map_gets_a_row_saying_why(tmp_path: Path, grader) -> None:
    download = tmp_path / "submissions.zip"
    with zipfile.ZipFile(download, "w") as zf:
        zf.writestr("adaada_1001_5001_workspace.zip", _workspace_zip({"print-forever-node": 2}))
        zf.writestr("notes from the TA.txt", "not a submission\n")
    _grade(download, "canvas", ["print-forever-node"], tmp_path / "out")
    rows = {r.student: r for r in gradebook.read_results(tmp_path / "out" / "results.jsonl")}
    assert rows["1001"].status == Status.PASSED
    (unmapped,) = [r for sid, r in rows.items() if sid != "1001"]
    assert unmapped.status == Status.NOT_GRADABLE and "not taken from the download" in unmapped.message
