"""A learner's ``ros2course check`` never runs past a deadline, whatever hangs inside it.

Every step of a check has a deadline of its own (colcon's build, each learner process's
watchdog, each probe's wait), but a hang of the grading process itself (a DDS or rclpy call
that never returns, a deadlock between the grader's threads) would leave a learner's
terminal waiting for ever. :func:`check_deadline` is the last guard: when it passes, every
thread's stack is written to a file (``faulthandler``), every process the check started is
killed, stale Fast DDS shared memory is swept, a one-line error with a hint is printed, and the
process ends with exit status :attr:`~ros2course.errors.ExitStatus.GRADER_ERROR` before the
attempt is recorded (the learner's progress and files are untouched).

A timer thread and ``os._exit`` are used, not ``signal.alarm`` and an exception: a main thread
blocked inside a C call (rclpy's wait, Fast DDS) never runs a Python signal handler.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import faulthandler
import os
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

from ros2course.errors import ExitStatus

#: Seconds a whole check may take: colcon's own build deadline (ros2course.builder.colcon.BUILD_TIMEOUT, 900 s)
#: and then the 600 s ``dev validate`` allows one grading (ros2course.dev.child.RUN_TIMEOUT).
CHECK_DEADLINE = 1500.0
#: Environment variable that sets another deadline (seconds; a slow machine, or a test).
DEADLINE_VAR = "ROS2COURSE_CHECK_DEADLINE"


def deadline_seconds() -> float:
    """The check's deadline in seconds: :data:`DEADLINE_VAR` when it holds a positive number, else
    :data:`CHECK_DEADLINE`."""
    with contextlib.suppress(ValueError):
        value = float(os.environ.get(DEADLINE_VAR, ""))
        if value > 0:
            return value
    return CHECK_DEADLINE


@contextlib.contextmanager
def check_deadline(what: str, dump_dir: Path, seconds: float | None = None) -> Iterator[None]:
    """Run the block under a deadline of ``seconds`` (default :func:`deadline_seconds`).

    Args:
        what: what runs, for the message ("the check of print-forever-node").
        dump_dir: folder for the stacks file (``hung-check-<time>.txt``), made when needed.
        seconds: wall-clock seconds.

    At the deadline the process ends (``os._exit``) as the module says; the block never resumes.
    """
    seconds = deadline_seconds() if seconds is None else seconds
    timer = threading.Timer(seconds, _expired, args=(what, dump_dir, seconds))
    timer.daemon = True
    timer.start()
    try:
        yield
    finally:
        timer.cancel()


def _expired(what: str, dump_dir: Path, seconds: float) -> None:
    """The deadline passed: write the stacks, kill the check's processes, say so, end the process."""
    import psutil  # noqa: PLC0415 - only when a check hangs

    stacks = dump_dir / f"hung-check-{dt.datetime.now().strftime('%Y-%m-%d_%H-%M-%S')}.txt"
    try:
        dump_dir.mkdir(parents=True, exist_ok=True)
        with open(stacks, "w", encoding="utf-8") as handle:
            faulthandler.dump_traceback(file=handle, all_threads=True)
    except OSError:
        stacks = None
    # every learner process, colcon and ros2 daemon the check started is a descendant (each in a session of its
    # own, so not in this process group); those started from another thread than the main one get no
    # parent-death signal (ros2course.run.process.LearnerProcess), so they are killed here
    with contextlib.suppress(psutil.Error):
        for child in psutil.Process().children(recursive=True):
            with contextlib.suppress(psutil.Error):
                child.kill()
    from ros2course.run.process import sweep_stale_fastdds_shm  # noqa: PLC0415 - only when a check hangs

    with contextlib.suppress(Exception):
        sweep_stale_fastdds_shm()
    where = f"; every thread's stack is in {stacks}" if stacks else ""
    if sys.stderr.isatty():  # rich's status line hid the cursor and no longer runs to show it again (ANSI DECTCEM)
        sys.stderr.write("\r\x1b[2K\x1b[?25h")
    sys.stderr.write(f"error: {what} ran past its {seconds:.0f}-s deadline and was stopped: a hang in ros2course, "
                     f"not a verdict on your code (nothing was recorded){where}\n"
                     f"hint: run the check again; if it hangs again, report it with that file (and set "
                     f"{DEADLINE_VAR}=SECONDS on a very slow machine)\n")
    sys.stderr.flush()
    os._exit(int(ExitStatus.GRADER_ERROR))
