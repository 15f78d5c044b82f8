"""``ros2course gradescope``: the batch grader for one submission inside a Gradescope autograder.

Gradescope copies the student's upload to ``/autograder/submission`` and
reads ``/autograder/results/results.json`` (its autograder specification:
``score``, ``output``, ``tests[name, score, max_score, output, visibility]``).
The grading is the same :func:`course.batch.run_job` as ``ros2course grade``
(scratch copy, worker subprocess, namespaces where the container allows them,
timeout), so a submission gets the same verdict on Gradescope as in a batch.

The lesson(s) come from ``--lesson``, else ``$ROS2COURSE_LESSON`` (ids
separated by commas or spaces), else the file ``gradescope/lesson`` of the
course (one id per line), written by the instructor before zipping the
autograder (see ``gradescope/setup.sh``).
"""

from __future__ import annotations

import json
import os
import tempfile
import uuid
from pathlib import Path

from course import gradebook
from course.progress import atomic_write_text
from course.batch import Job, default_hidden, lesson_checks, run_job
from course.batch_archive import ARCHIVE_SUFFIXES
from course.errors import CourseError


def configured_lessons(explicit: list[str]) -> list[str]:
    """The lessons to grade: ``explicit``, else ``$ROS2COURSE_LESSON``, else ``gradescope/lesson``.

    Raises:
        CourseError: none configured.
    """
    from course.lesson import content_root  # noqa: PLC0415

    if explicit:
        return explicit
    env = os.environ.get("ROS2COURSE_LESSON", "").replace(",", " ").split()
    if env:
        return env
    config = content_root() / "gradescope" / "lesson"
    if config.is_file():
        ids = [line.split("#")[0].strip() for line in config.read_text(encoding="utf-8").splitlines()]
        ids = [i for i in ids if i]
        if ids:
            return ids
    raise CourseError("no lesson to grade", f"pass --lesson, set ROS2COURSE_LESSON or write the lesson id into {config}")


def submission_entry(folder: Path) -> Path:
    """The entry to grade in Gradescope's submission folder: the one archive uploaded, or the folder itself.

    Raises:
        CourseError: ``folder`` does not exist.
    """
    if not folder.is_dir():
        raise CourseError(f"no submission folder {folder}", "run inside the Gradescope container or pass --submission")
    entries = [p for p in folder.iterdir() if not p.name.startswith(".")]
    if len(entries) == 1 and entries[0].is_file() and entries[0].name.lower().endswith(ARCHIVE_SUFFIXES):
        return entries[0]
    return folder


def run_gradescope(lessons: list[str], submission: Path, results: Path, timeout: float = 600.0) -> float:
    """Grade ``submission`` for ``lessons`` and write Gradescope's ``results.json`` to ``results``.

    Args:
        lessons: lesson ids (empty: see :func:`configured_lessons`).
        submission: the upload folder (``/autograder/submission``).
        results: the results file (``/autograder/results/results.json``); logs go beside it under ``submission/logs``.
        timeout: wall-clock seconds for the whole grading.

    Returns:
        the total score.

    Raises:
        CourseError: no lesson configured, unknown lesson, missing submission folder.
    """
    from course.lesson import load_catalog  # noqa: PLC0415

    lessons = configured_lessons(lessons)
    catalog = load_catalog()
    for lesson_id in lessons:
        catalog.get(lesson_id)
        lesson_checks(lesson_id)
    entry = submission_entry(submission)
    results.parent.mkdir(parents=True, exist_ok=True)
    hide = default_hidden(Path(tempfile.gettempdir()) / "ros2course-none", results.parent,
                          Path(tempfile.gettempdir()) / "ros2course-none")
    job = Job(uuid.uuid4().hex, "submission", str(entry.absolute()), "", lessons, str(results.parent), timeout, hide=hide)
    outcome = run_job(job)
    data = gradebook.gradescope_json(outcome["records"])
    atomic_write_text(results, json.dumps(data, indent=2) + "\n")
    return float(data["score"])
