"""Gradebook exports of a batch: CSV, JSON lines, Gradescope JSON and JUnit XML.

Every writer here is crash-safe: ``results.jsonl`` gets one line per result,
written, flushed and fsync'd (a batch killed at any moment leaves at most a
truncated last line, which :func:`read_results` skips); every other file is
rewritten whole through a temporary file and ``os.replace``.

A *record* is one line of ``results.jsonl``: the ``check --json`` object of one
student and lesson (``lesson, score, max_score, status, checks[...]``,
``message``) plus ``student``, ``timings`` (seconds), ``isolation`` and
``log_dir``.

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

#: Gradebook status of a submission that was graded (passed or failed checks).
GRADED = "graded"
NOT_GRADABLE = "not gradable"
GRADER_ERROR = "grader error"


def gradebook_status(engine_status: str) -> str:
    """``passed`` / ``failed`` -> ``graded``; ``not gradable`` and ``grader error`` stay."""
    return engine_status if engine_status in (NOT_GRADABLE, GRADER_ERROR) else GRADED


def append_record(path: Path, record: dict[str, Any]) -> None:
    """Append ``record`` as one JSON line to ``path``, flushed and fsync'd.

    A previous run killed mid-line left a truncated last line: a newline is
    written first so the new record starts on a line of its own.
    """
    line = json.dumps(record, separators=(",", ":"), ensure_ascii=False) + "\n"
    with open(path, "ab+") as handle:
        if handle.tell() > 0:
            handle.seek(-1, os.SEEK_END)
            if handle.read(1) != b"\n":
                line = "\n" + line
        handle.write(line.encode("utf-8"))
        handle.flush()
        os.fsync(handle.fileno())


def read_results(path: Path) -> list[dict[str, Any]]:
    """Every complete record of a ``results.jsonl`` (missing file: none; broken lines are skipped)."""
    out: list[dict[str, Any]] = []
    with contextlib.suppress(FileNotFoundError):
        with open(path, encoding="utf-8", errors="replace") as handle:
            for line in handle:
                line = line.strip()
                if not line:
                    continue
                try:
                    record = json.loads(line)
                except ValueError:
                    continue
                if isinstance(record, dict) and "student" in record and "lesson" in record:
                    out.append(record)
    return out


def latest(records: Iterable[dict[str, Any]]) -> dict[tuple[str, str], dict[str, Any]]:
    """The last record per (student, lesson), in first-seen order."""
    out: dict[tuple[str, str], dict[str, Any]] = {}
    for record in records:
        out[(record["student"], record["lesson"])] = record
    return out


def gradebook_csv(records: Iterable[dict[str, Any]], check_columns: dict[str, list[str]]) -> str:
    """The gradebook: one row per student and lesson, sorted by student then lesson.

    Args:
        records: results (the last one per student and lesson counts).
        check_columns: lesson id -> its check ids, in grader order. With one
            lesson the check columns are the check ids; with several,
            ``<lesson>:<check>``.

    Columns: ``student, lesson, score, max_score, status, reason``, then one per check (its points, empty
    when the check has no result, e.g. not gradable).
    """
    multi = len(check_columns) > 1
    columns = [(lesson, check, f"{lesson}:{check}" if multi else check)
               for lesson, checks in check_columns.items() for check in checks]
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["student", "lesson", "score", "max_score", "status", "reason", *[c[2] for c in columns]])
    rows = sorted(latest(records).values(), key=lambda r: (r["student"], r["lesson"]))
    for record in rows:
        points = {c["id"]: c["points"] for c in record.get("checks", [])}
        status = gradebook_status(record["status"])
        reason = record.get("message", "").splitlines()[0] if status != GRADED and record.get("message") else ""
        cells = [f"{points[check]:g}" if lesson == record["lesson"] and check in points else ""
                 for lesson, check, _ in columns]
        writer.writerow([record["student"], record["lesson"], f"{record['score']:g}",
                         f"{record['max_score']:g}", status, reason, *cells])
    return buffer.getvalue()


def _check_output(check: dict[str, Any]) -> str:
    lines = [f"observed: {check.get('observed', '')}", f"expected: {check.get('expected', '')}"]
    if check.get("hint") and not check.get("passed"):
        lines.append(f"hint: {check['hint']}")
    return "\n".join(lines)


def gradescope_json(records: list[dict[str, Any]]) -> dict[str, Any]:
    """The Gradescope autograder ``results.json`` of one student (all their lessons).

    Fields: ``score`` (total points), ``output`` (one line per lesson),
    ``visibility``, ``stdout_visibility``, ``execution_time`` (seconds, int), and ``tests``:
    one per check with ``name, score, max_score, output, visibility, status``
    (``passed``/``failed``); a lesson that could not be graded is one test with 0 points
    whose output is the reason.
    """
    tests: list[dict[str, Any]] = []
    lines: list[str] = []
    seconds = 0.0
    multi = len(records) > 1
    for record in records:
        seconds += float(record.get("timings", {}).get("total", 0.0))
        lesson = record["lesson"]
        lines.append(f"{lesson}: {record['status']} {record['score']:g}/{record['max_score']:g}")
        if record.get("message"):
            lines.append(record["message"])
        if record["status"] in (NOT_GRADABLE, GRADER_ERROR) and not record.get("checks"):
            tests.append({"name": f"{lesson}: {record['status']}", "score": 0.0,
                          "max_score": record["max_score"], "output": record.get("message", ""),
                          "visibility": "visible", "status": "failed"})
            continue
        for check in record.get("checks", []):
            tests.append({"name": f"{lesson}: {check['name']}" if multi else check["name"],
                          "score": check["points"], "max_score": check["max_points"],
                          "output": _check_output(check), "visibility": "visible",
                          "status": "passed" if check.get("passed") else "failed"})
    return {"score": round(sum(r["score"] for r in records), 3), "output": "\n".join(lines),
            "visibility": "visible", "stdout_visibility": "hidden", "execution_time": int(seconds + 0.5),
            "tests": tests}


def junit_xml(records: Iterable[dict[str, Any]]) -> str:
    """JUnit XML: one ``<testsuite>`` per student and lesson, one ``<testcase>`` per check.

    A check the learner lost is a ``<failure>``; a check that could not be judged
    because the grader or the grading machine failed (status ``grader error``,
    e.g. a crashed worker) is an ``<error>``. A submission that is not gradable
    (its build failed, it timed out) is one ``<failure>`` test case.
    """
    root = ET.Element("testsuites", name="ros2course")
    rows = sorted(latest(records).values(), key=lambda r: (r["student"], r["lesson"]))
    totals = {"tests": 0, "failures": 0, "errors": 0}
    for record in rows:
        suite = ET.SubElement(root, "testsuite", name=f"{record['student']}.{record['lesson']}")
        counts = {"tests": 0, "failures": 0, "errors": 0}
        grader_error = record["status"] == GRADER_ERROR
        seconds = float(record.get("timings", {}).get("total", 0.0))
        cases = record.get("checks") or [None]
        for check in cases:
            counts["tests"] += 1
            if check is None:
                case = ET.SubElement(suite, "testcase", classname=f"{record['student']}.{record['lesson']}",
                                     name=record["status"], time=f"{seconds:.3f}")
                kind = "error" if grader_error else "failure"
                node = ET.SubElement(case, kind, message=(record.get("message") or record["status"]).splitlines()[0][:500])
                node.text = record.get("message", "")
                counts["errors" if grader_error else "failures"] += 1
                continue
            case = ET.SubElement(suite, "testcase", classname=f"{record['student']}.{record['lesson']}",
                                 name=check["id"], time="0")
            if check.get("passed"):
                continue
            kind = "error" if grader_error else "failure"
            node = ET.SubElement(case, kind, message=str(check.get("observed", ""))[:500])
            node.text = _check_output(check)
            counts["errors" if grader_error else "failures"] += 1
        for key, value in counts.items():
            suite.set(key, str(value))
            totals[key] += value
        suite.set("time", f"{seconds:.3f}")
    for key, value in totals.items():
        root.set(key, str(value))
    ET.indent(root)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"
