"""An action server: moves a simulated point in a straight line to each MoveStraightIn2D goal."""

import math  # noqa: F401 - you will need math.hypot and math.isfinite
import time  # noqa: F401 - and time.sleep

import rclpy
from rclpy.action import ActionServer, CancelResponse, GoalResponse  # noqa: F401
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

from package_with_interfaces.action import MoveStraightIn2D

SPEED = 1.0  # metres per second
PERIOD = 0.1  # seconds between two steps, and between two feedback messages
MAX_DISTANCE = 2.0  # metres: a goal farther than this from the point is rejected


class MoveStraightIn2DActionServerNode(Node):
    """Serves /move_straight_in_2d."""

    def __init__(self) -> None:
        super().__init__('move_straight_in_2d_action_server')
        # TODO: keep the point's position here (it starts at (0, 0) and carries over between goals)
        # TODO: pass goal_callback, cancel_callback and handle_accepted_callback too, and a
        #       ReentrantCallbackGroup (see the instructions: why a multi-threaded executor)
        self.action_server = ActionServer(
            self,
            MoveStraightIn2D,
            '/move_straight_in_2d',
            execute_callback=self.execute_callback)

    # TODO: goal_callback(self, goal_request) -> GoalResponse: reject goals that are not finite
    #       or more than MAX_DISTANCE from the point

    # TODO: cancel_callback(self, goal_handle) -> CancelResponse: accept

    # TODO: handle_accepted_callback(self, goal_handle): abort the goal still executing, if any,
    #       then goal_handle.execute()

    def execute_callback(self, goal_handle):
        """Move towards the goal step by step, publishing the distance still to go."""
        # TODO: the loop: stop when aborted (not goal_handle.is_active) or canceled
        #       (goal_handle.is_cancel_requested -> goal_handle.canceled()); else one step of
        #       SPEED * PERIOD towards the goal, publish feedback, sleep PERIOD; land exactly on
        #       the goal when it is one step away or closer, publish 0.0 and succeed.
        goal_handle.succeed()
        result = MoveStraightIn2D.Result()
        # TODO: result.final_position = where the point is
        return result


def main(args=None) -> None:
    """Spin the node until Ctrl+C."""
    try:
        rclpy.init(args=args)
        node = MoveStraightIn2DActionServerNode()
        # TODO: spin with a MultiThreadedExecutor, or cancel requests wait for the goal to end
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
