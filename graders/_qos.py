"""The qos lesson's grader-side endpoints: probes of chosen QoS profiles, offered/requested QoS, a feed.

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
import random
import threading
from collections.abc import Callable, Iterable
from typing import Any

from ros2course.kit import GradingSession, wait_until

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

    def __init__(self, s: GradingSession, graph: Any, sensor_type: type, config_type: type, *,
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

    def _tick(self) -> None:
        if self._closed.is_set():
            return
        value = round(_RANDOM.uniform(-20.0, 40.0), 2)
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

    def __init__(self, s: GradingSession, graph: Any, sensor_type: type, config_type: type, *,
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
