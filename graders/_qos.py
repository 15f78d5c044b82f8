"""The qos lesson's helper: one function per part of graders/qos.py (sensor, config, monitor, cli), each
recording that part's checks, and the grader-side endpoints they use: probes of chosen QoS profiles,
offered/requested QoS, a feed, an oracle.

What the kit lacks for this lesson (and would offer in ``ros2course.kit`` if a
second lesson needed it): a topic probe with a QoS profile of the grader's
choice that says whether it has matched a publisher (``Subscription.get_publisher_count``)
and can be removed; the QoS a node's endpoint offers or requests
(``Node.get_publishers_info_by_topic`` / ``get_subscriptions_info_by_topic``,
what ``ros2 topic info --verbose`` prints); and the compatibility rule of
``rclpy.qos.qos_check_compatible`` (the rule rmw applies when it matches a
publisher with a subscription: ROS 2 docs, "Quality of Service settings",
"QoS compatibilities").

A remote endpoint's history and depth are not in the graph (rmw_fastrtps
reports ``UNKNOWN``, depth 0: ``ros2 topic info --verbose`` prints
``History (Depth): UNKNOWN``), so a publisher's depth is judged by what a
late-joining TRANSIENT_LOCAL subscription receives, never read from the graph.

rclpy and the message packages are imported inside the functions that grade: a grader module
is also loaded for its CHECKS alone (``ros2course list``, ``hint``), where ROS is not needed.
"""

from __future__ import annotations

import copy
import math
import random
import re
import threading
from collections.abc import Callable, Iterable
from typing import Any

from ros2course import kit
from ros2course.kit import LATE_DELIVERY, Session, Unmet, scripts, wait_until
from ros2course.kit import params as kit_params
from ros2course.kit import topics_services as ts

_RANDOM = random.SystemRandom()


# --- profiles -------------------------------------------------------------------------

def sensor_qos() -> Any:
    """``rclpy.qos.qos_profile_sensor_data``: BEST_EFFORT, VOLATILE, KEEP_LAST 5 (rmw/qos_profiles.h)."""
    from rclpy.qos import qos_profile_sensor_data  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

    return qos_profile_sensor_data


def profile(*, reliable: bool, transient_local: bool, depth: int) -> Any:
    """A KEEP_LAST ``depth`` profile, RELIABLE or BEST_EFFORT, TRANSIENT_LOCAL or VOLATILE."""
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth,
                      reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL if transient_local else DurabilityPolicy.VOLATILE)


def word(policy: Any) -> str:
    """``ReliabilityPolicy.BEST_EFFORT`` -> ``BEST_EFFORT`` (the word ``ros2 topic info --verbose`` prints)."""
    return str(getattr(policy, "name", policy)).upper()


def describe(qos: Any) -> str:
    """``BEST_EFFORT, VOLATILE`` (the two policies the graph reports that decide matching here)."""
    return f"{word(qos.reliability)}, {word(qos.durability)}"


def compatible(offered: Any, requested: Any) -> tuple[bool, str]:
    """Whether a publisher offering ``offered`` matches a subscription requesting ``requested``.

    ``rclpy.qos.qos_check_compatible`` (rmw_qos_profile_check_compatible): ERROR means they never
    match (e.g. BEST_EFFORT offered, RELIABLE requested; VOLATILE offered, TRANSIENT_LOCAL
    requested); a WARNING (a policy unknown to the graph) still counts as compatible.

    Returns:
        ``(compatible, reason)``; the reason is rmw's sentence, "" when compatible.
    """
    from rclpy.qos import QoSCompatibility, qos_check_compatible  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

    result, reason = qos_check_compatible(as_reported(offered), as_reported(requested))
    if result == QoSCompatibility.ERROR:
        return False, reason.strip().rstrip(";") or "incompatible QoS"
    return True, ""


def as_reported(qos: Any) -> Any:
    """``qos`` with its unspecified (system default) policies as the graph reports them once resolved.

    A profile made in code leaves deadline, lifespan and liveliness lease at 0 ("system default")
    and liveliness at SYSTEM_DEFAULT; rmw_fastrtps resolves them to Infinite and AUTOMATIC, which is
    what ``get_*_info_by_topic`` (and ``ros2 topic info --verbose``) report. ``qos_check_compatible``
    between such a profile and a reported one would see "a deadline on one side only" (an ERROR
    that the endpoints themselves never have), so a profile made in code is resolved first.
    Profiles from the graph come back unchanged.
    """
    from rclpy.duration import Infinite  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)
    from rclpy.qos import LivelinessPolicy  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

    resolved = copy.copy(qos)
    for field in ("deadline", "lifespan", "liveliness_lease_duration"):
        if getattr(resolved, field).nanoseconds == 0:
            setattr(resolved, field, Infinite)
    if resolved.liveliness == LivelinessPolicy.SYSTEM_DEFAULT:
        resolved.liveliness = LivelinessPolicy.AUTOMATIC
    return resolved


def endpoint_qos(graph: Any, topic: str, node: str | None, kind: str) -> list[Any]:
    """QoS profiles of ``node``'s (no leading ``/``) ``publishers`` or ``subscriptions`` on ``topic`` in ``graph``.

    What ``ros2 topic info --verbose TOPIC`` lists per endpoint (``Node.get_publishers_info_by_topic``).
    Empty when ``node`` is None or has no such endpoint.
    """
    if node is None:
        return []
    query = graph.node.get_publishers_info_by_topic if kind == "publishers" else graph.node.get_subscriptions_info_by_topic
    name = node.rsplit("/", 1)[-1]
    return [info.qos_profile for info in query(topic) if info.node_name == name]


def wait_endpoint_qos(graph: Any, topic: str, node: str | None, kind: str, timeout: float = 2.0) -> list[Any]:
    """:func:`endpoint_qos`, polled up to ``timeout`` seconds until the endpoint shows."""
    found: list[Any] = []

    def seen() -> bool:
        found[:] = endpoint_qos(graph, topic, node, kind)
        return bool(found)

    _wait(seen, timeout)
    return found


def _wait(predicate: Callable[[], bool], timeout: float, abort: Callable[[], bool] | None = None) -> bool:
    return wait_until(predicate, timeout, interval=0.02, abort=abort)


# --- a probe of a chosen profile --------------------------------------------------------

class Probe:
    """A subscription of the grader's node in ``graph`` with the QoS ``qos``, recording what arrives.

    Args:
        graph: a :class:`~ros2course.run.probes.RosSession` (its ``node`` is spun by the session).
        topic: the topic name; msg_type: the generated message class; qos: an rclpy ``QoSProfile``.

    Attributes:
        qos: the requested profile.
    """

    def __init__(self, graph: Any, topic: str, msg_type: type, qos: Any) -> None:
        from rclpy.event_handler import SubscriptionEventCallbacks  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

        self.qos = qos
        self.topic = topic
        self._lock = threading.Lock()
        self._messages: list[Any] = []
        #: set when rmw reports a publisher whose offer cannot match this request (the
        #: incompatible-QoS event; it replaces rclpy's default warning, which would print in
        #: the learner's terminal during ``check``).
        self.incompatible = threading.Event()
        callbacks = SubscriptionEventCallbacks(incompatible_qos=lambda _status: self.incompatible.set())
        self._sub = graph.node.create_subscription(msg_type, topic, self._on_message, qos,
                                                   event_callbacks=callbacks)

    def _on_message(self, msg: Any) -> None:
        with self._lock:
            self._messages.append(msg)

    def messages(self) -> list[Any]:
        """Messages so far, oldest first."""
        with self._lock:
            return list(self._messages)

    def matched(self) -> int:
        """Publishers matched with this subscription (``Subscription.get_publisher_count``)."""
        try:
            return self._sub.get_publisher_count()
        except Exception:  # noqa: BLE001 - destroyed meanwhile
            return 0


# --- the grader's own publishers ------------------------------------------------------------

#: Units the grader's configuration names (random per check, so a hard-coded log cannot pass).
UNITS = ("kelvin", "fahrenheit", "rankine", "reaumur", "delisle", "newton")


#: Seconds the configuration node is listened to before anything is set: a message then was not asked for.
UNASKED_WINDOW = 1.0
#: Seconds for the second instance (units set on its command line) to start, be discovered and publish.
START_PARAMETER_TIMEOUT = 10.0


def random_units(other_than: Iterable[str] = ()) -> str:
    """One of :data:`UNITS`, drawn for this check, none of ``other_than``."""
    return _RANDOM.choice([u for u in UNITS if u not in set(other_than)])


class Feed:
    """The grader's sensor publisher and latched configuration, for grading a monitor node.

    Publishes ``units: <random unit>`` once on ``config_topic`` (RELIABLE, TRANSIENT_LOCAL, depth 1)
    when made, and a Temperature of random value (two decimals, -20..40) every ``period`` seconds on
    ``sensor_topic`` (:func:`sensor_qos`) from a timer of ``graph``'s spun node, until the part ends.

    Attributes:
        config: the configuration text published.
        temperatures: every temperature published, oldest first.
        sensor_offered, config_offered: the profiles offered.
    """

    def __init__(self, s: Session, graph: Any, sensor_type: type, config_type: type, *,
                 sensor_topic: str, config_topic: str, period: float) -> None:
        self.sensor_offered = sensor_qos()
        self.config_offered = profile(reliable=True, transient_local=True, depth=1)
        self.config = f"units: {random_units()}"
        self.temperatures: list[float] = []
        self._lock = threading.Lock()
        self._sensor_type = sensor_type
        self._node = graph.node
        from rclpy.event_handler import PublisherEventCallbacks  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

        # a learner's subscription that cannot match is judged from the graph; the event only
        # replaces rclpy's default warning, which would print in the learner's terminal
        self.incompatible = threading.Event()
        quiet = PublisherEventCallbacks(incompatible_qos=lambda _status: self.incompatible.set())
        self._sensor = graph.node.create_publisher(sensor_type, sensor_topic, self.sensor_offered,
                                                   event_callbacks=quiet)
        self._config = graph.node.create_publisher(config_type, config_topic, self.config_offered,
                                                   event_callbacks=quiet)
        self._config.publish(config_type(data=self.config))
        self._closed = threading.Event()
        self._timer = graph.node.create_timer(period, self._tick)
        s.on_close(self.close)

    def publish_config(self) -> str:
        """Publish a second configuration, ``units: <another random unit>``, on the latched topic, as a
        ``ros2 param set`` of the lesson's configuration publisher would; returns its text (``config`` stays
        the first one's)."""
        text = f"units: {random_units(other_than=[self.config.removeprefix('units: ')])}"
        self._config.publish(self._config.msg_type(data=text))
        return text

    def _tick(self) -> None:
        if self._closed.is_set():
            return
        # one decimal: printed as it comes (f'{value}', round(value, 2)) it shows one, and only the lesson's
        # '{value:.2f}' shows two (two random decimals printed as they come matched 9 times in 10; audit of stop 71)
        value = round(_RANDOM.uniform(-20.0, 40.0), 1)
        msg = self._sensor_type()
        msg.header.frame_id = "grader_sensor"
        msg.temperature = value
        with self._lock:
            self.temperatures.append(value)
        self._sensor.publish(msg)

    def published(self) -> list[float]:
        """Temperatures published so far."""
        with self._lock:
            return list(self.temperatures)

    def close(self) -> None:
        """Stop publishing readings.

        The timer is left to the graph (closed with the check) and only silenced: cancelling it
        while the session's multi-threaded executor may be about to call it makes rclpy report
        "failed to call timer: timer is canceled" from the executor thread.
        """
        self._closed.set()


class Oracle:
    """Two visible nodes of random names in ``graph``: a sensor publisher and a latched config publisher.

    For the ``ros2 topic info --verbose`` script: nothing is published (the graph's endpoint
    information is what ``info`` prints), so no executor spins them. Destroyed when the part ends.

    Attributes:
        sensor_node, config_node: their names (no leading ``/``), e.g. ``thermometer_4821``.
    """

    def __init__(self, s: Session, graph: Any, sensor_type: type, config_type: type, *,
                 sensor_topic: str, config_topic: str) -> None:
        import rclpy  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

        self.sensor_node = f"thermometer_{_RANDOM.randrange(1000, 10000)}"
        self.config_node = f"configurator_{_RANDOM.randrange(1000, 10000)}"
        self._nodes = []
        for name, msg_type, topic, qos in ((self.sensor_node, sensor_type, sensor_topic, sensor_qos()),
                                           (self.config_node, config_type, config_topic,
                                            profile(reliable=True, transient_local=True, depth=1))):
            node = rclpy.create_node(name, context=graph.context, enable_rosout=False, start_parameter_services=False)
            node.create_publisher(msg_type, topic, qos)
            self._nodes.append(node)
        s.on_close(self.close)

    def close(self) -> None:
        """Remove both nodes from the graph (no executor spins them, so destroying is safe)."""
        for node in self._nodes:
            node.destroy_node()
        self._nodes = []


def wait_for(predicate: Callable[[], bool], timeout: float, abort: Callable[[], bool] | None = None) -> bool:
    """Wait until ``predicate()`` (or ``timeout`` seconds, or ``abort()``); returns ``predicate()`` then."""
    return _wait(predicate, timeout, abort)


# --- the lesson's parts, one function each (graders/qos.py calls them in order) ------------

def message_types() -> tuple[type, type]:
    """The generated classes ``(sensor_msgs/msg/Temperature, std_msgs/msg/String)``, imported only when grading."""
    from sensor_msgs.msg import Temperature  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)
    from std_msgs.msg import String  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

    return Temperature, String


def grade_sensor(s: Session, temperature: type, package: str, executable: str, node_name: str, *,
                 topic: str, type_name: str, frame_id: str, period: float, samples: int, warm_up: int,
                 start_timeout: float) -> None:
    """Grade the sensor publisher in the part's own graph (``s.graph``).

    Records ``sensor_executable``, ``sensor_node_name`` and the part's Ctrl+C check through the kit, then
    ``sensor_topic``, ``sensor_best_effort`` (a RELIABLE probe made before the node starts never matches it),
    ``sensor_volatile``, ``sensor_stream`` and ``sensor_rate`` (judged on the readings' send stamps).

    Args:
        temperature: the generated sensor_msgs/msg/Temperature class.
        package, executable, node_name: what ``ros2 run`` starts and the node's expected name.
        topic: the readings' topic (``/temperature``); type_name: its type as ``ros2 topic`` prints it.
        frame_id: the ``header.frame_id`` every reading must carry.
        period: seconds between readings (0.1: 10 Hz); samples: readings whose send stamps are judged, after
            ``warm_up`` first readings left out; start_timeout: seconds from the node appearing to its first reading.

    Raises:
        Unmet: no executable, no publisher of ``type_name``, or no reading reached a BEST_EFFORT subscription.
    """
    path = kit.executable(s, "sensor_executable", package, executable)
    graph = s.graph  # the part's own
    # both probes exist before the node starts: no reading is missed, and the RELIABLE one would match at once
    best_effort = graph.topic(topic, temperature, sensor_qos())
    reliable = Probe(graph, topic, temperature, profile(reliable=True, transient_local=False, depth=10))
    node = kit.start_node(s, "sensor_node_name", path, node_name, sigint_check="sensor_sigint_exit",
                          need_node=False)
    target, where = ts.own_endpoint(s, "sensor_topic", node, "publishers", topic, type_name,
                                    none=f"no {type_name} topic published to listen to", where="on")
    if target != topic:  # grade what flows where it is published
        best_effort = graph.topic(target, temperature, sensor_qos())
        reliable = Probe(graph, target, temperature, reliable.qos)
    with s.phase("observe"):
        window = best_effort.observe(warm_up + samples, period, start_timeout, abort=node.ended)
    readings = best_effort.messages()[:warm_up + samples]

    profiles = wait_endpoint_qos(graph, target, node.name, "publishers")
    verdicts = [compatible(p, reliable.qos) for p in profiles]
    incompatible = bool(profiles) and not any(ok for ok, _ in verdicts)
    received = len(reliable.messages())
    offered = ", ".join(f"({describe(p)})" for p in profiles) or "no publisher in the graph"
    reason = next((r for ok, r in verdicts if not ok), "")
    s.record("sensor_best_effort", incompatible and received == 0,
             f"it offers {offered}{where}; a RELIABLE subscription "
             + (f"cannot match ({reason})" if incompatible else "matches it")
             + f"; the grader's RELIABLE probe received {received} reading(s)"
             + ("" if not reliable.incompatible.is_set() else " and got the incompatible-QoS event"),
             "BEST_EFFORT offered: qos_check_compatible(offered, RELIABLE request) is ERROR and the RELIABLE probe "
             "receives nothing")

    volatile = bool(profiles) and all(word(p.durability) == "VOLATILE" for p in profiles)
    s.record("sensor_volatile", volatile, f"it offers {offered}{where}",
             "VOLATILE (qos_profile_sensor_data: no reading is kept for subscriptions that join later)")

    if not readings:
        raise Unmet(f"no reading reached a BEST_EFFORT subscription on {target} in {window:.1f} s; "
                    f"{kit.process_state(node.proc)}")
    frames = sorted({m.header.frame_id for m in readings})
    good = [m for m in readings if m.header.frame_id == frame_id and math.isfinite(m.temperature)]
    s.record("sensor_stream", len(good) == len(readings),
             f"{len(readings)} reading(s) received by a BEST_EFFORT (qos_profile_sensor_data) subscription{where}, "
             f"frame_id {', '.join(map(repr, frames))}, e.g. temperature {readings[0].temperature:.2f}",
             f"readings with header.frame_id {frame_id!r} and a finite temperature",
             fraction=len(good) / len(readings))
    kit.rate(s, "sensor_rate", best_effort.send_stamps(warm_up + samples)[warm_up:], period=period, needed=samples,
             waited=window, noun="reading", source="the readings' send stamps, the first one left out", where=where)


def grade_config(s: Session, string: type, package: str, executable: str, node_name: str, *,
                 topic: str, type_name: str, default_units: str) -> None:
    """Grade the configuration publisher in the session's graph (``s.ros``: the kit's parameter client asks there).

    Records ``config_executable``, ``config_node_name`` and the part's Ctrl+C check through the kit, then
    ``config_topic``, ``config_initial`` (``units: <default_units>`` replayed to a TRANSIENT_LOCAL subscription
    made after start), ``config_republish`` (``ros2 param set`` of a random unit, tried twice), and for a
    late-joining TRANSIENT_LOCAL subscription ``config_late_joiner`` and ``config_depth``, then ``config_latched``.

    Args:
        string: the generated std_msgs/msg/String class.
        package, executable, node_name: what ``ros2 run`` starts and the node's expected name.
        topic: the configuration's topic (``/sensor_config``); type_name: its type as ``ros2 topic`` prints it.
        default_units: the ``units`` parameter's default (``celsius``).

    Raises:
        Unmet: no executable, no publisher of ``type_name``, or the node's parameter services do not answer.
    """
    path = kit.executable(s, "config_executable", package, executable)
    node = kit.start_node(s, "config_node_name", path, node_name, sigint_check="config_sigint_exit",
                          need_node=False)
    target, where = ts.own_endpoint(s, "config_topic", node, "publishers", topic, type_name,
                                    none=f"no {type_name} topic published", where="on")
    profiles = wait_endpoint_qos(s.ros, target, node.name, "publishers")
    # a VOLATILE listener of whatever reliability is offered: it sees the change whatever the
    # durability and reliability (those are judged by the late joiner and config_latched)
    reliable = bool(profiles) and all(word(p.reliability) == "RELIABLE" for p in profiles)
    early = Probe(s.ros, target, string, profile(reliable=reliable, transient_local=False, depth=10))
    # a RELIABLE, TRANSIENT_LOCAL subscription made after the node started, before units is set: what the
    # node published at start is replayed to it (a VOLATILE offer cannot match it: nothing to wait for)
    start = Probe(s.ros, target, string, profile(reliable=True, transient_local=True, depth=10))
    start_can_match = any(compatible(p, start.qos)[0] for p in profiles)

    # the configuration changes once: with depth 1 only the new one is kept for late joiners
    services = kit_params.connect(s, node.name, proc=node.proc)
    with s.phase("observe"):
        wait_for(lambda: early.matched() > 0, 3.0, abort=node.ended)  # else the new configuration is missed
        if start_can_match:  # before units is set: the first message replayed is the one of the start
            wait_for(lambda: bool(start.messages()), LATE_DELIVERY, abort=node.ended)
        # nothing is set yet: what the VOLATILE listener hears now was not asked for (a timer that re-publishes)
        wait_for(lambda: bool(early.messages()), UNASKED_WINDOW, abort=node.ended)
    unasked = [m.data for m in early.messages()]
    initial = [m.data for m in start.messages()]
    wanted = f"units: {default_units}"
    s.record("config_initial", initial[:1] == [wanted],
             "a RELIABLE, TRANSIENT_LOCAL subscription made after the node started, before units was set, received "
             + (", ".join(map(repr, initial[:3])) or "nothing")
             + ("" if start_can_match or not profiles else
                f" (it cannot match the publisher's {', '.join(f'({describe(p)})' for p in profiles)})"),
             f"{wanted!r}, published at start and kept for subscriptions that join later")
    with s.phase("observe"):
        # The listener has matched the publisher; the publisher may learn of the listener a moment
        # later (discovery runs both ways) and a VOLATILE listener misses what is sent before: a
        # second change, to another unit, is the retry. The late joiner's verdicts use the last one.
        units, tried = "", []
        for patience in (1.5, LATE_DELIVERY):
            units = random_units(other_than=tried)
            tried.append(units)
            answers = services.set({"units": units})
            if wait_for(lambda u=units: any(m.data == f"units: {u}" for m in early.messages()), patience,
                        abort=node.ended):
                break
        latest = f"units: {units}"
    seen = [m.data for m in early.messages()]
    refused = [a.line() for a in answers if not a.successful]
    s.record("config_republish", latest in seen and not unasked,
             f"before anything was set it published {', '.join(map(repr, unasked[:2]))} within "
             f"{UNASKED_WINDOW:.0f} s (the configuration is published at start and when units is set, not on a "
             "timer)" if unasked else
             f"after `ros2 param set /{node.name} units {units}`"
             + (f" ({'; '.join(refused)})" if refused else "")
             + f" the grader received {', '.join(map(repr, seen[-3:])) or 'nothing'} on {target}",
             f"{latest!r} published after the parameter changed, and nothing while it did not")

    late = Probe(s.ros, target, string, profile(reliable=True, transient_local=True, depth=10))
    verdicts = [compatible(p, late.qos) for p in profiles]
    can_match = any(ok for ok, _ in verdicts)
    reason = next((r for ok, r in verdicts if not ok), "no publisher in the graph")
    offered = ", ".join(f"({describe(p)})" for p in profiles) or "no publisher"
    if can_match:
        with s.phase("observe"):
            wait_for(lambda: bool(late.messages()), LATE_DELIVERY, abort=node.ended)
            first = late.messages()[:1]
            if first and first[0].data != latest and latest in seen:  # an outdated one first: the rest follows
                wait_for(lambda: any(m.data == latest for m in late.messages()), 1.0)
    got = [m.data for m in late.messages()]
    shown = ", ".join(map(repr, got[:4])) + (" ..." if len(got) > 4 else "")
    s.record("config_late_joiner", bool(got),
             f"a TRANSIENT_LOCAL subscription made after the configuration was published received "
             f"{len(got)} message(s){': ' + shown if got else ''}"
             + ("" if can_match else f" (it cannot match the publisher's {offered}: {reason})") + where,
             "the configuration replayed to the late joiner (publisher TRANSIENT_LOCAL)")
    s.record("config_depth", got == [latest],
             f"the late joiner received {len(got)} message(s): {shown}",
             f"only the current configuration, {latest!r} (KEEP_LAST, depth 1)")
    latched = bool(profiles) and all(word(p.reliability) == "RELIABLE"
                                     and word(p.durability) == "TRANSIENT_LOCAL" for p in profiles)
    s.record("config_latched", latched, f"it offers {offered} on {target}", "RELIABLE, TRANSIENT_LOCAL")
    _start_from_parameter(s, string, path, node_name, topic)


def _start_from_parameter(s: Session, string: type, path: Any, node_name: str, topic: str) -> None:
    """``config_start_parameter``: a second instance, in a graph of its own, started with
    ``--ros-args -p units:=<random unit>`` (as a launch file or ``ros2 run`` would set it), must publish
    ``units: <that unit>`` at start: the value is the parameter's, not a fixed text (audit of stop 71, Q4)."""
    units = random_units()
    graph = s.new_graph()
    wanted = f"units: {units}"
    proc = s.launch(path, f"{path.name}.units", ["--ros-args", "-p", f"units:={units}"], graph=graph)
    start = Probe(graph, topic, string, profile(reliable=True, transient_local=True, depth=10))
    with s.phase("observe"):
        wait_for(lambda: any(m.data == wanted for m in start.messages()), START_PARAMETER_TIMEOUT,
                 abort=lambda: proc.poll() is not None)
    got = [m.data for m in start.messages()]
    proc.stop(sigint_timeout=1.0, sigterm_timeout=1.0)
    s.record("config_start_parameter", got[:1] == [wanted],
             f"started with units:={units}, it published {', '.join(map(repr, got[:3])) or 'nothing'} on {node_name}'s "
             f"{topic}" + ("" if got else f" in {START_PARAMETER_TIMEOUT:.0f} s ({kit.process_state(proc)})"),
             f"{wanted!r} at start: the parameter's value (get_parameter('units')), not a fixed text")


def matching(readings: list[float], text: str) -> list[float]:
    """The readings ``text`` logs as the lesson asks: ``Temperature: <value with two decimals>``."""
    return [r for r in readings if re.search(rf"Temperature: {r:.2f}(?![0-9])", text)]


def grade_monitor(s: Session, temperature: type, string: type, package: str, executable: str,
                  node_name: str, *, sensor_topic: str, sensor_type_name: str, config_topic: str,
                  config_type_name: str, period: float, logged: int) -> None:
    """Grade the monitor in the part's own graph (``s.graph``), fed by the grader's :class:`Feed`.

    The grader's latched configuration is published before the monitor starts (it joins late) and its
    BEST_EFFORT readings every ``period`` seconds. Records ``monitor_executable``, ``monitor_node_name`` and
    the part's Ctrl+C check through the kit, then ``monitor_topics``, ``monitor_sensor_qos``,
    ``monitor_config_qos``, ``monitor_logs_config``, ``monitor_logs_sensor`` and ``monitor_logs_every_reading``
    (from the node's /rosout).

    Args:
        temperature, string: the generated sensor_msgs/msg/Temperature and std_msgs/msg/String classes.
        package, executable, node_name: what ``ros2 run`` starts and the node's expected name.
        sensor_topic, sensor_type_name, config_topic, config_type_name: the topics the monitor must subscribe
            to and their types as ``ros2 topic`` prints them.
        period: seconds between the grader's readings; logged: how many of them the monitor must log.

    Raises:
        Unmet: no executable, or no node to inspect.
    """
    path = kit.executable(s, "monitor_executable", package, executable)
    graph = s.graph  # the part's own
    # the configuration is published before the monitor exists: it is a late joiner
    feed = Feed(s, graph, temperature, string, sensor_topic=sensor_topic, config_topic=config_topic, period=period)
    rosout = graph.rosout()
    node = kit.start_node(s, "monitor_node_name", path, node_name, sigint_check="monitor_sigint_exit",
                          need_node=False)
    found: dict[str, list[str]] = {}

    def both() -> bool:
        found.clear()
        found.update(ts.endpoints(graph, node.name, "subscriptions"))
        return sensor_topic in found and config_topic in found

    with s.phase("start"):
        wait_for(both, 3.0, abort=node.ended)
    s.record("monitor_topics",
             sensor_type_name in found.get(sensor_topic, []) and config_type_name in found.get(config_topic, []),
             f"{node.name or 'the node'} subscribes to: {ts.describe_endpoints(found)}",
             f"{sensor_topic} [{sensor_type_name}] and {config_topic} [{config_type_name}]")
    if node.name is None:
        raise Unmet(f"no node to inspect; {kit.process_state(node.proc)}")

    requested = wait_endpoint_qos(graph, sensor_topic, node.name, "subscriptions", 1.0)
    verdicts = [compatible(feed.sensor_offered, p) for p in requested]
    ok = bool(requested) and all(v for v, _ in verdicts)
    asked = ", ".join(f"({describe(p)})" for p in requested) or f"no subscription on {sensor_topic}"
    reason = next((r for v, r in verdicts if not v), "")
    s.record("monitor_sensor_qos", ok, f"it requests {asked}" + (f": {reason}" if reason else ""),
             f"a request a BEST_EFFORT publisher ({describe(feed.sensor_offered)}) satisfies")
    requested = wait_endpoint_qos(graph, config_topic, node.name, "subscriptions", 1.0)
    asked = ", ".join(f"({describe(p)})" for p in requested) or f"no subscription on {config_topic}"
    latched = bool(requested) and all(word(p.durability) == "TRANSIENT_LOCAL"
                                      and word(p.reliability) == "RELIABLE"
                                      and compatible(feed.config_offered, p)[0] for p in requested)
    s.record("monitor_config_qos", latched, f"it requests {asked}",
             "the latched profile: RELIABLE, TRANSIENT_LOCAL (as the configuration publisher offers)")

    def records() -> list[str]:
        return [r.msg for r in rosout.records(node=node.name)]

    def logged_readings() -> list[float]:
        published = feed.published()
        return sorted({r for text in records() for r in matching(published, text)})

    with s.phase("observe"):
        wait_for(lambda: any(f"Config: {feed.config}" in t for t in records())
                 and len(logged_readings()) >= logged, LATE_DELIVERY, abort=node.ended)
    texts = records()
    recent = " | ".join(t.strip()[:60] for t in texts[-2:]) or "no log records"
    config_logged = any(f"Config: {feed.config}" in t for t in texts)
    unlabelled = not config_logged and any(feed.config in t for t in texts)
    on_stdout = feed.config in node.proc.stdout()
    s.record("monitor_logs_config", config_logged,
             f"the grader published {feed.config!r} on {config_topic} before the node started; "
             + ("it is in the node's log" if config_logged else
                "the node logged it without the label 'Config: '" if unlabelled else
                f"not in the node's log (last records: {recent})")
             + ("; it appeared on stdout only (print() instead of the logger?)" if on_stdout and not config_logged
                else ""),
             f"a log record containing 'Config: {feed.config}'")
    # the lesson: 'Config: <data>' for every configuration, not only the one it found on joining (the independent
    # review of stop 82 got full marks with a monitor that logged its first configuration only); published now,
    # its record is looked for after the readings' window, which it spends no time of its own
    second = feed.publish_config() if config_logged else None
    readings = logged_readings()
    s.record("monitor_logs_sensor", len(readings) >= logged,
             f"{len(readings)} of the grader's {len(feed.published())} readings found in the node's log"
             + (f", e.g. {readings[0]:.2f}" if readings else f" (last records: {recent})"),
             f"at least {logged} of the grader's random temperatures logged as 'Temperature: <value with "
             "two decimals>'",
             fraction=min(1.0, len(readings) / logged))
    if readings:
        _logs_every_reading(s, feed, logged_readings, node, period)
    if second is not None:
        with s.phase("observe"):
            wait_for(lambda: any(f"Config: {second}" in t for t in records()), LATE_DELIVERY, abort=node.ended)
        texts = [t for t in records() if "Config:" in t]
        s.record("monitor_logs_each_config", any(f"Config: {second}" in t for t in texts),
                 f"the grader then published {second!r} while the node ran; its 'Config:' records: "
                 + (" | ".join(t.strip()[:60] for t in texts[-3:]) or "none"),
                 f"a record containing 'Config: {second}' too: every configuration is logged, not only the first")


#: Consecutive readings (from the first one the monitor logged) of which it must log at least
#: :data:`EVERY_READING_SHARE`: "for every reading" (a BEST_EFFORT reading lost on one host is rare; a log
#: throttled to once a second keeps about one in ten at 10 Hz).
EVERY_READING_RUN = 20
EVERY_READING_SHARE = 0.75  # 0.5 let a monitor logging every other reading pass (audit of stop 71)


def _logs_every_reading(s: Session, feed: Feed, logged_readings: Any, node: kit.StartedNode,
                        period: float) -> None:
    """``monitor_logs_every_reading``: of the :data:`EVERY_READING_RUN` readings published from the first one the
    monitor logged, it logs :data:`EVERY_READING_SHARE` or more (the lesson: 'Temperature: ...' for every reading;
    helper audit of issue 37: a log throttled to once a second passed the three-readings check)."""
    first_logged: list[int] = []  # the index, once known: what was published before it never changes

    def window() -> list[float]:
        published = feed.published()
        if not first_logged:
            logged = set(logged_readings())
            first_logged.extend(i for i, value in enumerate(published) if value in logged)
        return published[first_logged[0]:first_logged[0] + EVERY_READING_RUN] if first_logged else []

    with s.phase("observe"):
        wait_for(lambda: len(window()) >= EVERY_READING_RUN, EVERY_READING_RUN * period * 3 + LATE_DELIVERY,
                 abort=node.ended)
        wait_for(lambda: False, LATE_DELIVERY)  # the last ones' records on their way
    run = set(window())
    shown = run & set(logged_readings())
    s.record("monitor_logs_every_reading", bool(run) and len(shown) >= EVERY_READING_SHARE * len(run),
             f"{len(shown)} of {len(run)} readings in a row (from the first it logged) found in its log",
             f"'Temperature: ...' for every reading it receives: at least {EVERY_READING_SHARE:.0%} of "
             f"{EVERY_READING_RUN} readings in a row (BEST_EFFORT may lose one now and then; no throttle)")


def grade_cli(s: Session, temperature: type, string: type, script: str, *, timeout: float,
              sensor_topic: str, config_topic: str) -> None:
    """Grade the learner's ``ros2 topic info --verbose`` script in the part's own graph (``s.graph``).

    Runs it (up to ``timeout`` seconds) against an :class:`Oracle`'s two publishers of random names, on
    ``sensor_topic`` and ``config_topic``; records ``cli_script``, ``cli_ends``, ``cli_sensor_qos`` and
    ``cli_config_qos``.

    Args:
        temperature, string: the generated sensor_msgs/msg/Temperature and std_msgs/msg/String classes.
        script: the script's path from the workspace root (``cli/qos_topic_info.sh``).

    Raises:
        Unmet: the script is missing or not valid bash.
    """
    path = scripts.script(s, "cli_script", script)
    graph = s.graph  # the part's own
    oracle = Oracle(s, graph, temperature, string, sensor_topic=sensor_topic, config_topic=config_topic)
    run = scripts.run_script(s, path, timeout=timeout,
                             daemon_sees=[sensor_topic, config_topic, f"/{oracle.sensor_node}",
                                          f"/{oracle.config_node}"])
    scripts.ended(s, "cli_ends", run, "it ends by itself with exit code 0")
    scripts.printed(s, "cli_sensor_qos", run, [f"Node name: {oracle.sensor_node}", "Reliability: BEST_EFFORT"],
                    f"the QoS of the publisher of {sensor_topic}", f"ros2 topic info --verbose {sensor_topic}")
    scripts.printed(s, "cli_config_qos", run, [f"Node name: {oracle.config_node}", "Durability: TRANSIENT_LOCAL"],
                    f"the QoS of the publisher of {config_topic}", f"ros2 topic info --verbose {config_topic}")
