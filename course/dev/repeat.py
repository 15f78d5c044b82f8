"""``ros2course dev validate --repeat N --load K``: is every check of a grader steady?

A check that passes a right program nine times and fails it the tenth is a
grader defect (issue 24): the learner trusts the score. This module grades
each case of a lesson (:func:`ros2course.dev.validate.lesson_cases`) ``N``
times, ``K`` gradings at once (``K`` copies of the workspace, as ``K``
learners on one lab machine, or ``watch`` in one terminal and ``check`` in
another), and reports every check whose verdict changed between runs, with
the observed text of a run that passed it and of one that failed it.

Each grading runs in its own process (:func:`ros2course.dev.child.grade_in_child`), as
``ros2course check`` does: its own ROS domain, rclpy context and ``ros2``
daemon, so the runs share nothing but the machine. A steady grader is one
whose verdicts do not depend on what else runs; the fix for a flaky check is
to wait for what it observes the way ``ros2`` does, never a retry.
"""

from __future__ import annotations

import collections
import concurrent.futures
import dataclasses
import shutil
import tempfile
import time
from pathlib import Path
from typing import Any

from ros2course.dev import first_line
from ros2course.errors import CourseError
from ros2course.dev.child import grade_in_child
from ros2course.grade.results import LessonResult, Status
from ros2course.lesson.catalog import load_catalog


@dataclasses.dataclass
class Flake:
    """One check (or the status) whose verdict changed between runs of one case.

    Attributes:
        check: the check id, or ``status`` when the result's status itself changed.
        passed: runs in which it passed.
        failed: runs in which it failed.
        observed_pass: what one passing run observed.
        observed_fail: what one failing run observed.
    """

    check: str
    passed: int
    failed: int
    observed_pass: str
    observed_fail: str

    def describe(self) -> str:
        """``listed: passed 13, failed 7 (passed: "..."; failed: "...")``."""
        return (f"{self.check}: passed {self.passed}, failed {self.failed} "
                f"(passed: {self.observed_pass[:160]!r}; failed: {self.observed_fail[:160]!r})")


def unsteady(results: list[LessonResult]) -> list[Flake]:
    """The checks (and status) whose verdicts differ among ``results`` (runs of one case), by check order.

    A check that was "not checked" in a run (a check it needs failed) counts as that run's failure.
    """
    flakes: list[Flake] = []
    statuses = collections.Counter(str(r.status) for r in results)
    if len(statuses) > 1:
        passed = [r for r in results if r.status == Status.PASSED]
        other = [r for r in results if r.status != Status.PASSED]
        flakes.append(Flake("status", len(passed), len(other),
                            str(passed[0].status) if passed else str(results[0].status),
                            f"{other[0].status}: {first_line(other[0].message)}"
                            if other else ""))
    order: list[str] = []
    verdicts: dict[str, list[tuple[bool, str]]] = collections.defaultdict(list)
    for result in results:
        for check in result.checks:
            if check.id not in verdicts:
                order.append(check.id)
            verdicts[check.id].append((check.passed, check.observed))
    for check_id in order:
        seen = verdicts[check_id]
        good = [observed for ok, observed in seen if ok]
        bad = [observed for ok, observed in seen if not ok]
        if good and bad:
            flakes.append(Flake(check_id, len(good), len(bad), good[0], bad[0]))
    return flakes


@dataclasses.dataclass
class Steadiness:
    """The repeated runs of one case.

    Attributes:
        lesson: lesson id.
        case: ``reference``, ``starter`` or a fixture's name.
        runs: gradings that finished.
        load: gradings at once.
        flakes: what changed between runs (empty: steady).
        judged_ok: runs whose result the case's judge accepted (full marks for a reference, the named
            checks lost for a fixture).
        seconds: wall time of all runs of the case.
    """

    lesson: str
    case: str
    runs: int
    load: int
    flakes: list[Flake]
    judged_ok: int
    seconds: float

    @property
    def ok(self) -> bool:
        """Steady and accepted by the case's judge in every run."""
        return not self.flakes and self.judged_ok == self.runs

    def to_dict(self) -> dict[str, Any]:
        """JSON shape of ``dev validate --repeat --json``."""
        return {"lesson": self.lesson, "case": self.case, "ok": self.ok, "runs": self.runs, "load": self.load,
                "judged_ok": self.judged_ok, "seconds": round(self.seconds, 1),
                "flakes": [dataclasses.asdict(f) for f in self.flakes]}


def repeat_case(case, repeat: int, load: int, progress=None) -> Steadiness:
    """Grade one :class:`~ros2course.dev.validate.Case` ``repeat`` times, ``load`` at once.

    Args:
        case: from :func:`ros2course.dev.validate.lesson_cases`.
        repeat: gradings in all (>= 2 to say anything).
        load: gradings at once, each on its own copy of the workspace (the copies are built by their
            first grading, later ones find the build up to date, as a learner's second ``check`` does).
        progress: a rich Console for one line per finished grading, or None.
    """
    begin = time.monotonic()
    root = Path(tempfile.mkdtemp(prefix=f"ros2course-repeat-{case.lesson.id}-{case.name}-"))
    results: list[LessonResult] = []
    judged_ok = 0
    try:
        copies = []
        for index in range(min(load, repeat)):
            copy = root / f"ws{index}"
            copy.mkdir()
            case.prepare(copy)
            copies.append(copy)
        with concurrent.futures.ThreadPoolExecutor(max_workers=len(copies)) as pool:
            for first in range(0, repeat, len(copies)):
                batch = range(first, min(repeat, first + len(copies)))
                futures = [pool.submit(grade_in_child, case.lesson.id, copies[i - first], case.underlays,
                                       root / "logs" / f"run{i:03d}") for i in batch]
                for future in futures:
                    result = future.result()
                    results.append(result)
                    ok, _ = case.judge(result)
                    judged_ok += ok
                    if progress is not None:
                        failed = ", ".join(result.failed_checks()) or "none"
                        progress.print(f"  {case.lesson.id} {case.name} run {len(results)}/{repeat}: {result.status} "
                                       f"{result.score:g}/{result.max_score:g}; failed: {failed}")
    finally:
        shutil.rmtree(root, ignore_errors=True)
    return Steadiness(case.lesson.id, case.name, len(results), min(load, repeat), unsteady(results), judged_ok,
                      time.monotonic() - begin)


def repeat_lessons(lesson_ids: list[str] | None, repeat: int, load: int = 1, cases: list[str] | None = None,
                   progress=None) -> list[Steadiness]:
    """``dev validate --repeat``: every case of the lessons (or only ``cases``), ``repeat`` runs each, ``load`` at once.

    Raises:
        CourseError: ``repeat`` < 2 or ``load`` < 1, or a case name no lesson has.
        ValidationFailed: a lesson's dependencies do not build.
    """
    from ros2course.dev.validate import build_underlay, lesson_cases  # noqa: PLC0415 - validate imports the engine

    if repeat < 2:
        raise CourseError(f"--repeat needs at least 2 runs (got {repeat})", "e.g. --repeat 20 --load 2")
    if load < 1:
        raise CourseError(f"--load must be 1 or more (got {load})", "e.g. --load 2: two checks at once")
    catalog = load_catalog()
    lessons = [catalog.get(i) for i in lesson_ids] if lesson_ids else catalog.lessons
    out: list[Steadiness] = []
    for lesson in lessons:
        underlay = build_underlay(lesson)
        try:
            chosen = lesson_cases(lesson, underlay.path if underlay is not None else None)
            if cases:
                unknown = [name for name in cases if name not in {c.name for c in chosen}]
                if unknown and len(lessons) == 1:
                    raise CourseError(f"lesson {lesson.id} has no case {unknown[0]!r}",
                                      "cases: reference, starter or a fixture's name (tests/fixtures/<lesson>)")
                chosen = [c for c in chosen if c.name in cases]
            for case in chosen:
                if progress is not None:
                    progress.print(f"repeating {lesson.id} {case.name}: {repeat} runs, {load} at once ...")
                out.append(repeat_case(case, repeat, load, progress))
        finally:
            if underlay is not None:
                underlay.discard()
    return out


def render_steadiness(rows: list[Steadiness], console) -> None:
    """Table of every repeated case (steady or the checks that changed), then a one-line summary."""
    from rich.table import Table  # noqa: PLC0415 - rich only when printing

    table = Table(title="ros2course dev validate --repeat", title_justify="left")
    for column in ("lesson", "case", "runs", "", "what changed between runs"):
        table.add_column(column, overflow="fold")
    for row in rows:
        mark = "[green]steady[/]" if row.ok else "[red]UNSTEADY[/]" if row.flakes else "[red]WRONG[/]"
        detail = "; ".join(f.describe() for f in row.flakes) or (
            "nothing" if row.ok else f"the same verdict each time, but only {row.judged_ok} of {row.runs} "
            "runs were what the case expects")
        table.add_row(row.lesson, row.case, f"{row.runs} ({row.load} at once)", mark, detail)
    console.print(table)
    bad = [r for r in rows if not r.ok]
    console.print(f"{len(rows) - len(bad)} steady, {len(bad)} not")
