"""The class file (``class.yaml``): deadlines, extensions, the late policy, and the adjusted gradebook (issue 39).

A class file says when each lesson is due, which students have more time, and how lateness
costs points. It is read and checked whole by :func:`load_class` before anything is graded
or exported: every bad input is one :class:`~ros2course.errors.CourseError` (one line plus a
hint). :func:`adjust` then turns a batch's raw results (``OUTDIR/results.jsonl``) and the
submission times of the intake (``OUTDIR/intake/intake.json``, :func:`read_intake`) into one
:class:`Adjusted` row per student and lesson: raw score, due date after extension, lateness,
penalty, adjusted score and the reason in words. :mod:`ros2course.report.lms` exports these
rows for Canvas and Moodle.

A sample::

    lessons:
      print-forever-node: {due: 2026-03-01T23:59:00+01:00}
      publisher-subscriber: {due: "2026-03-15T23:59:00+01:00"}
    students: [alice, bob, carol, dave]          # optional: the class list
    extensions:
      alice: {print-forever-node: {days: 2}}     # two more days for one lesson
      bob: {"*": {due: 2026-03-20T12:00:00+01:00}}  # one new due date for every lesson
    late_policy: {penalty_per_day: 10, cap: 50, grace_minutes: 15}
    visibility:
      print-forever-node: {prints_forever: after_due}

The rules (documented in ``docs/instructors.md``):

* a due date must carry its time zone (``+01:00`` or ``Z``); lateness is measured between
  two instants, so an ambiguous local time is refused rather than guessed;
* an extension is ``{days: n}`` (added to the lesson's due date, fractions allowed) or
  ``{due: ...}`` (a new due date); a lesson's own extension wins over the student's ``"*"``;
* a submission is late when it arrives more than ``grace_minutes`` after its due date; the
  grace only decides *whether* it is late, lateness is then counted from the due date itself;
* lateness is counted in started days (``ceil(seconds / 86400)``: one minute late is one
  day) or, with ``penalty_per_hour``, in started hours (``ceil(seconds / 3600)``);
* the penalty is a percent of the score earned (8 of 10 points, 2 days late at 10 %/day:
  8 x (1 - 0.20) = 6.4), never more than ``cap`` percent;
* ``late_days: N`` gives each student N late days for the whole term, spent automatically on
  their late lessons in the chronological order of their (extended) due dates; the started
  days the late days do not cover cost ``penalty_per_day`` each (capped);
* with no submission time, nothing is adjusted and the reason says so; an LMS that marks a
  submission late without giving its time is reported, never turned into a guessed penalty.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import difflib
import json
import math
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any, Optional

from pydantic import AwareDatetime, BaseModel, ConfigDict, Field, ValidationError, model_validator

from ros2course.errors import CourseError
from ros2course.grade.results import LessonResult, Visibility

#: The name of the class file inside a grading OUTDIR (``ros2course report`` and ``export`` look for it there).
CLASS_FILE = "class.yaml"
#: Where the intake writes its manifest, relative to OUTDIR.
INTAKE_FILE = Path("intake") / "intake.json"
#: The key of an extension that applies to every lesson of a student.
ALL_LESSONS = "*"

DAY = 86400.0  #: seconds
HOUR = 3600.0  #: seconds

_TZ_HINT = "write the time zone offset, e.g. 2026-03-01T23:59:00+01:00 (or ...Z for UTC)"


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class LessonTerm(_Strict):
    """One lesson of the term: ``{due: datetime with a time zone}``."""

    due: AwareDatetime


class Extension(_Strict):
    """More time for one student: ``{days: n}`` (added to the due date; may be fractional) or ``{due: datetime}``."""

    days: Optional[float] = Field(default=None, gt=0)
    due: Optional[AwareDatetime] = None

    @model_validator(mode="after")
    def _one_of(self) -> Extension:
        if (self.days is None) == (self.due is None):
            raise ValueError("an extension is either {days: n} or {due: datetime}, exactly one of them")
        return self

    def applied_to(self, due: dt.datetime) -> dt.datetime:
        """The due date this extension gives, from the lesson's ``due``."""
        return self.due if self.due is not None else due + dt.timedelta(days=float(self.days or 0.0))


class LatePolicy(_Strict):
    """How lateness costs points. All percents are of the score earned; times in minutes / days.

    One of:

    * ``{penalty_per_day: p, cap: c, grace_minutes: g}``: p % per started day late, at most c %;
    * ``{penalty_per_hour: p, cap: c, grace_minutes: g}``: p % per started hour late, at most c %;
    * ``{late_days: n, penalty_per_day: p, cap: c, grace_minutes: g}``: n free late days per
      student over the term, then p % per started day they do not cover.

    ``cap`` defaults to 100 (a late submission can lose everything), ``grace_minutes`` to 0.
    """

    penalty_per_day: Optional[float] = Field(default=None, ge=0, le=100)
    penalty_per_hour: Optional[float] = Field(default=None, ge=0, le=100)
    late_days: Optional[int] = Field(default=None, ge=0)
    cap: float = Field(default=100.0, ge=0, le=100)
    grace_minutes: float = Field(default=0.0, ge=0)

    @model_validator(mode="after")
    def _one_kind(self) -> LatePolicy:
        if self.penalty_per_day is not None and self.penalty_per_hour is not None:
            raise ValueError("give penalty_per_day or penalty_per_hour, not both")
        if self.late_days is not None and self.penalty_per_hour is not None:
            raise ValueError("late_days go with penalty_per_day (the penalty once the late days are spent), "
                             "not penalty_per_hour")
        if self.late_days is not None and self.penalty_per_day is None:
            raise ValueError("late_days need penalty_per_day: the penalty once a student's late days are spent")
        if self.penalty_per_day is None and self.penalty_per_hour is None:
            raise ValueError("give penalty_per_day, penalty_per_hour, or late_days with penalty_per_day")
        return self




class ClassFile(_Strict):
    """The whole ``class.yaml`` (see the module docstring for a sample).

    Attributes:
        lessons: lesson id -> its due date.
        students: the class list (optional); when given, every extension must name one of them.
        extensions: student -> (lesson id or ``"*"``) -> :class:`Extension`.
        late_policy: :class:`LatePolicy`; None: lateness is reported, never penalised.
        visibility: lesson id -> check id -> ``visible | hidden | after_due``, over the grader's own
            (:meth:`~ros2course.grade.results.LessonResult.with_visibility`): Gradescope's per-test
            visibility follows it (check ids are kept as given).
    """

    lessons: dict[str, LessonTerm]
    students: Optional[list[str]] = None
    extensions: dict[str, dict[str, Extension]] = Field(default_factory=dict)
    late_policy: Optional[LatePolicy] = None
    visibility: dict[str, dict[str, Visibility]] = Field(default_factory=dict)

    def due_for(self, student: str, lesson: str) -> tuple[dt.datetime | None, dt.datetime | None]:
        """``(due date after extension, the extended due date or None)`` of ``student`` for ``lesson``.

        The first is None when the class file gives ``lesson`` no due date. A lesson's own
        extension wins over the student's ``"*"`` one.
        """
        term = self.lessons.get(lesson)
        if term is None:
            return None, None
        mine = self.extensions.get(student, {})
        extension = mine.get(lesson) or mine.get(ALL_LESSONS)
        if extension is None:
            return term.due, None
        extended = extension.applied_to(term.due)
        return extended, extended


# --- reading and checking -------------------------------------------------------------------

def _where(loc: tuple[Any, ...]) -> str:
    return ".".join(str(part) for part in loc) or "(top level)"


def _one_line(path: Path, exc: ValidationError) -> CourseError:
    """The first problem of a pydantic error as one line plus a hint."""
    error = exc.errors()[0]
    kind, loc, value = error["type"], tuple(error["loc"]), error.get("input")
    where = f"{path}: {_where(loc)}"
    if kind == "timezone_aware":
        return CourseError(f"{where}: {value} has no time zone", _TZ_HINT)
    if kind.startswith(("datetime", "date")):
        return CourseError(f"{where}: {value!r} is not a date and time ({error['msg']})", _TZ_HINT)
    if kind == "extra_forbidden":
        known = {"lessons": "lessons, students, extensions, late_policy, visibility",
                 "late_policy": "penalty_per_day, penalty_per_hour, late_days, cap, grace_minutes"}
        parent = "late_policy" if "late_policy" in loc else ("lessons" if len(loc) == 1 else "")
        allowed = known.get(parent) or ("days or due" if loc[:1] == ("extensions",) else "due")
        return CourseError(f"{where}: unknown key", f"the keys allowed here: {allowed}")
    if kind == "missing":
        return CourseError(f"{where}: missing", "see the sample class.yaml in docs/instructors.md")
    if kind == "literal_error":
        return CourseError(f"{where}: {value!r} is not a visibility", "use visible, hidden or after_due")
    message = str(error["msg"]).removeprefix("Value error, ")
    return CourseError(f"{where}: {message}" + (f" (got {value!r})" if not isinstance(value, (dict, list)) else ""),
                       "see the sample class.yaml in docs/instructors.md")


def _unknown(path: Path, where: str, name: str, known: Iterable[str], what: str, hint: str) -> CourseError:
    close = difflib.get_close_matches(name, list(known), n=3)
    return CourseError(f"{path}: {where}: unknown {what} {name!r}",
                       f"did you mean {', '.join(close)}?" if close else hint)


def parse_class(data: Any, path: Path | str = CLASS_FILE, known_lessons: Iterable[str] | None = None) -> ClassFile:
    """Check an already-parsed class file (``yaml.safe_load``'s output) and return it.

    Args:
        data: the YAML document (a mapping).
        path: named in the messages.
        known_lessons: the course's lesson ids; None: :func:`ros2course.lesson.catalog.load_catalog`'s.

    Raises:
        CourseError: the first problem, one line plus a hint: not a mapping, an unknown key, a
            due date without a time zone, a lesson the course does not have, an extension for a
            student not in ``students`` or for a lesson without a due date, a bad late policy.
    """
    path = Path(path)
    if not isinstance(data, dict):
        raise CourseError(f"{path}: a class file is a mapping with lessons: (and students:, extensions:, "
                          "late_policy:, visibility:)", "see the sample class.yaml in docs/instructors.md")
    try:
        parsed = ClassFile.model_validate(data)
    except ValidationError as exc:
        raise _one_line(path, exc) from None
    if known_lessons is None:
        from ros2course.lesson.catalog import load_catalog  # noqa: PLC0415 - only needed to check ids

        known_lessons = load_catalog().ids()
    known = set(known_lessons)
    for section, ids in (("lessons", parsed.lessons), ("visibility", parsed.visibility)):
        for lesson in ids:
            if lesson not in known:
                raise _unknown(path, section, lesson, known, "lesson", "run `ros2course list` to see every lesson id")
    for student, per_lesson in parsed.extensions.items():
        if parsed.students is not None and student not in parsed.students:
            raise _unknown(path, "extensions", student, parsed.students, "student",
                           "add them to students:, or fix the id")
        for lesson in per_lesson:
            if lesson != ALL_LESSONS and lesson not in parsed.lessons:
                problem = "lesson" if lesson not in known else "lesson without a due date"
                raise _unknown(path, f"extensions.{student}", lesson, parsed.lessons, problem,
                               'give the lesson a due date under lessons:, or use "*" for every lesson')
    return parsed


def load_class(path: Path | str, known_lessons: Iterable[str] | None = None) -> ClassFile:
    """Read and check a class file (``class.yaml``).

    Args:
        path: the YAML file.
        known_lessons: the course's lesson ids (tests inject them); None: the active course's
            (:func:`ros2course.lesson.catalog.load_catalog`).

    Raises:
        CourseError: the file is missing or not YAML, or anything :func:`parse_class` refuses.
    """
    import yaml  # noqa: PLC0415 - start time: the CLI imports this module lazily anyway

    from ros2course.lesson.catalog import yaml_error_text  # noqa: PLC0415 - start time: the catalog (yaml), with yaml above

    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise CourseError(f"no class file at {path}", "write one: see docs/instructors.md, "
                          "'Deadlines, late policy and the LMS gradebook'") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise CourseError(f"{path}: cannot be read: {exc}", "check the file's permissions and encoding (UTF-8)") from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise CourseError(f"{path}: not valid YAML: {yaml_error_text(exc)}",
                          "fix the YAML syntax (indentation, quotes)") from None
    return parse_class(data, path, known_lessons)


def check_students(class_file: ClassFile, results: Iterable[LessonResult], path: Path | str = CLASS_FILE) -> None:
    """Refuse extensions for students that have no graded result.

    Raises:
        CourseError: an extension names a student absent from ``results`` (a typo would
            otherwise silently leave the real student without their extension).
    """
    graded = {r.student for r in results}
    for student in class_file.extensions:
        if student not in graded:
            raise _unknown(Path(path), "extensions", student, graded, "student (not in the graded results)",
                           "fix the id, or grade that student's submission first")


# --- submission times -----------------------------------------------------------------------

@dataclasses.dataclass(frozen=True)
class Submission:
    """When a student submitted, as the intake recorded it.

    Attributes:
        student: the student id.
        name: their name for people (an LMS's "Student" column); "" when unknown.
        submitted_at: an aware datetime; None when the intake has no time.
        lms_late: the LMS's own late flag (True / False), None when it gave none.
        problem: why a given time was not used (unreadable, no time zone); "" otherwise.
    """

    student: str
    name: str = ""
    submitted_at: dt.datetime | None = None
    lms_late: bool | None = None
    problem: str = ""


def _submission(record: Mapping[str, Any], student: str) -> Submission:
    raw = record.get("submitted_at")
    when, problem = None, ""
    if isinstance(raw, str) and raw.strip():
        try:
            when = dt.datetime.fromisoformat(raw.strip().replace("Z", "+00:00"))
        except ValueError:
            problem = f"submission time {raw!r} unreadable"
        else:
            if when.tzinfo is None or when.utcoffset() is None:
                when, problem = None, f"submission time {raw!r} has no time zone"
    elif raw not in (None, ""):
        problem = f"submission time {raw!r} unreadable"
    late = record.get("lms_late")
    return Submission(student, str(record.get("name") or ""), when, late if isinstance(late, bool) else None, problem)


def read_intake(out_dir: Path) -> dict[str, Submission]:
    """Student id -> :class:`Submission` from ``OUTDIR/intake/intake.json`` (the intake's manifest).

    The file is a list of records, a mapping of student id -> record, or a mapping holding such
    a list (``{"submissions": [...]}``); each record has ``student`` (or is keyed by it),
    ``name``, ``submitted_at`` (ISO 8601 with an offset, or null), ``lms_late`` and ``commit``.
    Tolerant: a missing or unreadable file, or a broken record, means no submission times (the
    adjustments then say "no submission time").
    """
    try:
        data = json.loads((Path(out_dir) / INTAKE_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    records: list[tuple[str, Any]] = []
    if isinstance(data, list):
        records = [(str(r.get("student", "")), r) for r in data if isinstance(r, dict)]
    elif isinstance(data, dict):
        lists = [v for v in data.values() if isinstance(v, list)]
        if lists and not any(isinstance(v, dict) for v in data.values()):
            records = [(str(r.get("student", "")), r) for v in lists for r in v if isinstance(r, dict)]
        else:
            records = [(str(r.get("student") or key), r) for key, r in data.items() if isinstance(r, dict)]
    return {student: _submission(record, student) for student, record in records if student}


def intake_format(out_dir: Path) -> str | None:
    """The format the class came in with (``OUTDIR/intake/intake.json``'s ``format``: ``canvas``, ``git``...),
    None without a readable manifest."""
    try:
        data = json.loads((Path(out_dir) / INTAKE_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    fmt = data.get("format") if isinstance(data, dict) else None
    return fmt if isinstance(fmt, str) else None


# --- the adjustments ------------------------------------------------------------------------

@dataclasses.dataclass
class Adjusted:
    """One student's result for one lesson, after the late policy.

    Attributes:
        student, lesson: whose and which.
        raw_score, max_score: points as graded.
        status: the grading status (``passed``, ``failed``, ``not gradable``, ``grader error``).
        submitted_at: when it was submitted (aware), None when unknown.
        due: the due date after extension, None when the class file gives the lesson none.
        extended: True when an extension moved the due date.
        lateness: seconds after ``due`` (negative: early), None when unknown.
        penalty: percent of ``raw_score`` taken off (0..100).
        score: the adjusted score, ``raw_score * (1 - penalty / 100)`` rounded to 3 decimals.
        reason: the adjustment in words ("2 days late: -20 %", "on time", ...).
        late_days_used: late days of the term's allowance this lesson spent.
        late: True when it counted as late (after the due date and the grace), penalised or not.
    """

    student: str
    lesson: str
    raw_score: float
    max_score: float
    status: str
    submitted_at: dt.datetime | None
    due: dt.datetime | None
    extended: bool
    lateness: float | None
    penalty: float
    score: float
    reason: str
    late_days_used: int = 0
    late: bool = False


def format_when(when: dt.datetime) -> str:
    """``2026-03-03 12:00 +01:00``: a date, a time to the minute and the offset it was given in."""
    offset = when.utcoffset() or dt.timedelta(0)
    sign = "-" if offset < dt.timedelta(0) else "+"
    minutes = int(abs(offset).total_seconds() // 60)
    return f"{when:%Y-%m-%d %H:%M} {sign}{minutes // 60:02d}:{minutes % 60:02d}"


def _count(number: int, unit: str) -> str:
    return f"{number} {unit}" + ("" if number == 1 else "s")


def _percent(value: float) -> str:
    return f"{round(value, 3):g} %"


def _penalised(late_units: int, per_unit: float, cap: float) -> tuple[float, str]:
    """(percent, words) of ``late_units`` started days or hours at ``per_unit`` percent each, at most ``cap``."""
    penalty = min(cap, late_units * per_unit)
    return penalty, f"-{_percent(penalty)}" + (" (cap)" if late_units * per_unit > cap else "")


def adjust(results: Iterable[LessonResult], intake_times: Mapping[str, Submission | dt.datetime | None],
           class_file: ClassFile | None) -> list[Adjusted]:
    """One :class:`Adjusted` per (student, lesson) of ``results``, sorted by student then lesson.

    Args:
        results: graded results (the last one per student and lesson counts).
        intake_times: student id -> their :class:`Submission` (:func:`read_intake`), or directly
            their aware submission time (None: unknown). A student missing here has no time.
        class_file: the checked class file (:func:`load_class`); None: nothing is adjusted.

    The rules are the module docstring's (started days / hours, grace, cap, late days spent in
    the chronological order of each student's due dates after extension).

    Raises:
        CourseError: an extension names a student absent from ``results`` (:func:`check_students`).
    """
    latest: dict[tuple[str, str], LessonResult] = {}
    for result in results:
        latest[(result.student, result.lesson)] = result
    if class_file is not None:
        check_students(class_file, latest.values())
    policy = class_file.late_policy if class_file is not None else None
    grace = 60.0 * policy.grace_minutes if policy is not None else 0.0
    # each student's lessons in the order their late days are spent: by (extended) due date
    order: list[tuple[str, float, str]] = []
    dues: dict[tuple[str, str], tuple[dt.datetime | None, dt.datetime | None]] = {}
    for student, lesson in latest:
        dues[(student, lesson)] = class_file.due_for(student, lesson) if class_file is not None else (None, None)
        due = dues[(student, lesson)][0]
        order.append((student, due.timestamp() if due is not None else math.inf, lesson))
    left: dict[str, int] = {}
    out: dict[tuple[str, str], Adjusted] = {}
    for student, _, lesson in sorted(order):
        result = latest[(student, lesson)]
        due, extended = dues[(student, lesson)]
        given = intake_times.get(student)
        submission = given if isinstance(given, Submission) else Submission(
            student, submitted_at=given if isinstance(given, dt.datetime) and given.utcoffset() is not None else None)
        row = Adjusted(student, lesson, result.score, result.max_score, result.status.value, submission.submitted_at,
                       due, extended is not None, None, 0.0, result.score, "")
        prefix = f"extension to {format_when(extended)}; " if extended is not None else ""
        if class_file is None:
            row.reason = "no class file: not adjusted"
        elif due is None:
            row.reason = "no due date for this lesson in the class file: not adjusted"
        elif submission.submitted_at is None:
            why = submission.problem or "no submission time"
            if submission.lms_late:
                row.reason = prefix + f"{why}; the LMS marks it late: not adjusted (no penalty guessed)"
            else:
                row.reason = prefix + f"{why}: not adjusted"
        else:
            row.lateness = (submission.submitted_at - due).total_seconds()
            row.reason = prefix + _lateness_reason(row, policy, grace, left)
        row.score = round(row.raw_score * (1 - row.penalty / 100), 3)
        out[(student, lesson)] = row
    return [out[key] for key in sorted(out)]


def _lateness_reason(row: Adjusted, policy: LatePolicy | None, grace: float, left: dict[str, int]) -> str:
    """Set ``row.penalty`` / ``row.late_days_used`` from ``row.lateness`` (seconds) and say why, in words."""
    lateness = float(row.lateness or 0.0)
    if lateness <= 0:
        return "on time"
    if lateness <= grace:
        return f"on time ({_count(math.ceil(lateness / 60), 'minute')} late, within the " \
               f"{policy.grace_minutes if policy else 0:g}-minute grace)"
    days = math.ceil(lateness / DAY)
    row.late = True
    if policy is None:
        return f"{_count(days, 'day')} late: no late policy, not penalised"
    if policy.penalty_per_hour is not None:
        hours = math.ceil(lateness / HOUR)
        row.penalty, words = _penalised(hours, policy.penalty_per_hour, policy.cap)
        return f"{_count(hours, 'hour')} late: {words}"
    per_day = float(policy.penalty_per_day or 0.0)
    if policy.late_days is None:
        row.penalty, words = _penalised(days, per_day, policy.cap)
        return f"{_count(days, 'day')} late: {words}"
    remaining = left.setdefault(row.student, policy.late_days)
    used = min(days, remaining)
    left[row.student] = remaining - used
    row.late_days_used = used
    spent = f"{_count(used, 'late day')} used ({left[row.student]} left)"
    if used == days:
        return f"{_count(days, 'day')} late: {spent}"
    row.penalty, words = _penalised(days - used, per_day, policy.cap)
    return f"{_count(days, 'day')} late: {spent}, {_count(days - used, 'day')} not covered: {words}"


def late_counts(adjusted: Iterable[Adjusted]) -> dict[str, int]:
    """Lesson id -> how many of its submissions counted as late (no student data)."""
    counts: dict[str, int] = {}
    for row in adjusted:
        counts[row.lesson] = counts.get(row.lesson, 0) + (1 if row.late else 0)
    return dict(sorted(counts.items()))


@dataclasses.dataclass
class Gradebook:
    """A graded OUTDIR with its class file applied (:func:`adjust_out_dir`).

    Attributes:
        adjusted: one :class:`Adjusted` per student and lesson.
        class_file: the class file used, None when there is none.
        class_path: where it was read from, None when there is none.
        submissions: student id -> :class:`Submission` (the intake's; empty without one).
    """

    adjusted: list[Adjusted]
    class_file: ClassFile | None
    class_path: Path | None
    submissions: dict[str, Submission]

    @property
    def lessons(self) -> list[str]:
        """The lesson columns' order: the class file's lessons first, then the others, sorted."""
        first = list(self.class_file.lessons) if self.class_file is not None else []
        return first + sorted({row.lesson for row in self.adjusted} - set(first))

    @property
    def names(self) -> dict[str, str]:
        """Student id -> name, for those the intake names."""
        return {student: s.name for student, s in self.submissions.items() if s.name}


def adjust_out_dir(out_dir: Path, class_path: Path | None = None,
                   known_lessons: Iterable[str] | None = None) -> Gradebook:
    """Apply a class file to a graded OUTDIR: its ``results.jsonl`` and ``intake/intake.json``.

    Args:
        out_dir: the ``--out`` folder of ``ros2course grade``.
        class_path: the class file; None: ``OUTDIR/class.yaml`` when it exists, else none
            (nothing is adjusted, every reason says so).
        known_lessons: the course's lesson ids (see :func:`load_class`).

    Raises:
        CourseError: ``out_dir`` or its results.jsonl is missing or holds no complete record; the
            class file is missing (when given) or bad (:func:`load_class`); an extension names a
            student without a result (:func:`check_students`).
    """
    from ros2course.report.gradebook import latest, read_results  # noqa: PLC0415 - start time: the gradebook only when a term's results are read

    out_dir = Path(out_dir)
    if not out_dir.is_dir():
        raise CourseError(f"no such folder: {out_dir}", "give the --out folder of `ros2course grade`")
    path = out_dir / "results.jsonl"
    if not path.is_file():
        raise CourseError(f"no results.jsonl in {out_dir}", "run `ros2course grade SUBMISSIONS --lesson L --out OUTDIR` first")
    results = list(latest(read_results(path)).values())
    if not results:
        raise CourseError(f"{path} holds no complete result", "grade the class again (--resume keeps finished ones)")
    if class_path is None and (out_dir / CLASS_FILE).is_file():
        class_path = out_dir / CLASS_FILE
    class_file = load_class(class_path, known_lessons) if class_path is not None else None
    if class_file is not None:
        check_students(class_file, results, class_path or CLASS_FILE)
    submissions = read_intake(out_dir)
    return Gradebook(adjust(results, submissions, class_file), class_file, class_path, submissions)
