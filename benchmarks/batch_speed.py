"""Batch grading throughput: submissions per minute with ``--jobs 1`` and ``--jobs 2``.

Generates a class (the lesson's reference solution and its wrong fixtures,
round robin), grades it twice with :func:`ros2course.batch.runner.run_batch` (jobs 1, then
jobs N), and prints submissions per minute, the speedup, the peak memory of
one job (worker + colcon + the learner's nodes, RSS sampled every 0.5 s) and
whether any verdict changed between the two runs. A script, not a timed test::

    python benchmarks/batch_speed.py [--lesson print-forever-node] [--count 20] [--jobs 2]
    python benchmarks/batch_speed.py --overhead [--count 6]

Goal on the 2-core machine: speedup >= 1.7 with 2 jobs, no verdict changed.

``--overhead`` grades the class with ``--jobs 1`` twice instead, with every
protection of :mod:`ros2course.sandbox` (namespaces, submission uid, pids cgroup,
read-only mounts) and with ``isolate=False``, and prints the cost of the
isolation per submission (seconds) and whether any verdict changed.
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from ros2course.batch.runner import run_batch  # noqa: E402
from ros2course.dev.validate import (  # noqa: E402
    apply_edits,
    load_fixtures,
    reference_workspace,
    run_commands,
)
from ros2course.lesson.catalog import load_catalog  # noqa: E402
from ros2course.ros import env as env_mod  # noqa: E402


def make_class(lesson_id: str, count: int, dest: Path) -> dict[str, str]:
    """``count`` submissions in ``dest`` (reference and fixtures, round robin); student -> variant."""
    lesson = load_catalog().get(lesson_id)
    variants = [("reference", None), *[(f.name, f) for f in load_fixtures(lesson_id)]]
    built = {}
    for name, fixture in variants:
        folder = dest.parent / "variants" / name
        reference_workspace(lesson, folder)
        if fixture is not None:
            apply_edits(folder, fixture.edits)
        run_commands(folder, lesson.reference.commands if fixture is None or fixture.commands is None
                     else fixture.commands)
        built[name] = folder
    assignment = {}
    for i in range(count):
        name = variants[i % len(variants)][0]
        shutil.copytree(built[name], dest / f"s{i:02d}", symlinks=True)
        assignment[f"s{i:02d}"] = name
    return assignment


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lesson", default="print-forever-node")
    parser.add_argument("--count", type=int, default=20)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--overhead", action="store_true", help="isolated vs not isolated, one job at a time")
    args = parser.parse_args()
    env_mod.activate_process()
    root = Path(tempfile.mkdtemp(prefix="ros2course-bench-batch-"))
    try:
        make_class(args.lesson, args.count, root / "subs")
        if args.overhead:
            return overhead(root, args.lesson, args.count)
        runs = {}
        for jobs in sorted({1, args.jobs}):  # --jobs 1: one run (a second would find the first's results)
            begin = time.monotonic()
            report = run_batch(root / "subs", [args.lesson], root / f"out-{jobs}", jobs=jobs)
            seconds = time.monotonic() - begin
            verdicts = {r.student: (r.status.value, tuple(r.failed_checks())) for r in report.records}
            runs[jobs] = (seconds, verdicts, report)
            print(f"jobs {jobs}: {args.count} submissions in {seconds:.1f} s = {60 * args.count / seconds:.1f} "
                  f"submissions/min; peak memory per job max {max(report.peak_rss) / 2**20:.0f} MiB, "
                  f"mean {statistics.mean(report.peak_rss) / 2**20:.0f} MiB; "
                  f"netns: {report.isolation.get('netns')}", flush=True)
        one, many = runs[1], runs[args.jobs]
        changed = sorted(s for s in one[1] if one[1][s] != many[1].get(s))
        if args.jobs != 1:
            print(f"speedup with {args.jobs} jobs: {one[0] / many[0]:.2f}x (goal >= 1.7 with 2 jobs on 2 cores)")
            print(f"verdicts changed between the runs: {changed or 'none'}")
        return 1 if changed else 0
    finally:
        shutil.rmtree(root, ignore_errors=True)


def overhead(root: Path, lesson: str, count: int) -> int:
    """Grade the class one job at a time with and without isolation; print seconds per submission."""
    runs = {}
    for isolate in (False, True, False, True):  # interleaved: a warm-up effect favours neither
        begin = time.monotonic()
        report = run_batch(root / "subs", [lesson], root / f"out-{isolate}-{len(runs)}", jobs=1, isolate=isolate)
        seconds = time.monotonic() - begin
        verdicts = {r.student: (r.status.value, tuple(r.failed_checks())) for r in report.records}
        runs.setdefault(isolate, []).append((seconds / count, verdicts, report.isolation))
        print(f"isolate={isolate}: {seconds / count:.2f} s per submission "
              f"({report.isolation.get('reason', '')[:120]})", flush=True)
    plain = statistics.mean(r[0] for r in runs[False])
    walled = statistics.mean(r[0] for r in runs[True])
    changed = sorted(s for s in runs[False][0][1] if any(r[1][s] != runs[False][0][1][s] for r in runs[True]))
    print(f"isolation overhead: {walled - plain:+.2f} s per submission ({plain:.2f} s without, {walled:.2f} s with)")
    print(f"verdicts changed by isolation: {changed or 'none'}")
    return 1 if changed else 0


if __name__ == "__main__":
    raise SystemExit(main())
