"""Kit step that grades two independent parts of a lesson at the same time."""

from __future__ import annotations

import concurrent.futures
import contextlib
from collections.abc import Callable, Collection

from ros2course.kit.session_protocol import Session
from ros2course.run.probes import import_rclpy


def at_once(s: Session, background: str, grade_background: Callable[[], None], foreground: str,
            grade_foreground: Callable[[], None], *, own_graphs: Collection[str] = ()) -> None:
    """Grade part ``background`` on a worker thread while part ``foreground`` is graded on this thread.

    For halves that run in private graphs of their own (``s.new_graph()``), so
    neither sees the other nor waits for its discovery: the check takes about
    as long as the longer half. Processes started from the main thread get
    the parent-death signal (course/run/process.py), so start there the half
    whose programs run longest. ``s.part`` keeps each thread's closing actions
    (Ctrl+C checks) apart; an :class:`~ros2course.grade.checklist.Unmet` ends only its
    own part. A grader fault (any other exception) of the background half is
    raised here once both are done. ``own_graphs``: the names of the halves
    opened with ``s.part(name, own_graph=True)`` (each then observes its own
    private graph through ``s.graph``).
    """
    def run_background() -> None:
        with s.part(background, own_graph=background in own_graphs):
            grade_background()

    with contextlib.suppress(ImportError):  # a lesson without ROS on a machine without rclpy: nothing to race on
        import_rclpy()  # here, before the halves open their graphs on two threads at once
    with concurrent.futures.ThreadPoolExecutor(max_workers=1, thread_name_prefix=f"ros2course-{background}") as pool:
        done = pool.submit(run_background)
        try:
            with s.part(foreground, own_graph=foreground in own_graphs):
                grade_foreground()
        finally:
            done.result()
