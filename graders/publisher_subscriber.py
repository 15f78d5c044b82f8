"""Grader for ``publisher-subscriber`` (seed ch. 18-19; contract in shared/LESSONS.md).

Black-box. The **publisher** is watched like ``ros2 node info``,
``ros2 topic echo`` and ``ros2 topic hz`` would (its own topics and their
types, the messages' fields, the id sequence, the rate). The **subscriber**
is driven like ``ros2 topic pub`` would: the grader publishes quotes of its
own (texts, philosophers and ids it makes up for this check, so an echo of
the seed's example cannot pass) and looks for them in the subscriber's
``/rosout`` records. Each executable is a part of its own (partial credit)
and each ends with its Ctrl+C check. The publisher's parameter services are
asked once: a timer and ``rclpy.spin()``, not a ``while`` loop that publishes
(``pub_spins``, ros2course.kit.checks.spins).
"""

from __future__ import annotations


from ros2course import kit
from ros2course.kit import Check, Session, Unmet, checks, params, quotes
from ros2course.kit import topics_services as ts


PACKAGE = "python_package_that_uses_the_messages"
PUB_EXE = "amazing_quote_publisher_node"
PUB_NODE = "amazing_quote_publisher_node"
SUB_EXE = "amazing_quote_subscriber_node"
SUB_NODE = "amazing_quote_subscriber_node"
TOPIC = "/amazing_quote"
MSG_TYPE = "package_with_interfaces/msg/AmazingQuote"
QUOTE = "Use the force, Pikachu!"  # seed ch. 18.3
PHILOSOPHER = "Uncle Ben"
PERIOD = 0.5  # seconds, seed ch. 18.3
SAMPLES = 6  # messages -> 5 intervals, the minimum LESSONS.md asks for
#: Seconds from the publisher appearing to its first message (a loaded machine can be slow).
START_TIMEOUT = 5.0
GRADER_QUOTES = 8  # quotes the grader publishes to the subscriber: 75 % of them logged at once is 6

#: Seconds of observation the contract needs: the publisher's 6 messages at 2 Hz, then the
#: grader's quotes to the subscriber (one period each).
WINDOW = SAMPLES * PERIOD + GRADER_QUOTES * PERIOD
PUB, SUB = {"part": "publisher", "needs": ("pub_executable",)}, {"part": "subscriber", "needs": ("sub_executable",)}

CHECKS = [
    Check("build", "The packages build with colcon", 1),
    checks.interfaces_depend(),
    *checks.started("pub", PACKAGE, PUB_EXE, PUB_NODE, part="publisher"),
    Check("pub_topic", "It publishes /amazing_quote of type package_with_interfaces/msg/AmazingQuote", 2,
          "self.create_publisher(msg_type=AmazingQuote, topic='/amazing_quote', qos_profile=1)", **PUB),
    Check("pub_contents", "Each message says 'Use the force, Pikachu!' by 'Uncle Ben'", 2,
          "set amazing_quote.quote and amazing_quote.philosopher_name before publishing (check the spelling)", **PUB),
    Check("pub_id_counts", "The id counts up by 1 from one message to the next", 2,
          "keep the id in an attribute (self.incremental_id), put it in each message, then add 1", **PUB),
    Check("pub_id_from_zero", "The id starts at 0", 1,
          "set self.incremental_id = 0 in __init__, and add 1 after publishing, not before", **PUB),
    Check("pub_rate", "One message every 0.5 s (2 Hz)", 2,
          "self.create_timer(0.5, self.timer_callback), one publish per tick", **PUB),
    checks.ctrl_c("pub_sigint_exit", "the publisher", **PUB),
    checks.spins("pub_spins", **PUB),
    *checks.started("sub", PACKAGE, SUB_EXE, SUB_NODE, part="subscriber"),
    Check("sub_topic", "It subscribes to /amazing_quote of type package_with_interfaces/msg/AmazingQuote", 2,
          "self.create_subscription(msg_type=AmazingQuote, topic='/amazing_quote', callback=..., qos_profile=1)",
          **SUB),
    Check("sub_logs_quotes", "It logs the text of each quote it receives, every message", 3,
          "in the subscription callback, log msg.quote with self.get_logger().info(...) "
          "(print() does not reach /rosout)", **SUB),
    Check("sub_logs_details", "With each quote it logs the philosopher's name and the id", 2,
          "log msg.philosopher_name and msg.id too, e.g. in the same f-string as msg.quote", **SUB),
    checks.ctrl_c("sub_sigint_exit", "the subscriber", **SUB),
]


def _show(msg) -> str:
    return f"{{id: {msg.id}, quote: {msg.quote!r}, philosopher_name: {msg.philosopher_name!r}}}"


def _grade_publisher(s: Session, msg_type: type) -> None:
    path = kit.executable(s, "pub_executable", PACKAGE, PUB_EXE)
    probes = {TOPIC: ts.listen(s, TOPIC, msg_type)}  # before the node starts: no message is missed
    node = kit.start_node(s, "pub_node_name", path, PUB_NODE, sigint_check="pub_sigint_exit", need_node=False)
    params.record_spins(s, "pub_spins", node)  # a timer and rclpy.spin(), not a while loop that publishes
    target, where = ts.own_endpoint(s, "pub_topic", node, "publishers", TOPIC, MSG_TYPE,
                                    none=f"no {MSG_TYPE} topic published to listen to", where="on")
    probe = probes.get(target) or ts.listen(s, target, msg_type)  # grade the contents where they are published
    with s.phase("observe"):
        window = probe.observe(SAMPLES, PERIOD, START_TIMEOUT, abort=node.ended)
    messages = probe.messages()[:SAMPLES]
    if not messages:  # judged: nothing arrived is what the contents check observed (ids and rate then cannot be)
        observed = f"no message on {target} in {window:.1f} s; {kit.process_state(node.proc)}"
        s.record("pub_contents", False, observed + where,
                 f"quote: {QUOTE!r}, philosopher_name: {PHILOSOPHER!r} in every message, received by a reliable "
                 "subscription (a BEST_EFFORT publisher reaches none)")
        raise Unmet(observed)

    wrong_quote = [m for m in messages if m.quote != QUOTE]
    wrong_name = [m for m in messages if m.philosopher_name != PHILOSOPHER]
    share = (0.5 if not wrong_quote else 0.0) + (0.5 if not wrong_name else 0.0)
    bad = (wrong_quote or wrong_name or messages)[0]
    observed = (f"all {len(messages)} messages are {_show(bad)}" if share == 1.0
                else f"{len(wrong_quote) + len(wrong_name)} wrong field(s) in {len(messages)} messages, "
                f"e.g. {_show(bad)}")
    s.record("pub_contents", share == 1.0, observed + where,
             f"quote: {QUOTE!r}, philosopher_name: {PHILOSOPHER!r} in every message", fraction=share)
    quotes.id_counts(s, "pub_id_counts", messages, where)
    quotes.counts_from_zero(s, "pub_id_from_zero", messages, path, target, msg_type, PERIOD, where=where,
                            sequence=probe.sequence_numbers()[0])
    kit.rate(s, "pub_rate", probe.send_stamps(SAMPLES), period=PERIOD, needed=SAMPLES, waited=window,
             noun="message", source="the messages' send stamps", where=where)


def _grade_subscriber(s: Session, msg_type: type) -> None:
    path = kit.executable(s, "sub_executable", PACKAGE, SUB_EXE)
    rosout = s.graph.rosout()
    node = kit.start_node(s, "sub_node_name", path, SUB_NODE, sigint_check="sub_sigint_exit", need_node=False)
    target, where = ts.own_endpoint(s, "sub_topic", node, "subscriptions", TOPIC, MSG_TYPE,
                                    none=f"no {MSG_TYPE} subscription to publish to", where="published on")
    quotes.subscriber_logs(s, "sub_logs_quotes", "sub_logs_details", node, rosout, target, msg_type,
                           count=GRADER_QUOTES, where=where)


def grade(s: Session) -> None:
    """Grade the publisher (as a listener), then the subscriber (as a publisher), each a part of its own."""
    kit.depends(s, "depends", PACKAGE, ("rclpy", ts.INTERFACES))
    msg_type = ts.workspace_types(s, "msg", "AmazingQuote")
    with s.part("publisher"):
        _grade_publisher(s, msg_type)
    # A fresh graph: a process joining a graph whose participants already know each other is
    # discovered up to ~3 s later than one joining a fresh graph (Fast DDS, localhost discovery).
    with s.part("subscriber", own_graph=True):
        _grade_subscriber(s, msg_type)
