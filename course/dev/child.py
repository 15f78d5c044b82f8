"""Grade one workspace in a child process of its own, as ``ros2course check`` would.

``dev validate --repeat --load K`` (:mod:`ros2course.dev.repeat`) and ``dev validate
--jobs K`` (:mod:`ros2course.dev.validate`) grade several workspaces at once. Each
grading runs in its own ``python -m ros2course.dev.child`` process: its own ROS domain,
rclpy context and ``ros2`` daemon, so the gradings share nothing but the machine (and
nothing of the author's process, such as an rclpy context, leaks into the next one).
The child grades the lesson of the course this process has chosen (``--course``): it is
told through ``ROS2COURSE_CONTENT`` (:func:`ros2course.lesson.content_root`).
"""

from __future__ import annotations

import contextlib
import faulthandler
import json
import os
import re
import subprocess
import sys
from pathlib import Path

from ros2course.grade.checklist import StopWhen
from ros2course.grade.results import LessonResult, Status
from ros2course.lesson.catalog import content_root, load_catalog

#: Seconds one grading may take before the run is counted as hung (a grader's own deadlines are far shorter).
RUN_TIMEOUT = 600.0
#: Seconds before that deadline when a hung child writes every thread's stack to its stderr (faulthandler), so
#: the parent can say where it hung (CI of stop 73: sas-robot-driver ran past 600 s once, and nothing said where).
STACK_DUMP_LEAD = 10.0


def grade_in_child(lesson_id: str, root: Path, underlays: tuple[Path, ...], log_dir: Path,
                   timeout: float = RUN_TIMEOUT, stop_when: StopWhen | None = None) -> LessonResult:
    """Grade the workspace ``root`` for ``lesson_id`` in a fresh child process.

    Args:
        lesson_id: a lesson of the active course.
        root: the workspace folder (``src/`` and the lesson's folders); its build is
            reused when up to date, as a learner's second ``check`` does.
        underlays: built workspaces sourced before building and running it.
        log_dir: where the grading writes its logs (made when missing).
        timeout: seconds before the child is killed and the grading counted as hung.
        stop_when: when the grading may stop (``dev validate --until-settled``,
            :func:`~ros2course.grade.engine.grade_lesson`); None: graded whole.

    Returns:
        The child's result; a ``grader error`` result (never an exception) when the child
        ran past ``timeout``, failed, or printed no result.
    """
    argv = [sys.executable, "-m", "ros2course.dev.child", lesson_id, str(root), str(log_dir),
            "--dump-stacks-after", f"{max(timeout - STACK_DUMP_LEAD, timeout / 2):.1f}"]
    for underlay in underlays:
        argv += ["--underlay", str(underlay)]
    if stop_when:
        argv += [arg for check_id in sorted(stop_when.judged) for arg in ("--judged", check_id)]
        argv += ["--any-loss"] if stop_when.any_loss else []
    env = {**os.environ, "ROS2COURSE_CONTENT": str(content_root())}
    for attempt in (1, 2):
        try:
            proc = subprocess.run(argv, capture_output=True, text=True, timeout=timeout, env=env,  # noqa: S603
                                  stdin=subprocess.DEVNULL, check=False)
        except subprocess.TimeoutExpired as exc:
            printed = [line for line in _text(exc.stdout).splitlines() if line.startswith("{")]
            if printed:  # the grading ended and printed its result; only the child's exit hung
                return LessonResult.from_record(json.loads(printed[-1]))
            where = hung_at(exc.stderr, log_dir)
            return LessonResult.unfinished(lesson_id, Status.GRADER_ERROR,
                                           f"the grading ran past {timeout:.0f} s{where}")
        lines = [line for line in proc.stdout.splitlines() if line.startswith("{")]
        if proc.returncode == 0 and lines:
            return LessonResult.from_record(json.loads(lines[-1]))
        # killed by a signal with nothing printed: the grading process itself crashed (Fast DDS 2.14 can segfault
        # while a grader's participant is destroyed beside killed peers; GradingSession.close), not a verdict of
        # the grader: graded once more, and said so if it crashes again
        if not (proc.returncode < 0 and not lines and attempt == 1):
            break
    tail = (proc.stderr.strip().splitlines() or ["no output"])[-1]
    crashed = f" (exit {proc.returncode}, twice)" if proc.returncode < 0 else f" (exit {proc.returncode})"
    return LessonResult.unfinished(lesson_id, Status.GRADER_ERROR, f"the grading process failed: {tail}{crashed}")


def _text(output: bytes | str | None) -> str:
    """What a killed child had written (TimeoutExpired holds bytes, whatever ``text=`` said)."""
    return output.decode(errors="replace") if isinstance(output, bytes) else (output or "")


def hung_at(stderr: bytes | str | None, log_dir: Path) -> str:
    """Where a hung child was, from the stacks faulthandler wrote to its ``stderr`` (``--dump-stacks-after``).

    Writes the whole stderr to ``log_dir/hung-child.stderr.log`` and returns "" when it holds no stack dump,
    else ``"; its main thread was at FILE:LINE in FUNC <- ..."`` (the innermost three frames of the thread
    that runs :func:`_main`, else of the last thread listed, and its innermost frame in a grader) and the log's path.
    """
    text = _text(stderr)
    log = log_dir / "hung-child.stderr.log"
    with contextlib.suppress(OSError):
        log_dir.mkdir(parents=True, exist_ok=True)
        log.write_text(text)
    blocks = re.split(r"\n(?=(?:Current thread|Thread) 0x[0-9a-f]+ \(most recent call first\):)", "\n" + text)
    stacks = [b for b in blocks if "(most recent call first):" in b]
    if not stacks:
        return ""
    main = next((b for b in stacks if " in _main" in b), stacks[-1])  # the thread that runs the grading
    frames = re.findall(r'File "([^"]+)", line (\d+) in (\S+)', main)
    shown = frames[:3] + [next((f for f in frames[3:] if "/graders/" in f[0]), None)]
    said = " <- ".join(f"{Path(f).name}:{line} in {func}" for f, line, func in filter(None, shown))
    return f"; its main thread was at {said} (every thread's stack: {log})"


def _main(argv: list[str]) -> int:
    """The child: ``LESSON ROOT LOG_DIR [--underlay PATH]... [--judged CHECK]... [--any-loss]`` (the last two: its
    :class:`~ros2course.grade.checklist.StopWhen`); prints its result's JSON record."""
    import argparse  # noqa: PLC0415 - the child's side: a parent importing this module for grade_in_child needs none of it

    from ros2course.grade.engine import grade_lesson  # noqa: PLC0415 - the child's side: a parent importing this module for grade_in_child needs none of it
    from ros2course.ros import env as env_mod  # noqa: PLC0415 - the child's side: a parent importing this module for grade_in_child needs none of it

    parser = argparse.ArgumentParser(prog="python -m ros2course.dev.child")
    parser.add_argument("lesson")
    parser.add_argument("root", type=Path)
    parser.add_argument("log_dir", type=Path)
    parser.add_argument("--underlay", type=Path, action="append", default=[])
    parser.add_argument("--judged", action="append", default=[])
    parser.add_argument("--any-loss", action="store_true")
    parser.add_argument("--dump-stacks-after", type=float, default=None)
    args = parser.parse_args(argv)
    if args.dump_stacks_after:  # a hung grading says where (grade_in_child's hung_at); the parent kills it after
        faulthandler.dump_traceback_later(args.dump_stacks_after, exit=False)
    env_mod.activate_process()
    lesson = load_catalog().get(args.lesson)
    args.log_dir.mkdir(parents=True, exist_ok=True)
    result = grade_lesson(lesson, args.root, log_dir=args.log_dir, underlays=tuple(args.underlay),
                          stop_when=StopWhen(frozenset(args.judged), args.any_loss))
    sys.stdout.write(json.dumps(result.to_record()) + "\n")
    sys.stdout.flush()
    return 0


if __name__ == "__main__":
    os.environ.setdefault("PYTHONDONTWRITEBYTECODE", "1")
    code = _main(sys.argv[1:])
    sys.stdout.flush()
    sys.stderr.flush()
    # as `ros2course check` and the batch worker end (ros2course.cli.main): the interpreter's teardown of rclpy /
    # Fast DDS is skipped once the result is out. `check` never runs that teardown, and it can hang on its own
    # (destructors of DDS objects left to the garbage collector waiting on threads already gone: Fast-DDS #235,
    # #1921, rclpy #456); the suspected cause of the one child that ran past its 600-s deadline (CI of stop 73,
    # sas-robot-driver swallows-ctrl-c, which took 7-45 s in each of 116 runs here, three and six at once)
    os._exit(code)
