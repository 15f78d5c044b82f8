"""One result model for every consumer: ``check``, ``dev validate``, batch grading, Gradescope, JUnit.

A :class:`LessonResult` is what grading one submission for one lesson
produced. It renders itself to each output format, so the formats cannot
drift apart:

* :meth:`LessonResult.to_json`: the documented ``check --json`` object
  (``lesson, score, max_score, status, checks[id, name, points, max_points,
  passed, observed, expected, hint]``, plus ``message`` when not graded; a failed check
  that watched the graph may add ``diagnosis: [{kind, message, detail}]``, see
  :mod:`ros2course.run.diagnose`);
* :meth:`LessonResult.to_record` / :meth:`LessonResult.from_record`: one line of
  a batch's ``results.jsonl`` (the JSON object plus ``hint``, ``timings``,
  ``build``, ``log_dir`` and, in a batch, ``student``, ``isolation``,
  ``peak_rss``, ``seconds``);
* :meth:`LessonResult.gradebook_cells`, :meth:`LessonResult.gradescope_tests`,
  :meth:`LessonResult.junit_suite`: a gradebook row, Gradescope's test
  entries, a JUnit ``<testsuite>``.

The rich rendering for people lives in :mod:`ros2course.report.table`.
"""

from __future__ import annotations

import dataclasses
import enum
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from typing import Any, Literal

from ros2course.run.diagnose import Diagnosis


class Status(str, enum.Enum):
    """How grading one lesson ended (``check --json``'s ``status``; ``check``'s exit code follows it)."""

    PASSED = "passed"  #: full marks
    FAILED = "failed"  #: graded, some points lost
    NOT_GRADABLE = "not gradable"  #: the submission could not be graded (no package, build failed, timed out)
    GRADER_ERROR = "grader error"  #: the course or the grading machine failed, not the learner

    def __str__(self) -> str:
        return self.value

    @property
    def graded(self) -> bool:
        """True when the checks were judged (passed or failed)."""
        return self in (Status.PASSED, Status.FAILED)

    @property
    def gradebook(self) -> str:
        """The gradebook's word: ``graded`` for passed/failed, else the status itself."""
        return GRADED if self.graded else self.value


#: Gradebook status of a submission whose checks were judged (passed or failed).
GRADED = "graded"


#: How the engine's "not checked" verdicts begin (a check whose need failed, or whose part stopped).
NOT_CHECKED = "not checked: "

#: Who sees a check's verdict (issue 39): ``visible`` (the default: ``check`` shows it), ``after_due`` (graded when
#: the work is handed in, shown to the learner once the deadline has passed) or ``hidden`` (graded at hand-in, never
#: shown). Declared on the grader's :class:`~ros2course.grade.checklist.Check`, overridden per class by ``class.yaml``'s
#: ``visibility:`` (:func:`with_visibility`).
Visibility = Literal["visible", "hidden", "after_due"]
VISIBILITIES: tuple[str, ...] = ("visible", "hidden", "after_due")
#: Gradescope's ``visibility`` of a test for each of ours (Gradescope's autograder specification).
GRADESCOPE_VISIBILITY = {"visible": "visible", "after_due": "after_due_date", "hidden": "hidden"}


def _visibility(value: object) -> Visibility:
    """A results file's ``visibility`` (absent: ``visible``); a value it should not hold is ``hidden``, never shown."""
    if value is None or value == "":
        return "visible"
    return value if value in VISIBILITIES else "hidden"  # type: ignore[return-value]


@dataclasses.dataclass
class CheckResult:
    """The verdict on one check (the JSON shape of ``check --json``'s ``checks``)."""

    id: str
    name: str
    points: float
    max_points: float
    passed: bool
    observed: str
    expected: str
    hint: str
    #: not judged because a check it needs failed (not part of the JSON shape).
    skipped: bool = False
    #: where to see what a failed check judged: ``{"recording": path of the check's MCAP file,
    #: "start_ns", "end_ns": the wall-clock window (ns since the epoch)}``; None when the check
    #: observed no ROS graph. In the JSON of failed checks only (``ros2course evidence`` reads it).
    evidence: dict[str, Any] | None = None
    #: what the graph showed when a check that watched it failed (:class:`~ros2course.run.diagnose.Diagnosis`,
    #: made by the engine, never by a grader); in the JSON of failed checks only, when not empty.
    diagnosis: list[Diagnosis] = dataclasses.field(default_factory=list)
    #: who sees the verdict (:data:`Visibility`); in the JSON only when not ``visible``.
    visibility: Visibility = "visible"

    def to_dict(self) -> dict[str, Any]:
        """The documented JSON fields (plus ``evidence`` and ``diagnosis`` on a failed check that has them, and
        ``visibility`` when it is not ``visible``)."""
        out = dataclasses.asdict(self)
        out.pop("skipped")
        if self.visibility == "visible":
            out.pop("visibility")
        if self.passed or self.skipped or not self.evidence:
            out.pop("evidence")
        if self.passed or self.skipped or not self.diagnosis:
            out.pop("diagnosis")
        else:
            out["diagnosis"] = [d.to_dict() for d in self.diagnosis]
        return out

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> CheckResult:
        """The inverse of :meth:`to_dict` (unknown keys ignored)."""
        evidence = data.get("evidence")
        diagnosis = data.get("diagnosis")
        observed = str(data.get("observed", ""))
        return cls(str(data.get("id", "")), str(data.get("name", "")), float(data.get("points", 0.0)),
                   float(data.get("max_points", 0.0)), bool(data.get("passed")), observed,
                   str(data.get("expected", "")), str(data.get("hint", "")),
                   # the JSON has no "skipped": the engine's "not checked" verdicts say it in their text
                   skipped=not data.get("passed") and observed.startswith(NOT_CHECKED),
                   evidence=dict(evidence) if isinstance(evidence, dict) else None,
                   diagnosis=[Diagnosis.from_dict(d) for d in diagnosis if isinstance(d, dict)]
                   if isinstance(diagnosis, list) else [],
                   visibility=_visibility(data.get("visibility")))

    def output_text(self) -> str:
        """``observed: ...`` / ``expected: ...`` / ``hint: ...`` / ``why: ...`` (Gradescope output, JUnit failure text).

        One ``why:`` line per :attr:`diagnosis` finding of a failed check.
        """
        lines = [f"observed: {self.observed}", f"expected: {self.expected}"]
        if self.hint and not self.passed:
            lines.append(f"hint: {self.hint}")
        if not self.passed:
            lines += [f"why: {d.message}" for d in self.diagnosis]
        return "\n".join(lines)


@dataclasses.dataclass
class Plot:
    """Time series a grader observed, shown under the table of checks (e.g. joint positions).

    Attributes:
        title: what is plotted, e.g. ``"joints of /myrobot_1 over the graded window"``.
        times: seconds from the start of the window, one per sample.
        series: label -> values (same length as ``times``), e.g. ``{"joint 1": [...], ...}``.
        unit: unit of the values, e.g. ``"deg"``.
    """

    title: str
    times: list[float]
    series: dict[str, list[float]]
    unit: str = ""

    def to_dict(self) -> dict[str, Any]:
        return {"title": self.title, "times": self.times, "series": self.series, "unit": self.unit}


@dataclasses.dataclass
class LessonResult:
    """Everything known about one submission for one lesson.

    Attributes:
        status: see :class:`Status`.
        message: for not gradable / grader error, what happened (e.g. the build log excerpt).
        hint: for not gradable / grader error, what to do about it.
        timings: seconds spent per phase (``build``, ``grade``, ``teardown``, ``total``...).
        build: how the build went (``ok``, ``cached``, ``seconds``, ``log``, ``repairs``: one sentence per
            stale install state repaired, see :func:`ros2course.builder.colcon.stale_install`).
        log_dir: where the build and node logs of this check are.
        plots: time series the grader observed (:class:`Plot`), for people; not serialised.
        student: the student id (batch grading; "" for ``check``).
        isolation: the protections the submission ran under (batch; see :mod:`ros2course.sandbox`).
        peak_rss: peak memory of the grading job, bytes (batch).
        seconds: wall time of this lesson in the worker, seconds (batch; None when unknown).
        withheld: checks left out of what the learner is shown (:meth:`for_learner`): graded when the work
            is handed in; 0 in every whole result.
    """

    lesson: str
    score: float
    max_score: float
    status: Status
    checks: list[CheckResult]
    message: str = ""
    hint: str = ""
    timings: dict[str, float] = dataclasses.field(default_factory=dict)
    build: dict[str, Any] = dataclasses.field(default_factory=dict)
    log_dir: str = ""
    plots: list[Plot] = dataclasses.field(default_factory=list)
    student: str = ""
    isolation: dict[str, Any] = dataclasses.field(default_factory=dict)
    peak_rss: int = 0
    seconds: float | None = None
    withheld: int = 0

    def __post_init__(self) -> None:
        self.status = Status(self.status)

    def for_learner(self) -> LessonResult:
        """What ``ros2course check`` shows the learner: the ``visible`` checks only, scored over them, with
        :attr:`withheld` counting the others (graded when the work is handed in, issue 39); ``self`` when
        every check is visible. The status follows the visible checks (a learner who passed every check
        they can see has passed what ``check`` judges; ``next`` moves on)."""
        shown = [c for c in self.checks if c.visibility == "visible"]
        if len(shown) == len(self.checks):
            return self
        score = round(sum(c.points for c in shown), 3)
        maximum = round(sum(c.max_points for c in shown), 3)
        status = self.status
        if status.graded:
            status = Status.PASSED if score >= maximum else Status.FAILED
        return dataclasses.replace(self, checks=shown, score=score, max_score=maximum, status=status,
                                   withheld=len(self.checks) - len(shown))

    def with_visibility(self, overrides: Mapping[str, Visibility]) -> LessonResult:
        """This result with the visibility of the checks ``overrides`` names (check id -> :data:`Visibility`,
        a class file's ``visibility:`` for this lesson) replaced; ids it does not grade are ignored."""
        if not overrides:
            return self
        return dataclasses.replace(self, checks=[dataclasses.replace(c, visibility=overrides.get(c.id, c.visibility))
                                                 for c in self.checks])

    @classmethod
    def unfinished(cls, lesson: str, status: Status, message: str, hint: str = "", max_score: float = 0.0,
                   log_dir: str = "") -> LessonResult:
        """A result without checks: the lesson could not be graded (or the grader failed)."""
        return cls(lesson, 0.0, max_score, status, [], message, hint, log_dir=log_dir)

    # --- serialisations ---------------------------------------------------------------------

    def to_json(self) -> dict[str, Any]:
        """The documented ``check --json`` object (plus ``message`` when not graded)."""
        out: dict[str, Any] = {
            "lesson": self.lesson, "score": self.score, "max_score": self.max_score, "status": self.status.value,
            "checks": [c.to_dict() for c in self.checks],
        }
        if self.message:
            out["message"] = self.message
        if self.withheld:
            out["withheld"] = self.withheld
        return out

    def to_record(self) -> dict[str, Any]:
        """One line of ``results.jsonl``: :meth:`to_json` plus the context of the run."""
        out = self.to_json()
        out.update({"hint": self.hint, "timings": {k: round(v, 3) for k, v in self.timings.items()},
                    "build": self.build, "log_dir": self.log_dir})
        if self.student:
            out.update({"student": self.student, "isolation": self.isolation, "peak_rss": self.peak_rss})
        if self.seconds is not None:
            out["seconds"] = round(self.seconds, 3)
        return out

    @classmethod
    def from_record(cls, data: dict[str, Any]) -> LessonResult:
        """The inverse of :meth:`to_record` (also reads a bare :meth:`to_json` object).

        Raises:
            ValueError: ``data`` lacks ``lesson`` or has an unknown status.
        """
        if "lesson" not in data:
            raise ValueError("a result needs a lesson")
        seconds = data.get("seconds")
        return cls(str(data["lesson"]), float(data.get("score", 0.0)), float(data.get("max_score", 0.0)),
                   Status(data.get("status", Status.GRADER_ERROR.value)),
                   [CheckResult.from_dict(c) for c in data.get("checks", []) if isinstance(c, dict)],
                   str(data.get("message", "")), str(data.get("hint", "")), dict(data.get("timings", {})),
                   dict(data.get("build", {})), str(data.get("log_dir", "")), [], str(data.get("student", "")),
                   dict(data.get("isolation", {})), int(data.get("peak_rss", 0) or 0),
                   None if seconds is None else float(seconds))

    def failed_checks(self) -> list[str]:
        """Ids of the checks that did not get full points."""
        return [c.id for c in self.checks if not c.passed]

    def first_fix(self) -> CheckResult | None:
        """The one failed check to fix first, or None when fewer than two checks failed.

        The earliest judged failure whose diagnosis names a cause (a near name, a type, a
        QoS pair: :mod:`ros2course.run.diagnose`), else the earliest judged failure; a
        check "not checked" because another failed is never first. Feedback leads with it
        and keeps the whole table (exercism's analyzers rank comments essential first;
        issue 19).
        """
        failed = [c for c in self.checks if not c.passed and not c.skipped]
        if len(failed) < 2:
            return None
        return next((c for c in failed if c.diagnosis), failed[0])

    # --- gradebooks -----------------------------------------------------------------------

    def gradebook_cells(self, columns: list[tuple[str, str]]) -> list[str]:
        """``student, lesson, score, max_score, status, reason`` and one cell per ``(lesson, check)`` column.

        A check cell holds its points, empty when this result has no such check
        (another lesson's column, or not gradable).
        """
        points = {c.id: c.points for c in self.checks}
        reason = self.message.splitlines()[0] if not self.status.graded and self.message else ""
        cells = [f"{points[check]:g}" if lesson == self.lesson and check in points else ""
                 for lesson, check in columns]
        return [self.student, self.lesson, f"{self.score:g}", f"{self.max_score:g}", self.status.gradebook,
                reason, *cells]

    def gradescope_tests(self, prefix: bool) -> list[dict[str, Any]]:
        """Gradescope ``tests`` entries: one per check, or one 0-point entry saying why it was not graded.

        Args:
            prefix: name each test ``<lesson>: <check name>`` (several lessons in one results.json).
        """
        if not self.status.graded and not self.checks:
            return [{"name": f"{self.lesson}: {self.status.value}", "score": 0.0, "max_score": self.max_score,
                     "output": self.message, "visibility": "visible", "status": "failed"}]
        return [{"name": f"{self.lesson}: {c.name}" if prefix else c.name, "score": c.points,
                 "max_score": c.max_points, "output": c.output_text(),
                 "visibility": GRADESCOPE_VISIBILITY.get(c.visibility, "hidden"),
                 "status": "passed" if c.passed else "failed"} for c in self.checks]

    def junit_suite(self, parent: ET.Element) -> dict[str, int]:
        """Append this result as a ``<testsuite>`` to ``parent``; returns its ``tests/failures/errors`` counts.

        A check the learner lost is a ``<failure>``; with status ``grader error``
        (the course or the machine failed) it is an ``<error>``. A result
        without checks is one test case named after its status.
        """
        name = f"{self.student}.{self.lesson}"
        suite = ET.SubElement(parent, "testsuite", name=name)
        counts = {"tests": 0, "failures": 0, "errors": 0}
        fault = self.status is Status.GRADER_ERROR
        kind = "error" if fault else "failure"
        total = float(self.timings.get("total", 0.0))
        if not self.checks:
            counts["tests"] += 1
            case = ET.SubElement(suite, "testcase", classname=name, name=self.status.value, time=f"{total:.3f}")
            node = ET.SubElement(case, kind, message=(self.message or self.status.value).splitlines()[0][:500])
            node.text = self.message
            counts["errors" if fault else "failures"] += 1
        for check in self.checks:
            counts["tests"] += 1
            case = ET.SubElement(suite, "testcase", classname=name, name=check.id, time="0")
            if check.passed:
                continue
            node = ET.SubElement(case, kind, message=check.observed[:500])
            node.text = check.output_text()
            counts["errors" if fault else "failures"] += 1
        for key, value in counts.items():
            suite.set(key, str(value))
        suite.set("time", f"{total:.3f}")
        return counts
