"""Watch which nodes join the check's ROS graph while a learner's script runs (tutorial ch. 10, 23; issue 12).

A script that starts nodes with ``ros2 run`` / ``ros2 launch`` and then waits
(the ``launch-and-run`` lesson) runs in :func:`ros2course.kit.scripts.run_script`,
which blocks until the script ends; a :class:`NodeWatch` started before it
samples the graph on a thread of its own meanwhile (the grader's hidden node
asks the graph API, what ``ros2 node list`` shows; no ``ros2`` daemon involved).
"""

from __future__ import annotations

import threading
import time
from typing import Any

from ros2course.kit import Session


class NodeWatch:
    """Record the nodes of ``graph`` every ``interval`` seconds until :meth:`stop` (or the part ends).

    Args:
        s: the grading session; the watch stops when the current part ends (:meth:`Session.on_close`).
        graph: the :class:`~ros2course.run.probes.RosSession` to watch (default ``s.ros``).
        interval: seconds between two looks at the graph.

    Attributes:
        first_seen: fully qualified node name (``/print_forever``) -> seconds after the watch started
            when it was first listed.
    """

    def __init__(self, s: Session, graph: Any = None, interval: float = 0.1) -> None:
        self._graph = graph or s.ros
        self._interval = interval
        self._begin = time.monotonic()
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self.first_seen: dict[str, float] = {}
        self._thread = threading.Thread(target=self._run, daemon=True, name="node-watch")
        self._thread.start()
        s.on_close(self.stop)

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                names = self._graph.node_names()
            except Exception:  # noqa: BLE001 - the graph is being torn down: nothing more to see
                return
            now = time.monotonic() - self._begin
            with self._lock:
                for name in names:
                    self.first_seen.setdefault(name, now)
            self._stop.wait(self._interval)

    def seen(self) -> dict[str, float]:
        """A copy of :attr:`first_seen`."""
        with self._lock:
            return dict(self.first_seen)

    def stop(self) -> dict[str, float]:
        """Stop watching (idempotent); returns :attr:`first_seen`."""
        self._stop.set()
        self._thread.join(timeout=2.0)
        return self.seen()


def node_appeared(s: Session, check_id: str, watch: NodeWatch, node: str, command: str,
                  before: float | None = None) -> bool:
    """Record ``check_id``: ``node`` (fully qualified, ``/print_forever``) was in the graph while the script ran.

    Args:
        command: the command that starts it, for the expected text ("ros2 run python_package_with_a_node ...").
        before: seconds after the watch started (e.g. when Ctrl+C was pressed): a node first seen later
            does not count (a script that only got to it after Ctrl+C).
    """
    seen = watch.seen()
    expected = f"node {node} appears in the graph (started by `{command}`)"
    if node in seen and (before is None or seen[node] <= before):
        return s.record(check_id, True, f"{node} appeared {seen[node]:.1f} s after your script started", expected)
    if node in seen:
        return s.record(check_id, False, f"{node} appeared only {seen[node]:.1f} s after your script started, "
                        f"after Ctrl+C ({before:.1f} s): a command before it was still running", expected)
    others = ", ".join(sorted(seen)) or "no node at all"
    return s.record(check_id, False, f"no node {node} appeared while your script ran; `ros2 node list` showed: {others}",
                    expected)


__all__ = ["NodeWatch", "node_appeared"]
