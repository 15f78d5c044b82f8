"""The worker process of a batch: grades one submission's workspace for one or more lessons.

Run by :mod:`ros2course.batch.runner` as ``python -m ros2course.batch.worker ...`` in its own
session (and, where the machine allows, its own network and mount namespace).
It limits its own resources first (``RLIMIT_AS``, ``RLIMIT_FSIZE``; inherited by
colcon and the learner's nodes), configures the submission's identity
(``--run-as``: every command that runs submission code goes through
:func:`ros2course.sandbox.command`, so the worker stays the only root process
in the job), then calls the same
:func:`ros2course.grade.engine.grade_lesson` as ``ros2course check`` for each lesson and
rewrites ``--results`` (a JSON list, temp file + ``os.replace``) after each one,
so a worker killed half-way still leaves the lessons it finished.

Runs ``grade_lesson`` from its main thread, so learner processes get their
parent-death signal (see :class:`ros2course.run.process.LearnerProcess`).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import sys
import time
import traceback
from pathlib import Path
from typing import Any

from ros2course.files import atomic_write_text
from ros2course.grade.checklist import StopWhen
from ros2course.grade.engine import grade_lesson
from ros2course.grade.results import LessonResult, Status
from ros2course.lesson.catalog import load_catalog
from ros2course.ros import env as env_mod
from ros2course import sandbox


def _limit(kind: int, value: int) -> None:
    if value <= 0:
        return
    _soft, hard = resource.getrlimit(kind)
    new_hard = value if hard == resource.RLIM_INFINITY else min(hard, value)
    resource.setrlimit(kind, (min(value, new_hard), new_hard))


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns 0 when every lesson produced a result (whatever its score)."""
    parser = argparse.ArgumentParser(prog="python -m ros2course.batch.worker")
    parser.add_argument("--lesson", action="append", required=True)
    parser.add_argument("--workspace", required=True, type=Path)
    parser.add_argument("--results", required=True, type=Path)
    parser.add_argument("--logs", required=True, type=Path)
    parser.add_argument("--memory-limit", type=int, default=0, help="bytes of address space per process (0: none)")
    parser.add_argument("--file-limit", type=int, default=0, help="bytes per written file (0: none)")
    parser.add_argument("--run-as", default="", help="UID:GID the submission's code runs as (ros2course.sandbox)")
    parser.add_argument("--nproc", type=int, default=0, help="RLIMIT_NPROC of that uid (tasks at once)")
    parser.add_argument("--pids-cgroup", default="", help="cgroup.procs file of the job's pids cgroup")
    parser.add_argument("--trusted-interfaces", type=Path, default=None,
                        help="built workspace of the course's interface packages, imported instead of the submission's")
    parser.add_argument("--build-also", action="append", default=[], metavar="LESSON=PKG,PKG",
                        help="reference packages the lesson's packages depend on, built too when the workspace has "
                             "them (read by the batch: solutions/ is hidden here)")
    parser.add_argument("--until-judged", action="append", default=[], metavar="CHECK",
                        help="author's tools only (StopWhen): stop each lesson's grading once these checks are "
                             "judged (the rest 'not checked'); never given for a class")
    parser.add_argument("--until-first-loss", action="store_true",
                        help="author's tools only (StopWhen): stop each lesson's grading at its first lost point")
    args = parser.parse_args(argv)
    stop_when = StopWhen(frozenset(args.until_judged), args.until_first_loss) or None
    build_also = {lesson: [p for p in packages.split(",") if p]
                  for lesson, _, packages in (item.partition("=") for item in args.build_also)}

    _limit(resource.RLIMIT_AS, args.memory_limit)
    _limit(resource.RLIMIT_FSIZE, args.file_limit)

    env_mod.activate_process()
    if args.run_as:
        uid, _, gid = args.run_as.partition(":")
        sandbox.configure(sandbox.SubmissionIdentity(int(uid), int(gid or uid), args.nproc or 256, args.pids_cgroup))
    catalog = load_catalog()
    done: list[dict[str, Any]] = []
    atomic_write_text(args.results, json.dumps(done, indent=1))

    for lesson_id in args.lesson:
        log_dir = args.logs / lesson_id
        log_dir.mkdir(parents=True, exist_ok=True)
        begin = time.monotonic()
        try:
            lesson = catalog.get(lesson_id)
            result = grade_lesson(lesson, args.workspace, log_dir=log_dir,
                                  trusted_interfaces=args.trusted_interfaces, build_also=build_also.get(lesson_id),
                                  hand_in=True, stop_when=stop_when)
        except Exception as exc:  # noqa: BLE001 - any failure is this lesson's "grader error" row
            (log_dir / "grader-error.txt").write_text(traceback.format_exc(), encoding="utf-8")
            result = LessonResult.unfinished(lesson_id, Status.GRADER_ERROR,
                                             f"the grader failed: {type(exc).__name__}: {exc}",
                                             "a fault of the course or the grading machine, not of the submission",
                                             log_dir=str(log_dir))
        result.seconds = time.monotonic() - begin
        done.append(result.to_record())
        atomic_write_text(args.results, json.dumps(done, indent=1))
    sys.stdout.flush()
    return 0


if __name__ == "__main__":
    code = main()
    sys.stdout.flush()
    sys.stderr.flush()
    # rclpy / Fast DDS teardown at interpreter exit is slow and not needed (see ros2course.cli.main)
    os._exit(code)
