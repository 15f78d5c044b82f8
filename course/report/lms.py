"""The adjusted gradebook in the import formats of Canvas and Moodle, and as a plain CSV (issue 39).

Input: the :class:`~ros2course.report.term.Adjusted` rows of :func:`ros2course.report.term.adjust`
(one per student and lesson). Every export has one row per student, one column per lesson
(the adjusted score; empty when the student has no result for it, which both LMSs read as
"leave this grade as it is") and a total (the sum of the student's adjusted scores). The
student id (the name of their submission) is the identifier the LMS matches students by.

* Canvas, "Import grades in the Gradebook" (a CSV with the columns of Canvas's own Gradebook
  export: ``Student, ID, SIS User ID, SIS Login ID, Section``, then one column per assignment;
  the second row may be ``Points Possible``):
  https://community.canvaslms.com/t5/Instructor-Guide/How-do-I-import-grades-in-the-Gradebook/ta-p/807 ;
  the totals of Canvas's export are read-only columns ignored on import
  (https://ts.vcu.edu/askit/teaching-and-learning/canvas/faculty/grading-faculty/gradebook-action-menu-faculty/),
  so the total is written as ``Final Points``, one of them.
* Moodle, "Grade import" from a CSV file (a header row; when importing, map the identifier
  column to a user field, e.g. "ID number" to ``useridnumber``, and each other column to a
  grade item or "new grade item"): https://docs.moodle.org/311/en/Grade_import . Moodle
  computes its own course total: leave the ``Total`` column unmapped ("ignore").
"""

from __future__ import annotations

import csv
import io
from collections.abc import Iterable, Mapping

from ros2course.report.term import Adjusted, format_when

#: Canvas's student columns, in the order of its Gradebook export.
CANVAS_COLUMNS = ["Student", "ID", "SIS User ID", "SIS Login ID", "Section"]
#: Canvas's read-only total column (ignored on import): the student's adjusted points.
CANVAS_TOTAL = "Final Points"
#: The first cell of Canvas's points-possible row.
CANVAS_POINTS_POSSIBLE = "Points Possible"
#: Moodle's identifier column: map it to the "ID number" user field when importing.
MOODLE_ID = "ID number"
#: Moodle's total column (leave it unmapped: Moodle computes its course total itself).
MOODLE_TOTAL = "Total"
#: The plain CSV's columns, one row per student and lesson.
CSV_COLUMNS = ["student", "lesson", "status", "raw_score", "max_score", "submitted_at", "due", "lateness_seconds",
               "penalty_percent", "late_days_used", "score", "reason"]


def _number(value: float) -> str:
    return f"{round(value, 3):g}"


def _table(adjusted: Iterable[Adjusted], lessons: list[str] | None
           ) -> tuple[list[str], list[str], dict[tuple[str, str], Adjusted]]:
    """(students sorted, lesson columns, (student, lesson) -> row)."""
    cells = {(row.student, row.lesson): row for row in adjusted}
    students = sorted({student for student, _ in cells})
    seen = sorted({lesson for _, lesson in cells})
    columns = list(lessons or [])
    columns += [lesson for lesson in seen if lesson not in columns]
    return students, columns, cells


def _write(rows: list[list[str]]) -> str:
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="\n").writerows(rows)
    return buffer.getvalue()


def _student_cells(student: str, columns: list[str], cells: Mapping[tuple[str, str], Adjusted]) -> list[str]:
    """One cell per lesson (adjusted score, "" without a result) and the total."""
    scores = [cells[(student, lesson)].score if (student, lesson) in cells else None for lesson in columns]
    return [*("" if s is None else _number(s) for s in scores), _number(sum(s for s in scores if s is not None))]


def _maxima(columns: list[str], cells: Mapping[tuple[str, str], Adjusted]) -> list[float]:
    return [max((row.max_score for (_, lesson), row in cells.items() if lesson == column), default=0.0)
            for column in columns]


def canvas_csv(adjusted: Iterable[Adjusted], names: Mapping[str, str] | None = None,
               lessons: list[str] | None = None, section: str = "", canvas_user_ids: bool = False) -> str:
    """The Canvas Gradebook import CSV of the adjusted gradebook.

    Args:
        adjusted: :class:`~ros2course.report.term.Adjusted` rows.
        names: student id -> name for Canvas's ``Student`` column (the intake's ``name``); a
            student without one gets their id.
        lessons: the lesson columns' order (e.g. the class file's); lessons not in it follow, sorted.
        section: the ``Section`` cell of every student (Canvas does not match on it).
        canvas_user_ids: the student ids are Canvas's own user ids (the class came in with ``grade --from
            canvas``, whose download names each file with the user id): they go in ``ID``, which Canvas matches
            first, and the SIS columns stay empty.

    Rows: the header ``Student, ID, SIS User ID, SIS Login ID, Section, <lesson>..., Final Points``;
    ``Points Possible`` (each lesson's maximum score, and their sum); then one row per student,
    sorted by id. Unless ``canvas_user_ids``, ``ID`` (Canvas's internal number) is left empty and the student
    id fills ``SIS User ID`` and ``SIS Login ID``, which Canvas matches a row by when ``ID`` is empty.
    A lesson column whose name is not an assignment of the course becomes a new assignment on import.
    """
    students, columns, cells = _table(adjusted, lessons)
    maxima = _maxima(columns, cells)
    rows = [[*CANVAS_COLUMNS, *columns, CANVAS_TOTAL],
            [CANVAS_POINTS_POSSIBLE, "", "", "", "", *(_number(m) for m in maxima), _number(sum(maxima))]]
    for student in students:
        name = (names or {}).get(student) or student
        ids = [student, "", ""] if canvas_user_ids else ["", student, student]
        rows.append([name, *ids, section, *_student_cells(student, columns, cells)])
    return _write(rows)


def moodle_csv(adjusted: Iterable[Adjusted], lessons: list[str] | None = None) -> str:
    """The Moodle grade import CSV of the adjusted gradebook.

    Args:
        adjusted: :class:`~ros2course.report.term.Adjusted` rows.
        lessons: the lesson columns' order; lessons not in it follow, sorted.

    Rows: the header ``ID number, <lesson>..., Total`` then one row per student, sorted by id.
    Import with "Map from: ID number" / "Map to: useridnumber" (the students' ID number field must
    hold their ids), each lesson column mapped to its grade item, and ``Total`` ignored.
    """
    students, columns, cells = _table(adjusted, lessons)
    rows = [[MOODLE_ID, *columns, MOODLE_TOTAL]]
    rows += [[student, *_student_cells(student, columns, cells)] for student in students]
    return _write(rows)


def adjusted_csv(adjusted: Iterable[Adjusted]) -> str:
    """Every adjustment, one row per student and lesson: :data:`CSV_COLUMNS`.

    Times as ``2026-03-03 12:00 +01:00`` (empty when unknown), ``lateness_seconds`` in seconds
    (negative: early; empty when unknown), ``penalty_percent`` in percent of the raw score.
    """
    rows = [list(CSV_COLUMNS)]
    for row in sorted(adjusted, key=lambda r: (r.student, r.lesson)):
        rows.append([row.student, row.lesson, row.status, _number(row.raw_score), _number(row.max_score),
                     format_when(row.submitted_at) if row.submitted_at else "", format_when(row.due) if row.due else "",
                     "" if row.lateness is None else _number(row.lateness), _number(row.penalty),
                     str(row.late_days_used), _number(row.score), row.reason])
    return _write(rows)


#: ``--format`` of ``ros2course export`` -> what it writes.
FORMATS = ("canvas", "moodle", "csv")


def export(adjusted: list[Adjusted], fmt: str, names: Mapping[str, str] | None = None,
           lessons: list[str] | None = None, canvas_user_ids: bool = False) -> str:
    """The text of one export format (:data:`FORMATS`); ``canvas_user_ids``: see :func:`canvas_csv`.

    Raises:
        ValueError: an unknown format.
    """
    if fmt == "canvas":
        return canvas_csv(adjusted, names, lessons, canvas_user_ids=canvas_user_ids)
    if fmt == "moodle":
        return moodle_csv(adjusted, lessons)
    if fmt == "csv":
        return adjusted_csv(adjusted)
    raise ValueError(f"unknown format {fmt!r}")
