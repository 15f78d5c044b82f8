"""A lesson's recorded steadiness: the last ``dev validate --repeat`` of its reference (issue 24).

Kept with the lesson, beside its mutation score (``mutation-score.json``,
:func:`ros2course.dev.mutants.write_score`): docs/grader-strength.md and the README's
lesson table show both (:func:`ros2course.dev.validate.lessons_markdown`).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from ros2course.files import atomic_write_text
from ros2course.dev.mutants import course_version
from ros2course.lesson.catalog import Lesson

#: The lesson's last repeat run of its reference, beside its ``mutation-score.json`` (:func:`write_steadiness`).
STEADINESS_FILE = "steadiness.json"


def write_steadiness(lesson: Lesson, row: Any) -> Path | None:
    """Record the reference's repeat run (a :class:`~ros2course.dev.repeat.Steadiness`) in
    ``chapters/<lesson>/steadiness.json``; its path, or None.

    What docs/grader-strength.md and the README's lesson table show as the reference's
    steadiness (issue 24). None when the lesson folder is read-only (an installed course).
    """
    from ros2course.grade.fingerprint import measurement  # noqa: PLC0415 - reads the course's files

    data = {**row.to_dict(), **measurement(lesson), "course_version": course_version()}
    data.pop("lesson", None)
    path = lesson.folder / STEADINESS_FILE
    try:
        atomic_write_text(path, json.dumps(data, indent=1) + "\n")
    except OSError:
        return None
    return path


def steadiness_text(lesson: Lesson) -> str:
    """The reference's last repeat run in a few words (a table cell): ``"steady, 20 runs (2 at once)"``,
    ``"UNSTEADY: listed (passed 13, failed 7)"`` or ``"not measured"``; ``"; stale (2026-11-25)"`` added
    when it was measured under another grader fingerprint (:mod:`ros2course.grade.fingerprint`)."""
    try:
        data = json.loads((lesson.folder / STEADINESS_FILE).read_text(encoding="utf-8"))
        runs, load, flakes = data["runs"], data["load"], data["flakes"]
    except (OSError, ValueError, KeyError, TypeError):
        return "not measured"
    from ros2course.grade.fingerprint import grader_fingerprint  # noqa: PLC0415 - reads the course's files

    stale = "" if data.get("fingerprint") == grader_fingerprint(lesson) else f"; stale ({data.get('date', '?')})"
    if data.get("ok"):
        return f"steady, {runs} runs ({load} at once){stale}"
    if flakes:
        changed = ", ".join(f"{f['check']} (passed {f['passed']}, failed {f['failed']})" for f in flakes)
        return f"UNSTEADY in {runs} runs ({load} at once): {changed}{stale}"
    return f"not full marks in {runs - data.get('judged_ok', 0)} of {runs} runs ({load} at once){stale}"
