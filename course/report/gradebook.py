"""Gradebook exports of a batch: CSV, JSON lines, Gradescope JSON and JUnit XML.

Every writer here is crash-safe: ``results.jsonl`` gets one line per result,
written, flushed and fsync'd (a batch killed at any moment leaves at most a
truncated last line, which :func:`read_results` skips); every other file is
rewritten whole through a temporary file and ``os.replace``.

A *record* is one line of ``results.jsonl``: a :class:`~ros2course.grade.results.LessonResult`
of one student and lesson as :meth:`~ros2course.grade.results.LessonResult.to_record` writes it
(the ``check --json`` object plus ``student``, ``timings`` (seconds), ``isolation``,
``log_dir``...). Every format is rendered by the result itself; this module only
chooses, orders and writes.

JUnit XML is written with the standard library's ``xml.etree`` rather than the
``junit-xml`` package: that package has had no release since 2020, and the
format needs only four elements.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import os
import xml.etree.ElementTree as ET
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from ros2course.grade.results import LessonResult


def append_record(path: Path, result: LessonResult, graded_with: dict[str, str] | None = None) -> None:
    """Append ``result`` (:meth:`~ros2course.grade.results.LessonResult.to_record`) as one JSON line, flushed and fsync'd.

    ``graded_with``: what graded it (:mod:`ros2course.batch.provenance`: grader fingerprint, submission
    digest, time), kept under that key of the record. A previous run killed mid-line left a truncated
    last line: a newline is written first so the new record starts on a line of its own.
    """
    record = result.to_record()
    if graded_with:
        record["graded_with"] = graded_with
    line = json.dumps(record, separators=(",", ":"), ensure_ascii=False) + "\n"
    with open(path, "ab+") as handle:
        if handle.tell() > 0:
            handle.seek(-1, os.SEEK_END)
            if handle.read(1) != b"\n":
                line = "\n" + line
        handle.write(line.encode("utf-8"))
        handle.flush()
        os.fsync(handle.fileno())


def read_results(path: Path) -> list[LessonResult]:
    """Every complete record of a ``results.jsonl`` (missing file: none; broken lines are skipped)."""
    return read_results_counted(path)[0]


def read_results_counted(path: Path) -> tuple[list[LessonResult], int]:
    """``(records, lines skipped)`` of a ``results.jsonl``; a missing file has none.

    A line is skipped when it is not a JSON object with a ``student``, or when
    :meth:`~ros2course.grade.results.LessonResult.from_record` cannot read it: a
    truncated last line (a batch killed mid-write), or a row of another version
    (unknown status, a field of the wrong type).
    """
    out: list[LessonResult] = []
    skipped = 0
    with contextlib.suppress(FileNotFoundError):
        with open(path, encoding="utf-8", errors="replace") as handle:
            for line in handle:
                line = line.strip()
                if not line:
                    continue
                try:
                    record = json.loads(line)
                    if isinstance(record, dict) and "student" in record:
                        out.append(LessonResult.from_record(record))
                    else:
                        skipped += 1
                except (ValueError, TypeError, AttributeError, KeyError):
                    skipped += 1
    return out, skipped


def latest(results: Iterable[LessonResult]) -> dict[tuple[str, str], LessonResult]:
    """The last result per (student, lesson), in first-seen order."""
    out: dict[tuple[str, str], LessonResult] = {}
    for result in results:
        out[(result.student, result.lesson)] = result
    return out


def gradebook_csv(results: Iterable[LessonResult], check_columns: dict[str, list[str]]) -> str:
    """The gradebook: one row per student and lesson, sorted by student then lesson.

    Args:
        results: results (the last one per student and lesson counts).
        check_columns: lesson id -> its check ids, in grader order. With one
            lesson the check columns are the check ids; with several,
            ``<lesson>:<check>``.

    Columns: ``student, lesson, score, max_score, status, reason, total, total_max``, then one per
    check (its points, empty when the check has no result, e.g. not gradable). ``total`` and
    ``total_max`` are the student's points and maximum summed over all their lessons (the same on
    each of the student's rows).
    """
    multi = len(check_columns) > 1
    columns = [(lesson, check) for lesson, checks in check_columns.items() for check in checks]
    rows = sorted(latest(results).values(), key=lambda r: (r.student, r.lesson))
    totals: dict[str, list[float]] = {}
    for result in rows:
        total = totals.setdefault(result.student, [0.0, 0.0])
        total[0] += result.score
        total[1] += result.max_score
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["student", "lesson", "score", "max_score", "status", "reason", "total", "total_max",
                     *[f"{lesson}:{check}" if multi else check for lesson, check in columns]])
    for result in rows:
        cells = result.gradebook_cells(columns)
        score, maximum = totals[result.student]
        writer.writerow([*cells[:6], f"{round(score, 3):g}", f"{round(maximum, 3):g}", *cells[6:]])
    return buffer.getvalue()


def gradescope_json(results: list[LessonResult]) -> dict[str, Any]:
    """The Gradescope autograder ``results.json`` of one student (all their lessons).

    Fields: ``score`` (total points), ``output`` (one line per lesson),
    ``visibility``, ``stdout_visibility``, ``execution_time`` (seconds, int), and ``tests``:
    one per check with ``name, score, max_score, output, visibility, status``
    (``passed``/``failed``); a lesson that could not be graded is one test with 0 points
    whose output is the reason.
    """
    tests: list[dict[str, Any]] = []
    lines: list[str] = []
    for result in results:
        lines.append(f"{result.lesson}: {result.status.value} {result.score:g}/{result.max_score:g}")
        if result.message:
            lines.append(result.message)
        tests += result.gradescope_tests(prefix=len(results) > 1)
    seconds = sum(float(r.timings.get("total", 0.0)) for r in results)
    return {"score": round(sum(r.score for r in results), 3), "output": "\n".join(lines),
            "visibility": "visible", "stdout_visibility": "hidden", "execution_time": int(seconds + 0.5),
            "tests": tests}


def junit_xml(results: Iterable[LessonResult]) -> str:
    """JUnit XML: one ``<testsuite>`` per student and lesson (:meth:`~ros2course.grade.results.LessonResult.junit_suite`)."""
    root = ET.Element("testsuites", name="ros2course")
    totals = {"tests": 0, "failures": 0, "errors": 0}
    for result in sorted(latest(results).values(), key=lambda r: (r.student, r.lesson)):
        for key, value in result.junit_suite(root).items():
            totals[key] += value
    for key, value in totals.items():
        root.set(key, str(value))
    ET.indent(root)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def read_regrades(out_dir: Path) -> list[dict[str, Any]]:
    """Every object of ``OUTDIR/regrades.jsonl`` (what each regrade changed, written by
    :func:`ros2course.batch.provenance.append_changes`); none when missing, broken lines skipped."""
    out = []
    try:
        text = (out_dir / "regrades.jsonl").read_text(encoding="utf-8", errors="replace")
    except FileNotFoundError:
        return out
    for line in text.splitlines():
        try:
            data = json.loads(line)
        except ValueError:
            continue
        if isinstance(data, dict):
            out.append(data)
    return out
