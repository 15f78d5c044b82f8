"""An action client: sends one MoveStraightIn2D goal, logs its feedback and its result, then ends."""

import rclpy
from action_msgs.msg import GoalStatus  # noqa: F401 - the statuses: GoalStatus.STATUS_SUCCEEDED, ...
from rclpy.action import ActionClient
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

from package_with_interfaces.action import MoveStraightIn2D


class MoveStraightIn2DActionClientNode(Node):
    """Sends the goal (x, y) to /move_straight_in_2d once, and sets ``done`` when it has ended."""

    def __init__(self) -> None:
        super().__init__('move_straight_in_2d_action_client')
        # TODO: declare the parameters x and y (metres) and keep their values
        self.action_client = ActionClient(self, MoveStraightIn2D, '/move_straight_in_2d')
        self.done = False
        # TODO: a timer (every 0.2 s) whose callback waits for the server, then sends the goal once

    # TODO: timer_callback: while not self.action_client.server_is_ready(), log that you wait
    #       (throttle_duration_sec=1.0) and return; then cancel the timer and
    #       send_goal_async(goal, feedback_callback=self.feedback_callback), adding
    #       goal_response_callback as the future's done callback

    # TODO: goal_response_callback(future): goal_handle = future.result(); if not accepted, log
    #       that the goal was rejected and set self.done; else get_result_async() and add
    #       result_callback

    # TODO: feedback_callback(feedback_message): log feedback_message.feedback.distance_to_goal

    # TODO: result_callback(future): log response.result.final_position and the status's name,
    #       then set self.done


def main(args=None) -> None:
    """Spin until the goal has ended (or Ctrl+C)."""
    try:
        rclpy.init(args=args)
        node = MoveStraightIn2DActionClientNode()
        while rclpy.ok() and not node.done:
            rclpy.spin_once(node, timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
