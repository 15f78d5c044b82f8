"""Where a Ctrl+C lands decides what it shows: the ends of one rclpy node pressed at a set moment (stop 65).

A node whose ``main()`` misses ``ExternalShutdownException`` shows it only when SIGINT arrives while rclpy
waits inside ``spin``/``spin_once``; pressed while a callback or the executor's own work runs, its loop may end
cleanly, or rclpy raises its own ``RCLError`` about the context (which the kit forgives,
:func:`ros2course.run.process.rclpy_shutdown_race`). So a wrong solution's Ctrl+C verdict, and how often a
correct one meets rclpy's race, depend on when the grader presses. This measures it for one Python node file
of a lesson's reference (``solutions/``), as it is or with a fixture's edits applied::

    python benchmarks/sigint_window.py nav2-custom-nodes \\
        src/python_package_that_uses_nav2/python_package_that_uses_nav2/nav2_initial_pose_publisher_node.py \\
        --fixture pose-ctrl-c-uncaught --runs 100 --delay 0.0

Each run starts the file the way the grader starts learner nodes (``LearnerProcess`` with rclpy's SIGINT
handling, in a ``RosSession``'s private domain), waits for the node's first ``/rosout`` record to reach the
session (as the graders' Ctrl+C steps do), waits ``--delay`` seconds more, presses Ctrl+C once, and sorts the
end: ``clean`` (exit 0, no traceback), ``rclpy race`` (the kit's allowance), ``traceback: <exception>``,
``exit N``, ``still running`` (after ``--timeout`` s). Prints a table, or JSON with ``--json``.

Measured at stop 65 (2 cores, idle): the fixture above, as it was (its loop `while rclpy.ok() and ...`), ended
clean in 2 of 150 runs pressed 0-300 ms after its first record; the same, pressed as the record is printed
(a plain subprocess, no /rosout hop), 60 of 200; the fixed fixture, 0 of 150.
"""

from __future__ import annotations

import argparse
import collections
import json
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from rich.console import Console  # noqa: E402
from rich.table import Table  # noqa: E402

from ros2course.dev.validate import apply_edits, load_fixtures  # noqa: E402
from ros2course.errors import CourseError  # noqa: E402
from ros2course.lesson.catalog import load_catalog  # noqa: E402
from ros2course.ros import env as env_mod  # noqa: E402

#: Seconds to wait for the node's first /rosout record before a run counts as "no record".
FIRST_RECORD_TIMEOUT = 20.0


def node_file(lesson_id: str, relative: str, fixture: str | None, folder: Path) -> Path:
    """The node file ``relative`` (a path under the lesson's ``solutions/``) copied into ``folder``, with the
    edits of ``fixture`` (a name under ``tests/fixtures/<lesson>/``) that touch it applied.

    Raises:
        CourseError: the file is not in the reference, or the fixture is unknown or edits no such file.
    """
    lesson = load_catalog().get(lesson_id)
    source = lesson.course.solutions / relative
    if not source.is_file():
        raise CourseError(f"{relative}: no such file under {lesson.course.solutions}", "give a path under solutions/")
    target = folder / relative
    target.parent.mkdir(parents=True, exist_ok=True)
    shutil.copy2(source, target)
    if fixture is not None:
        found = {f.name: f for f in load_fixtures(lesson_id)}
        if fixture not in found:
            raise CourseError(f"{lesson_id} has no fixture {fixture!r}", f"one of: {', '.join(sorted(found))}")
        edits = [e for e in found[fixture].edits if e.file == relative]
        if not edits:
            raise CourseError(f"fixture {fixture!r} edits no line of {relative}", "give the file the fixture edits")
        apply_edits(folder, edits)
    return target


def press(script: Path, runs: int, delay: float, timeout: float, progress: Console | None = None) -> collections.Counter:
    """Start ``script`` ``runs`` times as the grader starts a learner node; press Ctrl+C ``delay`` s after its
    first /rosout record reaches the session; count the ends (labels in the module docstring)."""
    from ros2course.run.probes import RosSession, wait_until  # noqa: PLC0415 - rclpy only when measuring
    from ros2course.run.process import LearnerProcess, rclpy_shutdown_race, sweep_stale_fastdds_shm  # noqa: PLC0415

    base_env = env_mod.activate()
    ends: collections.Counter = collections.Counter()
    for index in range(runs):
        with RosSession() as session:
            probe = session.rosout()
            proc = LearnerProcess([sys.executable, str(script)], session.learner_env(base_env), script.parent,
                                  f"press-{index}", cwd=script.parent, ros_sigint=True)
            try:
                proc.start()
                if not wait_until(lambda: bool(probe.messages()), FIRST_RECORD_TIMEOUT, interval=0.005,
                                  abort=lambda: proc.poll() is not None):
                    ends[f"no record (exit code {proc.poll()})"] += 1
                    continue
                time.sleep(delay)
                proc.interrupt()
                ended = wait_until(lambda: proc.poll() is not None, timeout, interval=0.01)
            finally:
                report = proc.stop(sigint_timeout=0.1, sigterm_timeout=2.0)
            if not ended:
                ends["still running"] += 1
            elif report.traceback:
                last = report.traceback.strip().splitlines()[-1]
                ends["rclpy race" if rclpy_shutdown_race(report.traceback) else f"traceback: {last.split(':')[0]}"] += 1
            else:
                ends["clean" if report.returncode == 0 else f"exit {report.returncode}"] += 1
        sweep_stale_fastdds_shm()
        if progress is not None and (index + 1) % 10 == 0:
            progress.print(f"  {index + 1}/{runs}: {dict(ends)}")
    return ends


def main() -> int:
    """Parse the arguments, measure, print; 2 on bad input."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("lesson")
    parser.add_argument("file", help="the node file, a path under solutions/")
    parser.add_argument("--fixture", default=None, help="apply this fixture's edits of the file first")
    parser.add_argument("--runs", type=int, default=50)
    parser.add_argument("--delay", type=float, default=0.0, help="seconds after the first record reaches the session")
    parser.add_argument("--timeout", type=float, default=3.0, help="seconds a run may take to end after Ctrl+C")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    console = Console(stderr=True)
    if args.runs < 1 or args.delay < 0 or args.timeout <= 0:
        console.print("error: --runs must be 1 or more, --delay 0 or more, --timeout above 0")
        return 2
    folder = Path(tempfile.mkdtemp(prefix="ros2course-sigint-window-"))
    try:
        script = node_file(args.lesson, args.file, args.fixture, folder)  # bad input is named before ROS starts
        env_mod.activate_process()
        ends = press(script, args.runs, args.delay, args.timeout, None if args.json else console)
    except CourseError as exc:
        console.print(f"error: {exc}")
        return 2
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    found = {"lesson": args.lesson, "file": args.file, "fixture": args.fixture, "runs": args.runs,
             "delay": args.delay, "ends": dict(ends.most_common())}
    if args.json:
        print(json.dumps(found))
        return 0
    table = Table(title=f"{args.file}{' + ' + args.fixture if args.fixture else ''}: Ctrl+C {args.delay:g} s "
                        f"after the first /rosout record, {args.runs} runs")
    table.add_column("end")
    table.add_column("runs", justify="right")
    for label, count in ends.most_common():
        table.add_row(label, str(count))
    Console().print(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
