"""Grader for ``nav2-custom-nodes`` (GitHub issue 40; contract in chapters/nav2-custom-nodes/CONTRACT.md).

Two nodes of ``python_package_that_uses_nav2`` that talk to nav2, which never runs here: the grader plays
it (graders/_nav2.py), each run in a graph of its own.

* **pose**: ``nav2_initial_pose_publisher_node`` with one subscriber of ``/initialpose`` (rviz2) from the
  start; it must say in its log that it waits, at most once a second; the second subscriber (amcl) joins
  2.5 s after its first such record. The one message it then publishes is judged: sent after the second
  subscriber joined, frame ``map``, the lesson's pose, covariance and a fresh stamp; it publishes once and
  ends by itself.
* **pose_crowded**: three subscribers of ``/initialpose`` (rviz2, amcl, a ``ros2 topic echo`` left open) there
  before it starts: two is a minimum, so it must publish.
* **pose_interrupted**: no subscriber at all; Ctrl+C while it waits.
* **goal**: ``nav2_navigate_to_pose_action_client_node`` with no ``/navigate_to_pose`` server at first (it
  must say it waits, at most once a second); then the grader's server appears, accepts the goal (judged:
  one goal, the lesson's pose in ``map``, stamped as it is sent, an empty behavior_tree), sends five feedback
  messages with random distances and succeeds: the log must show every distance_remaining and SUCCEEDED,
  and the node must end by itself.
* **aborted** / **canceled** / **rejected**: the server, offered once the client has logged its first record, aborts
  the goal (an error code and message of its own), cancels it (sending the cancel request itself, as rviz2's Cancel
  button would) or rejects it: the client must say so and end by itself, never hang.
* **interrupted**: no server; Ctrl+C while the client waits.
"""

from __future__ import annotations

from ros2course import kit
from ros2course.kit import Check, Session, checks
from ros2course.kit.settle import part_needed

from . import _nav2 as steps
from ._nav2 import (
    ACTION,
    CLIENT_EXECUTABLE,
    CLIENT_NODE,
    FRAME,
    PACKAGE,
    PERIOD,
    POSE_EXECUTABLE,
    POSE_NODE,
    THROTTLE_WINDOW,
    TOPIC,
)

#: Seconds the contract needs the nodes watched (benchmarks/all_lessons.py): each node's first "waiting"
#: record (about 1 s), the records that follow while what it waits for is missing, a goal of five feedback
#: messages, an aborted one of two and a canceled one of two.
WINDOW = 2 * (1.0 + THROTTLE_WINDOW) + (5 + 2 + 2) * PERIOD

POSE = {"needs": ("pose_executable",), "part": "pose"}
PUBLISHED = {"needs": ("pose_published",), "part": "pose"}
CLIENT = {"needs": ("client_executable",), "part": "goal"}
CHECKS = [
    Check("build", "The package builds with colcon", 1,
          f"colcon build --packages-up-to {PACKAGE} and read its first error (often a typo in setup.py's "
          "console_scripts or in package.xml)"),
    Check("depends", "package.xml depends on rclpy, geometry_msgs and nav2_msgs", 1,
          "add <depend>geometry_msgs</depend> and <depend>nav2_msgs</depend> next to rclpy in package.xml"),
    *checks.started("pose", PACKAGE, POSE_EXECUTABLE, POSE_NODE, part="pose"),
    Check("pose_waits", f"While fewer than two nodes subscribe to {TOPIC}, it says in its log that it waits", 1,
          f"in a timer: if self.publisher.get_subscription_count() < 2: log '... subscribers on {TOPIC}, waiting...' "
          "(throttle_duration_sec=1.0) and return", **POSE),
    Check("pose_waits_throttled", "It says so at most once a second", 1,
          "log the waiting record with throttle_duration_sec=1.0 (the timer may tick faster; the log must not)",
          needs=("pose_waits",), part="pose"),
    Check("pose_published", f"It publishes a PoseWithCovarianceStamped on {TOPIC} that amcl, the second subscriber, "
          "receives", 1,
          f"self.create_publisher(PoseWithCovarianceStamped, '{TOPIC}', 1), then publish once the two subscribers "
          "are there (one published before amcl subscribes never reaches it: the topic is VOLATILE)", **POSE),
    Check("at_least_two", "Two subscribers is a minimum: with three there from its start (rviz2, amcl and a "
          "ros2 topic echo left open), it publishes", 1,
          "compare with >= (self.publisher.get_subscription_count() >= 2), not == 2: a `ros2 topic echo "
          f"{TOPIC}` left open makes three, and a node waiting for exactly two would never publish",
          needs=("pose_executable",), part="pose_crowded"),
    Check("after_second", "It publishes only once the second subscriber (amcl) has joined", 2,
          "wait for two subscribers, not one: rviz2 is there first, amcl joins later and must get the pose "
          "(self.publisher.get_subscription_count() >= 2)", **PUBLISHED),
    Check("pose_frame", f"The pose is in the frame '{FRAME}'", 1, f"message.header.frame_id = '{FRAME}'", **PUBLISHED),
    Check("pose_values", "The pose is (-2.1, -0.3, 0.0), not rotated", 2,
          "message.pose.pose.position.x = -2.1, .y = -0.3 and message.pose.pose.orientation.w = 1.0: the pose is "
          "nested twice (PoseWithCovarianceStamped.pose is a PoseWithCovariance, whose .pose is the Pose)",
          **PUBLISHED),
    Check("covariance", "The covariance: 0.25 on x and y, 0.0685 on yaw, 0 elsewhere", 2,
          "message.pose.covariance is 36 numbers, a 6x6 matrix row by row over (x, y, z, roll, pitch, yaw): x's "
          "variance is index 0, y's index 7 (row 1, column 1), yaw's index 35 (row 5, column 5)", **PUBLISHED),
    Check("pose_stamp", "The pose is stamped with the node's clock as it is published", 1,
          "message.header.stamp = self.get_clock().now().to_msg() right before publishing (never left at 0)",
          **PUBLISHED),
    Check("published_once", "It publishes the pose once", 1,
          "publish once, then cancel the timer (self.timer.cancel()) and stop: a pose sent again and again resets "
          "amcl's estimate each time", **PUBLISHED),
    Check("pose_ends", "Once the pose is out, the node ends by itself: exit code 0, no traceback", 1,
          "after publishing, set a flag (self.done = True) and loop `while rclpy.ok() and not node.done: "
          "rclpy.spin_once(node, timeout_sec=0.1)` in main", **PUBLISHED),
    checks.ctrl_c("pose_sigint_exit", "the pose publisher while it waits for subscribers", needs=("pose_executable",),
                  part="pose_interrupted"),
    *checks.started("client", PACKAGE, CLIENT_EXECUTABLE, CLIENT_NODE, part="goal"),
    Check("client_waits", f"While no server offers {ACTION}, it says in its log that it waits", 1,
          "in a timer: if not self.action_client.server_is_ready(): log 'action server not available, waiting...' "
          "(throttle_duration_sec=1.0) and return", **CLIENT),
    Check("client_waits_throttled", "It says so at most once a second", 1,
          "log the waiting record with throttle_duration_sec=1.0 (the timer that checks server_is_ready() may "
          "tick faster; the log must not)", needs=("client_waits",), part="goal"),
    Check("goal_sent", "Once the server is there, it sends one goal", 2,
          "send the goal from the timer once server_is_ready() is True, then cancel the timer; "
          "self.action_client.send_goal_async(goal, feedback_callback=...)", **CLIENT),
    Check("goal_pose", f"The goal is (1.0, -1.0, 0.0) in '{FRAME}', not rotated, with an empty behavior_tree", 2,
          f"goal.pose.header.frame_id = '{FRAME}'; goal.pose.pose.position.x = 1.0, .y = -1.0; "
          "goal.pose.pose.orientation.w = 1.0; goal.behavior_tree = '' (nav2's default tree)", **CLIENT),
    Check("goal_stamp", "The goal is stamped with the node's clock as it is sent", 1,
          "goal.pose.header.stamp = self.get_clock().now().to_msg() in the callback that sends it (not in "
          "__init__, long before, and never left at 0)", **CLIENT),
    Check("logs_feedback", "It logs the distance_remaining of every feedback message, as each arrives", 2,
          "pass feedback_callback=self.feedback_callback to send_goal_async; there, log "
          "feedback_message.feedback.distance_remaining with get_logger().info(): one record per message",
          **CLIENT),
    Check("logs_result", "It logs how the goal ended: SUCCEEDED", 1,
          "goal_handle.get_result_async().add_done_callback(self.result_callback); there, response = "
          "future.result(): log the name of response.status (GoalStatus.STATUS_SUCCEEDED is 4) with "
          "response.result.error_code and error_msg", **CLIENT),
    Check("ends", "Once the goal has ended, the client ends by itself: exit code 0, no traceback", 1,
          "after logging the result, set a flag and loop `while rclpy.ok() and not node.done: "
          "rclpy.spin_once(node, timeout_sec=0.1)` in main", **CLIENT),
    Check("handles_abort", "A goal nav2 aborts is logged as ABORTED with its error code and message, and the client "
          "ends", 2, "read the status from response.status (GoalStatus.STATUS_ABORTED is 6), never assume success; log "
          "response.result.error_code and response.result.error_msg, then set the flag that ends main()",
          needs=("client_executable",), part="aborted"),
    Check("handles_cancel", "A goal that ends canceled is logged as CANCELED, and the client ends", 1,
          "name every status the result response can carry (GoalStatus: 4 SUCCEEDED, 5 CANCELED, 6 ABORTED): a goal "
          "canceled from rviz2 ends CANCELED; then set the flag that ends main(), whatever the status",
          needs=("client_executable",), part="canceled"),
    Check("handles_rejection", "A rejected goal is logged as rejected, and the client ends cleanly", 2,
          "in goal_response_callback: if not goal_handle.accepted: log that the goal was rejected, set the flag "
          "that ends main() and return before get_result_async() (a rejected goal has no result)",
          needs=("client_executable",), part="rejected"),
    checks.ctrl_c("client_sigint_exit", "the client while it waits for the server", needs=("client_executable",),
                  part="interrupted"),
]


def grade(s: Session) -> None:
    """The pose publisher's two runs, then the client's five (see the module docstring)."""
    kit.depends(s, "depends", PACKAGE, ("rclpy", "geometry_msgs", "nav2_msgs"))
    pose_message = s.installed_type("geometry_msgs", "msg", "PoseWithCovarianceStamped")
    action = steps.navigate_to_pose(s)  # the nav2 component of the underlay
    # each part runs only if a check of it can still change the verdict (always, but in dev validate
    # --until-settled); the later runs' checks need pose_executable or client_executable, so the part that
    # finds the executable runs whenever they do
    if part_needed(s, CHECKS, "pose"):
        with s.part("pose", own_graph=True):
            pose_path = kit.executable(s, "pose_executable", PACKAGE, POSE_EXECUTABLE)
            steps.pose_run(s, pose_message, pose_path)
    if part_needed(s, CHECKS, "pose_crowded"):
        with s.part("pose_crowded", own_graph=True):
            s.require("pose_executable")
            steps.crowded_run(s, pose_message, pose_path)
    if part_needed(s, CHECKS, "pose_interrupted"):
        with s.part("pose_interrupted", own_graph=True):
            s.require("pose_executable")
            steps.interrupted_run(s, "pose_sigint_exit", pose_path, POSE_NODE, f"{POSE_EXECUTABLE}.interrupted")
    if part_needed(s, CHECKS, "goal"):
        with s.part("goal", own_graph=True):
            client_path = kit.executable(s, "client_executable", PACKAGE, CLIENT_EXECUTABLE)
            steps.goal_run(s, action, client_path)
    for part, run in (("aborted", steps.aborted_run), ("canceled", steps.canceled_run),
                      ("rejected", steps.rejected_run)):
        if part_needed(s, CHECKS, part):
            with s.part(part, own_graph=True):
                s.require("client_executable")
                run(s, action, client_path)
    if part_needed(s, CHECKS, "interrupted"):
        with s.part("interrupted", own_graph=True):
            s.require("client_executable")
            steps.interrupted_run(s, "client_sigint_exit", client_path, CLIENT_NODE, f"{CLIENT_EXECUTABLE}.interrupted")
