"""Diagnosis on and off: the same verdicts, and what a diagnosis costs per failed check (issue 19).

For each lesson: every case ``dev validate`` grades (reference, starter, each
wrong solution in ``tests/fixtures/<lesson>``) is prepared once and graded
twice in the same workspace, with ``ROS2COURSE_DIAGNOSE=1`` and then ``=0``
(the second build is the first's, cached). The two results must agree on
status, score and the ids of the failed checks; the seconds each diagnosis
took (``GradingSession.diagnose_seconds``) are collected from the graded runs.
Whether each fixture still fails its named checks and carries its
``diagnosis:`` findings is reported too (the ``dev validate`` judgement). A
script, not a test::

    python benchmarks/diagnosis_parity.py [--json] [--skip-starter] [--off-first] LESSON [LESSON ...]

``--off-first`` grades with the diagnosis off first (the first grading after a build runs
on cold caches: swapping the order tells such a bias from an effect of the diagnosis).

Exit status 1 when any verdict differs between the two runs.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import shutil
import statistics
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from ros2course.grade import session as session_mod  # noqa: E402
from ros2course.grade.engine import grade_lesson  # noqa: E402
from ros2course.grade.observer import DIAGNOSE_ENV  # noqa: E402
from ros2course.grade.results import LessonResult  # noqa: E402
from ros2course.dev.validate import build_underlay, lesson_cases  # noqa: E402
from ros2course.lesson.catalog import load_catalog  # noqa: E402
from ros2course.ros import env as env_mod  # noqa: E402

#: issue 19: "Diagnosis adds at most 0.2 s to a check"
LIMIT = 0.2


@contextlib.contextmanager
def diagnosis_seconds() -> Iterator[list[float]]:
    """Collect ``GradingSession.diagnose_seconds`` of every session closed meanwhile (seconds per diagnosis).

    grade_lesson returns a LessonResult that keeps only their sum (``timings["diagnose"]``); the
    per-diagnosis figures live on the session, which only its ``close`` sees last. Wrapping ``close``
    here keeps a benchmark's bookkeeping out of the engine.
    """
    collected: list[float] = []
    original = session_mod.GradingSession.close

    def close(self: session_mod.GradingSession) -> None:
        try:
            original(self)
        finally:
            collected.extend(self.diagnose_seconds)

    session_mod.GradingSession.close = close  # type: ignore[method-assign]
    try:
        yield collected
    finally:
        session_mod.GradingSession.close = original  # type: ignore[method-assign]


def graded(lesson, root: Path, underlays: tuple[Path, ...], diagnose: bool) -> LessonResult:
    """``grade_lesson`` with the diagnosis on or off (``ROS2COURSE_DIAGNOSE``)."""
    previous = os.environ.get(DIAGNOSE_ENV)
    os.environ[DIAGNOSE_ENV] = "1" if diagnose else "0"
    try:
        return grade_lesson(lesson, root, underlays=underlays)
    finally:
        if previous is None:
            os.environ.pop(DIAGNOSE_ENV, None)
        else:
            os.environ[DIAGNOSE_ENV] = previous


def verdict(result: LessonResult) -> tuple[str, float, tuple[str, ...]]:
    """What must not depend on the diagnosis: status, score, failed check ids."""
    return str(result.status), result.score, tuple(result.failed_checks())


def compare_lesson(lesson, skip_starter: bool = False, off_first: bool = False, only: list[str] | None = None) -> dict:
    """Grade every case of ``lesson`` (or the ``only`` named ones) with the diagnosis on, then off;
    the differences and the costs."""
    underlay = build_underlay(lesson)
    rows = []
    try:
        for case in lesson_cases(lesson, underlay.path if underlay is not None else None):
            if (skip_starter and case.name == "starter") or (only and case.name not in only):
                continue
            root = Path(tempfile.mkdtemp(prefix=f"ros2course-parity-{lesson.id}-{case.name}-"))
            try:
                case.prepare(root)
                if off_first:
                    off = graded(lesson, root, case.underlays, False)
                with diagnosis_seconds() as seconds:
                    on = graded(lesson, root, case.underlays, True)
                if not off_first:
                    off = graded(lesson, root, case.underlays, False)
            finally:
                shutil.rmtree(root, ignore_errors=True)
            ok, expected = case.judge(on)
            rows.append({"case": case.name, "same": verdict(on) == verdict(off), "on": verdict(on),
                         "off": verdict(off), "fixture_ok": ok, "expected": expected,
                         "diagnoses": [d.kind for c in on.checks for d in c.diagnosis],
                         "why": {c.id: [d.message for d in c.diagnosis] for c in on.checks if c.diagnosis},
                         "diagnose_seconds": seconds})
            print(f"  {lesson.id} {case.name}: {'same' if rows[-1]['same'] else 'DIFFERENT'} "
                  f"{on.status} {on.score:g}/{on.max_score:g}; diagnoses {rows[-1]['diagnoses'] or '-'}; "
                  f"{'ok' if ok else 'WRONG: ' + expected}", file=sys.stderr)
    finally:
        if underlay is not None:
            underlay.discard()
    costs = [x for row in rows for x in row["diagnose_seconds"]]
    return {"lesson": lesson.id, "cases": len(rows), "differences": sum(not r["same"] for r in rows),
            "fixtures_wrong": [r["case"] for r in rows if not r["fixture_ok"]],
            "diagnoses": len(costs), "diagnose_median": statistics.median(costs) if costs else None,
            "diagnose_max": max(costs) if costs else None, "rows": rows}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("lessons", nargs="+", help="lesson ids")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a summary")
    parser.add_argument("--skip-starter", action="store_true", help="grade the reference and the fixtures only")
    parser.add_argument("--off-first", action="store_true", help="grade with the diagnosis off first")
    parser.add_argument("--case", action="append", default=[], help="grade only this case (repeatable)")
    args = parser.parse_args(argv)
    env_mod.activate_process()
    catalog = load_catalog()
    out = [compare_lesson(catalog.get(lesson_id), args.skip_starter, args.off_first, args.case or None)
           for lesson_id in args.lessons]
    if args.json:
        print(json.dumps(out, indent=2))
    else:
        fmt = lambda v: "-" if v is None else f"{v * 1000:.1f} ms"  # noqa: E731
        for r in out:
            print(f"{r['lesson']}: {r['cases']} cases compared, {r['differences']} differences; "
                  f"{r['diagnoses']} diagnoses, median {fmt(r['diagnose_median'])}, max {fmt(r['diagnose_max'])} "
                  f"(limit {LIMIT * 1000:.0f} ms); fixtures not as stated: {', '.join(r['fixtures_wrong']) or 'none'}")
        total = sum(r["cases"] for r in out)
        print(f"total: {total} cases compared, {sum(r['differences'] for r in out)} differences")
    return 1 if any(r["differences"] for r in out) else 0


if __name__ == "__main__":
    sys.exit(main())
