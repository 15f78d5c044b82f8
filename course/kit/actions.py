"""Kit steps for ROS 2 actions (``rclpy.action``): the grader as a learner server's client, or as a learner client's server.

An action is three services and two topics under ``<name>/_action/`` (design.ros2.org/articles/actions.html):
``send_goal``, ``cancel_goal`` and ``get_result``, ``feedback`` and ``status``. The grader speaks it
with rclpy's own :class:`rclpy.action.ActionClient` and :class:`rclpy.action.ActionServer`, as
``ros2 action send_goal`` does:

* :class:`GoalClient` sends goals to a learner's server, cancels them and waits for results.
  Feedback is judged from a probe on the ``feedback`` topic, whose messages carry the goal id and
  the server's send stamps (rates and speeds on send stamps, never on arrival times).
* :class:`StandInActionServer` answers a learner's client with goals scripted by the grader
  (accept or reject, the feedback to send, how the goal ends). It spins a node and executor of
  its own, so an executing goal never blocks the grader's /rosout subscription; nothing of it
  exists in the graph before :meth:`StandInActionServer.offer`.

:func:`offer_once_it_waits` offers a stand-in server only once the learner's client has said something, so a
client that sends without waiting for the server never reaches it, in any run.

:func:`action_endpoints` lists a node's action servers or clients, as ``ros2 node info`` does.
"""

from __future__ import annotations

import threading
import time
import uuid
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from ros2course.kit.session_protocol import Session
from ros2course.kit.topics_services import reliable_qos
from ros2course.run.probes import record, spin_until_shutdown, stop_spinning, wait_until

#: action_msgs/msg/GoalStatus status values, by name (GoalStatus.msg).
STATUS_NAMES = {0: "UNKNOWN", 1: "ACCEPTED", 2: "EXECUTING", 3: "CANCELING", 4: "SUCCEEDED", 5: "CANCELED",
                6: "ABORTED"}
SUCCEEDED, CANCELED, ABORTED = 4, 5, 6
#: action_msgs/srv/CancelGoal return_code: the goal had already ended when the cancel request arrived.
GOAL_TERMINATED = 3
#: Seconds :class:`StandInActionServer` waits for its own cancel request of a goal scripted CANCELED to be
#: accepted (a local service call: milliseconds).
CANCEL_TIMEOUT = 2.0


def status_name(status: int | None) -> str:
    """``SUCCEEDED`` for 4 (action_msgs/msg/GoalStatus), ``no result`` for None."""
    return "no result" if status is None else STATUS_NAMES.get(status, f"status {status}")


def action_endpoints(graph: Any, node: str | None, kind: str) -> dict[str, list[str]]:
    """The actions ``node`` serves (``kind="servers"``) or is a client of (``"clients"``): name -> type names.

    What ``ros2 node info`` lists under "Action Servers" / "Action Clients"
    (``rclpy.action.get_action_server_names_and_types_by_node``). Empty when
    ``node`` (``/name``) is None or not in ``graph`` (a :class:`~ros2course.run.probes.RosSession`).
    """
    from rclpy.action import (  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)
        get_action_client_names_and_types_by_node,
        get_action_server_names_and_types_by_node,
    )
    from rclpy.node import NodeNameNonExistentError  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

    if node is None:
        return {}
    query = {"servers": get_action_server_names_and_types_by_node,
             "clients": get_action_client_names_and_types_by_node}[kind]
    namespace, _, name = node.rpartition("/")
    try:
        found = query(graph.node, name, namespace or "/")
    except (NodeNameNonExistentError, RuntimeError):
        return {}
    return {action: list(types) for action, types in found}


def wait_for_action(s: Session, node: str | None, kind: str, name: str, timeout: float,
                    abort: Callable[[], bool] | None = None, graph: Any = None) -> dict[str, list[str]]:
    """Poll :func:`action_endpoints` until ``name`` is among them (at most ``timeout`` s, phase ``start``).

    Returns the last listing. Another action of the node ends the wait 1 s
    after it appears (a misnamed action will not rename itself).
    """
    seen: dict[str, list[str]] = {}
    first_other: list[float] = []

    def done() -> bool:
        seen.clear()
        seen.update(action_endpoints(graph or s.graph, node, kind))
        if name in seen:
            return True
        if seen and not first_other:
            first_other.append(time.monotonic())
        return bool(first_other) and time.monotonic() - first_other[0] > 1.0

    if node is not None:
        with s.phase("start"):
            wait_until(done, timeout, interval=0.05, abort=abort)
    return dict(seen)


def _new_goal_id() -> Any:
    """A random ``unique_identifier_msgs/UUID`` for a goal (rclpy's own choice when it picks one)."""
    from unique_identifier_msgs.msg import UUID  # noqa: PLC0415 - ROS modules only when grading

    return UUID(uuid=list(uuid.uuid4().bytes))


@dataclass
class Goal:
    """One goal the grader sent with :class:`GoalClient`, and what became of it.

    Attributes:
        request: the ``Action.Goal`` sent.
        sent: ``time.time()`` seconds when it was sent.
        accepted: the server's answer; None while (or when) there was none.
        status: the terminal status (:data:`STATUS_NAMES`), None before the result.
        result: the ``Action.Result``, None before it.
        ended: ``time.time()`` seconds when the result arrived.
        cancel_code: the ``return_code`` of the server's answer to the last cancel request
            (action_msgs/srv/CancelGoal: 0 ERROR_NONE, 1 ERROR_REJECTED, 2 ERROR_UNKNOWN_GOAL_ID,
            :data:`GOAL_TERMINATED`); None before an answer.
    """

    request: Any
    sent: float
    accepted: bool | None = None
    handle: Any = None
    status: int | None = None
    result: Any = None
    ended: float | None = None
    why: str = ""
    result_future: Any = None
    cancel_code: int | None = None

    @property
    def uuid(self) -> bytes | None:
        """The goal id the server gave it (None when it was not answered)."""
        return None if self.handle is None else bytes(self.handle.goal_id.uuid)


class GoalClient:
    """The grader's ``ros2 action send_goal`` for action ``name`` in ``graph``.

    Args:
        action_type: the generated action class (e.g. ``MoveStraightIn2D``).
        name: the action's name, ``/move_straight_in_2d``.
        graph: a :class:`~ros2course.run.probes.RosSession` (default ``s.graph``).

    Create it before the learner's server starts: its feedback probe then
    misses nothing. Closed with the part (:meth:`Session.on_close`).
    """

    def __init__(self, s: Session, action_type: type, name: str, graph: Any = None) -> None:
        from action_msgs.msg import GoalStatusArray  # noqa: PLC0415 - ROS modules only when grading
        from rclpy.action import ActionClient  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)
        from rclpy.qos import qos_profile_action_status_default  # noqa: PLC0415 - ROS modules only when grading

        self.graph = graph or s.graph
        self.action_type, self.name = action_type, name
        self.client = ActionClient(self.graph.node, action_type, name)
        self.feedback_probe = self.graph.topic(f"{name}/_action/feedback", action_type.Impl.FeedbackMessage,
                                               reliable_qos(100))
        # the server lists the goals it accepted here: how a lost answer to a goal is told from none (send)
        self.status_probe = self.graph.topic(f"{name}/_action/status", GoalStatusArray,
                                             qos_profile_action_status_default)
        s.on_close(self.close)

    def wait_for_server(self, timeout: float, abort: Callable[[], bool] | None = None) -> bool:
        """True once the server's three services and two topics match ours (``server_is_ready``)."""
        return wait_until(self.client.server_is_ready, timeout, interval=0.05, abort=abort)

    def send(self, request: Any, timeout: float = 3.0) -> Goal:
        """Send ``request`` (an ``Action.Goal``) and wait ``timeout`` s for accepted or rejected.

        Without an answer in ``timeout`` s the grader tells a lost answer from a server that never
        answers before it gives up (``Goal.why`` then says which): it waits ``timeout`` s more for the
        answer or for the goal on the server's ``status`` topic (a server lists every goal it
        accepted there, under the id the grader chose), and then sends the goal once more. On a busy
        machine rmw_fastrtps may drop a service answer whose reader the server has not discovered yet
        (its ``send_response`` waits only briefly for the match), or the request before the server's
        reader matched the grader's writer; CI saw a correct server's first goal "not answered".
        """
        goal = Goal(request=request, sent=time.time())
        record(self.graph, f"{self.name}/_action/send_goal/request", request)
        goal_id = _new_goal_id()
        future = self.client.send_goal_async(request, goal_uuid=goal_id)
        if wait_until(future.done, timeout, interval=0.005):
            return self._answered(goal, future)
        wait_until(lambda: future.done() or self._listed(bytes(goal_id.uuid)), timeout, interval=0.01)
        if future.done():
            return self._answered(goal, future)
        future.cancel()
        if self._listed(bytes(goal_id.uuid)):
            return self._accepted_unanswered(goal, goal_id)
        return self._resend(goal, timeout)

    def _answered(self, goal: Goal, future: Any, why: str = "") -> Goal:
        """``goal`` as the server's answer (``future``, done) says: accepted or rejected."""
        goal.handle = future.result()
        goal.accepted = bool(goal.handle.accepted) if goal.handle is not None else None
        goal.why = why
        return goal

    def _accepted_unanswered(self, goal: Goal, goal_id: Any) -> Goal:
        """``goal`` accepted without an answer: the server's status topic lists ``goal_id`` (a
        ``unique_identifier_msgs/UUID``). rclpy's own ``ClientGoalHandle`` is built for it, so its result
        and cancel requests work as for an answered goal; the goal is never sent twice."""
        from rclpy.action.client import ClientGoalHandle  # noqa: PLC0415 - ROS modules only when grading

        response = self.action_type.Impl.SendGoalService.Response(accepted=True)
        goal.handle = ClientGoalHandle(self.client, goal_id, response)
        goal.accepted = True
        goal.why = "its answer was lost, but the server's status topic lists it"
        return goal

    def _resend(self, goal: Goal, timeout: float) -> Goal:
        """Send ``goal``'s request once more, under a new id, when neither its answer nor its status came."""
        future = self.client.send_goal_async(goal.request, goal_uuid=_new_goal_id())
        if wait_until(future.done, timeout, interval=0.005):
            return self._answered(goal, future, f"no answer to the goal within {2 * timeout:.1f} s; "
                                                "the same goal sent again was answered")
        future.cancel()
        goal.why = f"no answer to the goal within {timeout:.1f} s, nor to the same goal sent again"
        return goal

    def _listed(self, goal_id: bytes) -> bool:
        """True once the server's ``status`` topic has listed the goal ``goal_id`` (any status)."""
        return any(bytes(status.goal_info.goal_id.uuid) == goal_id
                   for message in self.status_probe.messages() for status in message.status_list)

    def wait_result(self, goal: Goal, timeout: float, abort: Callable[[], bool] | None = None) -> Goal:
        """Wait up to ``timeout`` s for ``goal``'s result; sets ``status``, ``result``, ``ended`` (else ``why``)."""
        if not goal.accepted:
            return goal
        if goal.result_future is None:
            goal.result_future = goal.handle.get_result_async()
        future = goal.result_future
        wait_until(future.done, timeout, interval=0.005, abort=abort)
        if future.done() and future.result() is not None:
            response = future.result()
            goal.status, goal.result, goal.ended = response.status, response.result, time.time()
            record(self.graph, f"{self.name}/_action/get_result/response", response)
        else:
            goal.why = f"no result within {timeout:.1f} s"
        return goal

    def cancel(self, goal: Goal, timeout: float = 3.0) -> tuple[bool | None, str]:
        """Ask to cancel ``goal``: ``(True, "")`` when the server accepted, ``(False, why)``, ``(None, why)`` without an answer.

        A cancel is accepted when the server's answer lists the goal among
        ``goals_canceling`` (action_msgs/srv/CancelGoal), as ``ros2 action``
        and rclpy's ``ClientGoalHandle.cancel_goal_async`` read it.
        """
        future = goal.handle.cancel_goal_async()
        if not wait_until(future.done, timeout, interval=0.005):
            future.cancel()
            return None, f"no answer to the cancel request within {timeout:.1f} s"
        response = future.result()
        goal.cancel_code = response.return_code
        canceling = [bytes(info.goal_id.uuid) for info in response.goals_canceling]
        if goal.uuid in canceling:
            return True, ""
        if response.return_code == 0:  # rcl accepted it; the server's cancel_callback said REJECT (rclpy's default)
            return False, "the server refused it: the goal is not among goals_canceling (its cancel_callback rejected it)"
        codes = {1: "ERROR_REJECTED", 2: "ERROR_UNKNOWN_GOAL_ID",
                 GOAL_TERMINATED: "ERROR_GOAL_TERMINATED: it had already ended"}
        return False, f"the server refused it ({codes.get(response.return_code, response.return_code)})"

    def feedback(self, goal: Goal) -> list[tuple[float, Any]]:
        """``(send stamp seconds, Action.Feedback)`` of ``goal``, oldest first (from the feedback topic)."""
        uuid = goal.uuid
        if uuid is None:
            return []
        return [(stamp, message.feedback) for stamp, message in zip(self.feedback_probe.send_stamps(),
                                                                    self.feedback_probe.messages(), strict=False)
                if bytes(message.goal_id.uuid) == uuid]

    def close(self) -> None:
        """Remove the client from the graph."""
        self.client.destroy()


@dataclass
class Script:
    """How :class:`StandInActionServer` answers one goal.

    Attributes:
        accept: False rejects the goal.
        feedback: ``Action.Feedback`` messages to publish, one every ``period`` s.
        result: the ``Action.Result`` to return.
        status: how the goal ends: :data:`SUCCEEDED`, :data:`ABORTED` or :data:`CANCELED` (the server then
            sends a cancel request for the goal itself, as a second client would, and ends it canceled once
            the request is accepted: a goal ends CANCELED only after a cancel request, design.ros2.org
            actions, "Goal State Machine").
        period: seconds between two feedback messages.
    """

    accept: bool = True
    feedback: list[Any] = field(default_factory=list)
    result: Any = None
    status: int = SUCCEEDED
    period: float = 0.1


class StandInActionServer:
    """The grader's action server ``name``, answering each goal as ``script(index, goal)`` says.

    It lives on a node and a two-thread executor of its own (``_ros2course_stand_in_action_server``),
    so a goal executing (publishing feedback every ``period``) never blocks the grader's other
    callbacks. Nothing exists in the graph before :meth:`offer`.

    Args:
        graph: the :class:`~ros2course.run.probes.RosSession` to serve in.
        script: ``script(index, goal) -> Script``; ``index`` counts goals from 0.

    Attributes:
        goals: ``(time.monotonic() seconds, Action.Goal)`` per goal received.
        ended: per goal executed, ``(time.monotonic() seconds, status)`` when it ended.
    """

    def __init__(self, graph: Any, action_type: type, name: str, script: Callable[[int, Any], Script]) -> None:
        self.graph, self.action_type, self.name, self.script = graph, action_type, name, script
        self.goals: list[tuple[float, Any]] = []
        self.ended: list[tuple[float, int]] = []
        self._accepted: list[Script] = []  # scripts of accepted goals not executed yet, oldest first
        self._lock = threading.Lock()
        self._node = self._executor = self._thread = self._server = self._cancel = None

    def offer(self) -> None:
        """Create the server (it appears in the graph) and start answering."""
        import rclpy  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)
        from rclpy.action import ActionServer  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)
        from rclpy.callback_groups import ReentrantCallbackGroup  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)
        from rclpy.executors import MultiThreadedExecutor  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)
        from rclpy.parameter import Parameter  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

        self._node = rclpy.create_node(
            "_ros2course_stand_in_action_server", context=self.graph.context, enable_rosout=False,
            start_parameter_services=False,
            parameter_overrides=[Parameter("start_type_description_service", value=False)])
        group = ReentrantCallbackGroup()
        self._server = ActionServer(self._node, self.action_type, self.name, self._execute,
                                    goal_callback=self._on_goal, cancel_callback=self._on_cancel,
                                    callback_group=group)
        # the cancel requests of CANCELED scripts go through the action's own cancel_goal service, as
        # `ros2 action` or a second client would send them (rclpy's ServerGoalHandle cannot cancel itself)
        from action_msgs.srv import CancelGoal  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

        self._cancel = self._node.create_client(CancelGoal, f"{self.name}/_action/cancel_goal", callback_group=group)
        self._executor = MultiThreadedExecutor(num_threads=2, context=self.graph.context)
        self._executor.add_node(self._node)
        self._thread = threading.Thread(target=self._spin, daemon=True, name="ros2course-stand-in-action-server")
        self._thread.start()

    def _spin(self) -> None:
        spin_until_shutdown(self._executor)

    def _on_goal(self, goal: Any) -> Any:
        from rclpy.action import GoalResponse  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

        with self._lock:
            index = len(self.goals)
            self.goals.append((time.monotonic(), goal))
        record(self.graph, f"{self.name}/_action/send_goal/request", goal)
        script = self.script(index, goal)
        if script.accept:
            with self._lock:
                self._accepted.append(script)
        return GoalResponse.ACCEPT if script.accept else GoalResponse.REJECT

    def _on_cancel(self, goal_handle: Any) -> Any:
        from rclpy.action import CancelResponse  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

        return CancelResponse.ACCEPT  # the learner's client never cancels: only the server's own request comes

    def _execute(self, goal_handle: Any) -> Any:
        from action_msgs.srv import CancelGoal  # noqa: PLC0415 - ROS modules only when grading (graders load for CHECKS without ROS)

        with self._lock:
            script = self._accepted.pop(0)
        for feedback in script.feedback:
            time.sleep(script.period)
            goal_handle.publish_feedback(feedback)
        time.sleep(script.period)
        if script.status == CANCELED:
            request = CancelGoal.Request()
            request.goal_info.goal_id = goal_handle.goal_id
            if self._cancel.wait_for_service(timeout_sec=CANCEL_TIMEOUT):  # a request before matching is lost
                self._cancel.call_async(request)  # answered by the executor's other thread
            wait_until(lambda: goal_handle.is_cancel_requested, CANCEL_TIMEOUT)
        if script.status == CANCELED and goal_handle.is_cancel_requested:
            goal_handle.canceled()
        else:  # a cancel request that was never answered ends the goal aborted: the client is judged on that
            (goal_handle.abort if script.status in (ABORTED, CANCELED) else goal_handle.succeed)()
        with self._lock:
            self.ended.append((time.monotonic(), goal_handle.status))
        return script.result if script.result is not None else self.action_type.Result()

    def close(self) -> None:
        """Stop answering and remove the server from the graph (nothing to do before :meth:`offer`)."""
        if self._executor is not None:
            stop_spinning(self._executor, self._thread)
        if self._server is not None:
            self._server.destroy()
        if self._node is not None:
            self._node.destroy_node()
        self._node = self._executor = self._thread = self._server = self._cancel = None


def offer_once_it_waits(s: Session, server: StandInActionServer, rosout: Any, node: str, proc: Any,
                        timeout: float) -> None:
    """Offer ``server`` once the learner's client has started and logged its first record, not before.

    A goal request written before the client's request writer has matched the server's reader is lost,
    and whether discovery matched them first is a race: with the server offered before the client starts,
    a client that sends at once, without waiting for the server as the lessons ask, reached it in one run
    and not in another (``check`` and ``grade`` gave it different verdicts). Offered only once the client
    has logged (a client that waits says so), a goal sent without waiting goes into nothing in every run,
    and a client that waits sends its goal once the server is there, as with nav2 or any server that
    starts late.

    Args:
        server: the stand-in server, not offered yet.
        rosout: the session's :class:`~ros2course.run.probes.RosoutProbe`.
        node: the client's node (logger) name, e.g. ``"nav2_navigate_to_pose_action_client"``.
        proc: the client's :class:`~ros2course.run.process.LearnerProcess`.
        timeout: seconds to wait for that first record (the lesson's time to say it waits); the server is
            offered then, or as soon as the process ends, whatever it logged.
    """
    with s.phase("observe"):
        wait_until(lambda: bool(rosout.records(node=node)) or proc.poll() is not None, timeout)
    server.offer()


def stand_in_action_server(s: Session, action_type: type, name: str, script: Callable[[int, Any], Script],
                           graph: Any = None) -> StandInActionServer:
    """A :class:`StandInActionServer` in ``graph`` (default ``s.graph``), not offered yet, closed with the part.

    Create it before starting the learner's client (closers run newest first:
    the client's Ctrl+C is judged while the server still exists).
    """
    server = StandInActionServer(graph or s.graph, action_type, name, script)
    s.on_close(server.close)
    return server
