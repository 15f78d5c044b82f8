"""``ros2course gradescope``: the batch grader for one submission inside a Gradescope autograder.

Gradescope copies the student's upload to ``/autograder/submission`` and
reads ``/autograder/results/results.json`` (its autograder specification:
``score``, ``output``, ``tests[name, score, max_score, output, visibility]``).
The grading is the same :func:`ros2course.batch.job.run_job` as ``ros2course grade``
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

from ros2course.batch.archive import ARCHIVE_SUFFIXES
from ros2course.batch.job import Job, lesson_checks, run_job
from ros2course.batch.runner import (
    build_trusted_interfaces,
    needs_reference_sources,
    refuse_without_isolation,
    submission_walls,
)
from ros2course.errors import CourseError
from ros2course.files import atomic_write_text
from ros2course.lesson.catalog import content_root, load_catalog
from ros2course.report import gradebook
from ros2course import sandbox


def configured_lessons(explicit: list[str]) -> list[str]:
    """The lessons to grade: ``explicit``, else ``$ROS2COURSE_LESSON``, else ``gradescope/lesson``.

    Raises:
        CourseError: none configured.
    """
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


def run_gradescope(lessons: list[str], submission: Path, results: Path, timeout: float = 600.0,
                   pids_limit: int = sandbox.DEFAULT_PIDS_LIMIT, require_isolation: bool = False) -> float:
    """Grade ``submission`` for ``lessons`` and write Gradescope's ``results.json`` to ``results``.

    Args:
        lessons: lesson ids (empty: see :func:`configured_lessons`).
        submission: the upload folder (``/autograder/submission``).
        results: the results file (``/autograder/results/results.json``); logs go beside it under ``submission/logs``.
        timeout: wall-clock seconds for the whole grading.
        pids_limit: tasks (processes + threads) the submission may have at once.
        require_isolation: refuse unless every protection of :mod:`ros2course.sandbox` is in effect.

    Returns:
        the total score.

    Raises:
        CourseError: no lesson configured, unknown lesson, missing submission folder,
            or ``require_isolation`` and a protection is missing.
    """
    lessons = configured_lessons(lessons)
    if require_isolation:
        refuse_without_isolation()
    catalog = load_catalog()
    for lesson_id in lessons:
        catalog.get(lesson_id)
        lesson_checks(lesson_id)
    entry = submission_entry(submission)
    results.parent.mkdir(parents=True, exist_ok=True)
    walls = submission_walls(catalog.course, Path(tempfile.gettempdir()) / "ros2course-none", results.parent,
                             Path(tempfile.gettempdir()) / "ros2course-none")
    trusted = (build_trusted_interfaces([catalog.get(lesson_id) for lesson_id in lessons])
               if sandbox.capabilities().uid_drop or needs_reference_sources(lessons) else None)
    job = Job(uuid.uuid4().hex, "submission", str(entry.absolute()), "", lessons, str(results.parent), timeout,
              hide=walls.hide, masked=walls.masked, pids_limit=pids_limit, trusted_interfaces=str(trusted.path if trusted else ""), require_isolation=require_isolation,
              course=str(catalog.course.root))
    try:
        outcome = run_job(job)
    finally:
        if trusted is not None:
            trusted.discard()
    data = gradebook.gradescope_json(outcome.records)
    atomic_write_text(results, json.dumps(data, indent=2) + "\n")
    return float(data["score"])
