"""Grader for ``tf2-listener`` (issue 20; contract in chapters/tf2-listener/CONTRACT.md).

Black-box, on the node's ``/rosout`` records while the grader itself is the tf2 tree:

1. the node starts with no transform anywhere: it must keep running and say (WARN)
   that ``world -> target`` is not available yet, never crash; then both frames exist, in
   two trees that are not connected (``world -> ros2course_left``, ``target -> ros2course_right``):
   tf2 raises ``ConnectivityException`` instead of ``LookupException``, and the node must
   still keep running (it catches ``TransformException``, as the lesson says);
2. the grader broadcasts ``world -> target`` on ``/tf`` at 20 Hz with a random
   translation: the node must log it (INFO, three decimals), and again at the next
   lookups while it stays (one record per lookup: never throttled, never only on change);
3. the grader moves ``target`` to another random place: the node must log the new
   position (a listener that looked up once and kept the value fails).

The grader publishes ``tf2_msgs/msg/TFMessage`` itself, as ``tf2_ros.TransformBroadcaster``
does, without importing tf2_ros (its C extension needs the underlay's libtf2 on the
grading process's library path).
"""

from __future__ import annotations

import time

from ros2course import kit
from ros2course.kit import LATE_DELIVERY, Check, Session, checks, wait_until
from ros2course.kit import topics_services as ts

from ._tf2_listener import Broadcast, random_position

PACKAGE = "python_package_that_uses_tf2"
EXE = NODE = "frame_listener"
PARENT, CHILD = "world", "target"
PERIOD = 0.5  # seconds between the node's lookups (2 Hz)
BROADCAST_PERIOD = 0.05  # seconds between the grader's transforms (20 Hz, like a moving robot)
UNAVAILABLE_WINDOW = 1.5  # seconds with no transform: about three lookups
#: Seconds both frames exist in two unconnected trees: two lookups or more, each raising ConnectivityException.
UNCONNECTED_WINDOW = 1.2
#: The frames the grader hangs under world and under target while the two are not connected.
UNCONNECTED_CHILDREN = ("ros2course_left", "ros2course_right")
#: Seconds for a logged position: the node's next lookups plus discovery of the grader's publisher.
LOG_TIMEOUT = 4.0
TOLERANCE = 0.002  # metres: logged with three decimals
#: Records judged for the lookup rate (5 intervals: shared/LESSONS.md's minimum), from the first warning on:
#: the waiting phase and the two positions give 7 or more.
RATE_RECORDS = 6
WARN = 30  # rcl_interfaces/msg/Log WARN level
INFO = 20  # rcl_interfaces/msg/Log INFO level
#: Records of the first position judged for "every time": the first and the next two lookups' (issue 37).
REPEATS = 3
#: Seconds their stamps may span: two intervals of PERIOD, with half a period of slack for a late tick (the rate
#: itself is lookup_rate's); a position logged every 1 s or more, or only when it changes, spans more or never repeats.
REPEAT_SPAN = (REPEATS - 1) * PERIOD + PERIOD

WINDOW = UNAVAILABLE_WINDOW + 2 * 2 * PERIOD

LISTENER = {"part": "listener", "needs": ("listener_executable",)}

CHECKS = [
    Check("build", "The package builds with colcon", 1),
    *checks.started("listener", PACKAGE, EXE, NODE, part="listener"),
    Check("waits_for_transform", f"With no {PARENT} -> {CHILD} yet, it keeps running and warns", 2,
          "catch tf2_ros.TransformException around lookup_transform and log a warning: a frame nobody broadcasts "
          "yet is normal at start-up", **LISTENER),
    Check("warning_says_so", f"Its warning says what is missing (names {PARENT}, {CHILD} or the transform)", 1,
          f"e.g. self.get_logger().warning(f'{PARENT} -> {CHILD} not available yet: {{exc}}'): tf2's exception "
          "text names the missing frame", part="listener", needs=("waits_for_transform",)),
    Check("survives_unconnected", f"With {PARENT} and {CHILD} in two unconnected trees, it still keeps running", 1,
          "catch tf2_ros.TransformException, the base class of LookupException, ConnectivityException and "
          "ExtrapolationException: while nothing is broadcast the lookup raises LookupException, once both frames "
          "exist but are not connected it raises ConnectivityException", part="listener",
          needs=("waits_for_transform",)),
    Check("logs_transform", f"It logs (INFO) where {CHILD} is in {PARENT} once the transform exists", 3,
          f"t = self.buffer.lookup_transform('{PARENT}', '{CHILD}', rclpy.time.Time()); log "
          "t.transform.translation's x, y, z with three decimals with self.get_logger().info(...) (the warning is "
          "for the failed lookups)", needs=("survives_unconnected",), part="listener"),
    Check("logs_every_lookup", "It logs the position at every lookup, not only once or when it changes", 1,
          "log the position in every timer callback, with no throttle_duration_sec, once=True or 'only if it "
          "moved' test: one record per lookup", needs=("logs_transform",), part="listener"),
    Check("follows_changes", f"When {CHILD} moves, it logs the new position", 2,
          "look the transform up again at every tick: never keep the first answer", needs=("logs_transform",),
          part="listener"),
    Check("lookup_rate", f"It looks the transform up every {PERIOD} s: one record per lookup", 1,
          f"create the timer with self.create_timer({PERIOD}, self.on_timer) and log once per tick (a warning "
          "or the position)", needs=("survives_unconnected",), part="listener"),
    checks.ctrl_c("listener_sigint_exit", "the listener", **LISTENER),
]


def _logged(rosout, node: str, position: tuple[float, float, float]) -> list:
    """The node's records (any level) that show ``position`` (three numbers within :data:`TOLERANCE`, in order)."""
    out = []
    for record in rosout.records(node=node):
        numbers = ts.numbers_in(record.msg)
        if any(all(abs(a - b) <= TOLERANCE for a, b in zip(numbers[i:i + 3], position))
               for i in range(len(numbers) - 2)):
            out.append(record)
    return out


def _every_lookup(s: Session, rosout, name: str, node: kit.StartedNode,
                  position: tuple[float, float, float]) -> None:
    """logs_every_lookup: the unchanged position is logged again at the next lookups (the lesson's "every time").

    Judged on the records' stamps: :data:`REPEATS` records showing ``position`` within :data:`REPEAT_SPAN` s of
    the first one. A throttled log (``throttle_duration_sec``), a log made once, or one made only when the value
    changed, does not repeat it in time; the mean rate of all records is lookup_rate's.
    """
    with s.phase("observe"):
        wait_until(lambda: len(_logged(rosout, name, position)) >= REPEATS, REPEAT_SPAN + LATE_DELIVERY,
                   abort=node.ended)
    shown = [kit.stamp_seconds(r.stamp) for r in _logged(rosout, name, position)]
    span = shown[REPEATS - 1] - shown[0] if len(shown) >= REPEATS else None
    s.record("logs_every_lookup", span is not None and span <= REPEAT_SPAN,
             f"{len(shown)} record(s) showed the unchanged position"
             + (f", the first {REPEATS} over {span:.2f} s (their stamps)" if span is not None else
                f" within {REPEAT_SPAN + LATE_DELIVERY:.1f} s"),
             f"the unchanged position logged again at the next lookups: {REPEATS} records within {REPEAT_SPAN:.2f} s "
             f"(one lookup every {PERIOD} s, each logged)")


def _grade_listener(s: Session) -> None:
    tf_message = s.installed_type("tf2_msgs", "msg", "TFMessage")  # tf2 is not on PyPI: from the underlay
    path = kit.executable(s, "listener_executable", PACKAGE, EXE)
    rosout = s.graph.rosout()
    node = kit.start_node(s, "listener_node_name", path, NODE, sigint_check="listener_sigint_exit",
                          need_node=False)
    name = node.name or NODE
    # 1. nothing broadcast yet
    with s.phase("observe"):
        wait_until(lambda: bool(rosout.records(node=name, level=WARN)), UNAVAILABLE_WINDOW + 2 * PERIOD,
                   abort=node.ended)
        wait_until(node.ended, UNAVAILABLE_WINDOW)  # it must survive its first failed lookups
    warnings = rosout.records(node=name, level=WARN)
    alive = not node.ended()
    s.record("waits_for_transform", alive and bool(warnings),
             (f"still running after {UNAVAILABLE_WINDOW:.1f} s without the transform; " if alive
              else f"it ended: {kit.process_state(node.proc)}; ")
             + (f"it warned: {warnings[0].msg[:120]!r}" if warnings else "no WARN record from it"),
             f"it keeps running and logs a WARN record while {PARENT} -> {CHILD} does not exist")
    # "logs a warning saying so" (lesson.yaml): the text names the transform or one of its frames (tf2's own
    # exception text, which most learners append, names the missing frame)
    saying_so = [w for w in warnings if any(word in w.msg.lower() for word in (PARENT, CHILD, "transform"))]
    s.record("warning_says_so", bool(saying_so),
             f"it warned: {(saying_so or warnings)[0].msg[:120]!r}" if warnings else "no WARN record from it",
             f"a warning that names {PARENT}, {CHILD} or the transform")
    if not alive:
        return
    from geometry_msgs.msg import TransformStamped  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)
    broadcast = Broadcast(s, tf_message, TransformStamped, PARENT, CHILD, BROADCAST_PERIOD)
    if not _survives_unconnected(s, rosout, name, node, broadcast):
        return
    try:
        _follow(s, rosout, name, node, broadcast)
    finally:
        _lookup_rate(s, rosout, name, node)


def _survives_unconnected(s: Session, rosout, name: str, node: kit.StartedNode, broadcast: Broadcast) -> bool:
    """Record ``survives_unconnected``: with ``world`` and ``target`` in two trees (each with a child of the
    grader's), the node's lookups raise ConnectivityException for :data:`UNCONNECTED_WINDOW` s; it must keep
    running (helper audit of issue 37: a node catching only LookupException, the error of step 1, passed)."""
    broadcast.edges = list(zip((PARENT, CHILD), UNCONNECTED_CHILDREN))
    begin = time.time()
    with s.phase("observe"):
        wait_until(node.ended, UNCONNECTED_WINDOW)
    alive = not node.ended()
    warned = [w for w in rosout.records(node=name, level=WARN) if kit.stamp_seconds(w.stamp) >= begin]
    return s.record("survives_unconnected", alive,
                    (f"still running after {UNCONNECTED_WINDOW:.1f} s with {PARENT} and {CHILD} in two trees"
                     + (f"; it warned: {warned[-1].msg[:120]!r}" if warned else "")) if alive else
                    f"it ended once {PARENT} and {CHILD} both existed, unconnected: {kit.process_state(node.proc)}",
                    f"it keeps running while the lookup raises ConnectivityException ({PARENT} -> "
                    f"{UNCONNECTED_CHILDREN[0]} and {CHILD} -> {UNCONNECTED_CHILDREN[1]} on /tf, no path between "
                    f"{PARENT} and {CHILD})")


def _lookup_rate(s: Session, rosout, name: str, node: kit.StartedNode) -> None:
    """Record ``lookup_rate`` on the stamps of the node's records from its first warning on (one per lookup),
    waiting (at most twice the time they take at :data:`PERIOD`) until :data:`RATE_RECORDS` of them came: a
    node whose position checks failed early is judged on as many records as one that passed them."""

    def lookup_stamps() -> list[float]:
        records = rosout.records(node=name)
        first = next((i for i, r in enumerate(records) if r.level == WARN), None)
        return [kit.stamp_seconds(r.stamp) for r in records[first:]] if first is not None else []

    with s.phase("observe"):
        wait_until(lambda: len(lookup_stamps()) >= RATE_RECORDS, 2 * RATE_RECORDS * PERIOD, abort=node.ended)
    stamps = lookup_stamps()
    kit.rate(s, "lookup_rate", stamps[:RATE_RECORDS], period=PERIOD, needed=RATE_RECORDS,
             waited=(stamps[-1] - stamps[0]) if stamps else 0.0, noun="record",
             source="the stamps of its log records, one per lookup", few_note=f"; {kit.process_state(node.proc)}")


def _follow(s: Session, rosout, name: str, node: kit.StartedNode, broadcast: Broadcast) -> None:
    """Steps 2 and 3: logs_transform and follows_changes, the grader broadcasting ``world -> target``."""
    # 2. the grader becomes the tf2 tree
    first = random_position(s)
    broadcast.position = first
    with s.phase("observe"):
        wait_until(lambda: bool(_logged(rosout, name, first)), LOG_TIMEOUT, abort=node.ended)
    shown = _logged(rosout, name, first)
    info = [r for r in shown if r.level == INFO]
    latest = [r.msg for r in rosout.records(node=name)][-2:]
    if not s.record("logs_transform", bool(info),
                    f"it logged {info[0].msg[:120]!r}" if info else
                    f"it logged {shown[0].msg[:120]!r} at level {shown[0].level}, not INFO ({INFO})" if shown else
                    f"no record shows ({', '.join(f'{v:.3f}' for v in first)}) within {LOG_TIMEOUT:.0f} s; its last "
                    f"records: {latest or 'none'}; {kit.process_state(node.proc)}",
                    f"an INFO record with x, y, z of {PARENT} -> {CHILD}: ({', '.join(f'{v:.3f}' for v in first)}) "
                    f"(± {TOLERANCE} m, the grader's broadcast)"):
        return
    _every_lookup(s, rosout, name, node, first)
    # 3. target moves
    second = random_position(s, far_from=first)
    broadcast.position = second
    with s.phase("observe"):
        wait_until(lambda: bool(_logged(rosout, name, second)), LOG_TIMEOUT, abort=node.ended)
    moved = _logged(rosout, name, second)
    latest = [r.msg for r in rosout.records(node=name)][-1:]
    s.record("follows_changes", bool(moved),
             f"after the move it logged {moved[0].msg[:120]!r}" if moved else
             f"no record shows the new position within {LOG_TIMEOUT:.0f} s; its last record: {latest or 'none'}",
             f"a record with the new position ({', '.join(f'{v:.3f}' for v in second)})")


def grade(s: Session) -> None:
    """One part: the listener against the grader's own transforms (see the module docstring)."""
    with s.part("listener"):
        _grade_listener(s)
