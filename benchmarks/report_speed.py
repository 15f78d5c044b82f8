"""Time ``ros2course report`` on a synthetic class (issue 21: 300 students in < 30 s and < 20 MB).

    python benchmarks/report_speed.py                 # 300 students, one lesson
    python benchmarks/report_speed.py --count 20      # smaller
    python benchmarks/report_speed.py --json          # the figures as JSON only

The class: ``--count`` students of ``print-forever-node`` (the worst case for similarity: every
pair is in the same lesson), each with a result row of 6 checks (two of them rate checks with
the grader's band), a recording (``observed.mcap`` written by the grader's own
:class:`ros2course.run.recording.Recorder`, messages at 2 Hz, some late) and a submission folder:
the lesson's starter files plus a node and a helper module assembled from a pool of functions
with renamed identifiers, five pairs of near-copies among them. Prints the time of
``write_report`` with and without similarity, the similarity alone, and the report's size.
"""

from __future__ import annotations

import argparse
import json
import random
import shutil
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from ros2course.grade.results import CheckResult, LessonResult, Status  # noqa: E402
from ros2course.lesson.catalog import load_catalog  # noqa: E402
from ros2course.report.html import write_report  # noqa: E402
from ros2course.report.similarity import similar_pairs  # noqa: E402

LESSON = "print-forever-node"
PACKAGE = "python_package_with_a_node"
RATE_EXPECTED = "2.00 Hz: mean period 0.500 s ± 15%, over at least 5 intervals"
COPIES = 5

#: Statement shapes a synthetic function is assembled from ({v}: a variable, {n}: a number); copydetect
#: normalises names, so the variety comes from the shapes, their order and the numbers.
STATEMENTS = [
    "{v} = {v} + {n}", "{v} = [{n}, {n}, {n}]", "if {v} > {n}:\n        {v} = {n}", "for {v} in range({n}):\n        {v} += {v} * {n}",
    "{v} = {{'{v}': {n}}}", "while {v} < {n}:\n        {v} = {v} * {n}", "{v} = sorted({v})[:{n}]",
    "{v} = [{v} for {v} in range({n}) if {v} % {n}]", "self.get_logger().info(f'{{{v}}} after {n}')",
    "{v} = max({v}, {n}) - min({v}, {n})", "try:\n        {v} = {v} / {n}\n    except ZeroDivisionError:\n        {v} = {n}",
    "{v}.append({v} ** {n})", "{v} = tuple({v}[{n}:{n}])", "{v} = {v} if {v} else {n}", "assert {v} != {n}",
    "{v} = len({v}) * {n}", "{v} = str({v}).rjust({n})", "{v} = abs({v} - {n}) // {n}",
]
WORDS = ["count", "total", "items", "value", "result", "data", "node", "timer", "step", "index", "buffer", "entry",
         "report", "window", "sample", "target", "source", "limit", "state", "mode"]


def _module(rng: random.Random, functions: int) -> str:
    parts = ["import rclpy\nfrom rclpy.node import Node\n\n"]
    for number in range(functions):
        body = []
        for _ in range(rng.randint(6, 10)):
            shape = rng.choice(STATEMENTS)
            body.append("    " + _fill(rng, shape))
        parts.append(f"def {rng.choice(WORDS)}_{number}({rng.choice(WORDS)}):\n" + "\n".join(body)
                     + f"\n    return {rng.choice(WORDS)}\n\n\n")
    return "".join(parts)


def _fill(rng: random.Random, shape: str) -> str:
    out = shape
    while "{v}" in out or "{n}" in out:
        out = out.replace("{v}", rng.choice(WORDS), 1).replace("{n}", str(rng.randint(2, 999)), 1)
    return out.replace("{{", "{").replace("}}", "}")


def _result(index: int, student: str, log_dir: Path) -> LessonResult:
    rng = random.Random(index)
    checks = []
    for n in range(6):
        rate = n in (2, 3)
        passed = rng.random() > (0.3 if rate else 0.15)
        checks.append(CheckResult(
            id=f"check_{n}", name=f"check {n}", points=1.0 if passed else 0.0, max_points=1.0, passed=passed,
            observed=(f"{2 if passed else 1.4:.2f} Hz (mean period {0.5 if passed else 0.7:.3f} s)" if rate
                      else ("as expected" if passed else f"printed <{rng.choice(WORDS)}> instead")),
            expected=RATE_EXPECTED if rate else "as in the lesson", hint="" if passed else "see the lesson's hints"))
    score = sum(c.points for c in checks)
    status = Status.PASSED if score == 6 else Status.FAILED
    if index % 25 == 7:
        result = LessonResult.unfinished(LESSON, Status.NOT_GRADABLE, "colcon build failed: SyntaxError",
                                         "fix the build", max_score=6.0, log_dir=str(log_dir))
        result.student = student
        return result
    return LessonResult(LESSON, score, 6.0, status, checks, student=student, seconds=20.0 + index % 17,
                        isolation={"netns": True, "pidns": True}, log_dir=str(log_dir))


def _recording(path: Path, index: int) -> None:
    """An ``observed.mcap`` as the grader writes it: /chatter at ~2 Hz and the rate checks' windows."""
    from std_msgs.msg import String  # noqa: PLC0415 - needs the ROS environment

    from ros2course.run.recording import CHECKS_METADATA, Recorder  # noqa: PLC0415

    rng = random.Random(index)
    recorder = Recorder(path)
    start = 1_700_000_000_000_000_000 + index * 10**10
    stamp = start
    for n in range(12):
        stamp += int((0.5 + rng.uniform(-0.05, 0.05) + (0.4 if n % 4 == 3 and index % 3 == 0 else 0)) * 1e9)
        recorder.write(0, "/chatter", String(data=f"hello {n}"), publish_ns=stamp, log_ns=stamp + 1000)
    window = {"passed": True, "observed": "2.00 Hz", "start_ns": start, "end_ns": stamp}
    recorder.metadata(CHECKS_METADATA, {"check_2": json.dumps(window), "check_3": json.dumps(window)})
    recorder.close()


def make_class(root: Path, count: int, recordings: bool = True) -> tuple[Path, Path]:
    """(OUTDIR, SUBMISSIONS) of a synthetic class of ``count`` students under ``root``."""
    out, subs = root / "out", root / "subs"
    out.mkdir(parents=True)
    starter = load_catalog().get(LESSON).starter_dir
    lines = []
    for index in range(count):
        student = f"student{index:03d}"
        log_dir = out / student / "logs" / LESSON
        log_dir.mkdir(parents=True)
        if recordings:
            _recording(log_dir / "observed.mcap", index)
        lines.append(json.dumps(_result(index, student, log_dir).to_record()))
        workspace = subs / student
        shutil.copytree(starter, workspace)
        package = workspace / "src" / PACKAGE / PACKAGE
        package.mkdir(parents=True, exist_ok=True)
        rng = random.Random(index if index >= 2 * COPIES else index // 2)  # students 0-9: five pairs of copies
        node, helpers = _module(rng, 3), _module(rng, 4)
        if index < 2 * COPIES and index % 2:  # the copy: names changed, one statement added
            node = node.replace("count", "counter").replace("    return", "    total = 0\n    return", 1)
        (package / "print_forever_node.py").write_text(node)
        (package / "helpers.py").write_text(helpers)
    (out / "results.jsonl").write_text("\n".join(lines) + "\n")
    return out, subs


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=300, help="students (default 300)")
    parser.add_argument("--json", action="store_true", help="print the figures as JSON only")
    args = parser.parse_args()
    from ros2course.ros import env  # noqa: PLC0415

    env.activate_process()
    with tempfile.TemporaryDirectory() as folder:
        begin = time.perf_counter()
        out, subs = make_class(Path(folder), args.count)
        made = time.perf_counter() - begin
        from ros2course.report.gradebook import read_results  # noqa: PLC0415

        results = read_results(out / "results.jsonl")
        comparison = similar_pairs(results, subs)
        begin = time.perf_counter()
        plain = write_report(out, similarity=False)
        without = time.perf_counter() - begin
        begin = time.perf_counter()
        path = write_report(out, submissions=subs)
        full = time.perf_counter() - begin
        figures = {"students": args.count, "class_made_s": round(made, 2),
                   "report_s": round(full, 2), "report_without_similarity_s": round(without, 2),
                   "similarity_s": round(comparison.seconds, 2), "files_fingerprinted": comparison.files,
                   "pairs_flagged": len(comparison.pairs),
                   "pairs_flagged_ids": [(p.first, p.second) for p in comparison.pairs][:10],
                   "report_bytes": path.stat().st_size, "plots_drawn": path.read_text().count("<figure>")}
        del plain
    if args.json:
        print(json.dumps(figures))
    else:
        print(f"report of {args.count} students: {figures['report_s']:.2f} s "
              f"({figures['report_without_similarity_s']:.2f} s without similarity), "
              f"{figures['report_bytes'] / 1e6:.2f} MB, {figures['plots_drawn']} plots")
        print(f"similarity: {figures['similarity_s']:.2f} s over {figures['files_fingerprinted']} files, "
              f"{figures['pairs_flagged']} pairs flagged {figures['pairs_flagged_ids']}")
        print(f"(making the synthetic class took {made:.1f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
