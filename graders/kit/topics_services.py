"""Helpers of the interface lessons (publisher-subscriber, service-server-client).

Private to those graders: per-part skipping (a lesson grades two executables
independently, so one missing executable must not skip the other's checks),
the learner node's own endpoints (``ros2 node info``), the workspace's
``package_with_interfaces`` types, number matching in log records, and a
stand-in service server that can answer late without blocking any executor.
"""

from __future__ import annotations

import re
import threading
import time
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from course.grading import GradingSession
from course.probes import RateStats, wait_until

INTERFACES = "package_with_interfaces"
#: Endpoints every rclpy node has; not the learner's doing, left out of "observed" lists.
_STANDARD_TOPICS = {"/rosout", "/parameter_events"}
_STANDARD_SERVICE_SUFFIXES = ("/describe_parameters", "/get_parameter_types", "/get_parameters",
                              "/list_parameters", "/set_parameters", "/set_parameters_atomically",
                              "/get_type_description")
_NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")


# --- recording ---------------------------------------------------------------

def skip_checks(s: GradingSession, check_ids: Iterable[str], reason: str) -> None:
    """Record every check in ``check_ids`` not recorded yet as failed because of ``reason``.

    Unlike :meth:`GradingSession.skip_remaining` this leaves the other part of
    the lesson (the other executable) to be graded.
    """
    for check_id in check_ids:
        if check_id not in s.results:
            s.record(check_id, False, f"not checked: {reason}", "(depends on the failed check above)")


def give_up(s: GradingSession, checks: list[str], reason: str, proc) -> None:
    """Stop grading one executable: skip its ``checks`` but the last (with ``reason``), which is its
    SIGINT-exit check, recorded by pressing Ctrl+C on ``proc`` (``graders._common.record_sigint_exit``)."""
    from graders._common import record_sigint_exit  # noqa: PLC0415

    skip_checks(s, checks[:-1], reason)
    record_sigint_exit(s, checks[-1], proc)


def require_executable(s: GradingSession, check_id: str, package: str, executable: str,
                       dependents: Iterable[str]) -> Path | None:
    """Record ``check_id`` on whether ``ros2 run package executable`` finds it (ros2run's lookup).

    On failure, the ``dependents`` checks are skipped. Returns the path or None.
    """
    path, observed = s.find_executable(package, executable)
    s.record(check_id, path is not None, observed,
             f"ros2 run {package} {executable} finds install/{package}/lib/{package}/{executable}")
    if path is None:
        skip_checks(s, dependents, f"there is no {executable} executable to run")
    return path


def record_depends(s: GradingSession, check_id: str, package: str,
                   needed: tuple[str, ...] = ("rclpy", INTERFACES)) -> bool:
    """Record ``check_id`` on whether ``package``'s package.xml declares the ``needed`` dependencies.

    Seed ch. 18.1 creates the package with ``--dependencies rclpy
    package_with_interfaces``; without the second one ``colcon build
    --packages-up-to`` does not build the interfaces first.
    """
    from course.build import find_packages  # noqa: PLC0415

    expected = ", ".join(f"<depend>{n}</depend>" for n in needed)
    found = find_packages(s.workspace_root / "src").get(package)
    if found is None:
        return s.record(check_id, False, f"no package {package} in src/", expected)
    pkg = found[1]
    deps = {d.name for d in (*pkg.build_depends, *pkg.exec_depends)}
    missing = [n for n in needed if n not in deps]
    return s.record(check_id, not missing, f"package.xml dependencies: {', '.join(sorted(deps)) or 'none'}"
                    + (f" (missing {', '.join(missing)})" if missing else ""), expected,
                    fraction=(len(needed) - len(missing)) / len(needed))


def workspace_types(s: GradingSession, kind: str, name: str) -> Any | None:
    """``package_with_interfaces.<kind>.<name>`` of this workspace, or None when it is not built.

    Loaded through ``GradingSession.interface_type``; when it fails, every
    unrecorded check is skipped.

    The learner's nodes could not import them either; the depends check
    (recorded before) tells why.
    """
    from course.errors import NotGradable  # noqa: PLC0415

    try:
        return s.interface_type(INTERFACES, kind, name)
    except NotGradable as exc:
        s.skip_remaining(f"{exc.message} (colcon build --packages-up-to builds it only when package.xml "
                         f"depends on {INTERFACES})")
        return None


# --- the learner's node and its endpoints ------------------------------------

def launch_node(s: GradingSession, check_id: str, path: Path, executable: str, node: str,
                timeout: float = 10.0, grace: float = 3.0):
    """Start ``executable`` and record ``check_id`` on whether a node called ``node`` appears.

    :func:`graders._common.wait_for_node`, ignoring the nodes already in the
    graph before the launch. Later processes of a check can take about 3 s to
    be discovered (Fast DDS announcement period), hence ``timeout`` seconds.

    Returns:
        ``(process, name)``: the LearnerProcess, and the node name to inspect
        (``node``, else the only new node, e.g. a misnamed one, else None).
    """
    from graders._common import wait_for_node  # noqa: PLC0415

    before = set(s.ros.node_names())
    proc = s.launch(path, executable)
    if wait_for_node(s, check_id, proc, node, timeout, grace, before=before):
        return proc, node
    plain = [n for n in s.ros.node_names() if n not in before and n.count("/") == 1]
    return proc, (plain[0].lstrip("/") if len(plain) == 1 else None)


def endpoints(s: GradingSession, node: str, kind: str) -> dict[str, list[str]]:
    """The node's own ``publishers``, ``subscriptions`` or ``services``: name -> type names.

    What ``ros2 node info`` lists, without the endpoints every rclpy node has
    (``/rosout``, ``/parameter_events``, parameter and type description services).
    Empty when the node is not (or no longer) in the graph.
    """
    from rclpy.node import NodeNameNonExistentError  # noqa: PLC0415

    graph = s.ros.node
    query = {"publishers": graph.get_publisher_names_and_types_by_node,
             "subscriptions": graph.get_subscriber_names_and_types_by_node,
             "services": graph.get_service_names_and_types_by_node}[kind]
    try:
        found = query(node, "/")
    except (NodeNameNonExistentError, RuntimeError):
        return {}
    out = {}
    for name, types in found:
        if name in _STANDARD_TOPICS or name.endswith(_STANDARD_SERVICE_SUFFIXES):
            continue
        out[name] = list(types)
    return out


def wait_for_endpoint(s: GradingSession, node: str, kind: str, name: str, timeout: float,
                      abort: Callable[[], bool] | None = None) -> dict[str, list[str]]:
    """Poll :func:`endpoints` until ``name`` is among them or ``timeout`` seconds pass; returns the last listing.

    Discovery of a node's endpoints can lag behind the node itself by a few
    hundred milliseconds; any endpoint at all ends the wait early after 1 s
    more (a misnamed topic will not rename itself).
    """
    seen: dict[str, list[str]] = {}
    first_other: list[float] = []

    def done() -> bool:
        seen.clear()
        seen.update(endpoints(s, node, kind))
        if name in seen:
            return True
        if seen and not first_other:
            first_other.append(time.monotonic())
        return bool(first_other) and time.monotonic() - first_other[0] > 1.0

    wait_until(done, timeout, interval=0.05, abort=abort)
    return dict(seen)


def describe_endpoints(found: dict[str, list[str]]) -> str:
    """``/a [pkg/msg/T], /b [...]`` or ``none``."""
    return ", ".join(f"{n} [{', '.join(t)}]" for n, t in sorted(found.items())) or "none"


def pick_endpoint(found: dict[str, list[str]], name: str, type_name: str) -> str | None:
    """``name`` if present, else the only endpoint of type ``type_name`` (to grade a misnamed topic's behaviour)."""
    if name in found:
        return name
    same_type = [n for n, types in found.items() if type_name in types]
    return same_type[0] if len(same_type) == 1 else None


# --- the workspace's interface types -------------------------------------------

# --- text matching -------------------------------------------------------------

def numbers_in(text: str) -> list[float]:
    """Every number written in ``text`` (``12``, ``-3.25``, ``1e3``), as floats."""
    out = []
    for token in _NUMBER.findall(text):
        try:
            out.append(float(token))
        except ValueError:
            continue
    return out


def has_integer(text: str, value: int) -> bool:
    """True when ``value`` is written in ``text`` as a whole number (not part of a longer one)."""
    return re.search(rf"(?<![\d.]){value}(?![\d])", text) is not None


def has_point(text: str, point: tuple[float, float, float], tolerance: float = 0.006) -> bool:
    """True when the three coordinates are written in ``text`` (rounded to 2 decimals is fine)."""
    found = numbers_in(text)
    return all(any(abs(v - c) <= tolerance for v in found) for c in point)


# --- a service server the grader plays ----------------------------------------

class DeferredServer:
    """A stand-in service server that may answer ``delay`` seconds late without blocking anything.

    rclpy's service callbacks must return the response, so a late answer
    would block an executor thread (and with it the grader's /rosout
    subscription). This server lives on a node of its own that no executor
    spins: a thread takes requests as they arrive (every 5 ms), records their
    arrival time, and sends each response once it is due.

    Args:
        handler: ``handler(index, request, response) -> response``; ``index`` counts calls from 0.
        delay: seconds between a request's arrival and its answer; can be changed while running.

    Attributes:
        calls: ``(time.monotonic() seconds, request)`` per call, oldest first.
        sent: per call, when the client sent it (the request's DDS source
            timestamp, system clock seconds): rates use these, so delivery
            delays on a loaded machine do not count against the client.
        answers: ``(time.monotonic() seconds sent, response)`` per answer sent.
    """

    POLL = 0.005  # seconds

    def __init__(self, s: GradingSession, srv_type: type, name: str,
                 handler: Callable[[int, Any, Any], Any], delay: float = 0.0) -> None:
        import rclpy  # noqa: PLC0415
        from rclpy.parameter import Parameter  # noqa: PLC0415

        self.delay = delay
        self.calls: list[tuple[float, Any]] = []
        self.sent: list[float] = []
        self.answers: list[tuple[float, Any]] = []
        self._srv_type = srv_type
        self._handler = handler
        self._lock = threading.Lock()
        self._due: list[tuple[float, Any, Any]] = []
        self._stop = threading.Event()
        self._node = rclpy.create_node(
            "_ros2course_stand_in_server", context=s.ros.context, enable_rosout=False,
            start_parameter_services=False,
            parameter_overrides=[Parameter("start_type_description_service", value=False)])
        # The callback is never run: no executor spins this node; _run takes the requests.
        self._service = self._node.create_service(srv_type, name, lambda request, response: response)
        self._thread = threading.Thread(target=self._run, daemon=True, name="ros2course-stand-in-server")
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.is_set():
            now = time.monotonic()
            try:
                with self._service.handle:
                    taken = self._service.handle.service_take_request(self._srv_type.Request)
            except Exception:  # noqa: BLE001 - destroyed while closing
                return
            if taken is not None and taken[0] is not None:
                request, header = taken
                sent = getattr(header, "source_timestamp", 0) * 1e-9 or time.time()
                with self._lock:
                    index = len(self.calls)
                    self.calls.append((now, request))
                    self.sent.append(sent)
                    response = self._handler(index, request, self._srv_type.Response())
                    self._due.append((now + self.delay, response, header))
                continue  # take everything queued before sleeping
            self._send_due(now)
            self._stop.wait(self.POLL)

    def _send_due(self, now: float) -> None:
        with self._lock:
            due = [d for d in self._due if d[0] <= now]
            self._due = [d for d in self._due if d[0] > now]
        for _, response, header in due:
            try:
                self._service.send_response(response, header)
            except Exception:  # noqa: BLE001 - the client went away: nothing to answer
                continue
            with self._lock:
                self.answers.append((time.monotonic(), response))

    def calls_since(self, begin: float) -> list[tuple[float, Any]]:
        """Calls that arrived at or after ``begin`` (``time.monotonic()`` seconds)."""
        with self._lock:
            return [c for c in self.calls if c[0] >= begin]

    def send_stamps(self, begin: float = 0.0, count: int | None = None) -> list[float]:
        """The client's send stamps (seconds) of the first ``count`` calls arriving after ``begin``."""
        with self._lock:
            stamps = [sent for (arrived, _), sent in zip(self.calls, self.sent, strict=True) if arrived >= begin]
        return stamps[:count] if count else stamps

    def rate(self, begin: float = 0.0, count: int | None = None) -> RateStats | None:
        """Call rate over :meth:`send_stamps` (``ros2 topic hz``'s 1 / mean interval), not arrival times."""
        return RateStats.from_times(self.send_stamps(begin, count))

    def close(self) -> None:
        """Stop answering and remove the service from the graph."""
        self._stop.set()
        self._thread.join(timeout=2.0)
        self._node.destroy_node()
