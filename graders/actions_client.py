"""Grader for ``actions-client`` (contract in chapters/actions-client/CONTRACT.md).

The grader plays the action server (:class:`ros2course.kit.actions.StandInActionServer`)
and judges the learner's client from its /rosout records and how its process ends.
Five runs, each in a graph of its own, each with a goal of random coordinates
given as the parameters ``x`` and ``y``:

* **goal**: no server at first (the client must say it waits, at most once a second:
  the server stays missing 2.5 s after the first such record); then the grader's
  server appears, accepts the goal, sends five feedback messages with random
  distances and ends the goal SUCCEEDED with a final position of its own. The log
  must show every distance, each in a record of its own in the order sent, before
  the result's record (logged as each arrives), the final position and the status;
  the process must then end by itself with exit code 0.
* **aborted**: the server, offered once the client has logged its first record, accepts, sends two feedback
  messages and ABORTS: the log
  must name that status with the final position (a client that always says
  "succeeded" fails).
* **canceled**: as **aborted**, but the grader cancels the goal (its server sends the cancel request itself,
  as a second client would) and the goal ends CANCELED: the log must name that status with the final position.
* **rejected**: the server, offered as in **aborted**, rejects the goal: the client must say so and end cleanly,
  without a record that pretends the goal ended (a rejected goal has no result: asking
  for it gets an empty answer with status UNKNOWN).
* **interrupted**: no server at all; Ctrl+C while the client waits must end it with
  exit code 0 and no traceback.
"""

from __future__ import annotations

from ros2course import kit
from ros2course.kit import Check, Session, checks

from . import _actions_client as steps
from ._actions_client import ACTION, EXECUTABLE, NODE, PACKAGE, PERIOD, THROTTLE_WINDOW

#: Seconds the contract needs the client watched (benchmarks/all_lessons.py): its first "waiting" record
#: (rclpy's wait_for_server(timeout_sec=1.0) returns after 1 s), the records that follow while the server
#: is still missing, a goal of five feedback messages, an aborted one of two and a canceled one of two.
WINDOW = 1.0 + THROTTLE_WINDOW + (5 + 2 + 2) * PERIOD

RUN = ("executable",)
CHECKS = [
    Check("build", "The packages build with colcon", 1),
    *checks.started("", PACKAGE, EXECUTABLE, NODE, node_part="goal"),
    Check("waits", f"While no server offers {ACTION}, it says in its log that it waits", 1,
          "in a timer: if not self.action_client.server_is_ready(): log 'action server not available, waiting...' "
          "(throttle_duration_sec=1.0) and return", needs=RUN, part="goal"),
    Check("waits_throttled", "It says so at most once a second", 1,
          "log the waiting record with throttle_duration_sec=1.0 (the timer that checks server_is_ready() may "
          "tick faster; the log must not)", needs=("waits",), part="goal"),
    Check("goal_sent", "Once the server is there, it sends one goal: the parameters x and y", 2,
          "declare the parameters x and y (self.declare_parameter('x', 1.0).value), put them in "
          "goal.desired_position and call self.action_client.send_goal_async(goal, feedback_callback=...)",
          needs=RUN, part="goal"),
    Check("logs_feedback", "It logs the distance_to_goal of every feedback message, as each arrives", 2,
          "pass feedback_callback=self.feedback_callback to send_goal_async; there, log "
          "feedback_message.feedback.distance_to_goal with get_logger().info(): one record per message, the "
          "last (0.0) too", needs=RUN, part="goal"),
    Check("logs_result", "It logs the result: the final position and the status SUCCEEDED", 2,
          "in goal_response_callback: goal_handle.get_result_async().add_done_callback(self.result_callback); "
          "there, response = future.result(): log response.result.final_position and the name of "
          "response.status (GoalStatus.STATUS_SUCCEEDED is 4)", needs=RUN, part="goal"),
    Check("ends", "Once the goal has ended, the client ends by itself: exit code 0, no traceback", 1,
          "after logging the result, stop spinning: set a flag and loop `while rclpy.ok() and not node.done: "
          "rclpy.spin_once(node, timeout_sec=0.1)` in main", needs=RUN, part="goal"),
    Check("logs_aborted", "A goal the server aborts is logged as ABORTED, with its final position", 1,
          "log the status the result response carries (response.status: GoalStatus.STATUS_ABORTED is 6), "
          "never a fixed 'succeeded', and the final position whatever the status", needs=RUN, part="aborted"),
    Check("aborted_ends", "After an aborted goal too, the client ends by itself: exit code 0, no traceback", 1,
          "end whatever the status: set the flag that ends main() in the result callback for every status, not "
          "only for SUCCEEDED", needs=RUN, part="aborted"),
    Check("logs_canceled", "A goal that ends canceled is logged as CANCELED, with its final position", 1,
          "name every status the result response can carry (GoalStatus: 4 SUCCEEDED, 5 CANCELED, 6 ABORTED): a "
          "goal another client cancels ends CANCELED, and the log must not call it anything else", needs=RUN,
          part="canceled"),
    Check("canceled_ends", "After a canceled goal too, the client ends by itself: exit code 0, no traceback", 1,
          "end whatever the status: set the flag that ends main() in the result callback for every status "
          "(SUCCEEDED, CANCELED, ABORTED), not only for the ones you expect", needs=RUN, part="canceled"),
    checks.ctrl_c("sigint_exit", "the client while it waits for the server", 1, needs=RUN, part="interrupted"),
    Check("handles_rejection", "A rejected goal is logged as rejected, and the client ends cleanly", 2,
          "in goal_response_callback: if not goal_handle.accepted: log that the goal was rejected, set the flag "
          "that ends main() and return before get_result_async() (a rejected goal has no result: asking for it "
          "gets status UNKNOWN, and a log that pretends the goal ended)",
          needs=RUN, part="rejected"),
]


def grade(s: Session) -> None:
    """Five runs of the client against the grader's own server (see the module docstring)."""
    action = s.interface_type("package_with_interfaces", "action", "MoveStraightIn2D")
    path = kit.executable(s, "executable", PACKAGE, EXECUTABLE)
    with s.part("goal", own_graph=True):
        steps.goal_run(s, action, path)
    with s.part("aborted", own_graph=True):
        steps.aborted_run(s, action, path)
    with s.part("canceled", own_graph=True):
        steps.canceled_run(s, action, path)
    with s.part("rejected", own_graph=True):
        steps.rejected_run(s, action, path)
    with s.part("interrupted", own_graph=True):
        steps.interrupted_run(s, path)
