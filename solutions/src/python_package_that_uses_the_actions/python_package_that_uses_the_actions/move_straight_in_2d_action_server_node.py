"""An action server: moves a simulated point in a straight line to each MoveStraightIn2D goal.

The point starts at (0, 0) and stays where each goal leaves it (succeeded, canceled or
aborted): the next goal starts from there. It travels at SPEED, one step every PERIOD,
and publishes the distance still to go after each step.
"""

import math
import threading
import time

import rclpy
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.action.server import ServerGoalHandle
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor
from rclpy.node import Node

from package_with_interfaces.action import MoveStraightIn2D

SPEED = 1.0  # metres per second
PERIOD = 0.1  # seconds between two steps, and between two feedback messages
MAX_DISTANCE = 2.0  # metres: a goal farther than this from the point is rejected


class MoveStraightIn2DActionServerNode(Node):
    """Serves /move_straight_in_2d: one goal at a time, a newer goal aborts the one executing."""

    def __init__(self) -> None:
        super().__init__('move_straight_in_2d_action_server')
        self.position = [0.0, 0.0]  # metres; kept between goals
        self.goal_lock = threading.Lock()
        self.current_goal: ServerGoalHandle | None = None
        # A reentrant group lets the (multi-threaded) executor run the cancel and goal
        # callbacks while execute_callback is still inside its loop.
        self.action_server = ActionServer(
            self,
            MoveStraightIn2D,
            '/move_straight_in_2d',
            execute_callback=self.execute_callback,
            goal_callback=self.goal_callback,
            handle_accepted_callback=self.handle_accepted_callback,
            cancel_callback=self.cancel_callback,
            callback_group=ReentrantCallbackGroup())

    def goal_callback(self, goal_request: MoveStraightIn2D.Goal) -> GoalResponse:
        """Accept a goal with finite coordinates at most MAX_DISTANCE metres from the point."""
        goal = goal_request.desired_position
        if not (math.isfinite(goal.x) and math.isfinite(goal.y)):
            self.get_logger().warning(f'Rejected a goal with coordinates ({goal.x}, {goal.y}): not finite')
            return GoalResponse.REJECT
        distance = math.hypot(goal.x - self.position[0], goal.y - self.position[1])
        if distance > MAX_DISTANCE:
            self.get_logger().warning(f'Rejected the goal ({goal.x:.3f}, {goal.y:.3f}): {distance:.3f} m away, '
                                      f'more than {MAX_DISTANCE} m')
            return GoalResponse.REJECT
        return GoalResponse.ACCEPT

    def handle_accepted_callback(self, goal_handle: ServerGoalHandle) -> None:
        """One goal at a time: abort the goal still executing, then execute the new one."""
        with self.goal_lock:
            if self.current_goal is not None and self.current_goal.is_active:
                self.get_logger().info('A new goal arrived: aborting the previous one')
                self.current_goal.abort()
            self.current_goal = goal_handle
        goal_handle.execute()

    def cancel_callback(self, goal_handle: ServerGoalHandle) -> CancelResponse:
        """Accept every cancel request: execute_callback stops at its next step."""
        self.get_logger().info('Cancel requested')
        return CancelResponse.ACCEPT

    def execute_callback(self, goal_handle: ServerGoalHandle) -> MoveStraightIn2D.Result:
        """Step towards the goal every PERIOD seconds until it is reached, canceled or aborted."""
        goal = goal_handle.request.desired_position
        feedback = MoveStraightIn2D.Feedback()
        result = MoveStraightIn2D.Result()
        step = SPEED * PERIOD
        while True:
            if not goal_handle.is_active:  # aborted by a newer goal (handle_accepted_callback)
                break
            if goal_handle.is_cancel_requested:
                goal_handle.canceled()
                self.get_logger().info('Goal canceled')
                break
            dx, dy = goal.x - self.position[0], goal.y - self.position[1]
            distance = math.hypot(dx, dy)
            if distance <= step:
                # the last step lands on the goal exactly: no floating-point margin decides success
                self.position = [goal.x, goal.y]
                feedback.distance_to_goal = 0.0
                goal_handle.publish_feedback(feedback)
                goal_handle.succeed()
                self.get_logger().info(f'Goal reached: ({goal.x:.3f}, {goal.y:.3f})')
                break
            self.position = [self.position[0] + dx / distance * step, self.position[1] + dy / distance * step]
            feedback.distance_to_goal = distance - step
            goal_handle.publish_feedback(feedback)
            time.sleep(PERIOD)
        result.final_position.x, result.final_position.y = self.position
        return result


def main(args=None) -> None:
    """Spin the node on a multi-threaded executor until Ctrl+C."""
    try:
        rclpy.init(args=args)
        node = MoveStraightIn2DActionServerNode()
        # Two threads or more: one runs execute_callback, another serves cancel requests and new goals.
        rclpy.spin(node, executor=MultiThreadedExecutor())
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == '__main__':
    main()
