"""The whole course as one learner walks it, in one workspace, with the correct files' times kept (issue 36).

    python benchmarks/course_walk.py [--times past|future|fresh] [--offset SECONDS] [--json] [LESSON ...]

For each lesson in ``ros2course list`` order, in one workspace that keeps its build/, install/
and log/ from lesson to lesson, as a learner's does:

1. ``next``: the lesson's starter files are copied in (files the learner has are kept);
2. ``check`` on the starter (it must not get full marks);
3. the lesson's correct files (its reference solution) are put over the learner's, nothing
   deleted, keeping the times they carry, as ``unzip``, ``tar x``, ``cp -a`` or ``rsync -a`` do:
   dated ``--offset`` seconds in the past (``--times past``, the default), in the future
   (``future``: a clock skew), or written now (``fresh``: typed or pasted); then the lesson's
   reference commands run in the workspace, as the learner runs them;
4. ``check`` again: it must get full marks, whatever the files' times.

Prints one row per lesson (starter score, correct score, what the build check said) and exits 1
when a correct lesson is not given full marks. A script, not a test: the whole course takes
15 to 30 minutes on 2 cores; tests/test_source_drift.py walks three lessons of it.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

from rich.console import Console
from rich.table import Table

from ros2course.errors import MissingRequirement
from ros2course.grade.engine import grade_lesson
from ros2course.grade.results import Status
from ros2course.dev.validate import reference_workspace, run_commands
from ros2course.lesson.catalog import load_catalog
from ros2course.lesson.starter import copy_starter
from ros2course.ros import env as env_mod

#: colcon's output folders: a learner's copy of the correct files never brings them.
BUILT = ("build", "install", "log")


def put_correct_files(lesson, workspace: Path, staging: Path, times: str, offset: float) -> None:
    """Copy the lesson's reference files over ``workspace`` (nothing deleted), dated as ``times`` says."""
    shutil.rmtree(staging, ignore_errors=True)
    reference_workspace(lesson, staging)
    when = time.time() + (-offset if times == "past" else offset)
    for path in staging.rglob("*"):
        if times != "fresh" and not path.is_symlink():
            os.utime(path, (when, when))
    for entry in staging.iterdir():
        if entry.name in BUILT:
            continue
        target = workspace / entry.name
        if entry.is_dir():
            shutil.copytree(entry, target, dirs_exist_ok=True, symlinks=True,
                            copy_function=shutil.copy if times == "fresh" else shutil.copy2)
        elif times == "fresh":
            shutil.copy(entry, target)
        else:
            shutil.copy2(entry, target)


def walk(lesson_ids: list[str], times: str, offset: float, console: Console) -> list[dict]:
    """Walk ``lesson_ids`` (all lessons when empty) in one workspace; one row per lesson."""
    catalog = load_catalog()
    lessons = [catalog.get(i) for i in lesson_ids] if lesson_ids else list(catalog.lessons)
    root = Path(tempfile.mkdtemp(prefix="ros2course-walk-"))
    workspace = root / "ws"
    (workspace / "src").mkdir(parents=True)
    rows = []
    try:
        for lesson in lessons:
            console.print(f"{lesson.id}: starter ...")
            copy_starter(lesson, workspace)
            begin = time.monotonic()
            try:
                starter = grade_lesson(lesson, workspace)
            except MissingRequirement as exc:  # this machine cannot grade it: said, never counted as a pass
                console.print(f"{lesson.id}: {exc.message}")
                rows.append({"lesson": lesson.id, "starter": "-", "starter_passed": False, "correct": "-",
                             "full_marks": False, "status": "machine lacks a requirement", "message": exc.message,
                             "rebuilt_from_clean": False, "lost": [], "seconds": 0.0, "missing": True})
                put_correct_files(lesson, workspace, root / "staging", times, offset)
                continue
            console.print(f"{lesson.id}: correct files ({times}) ...")
            put_correct_files(lesson, workspace, root / "staging", times, offset)
            run_commands(workspace, lesson.reference.commands)
            correct = grade_lesson(lesson, workspace)
            build = next((c.observed for c in correct.checks if c.id == "build"), "")
            lost = [f"{c.id}: {c.observed[:120]}" for c in correct.checks if not c.passed]
            rows.append({"lesson": lesson.id, "starter": f"{starter.score:g}/{starter.max_score:g}",
                         "starter_passed": starter.status == Status.PASSED,
                         "correct": f"{correct.score:g}/{correct.max_score:g}",
                         "full_marks": correct.status == Status.PASSED, "status": str(correct.status),
                         "message": correct.message[:200], "rebuilt_from_clean": "rebuilt from clean" in build,
                         "lost": lost, "seconds": round(time.monotonic() - begin, 1)})
    finally:
        shutil.rmtree(root, ignore_errors=True)
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("lessons", nargs="*", help="lesson ids (default: the whole course, in order)")
    parser.add_argument("--times", choices=("past", "future", "fresh"), default="past",
                        help="the correct files' modification times (default: past, as unzip or cp -a keep them)")
    parser.add_argument("--offset", type=float, default=24 * 3600, help="seconds from now (default: a day)")
    parser.add_argument("--json", action="store_true", help="print the rows as JSON on stdout")
    args = parser.parse_args(argv)
    env_mod.activate_process()
    console = Console(file=sys.stderr, highlight=False, quiet=args.json)
    rows = walk(args.lessons, args.times, args.offset, console)
    full = sum(row["full_marks"] for row in rows)
    missing = sum(bool(row.get("missing")) for row in rows)
    if args.json:
        sys.stdout.write(json.dumps({"times": args.times, "offset": args.offset, "full_marks": full,
                                     "lessons": len(rows), "machine_lacks": missing, "rows": rows}, indent=1) + "\n")
    else:
        table = Table(title=f"the course walked in one workspace, correct files' times: {args.times}",
                      title_justify="left")
        for column in ("lesson", "starter", "correct", "rebuilt from clean", "s", "lost"):
            table.add_column(column)
        for row in rows:
            table.add_row(row["lesson"], row["starter"], row["correct"], "yes" if row["rebuilt_from_clean"] else "",
                          f"{row['seconds']:.0f}", "; ".join(row["lost"])[:160] or row["message"][:160],
                          style=None if row["full_marks"] else "red")
        Console(highlight=False).print(table)
        Console(highlight=False).print(f"{full} of {len(rows)} correct lessons got full marks"
                                       + (f" ({missing} not gradable on this machine)" if missing else ""))
    return 0 if full == len(rows) else 1


if __name__ == "__main__":
    sys.exit(main())
