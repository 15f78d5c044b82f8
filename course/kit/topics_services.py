"""Kit steps of the interface lessons (custom-interfaces, publisher-subscriber, service-server-client).

The workspace's ``package_with_interfaces`` types (as the grader and as a
fresh interpreter see them), a learner node's own endpoints (``ros2 node
info``), the grader's own publisher, number matching in log records, a
stand-in service server that can answer late without blocking any executor.
"""

from __future__ import annotations

import contextlib
import json
import re
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from ros2course.errors import NotGradable
from ros2course.grade.checklist import Unmet
from ros2course.kit.session_protocol import Session
from ros2course import sandbox
from ros2course.run.probes import RateStats, wait_until
from ros2course.kit.judge import STANDARD_TOPICS

INTERFACES = "package_with_interfaces"
_STANDARD_SERVICE_SUFFIXES = ("/describe_parameters", "/get_parameter_types", "/get_parameters",
                              "/list_parameters", "/set_parameters", "/set_parameters_atomically",
                              "/get_type_description")
_NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")


# --- the workspace's interface types ---------------------------------------------

def workspace_types(s: Session, kind: str, name: str) -> Any:
    """``package_with_interfaces.<kind>.<name>`` of this workspace (:meth:`Session.interface_type`).

    The learner's nodes could not import it either when it fails; the
    ``depends`` check (recorded before) tells why.

    Raises:
        Unmet: the interface package is not built or does not load (every unrecorded check of the
            current part becomes "not checked").
    """
    try:
        return s.interface_type(INTERFACES, kind, name)
    except NotGradable as exc:
        raise Unmet(f"{exc.message} (colcon build --packages-up-to builds it only when package.xml "
                    f"depends on {INTERFACES})") from exc


#: Run in a fresh interpreter with the workspace sourced: import each type, print its fields as JSON.
_FIELDS_PROBE = r"""
import json, sys
out = {}
for package, kind, name in json.loads(sys.argv[1]):
    key = f"{package}/{kind}/{name}"
    try:
        cls = getattr(__import__(f"{package}.{kind}", fromlist=[name]), name)
        cls.__class__.__import_type_support__()  # loads the generated C extension and typesupport
        if kind == "msg":
            out[key] = cls.get_fields_and_field_types()
        else:
            out[key + ".Request"] = cls.Request.get_fields_and_field_types()
            out[key + ".Response"] = cls.Response.get_fields_and_field_types()
    except Exception as exc:
        out[key + ".error"] = f"{type(exc).__name__}: {exc}"
print(json.dumps(out))
"""


def generated_fields(s: Session, types: Iterable[tuple[str, str, str]], timeout: float = 60.0) -> dict:
    """Fields of generated interface types as a fresh ``python3`` in the sourced workspace imports them.

    A Python process holds one build of an interface package
    (:mod:`ros2course.ros.interfaces`) and ``dev validate`` grades many variants in one
    process, so the types are imported in a new interpreter started with
    ``s.overlay()`` (``source install/setup.bash``), the way a learner's node would.

    Args:
        types: ``(package, "msg" | "srv", name)`` triples.
        timeout: seconds for the whole import.

    Returns:
        ``"pkg/msg/Name"`` -> ``{field: type}`` as ``get_fields_and_field_types()`` spells it
        (``"pkg/srv/Name.Request"`` and ``".Response"`` for a service); ``"<key>.error"`` -> a
        sentence when a type cannot be imported.
    """
    types = [list(t) for t in types]
    keys = ["/".join(t) for t in types]
    try:
        proc = sandbox.run([sys.executable, "-c", _FIELDS_PROBE, json.dumps(types)], env=s.overlay(),
                           cwd=s.workspace_root, capture_output=True, text=True, timeout=timeout, check=False)
    except subprocess.TimeoutExpired:
        return {f"{k}.error": f"importing the generated types took more than {timeout:.0f} s" for k in keys}
    lines = proc.stdout.strip().splitlines()
    try:
        return json.loads(lines[-1])
    except (IndexError, json.JSONDecodeError):
        last = (proc.stderr.strip().splitlines() or ["no output"])[-1]
        return {f"{k}.error": last for k in keys}


def fields(s: Session, check_id: str, what: str, observed: dict | None, expected: dict,
           error: str | None = None) -> bool:
    """Record ``check_id`` on whether a type has exactly the ``expected`` fields (name -> type).

    Partial credit per field with the right name and type; unexpected extra
    fields cost one share. The fields must come in ``expected``'s order (a
    message's fields are serialized in the order its file declares them:
    the same fields in another order are another layout); the right fields
    in another order lose one share. ``observed`` None means the type cannot be
    imported (``error`` says why). The rule is the tutorial's (seed ch. 17.4, 17.6).
    """
    wanted = ", ".join(f"{t} {n}" for n, t in expected.items())
    if observed is None:
        return s.record(check_id, False, f"{what} cannot be imported: {error}", f"{what} with {wanted}")
    problems = []
    good = 0
    for name, type_name in expected.items():
        got = observed.get(name)
        if got is None:
            problems.append(f"no field {name}")
        elif got != type_name:
            problems.append(f"{name} is {got}, not {type_name}")
        else:
            good += 1
    extra = [f"{t} {n}" for n, t in observed.items() if n not in expected]
    if extra:
        problems.append("unexpected field(s): " + ", ".join(extra))
    if not problems and list(observed) != list(expected):  # the order is the message's layout (CDR, in order)
        problems.append("the fields are in another order than " + ", ".join(expected))
        good -= 1
    total = len(expected) + (1 if extra else 0)
    shown = ", ".join(f"{t} {n}" for n, t in observed.items()) or "no fields"
    return s.record(check_id, not problems, f"{what}: {shown}" + (f" ({'; '.join(problems)})" if problems else ""),
                    f"{what}: {wanted}", fraction=good / total)


# --- the learner's node and its endpoints ------------------------------------

def endpoints(graph: Any, node: str | None, kind: str) -> dict[str, list[str]]:
    """The node's own ``publishers``, ``subscriptions`` or ``services``: name -> type names.

    What ``ros2 node info`` lists, without the endpoints every rclpy node has
    (``/rosout``, ``/parameter_events``, parameter and type description services).
    Empty when ``node`` is None or not (or no longer) in ``graph`` (a RosSession).
    """
    return {name: types for name, types in _listing(graph, node, kind).items()
            if name not in STANDARD_TOPICS and not name.endswith(_STANDARD_SERVICE_SUFFIXES)}


def _listing(graph: Any, node: str | None, kind: str) -> dict[str, list[str]]:
    """Every endpoint of ``kind`` the graph knows for ``node``, the standard ones included."""
    from rclpy.node import NodeNameNonExistentError  # noqa: PLC0415 - rclpy only when grading (graders load for CHECKS without ROS)

    if node is None:
        return {}
    query = {"publishers": graph.node.get_publisher_names_and_types_by_node,
             "subscriptions": graph.node.get_subscriber_names_and_types_by_node,
             "services": graph.node.get_service_names_and_types_by_node}[kind]
    try:
        return {name: list(types) for name, types in query(node, "/")}
    except (NodeNameNonExistentError, RuntimeError):
        return {}


#: Seconds :func:`wait_for_endpoint` waits beyond its ``timeout`` for the first sign that the node's
#: endpoints are being discovered at all (on a loaded machine a node is seen well before its endpoints).
DISCOVERY_GRACE = 6.0


def wait_for_endpoint(s: Session, node: str | None, kind: str, name: str, timeout: float,
                      abort: Callable[[], bool] | None = None, graph: Any = None) -> dict[str, list[str]]:
    """Poll :func:`endpoints` of ``node`` in ``graph`` (default ``s.graph``) until ``name`` is among them.

    Returns the last listing.

    The deadline is tied to what discovery shows, as ``ros2 node info`` would
    see it a moment later: ``timeout`` seconds from the first endpoint of the
    node that the graph shows (every rclpy and rclcpp node publishes
    ``/rosout``, created before any endpoint of the learner's code), and at
    most :data:`DISCOVERY_GRACE` seconds more while none is shown yet (two
    gradings at once on 2 cores: the node's endpoints can arrive seconds after
    the node). Any own endpoint at all ends the wait early after 1 s more (a
    misnamed topic will not rename itself). Timed as phase ``start``. ``{}``
    at once when ``node`` is None.

    Args:
        node: the node's name in the root namespace (as ``ros2 node list`` shows it, without the ``/``), or None.
        kind: ``publishers``, ``subscriptions`` or ``services``.
        name: the endpoint waited for (``/topic``).
        timeout: seconds (see above).
        abort: ends the wait early when it returns True (e.g. the process ended).
    """
    seen: dict[str, list[str]] = {}
    if node is None:
        return seen
    graph = graph or s.graph
    began = time.monotonic()
    first_other: list[float] = []
    discovered: list[float] = []

    def done() -> bool:
        seen.clear()
        seen.update(endpoints(graph, node, kind))
        if name in seen:
            return True
        now = time.monotonic()
        if seen and not first_other:
            first_other.append(now)
        if not discovered and (seen or _listing(graph, node, kind) or _listing(graph, node, "publishers")):
            discovered.append(now)
        if bool(first_other) and now - first_other[0] > 1.0:
            return True
        return now - (discovered[0] if discovered else began) > timeout

    with s.phase("start"):
        wait_until(done, timeout + DISCOVERY_GRACE, interval=0.05, abort=abort)
    return dict(seen)


def describe_endpoints(found: dict[str, list[str]]) -> str:
    """``/a [pkg/msg/T], /b [...]`` or ``none``."""
    return ", ".join(f"{n} [{', '.join(t)}]" for n, t in sorted(found.items())) or "none"


def pick_endpoint(found: dict[str, list[str]], name: str, type_name: str) -> str | None:
    """The endpoint to grade: ``name`` when it has ``type_name``, else the only endpoint of that type.

    A misnamed topic is still graded on what flows through it. None when
    there is no endpoint of ``type_name`` to use.
    """
    if name in found:
        return name if type_name in found[name] else None
    same_type = [n for n, types in found.items() if type_name in types]
    return same_type[0] if len(same_type) == 1 else None


_VERBS = {"publishers": "publishes", "subscriptions": "subscribes to", "services": "serves"}


def own_endpoint(s: Session, check_id: str, node: Any, kind: str, name: str, type_name: str, *,
                 none: str, where: str, graph: Any = None) -> tuple[str, str]:
    """Record ``check_id``: ``node`` (a :class:`~ros2course.kit.StartedNode`) has its own ``name`` of ``type_name``.

    ``kind`` is ``publishers``, ``subscriptions`` or ``services`` (what ``ros2
    node info`` lists); waits up to 3 s (:func:`wait_for_endpoint`) in
    ``graph`` (default ``s.graph``). A misnamed endpoint of the right type is
    still graded where it is (:func:`pick_endpoint`).

    Args:
        none: the reason given when there is no endpoint of ``type_name`` at all.
        where: how the grader uses the endpoint, e.g. "on" / "called at": the note
            returned for a misnamed one reads " (on /x, the topic your node uses)".

    Returns:
        ``(endpoint to grade, note)``; the note is "" when it is ``name``.

    Raises:
        Unmet: (``none``) no endpoint of ``type_name``.
    """
    graph = graph or s.graph
    found = wait_for_endpoint(s, node.name, kind, name, 3.0, abort=node.ended, graph=graph)
    ok = type_name in found.get(name, [])
    others = "" if ok or kind == "services" else f"; topics in the graph: {learner_topics(graph)}"
    s.record(check_id, ok, f"{node.name or 'the node'} {_VERBS[kind]}: {describe_endpoints(found)}{others}",
             f"{name} [{type_name}]")
    target = pick_endpoint(found, name, type_name)
    if target is None:
        raise Unmet(none)
    noun = "name your server uses" if kind == "services" else "topic your node uses"
    return target, ("" if target == name else f" ({where} {target}, the {noun})")


def learner_topics(graph: Any) -> str:
    """What ``ros2 topic list -t`` shows in ``graph``, without ROS's own topics and the grader's probes.

    A topic counts when a node not starting with ``_`` (the grader's hidden
    nodes) publishes or subscribes to it.
    """
    def learners(topic: str) -> bool:
        infos = [*graph.node.get_publishers_info_by_topic(topic), *graph.node.get_subscriptions_info_by_topic(topic)]
        return any(not info.node_name.startswith("_") for info in infos)

    return describe_endpoints({n: types for n, types in graph.topic_types().items()
                               if n not in STANDARD_TOPICS and learners(n)})


# --- the grader's side of a topic ---------------------------------------------------

def reliable_qos(depth: int = 10) -> Any:
    """Keep-last ``depth``, reliable: the QoS of the grader's probes and publisher.

    Matches a learner's ``qos_profile=1`` (reliable by default in rclpy) and
    keeps a burst of ``depth`` messages a loaded machine delivers at once.
    """
    from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy  # noqa: PLC0415 - rclpy only when grading (graders load for CHECKS without ROS)

    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=ReliabilityPolicy.RELIABLE)


def listen(s: Session, topic: str, msg_type: type, graph: Any = None) -> Any:
    """A :class:`~ros2course.run.probes.TopicProbe` on ``topic`` in ``graph`` (default ``s.graph``), :func:`reliable_qos`.

    Create it before the learner's publisher starts: no message is missed.
    """
    return (graph or s.graph).topic(topic, msg_type, reliable_qos())


@contextlib.contextmanager
def publisher(s: Session, topic: str, msg_type: type, graph: Any = None) -> Iterator[Any]:
    """The grader's own publisher on ``topic`` in ``graph`` (default ``s.graph``; like ``ros2 topic pub``).

    Removed on exit.

    Yields the rclpy publisher (``publish(msg)``, ``get_subscription_count()``),
    :func:`reliable_qos`.
    """
    node = (graph or s.graph).node
    pub = node.create_publisher(msg_type, topic, reliable_qos())
    try:
        yield pub
    finally:
        node.destroy_publisher(pub)


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
    arrival time, and sends each response once it is due. Nothing exists in
    the graph before :meth:`offer`.

    Args:
        graph: the :class:`~ros2course.run.probes.RosSession` to serve in.
        handler: ``handler(index, request, response) -> response``; ``index`` counts calls from 0.
        delay: seconds between a request's arrival and its answer; can be changed while running.

    Attributes:
        calls: ``(time.monotonic() seconds, request)`` per call, oldest first.
        sequence_numbers: per call, the request's sequence number (``request_id.sequence_number`` of the
            ``rmw_service_info_t``): the client's own count of the requests it sent, from 1, so a first call
            numbered above 1 was preceded by requests nothing answered (sent while no server existed).
        sent: per call, when the client sent it (the request's DDS source
            timestamp, system clock seconds): rates use these, so delivery
            delays on a loaded machine do not count against the client.
        answers: ``(time.monotonic() seconds sent, response)`` per answer sent.
    """

    POLL = 0.005  # seconds

    def __init__(self, graph: Any, srv_type: type, name: str,
                 handler: Callable[[int, Any, Any], Any], delay: float = 0.0) -> None:
        self.delay = delay
        self.calls: list[tuple[float, Any]] = []
        self.sent: list[float] = []
        self.sequence_numbers: list[int] = []
        self.answers: list[tuple[float, Any]] = []
        self._graph = graph
        self._name = name
        self._srv_type = srv_type
        self._handler = handler
        self._lock = threading.Lock()
        self._due: list[tuple[float, Any, Any]] = []
        self._stop = threading.Event()
        self._node = None
        self._service = None
        self._thread: threading.Thread | None = None

    def offer(self) -> None:
        """Create the service (it appears in the graph) and start answering."""
        import rclpy  # noqa: PLC0415 - rclpy only when grading (graders load for CHECKS without ROS)
        from rclpy.parameter import Parameter  # noqa: PLC0415 - rclpy only when grading (graders load for CHECKS without ROS)

        self._node = rclpy.create_node(
            "_ros2course_stand_in_server", context=self._graph.context, enable_rosout=False,
            start_parameter_services=False,
            parameter_overrides=[Parameter("start_type_description_service", value=False)])
        # The callback is never run: no executor spins this node; _run takes the requests.
        self._service = self._node.create_service(self._srv_type, self._name, lambda request, response: response)
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
                    self.sequence_numbers.append(int(getattr(getattr(header, "request_id", None),
                                                             "sequence_number", 0) or 0))
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
        """Stop answering and remove the service from the graph (nothing to do before :meth:`offer`)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        if self._node is not None:
            self._node.destroy_node()
            self._node = None


def stand_in_server(s: Session, srv_type: type, name: str,
                    handler: Callable[[int, Any, Any], Any], graph: Any = None) -> DeferredServer:
    """A :class:`DeferredServer` for ``name`` in ``graph`` (default ``s.graph``), not offered yet, closed with the part.

    Create it before starting the learner's client (``kit.start_node``): the
    closing actions run newest first, so the client's Ctrl+C check runs while
    the service still exists (what a learner would do), then the server goes.
    Call :meth:`DeferredServer.offer` when the service is to appear.
    """
    server = DeferredServer(graph or s.graph, srv_type, name, handler)
    s.on_close(server.close)
    return server
