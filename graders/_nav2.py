"""The steps of the ``nav2-custom-nodes`` grader (graders/nav2_custom_nodes.py): one function per run of the
learner's two nodes, and the lesson's contract values they and the grader's ``CHECKS`` share
(chapters/nav2-custom-nodes/CONTRACT.md). A helper of one lesson (the placement rule in ``ros2course.kit``'s
docstring).

nav2 itself never runs here: the grader plays it.

* For ``nav2_initial_pose_publisher_node`` it plays rviz2 and amcl, the two subscribers of ``/initialpose``
  (``geometry_msgs/msg/PoseWithCovarianceStamped``; RELIABLE, VOLATILE, as amcl subscribes): the first
  subscribes before the node starts, the second only :data:`THROTTLE_WINDOW` seconds after the node's first
  "waiting" record. The pose is what amcl receives: a message the node writes before any subscription matched
  its publisher is lost or not depending on discovery, so only amcl's subscription (which matches the node's
  publisher at once, this process knowing it already) judges whether it was published and what it holds. A
  node that publishes before the second joined is caught by the send stamp of the first message the first
  subscriber received (the DDS source timestamp: when the node wrote it), compared with the wall time just
  before the second subscription was made: a node can only count the second subscriber after it exists, so a
  node that waits for two never publishes earlier, however loaded the machine.
* For ``nav2_navigate_to_pose_action_client_node`` it plays nav2's ``bt_navigator``: a
  ``nav2_msgs/action/NavigateToPose`` server (:class:`ros2course.kit.actions.StandInActionServer`) that is
  missing at first, then accepts the goal, sends feedback and succeeds; in other runs it aborts the goal
  (with an error code and message of its own) or rejects it.

Positions are metres in the ``map`` frame, variances square metres and square radians, times seconds.
ROS modules are imported inside the functions that grade: a grader module is also loaded for its CHECKS
alone (``ros2course list``, ``hint``), where ROS is not needed.
"""

from __future__ import annotations

import math
import re
import string
import time
from collections.abc import Callable
from typing import Any

from ros2course import kit
from ros2course.kit import Session, Unmet, services
from ros2course.kit import actions as act
from ros2course.kit.console import log_texts
from ros2course.kit.records import names_status
from ros2course.kit.topics_services import numbers_in, reliable_qos

PACKAGE = "python_package_that_uses_nav2"
POSE_EXECUTABLE = POSE_NODE = "nav2_initial_pose_publisher_node"
CLIENT_EXECUTABLE = "nav2_navigate_to_pose_action_client_node"
CLIENT_NODE = "nav2_navigate_to_pose_action_client"
TOPIC = "/initialpose"
ACTION = "/navigate_to_pose"
FRAME = "map"
SUBSCRIBERS = 2  # rviz2 and amcl in the real demo
#: The initial pose (metres, map frame) and its orientation (x, y, z, w): facing along the map's x axis.
INITIAL_POSITION = (-2.1, -0.3, 0.0)
IDENTITY = (0.0, 0.0, 0.0, 1.0)
#: The covariance entries that are not 0 (row-major 6x6 over x, y, z, rotation about x, y, z): what rviz2's
#: "2D Pose Estimate" sends, 0.25 m^2 on x and y and (pi/12)^2 rad^2 (15 degrees of standard deviation) on yaw.
COVARIANCE = {0: 0.25, 7: 0.25, 35: 0.06853891909122467}
COVARIANCE_TOLERANCE = 1e-6
#: The goal (metres, map frame), orientation IDENTITY, behavior_tree empty (nav2's default tree).
GOAL_POSITION = (1.0, -1.0, 0.0)
POSITION_TOLERANCE = 1e-6  # metres: the values are given exactly
#: Seconds: how far a header stamp may be from when its message was sent (pose) or received (goal).
STAMP_TOLERANCE = 1.5
#: Seconds a node runs with what it waits for missing before its first "waiting" record must be there.
WAIT_WINDOW = 3.0
#: Seconds what a node waits for stays missing after its first "waiting" record (at most once a second:
#: three records; at every 0.1 s tick: about 25).
THROTTLE_WINDOW = 2.5
#: Seconds for the pose once the second subscriber has joined, and for a node to end by itself after its work.
PUBLISH_TIMEOUT = 3.0
#: Seconds for a node's process to start and join the graph (as long as ``kit.start_node`` waits for a node).
STARTUP_WINDOW = 10.0
END_TIMEOUT = 3.0
#: Seconds for the log records the grader looks for (one goal lasts under a second).
LOG_TIMEOUT = 5.0
PERIOD = 0.1  # seconds between the grader's feedback messages
#: Metres: a logged distance matches one the grader sent when it is this close (3 decimals printed).
NUMBER_TOLERANCE = 0.0006
#: What a record pretending a rejected goal ended says (a status, a result).
PRETENDS = re.compile(r"succe|abort|cancel|unknown|status|result|error_code", re.IGNORECASE)


# --- shared --------------------------------------------------------------------------------------------

def navigate_to_pose(s: Session) -> type:
    """``nav2_msgs/action/NavigateToPose`` of the ROS install (the underlay's nav2 component, or a system
    ROS 2 Jazzy's ``ros-jazzy-nav2-msgs``), loaded as ``s.installed_type`` loads one (the libraries of the
    interface packages nav2_msgs depends on, geographic_msgs and nav_msgs, first).

    Raises:
        NotGradable: nav2_msgs (or one of its dependencies) is not installed, or its types do not load
            (:func:`ros2course.kit.component_type`: the refusal every optional component's type gets).
    """
    return kit.component_type(s.base_env, "nav2_msgs", "action", "NavigateToPose", needed_by="this lesson")


def _gone(proc: kit.LearnerProcess) -> Callable[[], bool]:
    """True once ``proc`` has been dead for :data:`kit.LATE_DELIVERY` s: the records it logged (and the
    messages it published) just before exiting are still on their way to the grader until then."""
    def gone() -> bool:
        return proc.poll() is not None and time.monotonic() - (proc.ended_at or 0.0) > kit.LATE_DELIVERY

    return gone


def _records(rosout: Any, node: str, proc: kit.LearnerProcess | None = None) -> list[str]:
    """The log records of ``node``'s logger, oldest first, on one line each: /rosout's, then, with ``proc``,
    those its console holds after them (a client that logs its result and exits at once can lose that record
    on /rosout: :mod:`ros2course.kit.console`)."""
    return log_texts(rosout, node, proc)


def _last(rosout: Any, node: str, proc: kit.LearnerProcess | None = None, count: int = 3) -> str:
    return " | ".join(text[:80] for text in _records(rosout, node, proc)[-count:]) or "no log records"


def _has(text: str, value: float, tolerance: float = NUMBER_TOLERANCE) -> bool:
    return any(abs(number - value) <= tolerance for number in numbers_in(text))


def _close(found: tuple[float, ...], wanted: tuple[float, ...], tolerance: float = POSITION_TOLERANCE) -> bool:
    return all(abs(a - b) <= tolerance for a, b in zip(found, wanted, strict=True))


def _xyz(point: Any) -> tuple[float, float, float]:
    return point.x, point.y, point.z


def _xyzw(q: Any) -> tuple[float, float, float, float]:
    return q.x, q.y, q.z, q.w


def _shown(values: tuple[float, ...]) -> str:
    return "(" + ", ".join(f"{v:g}" for v in values) + ")"


def _stamp(header: Any) -> float:
    return header.stamp.sec + header.stamp.nanosec * 1e-9


def ends(s: Session, check_id: str, proc: kit.LearnerProcess, when: str, timeout: float = END_TIMEOUT) -> bool:
    """Record ``check_id``: ``proc`` ends by itself within :data:`END_TIMEOUT` s, exit code 0, no traceback.

    ``when`` says after what, for the feedback ("once it had published"); ``timeout``: the seconds still to
    wait (less than END_TIMEOUT when the caller has waited already). Returns the verdict.
    """
    with s.phase("observe"):
        kit.wait_until(lambda: proc.poll() is not None, timeout)
    expected = f"the process ends by itself within {END_TIMEOUT:.0f} s, exit code 0, no traceback"
    ended = proc.exit_state()
    if ended is None:
        return s.record(check_id, False, f"still running {END_TIMEOUT:.0f} s {when}", expected)
    traceback = "Traceback (most recent call last)" in proc.stderr() + proc.stdout()
    ok = ended.returncode == 0 and not traceback
    return s.record(check_id, ok, f"{when}, the process {ended.describe()}"
                    + (f" ({ended.last_line})" if ended.last_line and not ok else ""), expected)


def interrupted_run(s: Session, check_id: str, path: Any, node: str, label: str) -> None:
    """``check_id`` (a Ctrl+C check): start ``path`` with nothing it waits for in the graph; once it has logged
    (that it waits), Ctrl+C is pressed as the part ends (:func:`kit.ctrl_c_once_it_logs`). A run that ends in
    rclpy's own race, inside the executor or inside a timer callback it runs (``get_subscription_count()`` raising
    "publisher's context is invalid", seen in 1 of 20 reference runs at load 2), is not the node's doing: the kit
    judges a fresh run instead (:func:`ros2course.run.process.rclpy_shutdown_race`), and observed says so."""
    kit.ctrl_c_once_it_logs(s, check_id, lambda suffix: s.launch(path, label + suffix, []), node,
                            patience=2 * WAIT_WINDOW)


# --- the initial pose ----------------------------------------------------------------------------------

def _says_it_waits(s: Session, check_id: str, rosout: Any, node: kit.StartedNode) -> bool:
    """Record ``check_id``: within :data:`WAIT_WINDOW` s, with one subscriber on /initialpose, the node logs
    that it waits (a record holding "wait" or "availab")."""
    def said() -> list:
        return rosout.records(node=POSE_NODE, match=lambda text: services.WAITING.search(text) is not None) or \
            rosout.records(match=lambda text: services.WAITING.search(text) is not None)

    with s.phase("observe"):
        kit.wait_until(lambda: bool(said()), WAIT_WINDOW, abort=node.ended)
    found = said()
    expected = f"a log record saying it waits (e.g. '1 of {SUBSCRIBERS} subscribers on {TOPIC}, waiting...')"
    if found:
        return s.record(check_id, True, f"logged '{found[0].msg.strip()[:120]}' while one node subscribed to {TOPIC}",
                        expected)
    return s.record(check_id, False, f"in {WAIT_WINDOW:.0f} s with one subscriber on {TOPIC}: "
                    f"{_last(rosout, POSE_NODE)}; {kit.process_state(node.proc)}", expected)


def pose_run(s: Session, message_type: type, path: Any) -> None:
    """pose_waits, pose_waits_throttled, pose_published, after_second, pose_frame, pose_values, covariance,
    pose_stamp, published_once, pose_ends: one subscriber from the start, the second joining late (a third
    subscriber is :func:`crowded_run`'s)."""
    first = s.graph.topic(TOPIC, message_type, reliable_qos(100))  # rviz2: there before the node
    rosout = s.graph.rosout()
    node = kit.start_node(s, "pose_node_name", path, POSE_NODE, label=POSE_EXECUTABLE)
    if _says_it_waits(s, "pose_waits", rosout, node):
        services.waits_throttled(s, "pose_waits_throttled", rosout, node, node_name=POSE_NODE,
                                 window=THROTTLE_WINDOW)
    joined = time.time()  # just before the second subscription exists: nothing of the node can count it earlier
    # amcl's subscription is what pose_published judges: a message the node writes before any subscription has
    # matched its publisher is lost or not depending on discovery (the first subscriber gets it by check and
    # misses it under grade's load: CI of e09f7d1), while one written once the node counts amcl always reaches
    # it (this process already knows the node's publisher, so amcl's subscription matches it at once)
    second = s.graph.topic(TOPIC, message_type, reliable_qos(100))  # amcl: joins late
    with s.phase("observe"):
        kit.wait_until(lambda: bool(second.messages()), PUBLISH_TIMEOUT, abort=_gone(node.proc))
    received, received_stamps = second.messages(), second.send_stamps()
    heard, heard_stamps = first.messages(), first.send_stamps()
    if not received and heard and heard_stamps[0] > joined:
        # the node counted amcl and published (after amcl's subscription existed: its send stamp), and the first
        # subscriber got it; amcl's own reader had not matched the node's writer yet on the grader's side (1 run
        # in 60 at load 2 and more, stop 69), and the node ended before a reliable repair: the grader's race
        s.record("pose_published", True, f"a PoseWithCovarianceStamped on {TOPIC}, sent {heard_stamps[0] - joined:.2f} s "
                 "after amcl's subscription existed: the first subscriber got it, amcl's own had not matched yet "
                 "(the grader's discovery under load, not your node)", f"one PoseWithCovarianceStamped on {TOPIC} "
                 "that amcl receives")
        received, received_stamps = heard, heard_stamps
    elif not received:
        early = len(heard)
        s.record("pose_published", False, f"amcl (the second subscriber) got no message on {TOPIC} in "
                 f"{PUBLISH_TIMEOUT:.0f} s after it joined (with a third subscriber: at least two is enough)"
                 + (f"; the first subscriber got {early} before amcl joined" if early else
                    " (one published before a subscriber matched is lost: the topic is VOLATILE)")
                 + f"; last log records: {_last(rosout, POSE_NODE)}; {kit.process_state(node.proc)}",
                 f"one PoseWithCovarianceStamped on {TOPIC} that amcl receives")
        s.require("pose_published")
    else:
        s.record("pose_published", True, f"amcl got a PoseWithCovarianceStamped on {TOPIC}",
                 f"one PoseWithCovarianceStamped on {TOPIC} that amcl receives")
    # the first subscriber's first message: anything the node sent before amcl joined (or amcl's, not there yet);
    # and amcl's first by its publication sequence number: number k > 1 means k - 1 were written before it, which
    # neither subscriber may have heard (sent before discovery matched them), so before the node counted amcl
    early = joined - (first.send_stamps() or received_stamps)[0]
    unheard = ((second.sequence_numbers() or first.sequence_numbers() or [1])[0] or 1) - 1
    s.record("after_second", early <= 0 and not unheard,
             f"published {early:.2f} s before the second subscriber joined (one subscriber then)" if early > 0 else
             f"{unheard} message(s) written before the one amcl got first (its publication sequence number is "
             f"{unheard + 1}), none of which amcl got" if unheard else
             f"published {-early:.2f} s after the second subscriber joined",
             f"published once {SUBSCRIBERS} nodes subscribe to {TOPIC} (the second joined "
             f"{THROTTLE_WINDOW} s after your first 'waiting' record)")
    _judge_pose(s, received[0], received_stamps[0])
    with s.phase("observe"):  # every message it publishes until it ends (or END_TIMEOUT)
        kit.wait_until(_gone(node.proc), END_TIMEOUT + kit.LATE_DELIVERY)
    # what the node wrote, heard or not: the highest publication sequence number heard, when the middleware says
    count = max([len(first.messages()), *(n for n in first.sequence_numbers() + second.sequence_numbers() if n)])
    s.record("published_once", count == 1,
             f"{count} message(s) on {TOPIC} from the start until "
             + ("the process ended" if node.proc.poll() is not None else f"{END_TIMEOUT:.0f} s after the first"),
             "one message")
    ends(s, "pose_ends", node.proc, "once it had published", timeout=0.0)  # waited above


def crowded_run(s: Session, message_type: type, path: Any) -> None:
    """at_least_two: three subscribers of /initialpose (rviz2, amcl and a ``ros2 topic echo`` left open) are
    there before the node starts; it must publish (a message any of them receives, within
    :data:`STARTUP_WINDOW` + :data:`PUBLISH_TIMEOUT` s).

    Why a run of its own, not a third subscriber joining with amcl in :func:`pose_run`: a subscription count
    moves one match at a time, so going from one to three passes through two, for about a millisecond (two
    subscriptions made one after the other by one process: 0.6-0.9 ms, 5 of 5 runs, stop 76), and a node that
    publishes only at exactly two and polls every 0.1 s caught it in about one run in a hundred (CI of 92ddb5a:
    fixture publishes-at-exactly-two passed). Subscriptions the node's participant discovers together, as it
    starts, match in one burst: it saw three at once in 9 of 10 runs, two for 0.3 ms in the tenth."""
    heard = [s.graph.topic(TOPIC, message_type, reliable_qos(100)) for _ in range(3)]
    rosout = s.graph.rosout()
    node = s.launch(path, f"{POSE_EXECUTABLE}.crowded", [])
    with s.phase("observe"):
        kit.wait_until(lambda: any(probe.messages() for probe in heard), STARTUP_WINDOW + PUBLISH_TIMEOUT,
                       abort=_gone(node))
    expected = f"a PoseWithCovarianceStamped on {TOPIC}: two subscribers is a minimum, not an exact count"
    if any(probe.messages() for probe in heard):
        s.record("at_least_two", True, f"with three subscribers on {TOPIC} from its start, it published", expected)
        return
    s.record("at_least_two", False, f"with three subscribers on {TOPIC} from its start, nothing was published in "
             f"{STARTUP_WINDOW + PUBLISH_TIMEOUT:.0f} s; last log records: {_last(rosout, POSE_NODE)}; "
             f"{kit.process_state(node)}", expected)


def _judge_pose(s: Session, message: Any, sent: float) -> None:
    """pose_frame, pose_values, covariance, pose_stamp on the first message amcl received (``sent``: its send stamp, seconds
    since the epoch)."""
    s.record("pose_frame", message.header.frame_id == FRAME, f"header.frame_id '{message.header.frame_id}'",
             f"'{FRAME}'")
    position, orientation = _xyz(message.pose.pose.position), _xyzw(message.pose.pose.orientation)
    s.record("pose_values", _close(position, INITIAL_POSITION) and _close(orientation, IDENTITY),
             f"position {_shown(position)}, orientation {_shown(orientation)}",
             f"position {_shown(INITIAL_POSITION)}, orientation {_shown(IDENTITY)} (no rotation)")
    covariance = list(message.pose.covariance)
    # isclose, not abs(v - expected) > tolerance: a NaN entry (None in the list the node assigned, which
    # rosidl's numpy conversion turns into NaN) is close to nothing (mutmut held-out seed 42 found it passing)
    wrong = [(i, v) for i, v in enumerate(covariance)
             if not math.isclose(v, COVARIANCE.get(i, 0.0), rel_tol=0.0, abs_tol=COVARIANCE_TOLERANCE)]
    nonzero = ", ".join(f"[{i}] = {v:g}" for i, v in enumerate(covariance) if v) or "all 0"
    s.record("covariance", not wrong,
             f"entries not 0: {nonzero}" + (f"; {len(wrong)} of 36 differ, first at index {wrong[0][0]} (row "
                                           f"{wrong[0][0] // 6}, column {wrong[0][0] % 6})" if wrong else ""),
             ", ".join(f"[{i}] = {v:g}" for i, v in COVARIANCE.items()) + ", every other entry 0 (row-major 6x6: "
             "x, y, z, roll, pitch, yaw)")
    stamp = _stamp(message.header)
    s.record("pose_stamp", abs(stamp - sent) <= STAMP_TOLERANCE,
             "header.stamp is 0 (never set)" if stamp == 0 else
             f"header.stamp {abs(stamp - sent):.2f} s {'before' if stamp < sent else 'after'} the message was sent",
             f"stamped with the node's clock as it publishes (within {STAMP_TOLERANCE} s of sending)")


# --- the action client ---------------------------------------------------------------------------------

def _feedback(action: Any, distances: list[float]) -> list[Any]:
    """Feedback messages: the robot closing in on the goal along a straight line, ``distances`` metres away."""
    messages = []
    for index, distance in enumerate(distances):
        message = action.Feedback()
        message.current_pose.header.frame_id = FRAME
        message.current_pose.pose.position.x = GOAL_POSITION[0] - distance
        message.current_pose.pose.position.y = GOAL_POSITION[1]
        message.current_pose.pose.orientation.w = 1.0
        message.navigation_time.sec = index
        message.estimated_time_remaining.sec = len(distances) - index
        message.distance_remaining = distance
        messages.append(message)
    return messages


def _script(action: Any, distances: list[float], status: int, code: int = 0, text: str = "") -> act.Script:
    result = action.Result()
    result.error_code, result.error_msg = code, text
    return act.Script(accept=True, feedback=_feedback(action, distances), result=result, status=status, period=PERIOD)


def goal_run(s: Session, action: Any, path: Any) -> None:
    """client_waits, client_waits_throttled, goal_sent, goal_pose, goal_stamp, logs_feedback, logs_result, ends."""
    # none near 1.0, the goal's x, which a record of the goal sent may hold
    distances = sorted([mm / 1000 for mm in s.random.sample(range(1050, 2500), 2)]
                       + [mm / 1000 for mm in s.random.sample(range(50, 950), 2)], reverse=True) + [0.0]
    server = act.stand_in_action_server(s, action, ACTION, lambda index, goal: _script(action, distances, act.SUCCEEDED))
    rosout = s.graph.rosout()
    node = kit.start_node(s, "client_node_name", path, CLIENT_NODE, label=CLIENT_EXECUTABLE)
    if services.says_it_waits(s, "client_waits", rosout, node, ACTION, timeout=WAIT_WINDOW, what="action server"):
        services.waits_throttled(s, "client_waits_throttled", rosout, node, node_name=CLIENT_NODE,
                                 window=THROTTLE_WINDOW)
    offered = time.time()  # just before the server exists: nothing the client sends it can be stamped earlier
    server.offer()
    with s.phase("observe"):
        kit.wait_until(lambda: bool(server.goals), LOG_TIMEOUT, abort=node.ended)
    expected = f"one goal on {ACTION}"
    if not server.goals:
        s.record("goal_sent", False, f"no goal in {LOG_TIMEOUT:.0f} s after the server appeared; last log records: "
                 f"{_last(rosout, CLIENT_NODE, node.proc)}; {kit.process_state(node.proc)}", expected)
        s.require("goal_sent")
    received = time.time() - (time.monotonic() - server.goals[0][0])  # wall time the first goal arrived
    with s.phase("observe"):
        kit.wait_until(lambda: bool(server.ended), len(distances) * PERIOD + 2.0, abort=node.ended)
        kit.wait_until(lambda: any(names_status(text, act.SUCCEEDED) for text in _records(rosout, CLIENT_NODE, node.proc)),
                       LOG_TIMEOUT, abort=_gone(node.proc))
    _judge_goal(s, server.goals[0][1], offered, received)
    records = _records(rosout, CLIENT_NODE, node.proc)
    found = _feedback_records(records, distances)
    anywhere = [d for d in distances if any(_has(text, d) for text in records)]
    s.record("logs_feedback", len(found) == len(distances),
             f"{len(found)} of the {len(distances)} distances sent ({', '.join(f'{d:.3f}' for d in distances)}) "
             "found in the log, each in a record of its own, in the order sent, before the result"
             + ("" if len(anywhere) == len(found) else
                f" ({len(anywhere)} written somewhere: several in one record, out of order, or only with the result)")
             + ("" if found else f"; last log records: {_last(rosout, CLIENT_NODE, node.proc)}"),
             "each distance_remaining in a log record of its own as it arrives (the logger, not print())",
             fraction=len(found) / len(distances))
    said = [text for text in records if names_status(text, act.SUCCEEDED)]
    s.record("logs_result", bool(said), f"'{said[0][:120]}'" if said else
             f"no record names SUCCEEDED; last log records: {_last(rosout, CLIENT_NODE, node.proc)}",
             "a log record naming the status SUCCEEDED")
    ends(s, "ends", node.proc, "once its goal had SUCCEEDED")
    # counted once the client has ended (or END_TIMEOUT after its goal ended), as actions-client counts: a client
    # that starts over (main() called at import, then by the entry point) sends its second goal a second later
    s.record("goal_sent", len(server.goals) == 1, f"{len(server.goals)} goal(s) by the time the client had ended "
             f"(or {END_TIMEOUT:.0f} s after the first goal had)", expected)


def _judge_goal(s: Session, goal: Any, offered: float, received: float) -> None:
    """goal_pose and goal_stamp on the first goal (``offered``: the wall time just before the server was created;
    ``received``: when the goal reached it; seconds since the epoch).

    "Stamped as it is sent" is judged as: stamped after the server appeared (a client sends only once it sees
    the server; one stamped earlier, in ``__init__`` or at a tick before the server appeared, was not stamped as
    it was sent) and no later than :data:`STAMP_TOLERANCE` s after it arrived (a clock of its
    own). Not "within 1.5 s of its arrival": a goal request written before the server's reader has matched the
    client's writer is resent by DDS only after the next heartbeat, 3 s later (Fast DDS's default period): a
    reference goal arrived 3.12 s after its stamp in one validation, stop 76."""
    pose = goal.pose
    position, orientation = _xyz(pose.pose.position), _xyzw(pose.pose.orientation)
    problems = []
    if pose.header.frame_id != FRAME:
        problems.append(f"header.frame_id '{pose.header.frame_id}'")
    if not _close(position, GOAL_POSITION):
        problems.append(f"position {_shown(position)}")
    if not _close(orientation, IDENTITY):
        problems.append(f"orientation {_shown(orientation)}")
    if goal.behavior_tree:
        problems.append(f"behavior_tree '{goal.behavior_tree[:60]}'")
    s.record("goal_pose", not problems, "; ".join(problems) or
             f"'{FRAME}', position {_shown(position)}, orientation {_shown(orientation)}, behavior_tree ''",
             f"header.frame_id '{FRAME}', position {_shown(GOAL_POSITION)}, orientation {_shown(IDENTITY)}, "
             "behavior_tree '' (nav2's default tree)")
    stamp = _stamp(pose.header)
    s.record("goal_stamp", offered <= stamp <= received + STAMP_TOLERANCE,
             "pose.header.stamp is 0 (never set)" if stamp == 0 else
             f"pose.header.stamp {offered - stamp:.2f} s before the server appeared (the goal reached it "
             f"{received - offered:.2f} s after it appeared)" if stamp < offered else
             f"pose.header.stamp {stamp - received:.2f} s after the goal reached the server",
             "stamped with the node's clock as the goal is sent: after the server appeared, not after the goal "
             "reached it")


def _feedback_records(records: list[str], distances: list[float]) -> list[float]:
    """The distances logged as the feedback arrived: each in a record of its own (one record matches one
    distance), in the order sent, before the record naming the result (SUCCEEDED)."""
    found: list[float] = []
    for text in records:
        if len(found) == len(distances) or names_status(text, act.SUCCEEDED):
            break
        if _has(text, distances[len(found)]):
            found.append(distances[len(found)])
    return found


def aborted_run(s: Session, action: Any, path: Any) -> None:
    """handles_abort: the grader's server aborts the goal after two feedback messages, with an error code and
    message of its own; the client must log ABORTED, both, and end by itself."""
    ended_run(s, action, path, act.ABORTED, "handles_abort")


def canceled_run(s: Session, action: Any, path: Any) -> None:
    """handles_cancel: the grader cancels the goal after two feedback messages (its server sends the cancel
    request itself, as rviz2's Cancel button would: :class:`ros2course.kit.actions.Script`); the client must log
    CANCELED and end by itself."""
    ended_run(s, action, path, act.CANCELED, "handles_cancel")


def ended_run(s: Session, action: Any, path: Any, status: int, check_id: str) -> None:
    """Record ``check_id``: a goal the grader's server ends with ``status`` (ABORTED, with an error code and
    message of its own that the log must hold too, or CANCELED) after two feedback messages is logged with
    that status's name, and the client ends by itself.

    Raises:
        Unmet: no goal reached the server.
    """
    name = act.status_name(status)
    aborted = status == act.ABORTED
    code = s.random.randint(101, 399) if aborted else 0
    token = "".join(s.random.choice(string.ascii_uppercase) for _ in range(6)) if aborted else ""
    text = f"no path to the goal ({token})" if aborted else ""
    server = act.stand_in_action_server(s, action, ACTION, lambda index, goal: _script(
        action, [0.6, 0.5], status, code, text))
    rosout = s.graph.rosout()
    proc = s.launch(path, f"{CLIENT_EXECUTABLE}.{name.lower()}", [])
    act.offer_once_it_waits(s, server, rosout, CLIENT_NODE, proc, WAIT_WINDOW)
    wanted = [(f"no log record names the status {name}", lambda r: names_status(r, status))]
    if aborted:
        wanted += [(f"no log record holds the error_code {code}", lambda r: code in numbers_in(r)),
                   (f"no log record holds the error_msg '{text}'", lambda r: token in r)]

    def shown() -> bool:
        records = _records(rosout, CLIENT_NODE, proc)
        return all(any(test(r) for r in records) for _, test in wanted)

    with s.phase("observe"):
        kit.wait_until(lambda: bool(server.goals), 2 * LOG_TIMEOUT, abort=lambda: proc.poll() is not None)
        if not server.goals:
            raise Unmet(f"no goal reached the server; last log records: {_last(rosout, CLIENT_NODE, proc)}; "
                        f"{kit.process_state(proc)}")
        kit.wait_until(shown, LOG_TIMEOUT, abort=_gone(proc))
        kit.wait_until(lambda: proc.poll() is not None, END_TIMEOUT)
        if proc.poll() is not None:  # what it logged just before exiting may still be on its way
            kit.wait_until(lambda: False, 0.5)
    records = _records(rosout, CLIENT_NODE, proc)
    problems = [why for why, test in wanted if not any(test(r) for r in records)]
    problems += _not_ended(proc, f"after the goal was {name}")
    said = [r for r in records if names_status(r, status)]
    s.record(check_id, not problems, "; ".join(problems) + f" (last records: {_last(rosout, CLIENT_NODE, proc)})"
             if problems else f"'{said[0][:120]}', then the process {proc.exit_state().describe()}",
             f"a log record naming {name}" + (f", the error_code ({code}) and the error_msg ('{text}')" if aborted
                                              else "") + ", then exit code 0, no traceback")


def _not_ended(proc: kit.LearnerProcess, when: str) -> list[str]:
    """What is wrong with how ``proc`` ended: still running, an exit code other than 0, a traceback."""
    ended = proc.exit_state()
    if ended is None:
        return [f"still running {END_TIMEOUT:.0f} s {when}"]
    traceback = "Traceback (most recent call last)" in proc.stderr() + proc.stdout()
    if ended.returncode != 0 or traceback:
        return [f"the process {ended.describe()}" + (f" ({ended.last_line})" if ended.last_line else "")]
    return []


def rejected_run(s: Session, action: Any, path: Any) -> None:
    """handles_rejection: the grader's server rejects the goal."""
    server = act.stand_in_action_server(s, action, ACTION, lambda index, goal: act.Script(accept=False))
    rosout = s.graph.rosout()
    proc = s.launch(path, f"{CLIENT_EXECUTABLE}.rejected", [])
    act.offer_once_it_waits(s, server, rosout, CLIENT_NODE, proc, WAIT_WINDOW)
    with s.phase("observe"):
        kit.wait_until(lambda: bool(server.goals), 2 * LOG_TIMEOUT, abort=lambda: proc.poll() is not None)
        if not server.goals:
            raise Unmet(f"no goal reached the server; last log records: {_last(rosout, CLIENT_NODE, proc)}; "
                        f"{kit.process_state(proc)}")
        kit.wait_until(lambda: any(re.search(r"reject", text, re.IGNORECASE) for text in _records(rosout, CLIENT_NODE, proc)),
                       LOG_TIMEOUT, abort=_gone(proc))
        kit.wait_until(lambda: proc.poll() is not None, END_TIMEOUT)
        if proc.poll() is not None:  # what it logged just before exiting may still be on its way
            kit.wait_until(lambda: False, 0.5)
    records = _records(rosout, CLIENT_NODE, proc)
    said = [text for text in records if re.search(r"reject", text, re.IGNORECASE)]
    after = records[records.index(said[0]) + 1:] if said else []
    pretends = [text for text in after if PRETENDS.search(text) and not re.search(r"reject", text, re.IGNORECASE)]
    problems = [] if said else [f"no log record says the goal was rejected (last records: {_last(rosout, CLIENT_NODE, proc)})"]
    problems += _not_ended(proc, "after the rejection")
    if pretends:
        problems.append(f"after the rejection, a record that pretends the goal ended: '{pretends[0][:120]}' (a rejected "
                        "goal has no result: do not ask for it)")
    s.record("handles_rejection", not problems, "; ".join(problems) or f"'{said[0][:120]}', then the process "
             f"{proc.exit_state().describe()}", "a log record saying the goal was rejected, no status or result "
             "logged after it, then exit code 0, no traceback")

