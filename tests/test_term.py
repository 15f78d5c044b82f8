"""The class file (deadlines, extensions, late policy), the adjusted gradebook and its LMS exports (issue 39).

No grading and no ROS: results are hand-made :class:`LessonResult` records.
"""

from __future__ import annotations

import datetime as dt
import json
from pathlib import Path

import pytest
import yaml
from ros2course.errors import CourseError
from ros2course.grade.results import LessonResult, Status
from ros2course.report.gradebook import append_record
from ros2course.report.lms import adjusted_csv, canvas_csv, moodle_csv
from ros2course.report.term import (
    Submission,
    adjust,
    adjust_out_dir,
    format_when,
    late_counts,
    load_class,
    parse_class,
    read_intake,
)

A, B = "print-forever-node", "publisher-subscriber"
KNOWN = {A, B, "parameters"}
CET = dt.timezone(dt.timedelta(hours=1))
DUE_A = dt.datetime(2026, 3, 1, 23, 59, tzinfo=CET)
DUE_B = dt.datetime(2026, 3, 15, 23, 59, tzinfo=CET)


def result(student: str, lesson: str, score: float, max_score: float = 10.0) -> LessonResult:
    status = Status.PASSED if score == max_score else Status.FAILED
    return LessonResult(lesson, score, max_score, status, [], student=student)


def klass(**extra) -> dict:
    data = {"lessons": {A: {"due": "2026-03-01T23:59:00+01:00"}, B: {"due": "2026-03-15T23:59:00+01:00"}}}
    data.update(extra)
    return data


def parsed(**extra):
    return parse_class(klass(**extra), "class.yaml", KNOWN)


def write(path: Path, data) -> Path:
    path.write_text(yaml.safe_dump(data) if not isinstance(data, str) else data, encoding="utf-8")
    return path


def one(rows, student, lesson):
    return next(r for r in rows if r.student == student and r.lesson == lesson)


# --- the class file ------------------------------------------------------------------------

def test_a_due_date_without_time_zone_is_one_line_with_a_hint(tmp_path: Path) -> None:
    path = write(tmp_path / "class.yaml", f"lessons:\n  {A}:\n    due: 2026-03-01 23:59\n")
    with pytest.raises(CourseError) as caught:
        load_class(path, KNOWN)
    assert "\n" not in caught.value.message
    assert f"lessons.{A}.due" in caught.value.message and "no time zone" in caught.value.message
    assert "+01:00" in caught.value.hint
    # YAML's own timestamp without an offset (a naive datetime) is refused too
    write(path, f"lessons:\n  {A}:\n    due: 2026-03-01T23:59:00\n")
    with pytest.raises(CourseError, match="no time zone"):
        load_class(path, KNOWN)
    write(path, f"lessons:\n  {A}:\n    due: 2026-03-01T23:59:00+01:00\n")
    assert load_class(path, KNOWN).lessons[A].due == DUE_A


def test_unknown_lesson_is_refused_with_the_closest_id() -> None:
    with pytest.raises(CourseError) as caught:
        parse_class({"lessons": {"print-forever-nod": {"due": "2026-03-01T23:59:00Z"}}}, "c.yaml", KNOWN)
    assert "unknown lesson 'print-forever-nod'" in caught.value.message
    assert A in caught.value.hint


def test_the_course_catalog_is_the_default_set_of_lessons() -> None:
    assert parse_class({"lessons": {A: {"due": "2026-03-01T23:59:00Z"}}}).lessons[A].due.tzinfo is not None
    with pytest.raises(CourseError, match="unknown lesson"):
        parse_class({"lessons": {"no-such-lesson": {"due": "2026-03-01T23:59:00Z"}}})


def test_extension_for_an_unknown_student_is_refused() -> None:
    with pytest.raises(CourseError, match="unknown student 'alic'") as caught:
        parsed(students=["alice", "bob"], extensions={"alic": {A: {"days": 2}}})
    assert "alice" in caught.value.hint
    # without students:, the graded results are the class list
    class_file = parsed(extensions={"zoe": {A: {"days": 2}}})
    with pytest.raises(CourseError, match="not in the graded results"):
        adjust([result("alice", A, 10)], {}, class_file)


@pytest.mark.parametrize(("data", "words"), [
    (klass(late_policy={"penalty_per_day": 10, "penalty_per_hour": 1}), "not both"),
    (klass(late_policy={"late_days": 3}), "need penalty_per_day"),
    (klass(late_policy={"penalty_per_day": 10, "cap": 150}), "late_policy.cap"),
    (klass(late_policy={"penalty_per_dya": 10}), "unknown key"),
    (klass(extensions={"alice": {A: {"days": 1, "due": "2026-03-02T00:00:00Z"}}}), "exactly one"),
    (klass(extensions={"alice": {"parameters": {"days": 1}}}), "lesson without a due date"),
    (klass(visibility={A: {"prints": "secret"}}), "not a visibility"),
    (klass(visibility={"nope": {"prints": "hidden"}}), "unknown lesson"),
    (klass(deadline=3), "unknown key"),
    ({"students": ["a"]}, "lessons: missing"),
    ([1, 2], "a mapping"),
])
def test_bad_class_files_are_one_line(data, words: str) -> None:
    with pytest.raises(CourseError) as caught:
        parse_class(data, "class.yaml", KNOWN)
    assert words in caught.value.message
    assert "\n" not in caught.value.message and caught.value.hint


def test_missing_and_broken_files(tmp_path: Path) -> None:
    with pytest.raises(CourseError, match="no class file"):
        load_class(tmp_path / "class.yaml", KNOWN)
    with pytest.raises(CourseError, match="not valid YAML"):
        load_class(write(tmp_path / "bad.yaml", "lessons: [\n"), KNOWN)


def test_visibility_is_kept() -> None:
    class_file = parsed(visibility={A: {"prints_forever": "after_due", "rate": "hidden"}})
    assert class_file.visibility[A] == {"prints_forever": "after_due", "rate": "hidden"}


# --- penalties ------------------------------------------------------------------------------

def at(due: dt.datetime, **late) -> dt.datetime:
    return due + dt.timedelta(**late)


def test_penalty_per_day_counts_started_days_and_caps() -> None:
    class_file = parsed(late_policy={"penalty_per_day": 10, "cap": 30})
    rows = adjust([result(s, A, 8) for s in "abcde"],
                  {"a": at(DUE_A, seconds=-5), "b": at(DUE_A, minutes=1), "c": at(DUE_A, days=1, minutes=1),
                   "d": at(DUE_A, days=9), "e": None}, class_file)
    a, b, c, d, e = rows
    assert (a.penalty, a.score, a.reason, a.late) == (0, 8, "on time", False)
    assert (b.penalty, b.score, b.reason, b.late) == (10, 7.2, "1 day late: -10 %", True)
    assert (c.penalty, c.score, c.reason) == (20, 6.4, "2 days late: -20 %")
    assert c.lateness == 86460
    assert (d.penalty, d.score, d.reason) == (30, 5.6, "9 days late: -30 % (cap)")
    assert (e.penalty, e.score, e.reason, e.lateness) == (0, 8, "no submission time: not adjusted", None)


def test_penalty_per_hour_and_grace() -> None:
    class_file = parsed(late_policy={"penalty_per_hour": 5, "grace_minutes": 15})
    rows = adjust([result(s, A, 10) for s in "abc"],
                  {"a": at(DUE_A, minutes=14), "b": at(DUE_A, minutes=16), "c": at(DUE_A, hours=2, minutes=30)},
                  class_file)
    assert rows[0].reason == "on time (14 minutes late, within the 15-minute grace)" and rows[0].penalty == 0
    assert not rows[0].late
    # the grace decides whether it is late; lateness then counts from the due date
    assert (rows[1].reason, rows[1].score) == ("1 hour late: -5 %", 9.5)
    assert (rows[2].reason, rows[2].score) == ("3 hours late: -15 %", 8.5)


def test_late_days_are_spent_in_due_date_order_across_lessons() -> None:
    class_file = parsed(late_policy={"late_days": 2, "penalty_per_day": 10})
    # B is listed first but due later: A's lateness spends the late days first
    results = [result("ann", B, 10), result("ann", A, 10)]
    times = {"ann": Submission("ann", submitted_at=at(DUE_A, days=16))}  # one time for both lessons
    rows = adjust(results, times, class_file)
    first, second = one(rows, "ann", A), one(rows, "ann", B)
    # A: 16 days late after DUE_A -> 16 started days; 2 covered by late days, 14 at 10 % (capped at 100)
    assert first.late_days_used == 2
    assert first.reason == "16 days late: 2 late days used (0 left), 14 days not covered: -100 % (cap)"
    assert first.score == 0
    # B: 2 days late, no late days left
    assert second.late_days_used == 0 and second.reason == "2 days late: 0 late days used (0 left), " \
        "2 days not covered: -20 %" and second.score == 8


def test_late_days_cover_whole_lateness() -> None:
    class_file = parsed(late_policy={"late_days": 3, "penalty_per_day": 25})
    rows = adjust([result("bo", A, 6), result("bo", B, 6)],
                  {"bo": Submission("bo", submitted_at=at(DUE_A, hours=30))}, class_file)
    assert one(rows, "bo", A).reason == "2 days late: 2 late days used (1 left)"
    assert one(rows, "bo", A).score == 6
    assert one(rows, "bo", B).reason == "on time"


def test_extensions_by_days_and_by_due_date() -> None:
    class_file = parsed(late_policy={"penalty_per_day": 10},
                        extensions={"al": {A: {"days": 2}},
                                    "bea": {"*": {"due": "2026-03-03T12:00:00+01:00"}, B: {"days": 0.5}}})
    times = {"al": at(DUE_A, days=1), "bea": dt.datetime(2026, 3, 4, 12, 0, tzinfo=CET)}
    rows = adjust([result("al", A, 10), result("bea", A, 10), result("bea", B, 10)], times, class_file)
    al = one(rows, "al", A)
    assert al.due == DUE_A + dt.timedelta(days=2) and al.extended
    assert al.reason == "extension to 2026-03-03 23:59 +01:00; on time" and al.score == 10
    bea = one(rows, "bea", A)
    assert bea.reason == "extension to 2026-03-03 12:00 +01:00; 1 day late: -10 %" and bea.score == 9
    # a lesson's own extension wins over "*"
    assert one(rows, "bea", B).due == DUE_B + dt.timedelta(hours=12)
    assert one(rows, "bea", B).reason.startswith("extension to 2026-03-16 11:59 +01:00; on time")


def test_reasons_without_times_or_due_dates() -> None:
    class_file = parse_class({"lessons": {A: {"due": "2026-03-01T23:59:00Z"}},
                              "late_policy": {"penalty_per_day": 10}}, "c.yaml", KNOWN)
    times = {"late": Submission("late", lms_late=True), "bad": Submission("bad", problem="submission time 'x' unreadable")}
    rows = adjust([result("late", A, 5), result("bad", A, 5), result("late", B, 5)], times, class_file)
    assert one(rows, "late", A).reason == ("no submission time; the LMS marks it late: not adjusted "
                                           "(no penalty guessed)")
    assert one(rows, "late", A).score == 5
    assert one(rows, "bad", A).reason == "submission time 'x' unreadable: not adjusted"
    assert one(rows, "late", B).reason == "no due date for this lesson in the class file: not adjusted"
    assert adjust([result("x", A, 5)], {}, None)[0].reason == "no class file: not adjusted"
    # no late policy: lateness reported, never penalised
    unpolicied = parse_class({"lessons": {A: {"due": "2026-03-01T23:59:00Z"}}}, "c.yaml", KNOWN)
    row = adjust([result("x", A, 5)], {"x": at(DUE_A, days=3)}, unpolicied)[0]
    assert (row.reason, row.score, row.late) == ("3 days late: no late policy, not penalised", 5, True)


def test_format_when_keeps_the_offset() -> None:
    assert format_when(dt.datetime(2026, 3, 3, 12, 0, tzinfo=CET)) == "2026-03-03 12:00 +01:00"
    assert format_when(dt.datetime(2026, 3, 3, 12, 0, tzinfo=dt.timezone(-dt.timedelta(hours=3, minutes=30)))) \
        == "2026-03-03 12:00 -03:30"


def test_read_intake_is_tolerant(tmp_path: Path) -> None:
    assert read_intake(tmp_path) == {}
    (tmp_path / "intake").mkdir()
    path = tmp_path / "intake" / "intake.json"
    path.write_text(json.dumps([
        {"student": "al", "name": "Al Smith", "submitted_at": "2026-03-02T10:00:00+01:00", "lms_late": True,
         "commit": "abc"},
        {"student": "bo", "name": "", "submitted_at": None, "lms_late": None, "commit": None},
        {"student": "cy", "submitted_at": "2026-03-02 10:00"},
        {"student": "di", "submitted_at": "yesterday"},
        "junk"]), encoding="utf-8")
    got = read_intake(tmp_path)
    assert got["al"].name == "Al Smith" and got["al"].submitted_at == dt.datetime(2026, 3, 2, 10, tzinfo=CET)
    assert got["al"].lms_late is True
    assert got["bo"].submitted_at is None and not got["bo"].problem
    assert got["cy"].submitted_at is None and "no time zone" in got["cy"].problem
    assert "unreadable" in got["di"].problem
    path.write_text(json.dumps({"al": {"submitted_at": "2026-03-02T09:00:00Z"}}), encoding="utf-8")
    assert read_intake(tmp_path)["al"].submitted_at == dt.datetime(2026, 3, 2, 9, tzinfo=dt.timezone.utc)
    path.write_text(json.dumps({"submissions": [{"student": "al", "submitted_at": "2026-03-02T09:00:00Z"}]}))
    assert "al" in read_intake(tmp_path)
    # the intake's manifest: its context, then the records under "students"
    path.write_text(json.dumps({"format": "canvas", "source": "/x", "before": None, "students": [
        {"student": "al", "name": "Al", "submitted_at": "2026-03-02T09:00:00+00:00", "lms_late": False,
         "commit": None}]}))
    assert read_intake(tmp_path)["al"].name == "Al"
    path.write_text("{broken", encoding="utf-8")
    assert read_intake(tmp_path) == {}


# --- the LMS exports: a class of 4 over 2 lessons -------------------------------------------

CLASS_OF_4 = {
    "lessons": {A: {"due": "2026-03-01T23:59:00+01:00"}, B: {"due": "2026-03-15T23:59:00+01:00"}},
    "students": ["ann", "bob", "cat", "dan"],
    "extensions": {"cat": {A: {"days": 3}}},
    "late_policy": {"penalty_per_day": 10, "cap": 50, "grace_minutes": 10},
}
INTAKE = [
    {"student": "ann", "name": "Ann Archer", "submitted_at": "2026-03-01T20:00:00+01:00", "lms_late": False},
    {"student": "bob", "name": "Bob, Jr.", "submitted_at": "2026-03-03T08:00:00+01:00", "lms_late": True},
    {"student": "cat", "name": "", "submitted_at": "2026-03-04T10:00:00+01:00", "lms_late": True},
    {"student": "dan", "name": "Dan Doe", "submitted_at": None, "lms_late": None},
]


@pytest.fixture
def outdir(tmp_path: Path) -> Path:
    out = tmp_path / "grades"
    out.mkdir()
    for student, a, b in (("ann", 10, 20), ("bob", 8, 15), ("cat", 6, 20), ("dan", 9, None)):
        append_record(out / "results.jsonl", result(student, A, a, 10))
        if b is not None:
            append_record(out / "results.jsonl", result(student, B, b, 20))
    (out / "intake").mkdir()
    (out / "intake" / "intake.json").write_text(json.dumps(INTAKE), encoding="utf-8")
    write(out / "class.yaml", CLASS_OF_4)
    return out


def test_adjusted_class_of_four(outdir: Path) -> None:
    book = adjust_out_dir(outdir, known_lessons=KNOWN)
    assert [(r.student, r.lesson, r.score, r.reason) for r in book.adjusted] == [
        ("ann", A, 10, "on time"),
        ("ann", B, 20, "on time"),
        ("bob", A, 6.4, "2 days late: -20 %"),  # 32 h 1 min late
        ("bob", B, 15, "on time"),
        ("cat", A, 6, "extension to 2026-03-04 23:59 +01:00; on time"),
        ("cat", B, 20, "on time"),
        ("dan", A, 9, "no submission time: not adjusted"),
    ]
    assert book.lessons == [A, B]
    assert book.names == {"ann": "Ann Archer", "bob": "Bob, Jr.", "dan": "Dan Doe"}
    assert late_counts(book.adjusted) == {A: 1, B: 0}


def test_canvas_export_exact(outdir: Path) -> None:
    book = adjust_out_dir(outdir, known_lessons=KNOWN)
    assert canvas_csv(book.adjusted, book.names, book.lessons).splitlines() == [
        f"Student,ID,SIS User ID,SIS Login ID,Section,{A},{B},Final Points",
        "Points Possible,,,,,10,20,30",
        "Ann Archer,,ann,ann,,10,20,30",
        '"Bob, Jr.",,bob,bob,,6.4,15,21.4',
        "cat,,cat,cat,,6,20,26",
        "Dan Doe,,dan,dan,,9,,9",
    ]


def test_moodle_export_exact(outdir: Path) -> None:
    book = adjust_out_dir(outdir, known_lessons=KNOWN)
    assert moodle_csv(book.adjusted, book.lessons).splitlines() == [
        f"ID number,{A},{B},Total",
        "ann,10,20,30",
        "bob,6.4,15,21.4",
        "cat,6,20,26",
        "dan,9,,9",
    ]


def test_plain_csv_has_every_adjustment(outdir: Path) -> None:
    lines = adjusted_csv(adjust_out_dir(outdir, known_lessons=KNOWN).adjusted).splitlines()
    assert lines[0] == ("student,lesson,status,raw_score,max_score,submitted_at,due,lateness_seconds,"
                        "penalty_percent,late_days_used,score,reason")
    assert lines[3] == (f"bob,{A},failed,8,10,2026-03-03 08:00 +01:00,2026-03-01 23:59 +01:00,115260,20,0,6.4,"
                        "2 days late: -20 %")
    assert lines[-1] == f"dan,{A},failed,9,10,,2026-03-01 23:59 +01:00,,0,0,9,no submission time: not adjusted"


# --- the command line -------------------------------------------------------------------------

def cli(*args: str):
    from conftest import run_cli_in_process

    return run_cli_in_process(*args)


def test_cli_export_each_format(outdir: Path, tmp_path: Path) -> None:
    proc = cli("export", str(outdir), "--format", "moodle")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines()[2] == "bob,6.4,15,21.4"
    target = tmp_path / "canvas.csv"
    proc = cli("export", str(outdir), "--format", "canvas", "--output", str(target))
    assert proc.returncode == 0, proc.stderr
    assert target.read_text(encoding="utf-8").splitlines()[1] == "Points Possible,,,,,10,20,30"
    assert "1 late" in proc.stderr
    proc = cli("export", str(outdir))
    assert proc.returncode == 0 and "2 days late: -20 %" in proc.stdout


def test_cli_export_with_another_class_file(outdir: Path, tmp_path: Path) -> None:
    other = write(tmp_path / "strict.yaml", dict(CLASS_OF_4, late_policy={"penalty_per_hour": 50}))
    proc = cli("export", str(outdir), "--format", "moodle", "--class", str(other))
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.splitlines()[2] == "bob,0,15,15"  # 33 started hours at 50 %: capped at 100 %
    (outdir / "class.yaml").unlink()
    proc = cli("export", str(outdir), "--format", "moodle")
    assert proc.returncode == 0 and proc.stdout.splitlines()[2] == "bob,8,15,23"


@pytest.mark.parametrize(("args", "words"), [
    (["--format", "blackboard"], "unknown --format"),
    (["--class", "missing.yaml"], "no class file"),
])
def test_cli_export_bad_input(outdir: Path, args: list[str], words: str) -> None:
    proc = cli("export", str(outdir), *args)
    assert proc.returncode == 5
    assert words in proc.stderr and "hint:" in proc.stderr and "Traceback" not in proc.stderr


def test_cli_export_bad_class_file_and_folder(outdir: Path, tmp_path: Path) -> None:
    write(outdir / "class.yaml", f"lessons:\n  {A}:\n    due: 2026-03-01 23:59\n")
    proc = cli("export", str(outdir), "--format", "canvas")
    assert proc.returncode == 5 and "no time zone" in proc.stderr and "+01:00" in proc.stderr
    write(outdir / "class.yaml", dict(CLASS_OF_4, students=None, extensions={"eve": {A: {"days": 1}}}))
    proc = cli("export", str(outdir))
    assert proc.returncode == 5 and "not in the graded results" in proc.stderr
    proc = cli("export", str(tmp_path / "nowhere"))
    assert proc.returncode == 5 and "no such folder" in proc.stderr


def test_report_shows_the_adjustments(outdir: Path) -> None:
    from ros2course.report.html import adjustments_section, render_report, write_markdown

    section = adjustments_section(outdir)
    assert section is not None
    assert {"student": "bob", "lesson": A, "raw": "8", "max": "10", "score": "6.4",
            "reason": "2 days late: -20 %"} in section["rows"]
    html = render_report(outdir, similarity=False)
    assert "Deadlines and late policy" in html and "2 days late: -20 %" in html
    markdown = write_markdown(outdir)
    assert f"Late submissions (class.yaml): {A}: 1, {B}: 0" in markdown
    assert "bob" not in markdown
    (outdir / "class.yaml").unlink()
    assert adjustments_section(outdir) is None
    assert "Deadlines and late policy" not in render_report(outdir, similarity=False)
