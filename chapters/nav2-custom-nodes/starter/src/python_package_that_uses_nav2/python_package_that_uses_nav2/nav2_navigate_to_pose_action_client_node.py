"""Sends nav2 one goal on /navigate_to_pose, logs its feedback and how it ended, then ends."""

import rclpy
from action_msgs.msg import GoalStatus  # noqa: F401 - the statuses: GoalStatus.STATUS_SUCCEEDED, ...
from geometry_msgs.msg import PoseStamped  # noqa: F401 - the goal's pose
from nav2_msgs.action import NavigateToPose
from rclpy.action import ActionClient
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

ACTION = '/navigate_to_pose'
FRAME = 'map'
GOAL_X, GOAL_Y = 1.0, -1.0  # metres, in the map frame; no rotation


class Nav2NavigateToPoseActionClient(Node):
    """Waits for /navigate_to_pose, sends the goal once, and sets ``done`` when it has ended."""

    def __init__(self) -> None:
        super().__init__('nav2_navigate_to_pose_action_client')
        self.action_client = ActionClient(self, NavigateToPose, ACTION)
        self.done = False
        # TODO 8: a timer (every 0.2 s) whose callback waits for the server, then sends the goal once

    # TODO 9: timer_callback: while not self.action_client.server_is_ready(), log that you wait
    #         (throttle_duration_sec=1.0) and return; then cancel the timer, build the goal
    #         (goal.pose: a PoseStamped in FRAME, stamped now; goal.behavior_tree = '') and
    #         send_goal_async(goal, feedback_callback=self.feedback_callback), adding
    #         goal_response_callback as the future's done callback

    # TODO 10: goal_response_callback(future): goal_handle = future.result(); if not accepted, log
    #          that the goal was rejected and set self.done; else get_result_async() and add
    #          result_callback

    # TODO 11: feedback_callback(feedback_message): log feedback_message.feedback.distance_remaining

    # TODO 12: result_callback(future): log the name of response.status with response.result's
    #          error_code and error_msg, then set self.done


def main(args=None) -> None:
    """Spin until the goal has ended (or Ctrl+C)."""
    try:
        rclpy.init(args=args)
        node = Nav2NavigateToPoseActionClient()
        while rclpy.ok() and not node.done:
            rclpy.spin_once(node, timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
