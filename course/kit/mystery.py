"""The grader's "mystery" nodes for the ``ros2`` CLI lessons (tutorial ch. 19 and 24; issue 12).

A CLI lesson's learner writes a bash script of ``ros2 topic`` / ``ros2 param``
commands; the grader first starts nodes of its own in the check's private
graph, with values drawn at random for each check (an id, a quote, a topic
suffix, an initial parameter value), so that only a script that really asks
the graph prints them. Each node is a real rclpy node of the grader's process
(visible to ``ros2 node list``, unlike the grader's hidden probe node), spun on
a thread of its own and destroyed when the grader's part ends
(:meth:`Session.on_close`).

Random values come from :class:`random.SystemRandom` (not seedable, so a
submission cannot reproduce them). Texts avoid ``:``, quotes and ``#``, so
``ros2 topic echo`` and ``ros2 param get`` print them as they are (YAML plain scalars).
"""

from __future__ import annotations

import random
import threading
import time
from typing import Any

from ros2course.errors import NotGradable
from ros2course.kit.session_protocol import Session
from ros2course.run.probes import TopicProbe, spin_until_shutdown, stop_spinning

_RANDOM = random.SystemRandom()

#: Quotes the mystery publishers say (plain text: no ``:``, quote characters or ``#``).
QUOTES = (
    "Do or do not, there is no try",
    "The cake is a lie",
    "Stay hungry, stay foolish",
    "Not all those who wander are lost",
    "Talk is cheap, show me the code",
    "Simplicity is prerequisite for reliability",
    "First, solve the problem. Then, write the code",
    "Make it work, make it right, make it fast",
)
PHILOSOPHERS = ("Yoda", "GLaDOS", "Steve", "Bilbo", "Linus", "Edsger", "John", "Kent")

#: Topic the grader listens on for the learner's ``ros2 topic pub --once`` (shared/LESSONS.md, inspect-topics).
INBOX_TOPIC = "/amazing_quote_in"

#: The launch-files lesson's node and topic (tutorial ch. 22.9), played by :class:`ConfigurableQuotePublisher`.
CONFIGURABLE_NODE = "peanut_butter_falcon_quote_publisher_node"
CONFIGURABLE_TOPIC = "truly_inspirational_quote"
CONFIGURABLE_PERIOD = 0.25  # seconds
CONFIGURABLE_PHILOSOPHER = "Tyler"


#: AmazingQuote's fields (custom-interfaces lesson, tutorial ch. 17.4) the mystery nodes fill.
QUOTE_FIELDS = {"id": "int32", "quote": "string", "philosopher_name": "string"}


def require_quote_fields(msg_type: type) -> None:
    """Make sure the learner's AmazingQuote has the fields the mystery nodes publish.

    Raises:
        NotGradable: a field is missing or of another type (the custom-interfaces lesson is unfinished).
    """
    fields = msg_type.get_fields_and_field_types()
    wrong = [f"{name} ({kind})" for name, kind in QUOTE_FIELDS.items() if fields.get(name) != kind]
    if wrong:
        raise NotGradable(f"your package_with_interfaces/msg/AmazingQuote lacks {', '.join(wrong)}; it has "
                          f"{', '.join(f'{k} {v}' for k, v in fields.items()) or 'no field'}",
                          "finish the custom-interfaces lesson first (ros2course check custom-interfaces)")


class MysteryNode:
    """A visible rclpy node of the grader's in ``s.graph`` (the check's domain), spinning until the part ends.

    Args:
        s: the grading session; the node is destroyed by :meth:`Session.on_close`.
        name: the node's name (no leading ``/``).
        parameter_services: offer ``list_parameters``/``get_parameters``/... (what ``ros2 param`` calls).
        parameters: ``name -> value`` declared at start (their Python types fix the parameter types).
    """

    def __init__(self, s: Session, name: str, *, parameter_services: bool = False,
                 parameters: dict[str, Any] | None = None) -> None:
        import rclpy  # noqa: PLC0415 - rclpy only when grading (graders load for CHECKS without ROS)
        from rclpy.executors import SingleThreadedExecutor  # noqa: PLC0415 - rclpy only when grading (graders load for CHECKS without ROS)

        context = s.graph.context
        self.node = rclpy.create_node(name, context=context, enable_rosout=False,
                                      start_parameter_services=parameter_services)
        for key, value in (parameters or {}).items():
            self.node.declare_parameter(key, value)
        self._executor = SingleThreadedExecutor(context=context)
        self._executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, daemon=True, name=f"mystery-{name}")
        self._thread.start()
        s.on_close(self.close)

    def _spin(self) -> None:
        spin_until_shutdown(self._executor)

    def close(self) -> None:
        """Stop spinning and destroy the node (idempotent)."""
        if self._executor is None:
            return
        if stop_spinning(self._executor, self._thread):
            self.node.destroy_node()
        # else: still inside wait, so the node is left to the session's context shutdown (never a crash)
        self._executor = None


class QuotePublisher(MysteryNode):
    """Publishes one random AmazingQuote over and over on a random ``/amazing_quote_NNNN`` topic (ch. 19).

    Attributes:
        topic: e.g. ``"/amazing_quote_8341"`` (a four-digit suffix).
        quote_id: the ``id`` field (100000-999999), the same in every message.
        quote, philosopher: the ``quote`` and ``philosopher_name`` fields.
        publishers: how many publishers the node holds on the topic (1-3): the
            ``Publisher count`` ``ros2 topic info`` prints (only the first publishes).
        period: seconds between messages.

    Args:
        msg_type: the AmazingQuote class (``s.interface_type("package_with_interfaces", "msg", "AmazingQuote")``).

    Raises:
        NotGradable: the learner's AmazingQuote lacks a field (:func:`require_quote_fields`).
    """

    def __init__(self, s: Session, msg_type: type, *, period: float = 0.2) -> None:
        require_quote_fields(msg_type)
        super().__init__(s, f"quote_oracle_{_RANDOM.randrange(100, 1000)}")
        self.topic = f"/amazing_quote_{_RANDOM.randrange(1000, 10000)}"
        self.quote_id = _RANDOM.randrange(100000, 1000000)
        self.quote = _RANDOM.choice(QUOTES)
        self.philosopher = _RANDOM.choice(PHILOSOPHERS)
        self.publishers = _RANDOM.randint(1, 3)
        self.period = period
        self._msg = msg_type(id=self.quote_id, quote=self.quote, philosopher_name=self.philosopher)
        self._pubs = [self.node.create_publisher(msg_type, self.topic, 10) for _ in range(self.publishers)]
        self.node.create_timer(period, lambda: self._pubs[0].publish(self._msg))


def quote_inbox(s: Session, msg_type: type) -> TopicProbe:
    """Listen on :data:`INBOX_TOPIC` for the learner's ``ros2 topic pub --once`` (reliable, depth 10).

    A subscription of the grader's hidden node: ``ros2 topic pub --once`` waits
    for one matching subscription (Jazzy's default for ``--once``) and this is it.
    Returns the :class:`~ros2course.run.probes.TopicProbe` recording what arrives.
    """
    return s.graph.topic(INBOX_TOPIC, msg_type, 10)


class ConfigurableQuotePublisher(MysteryNode):
    """The launch-files lesson's node, played by the grader: ``/peanut_butter_falcon_quote_publisher_node``.

    The parameters lesson's interface (ch. 22): parameters ``quote``,
    ``philosopher_name``, ``topic_name`` (``truly_inspirational_quote``) and
    ``period`` (0.25 s, a double); it publishes AmazingQuote every ``period``
    seconds with ``quote`` and ``philosopher_name`` read at each publish, so a
    ``ros2 param set`` shows in the next message. The initial ``quote`` is
    random for each check.

    Attributes:
        initial_quote: the random initial value of ``quote``.
        changes: ``(time.time() seconds, name, value)`` of every parameter change
            the node accepted (recorded before the next message is sent).
        probe: a :class:`~ros2course.run.probes.TopicProbe` of ``/truly_inspirational_quote`` (send stamps).

    Raises:
        NotGradable: the learner's AmazingQuote lacks a field (:func:`require_quote_fields`).
    """

    def __init__(self, s: Session, msg_type: type) -> None:
        require_quote_fields(msg_type)
        self.initial_quote = f"{_RANDOM.choice(QUOTES)}. Fortune number {_RANDOM.randrange(1000, 10000)}"
        self.changes: list[tuple[float, str, Any]] = []
        self._lock = threading.Lock()
        super().__init__(s, CONFIGURABLE_NODE, parameter_services=True, parameters={
            "quote": self.initial_quote, "philosopher_name": CONFIGURABLE_PHILOSOPHER,
            "topic_name": CONFIGURABLE_TOPIC, "period": CONFIGURABLE_PERIOD})
        self._msg_type = msg_type
        self._count = 0
        self.node.add_post_set_parameters_callback(self._changed)
        self.probe = s.graph.topic(f"/{CONFIGURABLE_TOPIC}", msg_type, 10)
        self._pub = self.node.create_publisher(msg_type, CONFIGURABLE_TOPIC, 10)
        self.node.create_timer(CONFIGURABLE_PERIOD, self._publish)

    def _changed(self, parameters: list[Any]) -> None:
        with self._lock:
            self.changes.extend((time.time(), p.name, p.value) for p in parameters)

    def _publish(self) -> None:
        quote = self.node.get_parameter("quote").value
        name = self.node.get_parameter("philosopher_name").value
        self._pub.publish(self._msg_type(id=self._count, quote=str(quote), philosopher_name=str(name)))
        self._count += 1

    def change_time(self, name: str, value: Any) -> float | None:
        """``time.time()`` of the first accepted change of ``name`` to ``value``; None if there was none."""
        with self._lock:
            return next((t for t, n, v in self.changes if n == name and v == value), None)

    def parameters(self) -> dict[str, Any]:
        """The node's current parameter values (``ros2 param dump`` would print these)."""
        return {name: p.value for name, p in self.node.get_parameters_by_prefix("").items()}


__all__ = [
    "CONFIGURABLE_NODE", "CONFIGURABLE_PERIOD", "CONFIGURABLE_PHILOSOPHER", "CONFIGURABLE_TOPIC", "INBOX_TOPIC",
    "QUOTE_FIELDS", "ConfigurableQuotePublisher", "MysteryNode", "QuotePublisher", "quote_inbox",
    "require_quote_fields",
]
